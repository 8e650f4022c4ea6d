//! What an ensemble of beds says about the damper
//! ([`crate::experiment::ensemble`]): its figures, each the mean over the
//! beds with the error of their spread (Student's t on `N − 1` degrees of
//! freedom, [`crate::stats::ensemble_mean`]), the rule's verdict, one row a
//! bed (`beds.csv`), and the words for a window not shown steady. Apart
//! from the runner so that a shake's summary can carry it.

use serde::Serialize;

use crate::experiment::damper::{DRIFT_FLOOR_REL, Steadiness};
use crate::stats::{MeanStderr, ensemble_mean, ensemble_mean_floored};

/// How far the mean of the same beds driven on for hundreds more cycles
/// may lie from a window's mean, one sigma, relative, times the square root
/// of the window's cycles ([`longer_drive_rel`]): 21 %, so 3.0 % over the
/// default job's 50 cycles at 40 Hz Γ 20, 1.3 % over 250.
///
/// The beds keep changing after any window a run can show stationary, in
/// either direction and by more than the window's noise: a slow creep (at
/// 80 Hz Γ 28 the runs of 124-400 cycles read 1.5 % above twelve beds
/// driven 800), or a bed falling at a random time into a state that
/// dissipates 10-15 % less (at 20 Hz Γ 5 two of six beds did between
/// cycles 50 and 800; the run that stopped at 50 read 5.0 % above the same
/// beds over cycles 401-800). No window's own drift can see either (its
/// error across the window is √12 times the mean's), and the beds' spread
/// sees only the changes that have happened. Taken as the error of the
/// mean of a slow fluctuation whose correlation time is longer than the
/// window, it falls as one over the root of the window's cycles. What the
/// +- of an ensemble leaves out, so printed beside it, never folded in: the
/// beds' +- is checked against how far runs of the same length scatter, this
/// part against beds driven 800 cycles.
///
/// 0.21: the rms of `d √w` over the five conditions where it was measured
/// (`d` how far the runs read from beds driven 800 cycles, `w` their
/// windows' cycles: 80 Hz Γ 4, 9, 10 and 28 and 20 Hz Γ 5; 10-28 each),
/// checked at conditions and seeds not used to choose it (three so far)
/// (`docs/accuracy.md`, "A longer drive"). An allowance, not a measured
/// error: where the beds neither creep nor fall it is wide (at 40 Hz Γ 20
/// the default job's six beds driven 800 cycles read 0.13 % from its
/// figure, against 3.0 % allowed).
pub const LONGER_DRIVE_SCALE: f64 = 0.21;

/// The allowance for a longer drive of a figure over a window of
/// `window_cycles` cycles, relative ([`LONGER_DRIVE_SCALE`]).
pub fn longer_drive_rel(window_cycles: u32) -> f64 {
    LONGER_DRIVE_SCALE / f64::from(window_cycles.max(1)).sqrt()
}

/// An ensemble's figure: the mean over the beds and its one-sigma error
/// from their spread (Student's t on `beds − 1` degrees of freedom), never
/// less than the beds' own window errors make it
/// ([`crate::stats::ensemble_mean_floored`]), and beside it the allowance
/// for a longer drive ([`longer_drive_rel`]).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct EnsembleFigure {
    pub mean: f64,
    /// `None` for one bed: its spread is not known.
    pub stderr: Option<f64>,
    /// Sample standard deviation of the beds' figures (0 for one bed).
    pub spread: f64,
    /// One sigma of how far the same beds driven for hundreds more cycles
    /// may read ([`longer_drive_rel`] of the mean): not in `stderr`.
    pub longer_drive: f64,
}

impl EnsembleFigure {
    /// The figure of `values`, one per bed, each with its own window's
    /// error where known (the error is floored only if every bed's is),
    /// over windows of `window_cycles` cycles.
    pub fn of(values: &[f64], window_stderrs: &[Option<f64>], window_cycles: u32) -> Self {
        let windows: Option<Vec<f64>> = window_stderrs.iter().copied().collect();
        let m: MeanStderr = match windows {
            Some(w) if w.len() == values.len() => ensemble_mean_floored(values, &w),
            _ => ensemble_mean(values),
        };
        EnsembleFigure {
            mean: m.mean,
            stderr: m.stderr,
            spread: crate::stats::mean_std(values).std,
            longer_drive: longer_drive_rel(window_cycles) * m.mean.abs(),
        }
    }

    /// The one-sigma error of the mean as the state of beds driven on:
    /// `stderr` and `longer_drive` in quadrature (`None` where `stderr` is
    /// not known).
    pub fn stderr_with_longer_drive(&self) -> Option<f64> {
        self.stderr.map(|se| se.hypot(self.longer_drive))
    }
}

/// One bed of an ensemble, as `beds.csv` and the summary list it.
#[derive(Debug, Clone, Serialize)]
pub struct BedRow {
    pub bed: u32,
    pub seed: u64,
    pub dem_energy_per_cycle_j: f64,
    /// This bed's window error (J): what one bed alone would claim.
    pub dem_window_stderr_j: Option<f64>,
    pub dem_efficiency: f64,
    pub measured_energy_per_cycle_j: f64,
    pub measured_stderr_j: Option<f64>,
    pub measured_efficiency: f64,
    /// The bed's energy per cycle alternates (period 2).
    pub alternates: bool,
    /// Drift across the window, of the mean (its own window judged alone).
    pub drift_rel: Option<f64>,
    pub drift_stderr_rel: Option<f64>,
}

/// What an ensemble says about the damper.
#[derive(Debug, Clone, Serialize)]
pub struct EnsembleSummary {
    pub beds: usize,
    /// Energy dissipated per cycle (J), DEM truth, over the beds.
    pub dem_energy_per_cycle_j: EnsembleFigure,
    pub dem_efficiency: EnsembleFigure,
    /// Yang's method on each bed's rig record (J), over the beds.
    pub measured_energy_per_cycle_j: EnsembleFigure,
    pub measured_efficiency: EnsembleFigure,
    /// The steady rule's verdict on the ensemble (error of the beds'
    /// spread, drift and warm-up of their mean series).
    pub steadiness: Steadiness,
    pub cycles: u32,
    pub steady_first_cycle: u32,
    /// Wall time of the whole ensemble (s), and the threads it stepped on.
    pub wall_time_s: f64,
    pub threads: usize,
    /// Every bed's particles × drive steps over `wall_time_s`: the
    /// ensemble's speed, settling included (a bed's own figure counts its
    /// waits for the others: in a run of 6 beds on 1 thread it is about a
    /// sixth of the rate the DEM steps at).
    pub particle_steps_per_s: f64,
    /// Every bed's particles × drive steps over the drive's wall time (the
    /// longest bed's stepping loop, its waits for the others included): the
    /// DEM's speed over the beds, settling and the rig excluded.
    #[serde(default)]
    pub drive_particle_steps_per_s: f64,
    pub rows: Vec<BedRow>,
}

impl EnsembleSummary {
    /// `beds.csv`: one row per bed.
    pub fn beds_csv(&self) -> String {
        let mut out = String::from(
            "bed,seed,dem_energy_per_cycle_j,dem_window_stderr_j,dem_efficiency,measured_energy_per_cycle_j,measured_stderr_j,measured_efficiency,alternates,drift_rel,drift_stderr_rel\n",
        );
        let opt = |v: Option<f64>| v.map_or(String::new(), |x| format!("{x:e}"));
        for r in &self.rows {
            out.push_str(&format!(
                "{},{},{:e},{},{:e},{:e},{},{:e},{},{},{}\n",
                r.bed,
                r.seed,
                r.dem_energy_per_cycle_j,
                opt(r.dem_window_stderr_j),
                r.dem_efficiency,
                r.measured_energy_per_cycle_j,
                opt(r.measured_stderr_j),
                r.measured_efficiency,
                r.alternates,
                opt(r.drift_rel),
                opt(r.drift_stderr_rel),
            ));
        }
        out
    }
}

/// Why a window is not shown steady, in words.
pub fn unsteady_reasons(s: &Steadiness, first_cycle: u32) -> String {
    let mut why = Vec::new();
    if let (Some(d), Some(e)) = (s.drift_rel, s.drift_stderr_rel) {
        if s.drifts() {
            why.push(format!(
                "the mean energy per cycle drifts by {:+.2} % +- {:.2} % across the window",
                100.0 * d,
                100.0 * e
            ));
        } else if s.drift_asked_small() && !s.drift_shown_small() {
            why.push(format!(
                "the drift across the window, {:+.2} % +- {:.2} %, is not shown small (within twice the error of the mean, or {:.0} %, at two of its errors)",
                100.0 * d,
                100.0 * e,
                100.0 * DRIFT_FLOOR_REL
            ));
        }
    }
    if s.warming_up(first_cycle) {
        why.push(match s.warm_up_cycles {
            Some(d) if s.warm_up_open => format!(
                "the warm-up may not be over (MSER-5's least lies at cycle {d}, the end of the half of the drive it searches)"
            ),
            Some(d) => format!(
                "the warm-up (MSER-5) runs to cycle {d}, past the window's start at {first_cycle}"
            ),
            None => "the warm-up could not be told".to_string(),
        });
    }
    match (s.stderr_rel, s.window_part_rel) {
        (Some(r), Some(w)) => why.push(format!(
            "the error of the mean is {:.2} %, {:.2} % of it from the beds' windows",
            100.0 * r,
            100.0 * w
        )),
        (Some(r), None) => why.push(format!(
            "the error of the mean is {:.2} % (the windows' part not known)",
            100.0 * r
        )),
        _ => why.push("the error of the mean is not known".to_string()),
    }
    why.join("; ")
}
