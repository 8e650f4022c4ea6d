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
//! A team runs on as many threads as it is given ([`Team::new`]), the
//! caller's included: whoever runs worlds side by side gives each its share
//! of the cores, so that N beds on P cores keep P threads busy, not N × P.
//! The helpers are started at the first parallel phase. How a phase is
//! handed out and how a helper sleeps and is woken is [`super::wake`].

use std::any::Any;
use std::panic::{AssertUnwindSafe, catch_unwind, resume_unwind};
use std::sync::atomic::{AtomicPtr, AtomicU64, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex, PoisonError};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use crossbeam_utils::CachePadded;

use super::wake::{Bell, Look};

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
/// Dropping one stops and joins its helpers.
pub struct Team {
    /// Threads the team runs blocks on, the caller's included.
    threads: usize,
    crew: Option<Crew>,
}

impl Default for Team {
    /// A team of one thread: the caller.
    fn default() -> Self {
        Team::new(1)
    }
}

/// The helpers of a started team and what they share with the caller.
struct Crew {
    shared: Arc<Shared>,
    helpers: Vec<JoinHandle<()>>,
}

/// What the caller and the helpers share. The words the caller writes
/// every phase and the helpers read (the bell's epoch, `open`, `inside`)
/// each have a cache line of their own.
#[derive(Default)]
struct Shared {
    /// The epoch of the phases handed out (the first is 1); a helper that
    /// sees it change looks for the phase at `job`.
    bell: Bell,
    /// The phase under way, on the caller's stack until the caller has
    /// closed it and `inside` is zero.
    job: AtomicPtr<Job<'static>>,
    /// The epoch of the phase helpers may still join; 0 once the caller has
    /// taken the last block and closed it.
    open: CachePadded<AtomicU64>,
    /// Helpers between asking to join a phase and leaving it.
    inside: CachePadded<AtomicUsize>,
}

/// One phase: `count` blocks, each run by one call of `run(from_back)`,
/// which takes the next block from that end of the phase's items.
struct Job<'a> {
    /// Blocks taken from the front (high 32 bits) and from the back (low
    /// 32 bits); they meet when their sum reaches `count`. Every thread
    /// takes from it, so it has a cache line of its own.
    ends: CachePadded<AtomicU64>,
    count: usize,
    run: &'a (dyn Fn(bool) + Sync),
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
        while self.take(from_back).is_some() {
            (self.run)(from_back);
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

impl std::fmt::Debug for Team {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Team")
            .field("threads", &self.threads())
            .finish()
    }
}

impl Team {
    /// A team of `threads` threads, the caller's included (at least 1); its
    /// helpers start at its first phase of several blocks.
    pub fn new(threads: usize) -> Self {
        Team {
            threads: threads.max(1),
            crew: None,
        }
    }

    /// Threads the team runs blocks on, the caller's included.
    pub fn threads(&self) -> usize {
        self.threads
    }

    /// Helper threads started so far (none before the first phase of
    /// several blocks, and none for a team of one).
    pub fn helpers_started(&self) -> usize {
        self.crew.as_ref().map_or(0, |c| c.helpers.len())
    }

    /// Runs `f` on every item, on the caller and the helpers side by side,
    /// each item once, and returns when all are done. The items are handed
    /// out from both ends of `items`, which stays where it is (on the
    /// caller's stack, behind a lock taken once a block): the caller takes
    /// from the front, the first helper from the back, so a phase allocates
    /// nothing. `items` must be as long as it says. Starts the helpers at
    /// the first phase; where threads cannot be started the items run on
    /// the caller. A panic in `f` is raised again here once every thread
    /// has stopped.
    pub fn for_each<I>(&mut self, items: I, f: impl Fn(I::Item) + Sync)
    where
        I: DoubleEndedIterator + ExactSizeIterator + Send,
        I::Item: Send,
    {
        let count = items.len();
        let crew = match count {
            0 | 1 => None,
            _ => self.crew(),
        };
        let Some(crew) = crew else {
            return items.for_each(f);
        };
        let items = Mutex::new(items);
        let run = |from_back: bool| {
            let item = {
                let mut items = items.lock().unwrap_or_else(PoisonError::into_inner);
                if from_back {
                    items.next_back()
                } else {
                    items.next()
                }
            };
            if let Some(item) = item {
                f(item);
            }
        };
        crew.run(count, &run);
        debug_assert!(
            items
                .into_inner()
                .unwrap_or_else(PoisonError::into_inner)
                .next()
                .is_none(),
            "the items were longer than they said"
        );
    }

    /// The crew of the team's helpers, started if need be; `None` for a
    /// team of one, or where threads cannot be started.
    fn crew(&mut self) -> Option<&Crew> {
        if self.threads < 2 {
            return None;
        }
        if self.crew.is_none() {
            self.crew = Crew::start(self.threads - 1);
        }
        self.crew.as_ref()
    }
}

/// Runs `f` on every item: on `team`'s threads, or one after the other on
/// the caller when there is none.
pub fn for_each_block<I>(team: Option<&mut Team>, items: I, f: impl Fn(I::Item) + Sync)
where
    I: DoubleEndedIterator + ExactSizeIterator + Send,
    I::Item: Send,
{
    match team {
        Some(team) => team.for_each(items, f),
        None => items.for_each(f),
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
    fn run(&self, count: usize, run: &(dyn Fn(bool) + Sync)) {
        let job = Job {
            ends: CachePadded::new(AtomicU64::new(0)),
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
        let epoch = s.bell.epoch() + 1;
        s.open.store(epoch, Ordering::SeqCst);
        s.bell.ring(epoch);
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
        self.shared.bell.stop();
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
/// after [`PARK_AFTER`], asleep ([`Bell::sleep`]). `None` when the team
/// stops.
fn next_epoch(s: &Shared, seen: u64) -> Option<u64> {
    let started = Instant::now();
    let mut spins = 0u32;
    loop {
        match s.bell.look(seen) {
            Look::Quit => return None,
            Look::Phase(epoch) => return Some(epoch),
            Look::Nothing => {}
        }
        if spins < SPINS_BEFORE_YIELD {
            spins += 1;
            std::hint::spin_loop();
        } else if started.elapsed() < PARK_AFTER {
            std::thread::yield_now();
        } else {
            return match s.bell.sleep(seen) {
                Look::Phase(epoch) => Some(epoch),
                _ => None,
            };
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Fewer rounds under Miri, which runs a thousand times slower.
    fn rounds(native: usize, miri: usize) -> usize {
        if cfg!(miri) { miri } else { native }
    }

    /// Every item is run exactly once, on more than one thread when the
    /// team has several, and the team is reused from phase to phase.
    #[test]
    fn every_item_runs_once_across_the_threads() {
        let mut team = Team::new(3);
        let n = rounds(200, 6);
        let names = Mutex::new(std::collections::BTreeSet::new());
        for round in 0..n {
            let mut out = vec![0usize; 37];
            team.for_each(out.iter_mut().enumerate(), |(i, o)| {
                *o += i * round + 1;
                let name = std::thread::current().name().map(str::to_owned);
                names.lock().unwrap().insert(name);
                std::thread::sleep(Duration::from_micros(20));
            });
            let want: Vec<usize> = (0..37).map(|i| i * round + 1).collect();
            assert_eq!(out, want, "round {round}");
        }
        assert!(names.lock().unwrap().len() > 1, "one thread did it all");
        assert_eq!((team.threads(), team.helpers_started()), (3, 2));
    }

    /// A helper that has gone to sleep is woken by the next phase.
    #[test]
    fn a_sleeping_helper_wakes_for_the_next_phase() {
        let mut team = Team::new(2);
        let mut hits = [0u8; 4];
        team.for_each(hits.iter_mut(), |h| *h += 1);
        std::thread::sleep(PARK_AFTER * 5);
        team.for_each(hits.iter_mut(), |h| *h += 1);
        assert_eq!(hits, [2; 4]);
    }

    /// A team of one: everything on the caller, no helper started.
    #[test]
    fn a_team_of_one_runs_on_the_caller() {
        let mut team = Team::default();
        let caller = std::thread::current().id();
        team.for_each(0..8, |_| assert_eq!(std::thread::current().id(), caller));
        assert_eq!((team.threads(), team.helpers_started()), (1, 0));
    }

    /// A panic in a block reaches the caller with its own message, from the
    /// caller's blocks and from a helper's, and the team still works.
    #[test]
    fn a_panicking_block_panics_the_caller() {
        let mut team = Team::new(2);
        let text = |p: &Box<dyn Any + Send>| {
            let s = p.downcast_ref::<&str>().map(|s| s.to_string());
            s.or_else(|| p.downcast_ref::<String>().cloned())
        };
        let message = |r: std::thread::Result<()>| text(&r.expect_err("the phase panicked"));
        let r = catch_unwind(AssertUnwindSafe(|| {
            team.for_each(0..16, |i| assert!(i != 0, "block 0"));
        }));
        assert_eq!(message(r).as_deref(), Some("block 0"));
        // A helper's: only a helper panics, so retry until one has joined a
        // phase (it takes the first block from the back).
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
    /// phase and hung here.) Every interleaving of the sleep and the wake
    /// is the model test's (`tests/suite/team_wake_model.rs`).
    #[test]
    fn no_phase_is_lost_however_the_gaps_fall() {
        let (teams, phases) = (rounds(300, 3), rounds(1500, 8));
        within(
            Duration::from_secs(if cfg!(miri) { 3600 } else { 60 }),
            move || {
                for _ in 0..teams {
                    let mut team = Team::new(2);
                    let mut v = [0u8; 4];
                    team.for_each(v.iter_mut(), |h| *h += 1);
                    assert_eq!(v, [1; 4]);
                }
                let mut team = Team::new(2);
                let mut x = 0x2545_f491_4f6c_dd1d_u64;
                for _ in 0..phases {
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
            },
        );
    }

    /// The two ends take blocks from the front and from the back until they
    /// meet: every block once, the front's from 0 up, the back's from the
    /// last down.
    #[test]
    fn the_two_ends_take_every_block_once() {
        let run = |_: bool| {};
        let job = Job {
            ends: CachePadded::new(AtomicU64::new(0)),
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

    /// The words the caller writes every phase and the helpers read lie on
    /// cache lines of their own (a helper's look at the epoch does not stall
    /// the caller's count of who is inside).
    #[test]
    fn the_hot_words_have_cache_lines_of_their_own() {
        let s = Shared::default();
        let line = |p: *const u8| p as usize / 64;
        let epoch = line((&*s.bell.epoch as *const AtomicU64).cast());
        let open = line((&*s.open as *const AtomicU64).cast());
        let inside = line((&*s.inside as *const AtomicUsize).cast());
        let sleeping = line((&*s.bell.sleeping as *const AtomicUsize).cast());
        let all = std::collections::BTreeSet::from([epoch, open, inside, sleeping]);
        assert_eq!(all.len(), 4, "epoch, open, inside, sleeping share a line");
    }
}
