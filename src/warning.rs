//! Warnings a run reports beside its result, and what would lift them.
//!
//! A [`Warning`] is its text, in the library's words (naming keys and
//! parameters, never command-line flags), and optionally the input `A` that
//! would lift it (a domain's own enum, such as
//! [`crate::experiment::replay::ReplayOption`]); the `vlab` binary turns that into
//! the flag that gives it. Written out (`summary.json`, `--json`) a warning is
//! its text alone.

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
