//! Warnings a run reports beside its result, and what would lift them.
//!
//! A [`Warning`] is its text, in the library's words (naming keys and
//! parameters, never command-line flags), and optionally the input `A` that
//! would lift it (a domain's own enum, such as
//! [`crate::experiment::replay::ReplayOption`], or the [`FileKey`] of a scene
//! or rig file for the warnings of a run: [`RunWarning`]); the `vlab` binary
//! turns that into the flag that gives it. Written out (`summary.json`,
//! `--json`) a warning is its text alone, and the library hands warnings on
//! as warnings: only the binary makes text of them.

use std::fmt;

use serde::{Serialize, Serializer};

/// A warning's text and the input that would lift it, if any.
#[derive(Debug, Clone, PartialEq)]
pub struct Warning<A> {
    /// What is wrong and what to do, in the library's words.
    pub text: String,
    /// The input that would lift it.
    pub advice: Option<A>,
}

impl<A> Warning<A> {
    /// A warning that `advice` would lift.
    pub fn advising(text: impl Into<String>, advice: A) -> Self {
        Warning {
            text: text.into(),
            advice: Some(advice),
        }
    }
}

impl<A> Warning<A> {
    /// The same warning with its advice made a `B` (`None` when `B` cannot
    /// say it): a warning handed on to a caller with other inputs.
    pub fn advising_as<B>(self, f: impl FnOnce(A) -> Option<B>) -> Warning<B> {
        Warning {
            text: self.text,
            advice: self.advice.and_then(f),
        }
    }
}

/// A key of a scene or rig file (`simulation.dt_s`, `drive.cycles`,
/// `daq.sample_rate_hz`) whose value would lift a warning.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FileKey(pub &'static str);

impl fmt::Display for FileKey {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.0)
    }
}

/// A warning of a run (settling, the bed cache, a shake, a drop, the rig's
/// digitiser), and the file key that would lift it.
pub type RunWarning = Warning<FileKey>;

impl<A> From<String> for Warning<A> {
    fn from(text: String) -> Self {
        Warning { text, advice: None }
    }
}

impl<A> fmt::Display for Warning<A> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.text)
    }
}

impl<A> Serialize for Warning<A> {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(&self.text)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_warning_is_written_as_its_text_and_keeps_advice_another_type_can_say() {
        let w = RunWarning::advising("lengthen the drive", FileKey("drive.cycles"));
        assert_eq!(w.to_string(), "lengthen the drive");
        assert_eq!(
            serde_json::to_string(&vec![w.clone()]).expect("json"),
            "[\"lengthen the drive\"]"
        );
        let kept: Warning<&str> = w.clone().advising_as(|k| Some(k.0));
        assert_eq!(kept.advice, Some("drive.cycles"));
        let dropped: Warning<()> = w.advising_as(|_| None);
        assert_eq!(
            (dropped.text.as_str(), dropped.advice),
            ("lengthen the drive", None)
        );
    }
}
