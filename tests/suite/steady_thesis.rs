//! Issue 9, item 2: at every condition of the thesis' DEM study and of the
//! tutorial (40 Hz Γ 3 and 20, 20 Hz Γ 5 and 12, 160 Hz Γ 3 and 10), the
//! default `vlab shake` (thesis rig, electrodynamic shaker, phase error
//! calibrated on the fly, driven until steady) measures within 1 % of the
//! DEM truth (`measured.error_vs_dem_rel`); a drive that stops at its cap of
//! 400 cycles says so in `summary.json` (`dem.steadiness.capped`) and prints
//! a warning.
//!
//! Long (about 15 minutes on 2 idle cores: six beds a condition, 20 Hz
//! driving the longest), so ignored by default; it prints each condition's
//! ensemble figures, its first bed's chain and wall time:
//!
//! ```sh
//! cargo test --release --test suite steady_thesis:: -- --ignored --nocapture
//! ```
//!
//! The quick test runs the same checks on drives forced to their cap after 8
//! cycles, so the plumbing of the long one is tested by `cargo test`, and
//! holds what such a capped run prints against the steady truth: its ±
//! must cover how far it is from it ([`STEADY_160_HZ`]).

#![cfg(all(feature = "cli", feature = "plot"))]

use crate::common;

use std::time::Instant;

use common::{Scratch, json, stderr, vlab};

/// The most cycles a default drive runs (`drive.max_cycles` of the thesis
/// scene).
const CAP: u64 = 400;

/// Long-run DEM efficiency and its standard error at 160 Hz, Γ 3 and Γ 10
/// (`--gamma` text, efficiency, ±): the default shakes of 2026-11-25, seed 1,
/// under the steady rule of then (400 cycles, the cap, and 173 cycles:
/// windows of 250 and 108 cycles; docs/physics.md). The long test below
/// checks that today's default shakes (79 and 32 cycles, 0.475 ± 0.004 and
/// 0.166 ± 0.003) still agree with them.
const STEADY_160_HZ: [(&str, f64, f64); 2] = [("3", 0.459, 0.009), ("10", 0.169, 0.002)];

/// How many combined standard errors a figure may lie from the steady truth.
const Z_MAX: f64 = 3.0;

/// `(figure - truth) / sqrt(se^2 + se_truth^2)`.
fn z_score(figure: f64, se: f64, truth: f64, se_truth: f64) -> f64 {
    (figure - truth) / se.hypot(se_truth)
}

/// A finished shake: its summary, its standard error, its wall time.
struct Shake {
    what: String,
    summary: serde_json::Value,
    stderr: String,
    wall_s: f64,
}

impl Shake {
    fn dem(&self, key: &str) -> &serde_json::Value {
        &self.summary["dem"][key]
    }

    fn number(&self, value: &serde_json::Value, key: &str) -> f64 {
        value
            .as_f64()
            .unwrap_or_else(|| panic!("{}: {key} missing from summary.json", self.what))
    }
}

/// `vlab --quiet shake --freq F --gamma G ARGS --out OUT` in `dir` (quiet
/// silences progress, never warnings); it must succeed.
fn shake(dir: &Scratch, freq: &str, gamma: &str, args: &[&str]) -> Shake {
    let out = format!("{freq}Hz-G{gamma}");
    let mut all = vec![
        "--quiet", "shake", "--freq", freq, "--gamma", gamma, "--out", &out,
    ];
    all.extend_from_slice(args);
    let started = Instant::now();
    let o = vlab(&dir.0, &all);
    let wall_s = started.elapsed().as_secs_f64();
    let what = format!("{freq} Hz, Gamma {gamma}");
    assert!(o.status.success(), "{what}: {}", stderr(&o));
    Shake {
        summary: json(&dir.path(&format!("{out}/summary.json"))),
        stderr: stderr(&o),
        wall_s,
        what,
    }
}

/// A drive that ended at `cap` cycles without reaching steady state says so:
/// `dem.steadiness.capped` in the summary, the cap warning in its
/// `warnings` and on standard error; and `capped` is never set below the cap.
/// Returns whether it was capped.
fn cap_is_said(run: &Shake, cap: u64) -> bool {
    let steadiness = run.dem("steadiness");
    let capped = steadiness["capped"].as_bool().expect("steadiness.capped");
    let reached = steadiness["reached"].as_bool().expect("steadiness.reached");
    let cycles = run.dem("cycles").as_u64().expect("dem.cycles");
    let what = &run.what;
    assert!(
        cycles <= cap,
        "{what}: {cycles} cycles, above the cap {cap}"
    );
    assert_eq!(
        capped,
        cycles == cap && !reached,
        "{what}: {cycles} cycles, reached {reached}, capped {capped}"
    );
    if capped {
        let phrase = format!("the drive stopped at its cap of {cap} cycles");
        let in_summary = run.summary["warnings"]
            .as_array()
            .expect("warnings")
            .iter()
            .any(|w| w.as_str().is_some_and(|w| w.contains(&phrase)));
        assert!(in_summary, "{what}: summary.json lacks '{phrase}'");
        assert!(
            run.stderr.contains(&format!("warning: {phrase}")),
            "{what}: no cap warning printed: {}",
            run.stderr
        );
    }
    capped
}

/// One line about a run: cycles, the ensemble's efficiency (DEM and
/// measured) where it ran one, the first bed's efficiency, the chain's
/// error, the bed's unsteadiness and their sum (the error against the DEM),
/// wall times.
fn report(run: &Shake, capped: bool) -> String {
    let s = &run.summary;
    let m = &s["measured"];
    let e = &s["ensemble"];
    let ensemble = if e.is_object() {
        let fig = |k: &str| {
            format!(
                "{:.4} +- {:.4}",
                run.number(&e[k]["mean"], k),
                run.number(&e[k]["stderr"], k)
            )
        };
        format!(
            "ensemble of {}: DEM {}, measured {}; first bed ",
            e["beds"],
            fig("dem_efficiency"),
            fig("measured_efficiency")
        )
    } else {
        String::new()
    };
    format!(
        "{:<16} {:>4} cycles{:<6} {ensemble}efficiency {:.3} +- {:.3}  chain {:+.2} % + unsteadiness {:+.2} % = measured vs DEM {:+.2} %  wall {:.0} s (settle {:.1} s{}, drive {:.1} s, rig {:.2} s)",
        run.what,
        run.dem("cycles"),
        if capped { " (cap)" } else { "" },
        run.number(run.dem("efficiency"), "dem.efficiency"),
        run.number(run.dem("efficiency_stderr"), "dem.efficiency_stderr"),
        100.0 * run.number(&m["error_vs_dem_work_rel"], "error_vs_dem_work_rel"),
        100.0 * run.number(&m["unsteadiness_rel"], "unsteadiness_rel"),
        100.0 * run.number(&m["error_vs_dem_rel"], "error_vs_dem_rel"),
        run.wall_s,
        run.number(&s["settle_wall_time_s"], "settle_wall_time_s"),
        if s["bed_from_cache"] == true {
            ", cached"
        } else {
            ""
        },
        run.number(&s["wall_time_s"], "wall_time_s"),
        run.number(&s["rig_wall_time_s"], "rig_wall_time_s"),
    )
}

/// The claim: within 1 % of the DEM truth at all six conditions, each run
/// with vlab's defaults (the bed settles once, in the test's own cache).
#[test]
#[ignore = "long: six default shakes of six beds, about 15 min; run with --ignored --nocapture"]
fn default_shake_measures_within_one_percent_of_the_dem_at_every_thesis_condition() {
    let dir = Scratch::new("steady-thesis");
    let conditions = [
        ("40", "3"),
        ("40", "20"),
        ("20", "5"),
        ("20", "12"),
        ("160", "3"),
        ("160", "10"),
    ];
    let mut lines = Vec::new();
    let mut outside = Vec::new();
    for (freq, gamma) in conditions {
        let run = shake(&dir, freq, gamma, &[]);
        let capped = cap_is_said(&run, CAP);
        let line = report(&run, capped);
        eprintln!("{line}");
        lines.push(line);
        let error = run.number(
            &run.summary["measured"]["error_vs_dem_rel"],
            "error_vs_dem_rel",
        );
        // A NaN error is outside too.
        let within = error.abs() < 0.01;
        if !within {
            outside.push(format!("{}: {:+.2} %", run.what, 100.0 * error));
        }
        // The steady figures the quick test holds capped runs against.
        if let Some(&(_, truth, se_truth)) =
            STEADY_160_HZ.iter().find(|s| freq == "160" && s.0 == gamma)
        {
            let eta = run.number(run.dem("efficiency"), "dem.efficiency");
            let se = run.number(run.dem("efficiency_stderr"), "dem.efficiency_stderr");
            let z = z_score(eta, se, truth, se_truth);
            // A NaN z is outside too.
            if z.is_nan() || z.abs() > Z_MAX {
                outside.push(format!(
                    "{}: efficiency {eta:.3} +- {se:.3}, STEADY_160_HZ says {truth} +- {se_truth} (z {z:+.1})",
                    run.what
                ));
            }
        }
    }
    eprintln!("\n{}", lines.join("\n"));
    assert!(
        outside.is_empty(),
        "measured more than 1 % from the DEM truth: {}",
        outside.join("; ")
    );
}

/// The plumbing of the long test, quick, and the capped run's ± held to
/// account: 160 Hz, Γ 3 and Γ 10 with criteria no drive meets (1e-6) and a
/// cap of 60 cycles (at Γ 3 the bed alternates from cycle to cycle, and
/// its error is that of pairs: the window after its warm-up, cycles 27–60,
/// holds 17; with glibc's bits the warm-up was shorter and 52 cycles held
/// 16, with `libm`'s a cap of 52 left 13 and no error) stop at the cap, and
/// the summary and standard error say so. A
/// 60-cycle bed at 160 Hz is not steady, so its figures are not held to 1 %;
/// instead the ± it prints must cover its distance from the steady truth
/// ([`STEADY_160_HZ`]): the DEM efficiency, and the measured one, within
/// [`Z_MAX`] = 3 combined standard errors of it (measured on 2026-11-29:
/// DEM 0.470 +- 0.004 at Γ 3, z +1.1, and 0.166 +- 0.001 at Γ 10, z −1.3;
/// on 2026-11-26, with 52 cycles and glibc's bits, 0.475 +- 0.008, z +1.3,
/// and 0.164 +- 0.001, z −2.2).
/// At Γ 10 the long-run figure's own error (0.002) outweighs the run's
/// (0.001), so this holds the capped run's figure more than its ±: a run
/// reading 0.008 off fails, a ± understated by any factor would not
/// (`tests/suite/coverage.rs` checks the ± itself). The measured
/// figure's error against the DEM over the same window (the chain plus the
/// bed's unsteadiness, +0.26 % and +0.04 %) lies within 3 combined standard
/// errors of the two too.
#[test]
fn a_drive_that_reaches_its_cap_says_so_and_its_error_is_within_its_stderr() {
    let dir = Scratch::new("steady-cap");
    dir.write(
        "capped.toml",
        "[drive]\nmax_cycles = 60\nbalance_rel = 1e-6\nstderr_rel = 1e-6\n",
    );
    for (gamma, truth, se_truth) in STEADY_160_HZ {
        let run = shake(
            &dir,
            "160",
            gamma,
            &["--scene", "capped.toml", "--beds", "1"],
        );
        assert!(cap_is_said(&run, 60), "{}: not capped", run.what);
        eprintln!("{}", report(&run, true));
        let what = &run.what;
        let dem = run.number(run.dem("efficiency"), "dem.efficiency");
        let dem_se = run.number(run.dem("efficiency_stderr"), "dem.efficiency_stderr");
        let m = &run.summary["measured"];
        let measured = run.number(&m["efficiency"], "measured.efficiency");
        let measured_se = run.number(&m["efficiency_stderr"], "measured.efficiency_stderr");
        for (name, eta, se) in [("DEM", dem, dem_se), ("measured", measured, measured_se)] {
            let z = z_score(eta, se, truth, se_truth);
            eprintln!(
                "{what}: {name} {eta:.3} +- {se:.3} vs steady {truth} +- {se_truth}: z {z:+.2}"
            );
            assert!(
                z.abs() <= Z_MAX,
                "{what}: {name} efficiency {eta:.4} +- {se:.4} is {z:+.1} standard errors from the steady {truth} +- {se_truth}: its +- understates how far it is"
            );
        }
        let error = run.number(&m["error_vs_dem_rel"], "error_vs_dem_rel");
        let z = z_score(measured, measured_se, dem, dem_se);
        assert!(
            (error - (measured / dem - 1.0)).abs() < 1e-9 && z.abs() <= Z_MAX,
            "{what}: measured vs DEM {:+.2} %, {z:+.1} combined standard errors",
            100.0 * error
        );
    }
}

/// An ensemble the rule cannot show stationary by its cap says so, once,
/// for the ensemble: `ensemble.steadiness.capped` (and not `reached`), the
/// warning naming why in `summary.json` and on standard error, and the
/// printout's verdict "NOT shown steady".
#[test]
fn an_ensemble_stopped_at_its_cap_says_why() {
    let dir = Scratch::new("steady-cap-ensemble");
    dir.write(
        "capped.toml",
        "[drive]\nmax_cycles = 26\nbalance_rel = 1e-6\nstderr_rel = 1e-6\n",
    );
    let out = vlab(
        &dir.0,
        &[
            "shake",
            "--freq",
            "160",
            "--gamma",
            "10",
            "--scene",
            "capped.toml",
            "--beds",
            "2",
            "--out",
            "run",
        ],
    );
    assert!(out.status.success(), "{}", stderr(&out));
    let s = json(&dir.path("run/summary.json"));
    let st = &s["ensemble"]["steadiness"];
    assert_eq!(st["capped"], true, "{st}");
    assert_eq!(st["reached"], false, "{st}");
    let phrase = "the 2 beds were driven to the cap of 26 cycles without a window shown stationary";
    let warned = s["warnings"]
        .as_array()
        .expect("warnings")
        .iter()
        .filter(|w| w.as_str().is_some_and(|w| w.contains(phrase)))
        .count();
    assert_eq!(warned, 1, "{}", s["warnings"]);
    assert!(stderr(&out).contains(phrase), "{}", stderr(&out));
    let printed = String::from_utf8_lossy(&out.stdout);
    assert!(printed.contains("NOT shown steady"), "{printed}");
}
