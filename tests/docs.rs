//! The tutorial's commands run, in order, so that `docs/tutorial.md` cannot rot.
//! Lines marked `# takes minutes` are skipped.

#![cfg(all(feature = "cli", feature = "plot"))]

mod common;

use std::process::Command;

use common::Scratch;

#[test]
fn tutorial_commands_run() {
    let text = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/docs/tutorial.md"))
        .expect("docs/tutorial.md");
    let mut in_block = false;
    let mut commands = Vec::new();
    for line in text.lines() {
        if line.starts_with("```") {
            in_block = line == "```sh";
            continue;
        }
        if in_block && line.starts_with("vlab ") && !line.contains("# takes minutes") {
            commands.push(line.to_string());
        }
    }
    assert!(
        commands.len() >= 10,
        "found only {} commands",
        commands.len()
    );
    let bin_dir = std::path::Path::new(env!("CARGO_BIN_EXE_vlab"))
        .parent()
        .expect("binary folder")
        .to_path_buf();
    let path = format!(
        "{}:{}",
        bin_dir.display(),
        std::env::var("PATH").unwrap_or_default()
    );
    let dir = Scratch::new("tutorial");
    // Step 9 reads the reference records, as a reader would from a checkout.
    copy_dir(
        &std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("signals/reference"),
        &dir.path("signals/reference"),
    );
    for cmd in &commands {
        let out = Command::new("sh")
            .args(["-c", &format!("set -e; {cmd}")])
            .env("PATH", &path)
            .current_dir(&dir.0)
            .output()
            .expect("run sh");
        assert!(
            out.status.success(),
            "tutorial command failed: {cmd}\n{}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
    // Step 7's claim: the mis-calibrated rig reads off, the right one does not.
    let read = |p: &str| -> serde_json::Value {
        serde_json::from_str(&std::fs::read_to_string(dir.path(p)).expect(p)).expect("json")
    };
    let good = read("run/summary.json")["measured"]["error_vs_dem_rel"]
        .as_f64()
        .expect("error");
    let wrong = read("wrong/summary.json")["measured"]["error_vs_dem_rel"]
        .as_f64()
        .expect("error");
    assert!(good.abs() < 0.01, "calibrated run off by {good}");
    assert!(wrong.abs() > 0.02, "mis-calibrated run only off by {wrong}");
}

/// Copies the folder `from` to `to`, recursively.
fn copy_dir(from: &std::path::Path, to: &std::path::Path) {
    std::fs::create_dir_all(to).expect("create folder");
    for entry in std::fs::read_dir(from).expect("read folder") {
        let path = entry.expect("entry").path();
        let target = to.join(path.file_name().expect("name"));
        if path.is_dir() {
            copy_dir(&path, &target);
        } else {
            std::fs::copy(&path, &target).expect("copy");
        }
    }
}
