//! The one error type of the `rig` module.
//!
//! Every fallible function in `rig` returns [`RigError`]. A refused value is
//! the crate's one [`InvalidParameter`] (its rig-file key where there is one,
//! its unit and the valid range); a refusal because the lab hardware cannot do what was asked names the
//! limit and suggests the `ideal` rig, which has none. Messages name rig keys
//! and parameters (`gamma`), never the `vlab` binary's flags.

use std::path::PathBuf;

use crate::signals::SignalsError;
pub use crate::validation::InvalidParameter;
pub(crate) use crate::validation::{finite, non_negative, positive};

/// Everything that can go wrong in `rig`.
#[derive(Debug, thiserror::Error)]
pub enum RigError {
    /// A parameter is out of its valid range (named by its rig-file key, e.g.
    /// `daq.sample_rate_hz`, or by its API argument name).
    #[error("{0}")]
    Invalid(#[from] InvalidParameter),
    /// The requested motion needs more stroke than the shaker has.
    #[error(
        "Gamma {gamma} at {freq_hz} Hz needs {needed_mm:.1} mm peak-to-peak stroke; the {rig} rig \
         allows {allowed_mm} mm (stroke limit, shaker.stroke_pp_m): lower gamma or use the ideal rig"
    )]
    StrokeLimit {
        /// Rig name.
        rig: String,
        /// Requested Gamma.
        gamma: f64,
        /// Drive frequency, Hz.
        freq_hz: f64,
        /// Peak-to-peak displacement needed, mm.
        needed_mm: f64,
        /// Peak-to-peak displacement allowed, mm.
        allowed_mm: f64,
    },
    /// The requested motion needs more acceleration than the shaker can give.
    #[error(
        "Gamma {gamma} at {freq_hz} Hz needs {needed_mps2:.1} m/s^2 peak acceleration; the {rig} rig \
         allows {allowed_mps2} m/s^2 (acceleration limit, shaker.max_accel_mps2): lower gamma or \
         use the ideal rig"
    )]
    AccelerationLimit {
        /// Rig name.
        rig: String,
        /// Requested Gamma.
        gamma: f64,
        /// Drive frequency, Hz.
        freq_hz: f64,
        /// Peak acceleration needed, m/s^2.
        needed_mps2: f64,
        /// Peak acceleration allowed, m/s^2.
        allowed_mps2: f64,
    },
    /// A rig name that is not built in and not a file.
    #[error("no built-in rig '{name}' (built-in: {available}) and no file of that name")]
    UnknownRig {
        /// The name asked for.
        name: String,
        /// Comma-separated built-in names.
        available: String,
    },
    /// A rig file could not be read.
    #[error("cannot read rig file {}: {source}", path.display())]
    Read {
        /// The file.
        path: PathBuf,
        /// The OS error.
        #[source]
        source: std::io::Error,
    },
    /// A rig file did not parse (unknown key, missing key, wrong type, ...).
    #[error("{origin}: {message}")]
    Parse {
        /// File path or built-in name.
        origin: String,
        /// The TOML parser's message (names the key, line and column).
        message: String,
    },
    /// A value of a rig file is refused.
    #[error("{origin}: {source}")]
    InFile {
        /// File path or built-in name.
        origin: String,
        /// What is wrong with it.
        #[source]
        source: Box<RigError>,
    },
    /// A rig file of another kind than the one needed.
    #[error("{origin} is a {found} rig; a {wanted} rig is needed here")]
    WrongKind {
        /// File path or built-in name.
        origin: String,
        /// Kind of the file (`shaker`, `drop-test`).
        found: &'static str,
        /// Kind needed.
        wanted: &'static str,
    },
    /// A rig file of another format version.
    #[error(
        "{origin}: version = {found} is not supported: this vlab reads rig files of version {supported}"
    )]
    Version {
        /// File path or built-in name.
        origin: String,
        /// Version found.
        found: u32,
        /// Version supported.
        supported: u32,
    },
    /// A section needed for what was asked is missing from the rig.
    #[error("rig '{rig}' has no [{section}] section: {hint}")]
    MissingSection {
        /// Rig name.
        rig: String,
        /// Section, e.g. `shaker.electrodynamic`.
        section: &'static str,
        /// What to do about it.
        hint: String,
    },
    /// The record holds no samples.
    #[error("the DAQ recorded no samples: {reason}")]
    EmptyRecord {
        /// Why.
        reason: String,
    },
    /// A non-finite value reached the DAQ.
    #[error(
        "{what} was {value} at t = {t_s} s (from the drive start): the simulation diverged or was \
         fed a non-finite force; nothing was recorded"
    )]
    NonFinite {
        /// Which input.
        what: &'static str,
        /// The value.
        value: f64,
        /// When.
        t_s: f64,
    },
    /// Building the trace failed.
    #[error(transparent)]
    Signals(#[from] SignalsError),
}

/// Result alias used throughout `rig`.
pub type Result<T, E = RigError> = std::result::Result<T, E>;
