//! Every value is checked before any work: a command that pours a bed
//! refuses a bad flag or scene key before it pours (a pour of the thesis bed
//! takes seconds), names the key or flag the user wrote with its unit and
//! range, and writes nothing. Each case below was refused after the pour,
//! named a key the user did not write, panicked, or was accepted.

#![cfg(all(feature = "cli", feature = "plot"))]

use crate::common;

use std::time::{Duration, Instant};

use common::{Scratch, refuses_in};

/// Longer than any refusal takes and shorter than any pour (the thesis
/// bed's alone takes about a second in a release build, several in a test
/// build).
const BOUND: Duration = Duration::from_secs(2);

/// Runs `args` (a `scene.toml` holding `scene`, if given) and checks the
/// refusal: a non-zero exit, nothing written, a first line that starts
/// with `error: {starts}` and mentions `also`, within [`BOUND`].
fn refused_before_work(args: &[&str], scene: Option<&str>, starts: &str, also: &[&str]) {
    let dir = Scratch::new("checks");
    if let Some(text) = scene {
        dir.write("scene.toml", text);
    }
    let started = Instant::now();
    let first = refuses_in(&dir, args, also);
    let took = started.elapsed();
    let wanted = format!("error: {starts}");
    assert!(
        first.starts_with(&wanted),
        "{args:?}: '{first}' does not start with '{wanted}'"
    );
    assert!(took < BOUND, "{args:?} took {took:?} to refuse: '{first}'");
}

const SHAKE: &[&str] = &["shake", "--freq", "40", "--gamma", "20", "--no-cache"];

const EXPORT: &[&str] = &[
    "export",
    "lammps",
    "--freq",
    "40",
    "--gamma",
    "20",
    "--out",
    "o",
    "--no-cache",
];

fn with<'a>(base: &[&'a str], more: &[&'a str]) -> Vec<&'a str> {
    base.iter().chain(more).copied().collect()
}

#[test]
fn export_refuses_cycles_below_the_window_by_the_flag_given() {
    // Was "drive.steady_cycles = 5: must be in [1, drive.cycles = 2]": a key
    // the user did not write.
    refused_before_work(
        &with(EXPORT, &["--cycles", "2"]),
        None,
        "--cycles = 2: must be at least",
        &["drive.steady_cycles = 5"],
    );
}

#[test]
fn export_names_the_equivalent_diameter_as_written() {
    // Was "particles.diameter_m = -0.0076 m".
    refused_before_work(
        &with(EXPORT, &["--scene", "scene.toml"]),
        Some("[particles]\nequivalent_diameter_m = -0.0076\n"),
        "scene file scene.toml is not valid: particles.equivalent_diameter_m = -0.0076 m",
        &["positive and finite"],
    );
}

/// Shared multi-point contacts have no LAMMPS form (its granular pair style
/// makes every pair of atoms a whole contact): refused by the key, before
/// the pour of the prolate bed.
#[test]
fn export_refuses_shared_multi_point_contacts_by_the_key() {
    refused_before_work(
        &with(EXPORT, &["--scene", "scene.toml"]),
        Some(
            "[particles]\ncount = 90\nshape = \"prolate\"\naspect_ratio = 1.5\n[contact]\nmulti_point = \"shared\"\n",
        ),
        "contact.multi_point = \"shared\": must be",
        &["\"independent\" (the default) for the LAMMPS export"],
    );
}

#[test]
fn shake_refuses_a_record_longer_than_a_drive_may_run() {
    // Was a panic (an overflow adding the transient cycles).
    refused_before_work(
        &with(SHAKE, &["--duration-s", "1e9"]),
        None,
        "--duration-s = 1000000000 s: must be positive and at most",
        &["100000"],
    );
}

#[test]
fn shake_refuses_a_cycle_count_no_drive_can_run() {
    // Was accepted: 4e9 cycles, a hundred million seconds of drive.
    refused_before_work(
        &with(SHAKE, &["--cycles", "4000000000"]),
        None,
        "--cycles = 4000000000: must be an integer in 1..=100000",
        &[],
    );
}

#[test]
fn shake_refuses_a_scene_without_gravity_by_its_key() {
    // Was "--rig thesis-shaker: g_mps2 = 0 m/s^2", a rig key.
    refused_before_work(
        &with(SHAKE, &["--scene", "scene.toml"]),
        Some("[simulation]\ngravity_mps2 = 0\n"),
        "scene file scene.toml is not valid: simulation.gravity_mps2 = 0 m/s^2: must be positive",
        &[],
    );
}

#[test]
fn shake_names_the_min_cycles_written_not_the_presets_max() {
    // Was "drive.max_cycles = 400: must be an integer in 500..=100000".
    refused_before_work(
        &with(SHAKE, &["--scene", "scene.toml"]),
        Some("[drive]\nmin_cycles = 500\n"),
        "scene file scene.toml is not valid: drive.min_cycles = 500: must be at most drive.max_cycles = 400",
        &[],
    );
}

#[test]
fn sweep_names_its_flags_not_the_rig() {
    // Were "--rig thesis-shaker: drive.steady_cycles = 1: ..." and
    // "--rig thesis-shaker: fill_ratio = 0.9: ...".
    let sweep = &[
        "sweep",
        "--freq",
        "40",
        "--gamma",
        "20",
        "--no-cache",
        "--out",
        "o",
    ];
    refused_before_work(
        &with(sweep, &["--steady-cycles", "1"]),
        None,
        "--steady-cycles = 1: must be at least 2",
        &[],
    );
    refused_before_work(
        &with(sweep, &["--fill-ratio", "0.9"]),
        None,
        "--fill-ratio = 0.9: must be in (0, 0.64)",
        &[],
    );
}

#[test]
fn sweep_names_the_cycles_a_scene_file_wrote() {
    refused_before_work(
        &[
            "sweep",
            "--freq",
            "40",
            "--gamma",
            "20",
            "--scene",
            "scene.toml",
            "--no-cache",
            "--out",
            "o",
        ],
        Some("[drive]\ncycles = 2\n"),
        "scene file scene.toml is not valid: drive.cycles = 2: must be at least",
        &["drive.steady_cycles = 5"],
    );
}

#[test]
fn host_run_refuses_a_scene_without_gravity_before_the_pour() {
    // Was refused after pouring and settling for 2 s of simulated time (4 s
    // of wall time): "the bed did not come to rest while closing".
    refused_before_work(
        &[
            "host",
            "run",
            "--excitation",
            "sine:40:5",
            "--scene",
            "scene.toml",
            "--no-cache",
            "--out",
            "o",
        ],
        Some("[simulation]\ngravity_mps2 = 0\n"),
        "scene file scene.toml is not valid: simulation.gravity_mps2 = 0 m/s^2",
        &["positive"],
    );
}

#[test]
fn host_run_refuses_a_force_no_shaker_gives() {
    // Was accepted, and the bed poured, then blew up at the drive's start.
    refused_before_work(
        &[
            "host",
            "run",
            "--excitation",
            "sine:40:1e9",
            "--no-cache",
            "--out",
            "o",
        ],
        None,
        "invalid value 'sine:40:1e9' for '--excitation <KEY>': force_n = 1000000000 N: must be in (0, 10000]",
        &[],
    );
}

#[test]
fn host_run_names_its_duration_flag() {
    // Was "running the damper on its host: duration_s = ...".
    refused_before_work(
        &[
            "host",
            "run",
            "--excitation",
            "sine:40:5",
            "--duration-s",
            "1e9",
            "--no-cache",
            "--out",
            "o",
        ],
        None,
        "--duration-s = 1000000000 s: must be in (0, 600]",
        &[],
    );
}

#[test]
fn host_decay_names_beds_once() {
    // Was "--beds: beds = 0: ...".
    refused_before_work(
        &["host", "decay", "--beds", "0", "--no-cache", "--out", "o"],
        None,
        "--beds = 0: must be from 1 to 64",
        &[],
    );
}

#[test]
fn host_frf_refuses_a_random_force_no_shaker_gives() {
    // Was accepted, and the bed poured.
    refused_before_work(
        &[
            "host",
            "frf",
            "--random",
            "10:100:1e9:1:1",
            "--no-cache",
            "--out",
            "o",
        ],
        None,
        "--random rms_n = 1000000000 N: must be in (0, 10000]",
        &[],
    );
}

#[test]
fn accuracy_refuses_a_scene_without_gravity_by_its_key() {
    // Was "--rig thesis-shaker: g_mps2 = 0 m/s^2".
    refused_before_work(
        &["accuracy", "--scene", "scene.toml", "--quick", "--out", "o"],
        Some("[simulation]\ngravity_mps2 = 0\n"),
        "--scene scene.toml: scene file scene.toml is not valid: simulation.gravity_mps2 = 0 m/s^2",
        &["positive"],
    );
}

#[test]
fn press_and_shear_box_name_the_equivalent_diameter_as_written() {
    let scene = "[particles]\nequivalent_diameter_m = -0.0076\n";
    for args in [
        &["press", "--scene", "scene.toml", "--out", "o"][..],
        &[
            "shear-box",
            "--scene",
            "scene.toml",
            "--no-cache",
            "--out",
            "o",
        ][..],
    ] {
        refused_before_work(
            args,
            Some(scene),
            "scene file scene.toml is not valid: particles.equivalent_diameter_m = -0.0076 m",
            &[],
        );
    }
}

#[test]
fn shake_refuses_a_step_or_a_step_count_that_never_ends() {
    // Both were accepted, and the run never ended: 1e-15 s steps make a
    // second of drive 10^15 steps; 1e12 steps a contact as many.
    refused_before_work(
        &with(SHAKE, &["--scene", "scene.toml"]),
        Some("[simulation]\ndt_s = 1e-15\n"),
        "scene file scene.toml is not valid: simulation.dt_s = 0.000000000000001 s: must be at most the stability limit",
        &["at least a thousandth of it"],
    );
    refused_before_work(
        &with(SHAKE, &["--scene", "scene.toml"]),
        Some("[simulation]\nsteps_per_contact = 1e12\n"),
        "scene file scene.toml is not valid: simulation.steps_per_contact = 1000000000000: must be in [5, 1000]",
        &[],
    );
}

#[test]
fn shake_refuses_a_dump_of_a_file_every_step() {
    // Was accepted: a frame of the whole bed every 1e-12 s is a file every
    // step, and the run never ended.
    refused_before_work(
        &with(
            SHAKE,
            &["--dump", "frames", "--dump-every-s", "1e-12", "--out", "o"],
        ),
        None,
        "--dump-every-s = 0.000000000001 s: must be finite and at least a thousandth of the drive's period, 2.500e-5 s",
        &["1000 frames a cycle"],
    );
}
