//! `vlab drop`: the drop test of thesis Section 7.3. A sphere released from
//! one or several heights bounces on the drop rig's plate; the transducer's
//! force is recorded at 200 kHz (or `--sample-rate-hz`); the lab's estimator
//! (eq. 7.3-7.5) turns the gaps between impacts into restitution, which is set
//! beside what the DEM contact really did.
//!
//! Writes into the output folder (default `signals/drop-<particle>/`):
//! `force-h<mm>mm.csv` and `.wav` (+ `.wav.json` sidecar) per height, the force
//! record; `results.csv`, one row per triple; `cor-vs-speed.svg`, COR against
//! impact speed (thesis Fig. 7.5); `drop.json`, the summary (`--json` prints
//! it). Everything is checked before the first drop; nothing is written if a
//! drop or its estimate fails.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use clap::{Args, ValueEnum};
use rayon::prelude::*;
use serde::Serialize;

use vlab::atomic_write::{OutputDir, write_atomic, write_bytes_atomic};
use vlab::rig::{DROP_RIG, DropRigSpec, RigFile};
use vlab::scene::drop::{
    DROP_FRICTION, DROP_GRAVITY_MPS2, DemImpact, DropEstimate, DropNumerics, DropOutcome,
    DropParticle, DropSetup, run_drop,
};
use vlab::scene::validity::yield_warning;
use vlab::signals::{ImpactParams, Series, SeriesStyle, plot_xy_svg, write_csv, write_wav};

use super::args;

/// The built-in particles.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum ParticleArg {
    /// Smooth acrylic, e = 0.91 (thesis Fig. 7.5).
    AcrylicSmooth,
    /// 3D-printed acrylic, e = 0.83 (thesis Fig. 7.5).
    AcrylicPrinted,
    /// Hardened steel, e = 0.90 (yields above 0.30 m/s on the plate).
    Steel,
}

impl ParticleArg {
    fn preset(self) -> DropParticle {
        match self {
            ParticleArg::AcrylicSmooth => DropParticle::AcrylicSmooth,
            ParticleArg::AcrylicPrinted => DropParticle::AcrylicPrinted,
            ParticleArg::Steel => DropParticle::Steel,
        }
    }
}

#[derive(Debug, Clone, Args)]
#[command(allow_negative_numbers = true)]
pub struct DropArgs {
    /// Release height: gap between the sphere's bottom and the plate (m).
    #[arg(long = "height-m", value_name = "M", default_value = "0.05", value_parser = args::metres)]
    pub height_m: f64,
    /// Several release heights (m), comma-separated, one record each; replaces --height-m.
    #[arg(long, value_name = "M,M,...", value_delimiter = ',', value_parser = args::metres, conflicts_with = "height_m")]
    pub heights: Option<Vec<f64>>,
    /// The sphere.
    #[arg(long, value_enum, default_value = "acrylic-smooth")]
    pub particle: ParticleArg,
    /// Coefficient of restitution e of the sphere on the plate, in (0, 1] [default: the particle's].
    #[arg(long, value_parser = args::restitution)]
    pub cor: Option<f64>,
    /// Sphere diameter (m).
    #[arg(long = "diameter-m", value_name = "M", default_value = "0.005", value_parser = args::metres)]
    pub diameter_m: f64,
    /// Sample rate of the force record (Hz) [default: the rig's, 200000].
    #[arg(long = "sample-rate-hz", value_name = "HZ", value_parser = args::sample_rate_hz)]
    pub sample_rate_hz: Option<f64>,
    /// Drop rig file (TOML) [default: the built-in drop-test rig].
    #[arg(long, value_name = "FILE")]
    pub rig: Option<PathBuf>,
    /// Impact detection threshold (N) [default: 10 % of the largest peak].
    #[arg(long = "threshold-n", value_name = "N", value_parser = args::newtons)]
    pub threshold_n: Option<f64>,
    /// No re-trigger for this long after an impact starts (s), to ignore ringing [default: 0.002].
    #[arg(long = "holdoff-s", value_name = "S", value_parser = args::non_negative_seconds)]
    pub holdoff_s: Option<f64>,
    /// Seed of the transducer noise.
    #[arg(long, default_value = "1")]
    pub seed: u64,
    /// Output folder [default: signals/drop-<particle>].
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Print the summary as JSON on standard output.
    #[arg(long)]
    pub json: bool,
}

/// One height's record and what was made of it.
#[derive(Debug, Serialize)]
struct RunSummary {
    height_m: f64,
    /// `sqrt(2 g h)`, m/s.
    first_impact_speed_mps: f64,
    /// Hertz contact duration at the first impact (eq. 5.10), s.
    contact_duration_s: f64,
    impacts_detected: usize,
    onset_times_s: Vec<f64>,
    /// COR of each triple (eq. 7.5).
    cor_per_triple: Vec<f64>,
    /// Speed at the middle impact of each triple (eq. 7.3), m/s.
    impact_speeds_mps: Vec<f64>,
    cor_mean: f64,
    cor_std: f64,
    /// DEM restitution (bounce) of each triple's middle impact.
    realised_model_cor_per_triple: Vec<Option<f64>>,
    realised_model_cor: Option<f64>,
    /// Triples whose gaps grew (a missed or false impact).
    growing_gap_triples: Vec<usize>,
    threshold_n: f64,
    holdoff_s: f64,
    peak_transducer_force_n: f64,
    clipped_samples: u64,
    /// Every contact the DEM resolved.
    dem_impacts: Vec<DemImpact>,
    rest_time_s: Option<f64>,
    tick_s: f64,
    dem_steps: u64,
    fine_steps: u64,
    wall_time_s: f64,
    files: Vec<String>,
}

#[derive(Debug, Serialize)]
struct DropSummary {
    vlab_version: &'static str,
    particle: String,
    material: &'static str,
    diameter_m: f64,
    /// The contact law's configured restitution (exact mode).
    configured_cor: f64,
    rig: String,
    sample_rate_hz: f64,
    gravity_mps2: f64,
    seed: u64,
    /// Mean of every triple's COR over all heights.
    cor_mean: f64,
    /// Sample standard deviation of the same.
    cor_std: f64,
    cor_per_triple: Vec<f64>,
    /// Speed at each triple's middle impact, m/s.
    impact_speeds_mps: Vec<f64>,
    /// Heights of each triple, m.
    heights_m: Vec<f64>,
    /// Mean DEM restitution of the triples' middle impacts: the sphere's own
    /// rebound / impact speed (eq. 7.2).
    realised_model_cor: Option<f64>,
    realised_model_cor_per_triple: Vec<Option<f64>>,
    /// The same relative to the moving plate: the contact law's restitution.
    realised_contact_cor: Option<f64>,
    /// `cor_mean / realised_model_cor - 1`.
    cor_error_rel: Option<f64>,
    /// Yield velocity of the sphere on the plate (eq. 5.26), m/s.
    yield_velocity_mps: Option<f64>,
    /// Lowest accepted sample rate: one sample per first pulse, Hz.
    min_sample_rate_hz: f64,
    warnings: Vec<String>,
    runs: Vec<RunSummary>,
    files: Vec<String>,
}

/// Text for a height in a file name: 0.05 -> "50", 0.0125 -> "12.5".
fn millimetres(h_m: f64) -> String {
    format!("{}", (h_m * 1e6).round() / 1e3)
}

/// The flag the heights came from.
fn height_flag(a: &DropArgs) -> &'static str {
    if a.heights.is_some() {
        "--heights"
    } else {
        "--height-m"
    }
}

/// The set-up keys these flags set.
fn flag_keys(a: &DropArgs) -> args::FlagKeys {
    args::FlagKeys::new()
        .set(true, "diameter_m", "--diameter-m")
        .set(a.cor.is_some(), "restitution", "--cor")
        .set(true, "height_m", height_flag(a))
        .set(
            a.sample_rate_hz.is_some(),
            "daq.sample_rate_hz",
            "--sample-rate-hz",
        )
}

fn setups(a: &DropArgs) -> Result<Vec<DropSetup>> {
    let preset = a.particle.preset();
    let mut rig = match &a.rig {
        Some(path) => DropRigSpec::load(path)?,
        None => DropRigSpec::builtin(DROP_RIG)?,
    };
    if let Some(fs) = a.sample_rate_hz {
        rig.daq.sample_rate_hz = fs;
    }
    let fs = rig.daq.sample_rate_hz;
    if fs.fract() != 0.0 || fs > 1e6 {
        bail!(
            "daq.sample_rate_hz = {fs} Hz in the rig file: must be a whole number of hertz, at most \
             1000000 (the record is also written as WAV)"
        );
    }
    let heights = a.heights.clone().unwrap_or_else(|| vec![a.height_m]);
    let mut seen = Vec::new();
    for &h in &heights {
        if seen.contains(&millimetres(h)) {
            bail!("--heights lists {h} m twice (to the micrometre); give each height once");
        }
        seen.push(millimetres(h));
    }
    let flags = flag_keys(a);
    heights
        .iter()
        .map(|&height_m| {
            let s = DropSetup {
                particle_name: preset.name().to_string(),
                material: preset.material(),
                diameter_m: a.diameter_m,
                restitution: a.cor.unwrap_or(preset.restitution()),
                friction: DROP_FRICTION,
                height_m,
                rig: rig.clone(),
                gravity_mps2: DROP_GRAVITY_MPS2,
                seed: a.seed,
                numerics: DropNumerics::default(),
            };
            s.validate().map_err(|e| flags.name_flags(e.into()))?;
            Ok(s)
        })
        .collect()
}

/// Runs the command.
pub fn run(a: DropArgs) -> Result<()> {
    let setups = setups(&a)?;
    let first = &setups[0];
    let mut warnings: Vec<String> = Vec::new();
    // The fastest drop sets the sampling demands.
    let fastest = setups
        .iter()
        .max_by(|x, y| x.height_m.total_cmp(&y.height_m))
        .unwrap_or(first);
    if let Some(w) = fastest.sampling_warning_naming(flag_keys(&a).name("daq.sample_rate_hz"))? {
        warnings.push(w);
    }
    let out_dir = a
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from("signals").join(format!("drop-{}", first.particle_name)));
    let made = OutputDir::prepare(&out_dir)?;
    let params = ImpactParams {
        threshold_n: a.threshold_n,
        holdoff_s: a.holdoff_s,
        ..ImpactParams::default()
    };
    let result = simulate(&setups, &params);
    let runs = made.keep_if_ok(result)?;

    let g = DROP_GRAVITY_MPS2;
    let yield_mps = first.yield_velocity_mps();
    for (s, (out, _)) in setups.iter().zip(&runs) {
        let fastest = out
            .impacts
            .iter()
            .map(|d| d.arrival_speed_mps)
            .fold(0.0, f64::max);
        if let Some(w) = yield_mps.and_then(|vy| yield_warning(&s.pair_label(), fastest, vy)) {
            warnings.push(format!("height {} m: {w}", s.height_m));
        }
        if out.rig_report.clipped > 0 {
            warnings.push(format!(
                "height {} m: {} samples clipped at the ADC's full scale ({:.1} N): the record is distorted",
                s.height_m, out.rig_report.clipped, out.rig_report.full_scale_n
            ));
        }
    }
    for (s, (_, est)) in setups.iter().zip(&runs) {
        let grown = est.result.cor.growing_gaps();
        if !grown.is_empty() {
            warnings.push(format!(
                "height {} m: triple(s) {} have a second gap longer than the first (COR > 1): an \
                 impact was missed or ringing taken for one; that estimate is not to be trusted \
                 (try a lower --threshold-n)",
                s.height_m,
                grown
                    .iter()
                    .map(|k| (k + 1).to_string())
                    .collect::<Vec<_>>()
                    .join(", ")
            ));
        }
    }
    let summary = summarise(&a, &setups, &runs, warnings, g)?;
    write_outputs(&out_dir, &setups, &runs, summary, a.json)
}

fn simulate(
    setups: &[DropSetup],
    params: &ImpactParams,
) -> Result<Vec<(DropOutcome, DropEstimate)>> {
    setups
        .par_iter()
        .map(|s| {
            let out =
                run_drop(s).with_context(|| format!("dropping from {} m", s.height_m))?;
            let est = out
                .estimate(params, s.gravity_mps2)
                .with_context(|| {
                    format!(
                        "height {} m: estimating the restitution from the force record ({} DEM contacts)",
                        s.height_m,
                        out.impacts.len()
                    )
                })?;
            Ok((out, est))
        })
        .collect()
}

fn mean_std(x: &[f64]) -> (f64, f64) {
    let n = x.len() as f64;
    let mean = x.iter().sum::<f64>() / n;
    let std = if x.len() > 1 {
        (x.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt()
    } else {
        0.0
    };
    (mean, std)
}

fn summarise(
    a: &DropArgs,
    setups: &[DropSetup],
    runs: &[(DropOutcome, DropEstimate)],
    warnings: Vec<String>,
    g: f64,
) -> Result<DropSummary> {
    let first = &setups[0];
    let mut all_cor = Vec::new();
    let mut all_speed = Vec::new();
    let mut all_height = Vec::new();
    let mut all_realised = Vec::new();
    let mut contact = Vec::new();
    let mut run_summaries = Vec::new();
    for (s, (out, est)) in setups.iter().zip(runs) {
        let cor = &est.result.cor;
        let n = cor.cor_per_triple.len();
        let speeds = cor.impact_speeds_mps[..n].to_vec();
        all_cor.extend_from_slice(&cor.cor_per_triple);
        all_speed.extend_from_slice(&speeds);
        all_height.extend(std::iter::repeat_n(s.height_m, n));
        all_realised.extend_from_slice(&est.realised_per_triple);
        contact
            .extend((0..n).filter_map(|k| est.matched[k + 1].map(|i| out.impacts[i].contact_cor)));
        let stem = format!("force-h{}mm", millimetres(s.height_m));
        run_summaries.push(RunSummary {
            height_m: s.height_m,
            first_impact_speed_mps: s.first_impact_speed_mps(),
            contact_duration_s: out.first_contact_duration_s,
            impacts_detected: est.result.detection.impacts.len(),
            onset_times_s: est.result.detection.onset_times_s(),
            cor_per_triple: cor.cor_per_triple.clone(),
            impact_speeds_mps: speeds,
            cor_mean: cor.cor_mean,
            cor_std: cor.cor_std,
            realised_model_cor_per_triple: est.realised_per_triple.clone(),
            realised_model_cor: est.realised_mean(),
            growing_gap_triples: cor.growing_gaps(),
            threshold_n: est.result.detection.threshold_n,
            holdoff_s: est.result.detection.holdoff_s,
            peak_transducer_force_n: out.rig_report.peak_transducer_force_n,
            clipped_samples: out.rig_report.clipped,
            dem_impacts: out.impacts.clone(),
            rest_time_s: out.rest_time_s,
            tick_s: out.tick_s,
            dem_steps: out.dem_steps,
            fine_steps: out.fine_steps,
            wall_time_s: out.wall_time_s,
            files: vec![
                format!("{stem}.csv"),
                format!("{stem}.wav"),
                format!("{stem}.wav.json"),
            ],
        });
    }
    let (cor_mean, cor_std) = mean_std(&all_cor);
    let realised: Vec<f64> = all_realised.iter().flatten().copied().collect();
    let realised_model_cor = (!realised.is_empty()).then(|| mean_std(&realised).0);
    let mut files: Vec<String> = run_summaries.iter().flat_map(|r| r.files.clone()).collect();
    files.extend(["results.csv", "cor-vs-speed.svg", "drop.json"].map(String::from));
    Ok(DropSummary {
        vlab_version: env!("CARGO_PKG_VERSION"),
        particle: first.particle_name.clone(),
        material: a.particle.preset().material_name(),
        diameter_m: first.diameter_m,
        configured_cor: first.restitution,
        rig: first.rig.name.clone(),
        sample_rate_hz: first.rig.daq.sample_rate_hz,
        gravity_mps2: g,
        seed: first.seed,
        cor_mean,
        cor_std,
        cor_per_triple: all_cor,
        impact_speeds_mps: all_speed,
        heights_m: all_height,
        realised_model_cor,
        realised_model_cor_per_triple: all_realised,
        realised_contact_cor: (!contact.is_empty()).then(|| mean_std(&contact).0),
        cor_error_rel: realised_model_cor.map(|r| cor_mean / r - 1.0),
        yield_velocity_mps: first.yield_velocity_mps(),
        min_sample_rate_hz: setups
            .iter()
            .map(|s| s.min_sample_rate_hz().map(|(_, r)| r))
            .collect::<Result<Vec<f64>, _>>()?
            .into_iter()
            .fold(0.0, f64::max),
        warnings,
        runs: run_summaries,
        files,
    })
}

fn write_outputs(
    dir: &Path,
    setups: &[DropSetup],
    runs: &[(DropOutcome, DropEstimate)],
    summary: DropSummary,
    json: bool,
) -> Result<()> {
    for (r, (out, _)) in summary.runs.iter().zip(runs) {
        write_csv(&dir.join(&r.files[0]), &out.trace)?;
        write_wav(&dir.join(&r.files[1]), &out.trace)?;
    }
    let csv = dir.join("results.csv");
    write_atomic(&csv, |w| {
        use std::io::Write;
        writeln!(
            w,
            "height [m],triple [],impact speed [m/s],cor [],realised model cor [],height cor mean [],height cor std []"
        )?;
        for r in &summary.runs {
            for (k, (c, v)) in r.cor_per_triple.iter().zip(&r.impact_speeds_mps).enumerate() {
                let realised = r.realised_model_cor_per_triple[k]
                    .map(|x| x.to_string())
                    .unwrap_or_default();
                writeln!(
                    w,
                    "{},{},{},{},{},{},{}",
                    r.height_m,
                    k + 1,
                    v,
                    c,
                    realised,
                    r.cor_mean,
                    r.cor_std
                )?;
            }
        }
        Ok(())
    })
    .with_context(|| format!("writing {}", csv.display()))?;
    write_plot(dir, &summary)?;
    let text = serde_json::to_string_pretty(&summary)? + "\n";
    let path = dir.join("drop.json");
    write_bytes_atomic(&path, text.as_bytes())
        .with_context(|| format!("writing {}", path.display()))?;
    for w in &summary.warnings {
        eprintln!("warning: {w}");
    }
    if json {
        print!("{text}");
    } else {
        print_summary(&summary, setups, dir);
    }
    Ok(())
}

fn write_plot(dir: &Path, s: &DropSummary) -> Result<()> {
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
    let svg = dir.join("cor-vs-speed.svg");
    plot_xy_svg(
        &svg,
        &format!(
            "{} on {}: COR vs impact velocity (Fig. 7.5)",
            s.particle, s.rig
        ),
        "impact velocity of the middle impact (m/s)",
        "COR = T(k+1,k+2) / T(k,k+1)",
        &series,
    )?;
    Ok(())
}

fn print_summary(s: &DropSummary, setups: &[DropSetup], dir: &Path) {
    println!(
        "drop test: {} sphere ({} m {}, e = {} configured) on the {} rig, {} Hz, seed {}",
        s.particle, s.diameter_m, s.material, s.configured_cor, s.rig, s.sample_rate_hz, s.seed
    );
    println!("  height    impacts  triples  COR mean  std       realised  error      run");
    for r in &s.runs {
        let (real, err) = match r.realised_model_cor {
            Some(x) => (
                format!("{x:.5}"),
                format!("{:+.3} %", 100.0 * (r.cor_mean / x - 1.0)),
            ),
            None => ("-".into(), "-".into()),
        };
        println!(
            "  {:.4} m  {:7}  {:7}  {:.5}   {:.5}   {:8}  {:9}  {:.2} s",
            r.height_m,
            r.impacts_detected,
            r.cor_per_triple.len(),
            r.cor_mean,
            r.cor_std,
            real,
            err,
            r.wall_time_s
        );
    }
    println!(
        "  all: COR {:.5} +- {:.5} over {} triples at impact speeds {:.3}-{:.3} m/s",
        s.cor_mean,
        s.cor_std,
        s.cor_per_triple.len(),
        s.impact_speeds_mps
            .iter()
            .copied()
            .fold(f64::INFINITY, f64::min),
        s.impact_speeds_mps.iter().copied().fold(0.0, f64::max),
    );
    if let (Some(r), Some(c)) = (s.realised_model_cor, s.realised_contact_cor) {
        println!(
            "  realised by the model: {r:.5} (the sphere's rebound / impact speed), {c:.5} relative to the plate; configured {}",
            s.configured_cor
        );
    }
    if let Some(vy) = s.yield_velocity_mps {
        let fastest = setups
            .iter()
            .map(|x| x.first_impact_speed_mps())
            .fold(0.0, f64::max);
        println!(
            "  yield velocity on the plate (eq. 5.26) {vy:.3} m/s; fastest impact {fastest:.3} m/s"
        );
    }
    println!("  wrote {}", dir.display());
}
