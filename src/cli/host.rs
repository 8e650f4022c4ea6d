//! `vlab host`: the damper on a host structure (thesis Section 2.3.1, 9.4 i
//! and v). `run` records any excitation; `decay` and `frf` measure the host
//! the classical ways and hold each estimate against the DEM's dissipation;
//! `predict` answers from a sweep's map in milliseconds; `modal` fits the
//! modes of a measured FRF. The work is
//! [`vlab::experiment::host_test`]'s and [`vlab::host`]'s; this is the
//! command line.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use clap::{Args, Subcommand};

use vlab::atomic_write::OutputDir;
use vlab::experiment::host_test::{Damper, HostRun, HostTest, run_host_test};
use vlab::host::{DEFAULT_HOST, Excitation, HostSpec};
use vlab::rig::{RigFile, RigSpec};
use vlab::scene::Scene;
use vlab::study::host_prediction::{MAX_FREQUENCIES, check_frequencies};

use super::args;
use super::cache_cmd::NoCacheArg;
use super::progress::ProgressLine;

mod base;
mod decay;
mod frf;
mod modal;
mod predict;
mod updown;

#[derive(Debug, Clone, Args)]
pub struct HostArgs {
    #[command(subcommand)]
    command: HostCommand,
}

#[derive(Debug, Clone, Subcommand)]
enum HostCommand {
    /// Drive the host with any excitation and record it (lab channels and truth).
    Run(RunArgs),
    /// Free decay (released, or struck by a hammer): loss factor against
    /// amplitude by logarithmic decrement and by the Hilbert envelope, each
    /// against the DEM's own dissipation per cycle.
    Decay(decay::DecayArgs),
    /// Frequency response: stepped sine (half-power loss factor, peak
    /// reduction, power input) or periodic random (H1, H2, coherence).
    Frf(frf::FrfArgs),
    /// The host's steady response predicted from a sweep's dissipation map
    /// (describing function and harmonic balance), in milliseconds.
    Predict(predict::PredictArgs),
    /// Base excitation: the host on the rig's shaker table, a stepped sine
    /// of the table's acceleration; the transmissibility (damper over
    /// table), the exact one for a linear payload, and the power the table
    /// put in (Yang's method) against what was dissipated.
    Base(base::BaseArgs),
    /// Modal parameters (natural frequency, damping ratio, loss factor,
    /// modal constant, each +- one sigma) of the modes in a frf.csv, by a
    /// least-squares fit of a sum of modes.
    Modal(modal::ModalArgs),
}

/// What every test of a damper on a host needs.
#[derive(Debug, Clone, Args)]
#[command(allow_negative_numbers = true)]
pub struct HostTestArgs {
    /// The host: a built-in name (plate-40hz, beam-2mode) or a host file (TOML).
    #[arg(long, value_name = "NAME|FILE", default_value = DEFAULT_HOST)]
    pub host: String,
    /// What the enclosure holds: particles (the DEM), empty, solid (the
    /// particles' mass as a rigid solid) or dashpot:N_S_PER_M (a linear
    /// viscous damper to ground; on a table, to the table).
    #[arg(long, value_name = "KIND", default_value = "particles", value_parser = parse_damper)]
    pub damper: Damper,
    #[command(flatten)]
    pub scene: args::BedArgs,
    /// The rig whose channels record the test: its accelerometer at the
    /// damper, its force transducer at the drive point.
    #[arg(long, value_name = "NAME|FILE", default_value = vlab::rig::DEFAULT_RIG)]
    pub rig: String,
    /// Seed of the channels' noise [default: the bed's seed].
    #[arg(long = "noise-seed", value_name = "N")]
    pub noise_seed: Option<u64>,
    #[command(flatten)]
    pub cache: NoCacheArg,
}

fn parse_damper(s: &str) -> Result<Damper, String> {
    Damper::parse(s).map_err(|e| e.to_string())
}

fn parse_excitation(s: &str) -> Result<Excitation, String> {
    Excitation::parse(s).map_err(|e| e.to_string())
}

impl HostTestArgs {
    /// The scene, and the test of `excitation` for `duration_s`.
    pub fn test(&self, excitation: Excitation, duration_s: f64) -> Result<(Scene, HostTest)> {
        let scene = self.scene.resolve()?;
        let host = HostSpec::from_name_or_path(&self.host)
            .with_context(|| format!("--host {}", self.host))?;
        let rig =
            RigSpec::from_name_or_path(&self.rig).with_context(|| format!("--rig {}", self.rig))?;
        let test = HostTest::new(
            &scene,
            host,
            self.damper,
            excitation,
            duration_s,
            rig,
            self.noise_seed,
        );
        test.check().map_err(|e| {
            args::FlagKeys::new()
                .set(true, "duration_s", "--duration-s")
                .name_flags(e.into())
        })?;
        Ok((scene, test))
    }
}

#[derive(Debug, Clone, Args)]
#[command(allow_negative_numbers = true)]
pub struct RunArgs {
    #[command(flatten)]
    common: HostTestArgs,
    /// The force at the drive point: sine:F_HZ:FORCE_N,
    /// sweep:F0_HZ:F1_HZ:DURATION_S:FORCE_N, multisine:F1_HZ:N1,F2_HZ:N2,...,
    /// random:LOW_HZ:HIGH_HZ:RMS_N:PERIOD_S:SEED, hammer:IMPULSE_N_S or
    /// release:X0_M (docs/host.md).
    #[arg(long, value_name = "KEY", value_parser = parse_excitation)]
    excitation: Excitation,
    /// Length of the test (s).
    #[arg(long = "duration-s", value_name = "S", default_value = "1", value_parser = args::seconds)]
    duration_s: f64,
    /// Output folder [default: signals/host-<host>-<damper>].
    #[arg(long, value_name = "DIR")]
    out: Option<PathBuf>,
}

pub fn run(a: HostArgs, quiet: bool) -> Result<()> {
    match a.command {
        HostCommand::Run(r) => run_record(r, quiet),
        HostCommand::Decay(d) => decay::run(d, quiet),
        HostCommand::Frf(f) => frf::run(f, quiet),
        HostCommand::Base(b) => base::run(b, quiet),
        HostCommand::Predict(p) => predict::run(p),
        HostCommand::Modal(m) => modal::run(m),
    }
}

/// A folder name for a test's damper.
fn damper_slug(d: Damper) -> String {
    match d {
        Damper::Dashpot { n_s_per_m } => format!("dashpot{n_s_per_m}"),
        other => other.label().replace(' ', "-"),
    }
}

/// Runs one host test with progress on standard error.
pub fn run_test(scene: &Scene, test: &HostTest, cache: NoCacheArg, quiet: bool) -> Result<HostRun> {
    let mut progress = ProgressLine::new("host", quiet);
    let beds = cache.source(&mut |n| progress.warn(n));
    let scene = &super::args::run_alone(scene.clone());
    let run = run_host_test(scene, &beds, test, &mut |p| progress.update(p))
        .context("running the damper on its host");
    if let Ok(r) = &run {
        for w in &r.warnings {
            progress.warn(&format!("host: warning: {}", w.text));
        }
    }
    progress.finish();
    run
}

fn run_record(a: RunArgs, quiet: bool) -> Result<()> {
    let (scene, test) = a.common.test(a.excitation.clone(), a.duration_s)?;
    let out = a.out.clone().unwrap_or_else(|| {
        PathBuf::from("signals").join(format!(
            "host-{}-{}",
            test.host.name,
            damper_slug(test.damper)
        ))
    });
    let made = OutputDir::prepare(&out)
        .with_context(|| format!("cannot create output folder {}", out.display()))?;
    let run = made.keep_if_ok(run_test(&scene, &test, a.common.cache, quiet))?;
    made.keep_if_ok(write_records(&out, &run))?;
    let e = &run.energy;
    println!(
        "{} on {} ({}), {:.3} s: {} steps of {:.3e} s, {:.1} s wall",
        test.damper.label(),
        test.host.name,
        excitation_text(&test.excitation),
        test.duration_s,
        run.steps,
        run.dt_s,
        run.wall_time_s
    );
    println!(
        "  excitation did {:.5} J; the host's damping took {:.5} J, the damper {:.5} J{}",
        e.excitation_work_j,
        e.host_dissipated_j,
        run.damper_dissipated_j + e.dashpot_dissipated_j,
        match run.bed {
            Some(b) => format!(
                " (the DEM's walls did {:.5} J on the bed; the host booked {:.5} J given)",
                b.work_in_j, -e.damper_work_j
            ),
            None => String::new(),
        }
    );
    println!("wrote {}", out.display());
    Ok(())
}

/// One line for an excitation.
pub fn excitation_text(e: &Excitation) -> String {
    serde_json::to_string(e).unwrap_or_default()
}

/// Writes the run's records into `dir` ([`HostRun::write_records`]).
pub fn write_records(dir: &Path, run: &HostRun) -> Result<()> {
    run.write_records(dir)
        .with_context(|| format!("writing the records into {}", dir.display()))
}

/// Frequencies in Hz, ascending.
#[derive(Debug, Clone, PartialEq)]
pub struct FreqList(pub Vec<f64>);

/// The sweep files of `--map` as one map's rows
/// ([`vlab::study::dissipation_map::read_map_files`]: the first file, each
/// later one replacing the conditions it holds), and their label.
pub fn read_maps(paths: &[PathBuf]) -> Result<(vlab::study::sweep::SweepFile, String)> {
    let label = vlab::study::dissipation_map::map_files_label(paths);
    let file = vlab::study::dissipation_map::read_map_files(paths)
        .with_context(|| format!("--map {label}"))?;
    Ok((file, label))
}

/// `FROM:TO:STEP` (both ends included) or a comma-separated list, in Hz,
/// each positive and at most 5 kHz, ascending, at most 1000.
pub fn parse_freqs(s: &str) -> Result<FreqList, String> {
    let number = |t: &str| -> Result<f64, String> {
        t.trim()
            .parse::<f64>()
            .map_err(|_| format!("'{t}' is not a number (Hz)"))
    };
    let freqs: Vec<f64> = if s.contains(':') {
        let parts: Vec<&str> = s.split(':').collect();
        let [from, to, step] = parts.as_slice() else {
            return Err(format!(
                "'{s}': give FROM:TO:STEP in Hz or a comma-separated list"
            ));
        };
        let (from, to, step) = (number(from)?, number(to)?, number(step)?);
        if step.is_nan() || step <= 0.0 || to < from {
            return Err(format!("'{s}': STEP must be positive and TO at least FROM"));
        }
        let n = ((to - from) / step + 1e-9).floor() as usize;
        if n >= MAX_FREQUENCIES {
            // Refused before the list is made: a tiny STEP would fill memory.
            return Err(format!(
                "'{s}' gives {} frequencies: at most {MAX_FREQUENCIES}",
                n + 1
            ));
        }
        (0..=n).map(|k| from + step * k as f64).collect()
    } else {
        s.split(',').map(number).collect::<Result<_, _>>()?
    };
    check_frequencies(&freqs).map_err(|e| e.renamed("--freq").to_string())?;
    Ok(FreqList(freqs))
}
