//! `vlab replay` as library API: another DEM code's record of a damper put
//! through vlab's rig and measured as `vlab shake` measures (thesis Section
//! 7.4.2), with the record's own input power as the truth.
//!
//! The record holds, against time, the enclosure's motion along the drive
//! axis (velocity, or displacement, or acceleration) and the force the
//! particles exert on the enclosure along that axis, `F_p` (N, positive along
//! the axis), sampled at the DEM step or averaged over windows: vlab's own
//! `kinematics.csv`, a plain CSV with named columns, or the text LAMMPS and
//! LIGGGHTS `fix ave/time` / `fix print` write ([`crate::signals::table`]).
//! Its time column (s) is found by name (`t`, `time`, `Time`, `TIME`,
//! `time_s`, a CSV's `time [s]`, LAMMPS' `v_time`) or named by the caller
//! ([`ColumnMap::time`]).
//!
//! The rig then does what it does in a shake, with the recorded motion as a
//! prescribed drive ([`RecordedMotion`]): every push step the transducer
//! reads `m_enc a - F_p + W` ([`transducer_force_n`], the enclosure and
//! transducer masses adding their inertia), the accelerometer reads `a`, and
//! both channels go through conditioner, anti-alias filters, sampling, noise
//! and ADC at the DAQ rate ([`Daq`]). The rig's phase error is calibrated
//! and Yang's method (eq. 7.8-7.12) measures the power with the functions a
//! shake uses ([`phase_calibration`], [`measure_trace`]): the empty enclosure
//! at the drive and its 4th and 16th harmonics, the fitted high-pass + skew
//! model at the harmonics, no calibration on a rig that reads exactly, and
//! the uncorrected power and the per-period series with the polarity the corrected
//! power found.
//!
//! **Resampling without aliasing.** Each record value stands for its sample
//! interval `[t_i - h/2, t_i + h/2]`: the force is held over it (exact for a
//! window mean, and for a value at every DEM step), the velocity is the
//! smooth curve whose mean over the interval is its sample
//! ([`RecordedMotion`]), so the work the pushed signals carry is the
//! record's own `Σ F_i v_i h` and an impact between two samples keeps its
//! impulse. The rig is stepped at `h / n`, `n = ceil(h / 1 µs)`
//! (the DEM step of the thesis, so the rig's filters are discretised as in
//! a shake), and its own anti-alias filters and sampling take it to the DAQ
//! rate. A record must therefore be sampled at every DEM step or averaged
//! over its windows (LAMMPS `fix ave/time 1 N N`): a point sample of the
//! impulsive force every `N` steps has aliased before vlab sees it.
//!
//! **Truth.** The record's own dissipated power is its mean input power over
//! the window, `P = (1/T_w) Σ -F_i v_i h` (the work the enclosure did on the
//! particles; in a steady state what they dissipate, thesis eq. 6.3-6.9;
//! [`EnclosureRecord::input_power_w`]), and
//! `E_cycle = P / f`, efficiency `E_cycle / (4 (Γ g / ω)² M)` (eq. 6.8-6.10)
//! when the particle mass `M` is known.
//!
//! **Window.** The last `steady_cycles` (given, else the record's declared
//! `steady_cycles`, else 5, the thesis' protocol) whole drive periods the
//! record covers, ending on a whole number of periods
//! of the record's time axis (`t = k / f`, the drive start for vlab and for
//! `vlab export lammps` decks). Measurement and truth use the same window.
//!
//! Refused, with the reason: a record shorter than two whole periods (Yang's
//! method needs two), with a gap or an irregular step, with time running
//! backwards, with no particle-force column or no motion column, or with a
//! column in a unit that is not SI.

use std::f64::consts::PI;
use std::path::{Path, PathBuf};

use serde::Serialize;

use crate::atomic_write::write_bytes_atomic;
use crate::drive::Drive;
use crate::experiment::measurement::{
    CalibrationRun, CalibrationSource, YangMeasurement, check_given_calibration, measure_trace,
    phase_calibration,
};
use crate::experiment::shake::write_rig_record;
use crate::rig::{
    Daq, DaqReport, EnclosureMotion, RecordedMotion, RigSpec, ShakerKind, check_limits,
    transducer_force_n,
};
use crate::scene::{Orientation, Scene, SceneError};
use crate::signals::column_names::strip_lammps_prefix;
use crate::signals::{
    Channel, PhaseCalibration, Table, Trace, TraceMetadata, efficiency, read_table,
};
use crate::validation::{InvalidParameter, positive};
use crate::warning::{RunWarning, Warning};

/// The rig is stepped at most this far apart (s): the thesis' DEM step.
pub const PUSH_STEP_S: f64 = 1e-6;

/// Default number of whole periods measured (the thesis' steady cycles).
pub const DEFAULT_STEADY_CYCLES: u32 = 5;

/// Names a column may have, per role (compared after LAMMPS' `v_`/`c_`/`f_`
/// prefix is stripped, case-insensitively).
pub const FORCE_NAMES: [&str; 4] = [
    "particle_force_axial",
    "particle_force",
    "force_on_enclosure",
    "enclosure_force",
];
/// Names of an enclosure-velocity column.
pub const VELOCITY_NAMES: [&str; 2] = ["enclosure_velocity", "velocity"];
/// Names of an enclosure-displacement column.
pub const DISPLACEMENT_NAMES: [&str; 2] = ["enclosure_displacement", "displacement"];
/// Names of an enclosure-acceleration column.
pub const ACCELERATION_NAMES: [&str; 2] = ["enclosure_acceleration", "acceleration"];

/// Columns named by the caller, overriding the names above (`None`: found by
/// name; time by [`crate::signals::column_names::TIME_NAMES`]).
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct ColumnMap {
    /// The time column (s), exactly as written (a CSV header's name without
    /// its unit, or the whole cell).
    pub time: Option<String>,
    pub force: Option<String>,
    pub velocity: Option<String>,
    pub displacement: Option<String>,
    pub acceleration: Option<String>,
}

pub use crate::scene::ReplayOption;

/// A warning of a replay, and the option that would lift it.
pub type ReplayWarning = Warning<ReplayOption>;

/// How a record is replayed. `None` fields come from the record's
/// declarations (a vlab CSV's metadata, `# key: value` comments such as those
/// of a `vlab export lammps` record) or, failing that, from the record itself
/// (frequency, Γ) or a default (orientation vertical, g 9.81 m/s²).
#[derive(Debug, Clone)]
pub struct ReplayOptions {
    pub rig: RigSpec,
    pub freq_hz: Option<f64>,
    pub gamma: Option<f64>,
    pub particle_mass_kg: Option<f64>,
    pub orientation: Option<Orientation>,
    pub gravity_mps2: Option<f64>,
    /// Whole periods measured; `None`: the record's declared
    /// `steady_cycles`, else 5, or all the record holds if fewer.
    pub steady_cycles: Option<u32>,
    pub columns: ColumnMap,
    pub calibration: CalibrationSource,
    /// Seed of the rig's noise.
    pub seed: u64,
}

impl ReplayOptions {
    /// Defaults for `rig`: everything from the record, calibration on the fly.
    pub fn new(rig: RigSpec) -> Self {
        ReplayOptions {
            rig,
            freq_hz: None,
            gamma: None,
            particle_mass_kg: None,
            orientation: None,
            gravity_mps2: None,
            steady_cycles: None,
            columns: ColumnMap::default(),
            calibration: CalibrationSource::OnTheFly,
            seed: 1,
        }
    }
}

/// Which columns of the record were used.
#[derive(Debug, Clone, Serialize)]
pub struct UsedColumns {
    pub time: String,
    pub force: String,
    /// The motion column and what it holds (`velocity`, `displacement`,
    /// `acceleration`).
    pub motion: String,
    pub motion_kind: &'static str,
    /// Columns present but not used.
    pub ignored: Vec<String>,
}

/// A record read and checked: uniform time, the particles' force and the
/// enclosure's motion.
#[derive(Debug, Clone)]
pub struct EnclosureRecord {
    pub table: Table,
    pub step_s: f64,
    /// Time of the first row, s.
    pub start_s: f64,
    /// The particles' axial force on the enclosure per row, N.
    pub force_axial_n: Vec<f64>,
    pub motion: RecordedMotion,
    pub columns: UsedColumns,
}

impl EnclosureRecord {
    /// Time of the last row, s.
    pub fn end_s(&self) -> f64 {
        self.start_s + (self.force_axial_n.len() - 1) as f64 * self.step_s
    }

    /// The record's mean input power over `[from_s, to_s]`, W: the mean of
    /// `-F_p v` over the rows, each weighted by the part of its interval
    /// `[t_i - h/2, t_i + h/2]` inside the window.
    pub fn input_power_w(&self, from_s: f64, to_s: f64) -> f64 {
        let h = self.step_s;
        let v = self.motion.velocity_samples_mps();
        let work: f64 = self
            .force_axial_n
            .iter()
            .zip(v)
            .enumerate()
            .map(|(i, (f, v))| {
                let t = self.start_s + i as f64 * h;
                let inside = ((t + 0.5 * h).min(to_s) - (t - 0.5 * h).max(from_s)).max(0.0);
                -f * v * inside
            })
            .sum();
        work / (to_s - from_s)
    }

    /// The particles' force at `t_s`: the value of the row whose interval
    /// `[t_i - h/2, t_i + h/2)` holds `t_s` (the first or last row outside).
    pub fn force_at_n(&self, t_s: f64) -> f64 {
        let i = ((t_s - self.start_s) / self.step_s).round();
        let last = self.force_axial_n.len() - 1;
        self.force_axial_n[(i.max(0.0) as usize).min(last)]
    }
}

/// Reads the record at `path` and picks its columns (see the module docs).
pub fn read_enclosure_record(
    path: &Path,
    names: &ColumnMap,
) -> Result<EnclosureRecord, SceneError> {
    let table = read_table(path, names.time.as_deref())?;
    EnclosureRecord::from_table(table, names)
}

impl EnclosureRecord {
    /// Picks the columns of `table` and checks its time axis. The time column
    /// is the one `table` was read with ([`read_enclosure_record`] reads it
    /// with `names.time`).
    pub fn from_table(table: Table, names: &ColumnMap) -> Result<EnclosureRecord, SceneError> {
        let force = force_column(&table, names)?;
        let motion = motion_columns(&table, names)?;
        check_si_units(&table, force, &motion)?;
        let step_s = table.uniform_step_s()?;
        let start_s = table.time_s[0];
        let recorded = recorded_motion(&motion, start_s, step_s)?;
        let columns = used_columns(&table, force, &motion);
        Ok(EnclosureRecord {
            force_axial_n: force.samples.clone(),
            step_s,
            start_s,
            motion: recorded,
            columns,
            table,
        })
    }
}

/// A refusal of the record `table` was read from.
fn record_refusal(table: &Table, problem: String) -> SceneError {
    SceneError::Record {
        path: table.path.clone(),
        problem,
    }
}

/// The names of the columns of `table`, comma-separated.
fn available_columns(table: &Table) -> String {
    table
        .columns
        .iter()
        .map(|c| c.name.as_str())
        .collect::<Vec<_>>()
        .join(", ")
}

/// The column named `given` (refused when there is none), else the first
/// whose bare name (LAMMPS prefix stripped, lowercase) is one of `known`.
fn find_column<'t>(
    table: &'t Table,
    given: &Option<String>,
    role: &str,
    known: &[&str],
) -> Result<Option<&'t Channel>, SceneError> {
    if let Some(name) = given {
        return table.column(name).map(Some).ok_or_else(|| {
            record_refusal(
                table,
                format!(
                    "no column '{name}' (given as the {role} column); the record has [{}]",
                    available_columns(table)
                ),
            )
        });
    }
    Ok(table.columns.iter().find(|c| {
        let bare = strip_lammps_prefix(&c.name).to_ascii_lowercase();
        known.contains(&bare.as_str())
    }))
}

/// The particles' force column (refused, with the option naming it, when
/// there is none).
fn force_column<'t>(table: &'t Table, names: &ColumnMap) -> Result<&'t Channel, SceneError> {
    find_column(table, &names.force, "force", &FORCE_NAMES)?.ok_or_else(|| {
        SceneError::RecordNeeds {
            path: table.path.clone(),
            problem: format!(
                "no column of the particles' force on the enclosure among [{}]: name it \
                 particle_force_axial (N, the particles' force on the enclosure, positive \
                 along the drive axis), or give its name as {}",
                available_columns(table),
                ReplayOption::ForceColumn
            ),
            option: ReplayOption::ForceColumn,
        }
    })
}

/// The enclosure's motion column of a record, what it holds, and the
/// displacement column if there is one.
struct MotionColumns<'t> {
    column: &'t Channel,
    /// `velocity`, `displacement` or `acceleration`.
    kind: &'static str,
    displacement: Option<&'t Channel>,
}

impl MotionColumns<'_> {
    /// The SI unit of the motion column.
    fn unit(&self) -> &'static str {
        match self.kind {
            "velocity" => "m/s",
            "displacement" => "m",
            _ => "m/s^2",
        }
    }
}

/// The motion column: velocity, else displacement, else acceleration
/// (refused, with the option naming it, when there is none).
fn motion_columns<'t>(
    table: &'t Table,
    names: &ColumnMap,
) -> Result<MotionColumns<'t>, SceneError> {
    let velocity = find_column(table, &names.velocity, "velocity", &VELOCITY_NAMES)?;
    let displacement = find_column(
        table,
        &names.displacement,
        "displacement",
        &DISPLACEMENT_NAMES,
    )?;
    let acceleration = find_column(
        table,
        &names.acceleration,
        "acceleration",
        &ACCELERATION_NAMES,
    )?;
    let (column, kind) = match (velocity, displacement, acceleration) {
        (Some(v), _, _) => (v, "velocity"),
        (None, Some(x), _) => (x, "displacement"),
        (None, None, Some(a)) => (a, "acceleration"),
        (None, None, None) => {
            return Err(SceneError::RecordNeeds {
                path: table.path.clone(),
                problem: format!(
                    "no column of the enclosure's motion among [{}]: name one \
                     enclosure_velocity (m/s), enclosure_displacement (m) or \
                     enclosure_acceleration (m/s^2), or give its name as {}",
                    available_columns(table),
                    ReplayOption::MotionColumn
                ),
                option: ReplayOption::MotionColumn,
            });
        }
    };
    Ok(MotionColumns {
        column,
        kind,
        displacement,
    })
}

/// Refuses a force or motion column whose declared unit is not SI.
fn check_si_units(
    table: &Table,
    force: &Channel,
    motion: &MotionColumns<'_>,
) -> Result<(), SceneError> {
    for (column, unit) in [(force, "N"), (motion.column, motion.unit())] {
        let given = column.unit.trim();
        let same = given.is_empty()
            || given == unit
            || (unit == "m/s^2" && matches!(given, "m/s2" | "m/s²" | "m s^-2"));
        if !same {
            return Err(record_refusal(
                table,
                format!(
                    "column '{}' is in {given}; vlab reads SI records: {unit}",
                    column.name
                ),
            ));
        }
    }
    Ok(())
}

/// The enclosure's motion from its column, rows from `start_s` every
/// `step_s` (s).
fn recorded_motion(
    motion: &MotionColumns<'_>,
    start_s: f64,
    step_s: f64,
) -> Result<RecordedMotion, SceneError> {
    let samples = &motion.column.samples;
    Ok(match motion.kind {
        "velocity" => {
            // Displacement at the start of the first row's interval.
            let x0 = motion
                .displacement
                .map_or(0.0, |x| x.samples[0] - 0.5 * samples[0] * step_s);
            RecordedMotion::from_velocity(start_s, step_s, samples.clone(), x0)?
        }
        "displacement" => RecordedMotion::from_displacement(start_s, step_s, samples)?,
        _ => RecordedMotion::from_acceleration(start_s, step_s, samples)?,
    })
}

/// Which columns of `table` were used, and which not.
fn used_columns(table: &Table, force: &Channel, motion: &MotionColumns<'_>) -> UsedColumns {
    let used = [force.name.as_str(), motion.column.name.as_str()];
    UsedColumns {
        time: table.time_column.clone(),
        force: force.name.clone(),
        motion: motion.column.name.clone(),
        motion_kind: motion.kind,
        ignored: table
            .columns
            .iter()
            .filter(|c| !used.contains(&c.name.as_str()))
            .map(|c| c.name.clone())
            .collect(),
    }
}

/// Where a value of the replay came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Source {
    /// Given by the caller.
    Given,
    /// Declared by the record (metadata or comment).
    Record,
    /// Estimated from the record's motion.
    Estimated,
    /// vlab's default.
    Default,
}

/// The record's own truth over the window.
#[derive(Debug, Clone, Serialize)]
pub struct RecordTruth {
    /// Mean input power `(1/T_w) ∫ -F_p v dt` (W).
    pub power_w: f64,
    /// `power_w / f` (J), eq. 6.9 in a steady state.
    pub energy_per_cycle_j: f64,
    /// `4 (Γ g / ω)² M` (J), eq. 6.10, when `M` is known.
    pub e_max_j: Option<f64>,
    /// `energy_per_cycle_j / e_max_j`, eq. 6.8.
    pub efficiency: Option<f64>,
}

/// The rig's measurement of the replayed record.
#[derive(Debug, Clone, Serialize)]
pub struct ReplayMeasured {
    pub power_w: f64,
    pub energy_per_cycle_j: f64,
    pub efficiency: Option<f64>,
    /// One-sigma errors from the spread of Yang's power over the record's
    /// periods ([`crate::stats::mean_stderr`]; a shake adds the bed-to-bed
    /// part, a replayed record is one run and has none); `None` for a record
    /// too short to tell.
    pub power_stderr_w: Option<f64>,
    pub energy_per_cycle_stderr_j: Option<f64>,
    pub efficiency_stderr: Option<f64>,
    /// Phase error subtracted at the drive frequency (rad).
    pub phase_correction_rad: f64,
    /// True when the rig's force read as the gauge reaction and was negated
    /// (`signals::power`, "Force polarity"), as in a shake.
    pub force_polarity_reversed: bool,
    /// (measured − record truth) / record truth.
    pub error_vs_record_rel: f64,
    pub uncorrected_energy_per_cycle_j: f64,
    pub uncorrected_error_vs_record_rel: f64,
    /// −½ m_enc ω V² sin φ / f (J): the false energy per cycle the
    /// enclosure mass leaks through the rig's phase error.
    pub predicted_leak_per_cycle_j: f64,
    /// The rig model's own phase error at the drive frequency (rad).
    pub rig_phase_error_rad: f64,
    pub calibration: String,
    pub n_periods: usize,
    pub rig: String,
    pub clipping: Vec<RunWarning>,
}

/// Everything `summary.json` says about a replay.
#[derive(Debug, Clone, Serialize)]
pub struct ReplaySummary {
    pub vlab_version: &'static str,
    pub record: String,
    pub format: &'static str,
    pub columns: UsedColumns,
    pub record_rows: usize,
    pub record_step_s: f64,
    pub record_start_s: f64,
    pub record_end_s: f64,
    pub freq_hz: f64,
    pub freq_source: Source,
    pub gamma: f64,
    pub gamma_source: Source,
    /// Fundamental of the recorded acceleration over the window / g.
    pub achieved_gamma: f64,
    pub particle_mass_kg: Option<f64>,
    pub particle_mass_source: Option<Source>,
    pub orientation: &'static str,
    pub orientation_source: Source,
    pub gravity_mps2: f64,
    /// The measured window, in the record's time (s), and its whole periods.
    pub window_start_s: f64,
    pub window_end_s: f64,
    pub periods: u32,
    pub rig: String,
    pub shaker: &'static str,
    pub sample_rate_hz: f64,
    /// Step at which the rig was driven (s).
    pub push_step_s: f64,
    pub truth: RecordTruth,
    pub measured: ReplayMeasured,
    pub warnings: Vec<ReplayWarning>,
    pub files: Vec<String>,
}

/// A finished replay.
#[derive(Debug, Clone)]
pub struct ReplayRun {
    pub summary: ReplaySummary,
    pub trace: Trace,
    pub daq: DaqReport,
    pub calibration: PhaseCalibration,
}

/// Estimates the drive frequency from the velocity's upward crossings of
/// its mean (Hz), if it crosses at least three times.
pub fn estimate_freq_hz(t0_s: f64, step_s: f64, velocity: &[f64]) -> Option<f64> {
    let mean = velocity.iter().sum::<f64>() / velocity.len().max(1) as f64;
    let crossings: Vec<f64> = velocity
        .windows(2)
        .enumerate()
        .filter(|(_, w)| w[0] - mean < 0.0 && w[1] - mean >= 0.0)
        .map(|(i, w)| {
            let frac = (mean - w[0]) / (w[1] - w[0]);
            t0_s + (i as f64 + frac) * step_s
        })
        .collect();
    if crossings.len() < 3 {
        return None;
    }
    let span = crossings[crossings.len() - 1] - crossings[0];
    Some((crossings.len() - 1) as f64 / span)
}

/// Replays `record` through the rig of `options` (see the module docs).
pub fn replay_record(
    record: &EnclosureRecord,
    options: &ReplayOptions,
) -> Result<ReplayRun, SceneError> {
    let mut warnings = Vec::new();
    let inputs = resolve_inputs(record, options, &mut warnings)?;
    let pushed = push_through_rig(record, options, &inputs)?;
    let truth = record_truth(record, &inputs);
    let (measured, calibration) = measure_replay(record, options, &inputs, &pushed, &truth)?;
    closing_warnings(&record.table, &truth, &measured, &mut warnings);
    let summary = replay_summary(
        record,
        &options.rig,
        &inputs,
        pushed.dt_s,
        truth,
        measured,
        warnings,
    );
    Ok(ReplayRun {
        summary,
        trace: pushed.trace,
        daq: pushed.daq,
        calibration,
    })
}

/// What a replay resolved from its options and the record: the drive, the
/// window, the bed, and where each came from.
struct ReplayInputs {
    drive: Drive,
    freq_source: Source,
    gamma_source: Source,
    /// Fundamental of the recorded acceleration over the window / g.
    achieved_gamma: f64,
    window: ReplayWindow,
    orientation: Orientation,
    orientation_source: Source,
    particle_mass_kg: Option<f64>,
    particle_mass_source: Option<Source>,
}

/// Resolves the drive (frequency, window, Γ, gravity), checked against the
/// rig's limits, and the bed (orientation, particle mass) of a replay.
fn resolve_inputs(
    record: &EnclosureRecord,
    options: &ReplayOptions,
    warnings: &mut Vec<ReplayWarning>,
) -> Result<ReplayInputs, SceneError> {
    let table = &record.table;
    let rig = &options.rig;
    let (freq_hz, freq_source) = drive_freq_hz(record, options, warnings)?;
    check_record_step(record, freq_hz, rig, warnings)?;
    let window = replay_window(record, options.steady_cycles, freq_hz, warnings)?;

    // Drive level: as given or declared, else the recorded fundamental.
    let g = gravity_of(options, table)?;
    let omega = 2.0 * PI * freq_hz;
    let achieved_gamma =
        fundamental_velocity_mps(record, freq_hz, window.start_s, window.end_s) * omega / g;
    let (gamma, gamma_source) = match (options.gamma, table.declared_f64("gamma")?) {
        (Some(x), _) => (x, Source::Given),
        (None, Some(x)) => (x, Source::Record),
        (None, None) => (achieved_gamma, Source::Estimated),
    };
    let drive = Drive::new(freq_hz, gamma, g)?;
    check_limits(rig, &drive)?;
    let (orientation, orientation_source) = orientation_of(options, table)?;
    let (particle_mass_kg, particle_mass_source) = particle_mass_of(options, table, warnings)?;
    Ok(ReplayInputs {
        drive,
        freq_source,
        gamma_source,
        achieved_gamma,
        window,
        orientation,
        orientation_source,
        particle_mass_kg,
        particle_mass_source,
    })
}

/// The rig's record of a replay.
struct PushedRecord {
    trace: Trace,
    daq: DaqReport,
    /// Step at which the rig was driven (s).
    dt_s: f64,
}

/// Drives the rig with the record, stepped at `h / n`. DAQ time is record
/// time shifted by whole periods so that the window starts at `t >= 0`.
fn push_through_rig(
    record: &EnclosureRecord,
    options: &ReplayOptions,
    inputs: &ReplayInputs,
) -> Result<PushedRecord, SceneError> {
    let rig = &options.rig;
    let window = &inputs.window;
    let period = inputs.drive.period_s();
    let h = record.step_s;
    let n_sub = ((h / PUSH_STEP_S) - 1e-9).ceil().max(1.0);
    let dt = h / n_sub;
    let shift = if window.start_s < 0.0 {
        (-window.start_s / period).ceil() * period
    } else {
        0.0
    };
    let weight = match inputs.orientation {
        Orientation::Vertical => rig.enclosure.mass_kg * inputs.drive.gravity_mps2(),
        Orientation::Horizontal => 0.0,
    };
    let mut daq = Daq::new(rig, dt, window.start_s + shift, options.seed)?;
    feed_daq(&mut daq, record, window, rig, dt, shift, weight);
    let metadata = replay_metadata(record, inputs, rig);
    let (trace, daq_report) = daq.finish(metadata)?;
    Ok(PushedRecord {
        trace,
        daq: daq_report,
        dt_s: dt,
    })
}

/// The record's own truth over the window: its mean input power, the energy
/// per cycle (eq. 6.9) and, when the particle mass is known, `E_max`
/// (eq. 6.10) and the efficiency (eq. 6.8).
fn record_truth(record: &EnclosureRecord, inputs: &ReplayInputs) -> RecordTruth {
    let drive = &inputs.drive;
    let power_w = record.input_power_w(inputs.window.start_s, inputs.window.end_s);
    let energy_per_cycle_j = power_w / drive.freq_hz();
    let e_max_j = inputs.particle_mass_kg.map(|m| drive.e_max_j(m));
    RecordTruth {
        power_w,
        energy_per_cycle_j,
        e_max_j,
        efficiency: e_max_j.map(|e| energy_per_cycle_j / e),
    }
}

/// Calibrates the rig as a shake calibrates it (the recorded motion is a
/// prescribed drive: the same helper, frequencies, amplitudes and window) and
/// measures the pushed record with Yang's method, against the record's truth.
///
/// Over 80 lines: the calibration and the measurement of one record, in the
/// order a shake does them, sharing the record's channels.
fn measure_replay(
    record: &EnclosureRecord,
    options: &ReplayOptions,
    inputs: &ReplayInputs,
    pushed: &PushedRecord,
    truth: &RecordTruth,
) -> Result<(ReplayMeasured, PhaseCalibration), SceneError> {
    let rig = &options.rig;
    let drive = &inputs.drive;
    let freq_hz = drive.freq_hz();
    let periods = inputs.window.periods;
    let calibration_warnings = match &options.calibration {
        CalibrationSource::Given(table, _) => check_given_calibration(table, &rig.name, freq_hz)?,
        CalibrationSource::OnTheFly => Vec::new(),
    };
    let (calibration, calibration_source) = phase_calibration(
        rig,
        &options.calibration,
        &CalibrationRun {
            shaker: ShakerKind::Prescribed,
            drive: *drive,
            dt_s: pushed.dt_s,
            cycles: inputs.window.transient + periods,
            record_cycles: periods,
            noise_seed: options.seed,
        },
    )?;
    let YangMeasurement {
        corrected,
        uncorrected: raw,
        periods: per_period,
    } = measure_trace(&pushed.trace, freq_hz, &calibration)?;
    if corrected.n_periods != periods as usize {
        return Err(SceneError::Record {
            path: record.table.path.clone(),
            problem: format!(
                "the rig's record holds {} whole periods where {periods} were replayed (the \
                 record ends {:.4e} s before the window's last sample)",
                corrected.n_periods,
                inputs.window.end_s - record.end_s()
            ),
        });
    }
    let measured_efficiency = inputs
        .particle_mass_kg
        .map(|m| {
            efficiency(
                corrected.energy_per_cycle_j,
                m,
                drive.gamma(),
                freq_hz,
                drive.gravity_mps2(),
            )
        })
        .transpose()?;
    let truth_energy = truth.energy_per_cycle_j;
    let v_amp = drive.velocity_amplitude_mps();
    let phi = rig.expected_phase_error_rad(freq_hz);
    let m_enc = rig.enclosure.mass_kg;
    let measured = ReplayMeasured {
        power_w: corrected.power_w,
        energy_per_cycle_j: corrected.energy_per_cycle_j,
        efficiency: measured_efficiency,
        power_stderr_w: per_period.stderr,
        energy_per_cycle_stderr_j: per_period.stderr.map(|e| e / freq_hz),
        efficiency_stderr: per_period
            .stderr
            .zip(truth.e_max_j)
            .map(|(se, e)| se / freq_hz / e),
        phase_correction_rad: corrected.phase_correction_rad,
        force_polarity_reversed: corrected.force_polarity.reversed,
        error_vs_record_rel: corrected.energy_per_cycle_j / truth_energy - 1.0,
        uncorrected_energy_per_cycle_j: raw.energy_per_cycle_j,
        uncorrected_error_vs_record_rel: raw.energy_per_cycle_j / truth_energy - 1.0,
        predicted_leak_per_cycle_j: -0.5 * m_enc * drive.omega_rad_s() * v_amp * v_amp * phi.sin()
            / freq_hz,
        rig_phase_error_rad: phi,
        calibration: calibration_source,
        n_periods: corrected.n_periods,
        rig: rig.name.clone(),
        clipping: [pushed.daq.level_warnings(), calibration_warnings].concat(),
    };
    Ok((measured, calibration))
}

/// The warnings only the finished replay can give: a truth that is not
/// positive (the force's sign), the rig's clipping, an undeclared LAMMPS unit
/// system.
fn closing_warnings(
    table: &Table,
    truth: &RecordTruth,
    measured: &ReplayMeasured,
    warnings: &mut Vec<ReplayWarning>,
) {
    let truth_power = truth.power_w;
    if truth_power <= 0.0 {
        warnings.push(ReplayWarning::from(format!(
            "the record's input power is {truth_power:.4e} W, not positive: is the force the \
             enclosure's on the particles rather than the particles' on the enclosure (the sign)?"
        )));
    }
    // A rig key is not a replay option: the clipping warnings come without advice.
    warnings.extend(
        measured
            .clipping
            .iter()
            .cloned()
            .map(|w| w.advising_as(|_| None)),
    );
    if table.format == crate::signals::TableFormat::LammpsText
        && !table.comments.contains_key("units")
    {
        warnings.push(ReplayWarning::from(
            "the record does not state its LAMMPS unit system (a '# units: si' comment); it was \
             read as SI"
                .to_string(),
        ));
    }
}

/// The summary of a replay (its `files` filled in when it is written).
fn replay_summary(
    record: &EnclosureRecord,
    rig: &RigSpec,
    inputs: &ReplayInputs,
    push_step_s: f64,
    truth: RecordTruth,
    measured: ReplayMeasured,
    warnings: Vec<ReplayWarning>,
) -> ReplaySummary {
    let table = &record.table;
    let drive = &inputs.drive;
    ReplaySummary {
        vlab_version: env!("CARGO_PKG_VERSION"),
        record: table.path.display().to_string(),
        format: table.format.as_str(),
        columns: record.columns.clone(),
        record_rows: table.len(),
        record_step_s: record.step_s,
        record_start_s: record.start_s,
        record_end_s: record.end_s(),
        freq_hz: drive.freq_hz(),
        freq_source: inputs.freq_source,
        gamma: drive.gamma(),
        gamma_source: inputs.gamma_source,
        achieved_gamma: inputs.achieved_gamma,
        particle_mass_kg: inputs.particle_mass_kg,
        particle_mass_source: inputs.particle_mass_source,
        orientation: inputs.orientation.as_str(),
        orientation_source: inputs.orientation_source,
        gravity_mps2: drive.gravity_mps2(),
        window_start_s: inputs.window.start_s,
        window_end_s: inputs.window.end_s,
        periods: inputs.window.periods,
        rig: rig.name.clone(),
        shaker: "recorded",
        sample_rate_hz: rig.daq.sample_rate_hz,
        push_step_s,
        truth,
        measured,
        warnings,
        files: Vec::new(),
    }
}

/// The drive frequency (Hz) and where it came from: given, declared by the
/// record, or estimated from its velocity (with a warning).
fn drive_freq_hz(
    record: &EnclosureRecord,
    options: &ReplayOptions,
    warnings: &mut Vec<ReplayWarning>,
) -> Result<(f64, Source), SceneError> {
    let table = &record.table;
    let h = record.step_s;
    let found = match (options.freq_hz, table.declared_f64("drive_freq_hz")?) {
        (Some(f), _) => (f, Source::Given),
        (None, Some(f)) => (f, Source::Record),
        (None, None) => {
            let f = estimate_freq_hz(record.start_s, h, record.motion.velocity_samples_mps())
                .ok_or_else(|| SceneError::RecordNeeds {
                    path: table.path.clone(),
                    problem: format!(
                        "the record does not state its drive frequency and its velocity does not \
                         oscillate enough to tell it: give it as {}",
                        ReplayOption::FreqHz
                    ),
                    option: ReplayOption::FreqHz,
                })?;
            warnings.push(ReplayWarning::advising(
                format!(
                    "the record does not state its drive frequency; {f:.4} Hz was estimated from \
                     its velocity (give {} for an exact window of whole periods)",
                    ReplayOption::FreqHz
                ),
                ReplayOption::FreqHz,
            ));
            (f, Source::Estimated)
        }
    };
    Ok(found)
}

/// Checks that the record's step resolves a `freq_hz` drive (at least 8
/// samples a period); warns when it is coarser than the DAQ of `rig` samples.
fn check_record_step(
    record: &EnclosureRecord,
    freq_hz: f64,
    rig: &RigSpec,
    warnings: &mut Vec<ReplayWarning>,
) -> Result<(), SceneError> {
    let table = &record.table;
    let h = record.step_s;
    positive("freq_hz", freq_hz, "Hz")?;
    let period = 1.0 / freq_hz;
    if h > period / 8.0 {
        return Err(SceneError::Record {
            path: table.path.clone(),
            problem: format!(
                "a step of {h:.4e} s resolves a {freq_hz} Hz drive with fewer than 8 samples a \
                 period; record at least every {:.4e} s",
                period / 8.0
            ),
        });
    }
    let sample_rate_hz = rig.daq.sample_rate_hz;
    if h > 1.0 / sample_rate_hz * (1.0 + 1e-9) {
        warnings.push(ReplayWarning::from(format!(
            "the record steps {h:.4e} s, coarser than the DAQ's {:.4e} s: each value is held over \
             its interval, so the record's content above {:.0} Hz is that of the hold, not of \
             the damper",
            1.0 / sample_rate_hz,
            0.5 / h
        )));
    }
    Ok(())
}

/// Gravity (m/s^2): given, declared by the record, else the thesis's.
fn gravity_of(options: &ReplayOptions, table: &Table) -> Result<f64, SceneError> {
    let g = match options.gravity_mps2 {
        Some(g) => g,
        None => table
            .declared_f64("gravity_mps2")?
            .unwrap_or(Scene::thesis().simulation.gravity_mps2),
    };
    positive("gravity_mps2", g, "m/s^2")?;
    Ok(g)
}

/// The replayed window of a record: the last whole periods it covers.
struct ReplayWindow {
    /// The record covers from here (its first sample less half a step), s.
    covered_from: f64,
    start_s: f64,
    end_s: f64,
    periods: u32,
    /// Whole periods before the window (at most 100).
    transient: u32,
}

/// The window of `record` at `freq_hz`: `steady_cycles` periods, else the
/// record's declared count, else the thesis's (or all the record covers,
/// with a warning, when it covers fewer).
fn replay_window(
    record: &EnclosureRecord,
    steady_cycles: Option<u32>,
    freq_hz: f64,
    warnings: &mut Vec<ReplayWarning>,
) -> Result<ReplayWindow, SceneError> {
    let table = &record.table;
    let h = record.step_s;
    let period = 1.0 / freq_hz;
    let covered_from = record.start_s - 0.5 * h;
    let end_k = ((record.end_s() + h) / period + 1e-9).floor();
    let window_end = end_k * period;
    let available = ((window_end - covered_from) / period + 1e-9).floor();
    if available < 2.0 {
        return Err(SceneError::Record {
            path: table.path.clone(),
            problem: format!(
                "the record covers {:.3} periods of the {freq_hz} Hz drive ({} rows of {h:.4e} s); \
                 Yang's method needs 2 whole periods",
                (record.end_s() + 0.5 * h - covered_from) / period,
                record.force_axial_n.len()
            ),
        });
    }
    let declared_cycles = match table.declared_f64("steady_cycles")? {
        Some(n) if n >= 1.0 && n.fract() == 0.0 && n <= f64::from(u32::MAX) => Some(n as u32),
        Some(n) => {
            return Err(SceneError::Record {
                path: table.path.clone(),
                problem: format!("steady_cycles = {n}: must be a whole number of periods"),
            });
        }
        None => None,
    };
    let periods = match steady_cycles.or(declared_cycles) {
        Some(n) if n < 2 => {
            return Err(InvalidParameter::new(
                "steady_cycles",
                n,
                "",
                "at least 2 (Yang's method needs 2 whole periods)",
            )
            .into());
        }
        Some(n) if f64::from(n) > available => {
            return Err(InvalidParameter::new(
                "steady_cycles",
                n,
                "",
                format!("at most {available}: the whole periods the record covers"),
            )
            .into());
        }
        Some(n) => n,
        None if available < f64::from(DEFAULT_STEADY_CYCLES) => {
            warnings.push(ReplayWarning::from(format!(
                "the record covers {available} whole periods, fewer than the {DEFAULT_STEADY_CYCLES} \
                 the thesis measured; all {available} are used"
            )));
            available as u32
        }
        None => DEFAULT_STEADY_CYCLES,
    };
    let window_start = window_end - f64::from(periods) * period;
    let transient = (((window_start - covered_from) / period + 1e-9).floor() as u32).min(100);
    Ok(ReplayWindow {
        covered_from,
        start_s: window_start,
        end_s: window_end,
        periods,
        transient,
    })
}

/// The enclosure's orientation and where it came from.
fn orientation_of(
    options: &ReplayOptions,
    table: &Table,
) -> Result<(Orientation, Source), SceneError> {
    Ok(
        match (options.orientation, table.declared_text("orientation")) {
            (Some(o), _) => (o, Source::Given),
            (None, Some(text)) => match text.trim() {
                "vertical" => (Orientation::Vertical, Source::Record),
                "horizontal" => (Orientation::Horizontal, Source::Record),
                other => {
                    return Err(SceneError::Record {
                        path: table.path.clone(),
                        problem: format!("orientation '{other}': must be vertical or horizontal"),
                    });
                }
            },
            (None, None) => (Orientation::Vertical, Source::Default),
        },
    )
}

/// The particles' mass (kg) and where it came from, if known (else a
/// warning: no efficiency).
fn particle_mass_of(
    options: &ReplayOptions,
    table: &Table,
    warnings: &mut Vec<ReplayWarning>,
) -> Result<(Option<f64>, Option<Source>), SceneError> {
    let (particle_mass_kg, particle_mass_source) = match (
        options.particle_mass_kg,
        table.declared_f64("particle_mass_kg")?,
    ) {
        (Some(m), _) => (Some(m), Some(Source::Given)),
        (None, Some(m)) => (Some(m), Some(Source::Record)),
        (None, None) => {
            warnings.push(ReplayWarning::advising(
                format!(
                    "the record does not state the particle mass: no efficiency (give {})",
                    ReplayOption::ParticleMassKg
                ),
                ReplayOption::ParticleMassKg,
            ));
            (None, None)
        }
    };
    if let Some(m) = particle_mass_kg {
        positive("particle_mass_kg", m, "kg")?;
    }
    Ok((particle_mass_kg, particle_mass_source))
}

/// Feeds `daq` with `record` over `window`, stepped at `dt` (s), on the
/// enclosure of `rig` of static weight `weight` (N); DAQ time is record time
/// plus `shift` (s, whole periods). The conditioner is settled first to the
/// record's mean levels, so the record's own start (the drive-start jolt)
/// passes as a transient.
fn feed_daq(
    daq: &mut Daq,
    record: &EnclosureRecord,
    window: &ReplayWindow,
    rig: &RigSpec,
    dt: f64,
    shift: f64,
    weight: f64,
) {
    let (window_start, window_end) = (window.start_s, window.end_s);
    let sample_rate_hz = rig.daq.sample_rate_hz;
    let m_enc = rig.enclosure.mass_kg;
    daq.reserve(window_end - window_start + 3.0 / sample_rate_hz);
    let first = (window.covered_from / dt).ceil() as i64;
    let last = ((window_end + 3.0 / sample_rate_hz) / dt).floor() as i64;
    let mean_force = {
        let (sum, n) = (first..=last)
            .map(|m| m as f64 * dt)
            .filter(|&t| t > window_start && t <= window_end)
            .fold((0.0, 0usize), |(s, n), t| (s + record.force_at_n(t), n + 1));
        sum / n.max(1) as f64
    };
    daq.settle_at(0.0, transducer_force_n(m_enc, 0.0, mean_force, weight));
    let mut motion = record.motion.clone();
    for m in first..=last {
        let t = m as f64 * dt;
        let a = motion.advance(t, dt, 0.0).acceleration_mps2;
        let f_p = record.force_at_n(t);
        daq.push(t + shift, a, transducer_force_n(m_enc, a, f_p, weight));
    }
}

/// Amplitude of the velocity's fundamental at `freq_hz` over `[from_s, to_s]`
/// (whole periods), from the record's samples in it (m/s).
fn fundamental_velocity_mps(record: &EnclosureRecord, freq_hz: f64, from_s: f64, to_s: f64) -> f64 {
    let omega = 2.0 * PI * freq_hz;
    let v = record.motion.velocity_samples_mps();
    let (mut re, mut im, mut n) = (0.0, 0.0, 0usize);
    for (i, vi) in v.iter().enumerate() {
        let t = record.start_s + i as f64 * record.step_s;
        if t >= from_s && t < to_s {
            let (s, c) = (omega * t).sin_cos();
            re += vi * c;
            im += vi * s;
            n += 1;
        }
    }
    if n == 0 {
        return 0.0;
    }
    2.0 * (re * re + im * im).sqrt() / n as f64
}

/// The metadata of the rig's trace: the drive, the bed and the record.
fn replay_metadata(
    record: &EnclosureRecord,
    inputs: &ReplayInputs,
    rig: &RigSpec,
) -> TraceMetadata {
    let mut extra = std::collections::BTreeMap::new();
    if let Some(m) = inputs.particle_mass_kg {
        extra.insert("particle_mass_kg".to_string(), serde_json::json!(m));
    }
    extra.insert(
        "gravity_mps2".to_string(),
        serde_json::json!(inputs.drive.gravity_mps2()),
    );
    extra.insert(
        "orientation".to_string(),
        serde_json::json!(inputs.orientation.as_str()),
    );
    extra.insert(
        "replayed_record".to_string(),
        serde_json::json!(record.table.path.display().to_string()),
    );
    extra.insert("shaker".to_string(), serde_json::json!("recorded"));
    TraceMetadata {
        source: format!(
            "vlab {} replay: {} through rig {}",
            env!("CARGO_PKG_VERSION"),
            record.table.path.display(),
            rig.name
        ),
        rig: rig.name.clone(),
        drive_freq_hz: Some(inputs.drive.freq_hz()),
        gamma: Some(inputs.drive.gamma()),
        extra,
        ..Default::default()
    }
}

/// Default output folder of a replay: `signals/replay-<record file stem>`.
pub fn default_out_dir(record: &Path) -> PathBuf {
    let stem = record
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "record".into());
    PathBuf::from("signals").join(format!("replay-{stem}"))
}

impl ReplayRun {
    /// Writes `trace.csv`, `trace.wav` (+ `.wav.json`), `calibration.json`,
    /// `trace.svg` (with the `plot` feature) and `summary.json` (last) into
    /// `dir`, which must exist; each file atomically.
    pub fn write(&mut self, dir: &Path, rig: &RigSpec) -> Result<(), SceneError> {
        write_rig_record(dir, &self.trace, &self.daq)?;
        self.calibration.save_json(&dir.join("calibration.json"))?;
        #[cfg_attr(not(feature = "plot"), allow(unused_mut))]
        let mut files = vec![
            "summary.json",
            "trace.csv",
            "trace.wav",
            "trace.wav.json",
            "calibration.json",
        ];
        #[cfg(feature = "plot")]
        {
            let s = &self.summary;
            for ext in ["svg", "png"] {
                crate::experiment::shake::plot_record(
                    &dir.join(format!("trace.{ext}")),
                    &self.trace,
                    rig.enclosure.mass_kg + s.particle_mass_kg.unwrap_or(0.0),
                    &format!(
                        "replay of {}, {} Hz, Gamma {:.3}: rig {} record (cf. thesis Fig. 7.12)",
                        Path::new(&s.record)
                            .file_name()
                            .map(|n| n.to_string_lossy().into_owned())
                            .unwrap_or_default(),
                        s.freq_hz,
                        s.gamma,
                        s.rig
                    ),
                    s.freq_hz,
                )?;
            }
            files.extend(["trace.svg", "trace.png"]);
        }
        #[cfg(not(feature = "plot"))]
        let _ = rig;
        self.summary.files = files.into_iter().map(String::from).collect();
        let path = dir.join("summary.json");
        write_bytes_atomic(&path, self.summary_json().as_bytes())
            .map_err(|source| SceneError::Write { path, source })
    }

    /// `summary.json`'s text.
    pub fn summary_json(&self) -> String {
        serde_json::to_string_pretty(&self.summary)
            .unwrap_or_else(|e| format!("{{\"error\": \"{e}\"}}"))
            + "\n"
    }
}
