//! `vlab accuracy --quick` end to end: the three studies in a tidy CSV, the
//! collision error falling with steps per contact at the order measured, the
//! plots and the summary; and a refusal that writes nothing.

#![cfg(all(feature = "cli", feature = "plot"))]

use crate::common;

use std::collections::BTreeMap;

use common::{Scratch, json, refuses_in, stderr, vlab};

/// The standard output of a run, as text.
fn stdout(o: &std::process::Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

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
        "accuracy.png",
        "yang.png",
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
    let yang: Vec<&Vec<&str>> = rows
        .iter()
        .filter(|r| r[0] == "yang" && r[1] == "record_periods")
        .collect();
    let summary_text = std::fs::read_to_string(dir.path("acc/summary.json")).expect("summary");
    chain_leads_then_unsteadiness_then_their_sum(&yang, &col, (&s, &summary_text), &stdout(&out));
    let chain = s["yang"]["baseline_error_vs_work_rel"]
        .as_f64()
        .expect("chain error");
    // The chain alone, against the enclosure's work over the same cycles,
    // is within a few percent on this small bed (measured -0.7 %).
    assert!(chain.abs() < 0.03, "Yang chain error {chain}");
    let files = s["files"].as_array().expect("files");
    assert!(files.iter().any(|f| f == "accuracy.svg"));
}

/// One of study (c)'s three leading figures: Yang's estimate or the work in
/// against its reference, as the CSV gives it.
struct Part {
    estimate: f64,
    reference: f64,
    error_rel: f64,
}

/// The sum of the chain's error `chain` and the bed's unsteadiness `unsteady`
/// is the error against the DEM's dissipation `sum`:
/// `(1 + chain)(1 + unsteady) − 1`, so their sum to within their product
/// (plus 1e-12 for rounding). Also asserts the unsteadiness is not zero, so
/// that a chain figure that silently equalled the sum cannot pass (with
/// |chain| < 1, `sum − chain = unsteady (1 + chain)` is then far from zero).
fn assert_sum(what: &str, chain: f64, unsteady: f64, sum: f64) {
    assert!(
        unsteady.abs() > 1e-6,
        "{what}: the unsteadiness {unsteady:e} is too small to tell the chain from the sum"
    );
    assert!(chain.abs() < 0.5, "{what}: chain error {chain}");
    let slack = (chain * unsteady).abs() + 1e-12;
    assert!(
        (sum - (chain + unsteady)).abs() <= slack,
        "{what}: {sum:e} vs DEM is not the chain {chain:e} plus the unsteadiness {unsteady:e} (slack {slack:e})"
    );
}

/// Study (c) leads with the chain's error (Yang against the work in), then
/// the bed's unsteadiness (work in against dissipated), then their sum (Yang
/// against the DEM dissipation): in the CSV rows of every record length, in
/// `summary.json`'s key order (in its `text`) and values, and in the printed line, whose
/// figures match the summary to the printed 0.001 %. Catches a reordering or
/// relabelling of the columns, a chain figure that is in fact the sum (or
/// the sum's reference put on the chain), an unsteadiness computed from the
/// wrong reference, and a printed line that swaps its figures.
fn chain_leads_then_unsteadiness_then_their_sum(
    yang: &[&Vec<&str>],
    col: &dyn Fn(&str) -> usize,
    (s, text): (&serde_json::Value, &str),
    stdout: &str,
) {
    let num = |r: &Vec<&str>, c: &str| -> f64 { r[col(c)].parse().expect("a number") };
    let mut lengths: Vec<&str> = yang.iter().map(|r| r[col("value")]).collect();
    lengths.dedup();
    assert!(lengths.len() >= 2, "record lengths {lengths:?}");
    let y = &s["yang"];
    let periods = y["baseline_record_periods"].as_u64().expect("baseline");
    let mut baseline = None;
    for length in &lengths {
        let of: Vec<&&Vec<&str>> = yang.iter().filter(|r| r[col("value")] == *length).collect();
        let quantities: Vec<&str> = of.iter().map(|r| r[col("quantity")]).collect();
        assert_eq!(
            quantities[..3],
            [
                "energy_per_cycle_vs_work_j",
                "work_in_per_cycle_j",
                "energy_per_cycle_j"
            ],
            "{length} periods: the chain, the unsteadiness, their sum: {quantities:?}"
        );
        let part = |i: usize| {
            let p = Part {
                estimate: num(of[i], "estimate"),
                reference: num(of[i], "reference"),
                error_rel: num(of[i], "error_rel"),
            };
            // The CSV keeps 17 digits: the error is its estimate over its
            // reference to the last few bits.
            let e = p.estimate / p.reference - 1.0;
            assert!(
                (p.error_rel - e).abs() < 1e-12,
                "{length} periods, {}: {} vs {e}",
                quantities[i],
                p.error_rel
            );
            p
        };
        let (chain, unsteady, sum) = (part(0), part(1), part(2));
        // One Yang figure; the chain's reference is the work in, which the
        // unsteadiness holds against the dissipation, the sum's reference.
        assert_eq!(
            chain.estimate, sum.estimate,
            "{length} periods: one estimate"
        );
        assert_eq!(
            chain.reference, unsteady.estimate,
            "{length} periods: work in"
        );
        assert_eq!(
            unsteady.reference, sum.reference,
            "{length} periods: dissipated"
        );
        assert!(
            of[0][col("note")].contains("the chain alone")
                && of[1][col("note")].contains("unsteadiness"),
            "{length} periods: notes {:?} {:?}",
            of[0][col("note")],
            of[1][col("note")]
        );
        assert_sum(
            &format!("{length} periods"),
            chain.error_rel,
            unsteady.error_rel,
            sum.error_rel,
        );
        if length.parse::<f64>().ok() == Some(periods as f64) {
            baseline = Some((chain.error_rel, unsteady.error_rel, sum.error_rel));
        }
    }
    let (chain, unsteady, sum) = baseline.expect("rows of the baseline length");
    let key = |k: &str| y[k].as_f64().unwrap_or_else(|| panic!("yang.{k}"));
    assert_eq!(key("baseline_error_vs_work_rel"), chain);
    assert_eq!(key("baseline_unsteadiness_rel"), unsteady);
    assert_eq!(key("baseline_error_rel"), sum);
    let at = |k: &str| text.find(&format!("\"{k}\"")).expect(k);
    assert!(
        at("baseline_error_vs_work_rel") < at("baseline_unsteadiness_rel")
            && at("baseline_unsteadiness_rel") < at("baseline_error_rel"),
        "summary.json: the chain, the unsteadiness, their sum: {text}"
    );

    let line = stdout
        .lines()
        .find(|l| l.contains("(c) Yang"))
        .unwrap_or_else(|| panic!("no study (c) line: {stdout}"));
    let after = |from: &str, to: &str| -> f64 {
        let i = line
            .find(from)
            .unwrap_or_else(|| panic!("'{from}' in {line}"))
            + from.len();
        let rest = &line[i..];
        let j = rest.find(to).unwrap_or_else(|| panic!("'{to}' in {line}"));
        rest[..j]
            .trim()
            .parse()
            .unwrap_or_else(|_| panic!("{line}"))
    };
    let printed = (
        after("the chain ", " % vs the work in, "),
        after("the bed's unsteadiness ", " %: "),
        after(" %: ", " % vs DEM dissipation"),
    );
    assert!(
        line.find("the chain ") < line.find("unsteadiness")
            && line.find("unsteadiness") < line.find("vs DEM dissipation"),
        "{line}"
    );
    // Printed as percent to 3 decimals: half a unit of 1e-5, and a little.
    for (p, j) in [(printed.0, chain), (printed.1, unsteady), (printed.2, sum)] {
        assert!((p / 100.0 - j).abs() <= 5.1e-6, "{line}: {p} vs {j}");
    }
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
