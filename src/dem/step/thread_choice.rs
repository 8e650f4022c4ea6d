//! Whether a step runs on one core or on all threads, decided by timing
//! both.
//!
//! Both ways give the same bits ([`super::forces`]), so the choice is only
//! about speed, and the machine, its load and the bed decide it: a small bed
//! loses more to handing its blocks to the [`super::team::Team`] three times
//! a step than it gains (the thesis bed of 358 spheres is one block and
//! never splits), a poured bed of 5 000 spheres gains most of a second core,
//! and a sweep whose other beds hold the cores gains nothing. So a world that can split its
//! step (several threads, several blocks) times it both ways, in runs of
//! [`RUN_STEPS`] steps taken in turn ([`TRIAL_RUNS`] of them, parallel
//! first), keeps the way of the fastest run for [`KEEP_STEPS`] steps, and
//! tries again, so that it follows a bed that settles or a machine whose
//! load changes. Runs, not single steps in turn: a team that sat idle
//! through serial steps has gone to sleep ([`super::team::PARK_AFTER`]) and
//! wakes slowly, which a parallel step run alone pays and a run of them
//! does not. Nobody has a key to tune; `vlab bench` shows
//! the result.

use std::time::Duration;

/// Steps of a run of a trial, all one way.
pub const RUN_STEPS: u32 = 16;
/// Runs of a trial, parallel and serial in turn.
pub const TRIAL_RUNS: usize = 4;
/// Steps of a whole trial.
pub const TRIAL_STEPS: u64 = RUN_STEPS as u64 * TRIAL_RUNS as u64;
/// Steps run the chosen way between trials.
pub const KEEP_STEPS: u64 = 4000;

/// The choice between the serial and the parallel step, and the trial that
/// makes it.
#[derive(Debug, Clone, Default)]
pub struct ThreadChoice {
    /// The way steps run between trials.
    parallel: bool,
    /// Steps left before the next trial.
    until_trial: u64,
    /// The trial under way: the times of its finished runs (in turn,
    /// parallel first), and of the steps of the run under way.
    runs: Vec<Duration>,
    run: Duration,
    run_steps: u32,
}

impl ThreadChoice {
    /// Whether the next step runs on all threads, when it `can_split`
    /// (several threads, several blocks); `forced`: always, when it can
    /// (tests run the parallel path on small beds).
    pub fn pick(&mut self, can_split: bool, forced: bool) -> bool {
        if !can_split {
            self.until_trial = 0;
            self.runs.clear();
            self.run = Duration::ZERO;
            self.run_steps = 0;
            return false;
        }
        if forced {
            return true;
        }
        if self.until_trial > 0 {
            return self.parallel;
        }
        // A trial: runs parallel and serial in turn.
        self.runs.len() % 2 == 0
    }

    /// Books the time a step took, and ends a trial once its runs are
    /// done: the way of the fastest run wins.
    pub fn record(&mut self, took: Duration) {
        if self.until_trial > 0 {
            self.until_trial -= 1;
            return;
        }
        self.run += took;
        self.run_steps += 1;
        if self.run_steps < RUN_STEPS {
            return;
        }
        self.runs.push(self.run);
        self.run = Duration::ZERO;
        self.run_steps = 0;
        if self.runs.len() == TRIAL_RUNS {
            let fastest = |first: usize| self.runs.iter().skip(first).step_by(2).min().copied();
            self.parallel = fastest(0) < fastest(1);
            self.runs.clear();
            self.until_trial = KEEP_STEPS;
        }
    }

    /// The way steps run now (between trials).
    pub fn parallel(&self) -> bool {
        self.parallel
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Runs `steps` steps whose serial and parallel times are given, and
    /// returns how many ran parallel.
    fn run(choice: &mut ThreadChoice, steps: u64, serial_us: u64, parallel_us: u64) -> u64 {
        let mut split = 0;
        for _ in 0..steps {
            let p = choice.pick(true, false);
            split += u64::from(p);
            let us = if p { parallel_us } else { serial_us };
            choice.record(Duration::from_micros(us));
        }
        split
    }

    /// The faster way wins the trial and is kept until the next, and a
    /// change of speeds is followed at the next trial. A choice of the
    /// slower way (a comparison turned round) fails it.
    #[test]
    fn the_faster_way_is_kept_until_the_next_trial() {
        let mut c = ThreadChoice::default();
        let trial = TRIAL_STEPS;
        let n = trial + KEEP_STEPS;
        // Parallel faster: all but the trial's serial runs run parallel.
        let split = run(&mut c, n, 300, 200);
        assert!(c.parallel());
        assert_eq!(split, n - trial / 2);
        // The bed changed: parallel now slower, and the next trial sees it.
        let split = run(&mut c, n, 100, 150);
        assert!(!c.parallel());
        assert_eq!(split, trial / 2);
    }

    /// One thread or one block: never parallel, and no trial runs.
    #[test]
    fn a_step_that_cannot_split_runs_serial() {
        let mut c = ThreadChoice::default();
        for _ in 0..100 {
            assert!(!c.pick(false, false));
            assert!(!c.pick(false, true));
        }
        assert!(c.pick(true, true), "forced");
    }
}
