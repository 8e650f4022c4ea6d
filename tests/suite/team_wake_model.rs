//! The step team's wake protocol (`src/dem/step/wake.rs`, issue 35) over
//! every interleaving of a caller handing out a phase and a helper going to
//! sleep, under `loom`: the file is included as it is, with loom's atomics,
//! mutex and condition variable in place of std's. A helper that sleeps
//! through the phase it waits for (a lost wake-up) leaves both threads
//! blocked, which loom reports as a deadlock; the planted test shows that it
//! does, with the caller looking at the sleepers before it moves the epoch
//! (run in a process of its own: loom aborts on it).

use loom::sync::Arc;
use loom::sync::atomic::Ordering;
use loom::thread;

/// The primitives `wake.rs` is written against: loom's.
mod sync {
    pub use loom::sync::atomic::{AtomicBool, AtomicU64, AtomicUsize, Ordering};
    pub use loom::sync::{Condvar, Mutex};
}

#[path = "../../src/dem/step/wake.rs"]
#[allow(dead_code)]
mod wake;

use wake::{Bell, Look};

/// Every interleaving of a helper that has seen no phase and gives up
/// spinning (it looks once, then sleeps) with a caller that hands out phase
/// 1 by `ring`: the helper must come back with phase 1.
fn helper_finds_the_phase(ring: fn(&Bell, u64)) {
    loom::model(move || {
        let bell = Arc::new(Bell::default());
        let b = Arc::clone(&bell);
        let helper = thread::spawn(move || match b.look(0) {
            Look::Nothing => b.sleep(0),
            found => found,
        });
        ring(&bell, 1);
        assert_eq!(helper.join().expect("the helper"), Look::Phase(1));
    });
}

#[test]
fn a_sleeping_helper_always_wakes_for_the_next_phase() {
    helper_finds_the_phase(Bell::ring);
}

#[test]
fn a_sleeping_helper_always_wakes_when_the_team_stops() {
    loom::model(|| {
        let bell = Arc::new(Bell::default());
        let b = Arc::clone(&bell);
        let helper = thread::spawn(move || match b.look(0) {
            Look::Nothing => b.sleep(0),
            found => found,
        });
        bell.stop();
        assert_eq!(helper.join().expect("the helper"), Look::Quit);
    });
}

/// The planted lost wake-up: the caller reads the sleepers before it moves
/// the epoch, so a helper that counts itself asleep and looks at the epoch
/// between the two sleeps through the phase.
fn ring_looking_first(bell: &Bell, epoch: u64) {
    let asleep = bell.sleeping.fetch_add(0, Ordering::SeqCst) > 0;
    bell.epoch.store(epoch, Ordering::SeqCst);
    if asleep {
        drop(bell.lock.lock().expect("the lock"));
        bell.wake.notify_all();
    }
}

/// Set in the process this test starts to run the planted model, which
/// loom aborts (its deadlock panic panics again while it unwinds), so it
/// cannot be caught in the test's own process.
const RUN_PLANTED: &str = "VLAB_WAKE_MODEL_RUN_PLANTED";

#[test]
fn the_model_finds_a_planted_lost_wake_up() {
    if std::env::var_os(RUN_PLANTED).is_some() {
        helper_finds_the_phase(ring_looking_first);
        return;
    }
    let exe = std::env::current_exe().expect("the test binary");
    // The test's name as the harness knows it: its module path in the
    // suite (tests/suite/main.rs), without the crate's name.
    let module = module_path!()
        .split_once("::")
        .map_or(module_path!(), |(_, m)| m);
    let name = format!("{module}::the_model_finds_a_planted_lost_wake_up");
    let out = std::process::Command::new(exe)
        .args(["--exact", &name, "--nocapture"])
        .env(RUN_PLANTED, "1")
        .env("RUST_BACKTRACE", "0")
        .output()
        .expect("the planted model runs");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success(),
        "loom found no lost wake-up in the planted bug"
    );
    assert!(
        stderr.contains("deadlock; threads"),
        "the planted model failed, but not on a deadlock:\n{stderr}"
    );
}
