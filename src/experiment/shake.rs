//! The main job, `vlab shake`, as library API: a damper filled, settled,
//! driven through a rig and measured, with the DEM truth beside the
//! measurement (thesis eq. 6.3–6.10 and Section 7.4.2), and the files a lab
//! run leaves behind.
//!
//! ```no_run
//! use vlab::scene::Scene;
//! use vlab::experiment::measurement::{CalibrationSource, ShakeSetup};
//! use vlab::experiment::shake::{resolve_rig, run_shake, shake_drive};
//!
//! let scene = Scene::thesis();
//! let drive = shake_drive(&scene, 40.0, 20.0)?;
//! let rig = resolve_rig("thesis-shaker", None, &drive)?;
//! let setup = ShakeSetup {
//!     rig,
//!     drive,
//!     noise_seed: scene.simulation.seed,
//!     calibration: CalibrationSource::OnTheFly,
//! };
//! let mut run = run_shake(&scene, &setup, &mut |_| {})?;
//! println!("efficiency {:.3}", run.summary.dem.efficiency);
//! run.write(std::path::Path::new("signals/my-run"), &scene, &setup, &[])?;
//! # Ok::<(), vlab::scene::SceneError>(())
//! ```

use crate::clock::Stopwatch;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde::Serialize;

use crate::atomic_write::write_bytes_atomic;
use crate::dem::orientation_order::{CYLINDER_AXIS, order_parameter};
use crate::dem::{Dissipation, LedgerBalance};
use crate::drive::Drive;
use crate::experiment::bed::cache::BedSource;
use crate::experiment::bed::settle::{SettledBed, prepare_drive};
use crate::experiment::damper::{
    DRIFT_FLOOR_REL, DriveJudge, DriveOutcome, Observers, OneBed, Progress, Steadiness,
    StepObserver, cycle_energies,
};
use crate::experiment::ensemble_summary::EnsembleSummary;
use crate::experiment::measurement::{
    Measured, ShakeExperiment, ShakeSetup, run_measured_shake_judged,
};
use crate::experiment::orientation_record::{OrientationOrder, OrientationTrack};
use crate::experiment::record::TruthSamples;
use crate::rig::{DaqReport, RigFile, RigSpec, ShakerKind, check_limits};
use crate::scene::{CyclesSpec, Scene, SceneError};
use crate::signals::{Trace, TraceMetadata, write_csv, write_wav_with_full_scale};
use crate::validation::{InvalidParameter, require};
use crate::warning::{FileKey, RunWarning};

/// Sample rate of the truth record (Hz), the thesis DAQ's.
pub const TRUTH_SAMPLE_RATE_HZ: f64 = 40_000.0;

/// The rig `name_or_path` (a built-in name or a rig file) driven by
/// `shaker` (`None`: the rig's own `shaker.kind`), refusing what the rig
/// cannot do with `drive` (thesis: Γ ≤ 12 at 20 Hz, ≤ 40 elsewhere) and an
/// electrodynamic drive on a rig without its parameters.
pub fn resolve_rig(
    name_or_path: &str,
    shaker: Option<ShakerKind>,
    drive: &Drive,
) -> Result<RigSpec, SceneError> {
    let mut rig = RigSpec::from_name_or_path(name_or_path)?;
    if let Some(kind) = shaker {
        rig = rig.with_shaker(kind);
    }
    check_limits(&rig, drive)?;
    if rig.shaker.kind == ShakerKind::Electrodynamic {
        rig.electrodynamic()?;
    }
    Ok(rig)
}

/// The drive of a shake of `scene` at `freq_hz` and `gamma` (under the
/// scene's gravity), checked once, here: a positive frequency and Γ
/// ([`Drive::new`]) that the scene's time step resolves (200 steps a cycle at
/// least) and the 40 kHz truth record too (4 samples a cycle). The run
/// functions below take it as built and do not check it again.
pub fn shake_drive(scene: &Scene, freq_hz: f64, gamma: f64) -> Result<Drive, SceneError> {
    let drive = scene.drive(freq_hz, gamma)?;
    let dt = scene.drive_dt_s(&drive);
    let by_step = 1.0 / (200.0 * dt);
    let by_record = TRUTH_SAMPLE_RATE_HZ / 4.0;
    if freq_hz > by_step.min(by_record) {
        let why = if by_step < by_record {
            format!("at most {by_step:.0} Hz: a cycle needs at least 200 time steps of {dt:.3e} s")
        } else {
            format!(
                "at most {by_record:.0} Hz: the {TRUTH_SAMPLE_RATE_HZ} Hz record needs 4 samples a cycle"
            )
        };
        return Err(InvalidParameter::new("freq_hz", freq_hz, "Hz", why).into());
    }
    Ok(drive)
}

/// Whole drive periods Yang's method needs in the rig's record.
pub const MIN_RECORD_PERIODS: u32 = 2;

/// Whole periods of a `freq_hz` drive that `n` of its periods hold once
/// sampled at `sample_rate_hz`: a record keeps whole samples, so at 1024 Hz
/// and 40 kHz two periods (78.1 samples) are 78 samples, 1.997 periods.
pub fn sampled_whole_periods(n: u32, freq_hz: f64, sample_rate_hz: f64) -> u32 {
    whole_periods_of(
        record_samples(n, freq_hz, sample_rate_hz),
        freq_hz,
        sample_rate_hz,
    )
}

/// Samples a record of `n` periods holds.
fn record_samples(n: u32, freq_hz: f64, sample_rate_hz: f64) -> f64 {
    (f64::from(n) * sample_rate_hz / freq_hz + 1e-9).floor()
}

/// Whole periods `samples` samples hold.
fn whole_periods_of(samples: f64, freq_hz: f64, sample_rate_hz: f64) -> u32 {
    (samples * freq_hz / sample_rate_hz + 1e-9).floor().max(0.0) as u32
}

/// Checks that the scene's steady window, `drive.steady_cycles`, holds the
/// [`MIN_RECORD_PERIODS`] whole periods Yang's method needs in the rig's
/// record of a `freq_hz` drive sampled at `sample_rate_hz`.
pub fn check_record_window(
    scene: &Scene,
    freq_hz: f64,
    sample_rate_hz: f64,
) -> Result<(), InvalidParameter> {
    let n = scene.drive.steady_cycles;
    // A window that starts with the drive (every cycle kept) lacks the
    // sample at its start: the DAQ reads the steps, the first at the end of
    // the first step.
    let from_start = matches!(scene.drive.cycles, CyclesSpec::Count(c) if c == n);
    let lost = if from_start { 1.0 } else { 0.0 };
    let held = |k| {
        whole_periods_of(
            record_samples(k, freq_hz, sample_rate_hz) - lost,
            freq_hz,
            sample_rate_hz,
        )
    };
    if n >= MIN_RECORD_PERIODS && held(n) >= MIN_RECORD_PERIODS {
        return Ok(());
    }
    // k + 1 periods always hold k whole ones, so this ends.
    let least = (MIN_RECORD_PERIODS..)
        .find(|&k| held(k) >= MIN_RECORD_PERIODS)
        .unwrap_or(MIN_RECORD_PERIODS + 1);
    let why = if least == MIN_RECORD_PERIODS {
        String::new()
    } else {
        let samples = record_samples(n, freq_hz, sample_rate_hz) - lost;
        let start = if from_start {
            " (a window from the drive's start lacks its first sample: keep a cycle before it, or one more)"
        } else {
            ""
        };
        format!(
            " at {freq_hz} Hz: sampled at {sample_rate_hz} Hz, {n} periods are {samples} samples, {} whole period{}{start}",
            held(n),
            if held(n) == 1 { "" } else { "s" }
        )
    };
    require(
        false,
        "drive.steady_cycles",
        n,
        "",
        format!(
            "at least {least}{why}: the rig's record needs {MIN_RECORD_PERIODS} whole periods for Yang's method"
        ),
    )
}

/// Default output folder of a shake: `signals/<scene>-<freq>Hz-G<gamma>`.
pub fn default_out_dir(scene: &Scene, drive: &Drive) -> PathBuf {
    let (freq_hz, gamma) = (drive.freq_hz(), drive.gamma());
    PathBuf::from("signals").join(format!("{}-{freq_hz}Hz-G{gamma}", scene.name))
}

pub use crate::scene::validity::YieldVelocities;

/// `r` as a percentage, or "not known" (a window too short to tell).
pub fn percent_or_unknown(r: Option<f64>) -> String {
    r.map_or("not known (too few cycles)".to_string(), |r| {
        format!("{:.2} %", 100.0 * r)
    })
}

/// Fraction of the scene's steps per contact below which a run warns.
pub const STEPS_PER_CONTACT_SLACK: f64 = 0.8;

/// What the DEM knows: thesis eq. 6.3–6.10.
#[derive(Debug, Clone, Serialize)]
pub struct DemTruth {
    /// Dissipated energy per cycle, averaged over the steady cycles (J), eq. 6.9.
    pub energy_per_cycle_j: f64,
    /// Its one-sigma error (J): this bed's window, from its cycle-to-cycle
    /// spread (of pairs of cycles where they alternate,
    /// [`crate::experiment::damper::window_mean`]); `None` when the window
    /// is too short to tell. It says nothing of how far another bed of the
    /// same damper lies: the ensemble's error does
    /// ([`crate::experiment::ensemble`]).
    pub energy_per_cycle_stderr_j: Option<f64>,
    /// Maximum dissipated energy per cycle 4 (Γ g / ω)² M (J), eq. 6.10.
    pub e_max_j: f64,
    /// `energy_per_cycle_j / e_max_j`, eq. 6.8.
    pub efficiency: f64,
    /// Its one-sigma error, as `energy_per_cycle_stderr_j`'s.
    pub efficiency_stderr: Option<f64>,
    /// How steady the window is, and whether the drive reached steady state
    /// or stopped at its cap.
    pub steadiness: Steadiness,
    /// Cycles driven, and the first cycle of the steady window.
    pub cycles: u32,
    pub steady_first_cycle: u32,
    /// Fewest time steps a collision of the drive took, counted from its
    /// first to its last step of overlap, over the collisions that began and
    /// ended during the drive; `None` (null) when none did.
    pub fewest_counted_steps_per_contact: Option<u32>,
    /// Of the collisions counted, the one planned the fewest steps (the
    /// fastest impact, the one the time step is chosen for): the steps it
    /// took, counted, and those planned for it; `None` (null) when none was
    /// counted. A glancing or interrupted contact may end within a step or
    /// two, so the fewest counted says little of how well the impacts are
    /// resolved; this one does.
    pub fastest_collision_counted_steps: Option<u32>,
    pub fastest_collision_planned_steps: Option<f64>,
    /// Fewest time steps a collision of the drive was planned to take: the
    /// Hertz duration at its approach speed (eq. 5.10) over the step, the
    /// prediction the time-step rule makes; the scene asks for
    /// `steps_per_contact`.
    pub planned_steps_per_contact: f64,
    /// Energy dissipated over the steady cycles, by source (J).
    pub dissipated_j: Dissipation,
    /// The same per cycle (J); sums to `energy_per_cycle_j`.
    pub dissipated_per_cycle_j: Dissipation,
    /// Work the enclosure did on the particles per steady cycle (J): what an
    /// input-power measurement sees.
    pub work_in_per_cycle_j: f64,
    /// (work in − dissipated) / dissipated over the steady cycles: zero in a
    /// steady state; otherwise the bed stored or gave back energy.
    pub steadiness_rel: f64,
    /// The energy check: energy the time integration lost / dissipated
    /// energy over the whole drive (or the work put in, when larger)
    /// (negative: it made energy). Velocity Verlet's own error, O(Δt²): it
    /// falls four times when the step halves, and a dissipation booked in the
    /// wrong channel would show here. (The books' residual is not reported:
    /// the integration term is what closes them, so it is rounding by
    /// construction; debug builds assert it.)
    pub integrator_rel: f64,
    /// Energy balance of the whole drive (J).
    pub ledger: LedgerBalance,
    /// Energy balance of the steady cycles (J).
    pub steady_ledger: LedgerBalance,
    /// Largest particle speed seen at a cycle boundary (m/s).
    pub largest_particle_speed_mps: f64,
    /// Largest normal approach speeds at contact onset during the drive (m/s).
    pub largest_impact_speed_mps: YieldVelocities,
    /// Yield velocities of eq. 5.26, when the material has a yield strength.
    pub yield_velocity_mps: Option<YieldVelocities>,
}

impl DemTruth {
    /// The truth of a drive of `scene`.
    pub fn new(out: &DriveOutcome, scene: &Scene) -> Self {
        // An identity of the books (the integration term is their remainder):
        // only an accounting bug breaks it.
        debug_assert!(
            out.whole.residual_j.abs() <= 1e-6 * out.whole.energy_flowed_j() + 1e-15,
            "energy books do not close: residual {} J",
            out.whole.residual_j
        );
        let energy = out.energy_per_cycle;
        DemTruth {
            energy_per_cycle_j: out.energy_per_cycle_j,
            energy_per_cycle_stderr_j: energy.stderr,
            e_max_j: out.e_max_j,
            efficiency: out.efficiency,
            efficiency_stderr: energy.stderr.map(|e| e / out.e_max_j),
            steadiness: out.steadiness,
            cycles: out.cycles,
            steady_first_cycle: out.steady_first_cycle,
            fewest_counted_steps_per_contact: out.fewest_counted_steps_per_contact,
            fastest_collision_counted_steps: out.fastest_collision.map(|c| c.counted_steps),
            fastest_collision_planned_steps: out
                .fastest_collision
                .map(|c| f64::from(c.planned_steps)),
            planned_steps_per_contact: out.planned_steps_per_contact,
            dissipated_j: out.steady.dissipated,
            dissipated_per_cycle_j: out.dissipated_per_cycle,
            work_in_per_cycle_j: out.work_in_per_cycle_j,
            steadiness_rel: out.work_in_per_cycle_j / out.energy_per_cycle_j - 1.0,
            integrator_rel: out.whole.integrator_relative(),
            ledger: out.whole,
            steady_ledger: out.steady,
            largest_particle_speed_mps: out.largest_speed_mps,
            largest_impact_speed_mps: YieldVelocities {
                particle_particle_mps: out.impact_speeds.particle_particle_mps,
                particle_wall_mps: out.impact_speeds.particle_wall_mps,
            },
            yield_velocity_mps: scene.yield_velocities_mps(),
        }
    }

    /// Warnings a user must see: impacts beyond yield, a record that is not
    /// steady, collisions resolved with too few steps; each with the scene
    /// key that lifts it, where one does.
    ///
    /// Over 80 lines: one check after another, each with its own words and the
    /// key that lifts it.
    pub fn warnings(&self, freq_hz: f64, steps_per_contact: f64, bodies: bool) -> Vec<RunWarning> {
        let mut w = Vec::new();
        if let Some(y) = &self.yield_velocity_mps {
            let v = &self.largest_impact_speed_mps;
            for (what, speed, limit) in [
                (
                    "particle-particle",
                    v.particle_particle_mps,
                    y.particle_particle_mps,
                ),
                ("particle-wall", v.particle_wall_mps, y.particle_wall_mps),
            ] {
                if speed > limit {
                    w.push(RunWarning::from(format!(
                        "{what} impacts reached {speed:.2} m/s, above the yield velocity {limit:.2} m/s (thesis eq. 5.26): the contacts would yield and the constant restitution of the model no longer holds (Section 5.5.4)"
                    )));
                }
            }
        }
        let s = &self.steadiness;
        if s.lossless {
            w.push(RunWarning::from(format!(
                "the bed dissipated no energy (every contact elastic and frictionless): the enclosure's work, {:.3e} J per cycle, only heats it, so it has no steady state and no efficiency; the drive stopped after {} cycles",
                self.work_in_per_cycle_j, self.cycles
            )));
        } else if s.capped {
            w.push(RunWarning::advising(format!(
                "the drive stopped at its cap of {} cycles without reaching a steady state: over the last {} cycles the enclosure's work and the dissipation differ by {:+.2} %, the energy per cycle has an error of {} and drifts by {} (the first two should be within drive.balance_rel and drive.stderr_rel, the drift within two of its errors and, for an ensemble, shown within twice the error, or {:.0} %, at two of its errors); the figures are those of an unsteady bed",
                self.cycles,
                self.cycles - self.steady_first_cycle,
                100.0 * s.balance_rel,
                percent_or_unknown(s.stderr_rel),
                match (s.drift_rel, s.drift_stderr_rel) {
                    (Some(d), Some(e)) => format!("{:+.2} % +- {:.2} %", 100.0 * d, 100.0 * e),
                    _ => "an unknown amount".to_string(),
                },
                100.0 * DRIFT_FLOOR_REL
            ), FileKey("drive.max_cycles")));
        } else if !s.reached && self.steadiness_rel.abs() > 0.01 {
            w.push(RunWarning::advising(format!(
                "the bed is not in a steady state over the record: the enclosure put in {:+.1} % of the energy the DEM dissipated (the bed {} the difference), so any input-power measurement differs from the DEM's dissipation by that much; let the drive run until steady (drive.cycles = \"steady\") or lengthen it (at {freq_hz} Hz try {} cycles)",
                100.0 * self.steadiness_rel,
                if self.steadiness_rel < 0.0 {
                    "gave back"
                } else {
                    "stored"
                },
                (freq_hz * 0.5).ceil().max(16.0)
            ), FileKey("drive.cycles")));
        }
        // The rule's impact speed is an estimate; a few collisions of a chaotic
        // bed beat it by a little (the thesis bed: 24 of 25 steps). Warn when
        // a collision lost a fifth of its steps: as counted for the fastest
        // collision counted, or as planned when no collision both began and
        // ended during the drive. (Not the fewest counted: a glancing or
        // interrupted contact ends within a step or two however fine the
        // step.)
        let (fewest, how) = match self.fastest_collision_counted_steps {
            Some(n) => (
                f64::from(n),
                format!("{n} time steps, counted for the fastest collision"),
            ),
            None => (
                self.planned_steps_per_contact,
                format!(
                    "{:.1} time steps, as planned (none was seen from start to end)",
                    self.planned_steps_per_contact
                ),
            ),
        };
        if fewest < STEPS_PER_CONTACT_SLACK * steps_per_contact {
            // A body's contact can pass from one sub-sphere to the next
            // before the collision ends: a sub-sphere pair's count is then
            // shorter than the collision was. And several sub-spheres
            // touching at once make a collision shorter than one pair's,
            // which "sub_sphere_contacts" does not resolve.
            let handed_over = if bodies {
                " (or, between bodies, several sub-spheres touched at once, which simulation.dt_s = \"sub_sphere_contacts\" does not resolve and \"contacts\" does, or the contact passed to a neighbouring sub-sphere before the collision ended)"
            } else {
                ""
            };
            w.push(RunWarning::advising(format!(
                "a collision was resolved with only {how} (the scene asks for {steps_per_contact}, warned below {:.0}): impacts were faster than the time step was chosen for{handed_over}; the contact forces and the restitution are less accurate (give simulation.dt_s a smaller step)",
                STEPS_PER_CONTACT_SLACK * steps_per_contact
            ), FileKey("simulation.dt_s")));
        }
        w
    }
}

/// The rigid bodies of a shake of shapes: how many, what shape, and how
/// they lie.
#[derive(Debug, Clone, Serialize)]
pub struct BodiesSummary {
    pub count: usize,
    pub shape: &'static str,
    /// The order parameter of their symmetry axes against the cylinder's
    /// axis ([`crate::dem::orientation_order`]); none for bodies without one.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub orientation_order: Option<OrientationOrder>,
}

/// Everything `summary.json` says about a shake.
#[derive(Debug, Clone, Serialize)]
pub struct ShakeSummary {
    pub vlab_version: &'static str,
    pub scene: String,
    pub freq_hz: f64,
    pub gamma: f64,
    pub orientation: &'static str,
    pub gravity_mps2: f64,
    /// Spheres in the DEM: the particles, or the sub-spheres of the bodies.
    pub n_particles: usize,
    /// Rigid bodies the spheres make (none in a scene of spheres).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub bodies: Option<BodiesSummary>,
    pub particle_mass_kg: f64,
    pub fill_ratio: f64,
    /// Seed of the bed (`simulation.seed`): the pour, hence the DEM truth.
    pub seed: u64,
    /// Seed of the rig's DAQ noise (`--noise-seed`; the bed's seed unless given).
    pub noise_seed: u64,
    pub dt_s: f64,
    pub cycles: u32,
    pub steady_cycles: u32,
    /// Drive steps.
    pub steps: u64,
    /// Simulated time spent pouring and settling before the drive (s).
    pub settle_time_s: f64,
    /// Start of the steady window and of the rig's record, from the drive start (s).
    pub steady_start_s: f64,
    pub rig: String,
    pub shaker: ShakerKind,
    pub sample_rate_hz: f64,
    /// Wall-clock time of the drive's stepping loop (s).
    pub wall_time_s: f64,
    /// Particles × drive steps / `wall_time_s`. In an ensemble this bed's,
    /// whose wall time counts its waits for the other beds: the DEM's rate
    /// over the beds is the ensemble's `drive_particle_steps_per_s`.
    pub particle_steps_per_s: f64,
    /// Wall-clock time of pouring and settling (s); of reading the bed when
    /// it came from the cache.
    pub settle_wall_time_s: f64,
    /// True when the settled bed was read from the bed cache.
    pub bed_from_cache: bool,
    /// Wall-clock time of the rig and the measurement beyond the drive's
    /// stepping loop: the channels, the calibration, Yang's analysis (s).
    pub rig_wall_time_s: f64,
    pub threads: usize,
    /// The final DEM state's fingerprint, 16 hex digits
    /// ([`crate::dem::state_hash`]): the same scene, drive and seed give the
    /// same on any thread count and platform (the browser lab's included).
    #[serde(default)]
    pub state_hash: String,
    pub dem: DemTruth,
    pub measured: Measured,
    pub warnings: Vec<RunWarning>,
    pub files: Vec<String>,
    /// The ensemble this bed was driven in, when it was one of several
    /// ([`crate::experiment::ensemble`]): the figures of the damper, each
    /// with the error of the beds' spread.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ensemble: Option<EnsembleSummary>,
}

/// A finished shake: the summary and everything recorded.
#[derive(Debug, Clone)]
pub struct ShakeRun {
    pub summary: ShakeSummary,
    pub experiment: ShakeExperiment,
}

/// Pours, settles, drives `scene` through the rig of `setup` and measures it.
pub fn run_shake(
    scene: &Scene,
    setup: &ShakeSetup,
    progress: &mut dyn FnMut(Progress),
) -> Result<ShakeRun, SceneError> {
    run_shake_observed(scene, setup, &mut [], progress)
}

/// [`run_shake`] with `observers` called in turn after every DEM step of the
/// drive (a ParaView dump, the snapshots, the motional-phase indicators).
pub fn run_shake_observed(
    scene: &Scene,
    setup: &ShakeSetup,
    observers: &mut [&mut dyn StepObserver],
    progress: &mut dyn FnMut(Progress),
) -> Result<ShakeRun, SceneError> {
    run_shake_from(scene, setup, &BedSource::Settle, observers, progress)
}

/// [`run_shake_observed`] with the bed taken from `beds` (the bed cache:
/// settling is paid once per scene and seed).
pub fn run_shake_from(
    scene: &Scene,
    setup: &ShakeSetup,
    beds: &BedSource,
    observers: &mut [&mut dyn StepObserver],
    progress: &mut dyn FnMut(Progress),
) -> Result<ShakeRun, SceneError> {
    let bed = beds.settle(scene, progress)?;
    run_shake_on_bed(scene, &bed, setup, observers, progress)
}

/// Drives an already settled `bed` of `scene` (the same scene and seed:
/// [`settle_bed`] is deterministic, so this equals [`run_shake`]) through the
/// rig of `setup` and measures it, `observers` called after every step; the
/// bed itself is not changed. A sweep settles each bed once and drives it at
/// every frequency and amplitude this way. The drive is the one
/// [`shake_drive`] built and checked.
pub fn run_shake_on_bed(
    scene: &Scene,
    bed: &SettledBed,
    setup: &ShakeSetup,
    observers: &mut [&mut dyn StepObserver],
    progress: &mut dyn FnMut(Progress),
) -> Result<ShakeRun, SceneError> {
    run_shake_carrying(scene, bed, setup, observers, progress).map(|(run, _)| run)
}

/// [`run_shake_on_bed`] as bed `judged.1` of the beds the judge `judged.0`
/// decides for together (an ensemble, [`crate::experiment::ensemble`]).
pub fn run_shake_on_bed_judged(
    scene: &Scene,
    bed: &SettledBed,
    setup: &ShakeSetup,
    observers: &mut [&mut dyn StepObserver],
    progress: &mut dyn FnMut(Progress),
    judged: (&dyn DriveJudge, usize),
) -> Result<ShakeRun, SceneError> {
    drive_bed(scene, bed, setup, observers, progress, judged).map(|(run, _)| run)
}

/// [`run_shake_on_bed`] that hands back the bed as the drive left it, for
/// the next condition of a sweep that carries the bed's state from one
/// amplitude to the next as a lab's controller does
/// ([`crate::study::sweep_updown`]).
///
/// The drive ends on a whole cycle, where a sine's enclosure is back at its
/// rest position: the particles keep their positions, velocities, spins and
/// contact histories, and the next drive starts from there at its own
/// amplitude (the enclosure's velocity steps from one amplitude's to the
/// other's at that zero crossing, as a controller's step does).
pub fn run_shake_carrying(
    scene: &Scene,
    bed: &SettledBed,
    setup: &ShakeSetup,
    observers: &mut [&mut dyn StepObserver],
    progress: &mut dyn FnMut(Progress),
) -> Result<(ShakeRun, SettledBed), SceneError> {
    let e_max_j = setup.drive.e_max_j(bed.world.particles.total_mass_kg());
    let judge = OneBed::new(scene.drive_length(), e_max_j);
    let (run, world) = drive_bed(scene, bed, setup, observers, progress, (&judge, 0))?;
    let next = SettledBed {
        world,
        settle_time_s: bed.settle_time_s,
        settle_steps: bed.settle_steps,
        wall_time_s: 0.0,
        packing_fraction: bed.packing_fraction,
        bed_height_m: bed.bed_height_m,
        from_cache: false,
        warnings: Vec::new(),
    };
    Ok((run, next))
}

/// One bed driven and measured: the run and the world as it ended.
fn drive_bed(
    scene: &Scene,
    bed: &SettledBed,
    setup: &ShakeSetup,
    observers: &mut [&mut dyn StepObserver],
    progress: &mut dyn FnMut(Progress),
    judged: (&dyn DriveJudge, usize),
) -> Result<(ShakeRun, crate::dem::World), SceneError> {
    let started = Stopwatch::start();
    let dt = scene.drive_dt_s(&setup.drive);
    // The step's threads are the scene's: an ensemble gives each of its
    // beds its share.
    let mut world = prepare_drive(bed, scene, dt)?;
    // A bed of bodies also keeps how they lie at the end of each cycle.
    let mut track = OrientationTrack::new(setup.drive.freq_hz());
    let mut all: Vec<&mut dyn StepObserver> = Vec::with_capacity(observers.len() + 1);
    all.extend(
        observers
            .iter_mut()
            .map(|o| &mut **o as &mut dyn StepObserver),
    );
    if !world.particles.clumps.is_empty() {
        all.push(&mut track);
    }
    let mut observers = Observers(&mut all);
    if observers.wants_particle_dissipation() {
        world.track_particle_dissipation(true);
    }
    let experiment =
        run_measured_shake_judged(scene, &mut world, setup, &mut observers, progress, judged)?;
    drop(all);
    let order = OrientationOrder::new(
        order_parameter(&bed.world.particles.clumps, CYLINDER_AXIS),
        track.per_cycle,
        experiment.outcome.steady_first_cycle,
    );
    let mut summary = ShakeSummary::new(scene, bed, setup, &experiment, &world, dt, started);
    if let Some(b) = summary.bodies.as_mut() {
        b.orientation_order = order;
    }
    Ok((
        ShakeRun {
            summary,
            experiment,
        },
        world,
    ))
}

impl ShakeSummary {
    /// The summary of `experiment`, a drive of `bed` at step `dt_s` that left
    /// `world`, begun at `started` (wall clock).
    fn new(
        scene: &Scene,
        bed: &SettledBed,
        setup: &ShakeSetup,
        experiment: &ShakeExperiment,
        world: &crate::dem::World,
        dt_s: f64,
        started: Stopwatch,
    ) -> ShakeSummary {
        let outcome = &experiment.outcome;
        let n = world.particles.len();
        let dem = DemTruth::new(outcome, scene);
        let mut warnings = bed.warnings.clone();
        warnings.extend(experiment.measured.clipping.iter().cloned());
        warnings.extend(experiment.measured.calibration_warnings.iter().cloned());
        warnings.extend(dem.warnings(
            setup.drive.freq_hz(),
            scene.simulation.steps_per_contact,
            !world.particles.clumps.is_empty(),
        ));
        ShakeSummary {
            vlab_version: env!("CARGO_PKG_VERSION"),
            scene: scene.name.clone(),
            freq_hz: setup.drive.freq_hz(),
            gamma: setup.drive.gamma(),
            orientation: scene.enclosure.orientation.as_str(),
            gravity_mps2: scene.simulation.gravity_mps2,
            n_particles: n,
            bodies: (!world.particles.clumps.is_empty()).then(|| BodiesSummary {
                count: world.particles.clumps.len(),
                shape: scene.particles.shape.as_str(),
                orientation_order: None,
            }),
            particle_mass_kg: world.particles.total_mass_kg(),
            fill_ratio: scene.fill_ratio(),
            seed: scene.simulation.seed,
            noise_seed: setup.noise_seed,
            dt_s,
            cycles: outcome.cycles,
            steady_cycles: outcome.cycles - outcome.steady_first_cycle,
            steps: outcome.steps,
            settle_time_s: bed.settle_time_s,
            steady_start_s: outcome.steady_start_s,
            rig: setup.rig.name.clone(),
            shaker: experiment.measured.shaker,
            sample_rate_hz: setup.rig.daq.sample_rate_hz,
            wall_time_s: outcome.wall_time_s,
            particle_steps_per_s: (n as u64 * outcome.steps) as f64 / outcome.wall_time_s,
            settle_wall_time_s: bed.wall_time_s,
            bed_from_cache: bed.from_cache,
            rig_wall_time_s: (started.elapsed().as_secs_f64() - outcome.wall_time_s).max(0.0),
            threads: rayon::current_num_threads(),
            state_hash: crate::dem::state_hash::hex(crate::dem::state_hash::state_hash(
                &world.particles,
            )),
            dem,
            measured: experiment.measured.clone(),
            warnings,
            files: Vec::new(),
            ensemble: None,
        }
    }
}

impl ShakeRun {
    /// Writes the run's files into `dir` (which must exist), each atomically,
    /// `summary.json` last; the file names end up in `summary.files`.
    /// `others` are the other beds of its ensemble (none for one bed): their
    /// energies per cycle go into `cycles.csv` beside this bed's.
    ///
    /// Over 80 lines: the run's files one after the other, each a few lines,
    /// `summary.json` last with the names of all.
    pub fn write(
        &mut self,
        dir: &Path,
        scene: &Scene,
        setup: &ShakeSetup,
        others: &[ShakeRun],
    ) -> Result<(), SceneError> {
        let path = dir.join("cycles.csv");
        write_bytes_atomic(&path, cycles_csv(self, others).as_bytes())
            .map_err(|source| SceneError::Write { path, source })?;
        let e = &self.experiment;
        let truth = truth_trace(&e.truth, &self.summary)?;
        write_csv(&dir.join("kinematics.csv"), &truth)?;
        write_rig_record(dir, &e.trace, &e.daq)?;
        e.calibration.save_json(&dir.join("calibration.json"))?;
        #[cfg_attr(not(feature = "plot"), allow(unused_mut))]
        let mut files = vec![
            "summary.json",
            "trace.csv",
            "trace.wav",
            "trace.wav.json",
            "kinematics.csv",
            "calibration.json",
            "cycles.csv",
        ];
        #[cfg(feature = "plot")]
        {
            for ext in ["svg", "png"] {
                plot_record(
                    &dir.join(format!("trace.{ext}")),
                    &e.trace,
                    setup.rig.enclosure.mass_kg + scene.particle_mass_kg(),
                    &format!(
                        "{} damper, {} Hz, Gamma {}: rig {} record (cf. thesis Fig. 7.12)",
                        scene.name,
                        setup.drive.freq_hz(),
                        setup.drive.gamma(),
                        setup.rig.name
                    ),
                    setup.drive.freq_hz(),
                )?;
            }
            files.extend(["trace.svg", "trace.png"]);
            for ext in ["svg", "png"] {
                plot_bed(
                    &dir.join(format!("bed.{ext}")),
                    &e.truth,
                    &format!(
                        "{} damper, {} Hz, Gamma {}: the bed over the last two cycles",
                        scene.name,
                        setup.drive.freq_hz(),
                        setup.drive.gamma()
                    ),
                    setup.drive.freq_hz(),
                )?;
            }
            files.extend(["bed.svg", "bed.png"]);
            for ext in ["svg", "png"] {
                plot_cycles(
                    &dir.join(format!("cycles.{ext}")),
                    self,
                    others,
                    &format!(
                        "{} damper, {} Hz, Gamma {}: efficiency of each cycle, window from cycle {}",
                        scene.name,
                        setup.drive.freq_hz(),
                        setup.drive.gamma(),
                        self.summary.dem.steady_first_cycle + 1
                    ),
                )?;
            }
            files.extend(["cycles.svg", "cycles.png"]);
        }
        #[cfg(not(feature = "plot"))]
        let _ = (scene, setup);
        if let Some(e) = &self.summary.ensemble {
            let path = dir.join("beds.csv");
            write_bytes_atomic(&path, e.beds_csv().as_bytes())
                .map_err(|source| SceneError::Write { path, source })?;
            files.push("beds.csv");
        }
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

/// The energy each cycle of the drive dissipated (J, from its start), for
/// `first` and then each of `others`.
fn beds_cycle_energies(first: &ShakeRun, others: &[ShakeRun]) -> Vec<Vec<f64>> {
    std::iter::once(first)
        .chain(others)
        .map(|r| cycle_energies(&r.experiment.outcome.cycle_snapshots, 0))
        .collect()
}

/// `cycles.csv`: the energy each bed dissipated in each cycle of the drive
/// (J, the DEM's books), their mean and whether the cycle is in the steady
/// window: the series the steady rule judged, to see a warm-up, a drift or
/// a period-2 bed for oneself. `first` is the bed whose records were kept,
/// `others` the rest of its ensemble, in bed order.
pub fn cycles_csv(first: &ShakeRun, others: &[ShakeRun]) -> String {
    let series = beds_cycle_energies(first, others);
    let window_from = first.experiment.outcome.steady_first_cycle as usize;
    let mut out = String::from("cycle,in_window,mean_dissipated_j");
    for k in 1..=series.len() {
        out.push_str(&format!(",bed_{k}_dissipated_j"));
    }
    out.push('\n');
    let cycles = series.iter().map(Vec::len).min().unwrap_or(0);
    for c in 0..cycles {
        let values: Vec<f64> = series.iter().map(|s| s[c]).collect();
        let mean = values.iter().sum::<f64>() / values.len() as f64;
        out.push_str(&format!(
            "{},{},{mean:e}",
            c + 1,
            u8::from(c >= window_from)
        ));
        for v in values {
            out.push_str(&format!(",{v:e}"));
        }
        out.push('\n');
    }
    out
}

/// Writes what a rig recorded: `trace.csv`, and `trace.wav` with its
/// `trace.wav.json` sidecar whose full scales are the ADC's, so that the WAV
/// stores the ADC codes exactly (each file atomically).
pub fn write_rig_record(dir: &Path, trace: &Trace, daq: &DaqReport) -> Result<(), SceneError> {
    write_csv(&dir.join("trace.csv"), trace)?;
    let full_scale: BTreeMap<String, f64> = if daq.ideal_adc {
        BTreeMap::new()
    } else {
        daq.channels
            .iter()
            .map(|c| (c.name.clone(), c.full_scale))
            .collect()
    };
    write_wav_with_full_scale(&dir.join("trace.wav"), trace, &full_scale)?;
    Ok(())
}

/// The truth record as a trace: the enclosure's kinematics and the particles'
/// force on it, at the lab's sample rate. Its metadata says what `vlab
/// replay` needs to replay it: drive frequency and Γ, and in `extra` the
/// particle mass (`particle_mass_kg`), `gravity_mps2`, `orientation` and the
/// whole periods the shake measured (`steady_cycles`).
pub fn truth_trace(samples: &TruthSamples, summary: &ShakeSummary) -> Result<Trace, SceneError> {
    let start = samples.time_s.first().copied().unwrap_or(0.0);
    let mut trace = Trace::new(summary.sample_rate_hz, start)?;
    let mut extra = BTreeMap::new();
    extra.insert(
        "particle_mass_kg".to_string(),
        serde_json::json!(summary.particle_mass_kg),
    );
    extra.insert(
        "gravity_mps2".to_string(),
        serde_json::json!(summary.gravity_mps2),
    );
    extra.insert(
        "orientation".to_string(),
        serde_json::json!(summary.orientation),
    );
    extra.insert("scene".to_string(), serde_json::json!(summary.scene));
    extra.insert(
        "steady_cycles".to_string(),
        serde_json::json!(summary.steady_cycles),
    );
    trace.metadata = TraceMetadata {
        source: format!("vlab {} shake: DEM truth", summary.vlab_version),
        rig: "none (DEM truth, no sensors)".into(),
        drive_freq_hz: Some(summary.freq_hz),
        gamma: Some(summary.gamma),
        extra,
        ..Default::default()
    };
    let columns: [(&str, &str, &Vec<f64>); 7] = [
        ("enclosure_displacement", "m", &samples.displacement_m),
        ("enclosure_velocity", "m/s", &samples.velocity_mps),
        (
            "enclosure_acceleration",
            "m/s^2",
            &samples.acceleration_mps2,
        ),
        ("particle_force_axial", "N", &samples.force_axial_n),
        ("particle_force_x", "N", &samples.force_x_n),
        ("particle_force_y", "N", &samples.force_y_n),
        ("bed_centre_rel", "m", &samples.bed_centre_rel_m),
    ];
    for (name, unit, data) in columns {
        trace.add_channel(name, unit, data.clone())?;
    }
    Ok(trace)
}

/// Two cycles of a rig record as the thesis plots them (Fig. 7.12): the
/// acceleration and the force divided by the total mass `m_total_kg`
/// (enclosure and particles), both in m/s².
#[cfg(feature = "plot")]
pub fn plot_record(
    path: &Path,
    trace: &Trace,
    m_total_kg: f64,
    title: &str,
    freq_hz: f64,
) -> Result<(), SceneError> {
    use crate::signals::{Series, SeriesStyle, plot_xy_svg};
    let a = &trace.channel(crate::rig::ACCEL_CHANNEL)?.samples;
    let f = &trace.channel(crate::rig::FORCE_CHANNEL)?.samples;
    let m_total = m_total_kg;
    let n = ((2.0 * trace.sample_rate_hz / freq_hz).round() as usize).min(a.len());
    let t = |i: usize| 1e3 * trace.time_s(i);
    // The static weight is a constant offset of the force; remove its mean.
    let f_mean = f[..n].iter().sum::<f64>() / n.max(1) as f64;
    let series = [
        Series {
            name: "acceleration".into(),
            points: (0..n).map(|i| (t(i), a[i])).collect(),
            style: SeriesStyle::Line,
        },
        Series {
            name: "force / (m_enclosure + m_particles), mean removed".into(),
            points: (0..n).map(|i| (t(i), (f[i] - f_mean) / m_total)).collect(),
            style: SeriesStyle::Line,
        },
    ];
    plot_xy_svg(
        path,
        title,
        "time from the record start (ms)",
        "m/s^2",
        &series,
    )?;
    Ok(())
}

/// The enclosure's floor and the bed's centre of mass along the axis over
/// the last two cycles of the truth record, in mm in the lab frame: the
/// bed's flights (parabolas under gravity, vertical), its impacts (where
/// its centre turns sharply) and how long it rides on the floor.
#[cfg(feature = "plot")]
pub fn plot_bed(
    path: &Path,
    truth: &TruthSamples,
    title: &str,
    freq_hz: f64,
) -> Result<(), SceneError> {
    use crate::signals::{Series, SeriesStyle, plot_xy_svg};
    let len = truth.len();
    let dt = match truth.time_s.as_slice() {
        [a, b, ..] => b - a,
        _ => return Ok(()),
    };
    let n = ((2.0 / (freq_hz * dt)).round() as usize).min(len);
    let from = len - n;
    let t = |i: usize| 1e3 * truth.time_s[i];
    let series = [
        Series {
            name: "enclosure floor".into(),
            points: (from..len)
                .map(|i| (t(i), 1e3 * truth.displacement_m[i]))
                .collect(),
            style: SeriesStyle::Line,
        },
        Series {
            name: "bed's centre of mass".into(),
            points: (from..len)
                .map(|i| {
                    let z = truth.displacement_m[i] + truth.bed_centre_rel_m[i];
                    (t(i), 1e3 * z)
                })
                .collect(),
            style: SeriesStyle::Line,
        },
    ];
    plot_xy_svg(
        path,
        title,
        "time (ms)",
        "position along the enclosure's axis (mm)",
        &series,
    )?;
    Ok(())
}

/// Most beds [`plot_cycles`] draws one by one; more are drawn as their
/// mean alone.
#[cfg(feature = "plot")]
const MOST_BEDS_DRAWN: usize = 8;

/// `cycles.{svg,png}`: the efficiency of each cycle of the drive (the
/// energy it dissipated over `E_max`) for each bed of `first` and `others`
/// (up to [`MOST_BEDS_DRAWN`]) and their mean, with the cycle the window
/// starts at: a warm-up, a creep, a bed falling into another state or a
/// period-2 bed, seen at once.
#[cfg(feature = "plot")]
pub fn plot_cycles(
    path: &Path,
    first: &ShakeRun,
    others: &[ShakeRun],
    title: &str,
) -> Result<(), SceneError> {
    use crate::signals::{Series, SeriesStyle, plot_xy_svg};
    let e_max = first.summary.dem.e_max_j;
    if e_max <= 0.0 {
        return Ok(());
    }
    let beds = beds_cycle_energies(first, others);
    let cycles = beds.iter().map(Vec::len).min().unwrap_or(0);
    if cycles == 0 {
        return Ok(());
    }
    let line = |name: String, values: &dyn Fn(usize) -> f64| Series {
        name,
        points: (0..cycles)
            .map(|c| ((c + 1) as f64, values(c) / e_max))
            .collect(),
        style: SeriesStyle::Line,
    };
    let mut series = Vec::new();
    if beds.len() <= MOST_BEDS_DRAWN {
        for (k, b) in beds.iter().enumerate() {
            series.push(line(format!("bed {}", k + 1), &|c| b[c]));
        }
    }
    if beds.len() > 1 {
        let n = beds.len() as f64;
        series.push(line(format!("mean of {} beds", beds.len()), &|c| {
            beds.iter().map(|b| b[c]).sum::<f64>() / n
        }));
    }
    let (lo, hi) = series
        .iter()
        .flat_map(|s| s.points.iter().map(|p| p.1))
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), y| {
            (lo.min(y), hi.max(y))
        });
    let start = f64::from(first.summary.dem.steady_first_cycle) + 0.5;
    series.push(Series {
        name: "window starts".into(),
        points: vec![(start, lo), (start, hi)],
        style: SeriesStyle::Line,
    });
    plot_xy_svg(path, title, "cycle", "energy dissipated / E_max", &series)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The truth of a healthy drive: steady, every collision resolved with
    /// the thesis bed's 24 steps, no impact near yield.
    fn healthy() -> DemTruth {
        DemTruth {
            energy_per_cycle_j: 0.056,
            energy_per_cycle_stderr_j: Some(5e-4),
            e_max_j: 0.068,
            efficiency: 0.83,
            efficiency_stderr: Some(0.008),
            steadiness: Steadiness {
                balance_rel: 0.0015,
                stderr_rel: Some(0.009),
                drift_rel: Some(0.002),
                drift_stderr_rel: Some(0.004),
                reached: true,
                capped: false,
                lossless: false,
                ..Steadiness::default()
            },
            cycles: 10,
            steady_first_cycle: 3,
            fewest_counted_steps_per_contact: Some(2),
            fastest_collision_counted_steps: Some(24),
            fastest_collision_planned_steps: Some(24.2),
            planned_steps_per_contact: 24.0,
            dissipated_j: Dissipation::default(),
            dissipated_per_cycle_j: Dissipation::default(),
            work_in_per_cycle_j: 0.056,
            steadiness_rel: 0.0015,
            integrator_rel: 6e-4,
            ledger: LedgerBalance::default(),
            steady_ledger: LedgerBalance::default(),
            largest_particle_speed_mps: 1.5,
            largest_impact_speed_mps: YieldVelocities {
                particle_particle_mps: 1.0,
                particle_wall_mps: 1.0,
            },
            yield_velocity_mps: Some(YieldVelocities {
                particle_particle_mps: 3.5,
                particle_wall_mps: 2.5,
            }),
        }
    }

    #[test]
    fn a_healthy_drive_warns_of_nothing() {
        assert!(healthy().warnings(40.0, 25.0, false).is_empty());
    }

    /// The rule asks for 25 steps at an estimated impact speed; the warning
    /// comes below 0.8 x 25 = 20 (exactly: at 20 steps it is silent), read
    /// from the steps counted for the fastest collision when one was
    /// counted, whatever was planned (and whatever the fewest counted, 2 in
    /// the healthy drive: a glancing contact), and from the planned ones
    /// only when none was. Catches a warning that reads the prediction while
    /// a count exists, one that reads the fewest counted, or one that falls
    /// silent when nothing was counted.
    #[test]
    fn a_collision_below_four_fifths_of_the_asked_steps_warns() {
        assert_eq!(STEPS_PER_CONTACT_SLACK * 25.0, 20.0);
        let mut t = healthy();
        t.fastest_collision_counted_steps = Some(20);
        t.planned_steps_per_contact = 19.9;
        assert!(t.warnings(40.0, 25.0, false).is_empty());
        t.fastest_collision_counted_steps = Some(19);
        t.planned_steps_per_contact = 24.0;
        let w = t.warnings(40.0, 25.0, false);
        assert_eq!(w.len(), 1, "{w:?}");
        for part in [
            "only 19 time steps, counted for the fastest collision",
            "asks for 25",
            "warned below 20",
            "simulation.dt_s",
        ] {
            assert!(w[0].text.contains(part), "'{}' lacks '{part}'", w[0]);
        }
        assert_eq!(w[0].advice, Some(FileKey("simulation.dt_s")));
        assert!(!w[0].text.contains("sub-sphere"), "{}", w[0]);
        // Between bodies a contact can pass to the next sub-sphere: said.
        let w = t.warnings(40.0, 25.0, true);
        assert!(w[0].text.contains("neighbouring sub-sphere"), "{}", w[0]);
        t.fastest_collision_counted_steps = None;
        assert!(t.warnings(40.0, 25.0, false).is_empty());
        t.planned_steps_per_contact = 19.9;
        let w = t.warnings(40.0, 25.0, false);
        assert_eq!(w.len(), 1, "{w:?}");
        assert!(
            w[0].text.contains("only 19.9 time steps, as planned"),
            "{}",
            w[0]
        );
    }

    #[test]
    fn a_drive_stopped_at_its_cap_says_so() {
        let mut t = healthy();
        t.steadiness = Steadiness {
            balance_rel: 0.034,
            stderr_rel: Some(0.021),
            drift_rel: Some(0.05),
            drift_stderr_rel: Some(0.01),
            reached: false,
            capped: true,
            lossless: false,
            ..Steadiness::default()
        };
        t.cycles = 400;
        t.steady_first_cycle = 150;
        t.steadiness_rel = 0.034;
        let w = t.warnings(160.0, 25.0, false);
        assert_eq!(w.len(), 1, "{w:?}");
        for part in [
            "stopped at its cap of 400 cycles",
            "last 250 cycles",
            "+3.40 %",
            "2.10 %",
            "+5.00 % +- 1.00 %",
            "unsteady bed",
        ] {
            assert!(w[0].text.contains(part), "'{}' lacks '{part}'", w[0]);
        }
    }

    #[test]
    fn a_lossless_bed_says_it_has_no_steady_state() {
        let mut t = healthy();
        t.steadiness = Steadiness {
            balance_rel: 100.0,
            stderr_rel: Some(0.0),
            drift_rel: Some(0.0),
            drift_stderr_rel: Some(0.0),
            reached: false,
            capped: false,
            lossless: true,
            ..Steadiness::default()
        };
        t.cycles = 8;
        t.energy_per_cycle_j = 0.0;
        t.work_in_per_cycle_j = 1.234e-3;
        t.steadiness_rel = f64::INFINITY;
        let w = t.warnings(40.0, 25.0, false);
        // One warning: not also "not in a steady state".
        assert_eq!(w.len(), 1, "{w:?}");
        for part in [
            "dissipated no energy",
            "1.234e-3 J per cycle",
            "no steady state and no efficiency",
            "after 8 cycles",
        ] {
            assert!(w[0].text.contains(part), "'{}' lacks '{part}'", w[0]);
        }
    }

    #[test]
    fn impacts_above_the_yield_velocity_warn() {
        let mut t = healthy();
        t.largest_impact_speed_mps.particle_wall_mps = 2.6;
        let w = t.warnings(40.0, 25.0, false);
        assert_eq!(w.len(), 1, "{w:?}");
        assert!(
            w[0].text.contains("particle-wall impacts reached 2.60 m/s")
                && w[0].text.contains("yield velocity 2.50 m/s"),
            "{}",
            w[0]
        );
    }

    #[test]
    fn a_bed_that_moves_with_the_floor_has_its_whole_mass_in_phase() {
        // At Gamma 0.8 the bed never leaves the floor: the particles push
        // the enclosure with -M a (and their weight), so the apparent mass
        // of their force's fundamental is the bed's mass, within 1 % (the
        // bed's own elastic ringing under the drive is all that differs);
        // at Gamma 20, bouncing, it is well below it.
        let mut scene = crate::scene::Scene::thesis();
        scene.drive.cycles = crate::scene::CyclesSpec::Count(12);
        scene.drive.steady_cycles = 8;
        let mass = scene.particle_mass_kg();
        let at = |gamma: f64| {
            let drive = super::shake_drive(&scene, 40.0, gamma).expect("drive");
            let setup = crate::experiment::measurement::ShakeSetup {
                rig: super::resolve_rig("ideal", None, &drive).expect("rig"),
                drive,
                noise_seed: 1,
                calibration: crate::experiment::measurement::CalibrationSource::OnTheFly,
            };
            let run = super::run_shake(&scene, &setup, &mut |_| {}).expect("runs");
            run.experiment
                .truth
                .apparent_mass_kg(run.summary.steady_start_s, 40.0)
        };
        let locked = at(0.8);
        assert!(
            (locked / mass - 1.0).abs() < 0.01,
            "{locked} kg of {mass} kg"
        );
        let bouncing = at(20.0);
        assert!(bouncing < 0.8 * mass, "{bouncing} kg of {mass} kg");
    }
}
