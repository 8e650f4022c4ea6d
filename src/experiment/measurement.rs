//! The damper measured the way the thesis rig measured it (Section 7.4.2).
//!
//! The rig's shaker moves the enclosure (prescribed, or electrodynamic and
//! disturbed by the particles); every DEM step the force transducer reads
//! `m_enc a - F_p + W` and the accelerometer reads `a`, and the rig's channels
//! digitise both from the start of the steady cycles. The conditioner has
//! settled on the damper at rest before the drive starts (its filters start
//! at the settled bed's load on the gauge, not at the first drive step, whose
//! dashpot jolt as the floor meets the resting bed would otherwise decay
//! through the AC coupling over the whole record). Yang's method (eq.
//! 7.8–7.12) turns the record into dissipated power, less the phase error
//! calibrated on the empty enclosure (Fig. 7.9), and the result is held against
//! the DEM's own tally of dissipated energy.
//!
//! The calibration runs the same rig with no particles (no DEM is built) at the
//! same drive frequency, the same number of cycles and the same record window as
//! the damper run, over a few amplitudes, and averages the phase error over them
//! as the thesis did. It also runs at two harmonics of the drive
//! ([`calibration_freqs_hz`]), so that the table's high-pass + skew model
//! (`signals::phase_model`) gives the phase error at every harmonic Yang's sum
//! adds, rather than a pure delay extrapolated from the fundamental.
//!
//! The force polarity of the record is checked (`signals::power`, "Force
//! polarity"); the blocks of the statistical error use the whole record's
//! verdict.

use serde::Serialize;

use crate::dem::World;
use crate::drive::Drive;
use crate::experiment::damper::window_mean;
use crate::experiment::damper::{
    DriveJudge, DriveOutcome, DrivePlan, NoObserver, OneBed, Progress, StepObserver,
    run_drive_judged,
};
use crate::experiment::record::{TruthRecorder, TruthSamples};
use crate::rig::{Daq, DaqReport, RigSpec, Shaker, ShakerKind, ShakerReport, transducer_force_n};
use crate::rig::{EnclosureMotion, Kinematics};
use crate::scene::{Orientation, Scene, SceneError};
use crate::signals::{
    ForcePolarity, PhaseCalibration, PhaseCorrection, PhaseErrorPoint, PowerOptions, PowerResult,
    Trace, TraceMetadata, estimate_phase_error, yang_power_of_trace,
};
use crate::stats::MeanStderr;
use crate::warning::RunWarning;

/// Feeds the rig's DAQ and the truth recorder from every DEM step, and the
/// caller's own observer (a dump, the motional-phase indicators).
struct Instruments<'a> {
    truth: TruthRecorder,
    daq: Daq,
    enclosure_mass_kg: f64,
    static_weight_n: f64,
    extra: &'a mut dyn StepObserver,
}

impl StepObserver for Instruments<'_> {
    fn observe(&mut self, t_s: f64, world: &World, enclosure: &Kinematics) {
        self.extra.observe(t_s, world, enclosure);
        self.truth.observe(t_s, world, enclosure);
        let particle_force = -world.wall_force().dot(world.walls.axis);
        let a = enclosure.acceleration_mps2;
        let f = transducer_force_n(
            self.enclosure_mass_kg,
            a,
            particle_force,
            self.static_weight_n,
        );
        self.daq.push(t_s, a, f);
    }
}

/// Where the phase calibration came from.
#[derive(Debug, Clone)]
pub enum CalibrationSource {
    /// A table given by the user (a file path or a description).
    Given(PhaseCalibration, String),
    /// Measured now on the empty enclosure of the same rig.
    OnTheFly,
}

/// How a measured shake is run: the rig (driven by its `shaker.kind`), the
/// drive, the seed of the rig's noise and the phase calibration.
#[derive(Debug, Clone)]
pub struct ShakeSetup {
    pub rig: RigSpec,
    pub drive: Drive,
    /// Seed of the DAQ's noise (the damper run's and the on-the-fly
    /// calibration's); the bed's seed is the scene's `simulation.seed`.
    /// `vlab shake` takes the bed's seed unless given `--noise-seed`.
    pub noise_seed: u64,
    pub calibration: CalibrationSource,
}

/// The measurement of a run and how it compares with the DEM.
#[derive(Debug, Clone, Serialize)]
pub struct Measured {
    pub power_w: f64,
    pub energy_per_cycle_j: f64,
    pub efficiency: f64,
    /// One-sigma error of `power_w` (W): Yang's method on each period of the
    /// record ([`period_powers`], the bed's cycle-to-cycle spread as the
    /// record shows it, of pairs of periods where they alternate,
    /// [`crate::experiment::damper::window_mean`]): this bed's window alone;
    /// the spread of independent beds is the ensemble's
    /// ([`crate::experiment::ensemble`]). `None` for a record too short to
    /// tell.
    pub power_stderr_w: Option<f64>,
    pub energy_per_cycle_stderr_j: Option<f64>,
    pub efficiency_stderr: Option<f64>,
    /// Phase error subtracted at the drive frequency (rad).
    pub phase_correction_rad: f64,
    /// True when the record's force read as the gauge reaction and was
    /// negated (`signals::power`, "Force polarity").
    pub force_polarity_reversed: bool,
    /// (measured − DEM dissipated per cycle) / DEM dissipated per cycle.
    pub error_vs_dem_rel: f64,
    /// (measured − DEM work in per cycle) / DEM work in per cycle: the error of
    /// the measurement chain alone, without the change of stored energy over
    /// the record.
    pub error_vs_dem_work_rel: f64,
    /// (DEM work in − DEM dissipated) / dissipated over the record: the part of
    /// `error_vs_dem_rel` that is the bed not being steady, not the chain.
    pub unsteadiness_rel: f64,
    /// Energy per cycle without the phase correction (J).
    pub uncorrected_energy_per_cycle_j: f64,
    pub uncorrected_error_vs_dem_rel: f64,
    /// The false energy per cycle the enclosure mass leaks through the rig's
    /// phase error, −½ m_enc ω V² sin φ_err / f (J): what the uncorrected error
    /// should be.
    pub predicted_leak_per_cycle_j: f64,
    /// The rig model's own phase error at the drive frequency (rad).
    pub rig_phase_error_rad: f64,
    pub calibration: String,
    pub n_periods: usize,
    pub rig: String,
    pub shaker: ShakerKind,
    /// Fundamental enclosure acceleration / g over the last cycle.
    pub achieved_gamma: Option<f64>,
    pub clipping: Vec<RunWarning>,
    /// What the given calibration table could not show
    /// ([`check_given_calibration`]).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub calibration_warnings: Vec<RunWarning>,
}

/// A measured damper run.
#[derive(Debug, Clone)]
pub struct ShakeExperiment {
    pub outcome: DriveOutcome,
    pub truth: TruthSamples,
    pub trace: Trace,
    pub daq: DaqReport,
    pub shaker: ShakerReport,
    pub measured: Measured,
    pub calibration: PhaseCalibration,
}

/// Static weight the force gauge carries along the drive axis (N).
fn static_weight_n(scene: &Scene, rig: &RigSpec) -> f64 {
    match scene.enclosure.orientation {
        Orientation::Vertical => rig.enclosure.mass_kg * scene.simulation.gravity_mps2,
        Orientation::Horizontal => 0.0,
    }
}

/// Drives a settled `world` of `scene` through the rig and measures it.
pub fn run_measured_shake(
    scene: &Scene,
    world: &mut World,
    setup: &ShakeSetup,
    progress: &mut dyn FnMut(Progress),
) -> Result<ShakeExperiment, SceneError> {
    run_measured_shake_observed(scene, world, setup, &mut NoObserver, progress)
}

/// [`run_measured_shake`], with `observer` also called after every DEM step
/// of the drive (before the rig's instruments, with the same arguments).
pub fn run_measured_shake_observed(
    scene: &Scene,
    world: &mut World,
    setup: &ShakeSetup,
    observer: &mut dyn StepObserver,
    progress: &mut dyn FnMut(Progress),
) -> Result<ShakeExperiment, SceneError> {
    let e_max_j = setup.drive.e_max_j(world.particles.total_mass_kg());
    let judge = OneBed::new(scene.drive_length(), e_max_j);
    run_measured_shake_judged(scene, world, setup, observer, progress, (&judge, 0))
}

/// [`run_measured_shake_observed`] as bed `judged.1` of the beds the judge
/// `judged.0` decides for together (an ensemble, [`crate::experiment::ensemble`]).
///
/// Over 80 lines: the drive through the rig and its measurement in the
/// order a lab works (the shaker and the DAQ set up, the drive, the record
/// cut to the steady window, the phase calibration, Yang's method, the
/// comparison with the DEM), each step using the ones before.
pub fn run_measured_shake_judged(
    scene: &Scene,
    world: &mut World,
    setup: &ShakeSetup,
    observer: &mut dyn StepObserver,
    progress: &mut dyn FnMut(Progress),
    judged: (&dyn DriveJudge, usize),
) -> Result<ShakeExperiment, SceneError> {
    let rig = &setup.rig;
    let drive = &setup.drive;
    let plan = DrivePlan {
        drive: *drive,
        length: scene.drive_length(),
    };
    let particle_mass = world.particles.total_mass_kg();
    let mut shaker = Shaker::new(
        rig,
        rig.shaker.kind,
        drive,
        rig.enclosure.mass_kg,
        particle_mass,
    )?;
    // The DAQ records from the earliest cycle the steady window can start at;
    // the record is cut to the window the drive finds steady.
    let record_start = f64::from(plan.length.min_transient_cycles()) * drive.period_s();
    let mut instruments = Instruments {
        truth: TruthRecorder::new(rig.daq.sample_rate_hz, 0.0),
        daq: settled_daq(scene, setup, world, &plan, record_start)?,
        enclosure_mass_kg: rig.enclosure.mass_kg,
        static_weight_n: static_weight_n(scene, rig),
        extra: observer,
    };
    let outcome = run_drive_judged(
        world,
        &plan,
        &mut shaker,
        &mut instruments,
        progress,
        judged.0,
        judged.1,
    )?;
    let metadata = trace_metadata(scene, setup, particle_mass);
    let (record, daq_report) = instruments.daq.finish(metadata)?;
    // The window's nominal start, a whole number of periods: the DEM's
    // boundary step lies within half a step of it, and cutting at the step's
    // time would drop the boundary sample and with it a whole period.
    let steady_start_s = f64::from(outcome.steady_first_cycle) * drive.period_s();
    let trace = record.from_time(steady_start_s - record_start);
    let (calibration, source) = phase_calibration(
        rig,
        &setup.calibration,
        &CalibrationRun {
            shaker: rig.shaker.kind,
            drive: *drive,
            dt_s: world.dt_s(),
            cycles: outcome.cycles,
            record_cycles: outcome.cycles - outcome.steady_first_cycle,
            noise_seed: setup.noise_seed,
        },
    )?;
    let yang = measure_trace(&trace, drive.freq_hz(), &calibration)?;
    let shaker_report = shaker.report();
    let measured = compare_with_dem(
        setup,
        &outcome,
        &yang,
        particle_mass,
        MeasuredBy {
            source,
            achieved_gamma: shaker_report.achieved_gamma,
            clipping: daq_report.level_warnings(),
        },
    );
    Ok(ShakeExperiment {
        truth: std::mem::take(&mut instruments.truth.samples),
        outcome,
        trace,
        daq: daq_report,
        shaker: shaker_report,
        measured,
        calibration,
    })
}

/// The rig's DAQ for a drive of `plan` on the settled `world`, recording from
/// `record_start_s`, its conditioner settled on the damper at rest.
fn settled_daq(
    scene: &Scene,
    setup: &ShakeSetup,
    world: &World,
    plan: &DrivePlan,
    record_start_s: f64,
) -> Result<Daq, SceneError> {
    let rig = &setup.rig;
    let period = plan.drive.period_s();
    let mut daq = Daq::new(rig, world.dt_s(), record_start_s, setup.noise_seed)?;
    daq.reserve(f64::from(plan.length.max_cycles().min(64)) * period + 0.01);
    // The conditioner has long settled on the damper at rest (the settled
    // bed's weight on the gauge), not on the first step of the drive, whose
    // dashpot jolt would otherwise stand in the AC coupling for seconds.
    let resting_particle_force = -world.wall_force().dot(world.walls.axis);
    daq.settle_at(
        0.0,
        transducer_force_n(
            rig.enclosure.mass_kg,
            0.0,
            resting_particle_force,
            static_weight_n(scene, rig),
        ),
    );
    Ok(daq)
}

/// What the measurement says about itself beside Yang's figures.
struct MeasuredBy {
    /// Where the phase calibration came from.
    source: String,
    achieved_gamma: Option<f64>,
    clipping: Vec<RunWarning>,
}

/// Yang's measurement `yang` of a drive held against the DEM's `outcome`.
fn compare_with_dem(
    setup: &ShakeSetup,
    outcome: &DriveOutcome,
    yang: &YangMeasurement,
    particle_mass_kg: f64,
    by: MeasuredBy,
) -> Measured {
    let rig = &setup.rig;
    let drive = &setup.drive;
    let freq_hz = drive.freq_hz();
    let (corrected, raw) = (&yang.corrected, &yang.uncorrected);
    // The record's statistical part: this bed's window, period by period.
    let power = yang.periods;
    let truth = outcome.energy_per_cycle_j;
    let work_truth = outcome.work_in_per_cycle_j;
    let omega = drive.omega_rad_s();
    let v = drive.velocity_amplitude_mps();
    let phi = rig.expected_phase_error_rad(freq_hz);
    let e_max = drive.e_max_j(particle_mass_kg);
    Measured {
        power_w: corrected.power_w,
        energy_per_cycle_j: corrected.energy_per_cycle_j,
        efficiency: corrected.energy_per_cycle_j / e_max,
        power_stderr_w: power.stderr,
        energy_per_cycle_stderr_j: power.stderr.map(|e| e / freq_hz),
        efficiency_stderr: power.stderr.map(|e| e / freq_hz / e_max),
        unsteadiness_rel: work_truth / truth - 1.0,
        phase_correction_rad: corrected.phase_correction_rad,
        force_polarity_reversed: corrected.force_polarity.reversed,
        error_vs_dem_rel: corrected.energy_per_cycle_j / truth - 1.0,
        error_vs_dem_work_rel: corrected.energy_per_cycle_j / work_truth - 1.0,
        uncorrected_energy_per_cycle_j: raw.energy_per_cycle_j,
        uncorrected_error_vs_dem_rel: raw.energy_per_cycle_j / truth - 1.0,
        predicted_leak_per_cycle_j: -0.5 * rig.enclosure.mass_kg * omega * v * v * phi.sin()
            / freq_hz,
        rig_phase_error_rad: phi,
        calibration: by.source,
        n_periods: corrected.n_periods,
        rig: rig.name.clone(),
        shaker: rig.shaker.kind,
        achieved_gamma: by.achieved_gamma,
        clipping: by.clipping,
        calibration_warnings: match &setup.calibration {
            CalibrationSource::Given(table, _) => {
                check_given_calibration(table, &rig.name, freq_hz).unwrap_or_default()
            }
            CalibrationSource::OnTheFly => Vec::new(),
        },
    }
}

/// How the empty enclosure runs for an on-the-fly calibration: as the run
/// it calibrates (the same shaker, drive, step, length and record window).
#[derive(Debug, Clone, Copy)]
pub struct CalibrationRun {
    pub shaker: ShakerKind,
    pub drive: Drive,
    /// The rig's step (s): the DEM's in a shake, the push step in a replay.
    pub dt_s: f64,
    /// Cycles run, and the last of them recorded.
    pub cycles: u32,
    pub record_cycles: u32,
    /// Seed of the DAQ's noise.
    pub noise_seed: u64,
}

/// The phase-error table a measured run is corrected with, and where it came
/// from, as `vlab shake` and `vlab replay` both take it: the table given;
/// none (zero phase error) when the rig reads exactly
/// ([`RigSpec::needs_no_calibration`]); else the empty enclosure run as
/// `run` at [`calibration_freqs_hz`] and Γ/2 and Γ, averaged over the
/// amplitudes, with the fitted high-pass + skew model for the harmonics.
pub fn phase_calibration(
    rig: &RigSpec,
    source: &CalibrationSource,
    run: &CalibrationRun,
) -> Result<(PhaseCalibration, String), SceneError> {
    if let CalibrationSource::Given(table, description) = source {
        return Ok((table.clone(), description.clone()));
    }
    let freq_hz = run.drive.freq_hz();
    let gamma = run.drive.gamma();
    if rig.needs_no_calibration(freq_hz) {
        return Ok((
            exact_calibration(rig, freq_hz)?,
            format!(
                "none needed: rig {} reads without phase error or noise",
                rig.name
            ),
        ));
    }
    let freqs = calibration_freqs_hz(freq_hz, rig.daq.sample_rate_hz);
    let gammas = [0.5 * gamma, gamma];
    let table = calibrate_rig(
        rig,
        run.shaker,
        &freqs,
        &gammas,
        run.drive.gravity_mps2(),
        run.dt_s,
        run.cycles,
        run.record_cycles,
        run.noise_seed,
    )?
    .table;
    let description = format!(
        "measured on the fly: empty enclosure of rig {} at {} Hz, Gamma {} and {}, averaged{}",
        rig.name,
        join_hz(&freqs),
        gammas[0],
        gammas[1],
        if table.model.is_some() {
            "; harmonics by the fitted high-pass + skew model"
        } else {
            ""
        }
    );
    Ok((table, description))
}

/// Checks a calibration table given to a run on rig `rig` at `freq_hz`
/// (`vlab shake --calibration`, `vlab replay --calibration`), before any
/// work: another rig's table is refused (its phase error is not this rig's:
/// the thesis rig's 5 mrad moves the power by 4.4 % at 40 Hz, Γ 20); a
/// table that names no rig, or a drive frequency outside the frequencies
/// it was measured at (beyond [`crate::signals::analysis::FREQ_TOLERANCE`]),
/// is a warning.
pub fn check_given_calibration(
    table: &PhaseCalibration,
    rig: &str,
    freq_hz: f64,
) -> Result<Vec<RunWarning>, SceneError> {
    let mut warnings = Vec::new();
    let named = table.rig.trim();
    if named.is_empty() {
        warnings.push(RunWarning::from(format!(
            "the calibration names no rig: it cannot be checked against rig {rig}; another rig's table moves the power by several percent"
        )));
    } else if named != rig.trim() {
        return Err(crate::validation::InvalidParameter::new(
            "calibration.rig",
            named,
            "",
            format!(
                "the rig of the run, {rig}: a table of rig {named} corrects another rig's phase error (calibrate this rig with `vlab calibrate --rig {rig}`)"
            ),
        )
        .into());
    }
    let tol = crate::signals::analysis::FREQ_TOLERANCE;
    if let (Some(lo), Some(hi)) = (table.points.first(), table.points.last())
        && (freq_hz < lo.freq_hz * (1.0 - tol) || freq_hz > hi.freq_hz * (1.0 + tol))
    {
        warnings.push(RunWarning::from(format!(
            "the drive frequency {freq_hz} Hz lies outside the calibration's {} to {} Hz: its phase error there is extrapolated",
            lo.freq_hz, hi.freq_hz
        )));
    }
    Ok(warnings)
}

/// Yang's measurement of a rig trace, as `vlab shake` and `vlab replay`
/// both make it.
#[derive(Debug, Clone)]
pub struct YangMeasurement {
    /// Corrected with the calibration, the force polarity detected.
    pub corrected: PowerResult,
    /// Without the phase correction, with the polarity `corrected` found.
    pub uncorrected: PowerResult,
    /// Mean and one-sigma error of Yang's power of each whole period, with
    /// the same correction and polarity ([`period_powers`],
    /// [`crate::stats::mean_stderr`]): the record's statistical part.
    pub periods: MeanStderr,
}

/// Yang's power of `trace` over all its whole periods, corrected with
/// `calibration`; the uncorrected power and the per-period series use the
/// whole record's polarity verdict.
pub fn measure_trace(
    trace: &Trace,
    freq_hz: f64,
    calibration: &PhaseCalibration,
) -> Result<YangMeasurement, SceneError> {
    let corrected = analyse(trace, freq_hz, PhaseCorrection::Table(calibration))?;
    let polarity = if corrected.force_polarity.reversed {
        ForcePolarity::Reversed
    } else {
        ForcePolarity::AsRecorded
    };
    let uncorrected = analyse_with(trace, freq_hz, PhaseCorrection::None, polarity)?;
    let periods = window_mean(&period_powers(trace, freq_hz, calibration, polarity)?).0;
    Ok(YangMeasurement {
        corrected,
        uncorrected,
        periods,
    })
}

/// The frequencies the on-the-fly calibration runs at, Hz: the drive and its
/// 4th and 16th harmonics, those below an eighth of the sample rate (two or
/// three points, so a high-pass + skew model can be fitted up to 1.25 kHz
/// drives at 40 kHz; above, the drive alone).
pub fn calibration_freqs_hz(drive_freq_hz: f64, sample_rate_hz: f64) -> Vec<f64> {
    let mut freqs: Vec<f64> = [4.0, 16.0]
        .iter()
        .map(|h| h * drive_freq_hz)
        .filter(|&f| f < sample_rate_hz / 8.0)
        .collect();
    freqs.insert(0, drive_freq_hz);
    freqs
}

fn join_hz(freqs: &[f64]) -> String {
    let list: Vec<String> = freqs.iter().map(|f| f.to_string()).collect();
    list.join(", ")
}

/// Yang's power of each whole drive period of `trace` (W), corrected with
/// `calibration` and `polarity`: the measured series whose spread says how
/// far to trust the record's mean.
pub fn period_powers(
    trace: &Trace,
    freq_hz: f64,
    calibration: &PhaseCalibration,
    polarity: ForcePolarity,
) -> Result<Vec<f64>, SceneError> {
    let period_samples = trace.sample_rate_hz / freq_hz;
    let n_periods = (trace.len() as f64 / period_samples + 1e-9).floor() as usize;
    let force = &trace.channel(crate::rig::FORCE_CHANNEL)?.samples;
    let accel = &trace.channel(crate::rig::ACCEL_CHANNEL)?.samples;
    let options = PowerOptions {
        phase_correction: PhaseCorrection::Table(calibration),
        force_polarity: polarity,
        ..PowerOptions::default()
    };
    Ok(crate::signals::period_powers(
        force,
        accel,
        trace.sample_rate_hz,
        freq_hz,
        0,
        n_periods,
        &options,
    )?)
}

/// Yang's power of a rig trace over all its whole drive periods, its force
/// polarity detected.
pub fn analyse(
    trace: &Trace,
    freq_hz: f64,
    correction: PhaseCorrection<'_>,
) -> Result<PowerResult, SceneError> {
    analyse_with(trace, freq_hz, correction, ForcePolarity::Detect)
}

/// [`analyse`] with the force polarity given.
pub fn analyse_with(
    trace: &Trace,
    freq_hz: f64,
    correction: PhaseCorrection<'_>,
    polarity: ForcePolarity,
) -> Result<PowerResult, SceneError> {
    let options = PowerOptions {
        phase_correction: correction,
        force_polarity: polarity,
        ..PowerOptions::default()
    };
    Ok(yang_power_of_trace(
        trace,
        crate::rig::FORCE_CHANNEL,
        crate::rig::ACCEL_CHANNEL,
        freq_hz,
        &options,
    )?)
}

fn trace_metadata(scene: &Scene, setup: &ShakeSetup, particle_mass_kg: f64) -> TraceMetadata {
    let g = scene.simulation.gravity_mps2;
    let mut extra = std::collections::BTreeMap::new();
    extra.insert(
        "particle_mass_kg".to_string(),
        serde_json::json!(particle_mass_kg),
    );
    extra.insert("gravity_mps2".to_string(), serde_json::json!(g));
    extra.insert("scene".to_string(), serde_json::json!(scene.name));
    extra.insert(
        "shaker".to_string(),
        serde_json::json!(setup.rig.shaker.kind.as_str()),
    );
    extra.insert("seed".to_string(), serde_json::json!(scene.simulation.seed));
    TraceMetadata {
        source: format!(
            "vlab {} shake: {} damper through rig {}",
            env!("CARGO_PKG_VERSION"),
            scene.name,
            setup.rig.name
        ),
        rig: setup.rig.name.clone(),
        drive_freq_hz: Some(setup.drive.freq_hz()),
        gamma: Some(setup.drive.gamma()),
        extra,
        ..Default::default()
    }
}

/// The calibration of a rig that reads exactly (see
/// [`RigSpec::needs_no_calibration`]): zero phase error at `freq_hz`.
fn exact_calibration(rig: &RigSpec, freq_hz: f64) -> Result<PhaseCalibration, SceneError> {
    let point = crate::signals::PhaseErrorPoint {
        freq_hz,
        accel_amplitude_mps2: 0.0,
        force_amplitude_n: 0.0,
        phase_error_rad: 0.0,
        force_polarity_reversed: false,
    };
    Ok(PhaseCalibration::from_points(rig.name.clone(), &[point])?)
}

/// An empty-enclosure calibration: the amplitude-averaged table and the
/// individual points it averages.
#[derive(Debug, Clone)]
pub struct RigCalibration {
    pub table: PhaseCalibration,
    pub points: Vec<PhaseErrorPoint>,
}

/// Fewest periods of each calibration frequency recorded on the empty
/// enclosure ([`calibrate_rig`]).
pub const MIN_CALIBRATION_PERIODS: u32 = 4;

/// Runs the empty enclosure of `rig` at every frequency and amplitude for
/// `cycles` cycles, recording the last `record_cycles` (at least
/// [`MIN_CALIBRATION_PERIODS`]) as a damper run does, its DAQ noise drawn
/// from `noise_seed`, and estimates the phase error of each record (true
/// force/velocity phase exactly 90°).
#[allow(clippy::too_many_arguments)]
pub fn calibrate_rig(
    rig: &RigSpec,
    kind: ShakerKind,
    freqs_hz: &[f64],
    gammas: &[f64],
    g_mps2: f64,
    dt_s: f64,
    cycles: u32,
    record_cycles: u32,
    noise_seed: u64,
) -> Result<RigCalibration, SceneError> {
    let mut points = Vec::new();
    for &f in freqs_hz {
        // A harmonic's period may not be a whole number of samples: a few
        // periods more than the drive's window keep 2 whole ones in the
        // record whatever the window (2 periods of 2560 Hz at 40 kHz are
        // 31 samples, 1.98 periods).
        let record_cycles_f = record_cycles.max(MIN_CALIBRATION_PERIODS);
        let cycles_f = cycles + (record_cycles_f - record_cycles);
        for &gamma in gammas {
            let drive = Drive::new(f, gamma, g_mps2)?;
            let mut shaker = Shaker::new(rig, kind, &drive, rig.enclosure.mass_kg, 0.0)?;
            let period = drive.period_s();
            let (cycles, record_cycles) = (cycles_f, record_cycles_f);
            let record_start = f64::from(cycles - record_cycles) * period;
            let mut daq = Daq::new(rig, dt_s, record_start, noise_seed)?;
            daq.reserve(f64::from(record_cycles) * period + 0.01);
            let steps = (f64::from(cycles) * period / dt_s).round() as u64;
            // The empty enclosure carries only itself; the rig model sees no
            // particle force (a vertical rig's static weight is DC, outside the method).
            let weight = rig.enclosure.mass_kg * g_mps2;
            for k in 1..=steps {
                let t = k as f64 * dt_s;
                let a = shaker.advance(t, dt_s, 0.0).acceleration_mps2;
                daq.push(
                    t,
                    a,
                    transducer_force_n(rig.enclosure.mass_kg, a, 0.0, weight),
                );
            }
            let (trace, _) = daq.finish(TraceMetadata::default())?;
            let force = &trace.channel(crate::rig::FORCE_CHANNEL)?.samples;
            let accel = &trace.channel(crate::rig::ACCEL_CHANNEL)?.samples;
            points.push(estimate_phase_error(force, accel, trace.sample_rate_hz, f)?);
        }
    }
    let table = PhaseCalibration::from_points(rig.name.clone(), &points)?;
    Ok(RigCalibration { table, points })
}
