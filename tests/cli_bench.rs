//! `vlab bench`: the report holds what it says it times, whatever the speed
//! of the machine (no timing is checked here: speed targets live in the
//! bench itself and in docs/performance.md, never in a test).

#![cfg(all(feature = "cli", feature = "plot"))]

mod common;

use common::{Scratch, refuses_in, stderr, vlab};

/// Runs `vlab --quiet bench --beds-only --json` on one bed of `spheres`,
/// `steps` steps, `repeats` runs, with `extra` arguments, in `dir`; the
/// report as JSON.
fn bench_beds_only(
    dir: &Scratch,
    spheres: &str,
    steps: &str,
    repeats: &str,
    extra: &[&str],
) -> serde_json::Value {
    let mut args = vec![
        "--quiet",
        "bench",
        "--beds-only",
        "--json",
        "--beds",
        spheres,
        "--bed-steps",
        steps,
        "--repeats",
        repeats,
    ];
    args.extend_from_slice(extra);
    let out = vlab(&dir.0, &args);
    assert!(out.status.success(), "{}", stderr(&out));
    serde_json::from_slice(&out.stdout).expect("bench --json prints JSON")
}

/// A bed of 4000 spheres (enough pairs for its step to split across
/// threads), timed twice: every row has the runs asked for and finite,
/// positive rates; with more than one core the bed also ran as independent
/// copies, and the speed-ups name both comparisons.
#[test]
fn bench_of_a_small_bed_reports_its_rows_and_speed_ups() {
    let dir = Scratch::new("bench");
    let report = bench_beds_only(&dir, "4000", "3", "2", &[]);
    let rows = report["rows"].as_array().expect("rows");
    let cores = report["cores"].as_u64().expect("cores");
    // 1 thread, and with more cores: all threads and the host's copies.
    assert_eq!(rows.len(), if cores > 1 { 3 } else { 1 }, "{report:#}");
    for r in rows {
        assert_eq!(r["particles"], 4000, "{r}");
        assert_eq!(r["runs"], 2, "{r}");
        assert_eq!(r["run_wall_s"].as_array().map(Vec::len), Some(2), "{r}");
        let rate = r["particle_steps_per_s"].as_f64().expect("rate");
        let fastest = r["fastest_particle_steps_per_s"].as_f64().expect("rate");
        assert!(rate.is_finite() && rate > 0.0, "{r}");
        assert!(fastest >= rate, "fastest run slower than the median: {r}");
        // A rate per CPU second, or none when the runs were too short for
        // the CPU clock: never an infinite one.
        let per_cpu = &r["particle_steps_per_cpu_s"];
        assert!(
            per_cpu.is_null() || per_cpu.as_f64().is_some_and(|x| x.is_finite() && x > 0.0),
            "{r}"
        );
    }
    if cores > 1 {
        let copies = rows.iter().find(|r| r["copies"] == cores).expect("copies");
        // The copies did `cores` times the work of one run in each run.
        assert_eq!(copies["threads"], cores, "{copies}");
        let split = rows
            .iter()
            .find(|r| r["threads"] == cores && r["copies"] == 1)
            .expect("all threads");
        assert_eq!(split["split_across_threads"], true, "{split}");
        let what: Vec<&str> = report["speedups"]
            .as_array()
            .expect("speed-ups")
            .iter()
            .filter_map(|s| s["what"].as_str())
            .collect();
        assert!(
            what.iter().any(|w| w.contains("what the host gives")),
            "{what:?}"
        );
        assert!(what.iter().any(|w| w.contains("against")), "{what:?}");
    }
    // Nothing written without --out.
    let written = common::files_below(&dir.0);
    assert!(written.is_empty(), "{written:?}");
}

/// `--no-copies` leaves the host's reference out (one bed in memory at a
/// time); a bed of fewer than 2 spheres is refused.
#[test]
fn bench_options_are_checked() {
    let dir = Scratch::new("bench-opts");
    let report = bench_beds_only(
        &dir,
        "300",
        "2",
        "1",
        &["--no-copies", "--out", "bench.csv"],
    );
    let rows = report["rows"].as_array().expect("rows");
    assert!(rows.iter().all(|r| r["copies"] == 1), "{report:#}");
    // The CSV has a row per configuration; a rate per CPU second is a
    // finite number or empty (2 steps of 300 spheres: below the CPU clock).
    let text = std::fs::read_to_string(dir.path("bench.csv")).expect("bench.csv");
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().expect("header").split(',').collect();
    let at = header
        .iter()
        .position(|h| h.starts_with("particle_steps_per_cpu_s"))
        .expect("per-CPU column");
    let body: Vec<&str> = lines.collect();
    assert_eq!(body.len(), rows.len(), "{text}");
    for line in body {
        let cell = line.split(',').nth(at).expect("cell");
        assert!(
            cell.is_empty() || cell.parse::<f64>().is_ok_and(f64::is_finite),
            "{line}"
        );
    }
    refuses_in(&dir, &["bench", "--beds", "1"], &["--beds", "at least 2"]);
    refuses_in(&dir, &["bench", "--repeats", "0"], &["--repeats"]);
}
