//! Bad input: a clear one-line error naming the parameter, its unit and valid
//! range; a non-zero exit status; nothing written.

#![cfg(all(feature = "cli", feature = "plot"))]

use crate::common;

use common::{Scratch, refuses_in, stderr, vlab};

/// Runs `args` in a fresh folder holding `scene.toml` (if given) and checks the
/// refusal; returns the first line of standard error.
fn refuses(args: &[&str], scene: Option<&str>, must_mention: &[&str]) -> String {
    let dir = Scratch::new("errors");
    if let Some(text) = scene {
        dir.write("scene.toml", text);
    }
    refuses_in(&dir, args, must_mention)
}

#[test]
fn bad_drive_parameters() {
    refuses(
        &["shake", "--freq", "0"],
        None,
        &["--freq", "Hz", "positive"],
    );
    refuses(&["shake", "--freq", "-40"], None, &["--freq", "Hz"]);
    refuses(&["shake", "--freq", "nan"], None, &["--freq", "finite"]);
    refuses(
        &["shake", "--freq", "abc"],
        None,
        &["--freq", "must be a number"],
    );
    refuses(&["shake", "--gamma", "0"], None, &["--gamma", "positive"]);
    refuses(&["shake", "--gamma", "inf"], None, &["--gamma", "finite"]);
    refuses(&["shake", "--freq", "100000"], None, &["--freq", "Hz"]);
    refuses(
        &["shake", "--cycles", "3", "--steady-cycles", "5"],
        None,
        &["--steady-cycles", "[1,"],
    );
}

/// The record's two whole periods: refused by the key when a scene file set
/// the window, by the flag when the flag did.
#[test]
fn steady_window_too_short_for_yangs_method() {
    let from_file = refuses(
        &["shake", "--scene", "scene.toml"],
        Some("[drive]\nsteady_cycles = 1\n"),
        &[
            "drive.steady_cycles = 1: must be at least 2",
            "Yang's method",
        ],
    );
    assert!(!from_file.contains("--steady-cycles"), "{from_file}");
    refuses(
        &["shake", "--steady-cycles", "1"],
        None,
        &["--steady-cycles = 1: must be at least 2", "Yang's method"],
    );
    // Every cycle kept: the record from the drive's start lacks its first
    // sample, so 2 periods hold 1999 samples, one whole period at 40 Hz:
    // refused before the run (it used to fail after the whole drive).
    refuses(
        &[
            "shake",
            "--beds",
            "1",
            "--freq",
            "40",
            "--gamma",
            "20",
            "--cycles",
            "2",
            "--steady-cycles",
            "2",
        ],
        None,
        &["--steady-cycles = 2: must be at least 3", "first sample"],
    );
}

#[test]
fn time_step_above_stability_limit() {
    refuses(
        &["shake", "--dt-s", "1e-4"],
        None,
        &["--dt-s", "stability limit", " s"],
    );
    refuses(
        &["shake", "--scene", "scene.toml"],
        Some("[simulation]\ndt_s = 2e-5\n"),
        &["dt_s", "stability limit"],
    );
}

#[test]
fn bad_scene_values() {
    let shake = ["shake", "--scene", "scene.toml"];
    refuses(
        &shake,
        Some("[particles]\ndiameter_m = -0.005\n"),
        &["diameter_m", "positive", " m: must"],
    );
    refuses(
        &shake,
        Some("[contact]\nparticle_particle = { restitution = 1.2, friction = 0.5 }\n"),
        &["restitution", "(0, 1]"],
    );
    refuses(
        &shake,
        Some("[contact]\nparticle_particle = { restitution = 0.0, friction = 0.5 }\n"),
        &["restitution", "(0, 1]"],
    );
    refuses(
        &shake,
        Some("[contact]\nparticle_wall = { restitution = 0.9, friction = -0.1 }\n"),
        &["friction", ">= 0"],
    );
    refuses(
        &shake,
        Some("[particles]\ncount = 700\n"),
        &["count", "random close packing"],
    );
    refuses(
        &shake,
        Some("[particles]\ncolour = \"red\"\n"),
        &["scene.toml", "colour"],
    );
    refuses(&shake, Some("[particles\ncount = 3\n"), &["scene.toml"]);
    refuses(&shake, Some("version = 7\n"), &["version"]);
}

#[test]
fn unreadable_scene_file() {
    refuses(
        &["shake", "--scene", "missing.toml"],
        None,
        &["missing.toml", "cannot read"],
    );
    refuses(
        &["scene", "--scene", "missing.toml"],
        None,
        &["missing.toml"],
    );
}

#[test]
fn bad_impact_parameters() {
    refuses(
        &["impact", "--radius-m", "0"],
        None,
        &["--radius-m", " m: must"],
    );
    refuses(
        &["impact", "--speed-mps", "-2"],
        None,
        &["--speed-mps", "m/s"],
    );
    refuses(&["impact", "--cor", "1.5"], None, &["--cor", "(0, 1]"]);
    refuses(&["impact", "--mu", "-1"], None, &["--mu", ">= 0"]);
    refuses(
        &["impact", "--angle-deg", "95"],
        None,
        &["--angle-deg", "[0, 90)"],
    );
    refuses(
        &["impact", "--dt-s", "1e-5"],
        None,
        &["--dt-s", "too coarse"],
    );
}

/// A run that fails half-way (a step the Rayleigh check lets through, 8e-6 s,
/// but too coarse for the spheres' collisions) stops with a diagnosis and
/// leaves no folder behind.
#[test]
fn failed_run_leaves_no_folders() {
    let dir = Scratch::new("failed-run");
    dir.write("coarse.toml", "[simulation]\ndt_s = 8e-6\n");
    let out = vlab(
        &dir.0,
        &[
            "--quiet",
            "shake",
            "--beds",
            "1",
            "--scene",
            "coarse.toml",
            "--out",
            "deep/run",
        ],
    );
    assert!(!out.status.success());
    let err = stderr(&out);
    assert!(
        err.contains("numerical instability") && err.contains("time step"),
        "{err}"
    );
    assert!(
        !dir.path("deep").exists(),
        "the failed run left deep/ behind"
    );
}

/// The same through the flag, to the default output folder: `--dt-s 8e-6`
/// (below the Rayleigh limit of 8.3e-6 s, so it is accepted) leaves a
/// sphere-sphere collision of under 5 steps in the settled thesis bed. The
/// run stops with a diagnosis that names the collision, the step and the step
/// to use instead, exits non-zero, prints no JSON, and writes nothing but the
/// settled bed in its cache (the folder `signals/` is never made).
#[test]
fn unresolved_collision_through_the_flag_stops_with_a_diagnosis() {
    let dir = Scratch::new("unresolved");
    let out = vlab(
        &dir.0,
        &["shake", "--beds", "1", "--dt-s", "8e-6", "--json"],
    );
    assert!(!out.status.success(), "the run should fail");
    assert!(out.stdout.is_empty(), "printed a summary");
    let err = stderr(&out);
    let line = err
        .lines()
        .find(|l| l.starts_with("error:"))
        .unwrap_or_else(|| panic!("no error line: {err}"));
    for part in [
        "numerical instability",
        "collision",
        "time steps of 8.000e-6 s",
        "use a time step of at most",
    ] {
        assert!(line.contains(part), "'{line}' lacks '{part}'");
    }
    assert!(!dir.path("signals").exists(), "left signals/ behind");
    let cache = dir.path(".vlab-cache");
    let written: Vec<_> = common::files_below(&dir.0)
        .into_iter()
        .filter(|p| !p.starts_with(&cache))
        .collect();
    assert!(written.is_empty(), "wrote {written:?}");
}

/// A bad value reads the same wherever it was given: `<key> = <value>
/// <unit>: must be <valid>`, with the scene key, the rig key or the flag.
#[test]
fn one_message_shape_for_a_scene_file_a_rig_file_and_a_flag() {
    let dir = Scratch::new("shape");
    dir.write("scene.toml", "[particles]\ndiameter_m = -0.005\n");
    let rig = vlab::rig::builtin_toml("ideal")
        .expect("built in")
        .replace("sensitivity_v_per_n = ", "sensitivity_v_per_n = -");
    dir.write("rig.toml", &rig);
    let scene = refuses_in(&dir, &["shake", "--scene", "scene.toml"], &[]);
    let rig = refuses_in(&dir, &["shake", "--rig", "rig.toml"], &[]);
    let flag = refuses_in(&dir, &["shake", "--freq", "-40"], &[]);
    let cycles = refuses_in(&dir, &["shake", "--cycles", "0"], &[]);
    for (line, shape) in [
        (
            &scene,
            "particles.diameter_m = -0.005 m: must be positive and finite",
        ),
        (&rig, "force.sensitivity_v_per_n = -"),
        (&flag, "--freq = -40 Hz: must be positive and finite"),
        (&cycles, "--cycles = 0: must be an integer in 1..=100000"),
    ] {
        assert!(line.contains(shape), "'{line}' lacks '{shape}'");
    }
    assert!(rig.contains(" V/N: must be positive and finite"), "{rig}");
    assert!(scene.contains("scene.toml"), "{scene}");
    assert!(rig.contains("rig.toml"), "{rig}");
    assert!(
        rig.contains("--rig rig.toml: force.sensitivity_v_per_n"),
        "the rig file is named once: {rig}"
    );
}
