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

/// What is wrong with a CSV trace file.
#[derive(Debug, thiserror::Error)]
pub enum CsvErrorKind {
    /// No header and no data.
    #[error("the file is empty (expected a header such as 'time [s],force [N]')")]
    Empty,
    /// The first column is not a time column.
    #[error("first column is '{found}'; expected a time column named {known}", known = TIME_NAMES_TEXT)]
    MissingTimeColumn {
        /// The header cell found.
        found: String,
    },
    /// A record has no time column (of a known name, or of the name given).
    #[error("{}", no_time_column(.given.as_deref(), .names))]
    NoTimeColumn {
        /// The name the caller gave the time column, if any.
        given: Option<String>,
        /// The header's column names.
        names: String,
    },
    /// The time column's unit is not seconds.
    #[error("time column '{header}' is in {unit}; vlab reads time in s")]
    TimeUnit {
        /// The header cell.
        header: String,
        /// Its unit.
        unit: String,
    },
    /// Only a time column.
    #[error("the header has no data columns after the time column")]
    NoDataColumns,
    /// A header cell cannot be used as a channel name.
    #[error("column {column} header '{header}': {problem}")]
    BadHeader {
        /// One-based column number.
        column: usize,
        /// The header cell.
        header: String,
        /// What is wrong.
        problem: String,
    },
    /// A row has the wrong number of cells.
    #[error("row has {got} cells but the header has {expected} columns")]
    Ragged {
        /// Cells in the header.
        expected: usize,
        /// Cells in the row.
        got: usize,
    },
    /// A cell is not a number.
    #[error("column '{column}': '{text}' is not a number")]
    NotANumber {
        /// Column header.
        column: String,
        /// The cell text.
        text: String,
    },
    /// A cell is NaN or infinite.
    #[error("column '{column}': value {value} is not finite")]
    NonFinite {
        /// Column header.
        column: String,
        /// The value.
        value: f64,
    },
    /// Fewer than two data rows.
    #[error("{got} data rows; at least 2 are needed to define a sample rate")]
    TooFewRows {
        /// Rows found.
        got: usize,
    },
    /// The time column is not uniformly spaced.
    #[error(
        "time {time_s} s deviates from the uniform grid (expected {expected_s} s, step {step_s} s, \
         tolerance {rel_tol:e} of a step)"
    )]
    NonUniformTime {
        /// Time read.
        time_s: f64,
        /// Time expected on the uniform grid.
        expected_s: f64,
        /// Sample period.
        step_s: f64,
        /// Relative tolerance used.
        rel_tol: f64,
    },
    /// A `# key: value` comment has a bad value.
    #[error("comment '{key}': {problem}")]
    BadComment {
        /// The key.
        key: String,
        /// What is wrong.
        problem: String,
    },
    /// The bytes are not UTF-8 text.
    #[error(
        "byte 0x{byte:02X} is not UTF-8 text: save the file as UTF-8 (a spreadsheet's \"CSV UTF-8\")"
    )]
    NotUtf8 {
        /// The first offending byte.
        byte: u8,
    },
    /// The field separator cannot be told from the file.
    #[error("{problem}; name the delimiter: ',', ';' or tab")]
    AmbiguousDelimiter {
        /// What makes it ambiguous.
        problem: String,
    },
    /// A number's decimal mark contradicts the file's (or the one asked for).
    #[error("column '{column}': '{text}' {problem}")]
    DecimalMark {
        /// Column header.
        column: String,
        /// The cell text.
        text: String,
        /// What is wrong, and where the file's decimal mark was decided.
        problem: String,
    },
    /// A delimiter other than the three vlab reads was asked for.
    #[error("delimiter {delimiter:?}: vlab reads ',', ';' or tab")]
    UnsupportedDelimiter {
        /// The delimiter asked for.
        delimiter: char,
    },
    /// The CSV parser itself refused the text.
    #[error("{problem}")]
    Syntax {
        /// The parser's message.
        problem: String,
    },
    /// A channel name or unit cannot be written into a CSV header.
    #[error(
        "channel '{name}' unit '{unit}': names and units must not contain ',', '[', ']', '\"' or line breaks"
    )]
    Unwritable {
        /// Channel name.
        name: String,
        /// Channel unit.
        unit: String,
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

/// What is wrong with a record of named columns ([`super::Table`]).
#[derive(Debug, thiserror::Error)]
pub enum RecordErrorKind {
    /// Too few rows to define a time step.
    #[error("{got} row(s): a record needs at least 2")]
    TooFewRows {
        /// Rows found.
        got: usize,
    },
    /// Time does not increase.
    #[error(
        "time {time_s} s is not after the previous row's {previous_s} s: the time column must \
         increase (two runs appended to one file?)"
    )]
    TimeNotIncreasing {
        /// Time on this row.
        time_s: f64,
        /// Time on the row before.
        previous_s: f64,
    },
    /// A step that is not the record's step.
    #[error(
        "time {time_s} s comes {step_s:.4e} s after the previous row but the record steps \
         {typical_s:.4e} s: {}; a record must be sampled uniformly",
        if step_s > typical_s { "rows are missing (a gap)" } else { "an irregular step" }
    )]
    IrregularStep {
        /// Time on this row.
        time_s: f64,
        /// Its step from the previous row.
        step_s: f64,
        /// The record's step.
        typical_s: f64,
    },
    /// A `# key: value` comment that should hold a number does not.
    #[error("comment '{key}': '{text}' is not a finite number")]
    BadComment {
        /// The key.
        key: String,
        /// Its text.
        text: String,
    },
    /// Nothing but comments.
    #[error("no data rows")]
    Empty,
    /// The columns are not named.
    #[error(
        "the {columns} data columns have no names (the last comment line is '{last_comment}'): \
         fix ave/time names them itself; give fix print a title naming them, e.g. \
         title \"time enclosure_velocity particle_force_axial\""
    )]
    NoColumnNames {
        /// Data columns found.
        columns: usize,
        /// The last comment line before the data.
        last_comment: String,
    },
    /// No column holds time (of a known name, or of the name given).
    #[error("{}", no_lammps_time_column(.given.as_deref(), .names))]
    NoTimeColumn {
        /// The name the caller gave the time column, if any.
        given: Option<String>,
        /// The columns present.
        names: String,
    },
    /// Two columns of one name.
    #[error("column '{name}' appears twice")]
    DuplicateName {
        /// The name.
        name: String,
    },
    /// A row with the wrong number of values.
    #[error("{got} values but the header names {expected} columns")]
    Ragged {
        /// Columns named.
        expected: usize,
        /// Values on the row.
        got: usize,
    },
    /// A value that is not a number.
    #[error("column '{column}': '{text}' is not a number")]
    NotANumber {
        /// Column name.
        column: String,
        /// The text.
        text: String,
    },
    /// NaN or an infinity.
    #[error("column '{column}': '{text}' is not finite")]
    NonFinite {
        /// Column name.
        column: String,
        /// The text.
        text: String,
    },
    /// `fix ave/time` in vector mode: blocks of rows per time step.
    #[error(
        "fix ave/time output in vector mode (a 'Row' column, one block of rows per time step) is \
         not a time series: use fix ave/time in scalar mode (the default)"
    )]
    VectorMode,
    /// Written in another LAMMPS unit system.
    #[error("written with LAMMPS 'units {units}': vlab reads SI records only (units si)")]
    NotSi {
        /// The unit style declared.
        units: String,
    },
    /// Text with CSV separators given to the whitespace reader.
    #[error(
        "the values are separated by '{separator}': a CSV file? vlab reads a record as CSV when its \
         name ends in .csv; LAMMPS text is separated by spaces"
    )]
    Separator {
        /// The separator found.
        separator: char,
    },
}

/// What is wrong with a WAV trace file or its JSON sidecar.
#[derive(Debug, thiserror::Error)]
pub enum WavErrorKind {
    /// hound could not read or write the WAV.
    #[error("WAV: {0}")]
    Hound(#[from] hound::Error),
    /// No sidecar next to the WAV.
    #[error(
        "no sidecar '{}' next to the WAV: channel names, units and full-scale values live \
         there (a WAV stores only normalised samples); supply them with read_wav_with",
        sidecar.display()
    )]
    SidecarMissing {
        /// Where the sidecar was expected.
        sidecar: PathBuf,
    },
    /// The sidecar is of another format or version.
    #[error("sidecar: {problem}")]
    BadSidecar {
        /// What is wrong.
        problem: String,
    },
    /// The sidecar's sample rate is not the WAV header's.
    #[error("sidecar sample rate {sidecar_hz} Hz disagrees with the WAV header's {header_hz} Hz")]
    SampleRateMismatch {
        /// Rate in the sidecar.
        sidecar_hz: f64,
        /// Rate in the WAV header.
        header_hz: u32,
    },
    /// The sidecar names a different number of channels than the WAV holds.
    #[error("the sidecar describes {described} channels but the WAV holds {in_wav}")]
    ChannelCountMismatch {
        /// Channels described.
        described: usize,
        /// Channels in the WAV.
        in_wav: usize,
    },
    /// The sidecar's sample count is not the WAV's.
    #[error("the sidecar says {described} samples per channel but the WAV holds {in_wav}")]
    LengthMismatch {
        /// Samples described.
        described: usize,
        /// Samples in the WAV.
        in_wav: usize,
    },
    /// A full-scale value is unusable.
    #[error("channel '{channel}' full scale {full_scale}: {problem}")]
    BadFullScale {
        /// Channel.
        channel: String,
        /// The value.
        full_scale: f64,
        /// What is wrong.
        problem: String,
    },
    /// Too many channels for a WAV file.
    #[error("{channels} channels: a WAV file holds at most 65535")]
    TooManyChannels {
        /// Channels requested.
        channels: usize,
    },
    /// Sample format not supported.
    #[error("unsupported WAV sample format: {0}")]
    UnsupportedFormat(String),
}

/// What is wrong with a TDMS trace file.
#[derive(Debug, thiserror::Error)]
pub enum TdmsErrorKind {
    /// The TDMS reader (crate `tdms-rs`) could not read the file.
    #[error("TDMS: {0}")]
    Reader(#[source] tdms_rs::TdmsError),
    /// A segment does not start with the TDMS tag.
    #[error(
        "byte {offset}: expected a TDMS segment (tag 'TDSm'), found {found:?}: not a TDMS file, or a damaged one"
    )]
    NotTdms {
        /// Byte offset of the segment.
        offset: u64,
        /// What was there, as text.
        found: String,
    },
    /// A segment uses a layout the reader does not support.
    #[error(
        "segment at byte {offset} holds {layout}, which vlab does not read: export the channels as plain little-endian f64/f32 waveforms"
    )]
    UnsupportedLayout {
        /// Byte offset of the segment.
        offset: u64,
        /// The layout, in words.
        layout: &'static str,
    },
    /// The raw data in the file do not add up to the channels found.
    #[error(
        "the segments hold {in_segments} bytes of raw data but the channels account for {in_channels}: \
         a layout vlab does not read (several data chunks per segment?)"
    )]
    RawDataUnaccounted {
        /// Raw bytes in the segments.
        in_segments: u64,
        /// Raw bytes the channels' indices describe.
        in_channels: u64,
    },
    /// No channel holds data.
    #[error("no channels: the file holds no waveform to read")]
    NoChannels,
    /// Channels in more than one group.
    #[error("channels in {count} groups [{groups}]: vlab reads one group (one record) per file")]
    SeveralGroups {
        /// Number of groups with channels.
        count: usize,
        /// Their names.
        groups: String,
    },
    /// A channel is not of a floating-point type.
    #[error(
        "channel '{channel}' holds {data_type} values: vlab reads f64 and f32 channels in physical units"
    )]
    UnsupportedDataType {
        /// Channel name.
        channel: String,
        /// Its TDMS data type.
        data_type: String,
    },
    /// A channel's waveform timing is missing or unusable.
    #[error("channel '{channel}': {problem}")]
    BadTiming {
        /// Channel name.
        channel: String,
        /// What is wrong.
        problem: String,
    },
    /// Channels of different lengths.
    #[error(
        "channel '{channel}' has {len} samples but '{first}' has {first_len}: \
         the channels of a record must have equal length"
    )]
    UnequalLength {
        /// First channel.
        first: String,
        /// Its length.
        first_len: usize,
        /// The channel that differs.
        channel: String,
        /// Its length.
        len: usize,
    },
    /// A segment runs past the end of the file.
    #[error(
        "segment at byte {offset} runs to byte {end} but the file ends at byte {len}: a truncated file"
    )]
    Truncated {
        /// Byte offset of the segment.
        offset: u64,
        /// Where the segment says it ends.
        end: u64,
        /// File length in bytes.
        len: u64,
    },
    /// A channel's samples cannot make a trace channel (empty name, NaN, ...).
    #[error("{problem}")]
    BadChannel {
        /// What is wrong, naming the channel.
        problem: String,
    },
    /// The file-level `vlab_metadata` property is unusable.
    #[error("property 'vlab_metadata': {problem}")]
    BadMetadata {
        /// What is wrong.
        problem: String,
    },
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
