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

mod dem;
mod impact;
#[cfg(feature = "plot")]
mod plots;
pub mod read_back;
mod yang;

use dem::dem_study;
use impact::impact_study;
use yang::yang_study;

/// What the plots take from `summary.json` besides the rows: their titles'
/// scene, drive, collision speed and record length, and the seeds' spread
/// (NaN: not measured; no line is drawn).
#[derive(Debug, Clone, PartialEq)]
pub struct PlotLabels {
    pub scene: String,
    pub freq_hz: f64,
    pub gamma: f64,
    pub seed_spread_rel: f64,
    pub impact_speed_mps: f64,
    pub baseline_record_periods: u32,
}

impl From<&AccuracySummary> for PlotLabels {
    fn from(s: &AccuracySummary) -> Self {
        PlotLabels {
            scene: s.scene.clone(),
            freq_hz: s.plan.freq_hz,
            gamma: s.plan.gamma,
            seed_spread_rel: s.dem.seed_spread_rel,
            impact_speed_mps: s.impact.speed_mps,
            baseline_record_periods: s.yang.baseline_record_periods,
        }
    }
}

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
            // 16: the fewest cycles whose mean has a standard error
            // (crate::stats); with 12 the difference had none and the study
            // could not say whether it was discretisation or chance.
            dt_steady_cycles: 16,
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
    pub study: String,
    /// What varies: `dt_over_rayleigh`, `seed`, `steady_cycles`,
    /// `steps_per_contact`, `record_periods`, `noise_factor`, `adc_bits`,
    /// `residual_phase_mrad`.
    pub parameter: String,
    pub value: f64,
    pub quantity: String,
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
            study: study.into(),
            parameter: parameter.into(),
            value,
            quantity: quantity.into(),
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
            r.study.clone(),
            r.parameter.clone(),
            num(r.value),
            r.quantity.clone(),
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
        files.extend(plots::write_plots(
            dir,
            &self.rows,
            &PlotLabels::from(&self.summary),
        )?);
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
