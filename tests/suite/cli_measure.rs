//! `vlab shake` through the rig, `vlab analyze`, `vlab calibrate`, end to end.

#![cfg(all(feature = "cli", feature = "plot"))]

use crate::common;

use common::{Scratch, refuses_in, run_summary, small_scene, stderr, vlab};

fn analyze_json(dir: &Scratch, trace: &str) -> serde_json::Value {
    let out = vlab(
        &dir.0,
        &[
            "analyze",
            trace,
            "--calibration",
            "run/calibration.json",
            "--json",
        ],
    );
    assert!(out.status.success(), "{}", stderr(&out));
    serde_json::from_slice(&out.stdout).expect("JSON")
}

/// CSV -> analyze and WAV -> analyze give the in-memory result of the run.
#[test]
fn csv_and_wav_analysis_equal_the_run() {
    let dir = Scratch::new("measure");
    dir.write("small.toml", &small_scene(5, 3, ""));
    let (_, s) = run_summary(
        &dir,
        &[
            "--quiet",
            "shake",
            "--beds",
            "1",
            "--scene",
            "small.toml",
            "--freq",
            "40",
            "--gamma",
            "10",
        ],
        "run",
    );
    let measured = s["measured"]["energy_per_cycle_j"]
        .as_f64()
        .expect("measured");
    for key in [
        "power_w",
        "energy_per_cycle_j",
        "efficiency",
        "phase_correction_rad",
        "error_vs_dem_rel",
    ] {
        assert!(s["measured"][key].is_f64(), "measured.{key} missing");
    }
    for file in [
        "trace.csv",
        "trace.wav",
        "trace.wav.json",
        "kinematics.csv",
        "calibration.json",
        "trace.svg",
        "trace.png",
        "bed.svg",
        "bed.png",
    ] {
        assert!(dir.path(&format!("run/{file}")).is_file(), "{file} missing");
    }
    bed_centre_follows_the_force(&dir.path("run/kinematics.csv"), &s);
    for trace in ["run/trace.csv", "run/trace.wav"] {
        let a = analyze_json(&dir, trace);
        let e = a["energy_per_cycle_j"].as_f64().expect("energy");
        assert!(
            (e / measured - 1.0).abs() < 1e-12,
            "{trace}: {e} vs in-memory {measured}"
        );
        let eta = a["efficiency"].as_f64().expect("efficiency from metadata");
        assert!((eta - s["measured"]["efficiency"].as_f64().expect("eta")).abs() < 1e-12);
    }
}

/// `vlab calibrate` recovers the rig model's own phase error at each frequency.
#[test]
fn calibrate_recovers_the_rig_phase_error() {
    let dir = Scratch::new("calibrate");
    let out = vlab(
        &dir.0,
        &[
            "calibrate",
            "--freq",
            "20,40,160",
            "--out",
            "cal.json",
            "--json",
        ],
    );
    assert!(out.status.success(), "{}", stderr(&out));
    let rows: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
    let rows = rows.as_array().expect("rows");
    assert_eq!(rows.len(), 3);
    for r in rows {
        let est = r["phase_error_rad"].as_f64().expect("estimate");
        let model = r["rig_model_phase_error_rad"].as_f64().expect("model");
        assert!(
            (est - model).abs() < 1e-4,
            "{}: {est} vs {model}",
            r["freq_hz"]
        );
        assert!(
            est > 0.002 && est < 0.01,
            "a fraction of a degree, got {est} rad"
        );
    }
    assert!(dir.path("cal.json").is_file());
}

/// Refuses `args` in a folder prepared by `setup`; nothing new is written.
fn refuses(setup: impl Fn(&Scratch), args: &[&str], must_mention: &[&str]) {
    let dir = Scratch::new("measure-errors");
    setup(&dir);
    refuses_in(&dir, args, must_mention);
}

const GOOD_HEADER: &str = "# sample_rate_hz: 1000\ntime [s],force [N],acceleration [m/s^2]\n";

fn good_csv(periods: usize) -> String {
    let mut s = GOOD_HEADER.to_string();
    let n = periods * 100;
    for i in 0..n {
        let t = i as f64 / 1000.0;
        let w = 2.0 * std::f64::consts::PI * 10.0;
        s += &format!("{t},{},{}\n", (w * t).cos(), (w * t).sin());
    }
    s
}

#[test]
fn analyze_refuses_bad_records() {
    let none = |_: &Scratch| {};
    refuses(
        none,
        &["analyze", "missing.csv", "--freq", "10"],
        &["missing.csv"],
    );
    refuses(
        |d: &Scratch| {
            d.write("t.txt", "x");
        },
        &["analyze", "t.txt", "--freq", "10"],
        &["t.txt", "unknown kind", ".csv", ".wav"],
    );
    refuses(
        |d: &Scratch| {
            d.write("t.csv", "time [s],force [N]\n0,1\n0.001,2\n0.002,3\n");
        },
        &["analyze", "t.csv", "--freq", "10"],
        &["acceleration"],
    );
    refuses(
        |d: &Scratch| {
            d.write(
                "t.csv",
                &(GOOD_HEADER.to_string() + "0,1,2\n0.001,abc,3\n0.002,1,1\n"),
            );
        },
        &["analyze", "t.csv", "--freq", "10"],
        &["abc"],
    );
    refuses(
        |d: &Scratch| {
            d.write(
                "t.csv",
                &(GOOD_HEADER.to_string() + "0,1,2\n0.001,NaN,3\n0.002,1,1\n"),
            );
        },
        &["analyze", "t.csv", "--freq", "10"],
        &["NaN"],
    );
    // Fewer than two drive periods.
    refuses(
        |d: &Scratch| {
            d.write("t.csv", &good_csv(1));
        },
        &["analyze", "t.csv", "--freq", "10"],
        &["2 whole periods"],
    );
    // No drive frequency anywhere.
    refuses(
        |d: &Scratch| {
            d.write("t.csv", &good_csv(4));
        },
        &["analyze", "t.csv"],
        &["drive frequency", "--freq"],
    );
}

#[test]
fn analyze_refuses_bad_wav_files() {
    let mono = |d: &Scratch| {
        // A mono WAV whose sidecar names only the force.
        let spec = hound::WavSpec {
            channels: 1,
            sample_rate: 1000,
            bits_per_sample: 32,
            sample_format: hound::SampleFormat::Float,
        };
        let mut w = hound::WavWriter::create(d.path("m.wav"), spec).expect("wav");
        for i in 0..400 {
            w.write_sample((i as f32 * 0.1).sin()).expect("sample");
        }
        w.finalize().expect("finalize");
        d.write(
            "m.wav.json",
            r#"{"format":"vlab-wav-sidecar","version":1,"sample_rate_hz":1000.0,"start_time_s":0.0,"n_samples":400,"channels":[{"name":"force","unit":"N","full_scale":1.0}],"metadata":{}}"#,
        );
    };
    refuses(
        mono,
        &["analyze", "m.wav", "--freq", "10"],
        &["acceleration"],
    );
    let wrong_rate = |d: &Scratch| {
        mono(d);
        d.write(
            "m.wav.json",
            r#"{"format":"vlab-wav-sidecar","version":1,"sample_rate_hz":2000.0,"start_time_s":0.0,"n_samples":400,"channels":[{"name":"force","unit":"N","full_scale":1.0}],"metadata":{}}"#,
        );
    };
    refuses(
        wrong_rate,
        &["analyze", "m.wav", "--freq", "10"],
        &["sample rate"],
    );
}

#[test]
fn analyze_warns_loudly_about_clipping() {
    let dir = Scratch::new("clip");
    let mut s = GOOD_HEADER.to_string();
    for i in 0..400 {
        let t = i as f64 / 1000.0;
        let w = 2.0 * std::f64::consts::PI * 10.0;
        s += &format!(
            "{t},{},{}\n",
            (2.0 * (w * t).cos()).clamp(-1.0, 1.0),
            (w * t).sin()
        );
    }
    dir.write("c.csv", &s);
    let out = vlab(&dir.0, &["analyze", "c.csv", "--freq", "10"]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(stderr(&out).contains("clipped"), "{}", stderr(&out));
}

#[test]
fn shake_refuses_what_the_rig_cannot_do() {
    let none = |_: &Scratch| {};
    refuses(
        none,
        &["shake", "--freq", "20", "--gamma", "15"],
        &["stroke", "--rig ideal"],
    );
    refuses(
        none,
        &["shake", "--freq", "40", "--gamma", "45"],
        &["--rig ideal"],
    );
    refuses(
        none,
        &["shake", "--rig", "nonexistent-rig"],
        &["nonexistent-rig"],
    );
    refuses(
        none,
        &["shake", "--rig", "ideal", "--shaker", "electrodynamic"],
        &["electrodynamic"],
    );
    refuses(
        none,
        &["shake", "--calibration", "nope.json"],
        &["nope.json"],
    );
    refuses(
        none,
        &["calibrate", "--freq", "20", "--gammas", "15"],
        &["--rig ideal"],
    );
}

/// The bed's centre of mass in `kinematics.csv` moves as the force on the
/// bed says (Newton's second law for the bed, vertical): `M z'' = -F - M g`
/// with `F` the particles' force on the enclosure. Integrated twice over
/// the last cycle from the recorded start (its velocity fitted), the force
/// gives the recorded centre to 2 % of its travel. A centre taken at the
/// wrong step, with the wrong masses or in the enclosure's frame without
/// its displacement would not follow.
fn bed_centre_follows_the_force(path: &std::path::Path, summary: &serde_json::Value) {
    let text = std::fs::read_to_string(path).expect("kinematics.csv");
    let mut lines = text.lines().filter(|l| !l.starts_with('#'));
    let header: Vec<&str> = lines.next().expect("header").split(',').collect();
    let col = |name: &str| {
        header
            .iter()
            .position(|h| h.starts_with(name))
            .unwrap_or_else(|| panic!("{name} in {header:?}"))
    };
    let (ti, ui, fi, bi) = (
        col("time"),
        col("enclosure_displacement"),
        col("particle_force_axial"),
        col("bed_centre_rel"),
    );
    let rows: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').map(|c| c.parse().expect("number")).collect())
        .collect();
    let m = summary["particle_mass_kg"].as_f64().expect("mass");
    let g = summary["gravity_mps2"].as_f64().expect("g");
    let dt = rows[1][ti] - rows[0][ti];
    let n = (1.0 / (40.0 * dt)).round() as usize;
    let last = &rows[rows.len() - n..];
    let z: Vec<f64> = last.iter().map(|r| r[ui] + r[bi]).collect();
    let acc: Vec<f64> = last.iter().map(|r| -r[fi] / m - g).collect();
    // Twice integrated from rest at the first sample (trapezoids).
    let (mut v, mut x) = (vec![0.0; n], vec![0.0; n]);
    for k in 1..n {
        v[k] = v[k - 1] + 0.5 * (acc[k - 1] + acc[k]) * dt;
        x[k] = x[k - 1] + 0.5 * (v[k - 1] + v[k]) * dt;
    }
    // The start's velocity by least squares: z - z0 - x = v0 t.
    let t: Vec<f64> = (0..n).map(|k| k as f64 * dt).collect();
    let v0 = (0..n).map(|k| t[k] * (z[k] - z[0] - x[k])).sum::<f64>()
        / t.iter().map(|t| t * t).sum::<f64>();
    let travel =
        z.iter().cloned().fold(f64::MIN, f64::max) - z.iter().cloned().fold(f64::MAX, f64::min);
    let worst = (0..n)
        .map(|k| (z[0] + v0 * t[k] + x[k] - z[k]).abs())
        .fold(0.0, f64::max);
    assert!(
        worst < 0.02 * travel,
        "the bed's centre strays {worst} m from what its force predicts (travel {travel} m)"
    );
}
