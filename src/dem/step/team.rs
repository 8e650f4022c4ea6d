//! The threads that run a step's blocks side by side: a team that stays
//! awake between the step's parallel phases.
//!
//! A step has three parallel phases (the first half kick and drift, the
//! forces, the second half kick) with 20-50 µs of serial work between them
//! on a 5 000-sphere bed. Run as rayon joins, each phase found the other
//! worker asleep (rayon lets an idle worker sleep after a few dozen rounds of
//! looking for work, and waking it cost 28-46 µs on the 2-core VM, more than
//! its share of a phase; `examples/fork_join_latency.rs` measures it). A
//! [`Team`] keeps its helpers waiting by spinning, then by yielding the core
//! to anything else that wants it, and only after [`PARK_AFTER`] without
//! work by sleeping, so a bed whose steps follow each other hands out a
//! phase in about a microsecond, and a world that has gone serial (or a sweep
//! whose other beds want the cores) does not keep a core busy.
//!
//! Which thread runs which block does not matter for the results: every
//! block writes only what it owns and its sums are added in block order
//! afterwards ([`super::block_size`]). The caller takes blocks one at a time
//! from the front of the bed and the first helper from the back until they
//! meet: a thread that finishes early takes more, and each thread runs
//! about the same lump of the bed phase after phase, which its own core's
//! cache still holds (driven 5 000-sphere bed on two threads: 5 % faster
//! than blocks taken in turn from one counter).
//!
//! The helpers are started at the first parallel phase, as many as the
//! current rayon pool has threads, less the caller, which works too.

use std::any::Any;
use std::panic::{AssertUnwindSafe, catch_unwind, resume_unwind};
use std::sync::atomic::{AtomicBool, AtomicPtr, AtomicU64, AtomicUsize, Ordering};
use std::sync::{Arc, Condvar, Mutex, PoisonError};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// How long a helper goes on looking for work, spinning and then yielding,
/// before it sleeps until woken.
pub const PARK_AFTER: Duration = Duration::from_millis(2);

/// Spins before a waiting thread starts to yield the core instead (a spin
/// is one `pause`, 14-17 ns on the 2-core VM: about 3 µs in all; after that
/// a look costs a system call, about a microsecond when nothing else wants
/// the core, and gives the core away when something does).
const SPINS_BEFORE_YIELD: u32 = 200;

/// A persistent team of helper threads for the blocks of a step.
///
/// Cloning gives a team that has started no threads yet; dropping one stops
/// and joins its helpers.
#[derive(Default)]
pub struct Team {
    crew: Option<Crew>,
}

/// The helpers of a started team and what they share with the caller.
struct Crew {
    shared: Arc<Shared>,
    helpers: Vec<JoinHandle<()>>,
}

/// What the caller and the helpers share.
#[derive(Default)]
struct Shared {
    /// Counts the phases handed out (the first is 1); a helper that sees it
    /// change looks for the phase at `job`.
    epoch: AtomicU64,
    /// The phase under way, on the caller's stack until the caller has
    /// closed it and `inside` is zero.
    job: AtomicPtr<Job<'static>>,
    /// The epoch of the phase helpers may still join; 0 once the caller has
    /// taken the last block and closed it.
    open: AtomicU64,
    /// Helpers between asking to join a phase and leaving it.
    inside: AtomicUsize,
    /// Helpers asleep, waiting for `wake`.
    sleeping: AtomicUsize,
    quit: AtomicBool,
    lock: Mutex<()>,
    wake: Condvar,
}

/// One phase: `count` blocks, each run by `run(index)` exactly once.
struct Job<'a> {
    /// Blocks taken from the front (high 32 bits) and from the back (low
    /// 32 bits); they meet when their sum reaches `count`.
    ends: AtomicU64,
    count: usize,
    run: &'a (dyn Fn(usize) + Sync),
    /// What a block that panicked on a helper panicked with.
    panic: Mutex<Option<Box<dyn Any + Send>>>,
}

impl Job<'_> {
    /// Takes blocks, from the front or from the back, and runs them until
    /// none is left. The caller takes from the front and the first helper
    /// from the back, so that each thread runs the same lump of the bed
    /// phase after phase and step after step, and finds its particles in
    /// its own core's cache.
    fn work(&self, from_back: bool) {
        while let Some(i) = self.take(from_back) {
            (self.run)(i);
        }
    }

    /// The next block from one end, if any is left.
    fn take(&self, from_back: bool) -> Option<usize> {
        let one = if from_back { 1 } else { 1 << 32 };
        let mut ends = self.ends.load(Ordering::Relaxed);
        loop {
            let (front, back) = ((ends >> 32) as usize, (ends & 0xffff_ffff) as usize);
            if front + back >= self.count {
                return None;
            }
            match self.ends.compare_exchange_weak(
                ends,
                ends + one,
                Ordering::Relaxed,
                Ordering::Relaxed,
            ) {
                Ok(_) => {
                    return Some(if from_back {
                        self.count - 1 - back
                    } else {
                        front
                    });
                }
                Err(now) => ends = now,
            }
        }
    }
}

impl Clone for Team {
    fn clone(&self) -> Self {
        Team::default()
    }
}

impl std::fmt::Debug for Team {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Team")
            .field("threads", &self.threads())
            .finish()
    }
}

impl Team {
    /// Threads the team runs blocks on, the caller included (1 until its
    /// helpers have started).
    pub fn threads(&self) -> usize {
        self.crew.as_ref().map_or(1, |c| c.helpers.len() + 1)
    }

    /// Runs `f` on every item, on the caller and the helpers side by side,
    /// each item once, and returns when all are done. Starts (or restarts)
    /// the helpers so that the team has as many threads as the current rayon
    /// pool; where threads cannot be started the items run on the caller. A
    /// panic in `f` is raised again here once every thread has stopped.
    pub fn for_each<T: Send>(&mut self, items: impl IntoIterator<Item = T>, f: impl Fn(T) + Sync) {
        let slots: Vec<Mutex<Option<T>>> = items.into_iter().map(|t| Mutex::new(Some(t))).collect();
        let run = |i: usize| {
            let item = slots[i]
                .lock()
                .unwrap_or_else(PoisonError::into_inner)
                .take();
            if let Some(item) = item {
                f(item);
            }
        };
        match self.crew_for(rayon::current_num_threads()) {
            Some(crew) if slots.len() > 1 => crew.run(slots.len(), &run),
            _ => (0..slots.len()).for_each(run),
        }
    }

    /// The crew of `threads` threads, started if need be.
    fn crew_for(&mut self, threads: usize) -> Option<&Crew> {
        if threads < 2 {
            return None;
        }
        if self.threads() != threads {
            self.crew = None;
            self.crew = Crew::start(threads - 1);
        }
        self.crew.as_ref()
    }
}

/// Runs `f` on every item: on `team`'s threads, or one after the other on
/// the caller when there is none.
pub fn for_each_block<T: Send>(
    team: Option<&mut Team>,
    items: impl IntoIterator<Item = T>,
    f: impl Fn(T) + Sync,
) {
    match team {
        Some(team) => team.for_each(items, f),
        None => items.into_iter().for_each(f),
    }
}

impl Crew {
    /// Starts `helpers` helper threads; `None` if one could not be started.
    fn start(helpers: usize) -> Option<Crew> {
        let shared = Arc::new(Shared::default());
        let mut crew = Crew {
            shared,
            helpers: Vec::with_capacity(helpers),
        };
        for k in 0..helpers {
            let shared = Arc::clone(&crew.shared);
            let handle = std::thread::Builder::new()
                .name(format!("vlab-step-{}", k + 1))
                .spawn(move || help(&shared, k == 0))
                .ok()?;
            crew.helpers.push(handle);
        }
        Some(crew)
    }

    /// Runs the `count` blocks of `run` on the caller and every helper.
    fn run(&self, count: usize, run: &(dyn Fn(usize) + Sync)) {
        let job = Job {
            ends: AtomicU64::new(0),
            count,
            run,
            panic: Mutex::new(None),
        };
        assert!(
            u32::try_from(count).is_ok(),
            "{count} blocks: more than a phase can count"
        );
        let s = &*self.shared;
        // SAFETY: a helper reads `job` only after it has counted itself
        // `inside` and then found this phase still `open`, and it leaves
        // `inside` once done with it; `Finish` (also when the caller's own
        // blocks panic) closes the phase and then waits until `inside` is
        // zero, so a helper either sees the phase closed and never reads
        // `job`, or is waited for (both sides use sequentially consistent
        // operations). So `job` and what `run` borrows outlive every use;
        // the lifetime is erased only to put the pointer where the helpers
        // can see it.
        let ptr = (&job as *const Job<'_>).cast_mut().cast::<Job<'static>>();
        // Closes the phase however this function is left, from before the
        // phase is open.
        let finish = Finish(s);
        s.job.store(ptr, Ordering::SeqCst);
        let epoch = s.epoch.load(Ordering::SeqCst) + 1;
        s.open.store(epoch, Ordering::SeqCst);
        s.epoch.store(epoch, Ordering::SeqCst);
        if s.sleeping.load(Ordering::SeqCst) > 0 {
            drop(s.lock.lock().unwrap_or_else(PoisonError::into_inner));
            s.wake.notify_all();
        }
        job.work(false);
        drop(finish);
        let panic = job
            .panic
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .take();
        if let Some(payload) = panic {
            resume_unwind(payload);
        }
    }
}

/// Closes the phase under way when dropped, and waits until no helper is
/// in it. A helper that has not joined by then never will: the caller does
/// not wait for a helper the scheduler has not run, it has taken the blocks
/// itself.
struct Finish<'a>(&'a Shared);

impl Drop for Finish<'_> {
    fn drop(&mut self) {
        self.0.open.store(0, Ordering::SeqCst);
        wait_until(|| self.0.inside.load(Ordering::SeqCst) == 0);
    }
}

/// Spins until `done`, then yields the core between looks.
fn wait_until(done: impl Fn() -> bool) {
    let mut spins = 0u32;
    while !done() {
        if spins < SPINS_BEFORE_YIELD {
            spins += 1;
            std::hint::spin_loop();
        } else {
            std::thread::yield_now();
        }
    }
}

impl Drop for Crew {
    fn drop(&mut self) {
        let s = &*self.shared;
        s.quit.store(true, Ordering::SeqCst);
        drop(s.lock.lock().unwrap_or_else(PoisonError::into_inner));
        s.wake.notify_all();
        for h in self.helpers.drain(..) {
            // A helper's panics are caught and reported by `run`; nothing
            // is left to report here.
            let _ = h.join();
        }
    }
}

/// A helper's life: wait for a phase, run blocks of it (`from_back`: the
/// first helper takes them from the back), repeat.
fn help(s: &Shared, from_back: bool) {
    // The crew is new, its epoch 0: read at the thread's start, it could
    // already be a phase this helper should join.
    let mut seen = 0;
    loop {
        let Some(epoch) = next_epoch(s, seen) else {
            return;
        };
        seen = epoch;
        s.inside.fetch_add(1, Ordering::SeqCst);
        if s.open.load(Ordering::SeqCst) == epoch {
            // SAFETY: see `Crew::run`: the phase was open after this
            // helper counted itself inside, so the caller waits for it.
            let job = unsafe { &*s.job.load(Ordering::SeqCst) };
            if let Err(payload) = catch_unwind(AssertUnwindSafe(|| job.work(from_back))) {
                // Kept for the caller to raise: dropped here, a payload
                // whose drop panicked would kill this helper inside.
                let mut first = job.panic.lock().unwrap_or_else(PoisonError::into_inner);
                first.get_or_insert(payload);
            }
        }
        s.inside.fetch_sub(1, Ordering::SeqCst);
    }
}

/// Waits for an epoch other than `seen`: spinning, then yielding, then,
/// after [`PARK_AFTER`], asleep. `None` when the team stops.
fn next_epoch(s: &Shared, seen: u64) -> Option<u64> {
    let started = Instant::now();
    let mut spins = 0u32;
    loop {
        if s.quit.load(Ordering::Acquire) {
            return None;
        }
        let epoch = s.epoch.load(Ordering::Acquire);
        if epoch != seen {
            return Some(epoch);
        }
        if spins < SPINS_BEFORE_YIELD {
            spins += 1;
            std::hint::spin_loop();
            continue;
        }
        if started.elapsed() < PARK_AFTER {
            std::thread::yield_now();
            continue;
        }
        // Asleep until the caller hands out a phase (it looks at `sleeping`
        // after it moves the epoch, we at the epoch after we count ourselves
        // asleep, so one of us sees the other) or the team stops.
        let guard = s.lock.lock().unwrap_or_else(PoisonError::into_inner);
        s.sleeping.fetch_add(1, Ordering::SeqCst);
        let guard = s
            .wake
            .wait_while(guard, |_| {
                s.epoch.load(Ordering::SeqCst) == seen && !s.quit.load(Ordering::SeqCst)
            })
            .unwrap_or_else(PoisonError::into_inner);
        s.sleeping.fetch_sub(1, Ordering::SeqCst);
        drop(guard);
        spins = 0;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn in_pool<R: Send>(threads: usize, f: impl FnOnce() -> R + Send) -> R {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("a pool")
            .install(f)
    }

    /// Every item is run exactly once, on more than one thread when the
    /// pool has several, and the team is reused from phase to phase.
    #[test]
    fn every_item_runs_once_across_the_threads() {
        in_pool(3, || {
            let mut team = Team::default();
            for round in 0..200usize {
                let mut out = vec![0usize; 37];
                let names = Mutex::new(std::collections::BTreeSet::new());
                team.for_each(out.iter_mut().enumerate(), |(i, o)| {
                    *o += i * round + 1;
                    let name = std::thread::current().name().map(str::to_owned);
                    names.lock().unwrap().insert(name);
                    std::thread::sleep(Duration::from_micros(20));
                });
                let want: Vec<usize> = (0..37).map(|i| i * round + 1).collect();
                assert_eq!(out, want, "round {round}");
                if round == 199 {
                    assert!(names.lock().unwrap().len() > 1, "one thread did it all");
                }
            }
            assert_eq!(team.threads(), 3);
        });
    }

    /// A helper that has gone to sleep is woken by the next phase.
    #[test]
    fn a_sleeping_helper_wakes_for_the_next_phase() {
        in_pool(2, || {
            let mut team = Team::default();
            let mut hits = [0u8; 4];
            team.for_each(hits.iter_mut(), |h| *h += 1);
            std::thread::sleep(PARK_AFTER * 5);
            team.for_each(hits.iter_mut(), |h| *h += 1);
            assert_eq!(hits, [2; 4]);
        });
    }

    /// One thread in the pool: everything on the caller, no helper started.
    #[test]
    fn one_thread_runs_on_the_caller() {
        in_pool(1, || {
            let mut team = Team::default();
            let caller = std::thread::current().id();
            team.for_each(0..8, |_| assert_eq!(std::thread::current().id(), caller));
            assert_eq!(team.threads(), 1);
        });
    }

    /// A panic in a block reaches the caller with its own message, from the
    /// caller's blocks and from a helper's, and the team still works.
    #[test]
    fn a_panicking_block_panics_the_caller() {
        in_pool(2, || {
            let mut team = Team::default();
            let text = |p: &Box<dyn Any + Send>| {
                let s = p.downcast_ref::<&str>().map(|s| s.to_string());
                s.or_else(|| p.downcast_ref::<String>().cloned())
            };
            let message = |r: std::thread::Result<()>| text(&r.expect_err("the phase panicked"));
            let r = catch_unwind(AssertUnwindSafe(|| {
                team.for_each(0..16, |i| assert!(i != 0, "block 0"));
            }));
            assert_eq!(message(r).as_deref(), Some("block 0"));
            // A helper's: only a helper panics, so retry until one has
            // joined a phase (it takes the first block from the back).
            let on_helper = (0..50).find_map(|_| {
                catch_unwind(AssertUnwindSafe(|| {
                    team.for_each(0..16, |_| {
                        std::thread::sleep(Duration::from_micros(50));
                        let name = std::thread::current().name().map(str::to_owned);
                        let helper = name.is_some_and(|n| n.starts_with("vlab-step"));
                        assert!(!helper, "a helper's block");
                    });
                }))
                .err()
            });
            let payload = on_helper.expect("a helper joined one of 50 phases");
            assert_eq!(text(&payload).as_deref(), Some("a helper's block"));
            let mut n = AtomicUsize::new(0);
            team.for_each(0..16, |_| {
                n.fetch_add(1, Ordering::Relaxed);
            });
            assert_eq!(*n.get_mut(), 16);
        });
    }

    /// Runs `f` on its own thread and fails if it has not finished within
    /// `limit`: a lost wake-up hangs instead of failing.
    fn within(limit: Duration, f: impl FnOnce() + Send + 'static) {
        let (tx, rx) = std::sync::mpsc::channel();
        std::thread::spawn(move || {
            f();
            let _ = tx.send(());
        });
        assert!(
            rx.recv_timeout(limit).is_ok(),
            "a phase did not finish within {limit:?}"
        );
    }

    /// New teams whose first phase comes before their helper has started,
    /// and phases after gaps on both sides of [`PARK_AFTER`] (spinning,
    /// yielding, asleep): every phase finishes with every item run once. (A
    /// first version waited for every helper to finish every phase; a
    /// helper that read the epoch when it started, not 0, missed its first
    /// phase and hung here.)
    #[test]
    fn no_phase_is_lost_however_the_gaps_fall() {
        within(Duration::from_secs(60), || {
            in_pool(2, || {
                for _ in 0..300 {
                    let mut team = Team::default();
                    let mut v = [0u8; 4];
                    team.for_each(v.iter_mut(), |h| *h += 1);
                    assert_eq!(v, [1; 4]);
                }
                let mut team = Team::default();
                let mut x = 0x2545_f491_4f6c_dd1d_u64;
                for _ in 0..1500 {
                    x ^= x << 13;
                    x ^= x >> 7;
                    x ^= x << 17;
                    let gap = Duration::from_micros(x % (3 * PARK_AFTER.as_micros() as u64));
                    let t = Instant::now();
                    while t.elapsed() < gap {
                        std::hint::spin_loop();
                    }
                    let mut v = [0u8; 10];
                    team.for_each(v.iter_mut(), |h| *h += 1);
                    assert_eq!(v, [1; 10]);
                }
            })
        });
    }

    /// The two ends take blocks from the front and from the back until they
    /// meet: every block once, the front's from 0 up, the back's from the
    /// last down.
    #[test]
    fn the_two_ends_take_every_block_once() {
        let run = |_: usize| {};
        let job = Job {
            ends: AtomicU64::new(0),
            count: 7,
            run: &run,
            panic: Mutex::new(None),
        };
        let mut front = Vec::new();
        let mut back = Vec::new();
        for k in 0..10 {
            let from_back = k % 3 == 0;
            match job.take(from_back) {
                Some(i) if from_back => back.push(i),
                Some(i) => front.push(i),
                None => {}
            }
        }
        assert_eq!(front, [0, 1, 2, 3]);
        assert_eq!(back, [6, 5, 4]);
        assert_eq!(job.take(false), None);
        assert_eq!(job.take(true), None);
    }
}
