//! Records written by other programs: a time column and named columns, such
//! as a DEM code's output of the enclosure's motion and the force on it. No
//! thesis equation lives here; this is the container `vlab replay` reads.
//!
//! A [`Table`] keeps the time column as written: unlike a [`super::Trace`] it
//! is not assumed to be uniformly sampled, so that a record with a missing
//! stretch or a time axis that runs backwards (two runs concatenated, a
//! restart) can be refused with the line at fault rather than misread.
//! [`Table::uniform_step_s`] is that check. Read one with `read_table`
//! (`table_file.rs`): a CSV through the CSV reader (`csv.rs`), the text
//! LAMMPS and LIGGGHTS write through `lammps.rs`.
//!
//! The time column is the one the caller names, else the first whose name is
//! a time name (`t`, `time`, `Time`, `TIME`, `time_s`, `v_time`, a CSV's
//! `time [s]`): [`super::column_names::time_column_index`] decides it for
//! both readers.
//!
//! Units are SI; a CSV column's unit is its header's `[unit]`, a LAMMPS
//! column has none (the file's `# units:` comment, when present, says which
//! LAMMPS unit system wrote it, and only `si` is read).
//!
//! This file is the type alone: the readers import it, it imports neither.

use std::collections::BTreeMap;
use std::path::PathBuf;

use super::error::{RecordErrorKind, Result, SignalsError};
use super::trace::{Channel, TraceMetadata};

/// How far one time step may be from the record's step, as a fraction of it.
/// A missing row is a deviation of 1 (100 %); the default `%g` format of
/// LAMMPS' `fix ave/time` (6 significant digits) rounds 25 us steps near
/// 0.5 s by up to 4 %.
pub const STEP_REL_TOL: f64 = 0.2;

/// Which reader made a [`Table`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TableFormat {
    /// A CSV file ([`super::csv`]).
    Csv,
    /// LAMMPS / LIGGGHTS `fix ave/time` or `fix print` text ([`super::lammps`]).
    LammpsText,
}

impl TableFormat {
    /// The format's name, for reports.
    pub fn as_str(self) -> &'static str {
        match self {
            TableFormat::Csv => "csv",
            TableFormat::LammpsText => "lammps-text",
        }
    }
}

/// A record of named columns against a time column, as read.
#[derive(Debug, Clone, PartialEq)]
pub struct Table {
    /// The file it came from.
    pub path: PathBuf,
    /// Which reader read it.
    pub format: TableFormat,
    /// The time column's name as written (`time [s]`, `v_time`).
    pub time_column: String,
    /// Time of each row, s.
    pub time_s: Vec<f64>,
    /// The other columns, in file order (unit empty when the file gives none).
    pub columns: Vec<Channel>,
    /// A vlab CSV's `# metadata:` (default otherwise).
    pub metadata: TraceMetadata,
    /// Every other `# key: value` comment of the file, as text.
    pub comments: BTreeMap<String, String>,
    /// One-based file line of each row, for messages.
    pub lines: Vec<usize>,
}

impl Table {
    /// Number of rows.
    pub fn len(&self) -> usize {
        self.time_s.len()
    }

    /// True when the table has no rows.
    pub fn is_empty(&self) -> bool {
        self.time_s.is_empty()
    }

    /// The column called `name` (exactly as written), if any.
    pub fn column(&self, name: &str) -> Option<&Channel> {
        self.columns.iter().find(|c| c.name == name)
    }

    /// A number the file declares: the metadata's `drive_freq_hz` or `gamma`,
    /// a numeric entry of its `extra`, or a `# key: value` comment. A comment
    /// that is not a number is refused, naming the key.
    pub fn declared_f64(&self, key: &str) -> Result<Option<f64>> {
        let from_metadata = match key {
            "drive_freq_hz" => self.metadata.drive_freq_hz,
            "gamma" => self.metadata.gamma,
            _ => self.metadata.extra.get(key).and_then(|v| v.as_f64()),
        };
        if from_metadata.is_some() {
            return Ok(from_metadata);
        }
        match self.comments.get(key) {
            None => Ok(None),
            Some(text) => match text.trim().parse::<f64>() {
                Ok(x) if x.is_finite() => Ok(Some(x)),
                _ => Err(self.error(
                    0,
                    RecordErrorKind::BadComment {
                        key: key.to_string(),
                        text: text.clone(),
                    },
                )),
            },
        }
    }

    /// A text the file declares: a string entry of the metadata's `extra` or
    /// a `# key: value` comment.
    pub fn declared_text(&self, key: &str) -> Option<String> {
        self.metadata
            .extra
            .get(key)
            .and_then(|v| v.as_str().map(str::to_string))
            .or_else(|| self.comments.get(key).cloned())
    }

    /// The record's time step, s: checks that there are at least two rows,
    /// that time increases strictly, and that every step is the record's
    /// step within [`STEP_REL_TOL`] (no missing rows, no irregular sampling).
    /// The step is `(t_last - t_first) / (rows - 1)`.
    pub fn uniform_step_s(&self) -> Result<f64> {
        let t = &self.time_s;
        if t.len() < 2 {
            return Err(self.error(0, RecordErrorKind::TooFewRows { got: t.len() }));
        }
        for i in 1..t.len() {
            if t[i] <= t[i - 1] {
                return Err(self.error(
                    self.lines[i],
                    RecordErrorKind::TimeNotIncreasing {
                        time_s: t[i],
                        previous_s: t[i - 1],
                    },
                ));
            }
        }
        // The typical step: the median, which one gap cannot move.
        let mut steps: Vec<f64> = t.windows(2).map(|w| w[1] - w[0]).collect();
        steps.sort_by(f64::total_cmp);
        let typical = steps[steps.len() / 2];
        for i in 1..t.len() {
            let step = t[i] - t[i - 1];
            if (step - typical).abs() > STEP_REL_TOL * typical {
                return Err(self.error(
                    self.lines[i],
                    RecordErrorKind::IrregularStep {
                        time_s: t[i],
                        step_s: step,
                        typical_s: typical,
                    },
                ));
            }
        }
        let n = t.len();
        let step = (t[n - 1] - t[0]) / (n - 1) as f64;
        if let Some(i) = (0..n).find(|&i| (t[i] - (t[0] + i as f64 * step)).abs() > 0.5 * step) {
            return Err(self.error(
                self.lines[i],
                RecordErrorKind::IrregularStep {
                    time_s: t[i],
                    step_s: t[i] - t[i - 1],
                    typical_s: step,
                },
            ));
        }
        Ok(step)
    }

    /// An error about this table's file at `line` (0: the whole file).
    pub fn error(&self, line: usize, kind: RecordErrorKind) -> SignalsError {
        SignalsError::Record {
            path: self.path.clone(),
            line,
            kind,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn table(time_s: Vec<f64>) -> Table {
        let n = time_s.len();
        Table {
            path: PathBuf::from("r.txt"),
            format: TableFormat::LammpsText,
            time_column: "time".into(),
            time_s,
            columns: Vec::new(),
            metadata: TraceMetadata::default(),
            comments: BTreeMap::new(),
            lines: (1..=n).collect(),
        }
    }

    #[test]
    fn uniform_time_gives_its_step() {
        let t: Vec<f64> = (0..1000).map(|i| 12e-6 + i as f64 * 25e-6).collect();
        let step = table(t).uniform_step_s().expect("uniform");
        assert!((step - 25e-6).abs() < 1e-15);
        // Six significant digits, as LAMMPS' default %g prints them.
        let t: Vec<f64> = (0..40_000)
            .map(|i| format!("{:.6}", 0.5 + i as f64 * 25e-6).parse().unwrap())
            .collect();
        assert!(table(t).uniform_step_s().is_ok());
    }

    #[test]
    fn gaps_and_backward_time_are_refused_with_their_line() {
        let mut t: Vec<f64> = (0..100).map(|i| i as f64 * 1e-3).collect();
        t.remove(40);
        let err = table(t).uniform_step_s().expect_err("gap").to_string();
        assert!(
            err.contains("line 41") && err.contains("0.041 s") && err.contains("2.0000e-3 s"),
            "{err}"
        );
        let mut t: Vec<f64> = (0..100).map(|i| i as f64 * 1e-3).collect();
        t[60] = 0.01;
        let err = table(t).uniform_step_s().expect_err("back").to_string();
        assert!(err.contains("line 61") && err.contains("increase"), "{err}");
        let err = table(vec![0.0]).uniform_step_s().expect_err("short");
        assert!(err.to_string().contains("1 row"), "{err}");
    }

    #[test]
    fn declared_numbers_from_metadata_or_comments() {
        let mut t = table(vec![0.0, 1.0]);
        t.metadata.drive_freq_hz = Some(40.0);
        t.comments.insert("gamma".into(), "20".into());
        t.comments.insert("particle_mass_kg".into(), "heavy".into());
        assert_eq!(t.declared_f64("drive_freq_hz").unwrap(), Some(40.0));
        assert_eq!(t.declared_f64("gamma").unwrap(), Some(20.0));
        assert_eq!(t.declared_f64("orientation").unwrap(), None);
        let err = t.declared_f64("particle_mass_kg").expect_err("text");
        assert!(err.to_string().contains("'heavy'"), "{err}");
    }
}
