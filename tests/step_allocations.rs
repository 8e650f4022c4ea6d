//! A step allocates nothing once its buffers have grown, on one thread and
//! on a team (issue 35: the blocks of a parallel phase are handed out from
//! both ends of their iterator, not from a list built for each phase; a
//! rebuild renumbers the bed in place). Every allocation of the process is
//! counted while a bed of three blocks steps, and while a bed is renumbered.

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

use vlab::dem::ordering::Renumbering;
use vlab::dem::testbed::lattice_bed;

/// The system allocator, counting while `COUNTING` is set.
struct Counting;

static COUNTING: AtomicBool = AtomicBool::new(false);
static ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        if COUNTING.load(Ordering::Relaxed) {
            ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        }
        // SAFETY: passed on unchanged.
        unsafe { System.alloc(layout) }
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        // SAFETY: passed on unchanged.
        unsafe { System.dealloc(ptr, layout) }
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        if COUNTING.load(Ordering::Relaxed) {
            ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        }
        // SAFETY: passed on unchanged.
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

/// Counts the allocations `f` makes.
fn counted(f: impl FnOnce()) -> usize {
    ALLOCATIONS.store(0, Ordering::SeqCst);
    COUNTING.store(true, Ordering::SeqCst);
    f();
    COUNTING.store(false, Ordering::SeqCst);
    ALLOCATIONS.load(Ordering::SeqCst)
}

/// Allocations made by `steps` steps of the lattice bed of 1 300 spheres
/// (three blocks, dissipation booked per particle) on `threads` threads,
/// forced onto the parallel path, after 300 steps that let its buffers
/// grow. (A bed shaken hard enough to rebuild its list keeps growing its
/// buffers as it packs: the renumbering at a rebuild is counted apart.)
fn allocations(threads: usize, steps: u32) -> usize {
    let mut w = lattice_bed(1300, 0.52, 7).expect("bed");
    w.set_step_threads(threads);
    w.numerics.parallel_min_pairs = 0;
    w.track_particle_dissipation(true);
    let wall = |k: u32| 2e-6 * (f64::from(k) * 0.02).sin();
    for k in 0..300 {
        w.step(wall(k)).expect("step");
    }
    let n = counted(|| {
        for k in 300..300 + steps {
            w.step(wall(k)).expect("step");
        }
    });
    assert_eq!(w.step_helpers_started(), threads - 1);
    assert!(w.ledger.dissipated.total() > 0.0, "no contact was booked");
    n
}

#[test]
fn a_step_allocates_nothing_on_one_thread_or_on_a_team() {
    // One test, so that no other test's allocations are counted.
    for threads in [1, 2, 3] {
        let n = allocations(threads, 400);
        assert_eq!(n, 0, "{threads} thread(s): {n} allocations in 400 steps");
    }
    // A rebuild's renumbering in space moves every array in place by the
    // cycles found once (it made a new array for each before).
    let w = lattice_bed(1300, 0.52, 7).expect("bed");
    let mut p = w.particles.clone();
    let order: Vec<u32> = (0..p.len() as u32).rev().collect();
    let mut cycles = Renumbering::default();
    cycles.find(&order);
    let n = counted(|| p.renumber_by(&cycles, &order));
    assert_eq!(n, 0, "renumbering: {n} allocations");
    assert_eq!(p.position[0], w.particles.position[p.len() - 1]);
}
