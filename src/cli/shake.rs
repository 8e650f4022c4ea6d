//! `vlab shake`: drive the damper at one frequency and amplitude through the
//! rig, measure it, and write what the lab records beside what the simulator
//! knows. The work is [`vlab::experiment::shake`]'s; this is its command line.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use clap::Args;

use vlab::atomic_write::OutputDir;
use vlab::drive::Drive;
use vlab::experiment::damper::{Steadiness, StepObserver};
use vlab::experiment::ensemble::{DEFAULT_BEDS, EnsembleSummary, unsteady_reasons};
use vlab::experiment::ensemble_summary::{LONGER_DRIVE_SCALE, longer_drive_rel};
use vlab::experiment::orientation_record::OrientationOrder;
use vlab::experiment::shake::{DemTruth, ShakeSummary, default_out_dir, percent_or_unknown};
use vlab::experiment::shake_plan::{RequestField, ShakePlan, ShakeRequest};
use vlab::export::snapshots::PhaseSnapshots;
use vlab::export::vtk_dump::VtkDump;
use vlab::rig::ShakerKind;
use vlab::scene::Scene;
use vlab::stats::MIN_SERIES_VALUES;

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
    /// Seed of the rig's DAQ noise [default: the bed's seed, --seed]: the same
    /// bed measured again with fresh noise.
    #[arg(long = "noise-seed", value_name = "N")]
    pub noise_seed: Option<u64>,
    /// Independent beds of the damper to drive together (seeds derived from
    /// --seed, the first bed --seed's own), 1 to 64; the printed figure is
    /// their mean and its +- their spread. One bed's +- is its window's
    /// alone and says nothing of another packing of the same damper.
    #[arg(long, value_name = "N", default_value_t = DEFAULT_BEDS)]
    pub beds: u32,
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

/// Runs the command: the plan from the flags, the observers `--dump` and
/// `--snapshots` ask for, the library's shake, and what it prints.
pub fn run(a: ShakeArgs, quiet: bool) -> Result<()> {
    let plan = plan(&a)?;
    let (scene, drive) = (&plan.scene, &plan.setup.drive);
    if a.dump.is_some() {
        dump_every_s(&a, drive)?;
    }
    let out_dir = a
        .out
        .clone()
        .unwrap_or_else(|| default_out_dir(scene, drive));
    let made = OutputDir::prepare(&out_dir)
        .with_context(|| format!("cannot create output folder {}", out_dir.display()))?;
    let mut dump = vtk_dump(&a, scene, drive)?;
    let mut snaps = a
        .snapshots
        .then(|| PhaseSnapshots::new(drive.freq_hz(), 0.0));
    let mut progress = ProgressLine::new("shake", quiet);
    let beds = a.cache.source(&mut |n| progress.warn(n));
    let mut observers: Vec<&mut dyn StepObserver> = Vec::new();
    if let Some(d) = dump.as_mut() {
        observers.push(d);
    }
    if let Some(s) = snaps.as_mut() {
        observers.push(s);
    }
    let result = plan
        .run(
            &beds,
            rayon::current_num_threads(),
            &mut observers,
            &mut |p| progress.update(p),
        )
        .context("running the damper through the rig");
    progress.finish();
    let mut shake = made.keep_if_ok(result)?;
    shake.write(&out_dir)?;
    if let (Some(d), Some(dir)) = (dump, &a.dump) {
        let files = d.finish()?;
        progress.note(&format!(
            "wrote {} ParaView files into {} (open particles.pvd and enclosure.pvd)",
            files.len(),
            dir.display()
        ));
    }
    if let Some(sn) = &snaps {
        plot_snapshots(sn, scene, drive, &out_dir)?;
    }
    for w in &shake.summary().warnings {
        progress.warn(&format!("warning: {w}"));
    }
    if a.json {
        print!("{}", shake.summary_json());
    } else {
        print_summary(shake.summary(), &out_dir);
    }
    Ok(())
}

/// The shake's plan from the flags ([`ShakePlan::new`] checks it whole); a
/// refusal names the flag it is about.
fn plan(a: &ShakeArgs) -> Result<ShakePlan> {
    let flags = a
        .scene
        .flags()
        .set(true, "freq_hz", "--freq")
        .set(a.duration_s.is_some(), "duration_s", "--duration-s")
        .set(true, "beds", "--beds");
    let mut scene = a.scene.resolve()?;
    if let Some(d) = a.duration_s {
        scene
            .set_record_length(d, a.freq_hz)
            .map_err(|e| flags.name_flags(e.into()))?;
    }
    let request = ShakeRequest {
        scene,
        freq_hz: a.freq_hz,
        gamma: a.gamma,
        rig: a.rig.clone(),
        shaker: a.shaker,
        noise_seed: a.noise_seed,
        calibration: args::calibration_source(a.calibration.as_deref())?,
        beds: a.beds,
    };
    ShakePlan::new(request).map_err(|e| match e.field {
        RequestField::Beds => flags.name_flags(e.error.into()),
        RequestField::Rig => anyhow::Error::new(e.error).context(format!("--rig {}", a.rig)),
        RequestField::Calibration => anyhow::Error::new(e.error).context("--calibration"),
        RequestField::Drive | RequestField::Record => flags.name_flags(e.error.into()),
    })
}

/// The dump's interval (s): `--dump-every-s`, or an eighth of a cycle;
/// checked before any folder is made or bed poured.
fn dump_every_s(a: &ShakeArgs, drive: &Drive) -> Result<f64> {
    let every_s = a.dump_every_s.unwrap_or(drive.period_s() / 8.0);
    VtkDump::check_every(every_s, drive.period_s())
        .map_err(|e| anyhow::Error::new(e.renamed("--dump-every-s")))?;
    Ok(every_s)
}

/// The ParaView dump `--dump` asks for (its folder made), if any.
fn vtk_dump(a: &ShakeArgs, scene: &Scene, drive: &Drive) -> Result<Option<VtkDump>> {
    let Some(dir) = &a.dump else {
        return Ok(None);
    };
    let every_s = dump_every_s(a, drive)?;
    std::fs::create_dir_all(dir)
        .with_context(|| format!("cannot create --dump folder {}", dir.display()))?;
    Ok(Some(VtkDump::new(
        dir,
        every_s,
        a.dump_from_s.unwrap_or(0.0),
        0.5 * scene.enclosure.inner_diameter_m,
        scene.enclosure.inner_length_m,
    )))
}

/// `snapshots.svg` and `snapshots.png` of the last steady cycle into `dir`.
fn plot_snapshots(sn: &PhaseSnapshots, scene: &Scene, drive: &Drive, dir: &Path) -> Result<()> {
    for ext in ["svg", "png"] {
        sn.plot(
            &dir.join(format!("snapshots.{ext}")),
            &format!(
                "{} damper, {} Hz, Gamma {}, {}: one steady cycle",
                scene.name,
                drive.freq_hz(),
                drive.gamma(),
                scene.enclosure.orientation.as_str()
            ),
            scene.enclosure.orientation,
            0.5 * scene.enclosure.inner_diameter_m,
            scene.enclosure.inner_length_m,
            drive.velocity_amplitude_mps(),
        )?;
    }
    Ok(())
}

/// How the bodies lie: the order parameter settled and over the drive.
fn print_orientation_order(o: &OrientationOrder, steady_cycles: u32) {
    println!(
        "  orientation order S {:+.3} settled, {:+.3} +- {:.3} over the last {} cycles (P2 of each body's symmetry axis against the cylinder's: +1 all along it, -0.5 all across, 0 at random; +- the cycle-to-cycle spread)",
        o.settled,
        o.steady_mean,
        o.steady_sd,
        steady_cycles.min(o.per_cycle.len() as u32),
    );
}

/// The summary as a person reads it.
fn print_summary(s: &ShakeSummary, dir: &Path) {
    let particles = match &s.bodies {
        Some(b) => format!("{} {}s of {} sub-spheres", b.count, b.shape, s.n_particles),
        None => format!("{} particles", s.n_particles),
    };
    println!(
        "{} damper, {} Hz, Gamma {}, {}: {particles} ({:.4} kg, fill {:.3}), dt {:.1e} s, seed {}",
        s.scene,
        s.freq_hz,
        s.gamma,
        s.orientation,
        s.particle_mass_kg,
        s.fill_ratio,
        s.dt_s,
        s.seed
    );
    if let Some(e) = &s.ensemble {
        print_ensemble(e);
        println!(
            "  the first bed (seed {}) alone; its +- is its own window's and leaves out how far other beds lie:",
            s.seed
        );
    }
    print_dem(&s.dem);
    if let Some(o) = s.bodies.as_ref().and_then(|b| b.orientation_order.as_ref()) {
        print_orientation_order(o, s.steady_cycles);
    }
    print_measured(s);
    println!(
        "  state hash {} (the final DEM state{}: the same on any thread count and platform)",
        s.state_hash,
        if s.ensemble.is_some() {
            ", first bed"
        } else {
            ""
        }
    );
    if s.ensemble.is_some() {
        println!("  wrote {}", dir.display());
        return;
    }
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

/// `value +- error unit`, or `value unit` and why there is no error.
fn with_error(value: String, error: Option<String>, unit: &str) -> String {
    match error {
        Some(e) => format!("{value} +- {e}{unit}"),
        None => {
            format!("{value}{unit} (+- not known: fewer than {MIN_SERIES_VALUES} steady cycles)")
        }
    }
}

/// An energy per cycle and its error as the summary prints them (J).
fn energy(value_j: f64, error_j: Option<f64>) -> String {
    with_error(
        format!("{value_j:.4e}"),
        error_j.map(|e| format!("{e:.1e}")),
        " J",
    )
}

/// An efficiency and its error as the summary prints them.
fn efficiency(value: f64, error: Option<f64>) -> String {
    let d = efficiency_decimals(error);
    with_error(
        format!("{value:.d$}"),
        error.map(|e| format!("{e:.d$}")),
        "",
    )
}

/// "1 degree of freedom", "5 degrees of freedom".
pub(crate) fn degrees_of_freedom(dof: usize) -> String {
    format!("{dof} degree{} of freedom", if dof == 1 { "" } else { "s" })
}

/// Decimals for an efficiency with error `error`: 3, or as many as show
/// the error's first significant digit (at 80 Hz, Gamma 38 the efficiency
/// is 0.066 and its error 0.0004, which three decimals print as 0.000).
fn efficiency_decimals(error: Option<f64>) -> usize {
    match error {
        Some(e) if e > 0.0 && e < 0.001 => ((-e.log10()).floor() as usize + 1).clamp(3, 8),
        _ => 3,
    }
}

/// The ensemble: the damper's figures with the beds' spread, and each bed.
fn print_ensemble(e: &EnsembleSummary) {
    let st = &e.steadiness;
    let verdict = if st.reached {
        "steady: error, drift and warm-up tested on the beds' mean".to_string()
    } else if st.lossless {
        "lossless: no steady state".to_string()
    } else if st.capped {
        format!(
            "NOT shown steady: {}",
            unsteady_reasons(st, e.steady_first_cycle)
        )
    } else {
        "not checked steady: fixed cycle count".to_string()
    };
    println!(
        "  ensemble of {} beds (cycles {}-{} of {}; {verdict}):",
        e.beds,
        e.steady_first_cycle + 1,
        e.cycles,
        e.cycles
    );
    let fig = |f: &vlab::experiment::ensemble::EnsembleFigure| match f.stderr {
        Some(_) => format!(
            "{} (+- {:.d$} longer drive)",
            efficiency(f.mean, f.stderr),
            f.longer_drive,
            d = efficiency_decimals(f.stderr)
        ),
        None => format!("{:.3} (+- not known)", f.mean),
    };
    println!(
        "    damping efficiency, DEM truth {}   measured {}",
        fig(&e.dem_efficiency),
        fig(&e.measured_efficiency)
    );
    println!(
        "    (+- : one sigma of the mean over the beds, from their spread ({:.2} % of the mean), Student's t on {}, never less than the beds' own windows' errors make it)",
        100.0 * e.dem_efficiency.spread / e.dem_efficiency.mean.abs().max(f64::MIN_POSITIVE),
        degrees_of_freedom(e.beds.saturating_sub(1))
    );
    let window = e.cycles - e.steady_first_cycle;
    println!(
        "    (longer drive: an allowance, one sigma more, {:.1} % of the mean ({:.0} % over the root of the window's {window} cycles), for where these beds driven hundreds more cycles would read: beds may creep, or fall into another state at random times, too slowly for any window to show, or stay where they are, when it is wide; see docs/accuracy.md)",
        100.0 * longer_drive_rel(window),
        100.0 * LONGER_DRIVE_SCALE
    );
    print_mean_series(st);
    print_bed_rows(e);
    println!(
        "    wall time {:.1} s for {} beds on {} thread{} (settling included), {:.2} M particle-steps/s; the drive {:.2} M particle-steps/s over the beds",
        e.wall_time_s,
        e.beds,
        e.threads,
        if e.threads == 1 { "" } else { "s" },
        e.particle_steps_per_s / 1e6,
        e.drive_particle_steps_per_s / 1e6
    );
}

/// The beds' mean series: its drift across the window, its warm-up and
/// whether it alternates.
fn print_mean_series(st: &Steadiness) {
    let drift = match (st.drift_rel, st.drift_stderr_rel) {
        (Some(r), Some(err)) => format!("{:+.2} % +- {:.2} %", 100.0 * r, 100.0 * err),
        _ => "not known".into(),
    };
    println!(
        "    beds' mean series: drift across the window {drift}, warm-up (MSER-5) {}{}",
        st.warm_up_cycles
            .map_or("not known".to_string(), |d| format!("{d} cycles")),
        if st.alternates {
            "; alternates from cycle to cycle (period 2): averaged in pairs"
        } else {
            ""
        }
    );
}

/// Each bed's efficiency, with its own window's +-, and the measured one.
fn print_bed_rows(e: &EnsembleSummary) {
    println!("    bed  seed        efficiency DEM (its window's +-)   measured");
    let d = efficiency_decimals(e.dem_efficiency.stderr);
    for r in &e.rows {
        let window = r.dem_window_stderr_j.map_or("not known".to_string(), |j| {
            format!("{:.d$}", j / r.dem_energy_per_cycle_j * r.dem_efficiency)
        });
        println!(
            "    {:>3}  {:<10}  {:.d$} (+- {window}){}   {:.d$}",
            r.bed,
            r.seed,
            r.dem_efficiency,
            if r.alternates { " period 2" } else { "" },
            r.measured_efficiency
        );
    }
}

/// What the DEM knows.
fn print_dem(d: &DemTruth) {
    let pc = &d.dissipated_per_cycle_j;
    let total = pc.total().max(f64::MIN_POSITIVE);
    let st = &d.steadiness;
    println!(
        "  DEM truth (cycles {}-{} of {}; {}):",
        d.steady_first_cycle + 1,
        d.cycles,
        d.cycles,
        if st.reached && !st.drift_asked_small() && !st.drift_shown_small() {
            // One bed is not asked to show its drift small (its error is
            // about 3.5 of its mean's; see damper::ensemble_steadiness).
            "steady as far as one bed tells: no drift told from its noise, none shown small (--beds 6 can)"
        } else if st.reached {
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
        "    energy dissipated per cycle   {}",
        energy(d.energy_per_cycle_j, d.energy_per_cycle_stderr_j)
    );
    println!("    E_max = 4 (Gamma g / w)^2 M   {:.4e} J", d.e_max_j);
    println!(
        "    damping efficiency            {}",
        efficiency(d.efficiency, d.efficiency_stderr)
    );
    let drift = match (st.drift_rel, st.drift_stderr_rel) {
        (Some(r), Some(e)) => format!("{:+.2} % +- {:.2} %", 100.0 * r, 100.0 * e),
        _ => "not known".to_string(),
    };
    println!(
        "    steadiness                    work in vs dissipated {:+.2} %, window's error {}, drift across the window {drift}",
        100.0 * st.balance_rel,
        st.stderr_rel.map_or(percent_or_unknown(None), |r| format!(
            "{} of the mean",
            percent_or_unknown(Some(r))
        ))
    );
    println!(
        "    by source: particle-particle normal {:.1} %, tangential {:.1} %; particle-wall normal {:.1} %, tangential {:.1} %",
        100.0 * pc.pp_normal / total,
        100.0 * pc.pp_tangential / total,
        100.0 * pc.pw_normal / total,
        100.0 * pc.pw_tangential / total
    );
    println!(
        "    energy check                  integration error {:+.1e} of the energy that flowed (velocity Verlet's; falls as dt^2)",
        d.integrator_rel
    );
    println!(
        "    steps per collision           {}",
        steps_per_collision(d)
    );
}

/// The fewest steps a collision took, counted first, then what the
/// time-step rule planned.
fn steps_per_collision(d: &DemTruth) -> String {
    let counted = match (
        d.fewest_counted_steps_per_contact,
        d.fastest_collision_counted_steps,
        d.fastest_collision_planned_steps,
    ) {
        (Some(n), Some(f), Some(p)) => format!(
            "fastest collision counted {f} (the time-step rule planned {p:.1}); fewest counted {n} (a glancing or interrupted contact)"
        ),
        _ => "none counted (no collision began and ended during the drive)".into(),
    };
    let planned = if d.planned_steps_per_contact.is_finite() {
        format!("{:.1}", d.planned_steps_per_contact)
    } else {
        "none".into()
    };
    format!("{counted}; fewest planned {planned}")
}

/// What the rig measured, and how it compares with the DEM.
fn print_measured(s: &ShakeSummary) {
    let d = &s.dem;
    let m = &s.measured;
    println!(
        "  measured by rig {} ({} shaker), Yang's method over {} periods:",
        s.rig, s.shaker, m.n_periods
    );
    let versus = if m.error_vs_dem_rel.is_finite() {
        format!(
            "the chain {:+.2} % vs the work in, the bed's unsteadiness {:+.2} %: {:+.2} % vs DEM",
            100.0 * m.error_vs_dem_work_rel,
            100.0 * m.unsteadiness_rel,
            100.0 * m.error_vs_dem_rel
        )
    } else {
        format!(
            "{:+.2} % vs the DEM's input work, the chain alone; the DEM dissipated nothing",
            100.0 * m.error_vs_dem_work_rel
        )
    };
    println!(
        "    energy per cycle              {}  ({versus})",
        energy(m.energy_per_cycle_j, m.energy_per_cycle_stderr_j),
    );
    println!(
        "    damping efficiency            {}",
        efficiency(m.efficiency, m.efficiency_stderr)
    );
    println!(
        "    (+- : one sigma, this bed's window: its spread from cycle to cycle (period to period for the measurement; pairs of them where they alternate); not the spread of other beds of the damper, which --beds measures (see docs/accuracy.md); the chain: the measurement against the work the enclosure put in, what a lab's post-processing controls; the bed's unsteadiness: work in vs dissipated over the record; their sum is the error vs the DEM's dissipation)"
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
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An error below a thousandth keeps its first significant digit; the
    /// usual three decimals otherwise.
    #[test]
    fn a_small_error_is_printed_with_a_digit() {
        assert_eq!(efficiency(0.066, Some(0.0004)), "0.0660 +- 0.0004");
        assert_eq!(efficiency(0.842, Some(0.004)), "0.842 +- 0.004");
        assert_eq!(efficiency(0.5, Some(0.0)), "0.500 +- 0.000");
        assert_eq!(degrees_of_freedom(1), "1 degree of freedom");
        assert_eq!(degrees_of_freedom(5), "5 degrees of freedom");
    }
}
