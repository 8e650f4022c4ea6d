//! The one error type of the `signals` module.
//!
//! Every fallible function in `signals` returns [`SignalsError`]. Messages name
//! the parameter, channel, file, line or column at fault, with the unit and the
//! valid range where there is one, so that a lab user can fix the input without
//! reading the source. File-format problems carry a nested kind
//! ([`CsvErrorKind`], [`WavErrorKind`], [`TdmsErrorKind`]) so callers can match
//! on them.

use std::io;
use std::path::PathBuf;

use super::column_names::TIME_NAMES_TEXT;
pub use crate::validation::InvalidParameter;

mod csv;
mod record;
mod tdms;
mod wav;

pub use csv::CsvErrorKind;
pub use record::RecordErrorKind;
pub use tdms::TdmsErrorKind;
pub use wav::WavErrorKind;

/// Result alias used throughout `signals`.
pub type Result<T, E = SignalsError> = std::result::Result<T, E>;

/// Everything that can go wrong in `signals`.
#[derive(Debug, thiserror::Error)]
pub enum SignalsError {
    /// A scalar parameter is out of its valid range (named as in the API,
    /// e.g. `sample_rate_hz`).
    #[error("{0}")]
    Invalid(#[from] InvalidParameter),
    /// A structural-dynamics method could not run on its record
    /// ([`super::structural`]).
    #[error("{0}")]
    Structural(#[from] super::structural::StructuralError),
    /// A sample is NaN or infinite.
    #[error("channel '{channel}' sample {index} is {value}: samples must be finite")]
    NonFiniteSample {
        /// Channel (or input) name.
        channel: String,
        /// Zero-based sample index.
        index: usize,
        /// The offending value.
        value: f64,
    },
    /// A channel name was looked up and is not in the trace.
    #[error("channel '{name}' not found; the trace has channels [{available}]")]
    ChannelNotFound {
        /// Requested name.
        name: String,
        /// Comma-separated names present.
        available: String,
    },
    /// A channel name is empty or already used.
    #[error("channel name '{name}' is {problem}")]
    BadChannelName {
        /// The name.
        name: String,
        /// What is wrong with it ("already used", "empty", ...).
        problem: String,
    },
    /// Two sequences that must have equal length do not.
    #[error(
        "{first} has {first_len} samples but {second} has {second_len}: they must have equal length"
    )]
    LengthMismatch {
        /// Name of the first sequence.
        first: String,
        /// Its length.
        first_len: usize,
        /// Name of the second sequence.
        second: String,
        /// Its length.
        second_len: usize,
    },
    /// A record is too short for the requested analysis.
    #[error("{what} needs at least {need} samples, got {got}")]
    TooFewSamples {
        /// The analysis or input.
        what: String,
        /// Minimum number of samples.
        need: usize,
        /// Number available.
        got: usize,
    },
    /// The power window holds fewer than two drive periods.
    #[error(
        "the analysis window holds {periods:.3} periods of the {drive_freq_hz} Hz drive \
         ({n_samples} samples at {sample_rate_hz} Hz); at least 2 whole periods are needed (1 in a window given explicitly)"
    )]
    TooFewPeriods {
        /// Drive periods that fit.
        periods: f64,
        /// Drive frequency.
        drive_freq_hz: f64,
        /// Samples available for the window.
        n_samples: usize,
        /// Sample rate.
        sample_rate_hz: f64,
    },
    /// An explicit window does not lie inside the record.
    #[error(
        "window start {start} + length {len} samples exceeds the record of {available} samples"
    )]
    WindowOutOfRange {
        /// First sample of the window.
        start: usize,
        /// Window length in samples.
        len: usize,
        /// Record length in samples.
        available: usize,
    },
    /// Too few impacts for the restitution estimator.
    #[error("found {found} impacts; the estimator needs at least 3 (two gaps)")]
    NotEnoughImpacts {
        /// Impacts found.
        found: usize,
    },
    /// Nothing in the force record looks like an impact.
    #[error("no impacts: {reason}")]
    NoImpacts {
        /// Why the detector concluded so.
        reason: String,
    },
    /// Impact times are not strictly increasing.
    #[error(
        "impact {index} at {time_s} s is not after impact {prev_index} at {prev_time_s} s: impact times must increase strictly"
    )]
    ImpactTimesNotIncreasing {
        /// Index of the offending time.
        index: usize,
        /// Its value.
        time_s: f64,
        /// Index of the previous time.
        prev_index: usize,
        /// Previous value.
        prev_time_s: f64,
    },
    /// A value the record's metadata does not hold and the caller did not
    /// give.
    #[error("unknown {what}: the record's metadata has no {metadata_key}; give {parameter}")]
    NotInMetadata {
        /// What it is, in words.
        what: &'static str,
        /// The metadata key that would have held it.
        metadata_key: &'static str,
        /// The parameter that gives it.
        parameter: &'static str,
    },
    /// A phase calibration table is unusable.
    #[error("phase calibration: {reason}")]
    InvalidCalibration {
        /// What is wrong.
        reason: String,
    },
    /// A trace file whose kind cannot be told from its name.
    #[error("{}: unknown kind of trace file: expected .csv (a time column first), .wav (with its .wav.json sidecar) or .tdms", path.display())]
    UnknownTraceFormat {
        /// The file.
        path: PathBuf,
    },
    /// Reading or writing a file failed at the OS level.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// The OS error.
        #[source]
        source: io::Error,
    },
    /// A JSON file (metadata, sidecar, calibration) did not parse.
    #[error("{}: {source}", path.display())]
    Json {
        /// The file.
        path: PathBuf,
        /// The parser's error, with line and column.
        #[source]
        source: serde_json::Error,
    },
    /// A CSV trace file is malformed.
    #[error("{}: line {line}: {kind}", path.display())]
    Csv {
        /// The file.
        path: PathBuf,
        /// One-based line number (0 when the problem concerns the whole file).
        line: usize,
        /// What is wrong.
        kind: CsvErrorKind,
    },
    /// A WAV trace file (or its sidecar) is malformed or inconsistent.
    #[error("{}: {kind}", path.display())]
    Wav {
        /// The WAV file.
        path: PathBuf,
        /// What is wrong.
        kind: WavErrorKind,
    },
    /// A TDMS trace file is unreadable or unusable as a trace.
    #[error("{}: {kind}", path.display())]
    Tdms {
        /// The TDMS file.
        path: PathBuf,
        /// What is wrong.
        kind: TdmsErrorKind,
    },
    /// A record of named columns (a DEM code's output, [`super::Table`]) is
    /// unusable.
    #[error("{}: {}{kind}", path.display(), at_line(*line))]
    Record {
        /// The file.
        path: PathBuf,
        /// One-based line number (0 when the problem concerns the whole file).
        line: usize,
        /// What is wrong.
        kind: RecordErrorKind,
    },
    /// A plot could not be drawn.
    #[error("{}: plot: {message}", path.display())]
    Plot {
        /// The SVG file.
        path: PathBuf,
        /// What went wrong.
        message: String,
    },
}

/// A record's missing time column, of a known name or of the name `given`.
fn no_time_column(given: Option<&str>, names: &str) -> String {
    match given {
        Some(given) => format!("no column '{given}' (given as the time column) among [{names}]"),
        None => format!(
            "no time column among [{names}]: vlab knows a time column by the names \
             {TIME_NAMES_TEXT}, or by the name given as the time column"
        ),
    }
}

/// [`no_time_column`] for LAMMPS text, with how to make LAMMPS write time.
fn no_lammps_time_column(given: Option<&str>, names: &str) -> String {
    let message = no_time_column(given, names);
    if given.is_some() {
        return message;
    }
    format!(
        "{message} (in LAMMPS: variable time equal time, and v_time among the fix's values; fix \
         ave/time then gives each averaging window's centre); a step number alone does not say \
         where in an averaging window a row lies"
    )
}

/// `line N: ` for a line, nothing for the whole file (line 0).
fn at_line(line: usize) -> String {
    if line == 0 {
        String::new()
    } else {
        format!("line {line}: ")
    }
}

/// Checks that `value` is positive and finite; names the parameter otherwise.
pub(crate) fn positive_finite(name: &str, value: f64, unit: &str) -> Result<f64> {
    Ok(crate::validation::positive(name, value, unit)?)
}

/// Checks that every sample is finite; names the input and index otherwise.
pub(crate) fn all_finite(channel: &str, samples: &[f64]) -> Result<()> {
    match samples.iter().position(|x| !x.is_finite()) {
        None => Ok(()),
        Some(index) => Err(SignalsError::NonFiniteSample {
            channel: channel.to_string(),
            index,
            value: samples[index],
        }),
    }
}
