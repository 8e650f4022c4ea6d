//! Ensembles of beds: the damper, not one random packing of it.
//!
//! One bed's window says how far its own cycles scatter; it cannot say how
//! far another bed of the same damper, poured with another seed, would read.
//! At 40 Hz, Γ 20 the means of independent beds spread by about 1 % while
//! each window claims 0.5 %; at 20 Hz, Γ 12 and 40 Hz, Γ 10 by 3.6 % against
//! 0.5-0.8 % (`docs/accuracy.md`). An ensemble drives `N` beds of one scene
//! (seeds [`bed_seed`]) alike and states the mean with the error of the
//! beds' spread, Student's t on `N − 1` degrees of freedom
//! ([`crate::stats::ensemble_mean`]): what a user asks about the damper.
//!
//! **Driven together.** The beds are judged together ([`EnsembleJudge`]):
//! each bed steps on its own thread, at most `threads` at once, and at
//! every checkpoint of the steady rule ([`crate::experiment::damper::judged_at`])
//! waits for the others; the verdict is taken on all of them at once
//! ([`crate::experiment::damper::ensemble_steadiness`]: the error of the
//! beds' spread, the drift and the warm-up of their mean series), so every
//! bed keeps the same window and the drive stops on the ensemble's error,
//! not on each bed's. The verdict depends only on the beds' ledgers, never
//! on which thread ran what: the same scene and seed give the same bits on
//! any number of threads. No thesis equation: the thesis measured one bed.

use std::sync::{Condvar, Mutex, MutexGuard};

use crate::dem::LedgerSnapshot;
use crate::experiment::bed::cache::BedSource;
use crate::experiment::bed::settle::SettledBed;
use crate::experiment::damper::{DriveJudge, Progress, Steadiness, StepObserver, Verdict, verdict};
pub use crate::experiment::ensemble_summary::{
    BedRow, EnsembleFigure, EnsembleSummary, unsteady_reasons,
};
use crate::experiment::measurement::ShakeSetup;
use crate::experiment::shake::{ShakeRun, run_shake_on_bed_judged};
use crate::scene::{DriveLength, Scene, SceneError};
use crate::validation::require;

/// Beds a `vlab shake` drives unless told (`--beds`): with 6 the z-scores
/// of the ensemble's mean against the truth spread by about 1.16
/// (Student's t on 5 degrees of freedom, `√(5/3)`, over its 68.3 % quantile
/// 1.11), within the 0.75-1.35 the coverage test asks, where 4 beds would
/// spread 1.45; on two cores six beds of the thesis damper take three beds'
/// time (`README.md`).
pub const DEFAULT_BEDS: u32 = 6;

/// Most beds one ensemble drives.
pub const MAX_BEDS: u32 = 64;

/// Where an ensemble's beds come from.
pub trait BedProvider: Sync {
    /// Bed `k` (0-based) of the ensemble, settled from `scene` (whose seed
    /// is already the bed's, [`bed_seed`]).
    fn bed(
        &self,
        scene: &Scene,
        k: u32,
        progress: &mut dyn FnMut(Progress),
    ) -> Result<SettledBed, SceneError>;
}

/// Each bed settled, or read from the bed cache.
impl BedProvider for BedSource {
    fn bed(
        &self,
        scene: &Scene,
        _k: u32,
        progress: &mut dyn FnMut(Progress),
    ) -> Result<SettledBed, SceneError> {
        self.settle(scene, progress)
    }
}

/// Seed of bed `k` (0-based) of an ensemble of seed `seed`: `seed` itself
/// for the first bed (so a one-bed run is the bed of `--seed`), then
/// `seed + k × 1 000 000`, so that ensembles of nearby seeds share no bed.
pub fn bed_seed(seed: u64, k: u32) -> u64 {
    seed.wrapping_add(u64::from(k) * 1_000_000)
}

/// Checks a number of beds: 1 to [`MAX_BEDS`].
pub fn check_beds(beds: u32) -> Result<(), SceneError> {
    Ok(require(
        (1..=MAX_BEDS).contains(&beds),
        "beds",
        beds,
        "",
        format!("from 1 to {MAX_BEDS}: independent beds of the damper, driven together"),
    )?)
}

/// Decides for beds driven together when their drive is done, and keeps
/// at most `threads` of them stepping at once (see the module docs).
pub struct EnsembleJudge {
    length: DriveLength,
    e_max_j: f64,
    beds: usize,
    threads: usize,
    state: Mutex<JudgeState>,
    turn: Condvar,
    running: Mutex<usize>,
    slot: Condvar,
}

#[derive(Default)]
struct JudgeState {
    /// Each bed's ledgers, posted for the round under way.
    posted: Vec<Option<Vec<LedgerSnapshot>>>,
    waiting: usize,
    round: u64,
    /// The last round's verdict.
    verdict: Option<Verdict>,
    latest: Option<Steadiness>,
    /// A bed failed: the others give up.
    failed: Option<String>,
}

impl EnsembleJudge {
    /// A judge of `beds` beds driven for `length` (`e_max_j` per cycle, as
    /// every bed's), stepping at most `threads` at once.
    pub fn new(length: DriveLength, e_max_j: f64, beds: usize, threads: usize) -> Self {
        EnsembleJudge {
            length,
            e_max_j,
            beds: beds.max(1),
            threads: threads.max(1),
            state: Mutex::new(JudgeState {
                posted: vec![None; beds.max(1)],
                ..JudgeState::default()
            }),
            turn: Condvar::new(),
            running: Mutex::new(0),
            slot: Condvar::new(),
        }
    }

    fn state(&self) -> MutexGuard<'_, JudgeState> {
        self.state.lock().unwrap_or_else(|p| p.into_inner())
    }

    /// Waits for a free thread slot, then holds it.
    pub fn start_stepping(&self) {
        let mut running = self.running.lock().unwrap_or_else(|p| p.into_inner());
        while *running >= self.threads {
            running = self.slot.wait(running).unwrap_or_else(|p| p.into_inner());
        }
        *running += 1;
    }

    /// Gives the thread slot back.
    pub fn stop_stepping(&self) {
        let mut running = self.running.lock().unwrap_or_else(|p| p.into_inner());
        *running = running.saturating_sub(1);
        self.slot.notify_one();
    }

    /// A bed failed (`why`): every bed waiting, or coming to wait, gives up.
    pub fn give_up(&self, why: String) {
        let mut st = self.state();
        st.failed.get_or_insert(why);
        self.turn.notify_all();
    }

    /// The ensemble's verdict of the last round.
    pub fn final_verdict(&self) -> Option<Verdict> {
        self.state().verdict
    }
}

impl DriveJudge for EnsembleJudge {
    fn judge(
        &self,
        bed: usize,
        snapshots: &[LedgerSnapshot],
    ) -> Result<Option<Verdict>, SceneError> {
        let mut st = self.state();
        if let Some(why) = &st.failed {
            return Err(SceneError::Ensemble(why.clone()));
        }
        st.posted[bed] = Some(snapshots.to_vec());
        st.waiting += 1;
        let round = st.round;
        if st.waiting == self.beds {
            let posted: Vec<&[LedgerSnapshot]> =
                st.posted.iter().flatten().map(Vec::as_slice).collect();
            let (done, latest) = verdict(self.length, &posted, self.e_max_j);
            st.verdict = done;
            st.latest = latest;
            st.waiting = 0;
            st.round += 1;
            st.posted.iter_mut().for_each(|p| *p = None);
            self.turn.notify_all();
        } else {
            self.stop_stepping();
            while st.round == round && st.failed.is_none() {
                st = self.turn.wait(st).unwrap_or_else(|p| p.into_inner());
            }
            drop(st);
            self.start_stepping();
            st = self.state();
            if st.round == round {
                let why = st.failed.clone().unwrap_or_default();
                return Err(SceneError::Ensemble(why));
            }
        }
        Ok(st.verdict)
    }

    fn latest(&self) -> Option<Steadiness> {
        self.state().latest
    }

    fn beds(&self) -> usize {
        self.beds
    }
}

/// Gives up the ensemble if a bed's thread unwinds before it finished.
struct GiveUpOnDrop<'a> {
    judge: &'a EnsembleJudge,
    bed: usize,
    armed: bool,
}

impl Drop for GiveUpOnDrop<'_> {
    fn drop(&mut self) {
        if self.armed {
            self.judge.give_up(format!("bed {} stopped", self.bed + 1));
        }
        self.judge.stop_stepping();
    }
}

/// A finished ensemble: the first bed's run (its records are the ones
/// written), with the ensemble in its summary, and every bed's run.
pub struct EnsembleRun {
    pub first: ShakeRun,
    pub others: Vec<ShakeRun>,
}

/// How `threads` threads are shared by `beds` beds: how many beds step at
/// once, and how many threads each of their steps may use (a bed driven
/// alone gets them all; 6 beds on 2 threads step 2 at a time, one thread
/// each; 2 beds on 8 threads 4 each). Never more than `threads` in all.
pub fn thread_shares(threads: usize, beds: u32) -> (usize, usize) {
    let threads = threads.max(1);
    let at_once = threads.min(beds.max(1) as usize);
    (at_once, threads / at_once)
}

/// Drives `beds` beds of `scene` (seeds [`bed_seed`] of its seed) alike
/// through the rig of `setup` on `threads` threads in all ([`thread_shares`]), judged
/// together; the first bed on the calling thread with `observers` and
/// `progress`, each other bed's rig noise seeded as its bed. The first
/// bed's summary carries the ensemble.
///
/// Over 80 lines: the beds' closures (judge, scenes, setups, the give-up guard)
/// and the scoped threads that run them share borrows of the caller's observers
/// and progress; split, each helper would take them all.
pub fn run_ensemble_shake(
    scene: &Scene,
    setup: &ShakeSetup,
    source: &dyn BedProvider,
    beds: u32,
    threads: usize,
    observers: &mut [&mut dyn StepObserver],
    progress: &mut dyn FnMut(Progress),
) -> Result<EnsembleRun, SceneError> {
    check_beds(beds)?;
    let started = crate::clock::Stopwatch::start();
    let (threads, step_threads) = thread_shares(threads, beds);
    let mass_kg = scene.particle_mass_kg();
    let judge = EnsembleJudge::new(
        scene.drive_length(),
        setup.drive.e_max_j(mass_kg),
        beds as usize,
        threads,
    );
    let bed_scene = |k: u32| {
        let mut s = scene.clone();
        s.simulation.seed = bed_seed(scene.simulation.seed, k);
        s.simulation.step_threads = step_threads;
        s
    };
    let bed_setup = |k: u32| ShakeSetup {
        noise_seed: bed_seed(setup.noise_seed, k),
        ..setup.clone()
    };
    let run_bed = |k: u32,
                   observers: &mut [&mut dyn StepObserver],
                   progress: &mut dyn FnMut(Progress)|
     -> Result<ShakeRun, SceneError> {
        judge.start_stepping();
        let mut guard = GiveUpOnDrop {
            judge: &judge,
            bed: k as usize,
            armed: true,
        };
        let s = bed_scene(k);
        let result = source.bed(&s, k, progress).and_then(|bed| {
            run_shake_on_bed_judged(
                &s,
                &bed,
                &bed_setup(k),
                observers,
                progress,
                (&judge, k as usize),
            )
        });
        if let Err(e) = &result {
            judge.give_up(format!("bed {} (seed {}): {e}", k + 1, s.simulation.seed));
        }
        guard.armed = false;
        result
    };
    let (first, others) = std::thread::scope(|scope| {
        let handles: Vec<_> = (1..beds)
            .map(|k| {
                let run_bed = &run_bed;
                scope.spawn(move || run_bed(k, &mut [], &mut |_| {}))
            })
            .collect();
        let first = run_bed(0, observers, progress);
        let others: Vec<Result<ShakeRun, SceneError>> = handles
            .into_iter()
            .map(|h| {
                h.join()
                    .unwrap_or_else(|_| Err(SceneError::Ensemble("a bed's thread panicked".into())))
            })
            .collect();
        (first, others)
    });
    // The first error that is not another bed giving up is the one to tell.
    let mut all = vec![first];
    all.extend(others);
    if all.iter().any(Result::is_err) {
        let errors: Vec<SceneError> = all.into_iter().filter_map(Result::err).collect();
        let own = errors
            .iter()
            .position(|e| !matches!(e, SceneError::Ensemble(_)))
            .unwrap_or(0);
        return Err(errors
            .into_iter()
            .nth(own)
            .unwrap_or(SceneError::Ensemble("a bed failed".into())));
    }
    let mut runs: Vec<ShakeRun> = all.into_iter().flatten().collect();
    let summary = summarise(&runs, &judge, started.elapsed().as_secs_f64(), threads);
    let mut first = runs.remove(0);
    if beds > 1 {
        first.summary.warnings.extend(ensemble_warnings(&summary));
        first.summary.ensemble = Some(summary);
    }
    Ok(EnsembleRun {
        first,
        others: runs,
    })
}

/// The ensemble's figures from its beds' runs.
///
/// Over 80 lines: the ensemble's figures filled field by field, each from the
/// beds' runs and the ones before it.
fn summarise(
    runs: &[ShakeRun],
    judge: &EnsembleJudge,
    wall_time_s: f64,
    threads: usize,
) -> EnsembleSummary {
    let particle_steps: f64 = runs
        .iter()
        .map(|r| r.summary.n_particles as f64 * r.summary.steps as f64)
        .sum();
    let rows: Vec<BedRow> = runs
        .iter()
        .enumerate()
        .map(|(k, r)| {
            let s = &r.summary;
            BedRow {
                bed: k as u32 + 1,
                seed: s.seed,
                dem_energy_per_cycle_j: s.dem.energy_per_cycle_j,
                dem_window_stderr_j: s.dem.energy_per_cycle_stderr_j,
                dem_efficiency: s.dem.efficiency,
                measured_energy_per_cycle_j: s.measured.energy_per_cycle_j,
                measured_stderr_j: s.measured.energy_per_cycle_stderr_j,
                measured_efficiency: s.measured.efficiency,
                alternates: s.dem.steadiness.alternates,
                drift_rel: s.dem.steadiness.drift_rel,
                drift_stderr_rel: s.dem.steadiness.drift_stderr_rel,
            }
        })
        .collect();
    // Each figure with its beds' own window errors (an efficiency's is its
    // energy's, scaled alike).
    let first = &runs[0].summary;
    let window_cycles = first.steady_cycles;
    let col = |f: fn(&BedRow) -> f64, err: fn(&BedRow) -> Option<f64>| {
        let values: Vec<f64> = rows.iter().map(f).collect();
        let errors: Vec<Option<f64>> = rows.iter().map(err).collect();
        EnsembleFigure::of(&values, &errors, window_cycles)
    };
    fn scaled(e: Option<f64>, figure: f64, energy: f64) -> Option<f64> {
        e.map(|e| {
            if energy == 0.0 {
                0.0
            } else {
                e * (figure / energy).abs()
            }
        })
    }
    let steadiness = judge
        .final_verdict()
        .map_or(first.dem.steadiness, |v| v.steadiness);
    EnsembleSummary {
        beds: runs.len(),
        dem_energy_per_cycle_j: col(|r| r.dem_energy_per_cycle_j, |r| r.dem_window_stderr_j),
        dem_efficiency: col(
            |r| r.dem_efficiency,
            |r| {
                scaled(
                    r.dem_window_stderr_j,
                    r.dem_efficiency,
                    r.dem_energy_per_cycle_j,
                )
            },
        ),
        measured_energy_per_cycle_j: col(
            |r| r.measured_energy_per_cycle_j,
            |r| r.measured_stderr_j,
        ),
        measured_efficiency: col(
            |r| r.measured_efficiency,
            |r| {
                scaled(
                    r.measured_stderr_j,
                    r.measured_efficiency,
                    r.measured_energy_per_cycle_j,
                )
            },
        ),
        steadiness,
        cycles: first.cycles,
        steady_first_cycle: first.dem.steady_first_cycle,
        wall_time_s,
        threads,
        particle_steps_per_s: particle_steps / wall_time_s.max(f64::MIN_POSITIVE),
        drive_particle_steps_per_s: particle_steps
            / runs
                .iter()
                .map(|r| r.summary.wall_time_s)
                .fold(f64::MIN_POSITIVE, f64::max),
        rows,
    }
}

/// What a user must be told of an ensemble: a window the rule could not
/// show stationary.
fn ensemble_warnings(e: &EnsembleSummary) -> Vec<crate::warning::RunWarning> {
    let s = &e.steadiness;
    let mut w = Vec::new();
    if s.capped {
        w.push(crate::warning::RunWarning::advising(
            format!(
                "the {} beds were driven to the cap of {} cycles without a window shown stationary: {}; the ensemble's figures are those of beds still changing",
                e.beds,
                e.cycles,
                unsteady_reasons(s, e.steady_first_cycle)
            ),
            crate::warning::FileKey("drive.max_cycles"),
        ));
    }
    w
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Beds share the threads without taking more than there are: one bed
    /// takes them all, more beds than threads one each, fewer a share.
    #[test]
    fn beds_share_the_threads_and_never_take_more() {
        assert_eq!(thread_shares(2, 1), (1, 2));
        assert_eq!(thread_shares(2, 6), (2, 1));
        assert_eq!(thread_shares(8, 2), (2, 4));
        assert_eq!(thread_shares(0, 0), (1, 1));
        for threads in 1..=16 {
            for beds in 1..=20 {
                let (at_once, each) = thread_shares(threads, beds);
                assert!(at_once * each <= threads, "{threads} threads, {beds} beds");
                assert!(at_once >= 1 && each >= 1 && at_once <= beds as usize);
            }
        }
    }

    #[test]
    fn the_first_bed_is_the_seeds_own_and_ensembles_of_nearby_seeds_share_none() {
        assert_eq!(bed_seed(7, 0), 7);
        assert_eq!(bed_seed(7, 3), 3_000_007);
        let a: Vec<u64> = (0..8).map(|k| bed_seed(1, k)).collect();
        let b: Vec<u64> = (0..8).map(|k| bed_seed(2, k)).collect();
        assert!(a.iter().all(|s| !b.contains(s)));
        assert!(check_beds(0).is_err() && check_beds(MAX_BEDS + 1).is_err());
        let said = check_beds(0).expect_err("0 beds").to_string();
        assert!(said.contains("beds") && said.contains("1 to 64"), "{said}");
    }
}
