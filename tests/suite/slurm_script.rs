//! `docs/slurm-sweep.sh` without a cluster: its shell syntax (`bash -n`), and a
//! whole run with a stub `sbatch` that records what it is asked to submit. The
//! test then plays Slurm: it runs every array task the way Slurm would (the
//! script with `SLURM_ARRAY_TASK_ID` set) and then the merge job's command,
//! on a tiny scene, and checks the merged sweep.

#![cfg(all(feature = "cli", feature = "plot", unix))]

use crate::common;

use std::path::Path;
use std::process::Command;

use common::{Scratch, TINY_SCENE};

const SCRIPT: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/docs/slurm-sweep.sh");

/// Records every call's arguments (one a line) in `callN`, the `--wrap`
/// command in `merge.sh`, and answers with a job id as `--parsable` does.
const STUB: &str = r#"#!/usr/bin/env bash
set -eu
n=$(( $(cat "$STUB_DIR/count" 2>/dev/null || echo 0) + 1 ))
echo "$n" > "$STUB_DIR/count"
printf '%s\n' "$@" > "$STUB_DIR/call$n"
prev=
for a in "$@"; do
    if [[ "$prev" == --wrap ]]; then printf '%s\n' "$a" > "$STUB_DIR/merge.sh"; fi
    prev=$a
done
echo "100$n"
"#;

const SWEEP: [&str; 8] = [
    "--freq",
    "40",
    "--gamma",
    "1,3",
    "--seeds",
    "1,2",
    "--scene",
    "tiny.toml",
];

fn bash(dir: &Path, args: &[&str], env: &[(&str, String)]) -> std::process::Output {
    let mut c = Command::new("bash");
    c.args(args).current_dir(dir);
    for (k, v) in env {
        c.env(k, v);
    }
    c.env_remove("SLURM_ARRAY_TASK_ID");
    c.output().expect("run bash")
}

fn ok(o: &std::process::Output, what: &str) {
    assert!(
        o.status.success(),
        "{what} failed:\n{}\n{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
}

#[test]
fn the_script_parses() {
    let o = Command::new("bash")
        .args(["-n", SCRIPT])
        .output()
        .expect("bash");
    ok(&o, "bash -n docs/slurm-sweep.sh");
}

#[test]
fn the_script_submits_runs_shards_and_merges() {
    let dir = Scratch::new("slurm");
    dir.write("tiny.toml", TINY_SCENE);
    let stub_dir = dir.path("stub");
    std::fs::create_dir_all(&stub_dir).expect("stub dir");
    let stub = dir.write("stub/sbatch", STUB);
    let mut perm = std::fs::metadata(&stub).expect("stub").permissions();
    std::os::unix::fs::PermissionsExt::set_mode(&mut perm, 0o755);
    std::fs::set_permissions(&stub, perm).expect("chmod stub");
    let env = vec![
        ("SHARDS", "3".to_string()),
        ("OUT", "shards".to_string()),
        ("VLAB", env!("CARGO_BIN_EXE_vlab").to_string()),
        ("SBATCH", stub.display().to_string()),
        ("STUB_DIR", stub_dir.display().to_string()),
    ];

    // On the login node: two submissions, the array and its merge.
    let mut args = vec![SCRIPT];
    args.extend_from_slice(&SWEEP);
    let o = bash(&dir.0, &args, &env);
    ok(&o, "submitting");
    let call = |n: u32| -> Vec<String> {
        std::fs::read_to_string(stub_dir.join(format!("call{n}")))
            .expect("a recorded sbatch call")
            .lines()
            .map(String::from)
            .collect()
    };
    let array = call(1);
    assert!(array.contains(&"--array=1-3".to_string()), "{array:?}");
    assert!(array.contains(&"shards/job.sh".to_string()), "{array:?}");
    assert!(array.ends_with(&SWEEP.map(String::from)), "{array:?}");
    let merge = call(2);
    assert!(
        merge.contains(&"--dependency=afterany:1001".to_string()),
        "{merge:?}"
    );
    assert!(
        !stub_dir.join("call3").exists(),
        "more than two submissions"
    );
    assert!(dir.path("shards/submit.log").exists());

    // Slurm runs the array's copy of the script once per task.
    for i in 1..=3 {
        let mut task_env = env.clone();
        task_env.push(("SLURM_CPUS_PER_TASK", "1".to_string()));
        let mut c = Command::new("bash");
        c.arg("shards/job.sh").args(SWEEP).current_dir(&dir.0);
        for (k, v) in &task_env {
            c.env(k, v);
        }
        c.env("SLURM_ARRAY_TASK_ID", i.to_string());
        let o = c.output().expect("run a task");
        ok(&o, &format!("array task {i}"));
        assert!(dir.path(&format!("shards/shard{i}/sweep.csv")).exists());
    }

    // Then the merge job.
    let o = bash(
        &dir.0,
        &[&stub_dir.join("merge.sh").display().to_string()],
        &env,
    );
    ok(&o, "the merge job");
    let merged = std::fs::read_to_string(dir.path("shards/merged/sweep.csv")).expect("merged");
    assert!(merged.contains("# shard: 1/1"), "{merged}");
    let rows = merged
        .lines()
        .filter(|l| !l.starts_with('#'))
        .skip(1)
        .filter(|l| l.contains(",ok,"))
        .count();
    assert_eq!(rows, 4, "{merged}");
}

const LAMMPS_SCRIPT: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/docs/slurm-lammps.sh");

/// Stands in for `lmp`: checks it was started in the deck's folder with the
/// deck, and writes the record a LAMMPS run of it would (`$STUB_RECORD`).
const LMP_STUB: &str = r#"#!/usr/bin/env bash
set -eu
[[ "$*" == "-in in.damper -log lammps.log" ]] || { echo "lmp stub: asked '$*'" >&2; exit 3; }
[[ -f in.damper && -f packing.data ]] || { echo "lmp stub: not in the deck's folder" >&2; exit 3; }
cp "$STUB_RECORD" record.txt
echo "stub run" > lammps.log
"#;

/// A record as the deck's `fix ave/time` writes it: a solid mass riding a
/// 40 Hz, Γ 20 sine for 4 cycles, at 40 kHz.
fn riding_mass_record(mass_kg: f64) -> String {
    let (freq_hz, g) = (40.0_f64, 9.81);
    let omega = std::f64::consts::TAU * freq_hz;
    let amplitude = 20.0 * g / (omega * omega);
    let mut text = format!(
        "# vlab replay record: tiny damper, 40 Hz, Gamma 20, from a LAMMPS deck of vlab test\n\
         # units: si\n# drive_freq_hz: 40\n# gamma: 20\n# particle_mass_kg: {mass_kg}\n\
         # gravity_mps2: {g}\n# orientation: vertical\n# steady_cycles: 2\n\
         # record_every_steps: 10\n\
         # TimeStep v_time v_enclosure_displacement v_enclosure_velocity v_enclosure_acceleration v_particle_force_axial\n"
    );
    for k in 1..=4000 {
        let t = k as f64 * 25e-6;
        let a = -amplitude * omega * omega * (omega * t).sin();
        text += &format!(
            "{} {t:e} {:e} {:e} {a:e} {:e}\n",
            10 * k,
            amplitude * (omega * t).sin(),
            amplitude * omega * (omega * t).cos(),
            -mass_kg * (a + g)
        );
    }
    text
}

#[test]
fn the_lammps_script_parses() {
    let o = Command::new("bash")
        .args(["-n", LAMMPS_SCRIPT])
        .output()
        .expect("bash");
    ok(&o, "bash -n docs/slurm-lammps.sh");
}

/// The job as Slurm would run it, `lmp` a stub: the deck run in its
/// folder, the record replayed into DECK/replay with the flags given; a
/// folder without a deck and an --out of one's own are refused.
#[test]
fn the_lammps_script_runs_the_deck_and_replays_its_record() {
    let dir = Scratch::new("slurm-lammps");
    dir.write("tiny.toml", TINY_SCENE);
    let vlab = env!("CARGO_BIN_EXE_vlab");
    let export = Command::new(vlab)
        .args(["--quiet", "export", "lammps", "--scene", "tiny.toml"])
        .args([
            "--freq", "40", "--gamma", "20", "--cycles", "4", "--out", "deck",
        ])
        .current_dir(&dir.0)
        .output()
        .expect("vlab export");
    ok(&export, "vlab export lammps");
    dir.write("record.txt", &riding_mass_record(0.0025));
    let stub = dir.write("lmp", LMP_STUB);
    let mut perm = std::fs::metadata(&stub).expect("stub").permissions();
    std::os::unix::fs::PermissionsExt::set_mode(&mut perm, 0o755);
    std::fs::set_permissions(&stub, perm).expect("chmod stub");
    let env = vec![
        ("LMP", stub.display().to_string()),
        ("VLAB", vlab.to_string()),
        ("LAUNCH", "env".to_string()),
        ("STUB_RECORD", dir.path("record.txt").display().to_string()),
    ];
    let o = bash(&dir.0, &[LAMMPS_SCRIPT, "deck", "--rig", "ideal"], &env);
    ok(&o, "the job");
    assert!(dir.path("deck/lammps.log").exists());
    let summary: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(dir.path("deck/replay/summary.json")).expect("summary.json"),
    )
    .expect("JSON");
    assert_eq!(summary["rig"], "ideal", "{summary}");
    // A solid mass dissipates nothing.
    let efficiency = summary["measured"]["efficiency"]
        .as_f64()
        .expect("efficiency");
    assert!(efficiency.abs() < 0.01, "{summary}");

    for (args, says) in [
        (&["nodeck"][..], "no in.damper"),
        (&["deck", "--out", "elsewhere"][..], "--out"),
    ] {
        let mut all = vec![LAMMPS_SCRIPT];
        all.extend_from_slice(args);
        let o = bash(&dir.0, &all, &env);
        assert_eq!(o.status.code(), Some(2), "{args:?}");
        assert!(
            String::from_utf8_lossy(&o.stderr).contains(says),
            "{args:?}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
    }
    assert!(!dir.path("elsewhere").exists());
}
