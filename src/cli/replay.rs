//! `vlab replay`: another DEM code's record of the enclosure's motion and
//! the particles' force on it, put through vlab's rig and measured as `vlab
//! shake` measures. The work is [`vlab::experiment::replay`]'s; this is its
//! command line.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use clap::Args;
use vlab::stats::MIN_SERIES_VALUES;

use vlab::atomic_write::OutputDir;
use vlab::experiment::replay::{
    ColumnMap, ReplayOptions, ReplaySummary, Source, default_out_dir, read_enclosure_record,
    replay_record,
};
use vlab::rig::{RigFile, RigSpec};
use vlab::scene::Orientation;

use super::{args, hints};

#[derive(Debug, Clone, Args)]
#[command(allow_negative_numbers = true)]
pub struct ReplayArgs {
    /// The record: vlab's kinematics.csv, a CSV with named columns, or the text of
    /// LAMMPS / LIGGGHTS `fix ave/time` or `fix print` (any name not ending in .csv).
    #[arg(value_name = "RECORD")]
    record: PathBuf,
    /// The rig that measures the record: a built-in name (thesis-shaker, ideal) or a
    /// rig file (TOML). Its shaker is replaced by the recorded motion.
    #[arg(long, value_name = "NAME|FILE", default_value = vlab::rig::DEFAULT_RIG)]
    rig: String,
    /// Drive frequency (Hz) [default: the record's, else estimated from its velocity].
    #[arg(long = "freq", value_name = "HZ", value_parser = args::freq_hz)]
    freq_hz: Option<f64>,
    /// Amplitude Γ [default: the record's, else its velocity's fundamental].
    #[arg(long, value_parser = args::gamma)]
    gamma: Option<f64>,
    /// Particle mass (kg), for the efficiency [default: the record's].
    #[arg(long = "particle-mass-kg", value_name = "KG", value_parser = args::positive_kg)]
    particle_mass_kg: Option<f64>,
    /// Gravity relative to the drive axis, for the gauge's static load [default: the
    /// record's, else vertical].
    #[arg(long, value_enum)]
    orientation: Option<Orientation>,
    /// Whole drive periods measured, the last ones of the record [default: 5, or all
    /// the record holds if fewer].
    #[arg(long, value_name = "N")]
    steady_cycles: Option<u32>,
    /// A column of the record by role, when its name is not one vlab knows:
    /// time=NAME (s; known: t, time, time_s, t_s in any case, 'time [s]'),
    /// force=NAME (the particles' force on the enclosure, N), velocity=NAME (m/s),
    /// displacement=NAME (m), acceleration=NAME (m/s^2). Repeatable.
    #[arg(long = "column", value_name = "ROLE=NAME")]
    columns: Vec<String>,
    /// Phase-error table of the rig (from `vlab calibrate`) [default: measure one now
    /// on the empty enclosure as `vlab shake` does: at the drive frequency and its 4th
    /// and 16th harmonics; none on a rig that reads exactly].
    #[arg(long, value_name = "FILE")]
    calibration: Option<PathBuf>,
    /// Seed of the rig's noise.
    #[arg(long, default_value = "1")]
    seed: u64,
    /// Output folder [default: signals/replay-<record name>].
    #[arg(long, value_name = "DIR")]
    out: Option<PathBuf>,
    /// Print the summary as JSON on standard output.
    #[arg(long)]
    json: bool,
}

/// The `--column ROLE=NAME` flags as a column map.
fn column_map(flags: &[String]) -> Result<ColumnMap> {
    let mut map = ColumnMap::default();
    for flag in flags {
        let Some((role, name)) = flag.split_once('=') else {
            bail!("--column = '{flag}': must be ROLE=NAME, e.g. force=particle_force_axial");
        };
        let slot = match role.trim() {
            "time" => &mut map.time,
            "force" => &mut map.force,
            "velocity" => &mut map.velocity,
            "displacement" => &mut map.displacement,
            "acceleration" => &mut map.acceleration,
            other => bail!(
                "--column = '{flag}': role '{other}' must be time, force, velocity, displacement or acceleration"
            ),
        };
        if name.trim().is_empty() {
            bail!("--column = '{flag}': the column name is empty");
        }
        *slot = Some(name.trim().to_string());
    }
    Ok(map)
}

/// Runs the command.
pub fn run(a: ReplayArgs) -> Result<()> {
    let flags = args::FlagKeys::new()
        .set(a.freq_hz.is_some(), "freq_hz", "--freq")
        .set(a.gamma.is_some(), "gamma", "--gamma")
        .set(true, "steady_cycles", "--steady-cycles")
        .set(true, "particle_mass_kg", "--particle-mass-kg");
    let columns = column_map(&a.columns)?;
    let rig = RigSpec::from_name_or_path(&a.rig).with_context(|| format!("--rig {}", a.rig))?;
    let calibration = args::calibration_source(a.calibration.as_deref())?;
    if let vlab::experiment::measurement::CalibrationSource::Given(table, _) = &calibration {
        // The rig, before any work (the frequency's range once it is known).
        vlab::experiment::measurement::check_given_calibration(table, &rig.name, f64::NAN)
            .context("--calibration")?;
    }
    let record = read_enclosure_record(&a.record, &columns)?;
    let options = ReplayOptions {
        freq_hz: a.freq_hz,
        gamma: a.gamma,
        particle_mass_kg: a.particle_mass_kg,
        orientation: a.orientation,
        gravity_mps2: None,
        steady_cycles: a.steady_cycles,
        columns,
        calibration,
        seed: a.seed,
        rig: rig.clone(),
    };
    let out_dir = a.out.clone().unwrap_or_else(|| default_out_dir(&a.record));
    let made = OutputDir::prepare(&out_dir)
        .with_context(|| format!("cannot create output folder {}", out_dir.display()))?;
    let result = replay_record(&record, &options)
        .map_err(|e| flags.name_flags(e.into()))
        .with_context(|| format!("replaying {} through rig {}", a.record.display(), rig.name));
    let mut run = made.keep_if_ok(result)?;
    run.write(&out_dir, &rig)?;
    for w in &run.summary.warnings {
        match w.advice {
            Some(o) => eprintln!("warning: {w} ({})", hints::replay_option_flag(o)),
            None => eprintln!("warning: {w}"),
        }
    }
    if a.json {
        print!("{}", run.summary_json());
    } else {
        print_summary(&run.summary, &out_dir);
    }
    Ok(())
}

fn source(s: Source) -> &'static str {
    match s {
        Source::Given => "given",
        Source::Record => "from the record",
        Source::Estimated => "estimated from the record",
        Source::Default => "default",
    }
}

/// The summary as text, and the folder written.
fn print_summary(s: &ReplaySummary, dir: &Path) {
    print_record(s);
    print_truth(s);
    print_measured(s);
    println!("  wrote {}", dir.display());
}

/// The record read: its rows, columns, drive and window.
fn print_record(s: &ReplaySummary) {
    let c = &s.columns;
    println!(
        "record {} ({}): {} rows every {:.4e} s from {:.6} s to {:.6} s",
        s.record, s.format, s.record_rows, s.record_step_s, s.record_start_s, s.record_end_s
    );
    println!(
        "  columns: time '{}', force '{}', {} '{}'{}",
        c.time,
        c.force,
        c.motion_kind,
        c.motion,
        if c.ignored.is_empty() {
            String::new()
        } else {
            format!("; not used: {}", c.ignored.join(", "))
        }
    );
    println!(
        "  drive {} Hz ({}), Gamma {:.4} ({}; the record's fundamental {:.4}), {} ({})",
        s.freq_hz,
        source(s.freq_source),
        s.gamma,
        source(s.gamma_source),
        s.achieved_gamma,
        s.orientation,
        source(s.orientation_source)
    );
    println!(
        "  window {:.6}-{:.6} s: the last {} whole periods",
        s.window_start_s, s.window_end_s, s.periods
    );
}

/// The record's own dissipation.
fn print_truth(s: &ReplaySummary) {
    let t = &s.truth;
    println!("  the record's own dissipation (mean of -F_p v):");
    println!(
        "    power {:.5} W, energy per cycle {:.4e} J{}",
        t.power_w,
        t.energy_per_cycle_j,
        match (t.efficiency, s.particle_mass_kg) {
            (Some(eta), Some(m)) => format!(", efficiency {eta:.4} (M = {m:.4} kg)"),
            _ => String::new(),
        }
    );
}

/// What the rig measured from the record.
fn print_measured(s: &ReplaySummary) {
    let t = &s.truth;
    let m = &s.measured;
    println!(
        "  measured by rig {} (recorded motion), Yang's method over {} periods:",
        s.rig, m.n_periods
    );
    let pm = |x: Option<f64>| x.map_or(String::new(), |x| format!(" +- {x:.1e}"));
    println!(
        "    power {:.5}{} W, energy per cycle {:.4e}{} J ({:+.3} % vs the record){}",
        m.power_w,
        pm(m.power_stderr_w),
        m.energy_per_cycle_j,
        pm(m.energy_per_cycle_stderr_j),
        100.0 * m.error_vs_record_rel,
        m.efficiency
            .map(|e| format!(", efficiency {e:.4}{}", pm(m.efficiency_stderr)))
            .unwrap_or_default()
    );
    if m.power_stderr_w.is_some() {
        println!(
            "    (+- : one sigma from the spread of Yang's power over the record's periods, the statistical part; a replayed record is one run of one bed, so no bed-to-bed part is in it)"
        );
    } else {
        println!(
            "    (+- not known: the record holds {} periods, the error needs {MIN_SERIES_VALUES})",
            m.n_periods
        );
    }
    println!(
        "    phase correction {:.3} mrad ({})",
        1e3 * m.phase_correction_rad,
        m.calibration
    );
    println!(
        "    force polarity {}",
        if m.force_polarity_reversed {
            "reversed (the force read as the gauge's reaction and was negated)"
        } else {
            "as recorded"
        }
    );
    println!(
        "    without the correction {:.4e} J ({:+.2} % vs the record; predicted leak {:+.2} %)",
        m.uncorrected_energy_per_cycle_j,
        100.0 * m.uncorrected_error_vs_record_rel,
        100.0 * m.predicted_leak_per_cycle_j / t.energy_per_cycle_j
    );
}
