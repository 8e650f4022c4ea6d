//! A finished study read back from the files it wrote (`accuracy.csv` and
//! the `summary.json` beside it), so that its plots are redrawn from saved
//! data in a second instead of from minutes of DEM: `vlab plot
//! accuracy.csv` calls [`redraw_plots`]. Numbers come back with the bits
//! they were written with ([`super::rows_to_csv`] writes the shortest form
//! that round-trips), so a redrawn plot is the run's own, byte for byte.

use std::path::Path;

pub use super::PlotLabels;
use super::{AccuracyRow, CSV_HEADER};
use crate::experiment::saved_file::SavedFileError;

/// What a file read here should be, for errors.
const WHAT: &str = "a vlab accuracy study's file";

impl PlotLabels {
    /// From the text of a study's `summary.json` (`path` names it in
    /// errors); a number written as `null` (a NaN) reads as NaN.
    pub fn from_summary_json(text: &str, path: &Path) -> Result<Self, SavedFileError> {
        let invalid = |what: String| SavedFileError::Invalid {
            path: path.to_path_buf(),
            expected: WHAT,
            what,
        };
        let v: serde_json::Value =
            serde_json::from_str(text).map_err(|e| invalid(e.to_string()))?;
        let field = |pointer: &str| {
            v.pointer(pointer)
                .ok_or_else(|| invalid(format!("no {}", &pointer[1..])))
        };
        let number = |pointer: &str| -> Result<f64, SavedFileError> {
            let x = field(pointer)?;
            match x {
                serde_json::Value::Null => Ok(f64::NAN),
                _ => x
                    .as_f64()
                    .ok_or_else(|| invalid(format!("{} is not a number", &pointer[1..]))),
            }
        };
        let periods = field("/yang/baseline_record_periods")?
            .as_u64()
            .and_then(|n| u32::try_from(n).ok())
            .ok_or_else(|| invalid("yang/baseline_record_periods is not a count".into()))?;
        Ok(PlotLabels {
            scene: field("/scene")?
                .as_str()
                .ok_or_else(|| invalid("scene is not text".into()))?
                .to_string(),
            freq_hz: number("/plan/freq_hz")?,
            gamma: number("/plan/gamma")?,
            seed_spread_rel: number("/dem/seed_spread_rel")?,
            impact_speed_mps: number("/impact/speed_mps")?,
            baseline_record_periods: periods,
        })
    }
}

/// Whether `text` starts as an `accuracy.csv` does (its header line).
pub fn is_accuracy_csv(text: &str) -> bool {
    text.lines().next().map(str::trim_end) == Some(CSV_HEADER)
}

/// The rows of an `accuracy.csv`'s `text` (`path` names it in errors): the
/// inverse of [`super::rows_to_csv`], an empty number NaN.
pub fn rows_from_csv(text: &str, path: &Path) -> Result<Vec<AccuracyRow>, SavedFileError> {
    let invalid = |what: String| SavedFileError::Invalid {
        path: path.to_path_buf(),
        expected: WHAT,
        what,
    };
    if !is_accuracy_csv(text) {
        return Err(invalid(format!("its first line is not {CSV_HEADER}")));
    }
    let mut reader = csv::Reader::from_reader(text.as_bytes());
    let mut rows = Vec::new();
    for (k, record) in reader.records().enumerate() {
        let line = k + 2;
        let record = record.map_err(|e| invalid(format!("line {line}: {e}")))?;
        if record.len() != 10 {
            return Err(invalid(format!(
                "line {line}: {} fields, not 10",
                record.len()
            )));
        }
        let num = |i: usize| -> Result<f64, SavedFileError> {
            match record[i].trim() {
                "" => Ok(f64::NAN),
                x => x
                    .parse()
                    .map_err(|_| invalid(format!("line {line}: '{x}' is not a number"))),
            }
        };
        rows.push(AccuracyRow {
            study: record[0].to_string(),
            parameter: record[1].to_string(),
            value: num(2)?,
            quantity: record[3].to_string(),
            estimate: num(4)?,
            reference: num(5)?,
            error_rel: num(6)?,
            stderr_rel: num(7)?,
            wall_s: num(8)?,
            note: record[9].to_string(),
        });
    }
    Ok(rows)
}

/// Redraws the plots of the study whose `accuracy.csv` is `csv_path` (its
/// `summary.json` beside it) into `dir`, which must exist, as the run drew
/// them; returns the files written.
#[cfg(feature = "plot")]
pub fn redraw_plots(
    csv_path: &Path,
    dir: &Path,
) -> Result<Vec<std::path::PathBuf>, SavedFileError> {
    use crate::experiment::saved_file::read_text as read;
    let rows = rows_from_csv(&read(csv_path)?, csv_path)?;
    let summary_path = csv_path.with_file_name("summary.json");
    let labels = PlotLabels::from_summary_json(&read(&summary_path)?, &summary_path)?;
    let names = super::plots::write_plots(dir, &rows, &labels)?;
    Ok(names.into_iter().map(|n| dir.join(n)).collect())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::study::accuracy::rows_to_csv;

    fn row(study: &str, value: f64, stderr_rel: f64, note: &str) -> AccuracyRow {
        AccuracyRow {
            study: study.into(),
            parameter: "steady_cycles".into(),
            value,
            quantity: "energy_per_cycle_j".into(),
            estimate: 0.1 + value * 1e-17,
            reference: 0.3,
            error_rel: (0.1 + value * 1e-17) / 0.3 - 1.0,
            stderr_rel,
            wall_s: 1.0 / 3.0,
            note: note.into(),
        }
    }

    #[test]
    fn rows_read_back_bit_for_bit() {
        let rows = vec![
            row("dem", 2.0, f64::NAN, ""),
            row("yang", 1e-300, 0.1, "a note, with a comma and \"quotes\""),
        ];
        let path = Path::new("accuracy.csv");
        let back = rows_from_csv(&rows_to_csv(&rows), path).expect("reads");
        assert_eq!(back.len(), 2);
        for (a, b) in rows.iter().zip(&back) {
            assert_eq!(a.note, b.note);
            assert_eq!(a.error_rel.to_bits(), b.error_rel.to_bits());
            assert_eq!(a.wall_s.to_bits(), b.wall_s.to_bits());
            assert_eq!(a.value.to_bits(), b.value.to_bits());
        }
        assert!(back[0].stderr_rel.is_nan());
    }

    #[test]
    fn a_file_that_is_not_a_study_is_refused_by_name() {
        let path = Path::new("x.csv");
        let e = rows_from_csv("time_s,force_n\n0,1\n", path).expect_err("refused");
        assert!(e.to_string().contains("x.csv"), "{e}");
        let bad = format!("{CSV_HEADER}\ndem,seed,one,q,1,1,0,,1,\n");
        let e = rows_from_csv(&bad, path).expect_err("refused");
        assert!(e.to_string().contains("line 2: 'one'"), "{e}");
    }

    #[test]
    fn labels_read_a_nan_spread_as_nan_and_name_a_missing_field() {
        let text = r#"{"scene": "thesis", "plan": {"freq_hz": 40.0, "gamma": 20.0},
            "dem": {"seed_spread_rel": null}, "impact": {"speed_mps": 2.45},
            "yang": {"baseline_record_periods": 32}}"#;
        let path = Path::new("summary.json");
        let l = PlotLabels::from_summary_json(text, path).expect("reads");
        assert!(l.seed_spread_rel.is_nan());
        assert_eq!((l.freq_hz, l.baseline_record_periods), (40.0, 32));
        let e = PlotLabels::from_summary_json(&text.replace("speed_mps", "speed"), path)
            .expect_err("refused");
        assert!(e.to_string().contains("impact/speed_mps"), "{e}");
    }
}
