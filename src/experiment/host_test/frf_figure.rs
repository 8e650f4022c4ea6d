//! A stepped sine's receptance figure (`frf-magnitude.svg`): the damper on
//! its host against the empty host, the particles' mass as a solid and the
//! map-based model, in dB re 1 m/N. Drawn from a finished stepped sine
//! (`SteppedSineOutcome::magnitudes`), or again from the `frf.csv` and `frf.json` it
//! wrote ([`redraw_magnitude`], what `vlab plot frf.csv` does), so that a
//! figure of minutes of coupled DEM is redrawn in a second; both give the
//! same bytes (the CSV holds every number in its shortest round-trip form).

use std::path::Path;

use realfft::num_complex::Complex64;

use crate::experiment::host_test::Damper;
use crate::experiment::saved_file::SavedFileError;

/// The header of a stepped sine's `frf.csv`.
pub const STEPPED_SINE_CSV_HEADER: &str = "freq_hz,receptance_re_m_per_n,receptance_im_m_per_n,amplitude_m,gamma,true_amplitude_m,power_input_w,host_storage_w,damper_power_w,damper_power_stderr_w,damper_power_record_stderr_w,true_input_w,true_host_w,true_damper_work_w,true_damper_w,host_energy_drift_w,steady,empty_receptance_m_per_n,solid_receptance_m_per_n,predicted_receptance_m_per_n,yang_map_w";

/// What the figure draws: each curve's receptance magnitude (m/N) at its
/// frequencies (Hz), and what its title and legend name.
#[derive(Debug, Clone, PartialEq)]
pub struct FrfMagnitudes {
    pub host: String,
    pub force_n: f64,
    /// The damper's label ([`Damper::label`]).
    pub damper: String,
    pub empty: Vec<(f64, f64)>,
    pub solid: Vec<(f64, f64)>,
    pub measured: Vec<(f64, f64)>,
    /// The map-based model's, with maps.
    pub predicted: Option<Vec<(f64, f64)>>,
}

impl FrfMagnitudes {
    /// The curves a stepped sine's `frf.csv` text holds, with the host, the
    /// force and the damper of its `frf.json` text (`csv_path` and
    /// `json_path` name them in errors); no prediction when its column is
    /// empty throughout.
    pub fn read(
        csv: &str,
        csv_path: &Path,
        json: &str,
        json_path: &Path,
    ) -> Result<Self, SavedFileError> {
        let invalid = |path: &Path, what: String| SavedFileError::Invalid {
            path: path.to_path_buf(),
            expected: "a stepped sine's frf.csv and frf.json",
            what,
        };
        let mut lines = csv.lines();
        if lines.next().map(str::trim_end) != Some(STEPPED_SINE_CSV_HEADER) {
            return Err(invalid(csv_path, "not its header".into()));
        }
        let (mut empty, mut solid, mut measured, mut predicted) =
            (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        for (k, line) in lines.enumerate() {
            let cells: Vec<&str> = line.trim_end().split(',').collect();
            let num = |i: usize| -> Result<f64, SavedFileError> {
                let cell = cells.get(i).copied().unwrap_or("");
                cell.parse().map_err(|_| {
                    invalid(
                        csv_path,
                        format!("line {}, column {}: '{cell}' is not a number", k + 2, i + 1),
                    )
                })
            };
            let f = num(0)?;
            measured.push((f, Complex64::new(num(1)?, num(2)?).norm()));
            empty.push((f, num(17)?));
            solid.push((f, num(18)?));
            predicted.push((f, num(19)?));
        }
        let v: serde_json::Value =
            serde_json::from_str(json).map_err(|e| invalid(json_path, e.to_string()))?;
        let host = v
            .pointer("/host/name")
            .and_then(|h| h.as_str())
            .ok_or_else(|| invalid(json_path, "no host/name".into()))?;
        let force_n = v["force_n"]
            .as_f64()
            .ok_or_else(|| invalid(json_path, "no force_n".into()))?;
        let damper = match v.pointer("/damper/kind").and_then(|k| k.as_str()) {
            Some("particles") => Damper::Particles,
            Some("empty") => Damper::Empty,
            Some("solid") => Damper::Solid,
            Some("dashpot") => Damper::Dashpot {
                n_s_per_m: v
                    .pointer("/damper/n_s_per_m")
                    .and_then(|c| c.as_f64())
                    .ok_or_else(|| invalid(json_path, "a dashpot without n_s_per_m".into()))?,
            },
            other => {
                return Err(invalid(json_path, format!("damper kind {other:?}")));
            }
        };
        let has_prediction = predicted.iter().any(|p| !p.1.is_nan());
        Ok(FrfMagnitudes {
            host: host.to_string(),
            force_n,
            damper: damper.label(),
            empty,
            solid,
            measured,
            predicted: has_prediction.then_some(predicted),
        })
    }

    /// Draws the figure at `path` (SVG or PNG by its extension).
    #[cfg(feature = "plot")]
    pub fn draw(&self, path: &Path) -> Result<(), crate::scene::SceneError> {
        use crate::signals::{Series, SeriesStyle, plot_xy_svg};
        let db = |points: &[(f64, f64)]| -> Vec<(f64, f64)> {
            points.iter().map(|&(f, h)| (f, 20.0 * h.log10())).collect()
        };
        let line = |name: &str, points: &[(f64, f64)]| Series {
            name: name.into(),
            points: db(points),
            style: SeriesStyle::Line,
        };
        let mut series = vec![
            line("empty host", &self.empty),
            line("particles' mass as a solid", &self.solid),
            Series {
                name: format!("{} (coupled DEM)", self.damper),
                points: db(&self.measured),
                style: SeriesStyle::Points,
            },
        ];
        if let Some(p) = &self.predicted {
            series.push(line("map-based model", p));
        }
        plot_xy_svg(
            path,
            &format!(
                "Receptance at the damper, {} N at the drive, {}",
                self.force_n, self.host
            ),
            "frequency (Hz)",
            "|X / F| (dB re 1 m/N)",
            &series,
        )?;
        Ok(())
    }
}

/// Whether `text` starts as a stepped sine's `frf.csv` does.
pub fn is_stepped_sine_csv(text: &str) -> bool {
    text.lines().next().map(str::trim_end) == Some(STEPPED_SINE_CSV_HEADER)
}

/// Redraws `frf-magnitude.svg` of the stepped sine whose `frf.csv` is
/// `csv_path` (its `frf.json` beside it) into `dir`, which must exist, as
/// the run drew it; returns the file written.
#[cfg(feature = "plot")]
pub fn redraw_magnitude(csv_path: &Path, dir: &Path) -> Result<std::path::PathBuf, SavedFileError> {
    use crate::experiment::saved_file::read_text;
    let json_path = csv_path.with_file_name("frf.json");
    let curves = FrfMagnitudes::read(
        &read_text(csv_path)?,
        csv_path,
        &read_text(&json_path)?,
        &json_path,
    )?;
    let path = dir.join("frf-magnitude.svg");
    curves.draw(&path)?;
    Ok(path)
}

#[cfg(test)]
mod tests {
    use super::*;

    const JSON: &str = r#"{"host": {"name": "plate-40hz"}, "force_n": 5.0,
        "damper": {"kind": "dashpot", "n_s_per_m": 10.0}}"#;

    fn row(f: f64, predicted: &str) -> String {
        let mut cells = vec!["0".to_string(); 21];
        cells[0] = f.to_string();
        cells[1] = "3e-4".into();
        cells[2] = "-4e-4".into();
        cells[17] = "1e-3".into();
        cells[18] = "2e-3".into();
        cells[19] = predicted.into();
        cells.join(",")
    }

    #[test]
    fn a_saved_stepped_sine_reads_back_its_curves() {
        let csv = format!(
            "{STEPPED_SINE_CSV_HEADER}\n{}\n{}\n",
            row(39.0, "NaN"),
            row(39.5, "NaN")
        );
        let (c, j) = (Path::new("frf.csv"), Path::new("frf.json"));
        let m = FrfMagnitudes::read(&csv, c, JSON, j).expect("reads");
        assert_eq!(m.host, "plate-40hz");
        assert_eq!(m.damper, "dashpot 10 N s/m");
        assert_eq!(m.measured[1], (39.5, 5e-4));
        assert_eq!(m.solid[0], (39.0, 2e-3));
        assert_eq!(m.predicted, None, "an empty prediction column is none");
        let with = format!("{STEPPED_SINE_CSV_HEADER}\n{}\n", row(40.0, "7e-4"));
        let m = FrfMagnitudes::read(&with, c, JSON, j).expect("reads");
        assert_eq!(m.predicted, Some(vec![(40.0, 7e-4)]));
    }

    #[test]
    fn a_file_that_is_not_a_stepped_sine_is_refused_by_name() {
        let (c, j) = (Path::new("frf.csv"), Path::new("frf.json"));
        let random = "freq_hz,h1_re,h1_im\n1,2,3\n";
        let e = FrfMagnitudes::read(random, c, JSON, j).expect_err("refused");
        assert!(e.to_string().contains("frf.csv"), "{e}");
        let csv = format!("{STEPPED_SINE_CSV_HEADER}\n{}\n", row(40.0, "x"));
        let e = FrfMagnitudes::read(&csv, c, JSON, j).expect_err("refused");
        assert!(e.to_string().contains("line 2, column 20: 'x'"), "{e}");
        let csv = format!("{STEPPED_SINE_CSV_HEADER}\n{}\n", row(40.0, "1"));
        let e = FrfMagnitudes::read(&csv, c, "{}", j).expect_err("refused");
        assert!(e.to_string().contains("host/name"), "{e}");
    }
}
