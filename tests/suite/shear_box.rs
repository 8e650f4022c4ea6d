//! The quasi-static compression and shear test of Terzioglu's thesis
//! (Section 8.5.1.2, Fig. 8.15): walls that move on their own book their
//! work, the bed's forces balance, the table holds its pre-load, and a box
//! the bed does not fill is refused.

use crate::common;

use common::{Scratch, refuses_in, vlab};
use vlab::experiment::bed::settle::settle_bed;
use vlab::experiment::shear_box::{BoxRun, BoxTest, Loading, ShearBox, run_test};
use vlab::scene::Scene;

/// 100 spheres of 7.6 mm (the thesis' Chapter 8 spheres) in the box.
fn box_scene() -> Scene {
    let mut s = Scene::thesis();
    s.particles.diameter_m = 0.0076;
    ShearBox::THESIS.scene(&s, 100)
}

fn run(test: BoxTest, travel_m: f64) -> BoxRun {
    let scene = box_scene();
    let bed = settle_bed(&scene, &mut |_| {}).expect("the box's bed settles");
    let loading = Loading {
        preload_n: test.thesis_preload_n(),
        speed_mps: 0.005,
        travel_m,
        points: 20,
    };
    run_test(&bed, &scene, &ShearBox::THESIS, test, loading, &mut |_| {}).expect("the test runs")
}

/// Shearing moves the upper ring and the table on their own, across and
/// up and down. Their work on the bed (their own forces on their own
/// strokes, booked by the step) must equal what the contacts dissipated
/// plus the change of the bed's kinetic, potential and elastic energy,
/// read from the state: three independent sums. Leaving the walls' own
/// work out of the books leaves the dissipation (0.05 J here) unpaid and
/// fails by far more than the 1e-3 allowed. The table holds its 50 N
/// within 10 % at every point, and the bed resists: the fixed container
/// is pushed the way the upper one moves.
#[test]
fn a_shear_test_books_the_work_of_the_walls_that_move_and_holds_its_load() {
    let run = run(BoxTest::Shear, 0.001);
    let residual = run.work_in_j - run.dissipated_j - run.energy_change_j;
    assert!(run.work_in_j > 0.0 && run.dissipated_j > 0.0, "{run:?}");
    assert!(
        residual.abs() < 1e-3 * run.work_in_j,
        "work {} J, dissipated {} J, energy change {} J: residual {residual} J",
        run.work_in_j,
        run.dissipated_j,
        run.energy_change_j
    );
    for p in &run.points {
        assert!(
            (p.table_load_n - 50.0).abs() < 5.0,
            "the table let its load go to {} N at x = {} m",
            p.table_load_n,
            p.displacement_m
        );
    }
    let mean = run.points.iter().map(|p| p.force_n).sum::<f64>() / run.points.len() as f64;
    assert!(mean > 5.0, "mean shear force {mean} N");
    assert!(run.preload_displacement_m > 0.0);
}

/// Pressed slowly, the bed is in equilibrium: the table's load and the
/// bed's weight are carried by the base and by the rings' friction (the
/// Janssen effect), each averaged over a point's stretch, to 3 % of the
/// load. A force booked to the wrong wall (the table's to a ring, say)
/// breaks the balance. The load rises as the table goes deeper.
#[test]
fn a_normal_test_balances_the_tables_load_with_the_base_and_the_rings() {
    let run = run(BoxTest::Normal, 0.0002);
    for p in &run.points {
        let imbalance = p.table_load_n + run.weight_n - p.force_n - p.rings_up_n;
        assert!(
            imbalance.abs() < 0.03 * p.table_load_n,
            "at z = {} m: table {} N + weight {} N against base {} N + rings {} N",
            p.displacement_m,
            p.table_load_n,
            run.weight_n,
            p.force_n,
            p.rings_up_n
        );
    }
    let (first, last) = (run.points[0], run.points[run.points.len() - 1]);
    assert!(
        last.force_n > 2.0 * first.force_n,
        "{} N at first, {} N at the end",
        first.force_n,
        last.force_n
    );
    assert!(first.table_load_n > 9.0, "{first:?}");
}

/// Too few particles to reach the upper container: refused, naming the
/// height and the key to change; nothing written.
#[test]
fn a_bed_that_does_not_reach_the_upper_container_is_refused() {
    let dir = Scratch::new("shear-box-low");
    refuses_in(
        &dir,
        &[
            "-q",
            "shear-box",
            "--count",
            "20",
            "--no-cache",
            "--out",
            "box",
        ],
        &["upper container", "particles.count"],
    );
    assert!(!dir.path("box").exists());
}

/// A short normal test of the default spheres in `dir`, with `more` flags.
fn quick_normal_test(dir: &Scratch, more: &[&str]) -> std::process::Output {
    let mut args = vec![
        "-q",
        "shear-box",
        "--test",
        "normal",
        "--normal-travel-m",
        "0.0001",
        "--points",
        "10",
    ];
    args.extend_from_slice(more);
    vlab(dir.path("").as_path(), &args)
}

/// The command writes a curve per test, the summary and the plots, and
/// `vlab plot` redraws the plots from the summary.
#[test]
fn the_command_writes_its_curves_summary_and_plots() {
    let dir = Scratch::new("shear-box-cli");
    let out = quick_normal_test(&dir, &["--out", "box"]);
    assert!(out.status.success(), "{}", common::stderr(&out));
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains("normal test"), "{text}");
    let csv = std::fs::read_to_string(dir.path("box/spheres-7.6mm/normal.csv")).expect("curve");
    assert!(
        csv.contains("z_test_m,f_test_z_n,table_load_n,rings_up_n"),
        "{csv}"
    );
    assert_eq!(csv.lines().filter(|l| !l.starts_with('#')).count(), 11);
    for f in ["shear_box.json", "normal.svg", "normal.png"] {
        assert!(dir.path("box").join(f).exists(), "{f}");
    }
    // Over two beds: a folder per seed, and the mean force with its
    // standard error.
    let out = quick_normal_test(&dir, &["--seeds", "1,2", "--out", "seeds"]);
    assert!(out.status.success(), "{}", common::stderr(&out));
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.contains(" +- "), "{text}");
    for seed in ["seed-1", "seed-2"] {
        assert!(
            dir.path("seeds/spheres-7.6mm")
                .join(seed)
                .join("normal.csv")
                .is_file(),
            "{seed}"
        );
    }
    // The summary holds every run to the bit: `vlab plot` redraws the
    // plots of two beds from it, byte for byte.
    let out = vlab(
        dir.path("").as_path(),
        &["plot", "seeds/shear_box.json", "--out", "redrawn"],
    );
    assert!(out.status.success(), "{}", common::stderr(&out));
    for f in ["normal.svg", "normal.png"] {
        let ran = std::fs::read(dir.path("seeds").join(f)).expect("the run's plot");
        let redrawn = std::fs::read(dir.path("redrawn").join(f)).expect("the redrawn plot");
        assert!(ran == redrawn, "{f} redrawn from shear_box.json differs");
    }
    // A JSON file that is not a shear box's summary is refused by name.
    std::fs::write(dir.path("other.json"), "{\"a\": 1}\n").expect("write");
    let out = vlab(dir.path("").as_path(), &["plot", "other.json"]);
    assert!(!out.status.success());
    assert!(
        common::stderr(&out).contains("shear_box.json"),
        "{}",
        common::stderr(&out)
    );
}
