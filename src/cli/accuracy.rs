//! `vlab accuracy`: error against wall-clock time for the DEM (time step,
//! cycles, seeds), a single collision (steps per contact) and Yang's method
//! (record length, noise, ADC bits, residual phase error). The work is
//! [`vlab::study::accuracy`]'s; this is its command line.

use std::path::PathBuf;
use std::sync::Mutex;
use std::time::Instant;

use anyhow::{Context, Result};
use clap::Args;

use vlab::atomic_write::OutputDir;
use vlab::experiment::shake::{resolve_rig, shake_drive};
use vlab::rig::ShakerKind;
use vlab::scene::Scene;
use vlab::study::accuracy::{
    AccuracyEvent, AccuracyPlan, AccuracyReport, DemAccuracy, run_accuracy,
};

use super::args;

#[derive(Debug, Clone, Args)]
pub struct AccuracyArgs {
    /// Drive frequency (Hz).
    #[arg(long = "freq", value_name = "HZ", default_value = "40", value_parser = args::freq_hz)]
    pub freq_hz: f64,
    /// Acceleration amplitude Γ (dimensionless).
    #[arg(long, default_value = "20", value_parser = args::gamma)]
    pub gamma: f64,
    /// Scene file (TOML) merged over the built-in thesis scene.
    #[arg(long, value_name = "FILE")]
    pub scene: Option<PathBuf>,
    /// The rig whose measurement chain Yang's study re-runs: a built-in name
    /// or a rig file.
    #[arg(long, value_name = "NAME|FILE", default_value = vlab::rig::DEFAULT_RIG)]
    pub rig: String,
    /// A few points of each study (2 seeds, 4 steady cycles): for tests and CI.
    #[arg(long)]
    pub quick: bool,
    /// Output folder [default: signals/accuracy-<scene>-<freq>Hz-G<gamma>].
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
}

/// Runs the command.
pub fn run(a: AccuracyArgs, quiet: bool) -> Result<()> {
    let scene = Scene::load_or_thesis(a.scene.as_deref()).with_context(|| {
        a.scene.as_ref().map_or("the thesis scene".into(), |p| {
            format!("--scene {}", p.display())
        })
    })?;
    let flags = args::FlagKeys::new()
        .set(true, "freq_hz", "--freq")
        .set(true, "gamma", "--gamma");
    let drive = shake_drive(&scene, a.freq_hz, a.gamma).map_err(|e| flags.name_flags(e.into()))?;
    let rig = resolve_rig(&a.rig, Some(ShakerKind::Prescribed), &drive)
        .with_context(|| format!("--rig {}", a.rig))?;
    let plan = if a.quick {
        AccuracyPlan::quick(a.freq_hz, a.gamma)
    } else {
        AccuracyPlan::full(a.freq_hz, a.gamma)
    };
    let out_dir = a.out.clone().unwrap_or_else(|| {
        PathBuf::from("signals").join(format!(
            "accuracy-{}-{}Hz-G{}",
            scene.name, a.freq_hz, a.gamma
        ))
    });
    let made = OutputDir::prepare(&out_dir)
        .with_context(|| format!("cannot create output folder {}", out_dir.display()))?;
    let started = Instant::now();
    let last_drive_line: Mutex<Option<Instant>> = Mutex::new(None);
    let progress = |e: AccuracyEvent| {
        if quiet {
            return;
        }
        let t = started.elapsed().as_secs_f64();
        match e {
            AccuracyEvent::Stage(s) => eprintln!("accuracy [{t:6.0} s] {s}"),
            AccuracyEvent::Drive {
                label,
                cycle,
                cycles,
                wall_s,
            } => {
                let Ok(mut last) = last_drive_line.lock() else {
                    return;
                };
                if last.is_some_and(|l| l.elapsed().as_secs_f64() < 15.0) {
                    return;
                }
                *last = Some(Instant::now());
                eprintln!(
                    "accuracy [{t:6.0} s] {label}: cycle {cycle} of {cycles} after {wall_s:.0} s"
                );
            }
        }
    };
    let result = run_accuracy(&scene, &rig, &plan, a.quick, &progress)
        .context("running the accuracy studies");
    let mut report = made.keep_if_ok(result)?;
    report.write(&out_dir)?;
    print_summary(&report, &out_dir);
    Ok(())
}

/// Study (a): the default time step against the reference, the integrator's
/// error and order, the seeds' spread.
fn print_dem_study(d: &DemAccuracy) {
    let pct = |x: f64| 100.0 * x;
    println!(
        "  (a) DEM: default dt {:.3e} s = {:.3} x Rayleigh ({:.3e} s); reference {} x Rayleigh",
        d.default_dt_s, d.default_dt_over_rayleigh, d.rayleigh_step_s, d.reference_dt_over_rayleigh
    );
    println!(
        "      default dt vs reference {:+.2} % +- {}; integrator energy error {:.1e} (order {})",
        pct(d.default_dt_error_rel),
        if d.default_dt_error_stderr_rel.is_nan() {
            "not known (fewer than 16 cycles)".to_string()
        } else {
            format!("{:.2} %", pct(d.default_dt_error_stderr_rel))
        },
        d.default_dt_integrator_rel,
        d.integrator_order.map_or("-".into(), |o| format!("{o:.2}"))
    );
    println!(
        "      seeds: energy per cycle {:.4e} J pooled (efficiency {:.3}), seed spread {:.2} % (their standard errors {:.2} %)",
        d.pooled_energy_per_cycle_j,
        d.pooled_efficiency,
        pct(d.seed_spread_rel),
        pct(d.seed_stderr_rms_rel)
    );
    for f in &d.failed {
        println!("      stopped: {f}");
    }
    println!("      dominant: {}", d.dominant);
}

fn print_summary(r: &AccuracyReport, dir: &std::path::Path) {
    let s = &r.summary;
    let d = &s.dem;
    let i = &s.impact;
    let y = &s.yang;
    let pct = |x: f64| 100.0 * x;
    println!(
        "{} damper, {} Hz, Gamma {}: {} particles, {} thread{}, {:.0} s in all{}",
        s.scene,
        s.plan.freq_hz,
        s.plan.gamma,
        s.n_particles,
        s.threads,
        if s.threads == 1 { "" } else { "s" },
        s.wall_s,
        if s.quick { " (--quick)" } else { "" }
    );
    print_dem_study(d);
    println!(
        "  (b) collision at {:.2} m/s, {} steps per contact: overlap {:+.2e}, duration {:+.2e} (eq. 5.10) {:+.2e} (exact), restitution {:+.2e}; orders {} / {} / {}",
        i.speed_mps,
        i.scene_steps_per_contact,
        i.max_overlap_error_rel,
        i.duration_error_rel_eq_5_10,
        i.duration_error_rel_exact,
        i.restitution_error_rel,
        i.order_max_overlap
            .map_or("-".into(), |o| format!("{o:.2}")),
        i.order_duration_exact
            .map_or("-".into(), |o| format!("{o:.2}")),
        i.order_restitution
            .map_or("-".into(), |o| format!("{o:.2}"))
    );
    println!(
        "  (c) Yang, rig {}, {} periods: the chain {:+.3} % vs the work in, the bed's unsteadiness {:+.3} %: {:+.3} % vs DEM dissipation; {} per mrad of residual phase",
        y.rig,
        y.baseline_record_periods,
        pct(y.baseline_error_vs_work_rel),
        pct(y.baseline_unsteadiness_rel),
        pct(y.baseline_error_rel),
        y.error_per_mrad
            .map_or("-".into(), |e| format!("{:+.2} %", pct(e)))
    );
    println!("  wrote {}", dir.display());
}
