//! Accuracy against run time: how much each figure vlab reports can be
//! trusted, and what it costs to make it better (issue 9, item 6).
//!
//! Three studies, every row with the wall-clock time it took:
//!
//! **(a) DEM: time step, cycles and seeds.** The energy dissipated per cycle
//! (thesis eq. 6.9) and the efficiency (eq. 6.8, 6.10) of the scene driven by
//! a prescribed sine (eq. 6.2). The bed is chaotic: two runs that differ in
//! the last bit diverge within a cycle, so a figure from `n` cycles scatters
//! by its statistical error whatever the time step. The study separates the
//! two errors:
//! - *time step*: one settled bed driven at `dt = x · Δt_R` (the Rayleigh
//!   step, eq. 3.31) for `x` from 0.05 to 1, each for the same cycles,
//!   against the finest `x` as reference; the integrator's own energy error
//!   (the ledger's `integrator` channel, O(Δt²)) is the part of the
//!   discretisation error that the chaos does not hide;
//! - *seeds*: several seeds (each its own random fill, settled once) at the
//!   default time step; the spread of their means is the seed-to-seed spread;
//! - *cycles*: the mean of the first `n` steady cycles against the mean of
//!   all cycles of all seeds, with its standard error (AR(1)-inflated, see
//!   [`crate::stats`]) and the rms deviation of disjoint blocks of `n`
//!   cycles, an empirical check of that standard error.
//!
//! **(b) A single collision** ([`crate::experiment::impact`]): head-on against the
//! wall at the drive's largest expected impact speed, resolved by 5 to 200
//! steps per contact. An elastic collision (e = 1) against Hertz theory: the
//! maximum overlap against Terzioglu 2023, eq. 5.8, the contact duration
//! against eq. 5.10 (twice the time to maximum overlap) and against the exact
//! Hertz integral `t_c = 2 I δ_max / v`, `I = ∫₀¹ (1 − x^{5/2})^{−1/2} dx =
//! (2/5) B(2/5, 1/2) = 1.471638`: eq. 5.10's rounded constant 1.435 sits
//! 6.0e-4 above it (1.4341 in eq. 5.10's form). The scene's damped
//! collision: the realised normal restitution against the configured `e`.
//!
//! **(c) Yang's method** (eq. 7.8–7.12, Section 7.4.2) against the DEM truth.
//! One DEM drive records the particles' force on the enclosure and its
//! acceleration at the DAQ rate (see [`crate::experiment::record`]); the rig's
//! chain ([`crate::rig::Daq`]: filters, skew, noise, ADC) is then re-run on
//! that record with changed settings, without re-running the DEM: record
//! length, noise (a factor on both channels' rms), ADC bits, and a residual
//! phase error left after calibration. Each setting is calibrated as `vlab
//! shake` calibrates: the same chain on the empty enclosure (the same
//! acceleration, no particle force) over the same record window, its phase
//! error at the drive frequency (Fig. 7.9) applied as a delay, as a
//! one-frequency calibration table is; the residual is added to it. The
//! calibration draws its noise from its own stream (a lab's calibration and
//! measurement do not share noise). The record-length rows lead with the
//! chain's own error, Yang's estimate against the work the enclosure did over
//! the record's cycles; then the bed's unsteadiness over them (that work
//! against the DEM's dissipation, thesis eq. 6.9); then the error against the
//! DEM truth, the dissipation over the same cycles, which is both together
//! (`(1 + chain)(1 + unsteadiness) − 1`); and the error against the bed's
//! long-run mean (chain plus statistics). The chain-setting rows compare with
//! the dissipation.
//!
//! The drive here is the prescribed sine, not the rig's electrodynamic
//! shaker: the DEM study is about the DEM, and the chain is re-run on the
//! recorded kinematics.

use crate::clock::Stopwatch;
use std::f64::consts::PI;
use std::path::Path;
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};

use serde::Serialize;

use crate::atomic_write::write_bytes_atomic;
use crate::dem::{LedgerBalance, LedgerSnapshot, World};
use crate::experiment::bed::settle::{SettledBed, prepare_drive, settle_bed};
use crate::experiment::damper::{
    DriveOutcome, DrivePlan, Kinematics, SineMotion, StepObserver, run_drive,
};
use crate::experiment::impact::{ImpactSetup, Target, run_impact};
use crate::experiment::record::{TruthRecorder, TruthSamples};
use crate::rig::{Daq, RigSpec, transducer_force_n};
use crate::scene::DriveLength;
use crate::scene::{Orientation, Scene, SceneError};
use crate::signals::{
    PhaseCorrection, PowerOptions, TraceMetadata, estimate_phase_error, yang_power,
};
use crate::stats::{MeanStderr, mean_stderr};
use crate::validation::InvalidParameter;

/// The exact Hertz duration constant: `t_c = 2 I δ_max / v` with
/// `I = (2/5) B(2/5, 1/2)`.
pub const HERTZ_DURATION_INTEGRAL: f64 = 1.471_637_59;

/// What the studies run.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct AccuracyPlan {
    pub freq_hz: f64,
    pub gamma: f64,
    /// Cycles driven before the steady window, in every DEM run.
    pub transient_cycles: u32,
    /// Seeds of the seed study; the first one's bed is also the bed of the
    /// time-step study and its record the record of Yang's study.
    pub seeds: Vec<u64>,
    /// Steady cycles of each seed's run (default time step).
    pub seed_steady_cycles: u32,
    /// Time steps of the time-step study, as fractions of the Rayleigh step.
    pub dt_over_rayleigh: Vec<f64>,
    /// Steady cycles of each time-step run (at most `seed_steady_cycles`:
    /// the default time step's row is the first seed's run cut there).
    pub dt_steady_cycles: u32,
    /// Cycle counts of the cycles study: up to `seed_steady_cycles` from the
    /// first seed, beyond it whole multiples of it (seeds pooled).
    pub cycle_counts: Vec<u32>,
    /// Steps per Hertz contact duration of the collision study.
    pub steps_per_contact: Vec<f64>,
    /// Record lengths of Yang's study (drive periods, below
    /// `seed_steady_cycles`); the longest is the record of the other rows.
    pub record_periods: Vec<u32>,
    /// Factors on both channels' noise rms.
    pub noise_factors: Vec<f64>,
    /// ADC resolutions (bits).
    pub adc_bits: Vec<u32>,
    /// Residual phase errors after calibration (mrad).
    pub residual_phase_mrad: Vec<f64>,
}

impl AccuracyPlan {
    /// The full study: about 6.5 million DEM steps of the thesis scene.
    pub fn full(freq_hz: f64, gamma: f64) -> Self {
        AccuracyPlan {
            freq_hz,
            gamma,
            transient_cycles: 4,
            seeds: vec![1, 2, 3, 4, 5],
            seed_steady_cycles: 40,
            dt_over_rayleigh: vec![0.05, 0.1, 0.2, 0.3, 0.5, 1.0],
            dt_steady_cycles: 12,
            cycle_counts: vec![2, 3, 5, 8, 12, 20, 40, 80, 120, 200],
            steps_per_contact: vec![
                5.0, 7.0, 10.0, 14.0, 20.0, 25.0, 28.0, 40.0, 57.0, 80.0, 113.0, 160.0, 200.0,
            ],
            record_periods: vec![2, 4, 8, 16, 32],
            noise_factors: vec![0.0, 1.0, 10.0, 100.0, 1000.0],
            adc_bits: vec![8, 10, 12, 14, 16, 20, 24],
            residual_phase_mrad: vec![0.0, 0.03, 0.1, 0.3, 1.0, 3.0],
        }
    }

    /// A few points of each study, for tests and CI.
    pub fn quick(freq_hz: f64, gamma: f64) -> Self {
        AccuracyPlan {
            freq_hz,
            gamma,
            transient_cycles: 2,
            seeds: vec![1, 2],
            seed_steady_cycles: 4,
            dt_over_rayleigh: vec![0.1, 0.25, 1.0],
            dt_steady_cycles: 3,
            cycle_counts: vec![2, 4, 8],
            steps_per_contact: vec![5.0, 10.0, 20.0, 40.0, 80.0, 200.0],
            record_periods: vec![2, 3],
            noise_factors: vec![0.0, 1.0, 100.0],
            adc_bits: vec![8, 16],
            residual_phase_mrad: vec![0.0, 1.0],
        }
    }

    /// Checks that the studies fit together; a refusal names the field.
    pub fn validate(&self) -> Result<(), InvalidParameter> {
        let bad = |key: &str, value: String, expected: String| {
            Err(InvalidParameter::new(key, value, "", expected))
        };
        let s = self.seed_steady_cycles;
        if self.seeds.is_empty() {
            return bad("seeds", "[]".into(), "at least one seed".into());
        }
        if s < 2 {
            return bad("seed_steady_cycles", s.to_string(), "at least 2".into());
        }
        if self.dt_steady_cycles < 2 || self.dt_steady_cycles > s {
            return bad(
                "dt_steady_cycles",
                self.dt_steady_cycles.to_string(),
                format!("in 2..={s} (seed_steady_cycles)"),
            );
        }
        if let Some(x) = self
            .dt_over_rayleigh
            .iter()
            .find(|x| !(**x > 0.0 && **x <= 1.0))
        {
            return bad("dt_over_rayleigh", x.to_string(), "in (0, 1]".into());
        }
        let most = s as usize * self.seeds.len();
        if let Some(n) = self
            .cycle_counts
            .iter()
            .find(|&&n| n < 2 || (n > s && (n % s != 0 || n as usize > most)))
        {
            return bad(
                "cycle_counts",
                n.to_string(),
                format!("2..={s}, or a multiple of {s} up to {most} (seeds pooled)"),
            );
        }
        if let Some(n) = self
            .steps_per_contact
            .iter()
            .find(|n| n.is_nan() || **n < 5.0)
        {
            return bad("steps_per_contact", n.to_string(), "at least 5".into());
        }
        if self.record_periods.is_empty() {
            return bad("record_periods", "[]".into(), "at least one".into());
        }
        if let Some(n) = self.record_periods.iter().find(|&&n| n < 2 || n >= s) {
            return bad(
                "record_periods",
                n.to_string(),
                format!(
                    "in 2..{s} (below seed_steady_cycles: the record's last sample needs the step after it)"
                ),
            );
        }
        if let Some(b) = self.adc_bits.iter().find(|b| !(1..=32).contains(*b)) {
            return bad("adc_bits", b.to_string(), "in 1..=32".into());
        }
        if let Some(k) = self.noise_factors.iter().find(|k| k.is_nan() || **k < 0.0) {
            return bad("noise_factors", k.to_string(), "zero or positive".into());
        }
        if let Some(p) = self.residual_phase_mrad.iter().find(|p| !p.is_finite()) {
            return bad("residual_phase_mrad", p.to_string(), "finite".into());
        }
        Ok(())
    }

    /// The longest record of Yang's study (periods).
    pub fn baseline_record_periods(&self) -> u32 {
        self.record_periods.iter().copied().max().unwrap_or(2)
    }
}

/// One row of `accuracy.csv`: one quantity of one point of one study.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct AccuracyRow {
    /// `dem`, `impact` or `yang`.
    pub study: &'static str,
    /// What varies: `dt_over_rayleigh`, `seed`, `steady_cycles`,
    /// `steps_per_contact`, `record_periods`, `noise_factor`, `adc_bits`,
    /// `residual_phase_mrad`.
    pub parameter: &'static str,
    pub value: f64,
    pub quantity: &'static str,
    pub estimate: f64,
    /// What the estimate is held against (NaN: none).
    pub reference: f64,
    /// `estimate / reference − 1`, or for a quantity that is itself an error
    /// (`integrator_rel`, `block_rms_rel`) the quantity.
    pub error_rel: f64,
    /// Standard error of `error_rel` from the cycle-to-cycle spread (NaN:
    /// deterministic or not estimated).
    pub stderr_rel: f64,
    /// Wall-clock time it took to get this figure, settling included (s).
    pub wall_s: f64,
    pub note: String,
}

impl AccuracyRow {
    #[allow(clippy::too_many_arguments)]
    fn new(
        study: &'static str,
        parameter: &'static str,
        value: f64,
        quantity: &'static str,
        estimate: f64,
        reference: f64,
        stderr_rel: f64,
        wall_s: f64,
    ) -> Self {
        AccuracyRow {
            study,
            parameter,
            value,
            quantity,
            estimate,
            reference,
            error_rel: estimate / reference - 1.0,
            stderr_rel,
            wall_s,
            note: String::new(),
        }
    }
}

/// Header of `accuracy.csv`.
pub const CSV_HEADER: &str =
    "study,parameter,value,quantity,estimate,reference,error_rel,stderr_rel,wall_s,note";

/// `rows` as CSV text: numbers in shortest round-trip form, NaN as an empty
/// field, a field quoted when it holds a comma, a quote or a line break.
pub fn rows_to_csv(rows: &[AccuracyRow]) -> String {
    let num = |x: f64| {
        if x.is_finite() {
            format!("{x:e}")
        } else {
            String::new()
        }
    };
    let mut w = csv::Writer::from_writer(Vec::new());
    // Writing into memory cannot fail.
    let _ = w.write_record(CSV_HEADER.split(','));
    for r in rows {
        let _ = w.write_record([
            r.study.to_string(),
            r.parameter.to_string(),
            num(r.value),
            r.quantity.to_string(),
            num(r.estimate),
            num(r.reference),
            num(r.error_rel),
            num(r.stderr_rel),
            num(r.wall_s),
            r.note.clone(),
        ]);
    }
    let bytes = w.into_inner().unwrap_or_default();
    String::from_utf8_lossy(&bytes).into_owned()
}

/// Least-squares slope of `ln |y|` against `ln x` over the points with both
/// finite and non-zero: the order of convergence when `y` is an error and `x`
/// a resolution. `None` below two points.
pub fn log_log_slope(points: &[(f64, f64)]) -> Option<f64> {
    let pts: Vec<(f64, f64)> = points
        .iter()
        .filter(|(x, y)| *x > 0.0 && y.abs() > 0.0 && x.is_finite() && y.is_finite())
        .map(|(x, y)| (x.ln(), y.abs().ln()))
        .collect();
    if pts.len() < 2 {
        return None;
    }
    let n = pts.len() as f64;
    let mx = pts.iter().map(|p| p.0).sum::<f64>() / n;
    let my = pts.iter().map(|p| p.1).sum::<f64>() / n;
    let sxx = pts.iter().map(|p| (p.0 - mx).powi(2)).sum::<f64>();
    let sxy = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum::<f64>();
    (sxx > 0.0).then(|| sxy / sxx)
}

/// The spread of block means about a reference.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BlockSpread {
    /// Root-mean-square relative deviation of the block means (NaN without
    /// blocks).
    pub rms_rel: f64,
    /// How many blocks.
    pub blocks: usize,
}

/// Root-mean-square relative deviation from `reference` of the means of
/// disjoint blocks of `n` values of each series (a series' leftover values
/// are dropped), and the number of blocks.
pub fn block_rms_rel(series: &[Vec<f64>], n: usize, reference: f64) -> BlockSpread {
    let none = BlockSpread {
        rms_rel: f64::NAN,
        blocks: 0,
    };
    let mut sum_sq = 0.0;
    let mut blocks = 0usize;
    if n == 0 {
        return none;
    }
    for s in series {
        for block in s.chunks_exact(n) {
            let mean = block.iter().sum::<f64>() / n as f64;
            sum_sq += (mean / reference - 1.0).powi(2);
            blocks += 1;
        }
    }
    if blocks == 0 {
        none
    } else {
        BlockSpread {
            rms_rel: (sum_sq / blocks as f64).sqrt(),
            blocks,
        }
    }
}

/// Sample standard deviation (n − 1); NaN below two values.
pub fn sample_sd(xs: &[f64]) -> f64 {
    if xs.len() < 2 {
        return f64::NAN;
    }
    let m = xs.iter().sum::<f64>() / xs.len() as f64;
    (xs.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (xs.len() - 1) as f64).sqrt()
}

/// Something the studies report while they run.
#[derive(Debug, Clone, Copy)]
pub enum AccuracyEvent<'a> {
    /// A stage began or ended.
    Stage(&'a str),
    /// A drive is under way.
    Drive {
        label: &'a str,
        cycle: u32,
        cycles: u32,
        wall_s: f64,
    },
}

/// Wall-clock time at every cycle boundary of a drive (the step
/// [`run_drive`] takes as the boundary), and optionally the truth record.
struct CycleClock {
    period_s: f64,
    half_dt_s: f64,
    started: Stopwatch,
    cycle_wall_s: Vec<f64>,
    truth: Option<TruthRecorder>,
}

impl StepObserver for CycleClock {
    fn observe(&mut self, t_s: f64, world: &World, enclosure: &Kinematics) {
        if let Some(t) = &mut self.truth {
            t.observe(t_s, world, enclosure);
        }
        let next = self.cycle_wall_s.len() as f64;
        if (t_s / self.period_s - next) * self.period_s > -self.half_dt_s {
            self.cycle_wall_s.push(self.started.elapsed().as_secs_f64());
        }
    }
}

/// One DEM drive of the studies.
#[derive(Debug, Clone)]
struct DriveJob {
    label: String,
    seed_index: usize,
    dt_s: f64,
    /// `Some(x)` for a run of the time-step study.
    dt_over_rayleigh: Option<f64>,
    steady_cycles: u32,
    record_truth: bool,
}

/// What a drive gave.
#[derive(Debug, Clone)]
struct DriveRun {
    job: DriveJob,
    outcome: Result<DriveOutcome, String>,
    /// Wall-clock time at the drive start (0) and at every cycle boundary (s).
    cycle_wall_s: Vec<f64>,
    wall_s: f64,
    truth: Option<TruthSamples>,
}

impl DriveRun {
    /// Energy dissipated in each cycle from `first` on (J).
    fn cycle_energies(&self, first: usize) -> Vec<f64> {
        self.outcome
            .as_ref()
            .map(|o| energies(&o.cycle_snapshots, first))
            .unwrap_or_default()
    }
}

fn energies(snapshots: &[LedgerSnapshot], first: usize) -> Vec<f64> {
    snapshots
        .get(first..)
        .unwrap_or(&[])
        .windows(2)
        .map(|w| w[1].flows.dissipated.total() - w[0].flows.dissipated.total())
        .collect()
}

/// Runs `work` on every job, as many at once as the rayon pool has threads,
/// longest first as listed; results in job order.
fn run_queue<J: Sync, R: Send>(jobs: &[J], work: impl Fn(&J) -> R + Sync) -> Vec<R> {
    let threads = rayon::current_num_threads().clamp(1, jobs.len().max(1));
    let next = AtomicUsize::new(0);
    let results: Mutex<Vec<(usize, R)>> = Mutex::new(Vec::with_capacity(jobs.len()));
    rayon::scope(|s| {
        for _ in 0..threads {
            s.spawn(|_| {
                loop {
                    let i = next.fetch_add(1, Ordering::Relaxed);
                    let Some(job) = jobs.get(i) else { break };
                    let r = work(job);
                    if let Ok(mut v) = results.lock() {
                        v.push((i, r));
                    }
                }
            });
        }
    });
    let mut v = results.into_inner().unwrap_or_else(|e| e.into_inner());
    v.sort_by_key(|(i, _)| *i);
    v.into_iter().map(|(_, r)| r).collect()
}

/// The summary of the time-step, seed and cycle studies.
#[derive(Debug, Clone, Serialize)]
pub struct DemAccuracy {
    pub rayleigh_step_s: f64,
    pub default_dt_s: f64,
    pub default_dt_over_rayleigh: f64,
    /// The time step every other is held against (fraction of Rayleigh).
    pub reference_dt_over_rayleigh: f64,
    /// Energy per cycle at the default step against the reference step,
    /// over the same cycles of the same bed, and its standard error.
    pub default_dt_error_rel: f64,
    pub default_dt_error_stderr_rel: f64,
    /// Integrator energy error / dissipated energy at the default step.
    pub default_dt_integrator_rel: f64,
    /// Order of the integrator error in Δt (log-log slope).
    pub integrator_order: Option<f64>,
    /// Time steps that stopped with a diagnosis, and why.
    pub failed: Vec<String>,
    /// Mean energy per cycle of each seed (J).
    pub seed_energy_per_cycle_j: Vec<f64>,
    /// Mean over every steady cycle of every seed (J): the reference of the
    /// cycles study.
    pub pooled_energy_per_cycle_j: f64,
    pub pooled_stderr_rel: f64,
    pub pooled_efficiency: f64,
    /// Standard deviation of the seeds' means / pooled mean.
    pub seed_spread_rel: f64,
    /// What the seeds' spread should be from each run's own standard error
    /// (rms of the seeds' relative standard errors).
    pub seed_stderr_rms_rel: f64,
    /// Steady cycles a default `vlab shake` window would need for a 1 %
    /// standard error, from the pooled cycle-to-cycle spread.
    pub cycles_for_1pct: f64,
    /// Which error dominates at the default time step, in words.
    pub dominant: String,
}

/// The summary of the collision study.
#[derive(Debug, Clone, Serialize)]
pub struct ImpactAccuracy {
    pub speed_mps: f64,
    pub hertz_duration_s: f64,
    /// Convergence orders (log-log slopes of |error| against steps per
    /// contact, negated) of the elastic overlap, duration (against the exact
    /// integral) and the damped restitution.
    pub order_max_overlap: Option<f64>,
    pub order_duration_exact: Option<f64>,
    pub order_restitution: Option<f64>,
    /// Errors at the scene's steps per contact.
    pub scene_steps_per_contact: f64,
    pub max_overlap_error_rel: f64,
    pub duration_error_rel_eq_5_10: f64,
    pub duration_error_rel_exact: f64,
    pub restitution_error_rel: f64,
}

/// The summary of Yang's study.
#[derive(Debug, Clone, Serialize)]
pub struct YangAccuracy {
    pub rig: String,
    pub baseline_record_periods: u32,
    /// The chain's error: Yang's estimate against the enclosure's work over
    /// the same cycles, thesis rig settings, calibrated on the empty
    /// enclosure. What a lab's chain and post-processing control.
    pub baseline_error_vs_work_rel: f64,
    /// The bed's unsteadiness over those cycles: the enclosure's work in
    /// against the DEM dissipation, minus one (the change of the energy the
    /// bed holds; not the chain's).
    pub baseline_unsteadiness_rel: f64,
    /// Error against the DEM dissipation over the same cycles: the chain's
    /// error and the unsteadiness together, `(1 + chain)(1 + unsteadiness)
    /// − 1`, their sum to within their product.
    pub baseline_error_rel: f64,
    /// The rig model's phase error at the drive frequency (rad).
    pub rig_phase_error_rad: f64,
    /// The phase error the empty-enclosure calibration measured over the
    /// baseline record (rad): the model's plus what the AC coupling's
    /// start-up transient looks like at the drive frequency.
    pub calibrated_phase_error_rad: f64,
    /// Error per mrad of residual phase error (relative, per mrad).
    pub error_per_mrad: Option<f64>,
}

/// Everything `summary.json` says.
#[derive(Debug, Clone, Serialize)]
pub struct AccuracySummary {
    pub vlab_version: &'static str,
    pub scene: String,
    pub n_particles: usize,
    pub threads: usize,
    pub quick: bool,
    pub plan: AccuracyPlan,
    /// Wall-clock time of settling each seed's bed (s).
    pub settle_wall_s: Vec<f64>,
    pub wall_s: f64,
    pub dem: DemAccuracy,
    pub impact: ImpactAccuracy,
    pub yang: YangAccuracy,
    pub files: Vec<String>,
}

/// The studies' result.
#[derive(Debug, Clone)]
pub struct AccuracyReport {
    pub rows: Vec<AccuracyRow>,
    pub summary: AccuracySummary,
}

/// Runs the three studies of `plan` on `scene` with the rig `rig`.
///
/// Over 80 lines: the three studies in turn, each a few lines, with progress
/// between them.
pub fn run_accuracy(
    scene: &Scene,
    rig: &RigSpec,
    plan: &AccuracyPlan,
    quick: bool,
    progress: &(dyn Fn(AccuracyEvent) + Sync),
) -> Result<AccuracyReport, SceneError> {
    plan.validate()?;
    let checked = crate::experiment::shake::shake_drive(scene, plan.freq_hz, plan.gamma)?;
    let started = Stopwatch::start();

    // Impact first: it takes milliseconds and fails fast on a bad scene.
    progress(AccuracyEvent::Stage("collision study (b)"));
    let (mut rows, impact) = impact_study(scene, plan)?;

    // Settle every seed's bed once.
    progress(AccuracyEvent::Stage("settling one bed per seed"));
    let scenes: Vec<Scene> = plan
        .seeds
        .iter()
        .map(|&seed| {
            let mut s = scene.clone();
            s.simulation.seed = seed;
            s
        })
        .collect();
    let beds = settle_seeds(&scenes, progress)?;
    let settle_wall_s: Vec<f64> = beds.iter().map(|b| b.1).collect();

    // Every drive, the longest first.
    let rayleigh = scene.rayleigh_limit_s();
    let default_dt = scene.drive_dt_s(&checked);
    let jobs = drive_jobs(plan, rayleigh, default_dt);
    let cost = |j: &DriveJob| job_cost(plan, j);
    progress(AccuracyEvent::Stage(&format!(
        "{} drives, {:.2} million steps of {} particles",
        jobs.len(),
        jobs.iter().map(|j| cost(j) / plan.freq_hz).sum::<f64>() / 1e6,
        scene.particles.count
    )));
    let runs = run_queue(&jobs, |job| {
        drive(
            &beds[job.seed_index].0,
            &scenes[job.seed_index],
            plan,
            job,
            progress,
        )
    });
    let (seed_runs, dt_runs) = sort_runs(plan, &runs)?;

    progress(AccuracyEvent::Stage("DEM study (a)"));
    let (dem_rows, dem) = dem_study(
        scene,
        plan,
        &seed_runs,
        &dt_runs,
        &settle_wall_s,
        rayleigh,
        default_dt,
    );
    rows.extend(dem_rows);

    progress(AccuracyEvent::Stage("Yang's study (c)"));
    let (yang_rows, yang) = yang_study(scene, rig, plan, seed_runs[0], settle_wall_s[0], &dem)?;
    rows.extend(yang_rows);

    let summary = AccuracySummary {
        vlab_version: env!("CARGO_PKG_VERSION"),
        scene: scene.name.clone(),
        n_particles: scene.particles.count,
        threads: rayon::current_num_threads(),
        quick,
        plan: plan.clone(),
        settle_wall_s,
        wall_s: started.elapsed().as_secs_f64(),
        dem,
        impact,
        yang,
        files: Vec::new(),
    };
    Ok(AccuracyReport { rows, summary })
}

/// Settles the bed of every scene of `scenes` (one per seed), with its
/// wall-clock time (s).
fn settle_seeds(
    scenes: &[Scene],
    progress: &(dyn Fn(AccuracyEvent) + Sync),
) -> Result<Vec<(SettledBed, f64)>, SceneError> {
    let beds: Vec<Result<(SettledBed, f64), SceneError>> = run_queue(scenes, |s| {
        let t = Stopwatch::start();
        let bed = settle_bed(s, &mut |_| {})?;
        let wall = t.elapsed().as_secs_f64();
        progress(AccuracyEvent::Stage(&format!(
            "settled seed {} in {wall:.1} s",
            s.simulation.seed
        )));
        Ok((bed, wall))
    });
    beds.into_iter().collect()
}

/// Relative cost of a drive: its steps.
fn job_cost(plan: &AccuracyPlan, j: &DriveJob) -> f64 {
    f64::from(plan.transient_cycles + j.steady_cycles) / j.dt_s
}

/// Every drive of `plan`, the longest first: one per time step of the
/// time-step study (on the first seed's bed), one per seed at the scene's
/// default step `default_dt` (s; the first records the truth for Yang).
fn drive_jobs(plan: &AccuracyPlan, rayleigh: f64, default_dt: f64) -> Vec<DriveJob> {
    let mut jobs: Vec<DriveJob> = Vec::new();
    for &x in &plan.dt_over_rayleigh {
        jobs.push(DriveJob {
            label: format!("dt {x} x Rayleigh"),
            seed_index: 0,
            dt_s: x * rayleigh,
            dt_over_rayleigh: Some(x),
            steady_cycles: plan.dt_steady_cycles,
            record_truth: false,
        });
    }
    for (i, &seed) in plan.seeds.iter().enumerate() {
        jobs.push(DriveJob {
            label: format!("seed {seed}"),
            seed_index: i,
            dt_s: default_dt,
            dt_over_rayleigh: None,
            steady_cycles: plan.seed_steady_cycles,
            record_truth: i == 0,
        });
    }
    jobs.sort_by(|a, b| job_cost(plan, b).total_cmp(&job_cost(plan, a)));
    jobs
}

/// The seeds' runs in seed order and the time-step study's runs; an error
/// when a seed's run failed at the default step (the time-step study's
/// runs may fail: that is a finding).
fn sort_runs<'a>(
    plan: &AccuracyPlan,
    runs: &'a [DriveRun],
) -> Result<(Vec<&'a DriveRun>, Vec<&'a DriveRun>), SceneError> {
    let failed_hard: Vec<&DriveRun> = runs
        .iter()
        .filter(|r| r.job.dt_over_rayleigh.is_none() && r.outcome.is_err())
        .collect();
    if let Some(r) = failed_hard.first() {
        let why = r.outcome.as_ref().err().cloned().unwrap_or_default();
        return Err(SceneError::Invalid(InvalidParameter::new(
            "seed",
            plan.seeds[r.job.seed_index],
            "",
            format!("a bed that drives at the default time step: {why}"),
        )));
    }
    let seed_runs: Vec<&DriveRun> = (0..plan.seeds.len())
        .filter_map(|i| {
            runs.iter()
                .find(|r| r.job.dt_over_rayleigh.is_none() && r.job.seed_index == i)
        })
        .collect();
    let dt_runs: Vec<&DriveRun> = runs
        .iter()
        .filter(|r| r.job.dt_over_rayleigh.is_some())
        .collect();
    Ok((seed_runs, dt_runs))
}

/// Drives a copy of `bed` as `job` says, with the clock (and the truth
/// recorder) watching.
fn drive(
    bed: &SettledBed,
    scene: &Scene,
    plan: &AccuracyPlan,
    job: &DriveJob,
    progress: &(dyn Fn(AccuracyEvent) + Sync),
) -> DriveRun {
    let started = Stopwatch::start();
    let period = 1.0 / plan.freq_hz;
    let cycles = plan.transient_cycles + job.steady_cycles;
    let mut clock = CycleClock {
        period_s: period,
        half_dt_s: 0.5 * job.dt_s,
        started,
        cycle_wall_s: vec![0.0],
        truth: job
            .record_truth
            .then(|| TruthRecorder::new(crate::experiment::shake::TRUTH_SAMPLE_RATE_HZ, 0.0)),
    };
    let outcome = (|| {
        let mut world = prepare_drive(bed, scene, job.dt_s)?;
        let drive = scene.drive(plan.freq_hz, plan.gamma)?;
        let drive_plan = DrivePlan {
            drive,
            length: DriveLength::Fixed {
                cycles,
                steady_cycles: job.steady_cycles,
            },
        };
        let mut motion = SineMotion::new(&drive);
        run_drive(&mut world, &drive_plan, &mut motion, &mut clock, &mut |p| {
            progress(AccuracyEvent::Drive {
                label: &job.label,
                cycle: p.cycle,
                cycles,
                wall_s: p.wall_time_s,
            })
        })
    })()
    .map_err(|e| e.to_string());
    let wall_s = started.elapsed().as_secs_f64();
    progress(AccuracyEvent::Stage(&match &outcome {
        Ok(_) => format!("{}: {cycles} cycles in {wall_s:.1} s", job.label),
        Err(e) => format!("{}: stopped after {wall_s:.1} s: {e}", job.label),
    }));
    DriveRun {
        job: job.clone(),
        outcome,
        cycle_wall_s: clock.cycle_wall_s,
        wall_s,
        truth: clock.truth.map(TruthRecorder::into_samples),
    }
}

/// Study (a) from the runs.
///
/// Over 80 lines: study (a)'s figures filled field by field from the runs, each
/// from the ones before.
fn dem_study(
    scene: &Scene,
    plan: &AccuracyPlan,
    seed_runs: &[&DriveRun],
    dt_runs: &[&DriveRun],
    settle_wall_s: &[f64],
    rayleigh: f64,
    default_dt: f64,
) -> (Vec<AccuracyRow>, DemAccuracy) {
    let t = plan.transient_cycles as usize;
    let s = plan.seed_steady_cycles as usize;
    // run_accuracy refused an invalid drive before any run.
    let e_max = scene
        .drive(plan.freq_hz, plan.gamma)
        .map_or(f64::NAN, |d| d.e_max_j(scene.particle_mass_kg()));
    let mut rows = Vec::new();

    // Seeds and the pooled reference.
    let series: Vec<Vec<f64>> = seed_runs.iter().map(|r| r.cycle_energies(t)).collect();
    let seed_stats: Vec<MeanStderr> = series.iter().map(|x| mean_stderr(x)).collect();
    let means: Vec<f64> = seed_stats.iter().map(|m| m.mean).collect();
    let pooled = means.iter().sum::<f64>() / means.len() as f64;
    let pooled_stderr = (seed_stats
        .iter()
        .map(|m| m.stderr_or_nan().powi(2))
        .sum::<f64>())
    .sqrt()
        / seed_stats.len() as f64;
    let run_wall = |i: usize, cycles: usize| -> f64 {
        let r = seed_runs[i];
        settle_wall_s[r.job.seed_index] + r.cycle_wall_s.get(cycles).copied().unwrap_or(r.wall_s)
    };
    for (i, m) in seed_stats.iter().enumerate() {
        let seed = plan.seeds[seed_runs[i].job.seed_index] as f64;
        rows.extend(seed_rows(seed, m, pooled, e_max, run_wall(i, t + s)));
    }
    let seed_spread_rel = sample_sd(&means) / pooled;
    let seed_stderr_rms_rel = (seed_stats
        .iter()
        .map(|m| (m.stderr_or_nan() / pooled).powi(2))
        .sum::<f64>()
        / seed_stats.len() as f64)
        .sqrt();

    rows.extend(cycle_rows(plan, &series, &seed_stats, pooled, &run_wall));
    let pooled_series: Vec<f64> = series.iter().flatten().copied().collect();
    let spread = sample_sd(&pooled_series) / pooled;
    let lag1 = mean_stderr(&series[0]).lag1;
    let cycles_for_1pct = (spread / 0.01).powi(2) * (1.0 + lag1) / (1.0 - lag1);

    let default_x = default_dt / rayleigh;
    let (dt_rows, step) =
        time_step_study(plan, seed_runs, dt_runs, settle_wall_s, default_x, e_max);
    rows.extend(dt_rows);
    let dominant = dominant_error(
        plan,
        &step,
        default_x,
        seed_stats[0].relative().unwrap_or(f64::NAN),
        seed_spread_rel,
    );
    let dem = DemAccuracy {
        rayleigh_step_s: rayleigh,
        default_dt_s: default_dt,
        default_dt_over_rayleigh: default_x,
        reference_dt_over_rayleigh: step.ref_x,
        default_dt_error_rel: step.default_err,
        default_dt_error_stderr_rel: step.default_se,
        default_dt_integrator_rel: step.default_integrator,
        integrator_order: step.integrator_order,
        failed: step.failed,
        seed_energy_per_cycle_j: means,
        pooled_energy_per_cycle_j: pooled,
        pooled_stderr_rel: pooled_stderr / pooled,
        pooled_efficiency: pooled / e_max,
        seed_spread_rel,
        seed_stderr_rms_rel,
        cycles_for_1pct,
        dominant,
    };
    (rows, dem)
}

/// Study (a)'s rows of one seed: its mean energy per cycle and efficiency
/// against the seeds' `pooled` mean (J), `e_max` (J) scaling energies to
/// efficiencies, `wall` its wall time (s).
fn seed_rows(seed: f64, m: &MeanStderr, pooled: f64, e_max: f64, wall: f64) -> Vec<AccuracyRow> {
    [("energy_per_cycle_j", 1.0), ("efficiency", 1.0 / e_max)]
        .into_iter()
        .map(|(quantity, scale)| {
            AccuracyRow::new(
                "dem",
                "seed",
                seed,
                quantity,
                m.mean * scale,
                pooled * scale,
                m.stderr_or_nan() / pooled,
                wall,
            )
        })
        .collect()
}

/// Study (a)'s rows of steady cycles: for each count of `plan`, the energy
/// per cycle over that many cycles (of the first seed, or whole seeds'
/// means) against the `pooled` mean, and the rms spread of disjoint blocks
/// of `series` that long; `run_wall(i, cycles)` is seed run `i`'s wall time
/// to `cycles` cycles (s).
fn cycle_rows(
    plan: &AccuracyPlan,
    series: &[Vec<f64>],
    seed_stats: &[MeanStderr],
    pooled: f64,
    run_wall: &dyn Fn(usize, usize) -> f64,
) -> Vec<AccuracyRow> {
    let t = plan.transient_cycles as usize;
    let s = plan.seed_steady_cycles as usize;
    let mut rows = Vec::new();
    for &n in &plan.cycle_counts {
        let n = n as usize;
        let (estimate, stderr, wall) = if n <= s {
            let m = mean_stderr(&series[0][..n]);
            (m.mean, m.stderr_or_nan(), run_wall(0, t + n))
        } else {
            let k = n / s;
            let m = seed_stats[..k].iter().map(|m| m.mean).sum::<f64>() / k as f64;
            let se = seed_stats[..k]
                .iter()
                .map(|m| m.stderr_or_nan().powi(2))
                .sum::<f64>()
                .sqrt()
                / k as f64;
            (m, se, (0..k).map(|i| run_wall(i, t + s)).sum())
        };
        let mut row = AccuracyRow::new(
            "dem",
            "steady_cycles",
            n as f64,
            "energy_per_cycle_j",
            estimate,
            pooled,
            stderr / pooled,
            wall,
        );
        if n == s * series.len() {
            row.note = "the reference itself".into();
        }
        rows.push(row);
        let BlockSpread {
            rms_rel: rms,
            blocks,
        } = block_rms_rel(series, n, pooled);
        if blocks >= 2 {
            let mut row = AccuracyRow::new(
                "dem",
                "steady_cycles",
                n as f64,
                "block_rms_rel",
                rms,
                f64::NAN,
                rms / (2.0 * blocks as f64).sqrt(),
                wall,
            );
            row.error_rel = rms;
            row.note = format!("rms deviation of {blocks} disjoint blocks of {n} cycles");
            rows.push(row);
        }
    }
    rows
}

/// One time step of study (a): its energy per cycle over the first
/// `dt_steady_cycles` steady cycles, the integrator's energy error, the
/// fewest steps a collision was planned to take and the fewest counted, the
/// wall time (s), or why the run stopped.
struct DtPoint {
    x: f64,
    mean: MeanStderr,
    integrator_rel: f64,
    planned_steps: f64,
    /// NaN when no collision was counted (or the run stopped).
    counted_steps: f64,
    wall: f64,
    error: Option<String>,
}

/// What the time-step study found, at the scene's default step against the
/// finest one that ran (`ref_x`, × Rayleigh).
struct TimeStepFindings {
    ref_x: f64,
    default_err: f64,
    default_se: f64,
    default_integrator: f64,
    integrator_order: Option<f64>,
    failed: Vec<String>,
}

/// The point of run `r` at `x` × Rayleigh.
fn dt_point(plan: &AccuracyPlan, settle_wall_s: &[f64], x: f64, r: &DriveRun) -> DtPoint {
    let t = plan.transient_cycles as usize;
    let n_dt = plan.dt_steady_cycles as usize;
    let wall_end = r.cycle_wall_s.get(t + n_dt).copied().unwrap_or(r.wall_s);
    let wall = settle_wall_s[r.job.seed_index] + wall_end;
    match &r.outcome {
        Ok(o) => {
            let snaps = &o.cycle_snapshots;
            let e = energies(&snaps[..=(t + n_dt).min(snaps.len() - 1)], t);
            let b = LedgerBalance::between(&snaps[0], &snaps[(t + n_dt).min(snaps.len() - 1)]);
            DtPoint {
                x,
                mean: mean_stderr(&e),
                integrator_rel: b.integrator_j / b.dissipated_j,
                planned_steps: o.planned_steps_per_contact,
                counted_steps: o
                    .fewest_counted_steps_per_contact
                    .map_or(f64::NAN, f64::from),
                wall,
                error: None,
            }
        }
        Err(e) => DtPoint {
            x,
            mean: MeanStderr {
                mean: f64::NAN,
                ..MeanStderr::default()
            },
            integrator_rel: f64::NAN,
            planned_steps: f64::NAN,
            counted_steps: f64::NAN,
            wall,
            error: Some(e.clone()),
        },
    }
}

/// Study (a)'s time steps: the runs of `dt_runs` and the first seed's run at
/// the default step `default_x` (× Rayleigh), each against the finest step
/// that ran; `e_max` (J) scales energies to efficiencies.
fn time_step_study(
    plan: &AccuracyPlan,
    seed_runs: &[&DriveRun],
    dt_runs: &[&DriveRun],
    settle_wall_s: &[f64],
    default_x: f64,
    e_max: f64,
) -> (Vec<AccuracyRow>, TimeStepFindings) {
    let mut points: Vec<DtPoint> = dt_runs
        .iter()
        .filter_map(|r| {
            r.job
                .dt_over_rayleigh
                .map(|x| dt_point(plan, settle_wall_s, x, r))
        })
        .collect();
    points.push(dt_point(plan, settle_wall_s, default_x, seed_runs[0]));
    points.sort_by(|a, b| a.x.total_cmp(&b.x));
    let reference = points.iter().find(|p| p.error.is_none());
    let (ref_x, ref_mean) = reference
        .map(|p| (p.x, p.mean))
        .unwrap_or((f64::NAN, MeanStderr::default()));
    let mut rows = Vec::new();
    let mut failed = Vec::new();
    for p in &points {
        let note = if p.x == default_x {
            format!(
                "the scene's default step (seed {} run, first {} steady cycles)",
                plan.seeds[0], plan.dt_steady_cycles
            )
        } else if p.x == ref_x {
            "the reference (finest step)".into()
        } else {
            String::new()
        };
        if let Some(e) = &p.error {
            failed.push(format!("{} x Rayleigh: {e}", p.x));
        }
        rows.extend(dt_rows(p, ref_mean, e_max, note));
    }
    let at_default = points.iter().find(|p| p.x == default_x);
    let (default_err, default_se, default_integrator) = at_default
        .map(|p| {
            (
                p.mean.mean / ref_mean.mean - 1.0,
                (p.mean.stderr_or_nan().powi(2) + ref_mean.stderr_or_nan().powi(2)).sqrt()
                    / ref_mean.mean,
                p.integrator_rel,
            )
        })
        .unwrap_or((f64::NAN, f64::NAN, f64::NAN));
    let integrator_order = log_log_slope(
        &points
            .iter()
            .filter(|p| p.error.is_none())
            .map(|p| (p.x, p.integrator_rel))
            .collect::<Vec<_>>(),
    );
    let findings = TimeStepFindings {
        ref_x,
        default_err,
        default_se,
        default_integrator,
        integrator_order,
        failed,
    };
    (rows, findings)
}

/// The rows of time-step point `p` against the reference `ref_mean`: energy
/// per cycle and efficiency (with `note`, or why the run stopped), the
/// integrator's error, the fewest steps per contact counted and planned.
fn dt_rows(p: &DtPoint, ref_mean: MeanStderr, e_max: f64, note: String) -> Vec<AccuracyRow> {
    let mut rows = Vec::new();
    let se = if p.error.is_some() {
        f64::NAN
    } else {
        (p.mean.stderr_or_nan().powi(2) + ref_mean.stderr_or_nan().powi(2)).sqrt() / ref_mean.mean
    };
    let note = match &p.error {
        Some(e) => format!("stopped: {e}"),
        None => note,
    };
    for (quantity, scale) in [("energy_per_cycle_j", 1.0), ("efficiency", 1.0 / e_max)] {
        let mut row = AccuracyRow::new(
            "dem",
            "dt_over_rayleigh",
            p.x,
            quantity,
            p.mean.mean * scale,
            ref_mean.mean * scale,
            se,
            p.wall,
        );
        row.note = note.clone();
        rows.push(row);
    }
    let mut row = AccuracyRow::new(
        "dem",
        "dt_over_rayleigh",
        p.x,
        "integrator_rel",
        p.integrator_rel,
        0.0,
        f64::NAN,
        p.wall,
    );
    row.error_rel = p.integrator_rel;
    row.note = "integration energy error / dissipated energy, whole run".into();
    rows.push(row);
    for (quantity, steps, note) in [
        (
            "fewest_counted_steps_per_contact",
            p.counted_steps,
            "fewest steps counted over the collisions that began and ended in the run",
        ),
        (
            "planned_steps_per_contact",
            p.planned_steps,
            "fewest steps a collision was planned to take: Hertz duration (eq. 5.10) at its approach speed / dt",
        ),
    ] {
        let mut row = AccuracyRow::new(
            "dem",
            "dt_over_rayleigh",
            p.x,
            quantity,
            steps,
            f64::NAN,
            f64::NAN,
            p.wall,
        );
        row.error_rel = f64::NAN;
        row.note = note.into();
        rows.push(row);
    }
    rows
}

/// Which error dominates at the default step, in words: the discretisation
/// error of `step` against the relative standard error of one run
/// (`default_stderr`) and the seeds' spread.
fn dominant_error(
    plan: &AccuracyPlan,
    step: &TimeStepFindings,
    default_x: f64,
    default_stderr: f64,
    seed_spread_rel: f64,
) -> String {
    let (default_err, default_se) = (step.default_err, step.default_se);
    let resolved = default_err.abs() > 2.0 * default_se;
    if !resolved {
        format!(
            "statistics: at the default time step ({default_x:.3} x Rayleigh) the discretisation error of the energy per cycle is not resolved, {:+.2} % +- {:.2} % against {} x Rayleigh over {} cycles (the integrator's own energy error is {:.1e} of the dissipation), while one run of {} steady cycles has a standard error of {:.2} % and the seeds' means spread by {:.2} %",
            100.0 * default_err,
            100.0 * default_se,
            step.ref_x,
            plan.dt_steady_cycles,
            step.default_integrator,
            plan.seed_steady_cycles,
            100.0 * default_stderr,
            100.0 * seed_spread_rel
        )
    } else if default_err.abs() > seed_spread_rel {
        format!(
            "discretisation: at the default time step the energy per cycle is {:+.2} % +- {:.2} % off the finest step, more than the seeds' spread of {:.2} %",
            100.0 * default_err,
            100.0 * default_se,
            100.0 * seed_spread_rel
        )
    } else {
        format!(
            "statistics: the default time step is {:+.2} % +- {:.2} % off the finest step, less than the seeds' spread of {:.2} %",
            100.0 * default_err,
            100.0 * default_se,
            100.0 * seed_spread_rel
        )
    }
}

/// Study (b): one collision per resolution.
fn impact_study(
    scene: &Scene,
    plan: &AccuracyPlan,
) -> Result<(Vec<AccuracyRow>, ImpactAccuracy), SceneError> {
    let pp = scene.contact.particle_wall;
    let speed = scene.expected_impact_speed_mps(&scene.drive(plan.freq_hz, plan.gamma)?);
    let base = ImpactSetup {
        material: scene.particle_material(),
        radius_m: scene.radius_m(),
        target: Target::Wall(scene.wall_material()),
        speed_mps: speed,
        angle_deg: 0.0,
        spin_rad_s: 0.0,
        restitution: pp.restitution,
        friction: pp.friction,
        mode: scene.contact.restitution_mode,
        dt_s: None,
    };
    let t_c = base.hertz_duration_s();
    let mut rows = Vec::new();
    let mut overlap_pts = Vec::new();
    let mut duration_pts = Vec::new();
    let mut restitution_pts = Vec::new();
    let scene_n = scene.simulation.steps_per_contact;
    let mut at_scene = (f64::NAN, f64::NAN, f64::NAN, f64::NAN);
    let mut best_gap = f64::INFINITY;
    for &n in &plan.steps_per_contact {
        let (e_overlap, e_dur, e_exact, e_rest) = impact_rows(&base, n, t_c / n, &mut rows)?;
        overlap_pts.push((n, e_overlap));
        duration_pts.push((n, e_exact));
        restitution_pts.push((n, e_rest));
        if (n - scene_n).abs() < best_gap {
            best_gap = (n - scene_n).abs();
            at_scene = (e_overlap, e_dur, e_exact, e_rest);
        }
    }
    let order = |pts: &[(f64, f64)]| log_log_slope(pts).map(|s| -s);
    Ok((
        rows,
        ImpactAccuracy {
            speed_mps: speed,
            hertz_duration_s: t_c,
            order_max_overlap: order(&overlap_pts),
            order_duration_exact: order(&duration_pts),
            order_restitution: order(&restitution_pts),
            scene_steps_per_contact: scene_n,
            max_overlap_error_rel: at_scene.0,
            duration_error_rel_eq_5_10: at_scene.1,
            duration_error_rel_exact: at_scene.2,
            restitution_error_rel: at_scene.3,
        },
    ))
}

/// The collision of `base` at `n` steps per contact (time step `dt` s),
/// elastic and with the scene's law, as rows added to `rows`; returns the
/// relative errors of the overlap, the duration against eq. 5.10 and against
/// the exact integral, and of the restitution.
fn impact_rows(
    base: &ImpactSetup,
    n: f64,
    dt: f64,
    rows: &mut Vec<AccuracyRow>,
) -> Result<(f64, f64, f64, f64), SceneError> {
    let speed = base.speed_mps;
    let t0 = Stopwatch::start();
    let elastic = run_impact(&ImpactSetup {
        restitution: 1.0,
        friction: 0.0,
        dt_s: Some(dt),
        ..*base
    })?;
    let wall_elastic = t0.elapsed().as_secs_f64();
    let t1 = Stopwatch::start();
    let damped = run_impact(&ImpactSetup {
        dt_s: Some(dt),
        ..*base
    })?;
    let wall_damped = t1.elapsed().as_secs_f64();
    let exact_duration = 2.0 * HERTZ_DURATION_INTEGRAL * elastic.hertz_max_overlap_m / speed;
    let mut push = |quantity, estimate, reference, wall, note: &str| {
        let mut row = AccuracyRow::new(
            "impact",
            "steps_per_contact",
            n,
            quantity,
            estimate,
            reference,
            f64::NAN,
            wall,
        );
        row.note = note.into();
        let e = row.error_rel;
        rows.push(row);
        e
    };
    let e_overlap = push(
        "max_overlap_m",
        elastic.max_overlap_m,
        elastic.hertz_max_overlap_m,
        wall_elastic,
        "e = 1 against Terzioglu 2023, eq. 5.8",
    );
    let e_dur = push(
        "contact_duration_s",
        elastic.contact_duration_s,
        elastic.hertz_duration_s,
        wall_elastic,
        "e = 1 against twice Terzioglu 2023, eq. 5.10",
    );
    let e_exact = push(
        "contact_duration_exact_s",
        elastic.contact_duration_s,
        exact_duration,
        wall_elastic,
        "e = 1 against the exact Hertz integral 2 I delta_max / v",
    );
    push(
        "elastic_restitution",
        elastic.normal_restitution,
        1.0,
        wall_elastic,
        "e = 1: energy the integration loses or makes",
    );
    let e_rest = push(
        "restitution",
        damped.normal_restitution,
        base.restitution,
        wall_damped,
        "the scene's particle-wall law against its configured e (wall time includes calibrating the exact-restitution damping)",
    );
    Ok((e_overlap, e_dur, e_exact, e_rest))
}

/// A chain's record of the truth: force and acceleration, and the sample rate.
struct Chained {
    force: Vec<f64>,
    accel: Vec<f64>,
    fs_hz: f64,
}

/// Runs the chain of `rig` on the truth record from `feed_start_s`, keeping
/// the record from `record_start_s`; with `particles` false, on the empty
/// enclosure (same motion, no particle force).
fn rechain(
    rig: &RigSpec,
    truth: &TruthSamples,
    feed_start_s: f64,
    record_start_s: f64,
    static_weight_n: f64,
    seed: u64,
    particles: bool,
) -> Result<Chained, SceneError> {
    let fs = rig.daq.sample_rate_hz;
    let dt = truth
        .time_s
        .get(1)
        .zip(truth.time_s.first())
        .map_or(1.0 / fs, |(b, a)| b - a);
    let mut daq = Daq::new(rig, dt.min(1.0 / fs), record_start_s, seed)?;
    let span = truth.time_s.last().copied().unwrap_or(0.0) - record_start_s;
    daq.reserve(span.max(0.0) + 0.01);
    let first = truth.time_s.partition_point(|&t| t < feed_start_s - 1e-12);
    for i in first..truth.len() {
        let a = truth.acceleration_mps2[i];
        let fp = if particles {
            truth.force_axial_n[i]
        } else {
            0.0
        };
        let f = transducer_force_n(rig.enclosure.mass_kg, a, fp, static_weight_n);
        daq.push(truth.time_s[i], a, f);
    }
    let (trace, _) = daq.finish(TraceMetadata::default())?;
    Ok(Chained {
        force: trace.channel(crate::rig::FORCE_CHANNEL)?.samples.clone(),
        accel: trace.channel(crate::rig::ACCEL_CHANNEL)?.samples.clone(),
        fs_hz: trace.sample_rate_hz,
    })
}

/// The rig's chain replayed on the first seed's truth record, and Yang's
/// method on what it records (study (c)).
struct YangBench<'a> {
    truth: &'a TruthSamples,
    /// Drive frequency (Hz) and its angular frequency (rad/s).
    freq_hz: f64,
    omega: f64,
    feed_start_s: f64,
    record_start_s: f64,
    static_weight_n: f64,
    seed: u64,
    /// The calibration record's noise seed.
    calibration_seed: u64,
}

impl YangBench<'_> {
    /// A chain setting `r`: the record, its calibration record (the empty
    /// enclosure) and the wall time both took (s).
    fn chain(&self, r: &RigSpec) -> Result<(Chained, Chained, f64), SceneError> {
        let t0 = Stopwatch::start();
        let (feed, record, weight) = (self.feed_start_s, self.record_start_s, self.static_weight_n);
        let full = rechain(r, self.truth, feed, record, weight, self.seed, true)?;
        let empty = rechain(
            r,
            self.truth,
            feed,
            record,
            weight,
            self.calibration_seed,
            false,
        )?;
        Ok((full, empty, t0.elapsed().as_secs_f64()))
    }

    /// Samples of `c` in `n` periods.
    fn samples(&self, c: &Chained, n: usize) -> usize {
        ((n as f64 * c.fs_hz / self.freq_hz).round() as usize).min(c.force.len())
    }

    /// The empty enclosure's phase error over the first n periods.
    fn calibrate(&self, c: &Chained, n: usize) -> Result<f64, SceneError> {
        let len = self.samples(c, n);
        Ok(
            estimate_phase_error(&c.force[..len], &c.accel[..len], c.fs_hz, self.freq_hz)?
                .phase_error_rad,
        )
    }

    /// Yang over the first n periods, less the phase error `phi_rad`.
    fn estimate(&self, c: &Chained, n: usize, phi_rad: f64) -> Result<f64, SceneError> {
        let len = self.samples(c, n);
        let options = PowerOptions {
            phase_correction: PhaseCorrection::TimeDelay(phi_rad / self.omega),
            ..PowerOptions::default()
        };
        Ok(yang_power(
            &c.force[..len],
            &c.accel[..len],
            c.fs_hz,
            self.freq_hz,
            &options,
        )?
        .energy_per_cycle_j)
    }
}

/// The DEM's truth over the cycles of run `run` after `transient` cycles:
/// dissipation and work per cycle over the first `n`.
fn truth_window(run: &DriveRun, transient: usize, n: usize) -> (f64, f64) {
    let snaps: &[LedgerSnapshot] = run
        .outcome
        .as_ref()
        .map(|o| o.cycle_snapshots.as_slice())
        .unwrap_or(&[]);
    let (Some(a), Some(b)) = (snaps.get(transient), snaps.get(transient + n)) else {
        return (f64::NAN, f64::NAN);
    };
    let bal = LedgerBalance::between(a, b);
    (bal.dissipated_j / n as f64, bal.work_in_j / n as f64)
}

/// Study (c): Yang's method on the first seed's record.
fn yang_study(
    scene: &Scene,
    rig: &RigSpec,
    plan: &AccuracyPlan,
    run: &DriveRun,
    settle_wall_s: f64,
    dem: &DemAccuracy,
) -> Result<(Vec<AccuracyRow>, YangAccuracy), SceneError> {
    let t = plan.transient_cycles as usize;
    let empty = TruthSamples::default();
    let bench = yang_bench(scene, rig, plan, run.truth.as_ref().unwrap_or(&empty));
    let baseline = plan.baseline_record_periods() as usize;
    let dem_wall =
        |n: usize| settle_wall_s + run.cycle_wall_s.get(t + n).copied().unwrap_or(run.wall_s);

    let (full, empty_rec, chain_s) = bench.chain(rig)?;
    let RecordPeriods {
        mut rows,
        baseline_err,
        baseline_phi,
    } = record_period_rows(
        &bench,
        plan,
        run,
        (&full, &empty_rec),
        &|n| dem_wall(n) + chain_s,
        dem.pooled_energy_per_cycle_j,
    )?;
    let (dissipated, _) = truth_window(run, t, baseline);
    let base_wall = dem_wall(baseline);
    rows.extend(chain_setting_rows(
        &bench, rig, plan, baseline, dissipated, base_wall,
    )?);
    let (phase_rows, error_per_mrad) = residual_phase_rows(
        &bench,
        &full,
        plan,
        baseline,
        baseline_phi,
        dissipated,
        base_wall + chain_s,
    )?;
    rows.extend(phase_rows);
    Ok((
        rows,
        YangAccuracy {
            rig: rig.name.clone(),
            baseline_record_periods: baseline as u32,
            baseline_error_vs_work_rel: baseline_err.chain,
            baseline_unsteadiness_rel: baseline_err.unsteadiness,
            baseline_error_rel: baseline_err.vs_dissipated,
            rig_phase_error_rad: rig.expected_phase_error_rad(plan.freq_hz),
            calibrated_phase_error_rad: baseline_phi,
            error_per_mrad,
        },
    ))
}

/// Study (c)'s bench: the DEM's `truth` record of a drive of `plan` put
/// through the chain of `rig` from the end of its first cycle, recorded
/// after the transient cycles.
fn yang_bench<'a>(
    scene: &Scene,
    rig: &RigSpec,
    plan: &AccuracyPlan,
    truth: &'a TruthSamples,
) -> YangBench<'a> {
    let f = plan.freq_hz;
    let period = 1.0 / f;
    let weight = match scene.enclosure.orientation {
        Orientation::Vertical => rig.enclosure.mass_kg * scene.simulation.gravity_mps2,
        Orientation::Horizontal => 0.0,
    };
    let record_start = f64::from(plan.transient_cycles) * period;
    // The prescribed sine starts at full velocity into the resting bed: the
    // first sample of the drive carries a slam (about -180 N on the thesis
    // rig's 60-sphere test bed) that an AC-coupled chain turns into a slowly
    // decaying offset across the record. A lab's chain runs long before the
    // record; feed it from the end of the first cycle.
    YangBench {
        truth,
        freq_hz: f,
        omega: 2.0 * PI * f,
        feed_start_s: period.min(record_start),
        record_start_s: record_start,
        static_weight_n: weight,
        seed: scene.simulation.seed,
        // The calibration's noise: another seed, so its noise is its own.
        calibration_seed: scene.simulation.seed ^ 0x5eed_ca1b,
    }
}

/// Study (c)'s rows of residual phase errors: Yang on the `record` over
/// `baseline` periods, corrected by the calibrated `baseline_phi` (rad) plus
/// each residual of `plan`, against the DEM's `dissipated` energy per cycle
/// (J); `wall` is the wall time to there (s). Also the error's slope per
/// mrad (from zero to the largest residual), when both were run.
fn residual_phase_rows(
    bench: &YangBench,
    record: &Chained,
    plan: &AccuracyPlan,
    baseline: usize,
    baseline_phi: f64,
    dissipated: f64,
    wall: f64,
) -> Result<(Vec<AccuracyRow>, Option<f64>), SceneError> {
    let mut rows = Vec::new();
    let mut phase_pts = Vec::new();
    for &mrad in &plan.residual_phase_mrad {
        let t1 = Stopwatch::start();
        let e = bench.estimate(record, baseline, baseline_phi + 1e-3 * mrad)?;
        let row = residual_phase_row(
            mrad,
            e,
            dissipated,
            wall + t1.elapsed().as_secs_f64(),
            baseline,
            baseline_phi,
        );
        phase_pts.push((mrad, row.error_rel));
        rows.push(row);
    }
    let error_per_mrad = {
        let zero = phase_pts.iter().find(|p| p.0 == 0.0).map(|p| p.1);
        let far = phase_pts
            .iter()
            .filter(|p| p.0 != 0.0)
            .max_by(|a, b| a.0.abs().total_cmp(&b.0.abs()));
        zero.zip(far).map(|(z, (m, e))| (e - z) / m)
    };
    Ok((rows, error_per_mrad))
}

/// Study (c)'s row of a residual phase error of `mrad` left after the
/// calibrated `baseline_phi` (rad) over `baseline` periods: Yang's estimate
/// `e` against the DEM's `dissipated` energy per cycle (J).
fn residual_phase_row(
    mrad: f64,
    e: f64,
    dissipated: f64,
    wall: f64,
    baseline: usize,
    baseline_phi: f64,
) -> AccuracyRow {
    let mut row = AccuracyRow::new(
        "yang",
        "residual_phase_mrad",
        mrad,
        "energy_per_cycle_j",
        e,
        dissipated,
        f64::NAN,
        wall,
    );
    row.note = format!(
        "correction {:.4} mrad (calibrated {:.4} mrad + residual), {baseline} periods",
        1e3 * baseline_phi + mrad,
        1e3 * baseline_phi
    );
    row
}

/// Yang's error at the baseline record length, in its two parts and whole.
struct BaselineErrors {
    /// Against the enclosure's work in: the chain's error.
    chain: f64,
    /// The work in against the DEM dissipation: the bed's unsteadiness.
    unsteadiness: f64,
    /// Against the DEM dissipation: both together.
    vs_dissipated: f64,
}

/// What [`record_period_rows`] gives.
struct RecordPeriods {
    rows: Vec<AccuracyRow>,
    /// Errors at the baseline length.
    baseline_err: BaselineErrors,
    /// The phase error calibrated at the baseline length (rad).
    baseline_phi: f64,
}

/// Study (c)'s rows of record lengths: Yang on the `record` (and on its
/// empty-enclosure `calibration`) over each length of `plan`, against the
/// DEM's dissipation and work over the same cycles and the `pooled` mean
/// (J); `wall(n)` is the wall time to `n` periods (s).
fn record_period_rows(
    bench: &YangBench,
    plan: &AccuracyPlan,
    run: &DriveRun,
    chained: (&Chained, &Chained),
    wall: &dyn Fn(usize) -> f64,
    pooled: f64,
) -> Result<RecordPeriods, SceneError> {
    let t = plan.transient_cycles as usize;
    let baseline = plan.baseline_record_periods() as usize;
    let mut rows = Vec::new();
    let mut baseline_err = BaselineErrors {
        chain: f64::NAN,
        unsteadiness: f64::NAN,
        vs_dissipated: f64::NAN,
    };
    let mut baseline_phi = f64::NAN;
    let cycle_energies = run.cycle_energies(t);
    for &n in &plan.record_periods {
        let n = n as usize;
        let t1 = Stopwatch::start();
        let (length_rows, phi) = record_length_rows(
            bench,
            chained,
            n,
            &|| wall(n) + t1.elapsed().as_secs_f64(),
            truth_window(run, t, n),
            (&cycle_energies, pooled),
        )?;
        if n == baseline {
            baseline_err = BaselineErrors {
                chain: length_rows[0].error_rel,
                unsteadiness: length_rows[1].error_rel,
                vs_dissipated: length_rows[2].error_rel,
            };
            baseline_phi = phi;
        }
        rows.extend(length_rows);
    }
    Ok(RecordPeriods {
        rows,
        baseline_err,
        baseline_phi,
    })
}

/// Study (c)'s five rows of a record of `n` periods, and the phase error
/// calibrated on it (rad), the chain's error first: Yang on the `record`
/// against the DEM's work per cycle over the same cycles (the chain), that
/// work against the dissipation per cycle (the bed's unsteadiness), Yang
/// against the dissipation (both: the error against the DEM truth), all from
/// `(dissipated, work)` (J); Yang on the `calibration` record itself (the
/// chain's false energy); Yang against the `pooled` mean with the standard
/// error of the first `n` of the bed's `cycle_energies` (J). `wall()` is the
/// wall time to there (s), taken once both are calibrated and estimated.
fn record_length_rows(
    bench: &YangBench,
    (record, calibration): (&Chained, &Chained),
    n: usize,
    wall: &dyn Fn() -> f64,
    (dissipated, work): (f64, f64),
    (cycle_energies, pooled): (&[f64], f64),
) -> Result<(Vec<AccuracyRow>, f64), SceneError> {
    let phi = bench.calibrate(calibration, n)?;
    let e = bench.estimate(record, n, phi)?;
    let wall = wall();
    let row = |quantity: &'static str, value: f64, reference: f64, stderr_rel: f64| {
        AccuracyRow::new(
            "yang",
            "record_periods",
            n as f64,
            quantity,
            value,
            reference,
            stderr_rel,
            wall,
        )
    };
    let note = format!("calibrated phase error {:.4} mrad", 1e3 * phi);
    let mut vs_work = row("energy_per_cycle_vs_work_j", e, work, f64::NAN);
    vs_work.note = "against the enclosure's work over the same cycles: the chain alone".into();
    let mut unsteady = row("work_in_per_cycle_j", work, dissipated, f64::NAN);
    unsteady.note =
        "the enclosure's work against the DEM dissipation over the same cycles: the bed's unsteadiness"
            .into();
    let mut vs_dissipated = row("energy_per_cycle_j", e, dissipated, f64::NAN);
    vs_dissipated.note = format!(
        "against the DEM dissipation over the same cycles: the chain and the unsteadiness; {note}"
    );
    // The chain's false energy: Yang on the calibration record itself.
    let false_e = bench.estimate(calibration, n, phi)?;
    let mut empty = row(
        "empty_enclosure_energy_per_cycle_j",
        false_e,
        work,
        f64::NAN,
    );
    empty.error_rel = false_e / work;
    empty.note = "Yang on the calibration record (no particles), relative to the work in: the chain's own false energy".into();
    let se = mean_stderr(&cycle_energies[..n.min(cycle_energies.len())]).stderr_or_nan();
    let mut vs_mean = row("energy_per_cycle_vs_bed_mean_j", e, pooled, se / pooled);
    vs_mean.note = "against the bed's long-run mean (all seeds): chain and statistics".into();
    Ok((vec![vs_work, unsteady, vs_dissipated, empty, vs_mean], phi))
}

/// Study (c)'s rows of chain settings: the noise factors and ADC bits of
/// `plan` on `rig`, each calibrated and estimated over `baseline` periods
/// against the DEM's `dissipated` energy per cycle (J); `base_wall` is the
/// DEM's wall time to there (s).
fn chain_setting_rows(
    bench: &YangBench,
    rig: &RigSpec,
    plan: &AccuracyPlan,
    baseline: usize,
    dissipated: f64,
    base_wall: f64,
) -> Result<Vec<AccuracyRow>, SceneError> {
    let mut rows = Vec::new();
    let mut setting = |parameter: &'static str,
                       value: f64,
                       r: &RigSpec,
                       note: String|
     -> Result<(), SceneError> {
        let t1 = Stopwatch::start();
        let (full, empty_rec, _) = bench.chain(r)?;
        let phi = bench.calibrate(&empty_rec, baseline)?;
        let e = bench.estimate(&full, baseline, phi)?;
        let mut row = AccuracyRow::new(
            "yang",
            parameter,
            value,
            "energy_per_cycle_j",
            e,
            dissipated,
            f64::NAN,
            base_wall + t1.elapsed().as_secs_f64(),
        );
        row.note = format!(
            "{note}, {baseline} periods, calibrated {:.4} mrad",
            1e3 * phi
        );
        rows.push(row);
        Ok(())
    };
    for &k in &plan.noise_factors {
        let mut r = rig.clone();
        r.force.noise_rms *= k;
        r.accelerometer.noise_rms *= k;
        let note = format!(
            "noise {:.3e} N and {:.3e} m/s^2 rms",
            r.force.noise_rms, r.accelerometer.noise_rms
        );
        setting("noise_factor", k, &r, note)?;
    }
    for &bits in &plan.adc_bits {
        let mut r = rig.clone();
        r.daq.bits = bits;
        r.daq.ideal_adc = false;
        let lsb_n = 2.0 * r.daq.full_scale_v
            / 2f64.powi(bits as i32)
            / (r.force.sensitivity * r.force.conditioner_gain);
        setting(
            "adc_bits",
            f64::from(bits),
            &r,
            format!("force LSB {lsb_n:.3e} N"),
        )?;
    }
    Ok(rows)
}

impl AccuracyReport {
    /// Writes `accuracy.csv`, the plots (with the `plot` feature) and
    /// `summary.json` (last) into `dir`, which must exist; each file
    /// atomically.
    pub fn write(&mut self, dir: &Path) -> Result<(), SceneError> {
        let write = |name: &str, text: &str| {
            let path = dir.join(name);
            write_bytes_atomic(&path, text.as_bytes())
                .map_err(|source| SceneError::Write { path, source })
        };
        write("accuracy.csv", &rows_to_csv(&self.rows))?;
        #[cfg_attr(not(feature = "plot"), allow(unused_mut))]
        let mut files = vec!["summary.json".to_string(), "accuracy.csv".to_string()];
        #[cfg(feature = "plot")]
        files.extend(plots::write_plots(dir, &self.rows, &self.summary)?);
        self.summary.files = files;
        write("summary.json", &self.summary_json())
    }

    /// `summary.json`'s text.
    pub fn summary_json(&self) -> String {
        serde_json::to_string_pretty(&self.summary)
            .unwrap_or_else(|e| format!("{{\"error\": \"{e}\"}}"))
            + "\n"
    }
}

#[cfg(feature = "plot")]
mod plots {
    //! The plots of the studies: log10 axes drawn by the crate's linear x-y
    //! plot, so every point must be positive.

    use std::path::Path;

    use super::{AccuracyRow, AccuracySummary};
    use crate::scene::SceneError;
    use crate::signals::{Series, SeriesStyle, plot_xy_svg};

    fn select<'a>(
        rows: &'a [AccuracyRow],
        study: &'a str,
        parameter: &'a str,
        quantity: &'a str,
    ) -> impl Iterator<Item = &'a AccuracyRow> + 'a {
        rows.iter()
            .filter(move |r| r.study == study && r.parameter == parameter && r.quantity == quantity)
    }

    fn series(name: &str, style: SeriesStyle, points: Vec<(f64, f64)>) -> Option<Series> {
        let points: Vec<(f64, f64)> = points
            .into_iter()
            .filter(|(x, y)| *x > 0.0 && *y > 0.0 && x.is_finite() && y.is_finite())
            .map(|(x, y)| (x.log10(), y.log10()))
            .collect();
        (!points.is_empty()).then(|| Series {
            name: name.into(),
            points,
            style,
        })
    }

    /// Writes the plots; returns their file names.
    pub fn write_plots(
        dir: &Path,
        rows: &[AccuracyRow],
        summary: &AccuracySummary,
    ) -> Result<Vec<String>, SceneError> {
        let mut files = vec![accuracy_plot(dir, rows, summary)?];
        files.extend(impact_plot(dir, rows, summary)?);
        files.extend(yang_plot(dir, rows, summary)?);
        Ok(files
            .into_iter()
            .flat_map(|svg| {
                let png = svg.replace(".svg", ".png");
                [svg, png]
            })
            .collect())
    }

    /// Draws `name.svg` and `name.png` in `dir`.
    fn svg_and_png(
        dir: &Path,
        name: &str,
        title: &str,
        x_label: &str,
        y_label: &str,
        series: &[Series],
    ) -> Result<(), crate::signals::SignalsError> {
        for ext in ["svg", "png"] {
            plot_xy_svg(
                &dir.join(format!("{name}.{ext}")),
                title,
                x_label,
                y_label,
                series,
            )?;
        }
        Ok(())
    }

    /// `accuracy.svg`: every study's error against its run time.
    ///
    /// Over 80 lines: one figure's series, a few lines each, that share the
    /// axes' range; split, the range and the rows would be passed to each.
    fn accuracy_plot(
        dir: &Path,
        rows: &[AccuracyRow],
        summary: &AccuracySummary,
    ) -> Result<String, SceneError> {
        let dem_q = "energy_per_cycle_j";
        let wall_err = |r: &AccuracyRow| (r.wall_s, r.error_rel.abs());
        let wall_se = |r: &AccuracyRow| (r.wall_s, r.stderr_rel);
        let dt_rows: Vec<&AccuracyRow> = select(rows, "dem", "dt_over_rayleigh", dem_q).collect();
        let cyc: Vec<&AccuracyRow> = select(rows, "dem", "steady_cycles", dem_q).collect();
        let all_wall: Vec<f64> = rows
            .iter()
            .filter(|r| r.study != "impact" && r.wall_s > 0.0)
            .map(|r| r.wall_s)
            .collect();
        let (w0, w1) = all_wall
            .iter()
            .fold((f64::INFINITY, 0.0f64), |(a, b), &w| (a.min(w), b.max(w)));
        let spread = summary.dem.seed_spread_rel;
        let mut main = vec![
            series(
                "DEM time step: |error| vs finest step",
                SeriesStyle::Points,
                dt_rows.iter().map(|r| wall_err(r)).collect(),
            ),
            series(
                "DEM time step: standard error of that",
                SeriesStyle::Line,
                dt_rows.iter().map(|r| wall_se(r)).collect(),
            ),
            series(
                "DEM time step: integrator energy error",
                SeriesStyle::Points,
                select(rows, "dem", "dt_over_rayleigh", "integrator_rel")
                    .map(wall_err)
                    .collect(),
            ),
            series(
                "DEM cycles: standard error of the mean",
                SeriesStyle::Line,
                cyc.iter().map(|r| wall_se(r)).collect(),
            ),
            series(
                "DEM cycles: rms error of blocks",
                SeriesStyle::Points,
                select(rows, "dem", "steady_cycles", "block_rms_rel")
                    .map(wall_err)
                    .collect(),
            ),
            series(
                "DEM seeds: |mean - pooled mean|",
                SeriesStyle::Points,
                select(rows, "dem", "seed", dem_q).map(wall_err).collect(),
            ),
            series(
                "Yang vs work in, same cycles (the chain): |error| by record length",
                SeriesStyle::Points,
                select(rows, "yang", "record_periods", "energy_per_cycle_vs_work_j")
                    .map(wall_err)
                    .collect(),
            ),
            series(
                "work in vs DEM dissipation (the bed's unsteadiness): |error| by record length",
                SeriesStyle::Points,
                select(rows, "yang", "record_periods", "work_in_per_cycle_j")
                    .map(wall_err)
                    .collect(),
            ),
            series(
                "Yang vs DEM, same cycles (chain and unsteadiness): |error| by record length",
                SeriesStyle::Points,
                select(rows, "yang", "record_periods", dem_q)
                    .map(wall_err)
                    .collect(),
            ),
        ];
        if spread.is_finite() && w1 > w0 {
            main.push(series(
                "seed-to-seed spread (sd of seed means)",
                SeriesStyle::Line,
                vec![(w0, spread), (w1, spread)],
            ));
        }
        let main: Vec<Series> = main.into_iter().flatten().collect();
        let title = format!(
            "{} damper, {} Hz, Gamma {}: error against run time",
            summary.scene, summary.plan.freq_hz, summary.plan.gamma
        );
        svg_and_png(
            dir,
            "accuracy",
            &title,
            "log10 wall-clock time (s)",
            "log10 relative error",
            &main,
        )?;
        Ok("accuracy.svg".to_string())
    }

    /// `impact.svg`: the collision's errors against its resolution (none
    /// without points).
    fn impact_plot(
        dir: &Path,
        rows: &[AccuracyRow],
        summary: &AccuracySummary,
    ) -> Result<Option<String>, SceneError> {
        let imp = |q: &str, name: &str| {
            series(
                name,
                SeriesStyle::Line,
                select(rows, "impact", "steps_per_contact", q)
                    .map(|r| (r.value, r.error_rel.abs()))
                    .collect(),
            )
        };
        let impact: Vec<Series> = [
            imp("max_overlap_m", "max overlap vs eq. 5.8"),
            imp("contact_duration_s", "duration vs eq. 5.10"),
            imp(
                "contact_duration_exact_s",
                "duration vs exact Hertz integral",
            ),
            imp("restitution", "restitution vs configured e"),
            imp("elastic_restitution", "restitution of e = 1 vs 1"),
        ]
        .into_iter()
        .flatten()
        .collect();
        if !impact.is_empty() {
            svg_and_png(
                dir,
                "impact",
                &format!(
                    "one collision at {:.2} m/s against Hertz theory",
                    summary.impact.speed_mps
                ),
                "log10 steps per contact",
                "log10 |relative error|",
                &impact,
            )?;
            return Ok(Some("impact.svg".to_string()));
        }
        Ok(None)
    }

    /// `yang.svg`: Yang's error against the chain's settings (none without
    /// points).
    fn yang_plot(
        dir: &Path,
        rows: &[AccuracyRow],
        summary: &AccuracySummary,
    ) -> Result<Option<String>, SceneError> {
        let dem_q = "energy_per_cycle_j";
        let yang: Vec<Series> = [
            series(
                "noise factor (x rig rms)",
                SeriesStyle::Points,
                select(rows, "yang", "noise_factor", dem_q)
                    .map(|r| (r.value, r.error_rel.abs()))
                    .collect(),
            ),
            series(
                "residual phase error (mrad)",
                SeriesStyle::Points,
                select(rows, "yang", "residual_phase_mrad", dem_q)
                    .map(|r| (r.value, r.error_rel.abs()))
                    .collect(),
            ),
            series(
                "ADC: 2^(16 - bits)",
                SeriesStyle::Points,
                select(rows, "yang", "adc_bits", dem_q)
                    .map(|r| (2f64.powf(16.0 - r.value), r.error_rel.abs()))
                    .collect(),
            ),
        ]
        .into_iter()
        .flatten()
        .collect();
        if !yang.is_empty() {
            svg_and_png(
                dir,
                "yang",
                &format!(
                    "Yang's estimate vs DEM truth, {} periods, chain settings",
                    summary.yang.baseline_record_periods
                ),
                "log10 setting (as in the legend)",
                "log10 |relative error|",
                &yang,
            )?;
            return Ok(Some("yang.svg".to_string()));
        }
        Ok(None)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn log_log_slope_recovers_a_power_law() {
        let pts: Vec<(f64, f64)> = [5.0, 10.0, 20.0, 40.0]
            .iter()
            .map(|&n: &f64| (n, -3.0 * n.powi(-2)))
            .collect();
        let s = log_log_slope(&pts).expect("slope");
        assert!((s + 2.0).abs() < 1e-12, "{s}");
        // Zeros and non-finite values are skipped; one point is not enough.
        assert_eq!(
            log_log_slope(&[(1.0, 0.0), (2.0, f64::NAN), (3.0, 1.0)]),
            None
        );
    }

    #[test]
    fn block_rms_uses_disjoint_whole_blocks() {
        let series = vec![vec![1.0, 3.0, 2.0, 2.0, 9.0], vec![2.0, 2.0]];
        // Blocks of 2: [1,3] [2,2] | [2,2]: means 2, 2, 2 → no deviation from 2.
        assert_eq!(
            block_rms_rel(&series, 2, 2.0),
            BlockSpread {
                rms_rel: 0.0,
                blocks: 3
            }
        );
        // Blocks of 1 of the first series against 2: deviations -0.5, 0.5, 0, 0, 3.5, 0, 0.
        let BlockSpread {
            rms_rel: rms,
            blocks: n,
        } = block_rms_rel(&series, 1, 2.0);
        assert_eq!(n, 7);
        assert!((rms - ((0.25 + 0.25 + 12.25) / 7.0f64).sqrt()).abs() < 1e-12);
        assert_eq!(block_rms_rel(&series, 6, 2.0).blocks, 0);
    }

    #[test]
    fn csv_is_tidy_and_leaves_nan_empty() {
        let mut row = AccuracyRow::new(
            "dem",
            "seed",
            2.0,
            "energy_per_cycle_j",
            0.055,
            0.05,
            f64::NAN,
            1.5,
        );
        row.note = "a \"quoted\" note, with a comma".into();
        let csv = rows_to_csv(&[row]);
        let mut lines = csv.lines();
        assert_eq!(lines.next(), Some(CSV_HEADER));
        let line = lines.next().expect("row");
        assert!(
            line.starts_with("dem,seed,2e0,energy_per_cycle_j,5.5e-2,5e-2,"),
            "{line}"
        );
        assert!(
            line.contains(",,1.5e0,\"a \"\"quoted\"\" note, with a comma\""),
            "{line}"
        );
        let error: f64 = line
            .split(',')
            .nth(6)
            .and_then(|x| x.parse().ok())
            .expect("error");
        assert!((error - 0.1).abs() < 1e-12);
    }

    #[test]
    fn plans_are_valid_and_refusals_name_the_field() {
        AccuracyPlan::full(40.0, 20.0).validate().expect("full");
        AccuracyPlan::quick(40.0, 20.0).validate().expect("quick");
        let mut p = AccuracyPlan::quick(40.0, 20.0);
        p.cycle_counts.push(6);
        let e = p
            .validate()
            .expect_err("6 is not a multiple of 4")
            .to_string();
        assert!(e.contains("cycle_counts"), "{e}");
        let mut p = AccuracyPlan::quick(40.0, 20.0);
        p.record_periods.push(4);
        assert!(p.validate().is_err());
        let mut p = AccuracyPlan::quick(40.0, 20.0);
        p.dt_over_rayleigh.push(1.5);
        assert!(p.validate().is_err());
    }

    #[test]
    fn hertz_integral_constant() {
        // (2/5) B(2/5, 1/2) by the midpoint rule after x = 1 - u², which
        // removes the endpoint singularity: I = ∫₀¹ 2u / √(1 - (1-u²)^{5/2}) du.
        let n = 200_000;
        let h = 1.0 / n as f64;
        let i: f64 = (0..n)
            .map(|k| {
                let u = (k as f64 + 0.5) * h;
                2.0 * u / (1.0 - (1.0 - u * u).powf(2.5)).sqrt() * h
            })
            .sum();
        assert!((i / HERTZ_DURATION_INTEGRAL - 1.0).abs() < 1e-6, "{i}");
        // Eq. 5.10's 1.435 in the δ_max / v form: 1.435 / (15/16)^{2/5}.
        let eq_5_10 = 1.435 / (15.0f64 / 16.0).powf(0.4);
        assert!((eq_5_10 / HERTZ_DURATION_INTEGRAL - 1.0 - 6.0e-4).abs() < 0.2e-4);
    }
}
