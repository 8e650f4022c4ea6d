//! What is wrong with a CSV trace file ([`crate::signals::csv`]).

use crate::signals::column_names::TIME_NAMES_TEXT;

use super::no_time_column;

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
