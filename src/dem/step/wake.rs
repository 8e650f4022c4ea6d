//! How a [`super::team::Team`]'s caller hands out a phase and how a helper
//! that has waited too long sleeps until it does: the one place in the team
//! where a lost wake-up could hang a step.
//!
//! The caller publishes the phase's epoch and then wakes the helpers if any
//! is asleep; a helper counts itself asleep under the lock and then looks at
//! the epoch before it waits. Either the caller's look at the sleepers comes
//! after the helper counted itself (and the caller takes the lock, which the
//! helper holds until it waits, and wakes it), or before, and then the
//! helper's look at the epoch sees the new one. The caller reads the
//! sleepers with a read-modify-write, which reads the latest count whatever
//! the orderings: the argument holds with acquire and release alone, which
//! is what the model test (`tests/suite/team_wake_model.rs`, every interleaving
//! of a caller and a sleeping helper under `loom`) checks. That test
//! includes this file as it is, with `loom`'s primitives in place of std's
//! (the `sync` module beside it), so this file uses nothing else of vlab.

use super::sync::{AtomicBool, AtomicU64, AtomicUsize, Condvar, Mutex, Ordering};
use crossbeam_utils::CachePadded;

/// The epoch of the phases handed out, and the bell that wakes sleeping
/// helpers when it moves.
#[derive(Default)]
pub struct Bell {
    /// Counts the phases handed out (the first is 1). Read by every
    /// waiting helper, so on a cache line of its own.
    pub(super) epoch: CachePadded<AtomicU64>,
    /// Helpers asleep, waiting for `wake`.
    pub(super) sleeping: CachePadded<AtomicUsize>,
    /// The team is stopping: every helper returns.
    pub(super) quit: AtomicBool,
    pub(super) lock: Mutex<()>,
    pub(super) wake: Condvar,
}

/// What a helper found when it looked.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Look {
    /// The team is stopping.
    Quit,
    /// A phase other than the one the helper has seen: this epoch.
    Phase(u64),
    /// Nothing new.
    Nothing,
}

impl Bell {
    /// The epoch of the last phase handed out (0 before the first).
    pub fn epoch(&self) -> u64 {
        self.epoch.load(Ordering::Acquire)
    }

    /// What a helper that has seen phase `seen` finds now.
    pub fn look(&self, seen: u64) -> Look {
        if self.quit.load(Ordering::Acquire) {
            return Look::Quit;
        }
        match self.epoch.load(Ordering::Acquire) {
            e if e != seen => Look::Phase(e),
            _ => Look::Nothing,
        }
    }

    /// Hands out phase `epoch` (what it is must be published before) and
    /// wakes every sleeping helper.
    pub fn ring(&self, epoch: u64) {
        self.epoch.store(epoch, Ordering::SeqCst);
        // A read-modify-write reads the latest count: a helper that counted
        // itself asleep before it is seen here; one that counts itself
        // after will see the epoch stored above.
        if self.sleeping.fetch_add(0, Ordering::SeqCst) > 0 {
            drop(self.lock.lock().unwrap_or_else(|p| p.into_inner()));
            self.wake.notify_all();
        }
    }

    /// Sleeps until a phase other than `seen` is handed out or the team
    /// stops, then says which.
    pub fn sleep(&self, seen: u64) -> Look {
        let mut guard = self.lock.lock().unwrap_or_else(|p| p.into_inner());
        self.sleeping.fetch_add(1, Ordering::SeqCst);
        let found = loop {
            match self.look(seen) {
                Look::Nothing => {
                    guard = self.wake.wait(guard).unwrap_or_else(|p| p.into_inner());
                }
                found => break found,
            }
        };
        self.sleeping.fetch_sub(1, Ordering::SeqCst);
        drop(guard);
        found
    }

    /// Stops the team: every helper, asleep or not, finds [`Look::Quit`].
    pub fn stop(&self) {
        self.quit.store(true, Ordering::SeqCst);
        drop(self.lock.lock().unwrap_or_else(|p| p.into_inner()));
        self.wake.notify_all();
    }
}
