//! What is wrong with a record of named columns ([`crate::signals::Table`]):
//! its rows, its columns, its time column (of LAMMPS text too).

use super::no_lammps_time_column;

/// What is wrong with a record of named columns ([`crate::signals::Table`]).
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
