//! `vlab accuracy --quick` end to end: the three studies in a tidy CSV, the
//! collision error falling with steps per contact at the order measured, the
//! plots and the summary; and a refusal that writes nothing.

#![cfg(all(feature = "cli", feature = "plot"))]

mod common;

use std::collections::BTreeMap;

use common::{Scratch, json, refuses_in, stderr, vlab};

/// A 60-sphere bed in the thesis enclosure: the same physics, a sixth of the
/// cost, so the quick run takes seconds.
const SMALL_SCENE: &str = "[particles]\ncount = 60\n";

#[test]
fn quick_accuracy_writes_three_studies_and_the_collision_converges() {
    let dir = Scratch::new("accuracy");
    dir.write("small.toml", SMALL_SCENE);
    let out = vlab(
        &dir.0,
        &[
            "accuracy",
            "--quick",
            "--scene",
            "small.toml",
            "--out",
            "acc",
        ],
    );
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(
        stderr(&out).contains("settling one bed per seed"),
        "progress on stderr"
    );
    for f in [
        "accuracy.csv",
        "summary.json",
        "accuracy.svg",
        "impact.svg",
        "yang.svg",
    ] {
        let p = dir.path("acc").join(f);
        assert!(p.is_file(), "{} missing", p.display());
    }

    let text = std::fs::read_to_string(dir.path("acc/accuracy.csv")).expect("csv");
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().expect("header").split(',').collect();
    assert_eq!(
        header,
        [
            "study",
            "parameter",
            "value",
            "quantity",
            "estimate",
            "reference",
            "error_rel",
            "stderr_rel",
            "wall_s",
            "note"
        ]
    );
    let col = |name: &str| header.iter().position(|h| *h == name).expect("column");
    let rows: Vec<Vec<&str>> = lines.map(|l| l.splitn(10, ',').collect()).collect();
    let studies: std::collections::BTreeSet<&str> = rows.iter().map(|r| r[0]).collect();
    assert_eq!(
        studies.into_iter().collect::<Vec<_>>(),
        ["dem", "impact", "yang"]
    );
    // Every row records its wall-clock time.
    for r in &rows {
        let wall: f64 = r[col("wall_s")].parse().expect("wall_s is a number");
        assert!(wall >= 0.0 && wall.is_finite(), "{r:?}");
    }
    // The DEM study varies the time step, the seeds and the cycles.
    for parameter in ["dt_over_rayleigh", "seed", "steady_cycles"] {
        assert!(
            rows.iter().any(|r| r[0] == "dem" && r[1] == parameter),
            "no dem row for {parameter}"
        );
    }

    // Collision: |error| against steps per contact for each quantity.
    let mut errors: BTreeMap<&str, Vec<(f64, f64)>> = BTreeMap::new();
    for r in rows.iter().filter(|r| r[0] == "impact") {
        let n: f64 = r[col("value")].parse().expect("steps");
        let e: f64 = r[col("error_rel")].parse().expect("error");
        errors
            .entry(r[col("quantity")])
            .or_default()
            .push((n, e.abs()));
    }
    // Measured: the overlap against eq. 5.8 and the duration against the
    // exact Hertz integral converge at second order (slopes 2.02), the
    // damped restitution at order 1.5. Asserted with 0.3 of slack.
    let order = |q: &str| -> f64 {
        let pts = &errors[q];
        let (x0, e0) = pts[0];
        let (x1, e1) = pts[pts.len() - 1];
        assert!(e1 < e0, "{q}: error does not fall: {pts:?}");
        -(e1 / e0).ln() / (x1 / x0).ln()
    };
    let overlap = order("max_overlap_m");
    assert!(overlap > 1.7, "overlap order {overlap}");
    let duration = order("contact_duration_exact_s");
    assert!(duration > 1.7, "duration order {duration}");
    let restitution = order("restitution");
    assert!(restitution > 1.2, "restitution order {restitution}");
    // Against eq. 5.10 itself the duration stops at its rounded constant:
    // 6e-4 (Terzioglu 2023, eq. 5.10: 1.435 against 1.4341 exact).
    let floor = errors["contact_duration_s"].last().expect("rows").1;
    assert!((floor - 6.0e-4).abs() < 1.0e-4, "eq. 5.10 floor {floor}");

    let s = json(&dir.path("acc/summary.json"));
    assert_eq!(s["quick"], true);
    assert_eq!(s["n_particles"], 60);
    assert!(s["dem"]["seed_spread_rel"].as_f64().is_some());
    assert!(s["dem"]["dominant"].as_str().is_some_and(|d| !d.is_empty()));
    assert!(s["impact"]["order_max_overlap"].as_f64().is_some());
    let chain = s["yang"]["baseline_error_vs_work_rel"]
        .as_f64()
        .expect("chain error");
    // The chain alone, against the enclosure's work over the same cycles,
    // is within a few percent on this small bed (measured -0.7 %).
    assert!(chain.abs() < 0.03, "Yang chain error {chain}");
    let files = s["files"].as_array().expect("files");
    assert!(files.iter().any(|f| f == "accuracy.svg"));
}

#[test]
fn accuracy_refuses_a_bad_drive_and_writes_nothing() {
    let dir = Scratch::new("accuracy-refuse");
    refuses_in(
        &dir,
        &["accuracy", "--quick", "--freq", "0", "--out", "never"],
        &["--freq"],
    );
    assert!(!dir.path("never").exists());
}
