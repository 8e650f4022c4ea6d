//! `vlab shake`: drive the damper at one frequency and amplitude through the
//! rig, measure it, and write what the lab records beside what the simulator
//! knows. The work is [`vlab::experiment::shake`]'s; this is its command line.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use clap::Args;

use vlab::atomic_write::OutputDir;
use vlab::experiment::damper::{Kinematics, NoObserver, StepObserver};
use vlab::experiment::measurement::ShakeSetup;
use vlab::experiment::shake::{
    ShakeSummary, check_drive, check_record_window, default_out_dir, resolve_rig, run_shake_from,
    run_shake_on_bed,
};
use vlab::export::snapshots::PhaseSnapshots;
use vlab::export::vtk_dump::VtkDump;
use vlab::rig::ShakerKind;

use super::args;
use super::cache_cmd::NoCacheArg;
use super::progress::ProgressLine;

#[derive(Debug, Clone, Args)]
#[command(allow_negative_numbers = true)]
pub struct ShakeArgs {
    /// Drive frequency (Hz).
    #[arg(long = "freq", value_name = "HZ", default_value = "40", value_parser = args::freq_hz)]
    pub freq_hz: f64,
    /// Acceleration amplitude Γ: peak enclosure acceleration / g (dimensionless).
    #[arg(long, default_value = "20", value_parser = args::gamma)]
    pub gamma: f64,
    #[command(flatten)]
    pub scene: args::SceneArgs,
    /// The rig that measures the damper: a built-in name (thesis-shaker, ideal)
    /// or a rig file (TOML).
    #[arg(long, value_name = "NAME|FILE", default_value = vlab::rig::DEFAULT_RIG)]
    pub rig: String,
    /// How the enclosure is moved [default: the rig's own].
    #[arg(long, value_enum)]
    pub shaker: Option<ShakerKind>,
    /// Length of the record after the transient cycles (s); sets the number of
    /// steady cycles instead of --steady-cycles.
    #[arg(long = "duration-s", value_name = "S", value_parser = args::seconds, conflicts_with = "steady_cycles")]
    pub duration_s: Option<f64>,
    /// Phase-error table of the rig (from `vlab calibrate`) [default: measure
    /// one now on the empty enclosure at the drive frequency].
    #[arg(long, value_name = "FILE")]
    pub calibration: Option<PathBuf>,
    /// Output folder [default: signals/<scene>-<freq>Hz-G<gamma>].
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Print the summary as JSON on standard output.
    #[arg(long)]
    pub json: bool,
    /// Write the particles and the enclosure for ParaView (VTK .vtp frames and
    /// .pvd time series) into this folder.
    #[arg(long, value_name = "DIR")]
    pub dump: Option<PathBuf>,
    /// Drive time between dump frames (s) [default: an eighth of a cycle].
    #[arg(long = "dump-every-s", value_name = "S", value_parser = args::seconds, requires = "dump")]
    pub dump_every_s: Option<f64>,
    /// Drive time of the first dump frame (s) [default: 0, the drive start].
    #[arg(long = "dump-from-s", value_name = "S", value_parser = args::non_negative_seconds, requires = "dump")]
    pub dump_from_s: Option<f64>,
    /// Also draw snapshots.svg/.png: side views of the bed at 8 phases of the
    /// last cycle, coloured by speed.
    #[arg(long)]
    pub snapshots: bool,
    #[command(flatten)]
    pub cache: NoCacheArg,
}

/// Two observers of one drive.
struct Both<'a>(&'a mut dyn StepObserver, &'a mut dyn StepObserver);

impl StepObserver for Both<'_> {
    fn observe(&mut self, t_s: f64, world: &vlab::dem::World, enclosure: &Kinematics) {
        self.0.observe(t_s, world, enclosure);
        self.1.observe(t_s, world, enclosure);
    }
}

/// Runs the command.
pub fn run(a: ShakeArgs, quiet: bool) -> Result<()> {
    let flags = a.scene.flags().set(true, "freq_hz", "--freq");
    let mut scene = a.scene.resolve()?;
    if let Some(d) = a.duration_s {
        scene.set_record_length(d, a.freq_hz);
    }
    check_drive(&scene, a.freq_hz, a.gamma).map_err(|e| flags.name_flags(e.into()))?;
    let g = scene.simulation.gravity_mps2;
    let rig = resolve_rig(&a.rig, a.shaker, a.freq_hz, a.gamma, g)
        .with_context(|| format!("--rig {}", a.rig))?;
    check_record_window(&scene, a.freq_hz, rig.daq.sample_rate_hz)
        .map_err(|e| flags.name_flags(e.into()))?;
    let calibration = args::calibration_source(a.calibration.as_deref())?;
    let out_dir = a
        .out
        .clone()
        .unwrap_or_else(|| default_out_dir(&scene, a.freq_hz, a.gamma));
    let made = OutputDir::prepare(&out_dir)
        .with_context(|| format!("cannot create output folder {}", out_dir.display()))?;
    let mut progress = ProgressLine::new("shake", quiet);
    let setup = ShakeSetup {
        rig,
        freq_hz: a.freq_hz,
        gamma: a.gamma,
        calibration,
    };
    let period = 1.0 / a.freq_hz;
    let mut dump = match &a.dump {
        Some(dir) => {
            std::fs::create_dir_all(dir)
                .with_context(|| format!("cannot create --dump folder {}", dir.display()))?;
            Some(VtkDump::new(
                dir,
                a.dump_every_s.unwrap_or(period / 8.0),
                a.dump_from_s.unwrap_or(0.0),
                0.5 * scene.enclosure.inner_diameter_m,
                scene.enclosure.inner_length_m,
            ))
        }
        None => None,
    };
    let mut snaps = a.snapshots.then(|| PhaseSnapshots::new(a.freq_hz, 0.0));
    let beds = a.cache.source(&mut |n| progress.warn(n));
    let result = (|| {
        if dump.is_none() && snaps.is_none() {
            return run_shake_from(&scene, &setup, &beds, &mut NoObserver, &mut |p| {
                progress.update(p)
            });
        }
        check_drive(&scene, a.freq_hz, a.gamma)?;
        let mut bed = beds.settle(&scene, &mut |p| progress.update(p))?;
        if dump.is_some() {
            bed.world.track_particle_dissipation(true);
        }
        let mut none_a = NoObserver;
        let mut none_b = NoObserver;
        let first: &mut dyn StepObserver = match dump.as_mut() {
            Some(d) => d,
            None => &mut none_a,
        };
        let second: &mut dyn StepObserver = match snaps.as_mut() {
            Some(s) => s,
            None => &mut none_b,
        };
        run_shake_on_bed(&scene, &bed, &setup, &mut Both(first, second), &mut |p| {
            progress.update(p)
        })
    })()
    .context("running the damper through the rig");
    progress.finish();
    let mut shake = made.keep_if_ok(result)?;
    shake.write(&out_dir, &scene, &setup)?;
    if let Some(d) = dump {
        let files = d.finish()?;
        progress.note(&format!(
            "wrote {} ParaView files into {} (open particles.pvd and enclosure.pvd)",
            files.len(),
            a.dump
                .as_deref()
                .map(|p| p.display().to_string())
                .unwrap_or_default()
        ));
    }
    if let Some(sn) = &snaps {
        let v = a.gamma * scene.simulation.gravity_mps2 / (2.0 * std::f64::consts::PI * a.freq_hz);
        for ext in ["svg", "png"] {
            sn.plot(
                &out_dir.join(format!("snapshots.{ext}")),
                &format!(
                    "{} damper, {} Hz, Gamma {}, {}: one steady cycle",
                    scene.name,
                    a.freq_hz,
                    a.gamma,
                    scene.enclosure.orientation.as_str()
                ),
                scene.enclosure.orientation,
                0.5 * scene.enclosure.inner_diameter_m,
                scene.enclosure.inner_length_m,
                v,
            )?;
        }
    }
    for w in &shake.summary.warnings {
        progress.warn(&format!("warning: {w}"));
    }
    if a.json {
        print!("{}", shake.summary_json());
    } else {
        print_summary(&shake.summary, &out_dir);
    }
    Ok(())
}

fn print_summary(s: &ShakeSummary, dir: &Path) {
    let d = &s.dem;
    let m = &s.measured;
    let pc = &d.dissipated_per_cycle_j;
    let total = pc.total().max(f64::MIN_POSITIVE);
    println!(
        "{} damper, {} Hz, Gamma {}, {}: {} particles ({:.4} kg, fill {:.3}), dt {:.1e} s, seed {}",
        s.scene,
        s.freq_hz,
        s.gamma,
        s.orientation,
        s.n_particles,
        s.particle_mass_kg,
        s.fill_ratio,
        s.dt_s,
        s.seed
    );
    let st = &d.steadiness;
    println!(
        "  DEM truth (cycles {}-{} of {}; {}):",
        d.steady_first_cycle + 1,
        d.cycles,
        d.cycles,
        if st.reached {
            "steady"
        } else if st.lossless {
            "lossless: no steady state"
        } else if st.capped {
            "NOT steady: stopped at the cycle cap"
        } else {
            "not checked steady: fixed cycle count"
        }
    );
    println!(
        "    energy dissipated per cycle   {:.4e} +- {:.1e} J",
        d.energy_per_cycle_j, d.energy_per_cycle_stderr_j
    );
    println!("    E_max = 4 (Gamma g / w)^2 M   {:.4e} J", d.e_max_j);
    println!(
        "    damping efficiency            {:.3} +- {:.3}",
        d.efficiency, d.efficiency_stderr
    );
    println!(
        "    steadiness                    work in vs dissipated {:+.2} %, standard error {:.2} % of the mean",
        100.0 * st.balance_rel,
        100.0 * st.stderr_rel
    );
    println!(
        "    by source: particle-particle normal {:.1} %, tangential {:.1} %; particle-wall normal {:.1} %, tangential {:.1} %",
        100.0 * pc.pp_normal / total,
        100.0 * pc.pp_tangential / total,
        100.0 * pc.pw_normal / total,
        100.0 * pc.pw_tangential / total
    );
    println!(
        "    energy ledger                 integration error {:+.1e}, residual {:.0e} of the energy that flowed",
        d.integrator_rel, d.ledger_residual_rel
    );
    println!(
        "  measured by rig {} ({} shaker), Yang's method over {} periods:",
        s.rig, s.shaker, m.n_periods
    );
    let versus = if m.error_vs_dem_rel.is_finite() {
        format!(
            "{:+.2} % vs DEM: {:+.2} % the chain, {:+.2} % the bed's unsteadiness",
            100.0 * m.error_vs_dem_rel,
            100.0 * m.error_vs_dem_work_rel,
            100.0 * m.unsteadiness_rel
        )
    } else {
        format!(
            "{:+.2} % vs the DEM's input work, the chain alone; the DEM dissipated nothing",
            100.0 * m.error_vs_dem_work_rel
        )
    };
    println!(
        "    energy per cycle              {:.4e}{} J  ({versus})",
        m.energy_per_cycle_j,
        m.energy_per_cycle_stderr_j
            .map_or(String::new(), |x| format!(" +- {x:.1e}")),
    );
    println!(
        "    damping efficiency            {:.3}{}",
        m.efficiency,
        m.efficiency_stderr
            .map_or(String::new(), |x| format!(" +- {x:.3}"))
    );
    println!(
        "    (+- : standard error from the cycle-to-cycle spread, the statistical part; % vs DEM: the measurement chain's error plus the bed's unsteadiness over the record)"
    );
    println!(
        "    phase correction              {:.3} mrad ({})",
        1e3 * m.phase_correction_rad,
        m.calibration
    );
    println!(
        "    without the correction        {:.4e} J  ({:+.2} % vs DEM; predicted leak {:+.2} %)",
        m.uncorrected_energy_per_cycle_j,
        100.0 * m.uncorrected_error_vs_dem_rel,
        100.0 * m.predicted_leak_per_cycle_j / d.energy_per_cycle_j
    );
    println!(
        "  speed {:.2} M particle-steps/s ({} thread{}); wall time: {} {:.1} s, drive {:.1} s, rig and measurement {:.2} s",
        s.particle_steps_per_s / 1e6,
        s.threads,
        if s.threads == 1 { "" } else { "s" },
        if s.bed_from_cache {
            "bed read from the cache"
        } else {
            "settling"
        },
        s.settle_wall_time_s,
        s.wall_time_s,
        s.rig_wall_time_s
    );
    println!("  wrote {}", dir.display());
}
