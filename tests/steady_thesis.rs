//! Issue 9, item 2: at every condition of the thesis' DEM study and of the
//! tutorial (40 Hz Γ 3 and 20, 20 Hz Γ 5 and 12, 160 Hz Γ 3 and 10), the
//! default `vlab shake` (thesis rig, electrodynamic shaker, phase error
//! calibrated on the fly, driven until steady) measures within 1 % of the
//! DEM truth (`measured.error_vs_dem_rel`); a drive that stops at its cap of
//! 400 cycles says so in `summary.json` (`dem.steadiness.capped`) and prints
//! a warning.
//!
//! Long (about 5 to 10 minutes on 2 idle cores, 160 Hz Γ 3 alone drives 400
//! cycles), so ignored by default; it prints each condition's wall time:
//!
//! ```sh
//! cargo test --release --test steady_thesis -- --ignored --nocapture
//! ```
//!
//! The quick test runs the same checks on a drive forced to its cap after 8
//! cycles, so the plumbing of the long one is tested by `cargo test`.

#![cfg(all(feature = "cli", feature = "plot"))]

mod common;

use std::time::Instant;

use common::{Scratch, json, stderr, vlab};

/// The most cycles a default drive runs (`drive.max_cycles` of the thesis
/// scene).
const CAP: u64 = 400;

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

/// One line about a run: cycles, the chain's error, the bed's unsteadiness
/// and their sum (the error against the DEM), wall times.
fn report(run: &Shake, capped: bool) -> String {
    let s = &run.summary;
    let m = &s["measured"];
    format!(
        "{:<16} {:>4} cycles{:<6} efficiency {:.3} +- {:.3}  chain {:+.2} % + unsteadiness {:+.2} % = measured vs DEM {:+.2} %  wall {:.0} s (settle {:.1} s{}, drive {:.1} s, rig {:.2} s)",
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
#[ignore = "long: six default shakes, one of 400 cycles at 160 Hz; run with --ignored --nocapture"]
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
    }
    eprintln!("\n{}", lines.join("\n"));
    assert!(
        outside.is_empty(),
        "measured more than 1 % from the DEM truth: {}",
        outside.join("; ")
    );
}

/// The plumbing of the long test, quick: 160 Hz, Γ 3 with criteria no drive
/// meets (1e-6) and a cap of 8 cycles stops at the cap, and the summary and
/// standard error say so; the measurement's error against the DEM is a
/// finite number (an 8-cycle bed at 160 Hz is far from steady, so it is not
/// held to 1 % here).
#[test]
fn a_drive_that_reaches_its_cap_says_so() {
    let dir = Scratch::new("steady-cap");
    dir.write(
        "capped.toml",
        "[drive]\nmax_cycles = 8\nbalance_rel = 1e-6\nstderr_rel = 1e-6\n",
    );
    let run = shake(&dir, "160", "3", &["--scene", "capped.toml"]);
    assert!(cap_is_said(&run, 8), "{}: not capped", run.what);
    let error = run.number(
        &run.summary["measured"]["error_vs_dem_rel"],
        "error_vs_dem_rel",
    );
    assert!(error.is_finite(), "error_vs_dem_rel = {error}");
    eprintln!("{}", report(&run, true));
}
