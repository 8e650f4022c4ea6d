//! The text LAMMPS and LIGGGHTS write with `fix ave/time` (scalar mode) and
//! `fix print`: a lab-file format of DEM codes. No thesis equation lives here.
//!
//! ```text
//! # vlab record: thesis damper, 40 Hz, Gamma 20        <- free comments
//! # drive_freq_hz: 40                                   <- `# key: value` comments
//! # TimeStep v_time v_enclosure_velocity v_particle_force_axial
//! 25 1.2e-05 0.7746 -157.3
//! 50 3.7e-05 0.7745 -156.9
//! ```
//!
//! - Lines starting with `#` are comments; a `# key: value` comment (one
//!   word before the colon) is kept as a declaration ([`Table::comments`]).
//! - The columns are named by the last comment line before the data when it
//!   has as many words as a data row (what `fix ave/time` writes: `# TimeStep
//!   v_a c_b[2]`), or by a first non-comment line that is not all numbers
//!   (a `fix print` title without `#`). Names are kept as written (`v_time`).
//! - Values are separated by spaces or tabs; every row has one value per
//!   column; NaN and infinities are refused.
//! - Time is the column the caller names, else the first named `time`, `t`,
//!   `time_s` or `t_s` in any case, with or without LAMMPS' `v_` / `c_` /
//!   `f_` prefix ([`super::column_names`]). A step column (`TimeStep`) alone is
//!   not read as time: a value `fix ave/time` averaged over `N` steps belongs
//!   to the middle of its window, not to the step it is printed with; averaging
//!   `time` itself (`variable time equal time`) gives exactly that middle.
//! - A `# units: NAME` comment other than `si` is refused; without one the
//!   file is read as SI (`units si`), which the caller should say.
//!
//! Refused with the line: `fix ave/time` in vector mode (a `Row` column),
//! rows of the wrong length, text that is not a number, values separated by
//! `,` or `;` (a CSV file under another name).

use std::collections::BTreeMap;
use std::path::Path;

use super::column_names::time_column_index;
use super::csv::read_utf8;
use super::error::{RecordErrorKind, Result, SignalsError};
use super::table::{Table, TableFormat};
use super::trace::{Channel, TraceMetadata};

/// Reads `fix ave/time` / `fix print` text (see the module docs); the time
/// column is the one called `time_column` when given (exactly as written),
/// else the first of a time name.
pub fn read_lammps_text(path: &Path, time_column: Option<&str>) -> Result<Table> {
    let text = read_utf8(path)?;
    parse(&text, time_column)
        .map_err(|(line, kind)| SignalsError::Record {
            path: path.to_path_buf(),
            line,
            kind,
        })
        .map(|mut t| {
            t.path = path.to_path_buf();
            t
        })
}

type ParseError = (usize, RecordErrorKind);

fn parse(text: &str, time_column: Option<&str>) -> std::result::Result<Table, ParseError> {
    let mut lines = Lines::default();
    for (k, raw) in text.lines().enumerate() {
        let n = k + 1;
        let line = raw.trim();
        if line.is_empty() {
            continue;
        }
        match line.strip_prefix('#') {
            Some(body) => lines.comment(n, body.trim()),
            None => lines.data(n, line)?,
        }
    }
    lines.into_table(time_column)
}

/// The file as read so far, line by line.
#[derive(Default)]
struct Lines {
    /// Every `# key: value` comment.
    comments: BTreeMap<String, String>,
    /// The last comment line before the first row: its line and text.
    last_comment: Option<(usize, String)>,
    /// The column names, once known.
    names: Option<Vec<String>>,
    rows: Vec<Vec<f64>>,
    /// File line of each row.
    lines: Vec<usize>,
}

impl Lines {
    /// A comment line `# body`: kept as a declaration when it is `key: value`
    /// (one word before the colon), and as the candidate names line while no
    /// row has been read.
    fn comment(&mut self, n: usize, body: &str) {
        if let Some((key, value)) = body.split_once(':')
            && !key.trim().is_empty()
            && !key.trim().contains(char::is_whitespace)
        {
            self.comments
                .insert(key.trim().to_string(), value.trim().to_string());
        }
        if self.rows.is_empty() {
            self.last_comment = Some((n, body.to_string()));
        }
    }

    /// A line that is not a comment: a `fix print` title naming the columns,
    /// or a row of numbers (named by the last comment when nothing named the
    /// columns yet).
    fn data(&mut self, n: usize, line: &str) -> std::result::Result<(), ParseError> {
        for separator in [',', ';'] {
            if line.contains(separator) {
                return Err((n, RecordErrorKind::Separator { separator }));
            }
        }
        let tokens: Vec<&str> = line.split_whitespace().collect();
        if self.names.is_none() {
            let numeric = tokens.iter().all(|t| t.parse::<f64>().is_ok());
            if !numeric && self.rows.is_empty() {
                let names: Vec<String> = tokens.iter().map(|t| t.to_string()).collect();
                check_names(n, &names)?;
                self.names = Some(names);
                return Ok(());
            }
            self.names = Some(self.names_from_comment(n, tokens.len())?);
        }
        let header = self.names.as_deref().unwrap_or_default();
        let row = parse_row(n, &tokens, header)?;
        self.rows.push(row);
        self.lines.push(n);
        Ok(())
    }

    /// The names of the last comment line before the first row, which must
    /// have one word per value of that row (line `n`, `columns` values).
    fn names_from_comment(
        &self,
        n: usize,
        columns: usize,
    ) -> std::result::Result<Vec<String>, ParseError> {
        let from_comment = self.last_comment.as_ref().map(|(line, body)| {
            (
                *line,
                body.split_whitespace()
                    .map(str::to_string)
                    .collect::<Vec<_>>(),
            )
        });
        match from_comment {
            Some((line, words)) if words.first().is_some_and(|w| w == "Row") => {
                Err((line, RecordErrorKind::VectorMode))
            }
            Some((line, words)) if words.len() == columns => {
                check_names(line, &words)?;
                Ok(words)
            }
            _ => Err((
                n,
                RecordErrorKind::NoColumnNames {
                    columns,
                    last_comment: self
                        .last_comment
                        .as_ref()
                        .map(|(_, b)| b.clone())
                        .unwrap_or_default(),
                },
            )),
        }
    }

    /// The table: units checked, the time column picked.
    fn into_table(self, time_column: Option<&str>) -> std::result::Result<Table, ParseError> {
        if let Some(units) = self.comments.get("units")
            && !units.eq_ignore_ascii_case("si")
        {
            return Err((
                0,
                RecordErrorKind::NotSi {
                    units: units.clone(),
                },
            ));
        }
        let Some(names) = self.names else {
            return Err((0, RecordErrorKind::Empty));
        };
        if self.rows.is_empty() {
            return Err((0, RecordErrorKind::Empty));
        }
        let bare: Vec<&str> = names.iter().map(String::as_str).collect();
        let Some(time_index) = time_column_index(&bare, time_column) else {
            return Err((
                0,
                RecordErrorKind::NoTimeColumn {
                    given: time_column.map(str::to_string),
                    names: names.join(", "),
                },
            ));
        };
        let rows = &self.rows;
        let column = |j: usize| rows.iter().map(|r| r[j]).collect::<Vec<f64>>();
        let columns = (0..names.len())
            .filter(|&j| j != time_index)
            .map(|j| Channel {
                name: names[j].clone(),
                unit: String::new(),
                samples: column(j),
            })
            .collect();
        Ok(Table {
            path: Default::default(),
            format: TableFormat::LammpsText,
            time_column: names[time_index].clone(),
            time_s: column(time_index),
            columns,
            metadata: TraceMetadata::default(),
            comments: self.comments,
            lines: self.lines,
        })
    }
}

/// One row of values, one per column of `header`, each a finite number.
fn parse_row(
    n: usize,
    tokens: &[&str],
    header: &[String],
) -> std::result::Result<Vec<f64>, ParseError> {
    if tokens.len() != header.len() {
        return Err((
            n,
            RecordErrorKind::Ragged {
                expected: header.len(),
                got: tokens.len(),
            },
        ));
    }
    let mut row = Vec::with_capacity(tokens.len());
    for (token, column) in tokens.iter().zip(header) {
        let value: f64 = token.parse().map_err(|_| {
            (
                n,
                RecordErrorKind::NotANumber {
                    column: column.clone(),
                    text: token.to_string(),
                },
            )
        })?;
        if !value.is_finite() {
            return Err((
                n,
                RecordErrorKind::NonFinite {
                    column: column.clone(),
                    text: token.to_string(),
                },
            ));
        }
        row.push(value);
    }
    Ok(row)
}

/// Refuses a header of `fix ave/time` vector mode or with a name twice.
fn check_names(line: usize, names: &[String]) -> std::result::Result<(), ParseError> {
    if names.first().is_some_and(|n| n == "Row") {
        return Err((line, RecordErrorKind::VectorMode));
    }
    for (i, name) in names.iter().enumerate() {
        if names[..i].contains(name) {
            return Err((line, RecordErrorKind::DuplicateName { name: name.clone() }));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    const AVE_TIME: &str = "# vlab record\n# drive_freq_hz: 40\n# units: si\n\
        # Time-averaged data for fix record\n# TimeStep v_time v_enclosure_velocity v_particle_force_axial\n\
        25 1.2e-05 0.7746 -157.3\n50 3.7e-05 0.7745 -156.9\n75 6.2e-05 0.7743 -150\n";

    #[test]
    fn reads_fix_ave_time_output() {
        let t = parse(AVE_TIME, None).expect("parses");
        assert_eq!(t.time_column, "v_time");
        assert_eq!(t.time_s, vec![1.2e-5, 3.7e-5, 6.2e-5]);
        let names: Vec<&str> = t.columns.iter().map(|c| c.name.as_str()).collect();
        assert_eq!(
            names,
            ["TimeStep", "v_enclosure_velocity", "v_particle_force_axial"]
        );
        assert_eq!(t.columns[2].samples, vec![-157.3, -156.9, -150.0]);
        assert_eq!(t.comments["drive_freq_hz"], "40");
        assert_eq!(t.lines, vec![6, 7, 8]);
        assert!((t.uniform_step_s().expect("uniform") - 25e-6).abs() < 1e-15);
    }

    #[test]
    fn reads_fix_print_with_a_title_line() {
        let text = "time enclosure_velocity particle_force_axial\n0.0 1 2\n0.1 1 2\n\n0.2 1 3\n";
        let t = parse(text, None).expect("parses");
        assert_eq!(t.time_column, "time");
        assert_eq!(t.columns.len(), 2);
        assert_eq!(t.lines, vec![2, 3, 5]);
        let text = "# time v\t f\n0 1 2\n1 1 2\n";
        assert_eq!(parse(text, None).expect("tabs").columns[1].name, "f");
    }

    #[test]
    fn refusals_name_line_and_reason() {
        let err = |text: &str| {
            let (line, kind) = parse(text, None).expect_err("must fail");
            format!("line {line}: {kind}")
        };
        let e = err("# Fix print output for fix rec\n0 1 2\n1 1 2\n");
        assert!(e.starts_with("line 2") && e.contains("no names"), "{e}");
        let e = err("# TimeStep v_time v_f\n1 0 2\n2 0.1\n");
        assert!(e.starts_with("line 3") && e.contains("2 values"), "{e}");
        let e = err("# TimeStep v_time v_f\n1 0 2\n2 0.1 nan\n");
        assert!(e.contains("'nan' is not finite"), "{e}");
        let e = err("# TimeStep v_time v_f\n1 0 2\n2 0.1 x\n");
        assert!(e.contains("'x' is not a number"), "{e}");
        let e = err("# TimeStep v_f\n1 2\n2 3\n");
        assert!(
            e.contains("no time column") && e.contains("TimeStep, v_f"),
            "{e}"
        );
        let e = err("# Row c_1 c_2\n100 2\n1 0.5 0.5\n");
        assert!(e.contains("vector mode"), "{e}");
        let e = err("# units: metal\n# time f\n0 1\n1 2\n");
        assert!(e.contains("units metal"), "{e}");
        let e = err("time,force\n0,1\n");
        assert!(e.contains("','") && e.contains(".csv"), "{e}");
        let e = err("# only comments\n");
        assert!(e.contains("no data rows"), "{e}");
        let e = err("time f f\n0 1 2\n");
        assert!(e.contains("'f' appears twice"), "{e}");
    }

    #[test]
    fn time_is_found_by_its_names_or_the_name_given() {
        for name in ["t", "time", "Time", "TIME", "time_s", "v_time", "T_S"] {
            let text = format!("step {name} v\n1 0.0 2\n2 0.1 3\n");
            let t = parse(&text, None).unwrap_or_else(|e| panic!("{name}: {}", e.1));
            assert_eq!(t.time_column, name);
            assert_eq!(t.time_s, vec![0.0, 0.1]);
        }
        let text = "stamp v time\n0.0 2 5\n0.1 3 6\n";
        let t = parse(text, Some("stamp")).expect("given");
        assert_eq!(t.time_column, "stamp");
        let names: Vec<&str> = t.columns.iter().map(|c| c.name.as_str()).collect();
        assert_eq!(names, ["v", "time"]);
        let (_, kind) = parse(text, Some("clock")).expect_err("absent");
        let e = kind.to_string();
        assert!(
            e.contains("no column 'clock' (given as the time column)") && e.contains("stamp, v"),
            "{e}"
        );
        let (_, kind) = parse("zeit v\n0 1\n1 2\n", None).expect_err("unknown");
        let e = kind.to_string();
        assert!(
            e.contains("[zeit, v]") && e.contains("t, time, time_s or t_s"),
            "{e}"
        );
    }
}
