//! Reading a record of named columns ([`Table`]) from a file of any format
//! vlab reads such records in, told apart by the file's extension:
//!
//! - `.csv` (case-insensitive): any CSV [`super::csv`] reads (dialects,
//!   `name [unit]` headers, `# key: value` comments), e.g. vlab's own
//!   `kinematics.csv`;
//! - any other name: the whitespace-separated text LAMMPS and LIGGGHTS write
//!   with `fix ave/time` and `fix print` ([`super::lammps`]).
//!
//! No thesis equation lives here. The type is [`super::table`]'s; this file
//! sits above both readers so that neither imports the other.

use std::path::Path;

use super::csv::{CsvReadOptions, read_csv_table};
use super::error::Result;
use super::lammps::read_lammps_text;
use super::table::Table;

/// Reads a record of named columns: `.csv` (case-insensitive) through
/// [`super::csv`], anything else as LAMMPS / LIGGGHTS text through
/// [`super::lammps`]. Its time column is the one called `time_column` when
/// given (exactly as written, without a CSV header's unit), else the first of
/// [`super::column_names::TIME_NAMES`].
pub fn read_table(path: &Path, time_column: Option<&str>) -> Result<Table> {
    let is_csv = path
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("csv"));
    if is_csv {
        read_csv_table(path, &CsvReadOptions::default(), time_column)
    } else {
        read_lammps_text(path, time_column)
    }
}
