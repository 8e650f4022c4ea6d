//! The step's wider loops (x86-64-v3, [`vlab::dem::isa`]) give the
//! baseline's bits: a lattice bed, with friction and without, of one block
//! and of several, stepped the same way with each, every particle's state
//! and the books compared bit for bit. On a processor without x86-64-v3
//! both runs take the baseline and the test compares nothing; under CI it
//! fails there instead, saying so.

use vlab::dem::World;
use vlab::dem::isa;
use vlab::dem::testbed::lattice_bed;

use crate::support::fingerprint;
use fingerprint::fingerprint;

/// `steps` steps of the lattice bed of `n` spheres, the walls moving so
/// that they do work, on the wider loops or the baseline's.
fn run(n: usize, friction: f64, steps: u32, baseline: bool) -> World {
    isa::set_baseline_only(baseline);
    assert_eq!(isa::wide(), !baseline && wide_processor());
    let mut w = lattice_bed(n, friction, 7).expect("bed");
    for k in 0..steps {
        w.step(2e-6 * (f64::from(k) * 0.02).sin()).expect("step");
    }
    w
}

fn wide_processor() -> bool {
    isa::set_baseline_only(false);
    isa::wide()
}

#[test]
fn the_wider_loops_give_the_baselines_bits() {
    if !wide_processor() {
        assert!(
            std::env::var_os("CI").is_none(),
            "this processor has no x86-64-v3: nothing to compare the baseline with"
        );
        eprintln!("skipped: this processor has no x86-64-v3, both runs would be the baseline");
        return;
    }
    for (n, friction) in [(400, 0.52), (400, 0.0), (3000, 0.52)] {
        let wide = run(n, friction, 400, false);
        let base = run(n, friction, 400, true);
        let (fw, bw) = fingerprint(&wide);
        let (fb, bb) = fingerprint(&base);
        let differ = fw.iter().zip(&fb).filter(|(x, y)| x != y).count();
        assert_eq!(
            differ, 0,
            "{n} spheres, mu {friction}: {differ} numbers differ"
        );
        assert_eq!(bw, bb, "{n} spheres, mu {friction}: the books differ");
        assert!(wide.ledger.dissipated.total() > 0.0, "nothing touched");
    }
    isa::set_baseline_only(false);
}
