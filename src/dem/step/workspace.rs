//! What a world's step works with but is not the world's state: the
//! buffers it keeps from step to step, the team of threads it may split
//! its blocks across, and the timing that decides whether it does.
//!
//! A world clones its state and starts a clone with a new workspace of the
//! same thread count (buffers are refilled by the first step, the team's
//! helpers start at its first parallel phase, the timing starts over): the
//! clone steps to the same bits, as every step does whatever its threads.

use super::forces::ForceScratch;
use super::integrate::KickSums;
use super::neighbour_update::OrderScratch;
use super::team::Team;
use super::thread_choice::ThreadChoice;

/// Buffers, threads and the serial/parallel choice of a world's step.
#[derive(Debug, Default)]
pub struct StepWorkspace {
    /// Per particle block: what its half kick found.
    pub kick_sums: Vec<KickSums>,
    /// The force stage's books and pair slots.
    pub forces: ForceScratch,
    /// The renumbering's keys and order.
    pub order: OrderScratch,
    /// The threads a parallel step runs its blocks on.
    pub team: Team,
    /// Whether steps run on one core or on the team, by timing both.
    pub choice: ThreadChoice,
}

impl StepWorkspace {
    /// A workspace whose step may use `threads` threads, the caller's
    /// included (1: every step on the caller).
    pub fn new(threads: usize) -> Self {
        StepWorkspace {
            team: Team::new(threads),
            ..StepWorkspace::default()
        }
    }

    /// Threads a step may use, the caller's included.
    pub fn threads(&self) -> usize {
        self.team.threads()
    }
}

impl Clone for StepWorkspace {
    /// A new workspace of the same thread count: nothing in it is state.
    fn clone(&self) -> Self {
        StepWorkspace::new(self.threads())
    }
}
