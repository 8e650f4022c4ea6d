//! The flags that act on the library's advice. Library errors name scene
//! keys, rig keys and function parameters ("lower gamma or use the ideal
//! rig", "give it as freq_hz"); when the `vlab` binary prints one that gives
//! such advice, it adds the flags that take it:
//!
//! ```text
//! error: Gamma 13 at 20 Hz needs 16.2 mm peak-to-peak stroke; the thesis-shaker rig
//!   allows 15 mm (stroke limit, shaker.stroke_pp_m): lower gamma or use the ideal rig
//!   (--gamma, --rig ideal)
//! ```
//!
//! (one line in the terminal). A value refused by its key is renamed to the
//! flag that set it by [`super::args::FlagKeys`] instead.

use std::error::Error;

use vlab::experiment::replay::ReplayOption;
use vlab::rig::RigError;
use vlab::scene::SceneError;
use vlab::signals::{CsvErrorKind, RecordErrorKind, SignalsError};
use vlab::study::sweep::SweepError;

/// The flags that take the advice of `err` (of the first cause that gives
/// advice), if any.
pub fn flag_hint(err: &anyhow::Error) -> Option<&'static str> {
    err.chain().find_map(hint_of)
}

/// `message` with the flags of [`flag_hint`] after it, in parentheses.
pub fn with_flag_hint(message: String, err: &anyhow::Error) -> String {
    match flag_hint(err) {
        Some(h) => format!("{message} ({h})"),
        None => message,
    }
}

/// The flag that gives a replay option.
pub fn replay_option_flag(option: ReplayOption) -> &'static str {
    match option {
        ReplayOption::FreqHz => "--freq HZ",
        ReplayOption::ParticleMassKg => "--particle-mass-kg KG",
        ReplayOption::ForceColumn => "--column force=NAME",
        ReplayOption::MotionColumn => "--column velocity=NAME",
    }
}

/// One cause, looking through the library's transparent wrappers.
fn hint_of(e: &(dyn Error + 'static)) -> Option<&'static str> {
    if let Some(e) = e.downcast_ref::<RigError>() {
        rig_hint(e)
    } else if let Some(e) = e.downcast_ref::<SignalsError>() {
        signals_hint(e)
    } else if let Some(e) = e.downcast_ref::<SceneError>() {
        scene_hint(e)
    } else if let Some(e) = e.downcast_ref::<SweepError>() {
        match e {
            SweepError::Scene(e) => scene_hint(e),
            SweepError::Exists { .. } => Some("--resume, or another --out"),
            SweepError::OtherSweep { .. } => {
                Some("the arguments it was started with, or another --out")
            }
            SweepError::UnfinishedShard { .. } => Some("--resume"),
            _ => None,
        }
    } else {
        None
    }
}

fn rig_hint(e: &RigError) -> Option<&'static str> {
    match e {
        RigError::StrokeLimit { .. } | RigError::AccelerationLimit { .. } => {
            Some("--gamma, --rig ideal")
        }
        RigError::InFile { source, .. } => rig_hint(source),
        RigError::Signals(e) => signals_hint(e),
        _ => None,
    }
}

fn signals_hint(e: &SignalsError) -> Option<&'static str> {
    match e {
        SignalsError::Csv {
            kind: CsvErrorKind::AmbiguousDelimiter { .. },
            ..
        } => Some("--delimiter"),
        SignalsError::NotInMetadata {
            parameter: "freq_hz",
            ..
        } => Some("--freq HZ"),
        // Only a record of named columns (`vlab replay`) looks for its time
        // column by name.
        SignalsError::Csv {
            kind: CsvErrorKind::NoTimeColumn { .. },
            ..
        }
        | SignalsError::Record {
            kind: RecordErrorKind::NoTimeColumn { .. },
            ..
        } => Some("--column time=NAME"),
        _ => None,
    }
}

fn scene_hint(e: &SceneError) -> Option<&'static str> {
    match e {
        SceneError::RecordNeeds { option, .. } => Some(replay_option_flag(*option)),
        SceneError::File { source, .. } => scene_hint(source),
        SceneError::Rig(e) => rig_hint(e),
        SceneError::Signals(e) => signals_hint(e),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn advice_gets_its_flags_and_other_errors_none() {
        use vlab::rig::RigFile;
        let rig = vlab::rig::RigSpec::builtin("thesis-shaker").expect("built in");
        let drive = vlab::drive::Drive::new(20.0, 13.0, 9.81).expect("valid drive");
        let err = vlab::rig::check_limits(&rig, &drive).expect_err("stroke");
        let err = anyhow::Error::new(SceneError::from(err)).context("--rig thesis-shaker");
        let shown = with_flag_hint(err.to_string(), &err);
        assert!(shown.ends_with(" (--gamma, --rig ideal)"), "{shown}");
        let plain = anyhow::anyhow!("something else");
        assert_eq!(flag_hint(&plain), None);
    }
}
