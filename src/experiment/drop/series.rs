//! A drop test from one or several heights (thesis Section 7.3) as one
//! outcome: each height's drop ([`run_drop`]) and the lab's estimate of its
//! restitution (eq. 7.3-7.5), what cannot be trusted said as warnings (an
//! impact above the yield velocity of eq. 5.26, a record clipped at the
//! ADC's full scale, a triple whose second gap outgrew the first), the
//! summary ([`summarise_drops`]), and the files a lab keeps of it
//! ([`DropSeries::write`]). `vlab drop` and Python's `vlab.drop` run it
//! alike and print or return what it holds.

use std::path::{Path, PathBuf};

use rayon::prelude::*;

use crate::atomic_write::write_bytes_atomic;
use crate::experiment::drop::{
    DROP_FRICTION, DROP_GRAVITY_MPS2, DropEstimate, DropNumerics, DropOutcome, DropParticle,
    DropSetup, DropSummary, millimetres, run_drop, summarise_drops,
};
use crate::rig::DropRigSpec;
use crate::scene::SceneError;
use crate::scene::validity::yield_warning;
use crate::signals::{ImpactParams, SignalsError, write_csv, write_wav};
use crate::validation::InvalidParameter;
use crate::warning::RunWarning;

/// A drop series as a user asks for it: a preset sphere (its restitution
/// unless `restitution` is given), its diameter, the heights, the rig and
/// its sample rate, the seed.
#[derive(Debug, Clone)]
pub struct DropRequest {
    pub particle: DropParticle,
    pub restitution: Option<f64>,
    pub diameter_m: f64,
    pub heights_m: Vec<f64>,
    pub rig: DropRigSpec,
    /// The DAQ's rate instead of the rig's (Hz).
    pub sample_rate_hz: Option<f64>,
    pub seed: u64,
}

impl DropRequest {
    /// Each height's drop, every value checked before any work: a refusal
    /// names the setup's key (`diameter_m`, `restitution`, `height_m`,
    /// `daq.sample_rate_hz`), for each front end to name its own input.
    pub fn setups(&self) -> Result<Vec<DropSetup>, SceneError> {
        let mut rig = self.rig.clone();
        if let Some(fs) = self.sample_rate_hz {
            rig.daq.sample_rate_hz = fs;
        }
        let fs = rig.daq.sample_rate_hz;
        if fs.fract() != 0.0 || fs > 1e6 {
            return Err(InvalidParameter::new(
                "daq.sample_rate_hz",
                fs,
                "Hz",
                "a whole number of hertz, at most 1000000 (the record is also written as WAV)",
            )
            .into());
        }
        let mut seen = Vec::new();
        for &h in &self.heights_m {
            if seen.contains(&millimetres(h)) {
                return Err(InvalidParameter::new(
                    "height_m",
                    h,
                    "m",
                    "given once (to the micrometre): it is listed twice",
                )
                .into());
            }
            seen.push(millimetres(h));
        }
        if self.heights_m.is_empty() {
            return Err(InvalidParameter::new("height_m", "[]", "", "at least one height").into());
        }
        let p = self.particle;
        self.heights_m
            .iter()
            .map(|&height_m| {
                let s = DropSetup {
                    particle_name: p.name().to_string(),
                    material: p.material(),
                    diameter_m: self.diameter_m,
                    restitution: self.restitution.unwrap_or(p.restitution()),
                    friction: DROP_FRICTION,
                    height_m,
                    rig: rig.clone(),
                    gravity_mps2: DROP_GRAVITY_MPS2,
                    seed: self.seed,
                    numerics: DropNumerics::default(),
                };
                s.validate()?;
                Ok(s)
            })
            .collect()
    }
}

/// The drop that asks most of the sampling (the highest) and, if its
/// record cannot resolve the impacts, the warning, naming the sample rate
/// `rate_name` as the caller's input is called.
pub fn sampling_warning(
    setups: &[DropSetup],
    rate_name: &str,
) -> Result<Option<RunWarning>, SceneError> {
    match setups
        .iter()
        .max_by(|x, y| x.height_m.total_cmp(&y.height_m))
    {
        Some(s) => s.sampling_warning_naming(rate_name),
        None => Ok(None),
    }
}

/// Why a drop series stopped, naming the height (the causes boxed: they
/// are large, and rare).
#[derive(Debug, thiserror::Error)]
pub enum DropSeriesError {
    #[error("dropping from {height_m} m")]
    Drop {
        height_m: f64,
        #[source]
        source: Box<SceneError>,
    },
    #[error(
        "height {height_m} m: estimating the restitution from the force record ({contacts} DEM contacts)"
    )]
    Estimate {
        height_m: f64,
        contacts: usize,
        #[source]
        source: Box<SignalsError>,
    },
    #[error(transparent)]
    Scene(Box<SceneError>),
}

impl From<SceneError> for DropSeriesError {
    fn from(e: SceneError) -> Self {
        DropSeriesError::Scene(Box::new(e))
    }
}

/// A finished drop series: the drops, each height's run and estimate, and
/// their summary (its warnings included).
pub struct DropSeries {
    pub setups: Vec<DropSetup>,
    pub runs: Vec<(DropOutcome, DropEstimate)>,
    pub summary: DropSummary,
}

impl DropSeries {
    /// Drops the sphere of `setups` (checked by the caller, at least one)
    /// from each height, the heights side by side on the machine's threads,
    /// and estimates each record's restitution with `params`; `material`
    /// names the sphere's material, `warnings` are the caller's (the
    /// sampling's, named by its own flags).
    pub fn run(
        setups: Vec<DropSetup>,
        params: &ImpactParams,
        material: &'static str,
        mut warnings: Vec<RunWarning>,
    ) -> Result<Self, DropSeriesError> {
        let runs = setups
            .par_iter()
            .map(|s| {
                let out = run_drop(s).map_err(|e| DropSeriesError::Drop {
                    height_m: s.height_m,
                    source: Box::new(e),
                })?;
                let est = out.estimate(params, s.gravity_mps2).map_err(|e| {
                    DropSeriesError::Estimate {
                        height_m: s.height_m,
                        contacts: out.impacts.len(),
                        source: Box::new(e),
                    }
                })?;
                Ok((out, est))
            })
            .collect::<Result<Vec<_>, DropSeriesError>>()?;
        warnings.extend(untrusted(&setups, &runs));
        let summary = summarise_drops(&setups, &runs, material, warnings)?;
        Ok(DropSeries {
            setups,
            runs,
            summary,
        })
    }

    /// `results.csv`: a row per triple of every height.
    pub fn results_csv(&self) -> String {
        let mut csv = String::from(
            "height [m],triple [],impact speed [m/s],cor [],realised model cor [],height cor mean [],height cor std []\n",
        );
        for r in &self.summary.runs {
            for (k, (c, v)) in r
                .cor_per_triple
                .iter()
                .zip(&r.impact_speeds_mps)
                .enumerate()
            {
                let realised = r.realised_model_cor_per_triple[k]
                    .map(|x| x.to_string())
                    .unwrap_or_default();
                csv.push_str(&format!(
                    "{},{},{},{},{},{},{}\n",
                    r.height_m,
                    k + 1,
                    v,
                    c,
                    realised,
                    r.cor_mean,
                    r.cor_std
                ));
            }
        }
        csv
    }

    /// `drop.json`: the summary, as `vlab drop --json` prints it.
    pub fn summary_json(&self) -> String {
        serde_json::to_string_pretty(&self.summary).unwrap_or_default() + "\n"
    }

    /// Writes each height's force record (`force-h<mm>mm.csv` and `.wav`
    /// with its sidecar), `results.csv`, with plots `cor-vs-speed.svg` and
    /// `.png` (COR against impact speed, thesis Fig. 7.5), and `drop.json`
    /// into `dir`, which must exist, each file atomically.
    pub fn write(&self, dir: &Path) -> Result<(), SceneError> {
        for (r, (out, _)) in self.summary.runs.iter().zip(&self.runs) {
            write_csv(&dir.join(&r.files[0]), &out.trace)?;
            write_wav(&dir.join(&r.files[1]), &out.trace)?;
        }
        write_text(dir.join("results.csv"), &self.results_csv())?;
        #[cfg(feature = "plot")]
        self.plot(dir)?;
        write_text(dir.join("drop.json"), &self.summary_json())
    }

    /// `cor-vs-speed.svg` and `.png`: each height's estimates against the
    /// middle impact's speed, the model's realised and the configured
    /// restitution as lines.
    #[cfg(feature = "plot")]
    fn plot(&self, dir: &Path) -> Result<(), SceneError> {
        use crate::experiment::drop::millimetres;
        use crate::signals::{Series, SeriesStyle, plot_xy_svg_spanning};
        let s = &self.summary;
        let mut series: Vec<Series> = s
            .runs
            .iter()
            .map(|r| Series {
                name: format!("estimate, {} mm drop", millimetres(r.height_m)),
                points: r
                    .impact_speeds_mps
                    .iter()
                    .copied()
                    .zip(r.cor_per_triple.iter().copied())
                    .collect(),
                style: SeriesStyle::Points,
            })
            .collect();
        let lo = s
            .impact_speeds_mps
            .iter()
            .copied()
            .fold(f64::INFINITY, f64::min);
        let hi = s.impact_speeds_mps.iter().copied().fold(0.0, f64::max);
        if let Some(r) = s.realised_model_cor {
            series.push(Series {
                name: format!("realised by the model, {r:.4}"),
                points: vec![(lo, r), (hi, r)],
                style: SeriesStyle::Line,
            });
        }
        series.push(Series {
            name: format!("configured e = {}", s.configured_cor),
            points: vec![(lo, s.configured_cor), (hi, s.configured_cor)],
            style: SeriesStyle::Line,
        });
        let title = format!(
            "{} on {}: COR vs impact velocity (Fig. 7.5)",
            s.particle, s.rig
        );
        for ext in ["svg", "png"] {
            plot_xy_svg_spanning(
                &dir.join(format!("cor-vs-speed.{ext}")),
                &title,
                "impact velocity of the middle impact (m/s)",
                "COR = T(k+1,k+2) / T(k,k+1)",
                &series,
                COR_AXIS_SPAN,
            )?;
        }
        Ok(())
    }
}

/// The restitution axis of `cor-vs-speed` spans at least this much.
#[cfg(feature = "plot")]
const COR_AXIS_SPAN: f64 = 0.05;

/// What the drops' records cannot be trusted for: an impact above the
/// yield velocity, a record clipped at the ADC's full scale, a triple whose
/// second gap outgrew the first (a missed impact, or ringing taken for one).
fn untrusted(setups: &[DropSetup], runs: &[(DropOutcome, DropEstimate)]) -> Vec<RunWarning> {
    let mut warnings = Vec::new();
    let yield_mps = setups.first().and_then(DropSetup::yield_velocity_mps);
    for (s, (out, _)) in setups.iter().zip(runs) {
        let fastest = out
            .impacts
            .iter()
            .map(|d| d.arrival_speed_mps)
            .fold(0.0, f64::max);
        if let Some(w) = yield_mps.and_then(|vy| yield_warning(&s.pair_label(), fastest, vy)) {
            warnings.push(format!("height {} m: {w}", s.height_m).into());
        }
        if out.rig_report.clipped > 0 {
            warnings.push(
                format!(
                    "height {} m: {} samples clipped at the ADC's full scale ({:.1} N): the record is distorted",
                    s.height_m, out.rig_report.clipped, out.rig_report.full_scale_n
                )
                .into(),
            );
        }
    }
    for (s, (_, est)) in setups.iter().zip(runs) {
        let grown = est.result.cor.growing_gaps();
        if !grown.is_empty() {
            warnings.push(RunWarning::from(format!(
                "height {} m: triple(s) {} have a second gap longer than the first (COR > 1): an \
                 impact was missed or ringing taken for one; that estimate is not to be trusted \
                 (try a lower --threshold-n)",
                s.height_m,
                grown
                    .iter()
                    .map(|k| (k + 1).to_string())
                    .collect::<Vec<_>>()
                    .join(", ")
            )));
        }
    }
    warnings
}

/// Writes `text` to `path` atomically, or says which file it could not.
fn write_text(path: PathBuf, text: &str) -> Result<(), SceneError> {
    write_bytes_atomic(&path, text.as_bytes()).map_err(|source| SceneError::Write { path, source })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::experiment::drop::DropParticle;

    #[test]
    fn a_series_keeps_every_triple_and_says_what_cannot_be_trusted() {
        // Two heights of the smooth acrylic sphere on the drop rig, one
        // sampled at 20 kHz: its ring is above the Nyquist frequency and
        // triples grow (a missed impact), which the series says per height.
        let mut coarse = DropSetup::preset(DropParticle::AcrylicSmooth, 0.05).expect("preset");
        coarse.rig.daq.sample_rate_hz = 20_000.0;
        let fine = DropSetup::preset(DropParticle::AcrylicSmooth, 0.02).expect("preset");
        let material = DropParticle::AcrylicSmooth.material_name();
        let series = DropSeries::run(
            vec![fine, coarse],
            &ImpactParams::default(),
            material,
            vec![],
        )
        .expect("runs");
        let triples: usize = series
            .summary
            .runs
            .iter()
            .map(|r| r.cor_per_triple.len())
            .sum();
        assert!(triples >= 10, "{triples}");
        assert_eq!(series.results_csv().lines().count(), 1 + triples);
        let grown: Vec<&str> = series
            .summary
            .warnings
            .iter()
            .map(|w| w.text.as_str())
            .filter(|w| w.contains("second gap longer"))
            .collect();
        assert!(
            grown.iter().all(|w| w.starts_with("height 0.05 m")) && !grown.is_empty(),
            "{grown:?}"
        );
        let json: serde_json::Value = serde_json::from_str(&series.summary_json()).expect("JSON");
        assert_eq!(json["runs"].as_array().map(Vec::len), Some(2));
    }
}
