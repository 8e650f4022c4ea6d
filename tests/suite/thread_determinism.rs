//! The same scene and seed give the same bits whatever the number of threads
//! (issue 10, item 4): a bed large enough for vlab to split the step across
//! threads, run on a pool of one thread (the serial path) and of two (the
//! parallel path), and a small bed of three blocks forced onto the parallel
//! path. And a bed renumbered in space as it moves gives the same bits as
//! the same bed read back in id order (issue 21, item 1).

use vlab::dem::testbed::lattice_bed;
use vlab::dem::{AUTO_PARALLEL_MIN_PAIRS, World};

use crate::support::fingerprint;
use fingerprint::fingerprint;

/// `steps` steps of the lattice bed of `n` spheres on `threads` threads, the
/// walls moving a little so that they do work.
fn run(threads: usize, n: usize, friction: f64, steps: u32, force_parallel: bool) -> World {
    let mut w = lattice_bed(n, friction, 7).expect("bed");
    w.set_step_threads(threads);
    if force_parallel {
        w.numerics.parallel_min_pairs = 0;
    }
    for k in 0..steps {
        w.step(2e-6 * (f64::from(k) * 0.02).sin()).expect("step");
    }
    if force_parallel {
        assert_eq!(w.step_helpers_started(), threads - 1, "the team ran");
    }
    w
}

fn assert_same(a: &World, b: &World) {
    let (fa, ba) = fingerprint(a);
    let (fb, bb) = fingerprint(b);
    let differ = fa.iter().zip(&fb).filter(|(x, y)| x != y).count();
    assert_eq!(differ, 0, "{differ} numbers differ");
    assert_eq!(ba, bb);
}

#[test]
fn one_and_two_threads_give_the_same_bits_on_a_bed_that_goes_parallel() {
    for friction in [0.52, 0.0] {
        let one = run(1, 3000, friction, 300, false);
        assert!(
            one.listed_pairs() >= AUTO_PARALLEL_MIN_PAIRS,
            "{} pairs: too few to go parallel",
            one.listed_pairs()
        );
        let two = run(2, 3000, friction, 300, false);
        assert_same(&one, &two);
        assert!(one.ledger.dissipated.total() > 0.0);
        // Collisions were counted, so their minima were merged across blocks.
        assert!(one.fastest_collision.is_some());
    }
}

#[test]
fn the_parallel_path_gives_the_serial_bits_on_a_small_bed() {
    // 1 300 spheres: three blocks of the step, far fewer pairs than vlab
    // splits a step for.
    let serial = run(1, 1300, 0.52, 400, false);
    assert!(serial.listed_pairs() < AUTO_PARALLEL_MIN_PAIRS);
    let parallel = run(2, 1300, 0.52, 400, true);
    assert_same(&serial, &parallel);
    assert!(serial.fastest_collision.is_some());
    let three = run(3, 1300, 0.52, 400, true);
    assert_same(&serial, &three);
}

/// A bed whose arrays the steps renumbered in space drives to the same bits
/// as the same bed read back in id order (what the bed cache and every file
/// hold) and built anew: the renumbering is a function of the positions and
/// ids alone. A tie broken by the arrays' order, or an array the
/// renumbering forgot (a mass left behind its sphere), fails it.
#[test]
fn a_bed_read_back_in_id_order_drives_to_the_same_bits() {
    {
        let mut moved = run(1, 3000, 0.52, 300, false);
        assert!(!moved.particles.in_id_order(), "the bed was renumbered");
        let mut read_back = World::new(
            moved.particles.by_id().into_owned(),
            moved.walls.clone(),
            moved.pp_law,
            moved.pw_law,
            moved.gravity,
            moved.numerics,
        )
        .expect("world");
        // As a drive starts: every contact detected anew, the books from zero.
        moved
            .set_contact_laws(moved.pp_law, moved.pw_law)
            .expect("laws");
        for w in [&mut moved, &mut read_back] {
            w.start_ledger();
            for k in 0..300 {
                w.step(2e-6 * (f64::from(k) * 0.02).sin()).expect("step");
            }
        }
        assert_eq!(moved.particles.id, read_back.particles.id);
        assert_same(&moved, &read_back);
        assert!(moved.ledger.dissipated.total() > 0.0);
    }
}

/// A world steps on the threads it is given, not on those of the pool it
/// steps in (issue 35): given one, a bed of three blocks forced onto the
/// parallel path starts no helper inside a pool of four, so that beds a
/// sweep runs side by side on the pool's threads add none of their own;
/// given three, it starts two.
#[test]
fn a_world_steps_on_the_threads_it_is_given_not_the_pools() {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(4)
        .build()
        .expect("thread pool");
    pool.install(|| {
        for (threads, helpers) in [(1, 0), (3, 2)] {
            let mut w = lattice_bed(1300, 0.52, 7).expect("bed");
            w.numerics.parallel_min_pairs = 0;
            w.set_step_threads(threads);
            for _ in 0..20 {
                w.step(0.0).expect("step");
            }
            assert_eq!(w.step_helpers_started(), helpers, "{threads} threads");
            assert_eq!(w.splits_across_threads(), threads > 1);
            // A copy steps on as many, with a team of its own.
            let copy = w.clone();
            assert_eq!(
                (copy.step_threads(), copy.step_helpers_started()),
                (threads, 0)
            );
        }
    });
}

/// A bed of bodies whose multi-point contacts are shared
/// (`contact.multi_point = "shared"`) gives the same bits on one thread and
/// on two: 30 prolates of 1.5 (51 sub-spheres each, three blocks of the
/// step) lying side by side in rows on the base, pressed together a little
/// and thrown, forced onto the parallel path. The counts are taken on the
/// caller in integers, and each block reads its own; a block reading
/// another's counts, or counts left from the step before, differs. The
/// shared bed also differs from the same bed with independent contacts,
/// so the counts were used.
#[test]
fn a_bed_of_bodies_sharing_its_contacts_gives_the_same_bits_on_one_and_two_threads() {
    use glam::{DQuat, DVec3};
    use vlab::dem::contact::MultiPoint;
    use vlab::dem::{ContactLaw, Material, Numerics, Particles, RestitutionMode, Walls};

    let body = crate::support::prolate::prolate15();
    let b = body.b_m;
    let half_length = body.template.bounding_radius_m();
    let run = |threads: usize, multi_point: MultiPoint| {
        let mut p = Particles::default();
        for k in 0..30 {
            let (row, column) = ((k / 6) as f64 - 2.0, (k % 6) as f64 - 2.5);
            // Along x, 1 % closer than touching across, resting on the base.
            let x = DVec3::new(row * 2.2 * half_length, column * 1.98 * b, 0.999 * b);
            let spin = 0.2 * (k as f64 * 0.7).sin();
            let v = DVec3::new(spin, -spin, 0.1 * (k as f64 * 1.3).cos());
            p.push_clump(&body.template, (x, DQuat::IDENTITY), (v, DVec3::ZERO));
        }
        let m = Material::ACRYLIC;
        let law = ContactLaw::new(&m, &m, 0.86, 0.52, RestitutionMode::Exact)
            .with_multi_point(multi_point);
        let mut numerics = Numerics::with_dt(2e-8);
        numerics.parallel_min_pairs = 0;
        numerics.skin_ratio = 0.05;
        let mut w = World::new(
            p,
            Walls::closed_cylinder(0.04, 0.02),
            law,
            law,
            DVec3::new(0.0, 0.0, -9.81),
            numerics,
        )
        .expect("world");
        w.set_step_threads(threads);
        for k in 0..400 {
            w.step(2e-7 * (f64::from(k) * 0.02).sin()).expect("step");
        }
        w
    };
    let one = run(1, MultiPoint::Shared);
    assert!(one.particles.len() > 1024, "three blocks");
    let two = run(2, MultiPoint::Shared);
    assert_eq!(two.step_helpers_started(), 1, "the team ran");
    assert_same(&one, &two);
    assert!(one.ledger.dissipated.total() > 0.0);
    let independent = run(1, MultiPoint::Independent);
    let (fa, _) = fingerprint(&one);
    let (fb, _) = fingerprint(&independent);
    assert_ne!(fa, fb, "sharing changed nothing");
}
