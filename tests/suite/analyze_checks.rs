//! `vlab analyze` gives no silent wrong number (issue 20 item 8), tried on
//! the tutorial's own reference record (`signals/reference/thesis-40Hz-G20`,
//! 40 Hz, rig `thesis-shaker`, exactly 7 periods):
//!
//! - a `--freq` its metadata and spectrum contradict is refused with both
//!   figures and `--force-freq`, which then uses it with a warning;
//! - another rig's calibration is refused with both rig names and
//!   `--force-calibration`; a calibration measured only at 160 Hz is warned
//!   about as outside the calibrated range at 40 Hz;
//! - a record cut to 3.7 periods says that 3 were used and what was left out.

#![cfg(all(feature = "cli", feature = "plot"))]

use crate::common;

use common::{Scratch, refuses_in, stderr, vlab};

fn reference(file: &str) -> String {
    format!(
        "{}/signals/reference/thesis-40Hz-G20/{file}",
        env!("CARGO_MANIFEST_DIR")
    )
}

/// Runs `args` in `dir`, which must succeed; returns (JSON on stdout, stderr).
fn analyze(dir: &Scratch, args: &[&str]) -> (serde_json::Value, String) {
    let mut all = vec!["analyze"];
    all.extend_from_slice(args);
    all.push("--json");
    let out = vlab(&dir.0, &all);
    assert!(out.status.success(), "{all:?}: {}", stderr(&out));
    (
        serde_json::from_slice(&out.stdout).expect("JSON"),
        stderr(&out),
    )
}

#[test]
fn the_reference_record_reads_without_a_warning() {
    let dir = Scratch::new("checks-clean");
    let (trace, cal) = (reference("trace.csv"), reference("calibration.json"));
    let (a, err) = analyze(&dir, &[&trace, "--calibration", &cal]);
    assert_eq!(err, "", "no warning on the tutorial's own record");
    assert_eq!(a["drive_freq_source"], "metadata");
    let s = a["spectrum_freq_hz"].as_f64().expect("spectrum");
    assert!((s - 40.0).abs() < 0.02, "{s}");
    assert_eq!(a["dropped_samples"], 0);
    // The semicolon export has no metadata: its --freq 40 agrees with its
    // spectrum; it names no rig, so the calibration's rig cannot be checked
    // against it, and it says so (a plain lab CSV analysed with another
    // rig's table would otherwise read 4.5 % off in silence).
    let semi = reference("trace-semicolon.csv");
    let (b, err) = analyze(&dir, &[&semi, "--freq", "40", "--calibration", &cal]);
    assert_eq!(
        err.matches("warning").count(),
        2,
        "the efficiency and the unchecked rig: {err}"
    );
    assert!(
        err.contains(
            "the calibration's rig cannot be checked against the record's: the record names no rig"
        ),
        "{err}"
    );
    assert_eq!(b["drive_freq_source"], "given");
    assert_eq!(b["power_w"], a["power_w"]);
}

#[test]
fn a_freq_the_record_contradicts_is_refused_unless_forced() {
    let dir = Scratch::new("checks-freq");
    let trace = reference("trace.csv");
    refuses_in(
        &dir,
        &["analyze", &trace, "--freq", "41"],
        &[
            "--freq 41 Hz",
            "drive_freq_hz is 40 Hz",
            "40.00 Hz",
            "--force-freq",
        ],
    );
    // Half a percent off is still the same frequency; one percent is not.
    analyze(&dir, &[&trace, "--freq", "40.1"]);
    refuses_in(
        &dir,
        &["analyze", &trace, "--freq", "40.4"],
        &["--force-freq"],
    );
    let (forced, err) = analyze(&dir, &[&trace, "--freq", "41", "--force-freq"]);
    assert_eq!(forced["drive_freq_hz"], 41.0);
    assert_eq!(forced["drive_freq_source"], "given");
    assert!(
        err.contains("warning: --freq 41 Hz contradicts the record")
            && err.contains("used as forced"),
        "{err}"
    );
    // The forced reading is the 7 % wrong number the refusal prevents.
    let (right, _) = analyze(&dir, &[&trace, "--freq", "40"]);
    let ratio =
        forced["power_w"].as_f64().expect("power") / right["power_w"].as_f64().expect("power");
    assert!((ratio - 1.0).abs() > 0.05, "{ratio}");
    // --force-freq without --freq is refused by the command line.
    assert!(
        !vlab(&dir.0, &["analyze", &trace, "--force-freq"])
            .status
            .success()
    );
}

#[test]
fn another_rigs_calibration_is_refused_unless_forced() {
    let dir = Scratch::new("checks-rig");
    let out = vlab(
        &dir.0,
        &[
            "calibrate",
            "--rig",
            "ideal",
            "--freq",
            "40",
            "--out",
            "ideal.json",
        ],
    );
    assert!(out.status.success(), "{}", stderr(&out));
    let trace = reference("trace.csv");
    refuses_in(
        &dir,
        &["analyze", &trace, "--calibration", "ideal.json"],
        &["'ideal'", "'thesis-shaker'", "--force-calibration"],
    );
    let (_, err) = analyze(
        &dir,
        &[&trace, "--calibration", "ideal.json", "--force-calibration"],
    );
    assert!(
        err.contains("'ideal'")
            && err.contains("'thesis-shaker'")
            && err.contains("applied as forced"),
        "{err}"
    );
}

#[test]
fn a_calibration_away_from_the_drive_is_warned_about() {
    let dir = Scratch::new("checks-range");
    // The reference calibration measured at 40, 160 and 640 Hz, kept at 160 Hz alone.
    let text = std::fs::read_to_string(reference("calibration.json")).expect("read");
    let mut cal: serde_json::Value = serde_json::from_str(&text).expect("JSON");
    let at_160 = cal["points"][1].clone();
    assert_eq!(at_160["freq_hz"], 160.0);
    cal["points"] = serde_json::json!([at_160]);
    cal.as_object_mut().expect("object").remove("model");
    dir.write("cal-160.json", &cal.to_string());
    let trace = reference("trace.csv");
    let (_, err) = analyze(&dir, &[&trace, "--calibration", "cal-160.json"]);
    assert!(
        err.contains("drive frequency 40 Hz lies outside the calibrated range (160 Hz alone)")
            && err.contains("extrapolated as a pure delay through 160 Hz")
            && err.contains("vlab calibrate --freq"),
        "{err}"
    );
    // The full table covers 40 Hz: no such warning.
    let (_, err) = analyze(
        &dir,
        &[&trace, "--calibration", &reference("calibration.json")],
    );
    assert!(!err.contains("outside the calibrated range"), "{err}");
}

#[test]
fn a_record_cut_short_says_what_was_left_out() {
    let dir = Scratch::new("checks-cut");
    let text = std::fs::read_to_string(reference("trace.csv")).expect("read");
    // The comment lines and the header, then 3.7 periods of 1000 samples.
    let head = text.lines().take_while(|l| l.starts_with('#')).count() + 1;
    let cut: String = text
        .lines()
        .take(head + 3700)
        .map(|l| format!("{l}\n"))
        .collect();
    dir.write("cut.csv", &cut);
    let (a, err) = analyze(&dir, &["cut.csv"]);
    assert_eq!(a["n_periods"], 3);
    assert_eq!(a["dropped_samples"], 700);
    assert!(
        err.contains("the record holds 3.70 drive periods: 3 whole periods were used and the last 0.70 periods (700 samples"),
        "{err}"
    );
    let out = vlab(&dir.0, &["analyze", "cut.csv"]);
    let human = String::from_utf8_lossy(&out.stdout);
    assert!(
        human.contains(
            "3 whole periods (3000 samples) of the record's 3.70, the last 700 samples left out"
        ),
        "{human}"
    );
}

/// The per-harmonic table gives each harmonic's phase, and its power is
/// `1/2 |F| |V| cos(phase)` to the printed digits; a negative power is
/// explained under the table (the reference record's harmonics 2-5 are).
#[test]
fn the_harmonic_table_gives_the_phase_that_signs_the_power() {
    let dir = Scratch::new("checks-harmonics");
    let (trace, cal) = (reference("trace.csv"), reference("calibration.json"));
    let out = vlab(&dir.0, &["analyze", &trace, "--calibration", &cal]);
    assert!(out.status.success(), "{}", stderr(&out));
    let text = String::from_utf8_lossy(&out.stdout);
    let header = text
        .lines()
        .position(|l| l.contains("phase [deg]") && l.contains("power [W]"))
        .expect("a phase column");
    let rows: Vec<Vec<f64>> = text
        .lines()
        .skip(header + 1)
        .take(5)
        .map(|l| l.split_whitespace().map(|c| c.parse().expect(l)).collect())
        .collect();
    assert_eq!(rows.len(), 5, "{text}");
    for r in &rows {
        let (f, v, phase_deg, p) = (r[2], r[3], r[4], r[5]);
        let expect = 0.5 * f * v * phase_deg.to_radians().cos();
        assert!(
            (p - expect).abs() <= 2e-3 * expect.abs() + 1e-6,
            "harmonic {}: {p} W printed, 1/2 |F||V| cos(phase) = {expect} W",
            r[0]
        );
    }
    assert!(rows.iter().any(|r| r[5] < 0.0), "{text}");
    assert!(text.contains("gave energy back to the shaker"), "{text}");
}

/// The force-displacement loop of the record (displacement from the
/// acceleration's spectrum, integrated in the time domain as the area
/// `∮ F dx`) encloses per cycle what Yang's method sums in the frequency
/// domain, to 0.5 %, when neither corrects the phase; a loop drawn from the
/// velocity or with the displacement's sign flipped encloses nothing like
/// it. The plots are written as SVG and PNG.
#[test]
fn the_force_loop_encloses_the_energy_yangs_method_finds() {
    let dir = Scratch::new("checks-loop");
    let trace = reference("trace.csv");
    let out = vlab(&dir.0, &["analyze", &trace, "--plots", "plots"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let text = String::from_utf8_lossy(&out.stdout);
    let number_after = |key: &str| -> f64 {
        let at = text.find(key).unwrap_or_else(|| panic!("{key}: {text}")) + key.len();
        text[at..]
            .split_whitespace()
            .next()
            .and_then(|w| w.parse().ok())
            .unwrap_or_else(|| panic!("a number after {key}: {text}"))
    };
    let yang = number_after("energy per cycle");
    let enclosed = number_after("force-displacement loop:");
    assert!(
        (enclosed / yang - 1.0).abs() < 5e-3,
        "loop {enclosed} J, Yang {yang} J per cycle"
    );
    for f in ["loop.svg", "loop.png", "phasor.svg", "phasor.png"] {
        assert!(dir.path("plots").join(f).is_file(), "{f}");
    }
}

/// A record whose force sign is flipped (a transducer mounted the other
/// way): `analyze` detects it and gives the same energy as the record as
/// it was; `--as-recorded` keeps the sign and finds the energy negative,
/// what a student without the detection would see.
#[test]
fn a_flipped_force_is_caught_unless_kept_as_recorded() {
    let dir = Scratch::new("checks-flipped");
    let text = std::fs::read_to_string(reference("trace.csv")).expect("trace");
    let mut flipped = String::new();
    let mut seen_header = false;
    for line in text.lines() {
        if line.starts_with('#') || !seen_header {
            seen_header |= !line.starts_with('#');
            flipped.push_str(line);
        } else {
            let mut cells: Vec<String> = line.split(',').map(String::from).collect();
            let f: f64 = cells[2].parse().expect("force");
            cells[2] = format!("{}", -f);
            flipped.push_str(&cells.join(","));
        }
        flipped.push('\n');
    }
    dir.write("flipped.csv", &flipped);
    let (original, _) = analyze(&dir, &[&reference("trace.csv")]);
    let (caught, err) = analyze(&dir, &["flipped.csv"]);
    let (kept, _) = analyze(&dir, &["flipped.csv", "--as-recorded"]);
    let e = |v: &serde_json::Value| v["energy_per_cycle_j"].as_f64().expect("energy");
    assert!(err.contains("polarity reversed"), "{err}");
    assert!((e(&caught) / e(&original) - 1.0).abs() < 1e-9);
    assert!((e(&kept) / e(&original) + 1.0).abs() < 1e-9, "{}", e(&kept));
}
