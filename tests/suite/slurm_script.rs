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
