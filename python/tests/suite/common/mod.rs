//! What the package's test and the notebooks' test share: Python, the
//! package staged with the compiled half this cargo run built (nothing
//! installed anywhere), and the `vlab` command built beside it.

#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::Command;

pub fn python() -> &'static str {
    if cfg!(windows) { "python" } else { "python3" }
}

/// Whether Python imports `modules` (`"numpy, pytest"`). Without them a
/// test fails on CI (the `CI` variable set; .ci/run installs them) and
/// elsewhere says what is missing and passes: the caller returns when this
/// is false.
pub fn python_has(modules: &str) -> bool {
    let ready = Command::new(python())
        .args(["-c", &format!("import {modules}")])
        .output()
        .is_ok_and(|o| o.status.success());
    if !ready {
        let missing = format!(
            "{} with {modules} (python3 -m pip install -r python/requirements-test.txt)",
            python()
        );
        assert!(
            std::env::var_os("CI").is_none(),
            "{missing} is needed on CI (.ci/run installs it)"
        );
        eprintln!("skipped: {missing} is not available");
    }
    ready
}

/// Where cargo puts what this run built: target/<profile>/ (a test is
/// target/<profile>/deps/<name>-<hash>).
fn profile_dir() -> PathBuf {
    let exe = std::env::current_exe().expect("the test's own path");
    exe.parent()
        .and_then(Path::parent)
        .expect("the test sits in target/<profile>/deps")
        .to_path_buf()
}

/// The `vlab` command built beside this test: `cargo test --workspace`
/// builds it with the library; alone (`-p vlab-python`) it may be missing,
/// or left from an earlier build (then a comparison with it may fail for
/// that reason: `cargo test --workspace` builds both).
pub fn vlab_command() -> Option<PathBuf> {
    let name = if cfg!(windows) { "vlab.exe" } else { "vlab" };
    Some(profile_dir().join(name)).filter(|p| p.is_file())
}

/// The compiled library cargo built beside this test, and the name Python
/// loads it by. A test run leaves it in target/<profile>/deps/, beside the
/// test itself (only `cargo build` copies it up to target/<profile>/, so a
/// copy there may be older than the code).
fn compiled_library() -> (PathBuf, &'static str) {
    let deps_dir = profile_dir().join("deps");
    let (built, loaded) = if cfg!(windows) {
        ("_vlab.dll", "_vlab.pyd")
    } else if cfg!(target_os = "macos") {
        ("lib_vlab.dylib", "_vlab.abi3.so")
    } else {
        ("lib_vlab.so", "_vlab.abi3.so")
    };
    (deps_dir.join(built), loaded)
}

/// Stages the package in a folder of its own named `name` under cargo's
/// temporary folder (python/vlab/ and the compiled half, named as Python
/// loads it) and returns the folder to put on `PYTHONPATH`.
pub fn stage_package(name: &str) -> PathBuf {
    let here = Path::new(env!("CARGO_MANIFEST_DIR"));
    let stage = Path::new(env!("CARGO_TARGET_TMPDIR")).join(name);
    let package = stage.join("vlab");
    let _ = std::fs::remove_dir_all(&stage);
    std::fs::create_dir_all(&package).expect("make the staging folder");
    std::fs::copy(here.join("vlab/__init__.py"), package.join("__init__.py"))
        .expect("stage __init__.py");
    let (built, loaded) = compiled_library();
    std::fs::copy(&built, package.join(loaded))
        .unwrap_or_else(|e| panic!("stage {}: {e}", built.display()));
    stage
}
