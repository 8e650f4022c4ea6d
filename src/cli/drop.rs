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

use anyhow::{Context, Result};
use clap::{Args, ValueEnum};

use vlab::atomic_write::OutputDir;
use vlab::experiment::drop::series::{DropRequest, DropSeries, sampling_warning};
use vlab::experiment::drop::{DropParticle, DropSetup, DropSummary};
use vlab::rig::{DROP_RIG, DropRigSpec, RigFile};
use vlab::signals::ImpactParams;
use vlab::warning::RunWarning;

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
    let rig = match &a.rig {
        Some(path) => DropRigSpec::load(path)?,
        None => DropRigSpec::builtin(DROP_RIG)?,
    };
    let request = DropRequest {
        particle: a.particle.preset(),
        restitution: a.cor,
        diameter_m: a.diameter_m,
        heights_m: a.heights.clone().unwrap_or_else(|| vec![a.height_m]),
        rig,
        sample_rate_hz: a.sample_rate_hz,
        seed: a.seed,
    };
    request
        .setups()
        .map_err(|e| flag_keys(a).name_flags(e.into()))
}

/// Runs the command.
pub fn run(a: DropArgs) -> Result<()> {
    let setups = setups(&a)?;
    let first = &setups[0];
    let keys = flag_keys(&a);
    let rate = keys.name("daq.sample_rate_hz");
    let warnings: Vec<RunWarning> = sampling_warning(&setups, rate)?.into_iter().collect();
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
    let material = a.particle.preset().material_name();
    let series = made.keep_if_ok(DropSeries::run(setups, &params, material, warnings))?;
    made.keep_if_ok(series.write(&out_dir))
        .with_context(|| format!("writing into {}", out_dir.display()))?;
    for w in &series.summary.warnings {
        eprintln!("warning: {w}");
    }
    if a.json {
        print!("{}", series.summary_json());
    } else {
        print_summary(&series.summary, &series.setups, &out_dir);
    }
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
