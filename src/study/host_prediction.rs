//! The host's steady response to a stepped sine predicted from a sweep's
//! dissipation map (describing function and harmonic balance,
//! [`crate::host::map_model`]), in milliseconds: the outcome `vlab host
//! predict` prints, with its `predict.csv` and `predict.json`.

use std::path::Path;
use std::time::Instant;

use crate::atomic_write::write_bytes_atomic;
use crate::host::map_model::{SteadyResponse, stepped_sine};
use crate::host::{DissipationMap, HostSpec};
use crate::scene::SceneError;

use super::dissipation_map::MapSource;
use super::sweep::SweepFile;
use crate::validation::{InvalidParameter, positive};

pub use crate::host::excitation::{MAX_FREQUENCIES, check_frequencies};

/// Checks a prediction's force (positive, N) and frequencies
/// ([`check_frequencies`]), naming `force_n` or `freqs_hz`.
pub fn check_request(freqs_hz: &[f64], force_n: f64) -> Result<(), InvalidParameter> {
    positive("force_n", force_n, "N")?;
    check_frequencies(freqs_hz)
}

/// A finished prediction: each frequency's response with its count of
/// roots, and the frequencies the map had to be extrapolated for.
pub struct HostPrediction {
    pub host: HostSpec,
    /// Where the map came from (the sweep's file), as the summary names it.
    pub map_label: String,
    pub source: MapSource,
    pub force_n: f64,
    /// The map's particle mass (kg), points and whether it measured the
    /// apparent mass.
    pub particle_mass_kg: f64,
    pub map_points: usize,
    pub has_apparent_mass: bool,
    /// Each frequency's steady response and how many roots it had.
    pub points: Vec<(SteadyResponse, usize)>,
    /// The map's words on each response outside it.
    pub warnings: Vec<String>,
    /// Where the map holds a branch of a carried sweep, what that means
    /// ([`HostPrediction::with_map_branch`]).
    pub branch_warning: Option<String>,
    pub elapsed_ms: f64,
}

impl HostPrediction {
    /// Predicts `host`'s response to `force_n` at each of `freqs_hz` with
    /// the damper of `map` (labelled `map_label`, of `source`'s efficiency).
    pub fn run(
        map: &DissipationMap,
        map_label: String,
        source: MapSource,
        host: HostSpec,
        freqs_hz: &[f64],
        force_n: f64,
    ) -> HostPrediction {
        let started = Instant::now();
        let points = stepped_sine(map, &host, freqs_hz, force_n);
        let elapsed_ms = started.elapsed().as_secs_f64() * 1e3;
        let warnings = points
            .iter()
            .filter_map(|(p, _)| map.outside(p.freq_hz, p.damper.gamma))
            .collect();
        HostPrediction {
            host,
            map_label,
            source,
            force_n,
            particle_mass_kg: map.particle_mass_kg,
            map_points: map.columns.iter().map(Vec::len).sum(),
            has_apparent_mass: map.has_apparent_mass(),
            points,
            warnings,
            branch_warning: None,
            elapsed_ms,
        }
    }

    /// The prediction with a warning first where the map (`file`, as
    /// [`super::dissipation_map::read_map_files`] read it) holds a branch
    /// of a carried sweep: its conditions came from the one before, not
    /// from the bed at rest, and the model's answer depends on it (at
    /// 40 Hz the up branch lifts the plate's 5 N flat top by up to 8 %,
    /// docs/host.md section 5).
    pub fn with_map_branch(mut self, file: &SweepFile) -> Self {
        if let Some(branch) = &file.header.carried {
            self.branch_warning = Some(format!(
                "the map holds the {branch} branch of a sweep carried in Gamma (`vlab sweep --up-down`): there its conditions started from the one before, not from the bed at rest, as a stepped sine that starts each frequency afresh does; the model answers for a bed on that branch"
            ));
        }
        self
    }

    /// Every warning: the map's branch first, then each response outside
    /// the map.
    pub fn all_warnings(&self) -> Vec<String> {
        self.branch_warning
            .iter()
            .chain(&self.warnings)
            .cloned()
            .collect()
    }

    /// `predict.csv`: one row per frequency.
    pub fn csv(&self) -> String {
        let mut csv = String::from(
            "freq_hz,amplitude_m,amplitude_low_m,amplitude_high_m,amplitude_if_more_damping_m,amplitude_if_less_damping_m,phase_rad,receptance_m_per_n,gamma,efficiency,efficiency_se,efficiency_low,efficiency_high,damping_n_s_per_m,apparent_mass_kg,damper_energy_per_cycle_j,extrapolated,roots\n",
        );
        for (p, roots) in &self.points {
            csv.push_str(&format!(
                "{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}\n",
                p.freq_hz,
                p.amplitude_m,
                p.amplitude_low_m,
                p.amplitude_high_m,
                p.amplitude_if_more_damping_m,
                p.amplitude_if_less_damping_m,
                p.phase_rad,
                p.amplitude_m / self.force_n,
                p.damper.gamma,
                p.damper.efficiency,
                p.damper.efficiency_se,
                p.damper.efficiency_low,
                p.damper.efficiency_high,
                p.damper.damping_n_s_per_m,
                p.damper.apparent_mass_kg,
                p.damper_energy_per_cycle_j,
                p.damper.extrapolated,
                roots
            ));
        }
        csv
    }

    /// `predict.json`: the host, the map, the force, the time taken, the
    /// warnings and every response.
    pub fn summary(&self) -> serde_json::Value {
        let points = self.points.iter();
        serde_json::json!({
            "host": self.host,
            "map": self.map_label,
            "source": match self.source { MapSource::Yang => "yang", MapSource::Dem => "dem" },
            "force_n": self.force_n,
            "elapsed_ms": self.elapsed_ms,
            "warnings": self.all_warnings(),
            "points": points.map(|(p, r)| serde_json::json!({"response": p, "roots": r})).collect::<Vec<_>>(),
        })
    }

    /// Writes `predict.csv` and `predict.json` into `dir` (made if need
    /// be), each file atomically.
    pub fn write(&self, dir: &Path) -> Result<(), SceneError> {
        let io = |path: std::path::PathBuf, text: std::io::Result<String>| {
            text.and_then(|t| write_bytes_atomic(&path, t.as_bytes()))
                .map_err(|source| SceneError::Write { path, source })
        };
        std::fs::create_dir_all(dir).map_err(|source| SceneError::Write {
            path: dir.to_path_buf(),
            source,
        })?;
        io(dir.join("predict.csv"), Ok(self.csv()))?;
        let json = serde_json::to_string_pretty(&self.summary()).map_err(std::io::Error::other);
        io(dir.join("predict.json"), json)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each refusal names its keyword; a good request passes.
    #[test]
    fn a_request_is_checked_and_a_refusal_names_its_keyword() {
        assert!(check_request(&[36.0, 39.0, 40.0], 5.0).is_ok());
        let said = |freqs: &[f64], force: f64| check_request(freqs, force).unwrap_err().to_string();
        assert!(said(&[40.0], -1.0).contains("force_n"));
        assert!(said(&[], 1.0).contains("between 1 and 1000"));
        assert!(said(&[0.0], 1.0).contains("freqs_hz"));
        assert!(said(&[6000.0], 1.0).contains("5000"));
        assert!(said(&[40.0, 39.0], 1.0).contains("ascending"));
        assert!(said(&[f64::NAN], 1.0).contains("freqs_hz"));
    }
}
