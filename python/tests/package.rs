//! The Python package `vlab` passes its tests (python/tests/test_*.py)
//! with the compiled half this cargo run built: the package is staged in a
//! folder of its own (python/vlab/ and the library, named as Python loads
//! it) and pytest runs on it, nothing installed anywhere. Python needs numpy,
//! pytest, pandas and tqdm (`python3 -m pip install -r
//! python/requirements-test.txt`); without them the test
//! fails on CI (the `CI` variable set; .ci/run installs them) and elsewhere
//! says what is missing and passes.

use std::path::{Path, PathBuf};
use std::process::Command;

use vlab::experiment::bed::cache::BedSource;
use vlab::experiment::shake_plan::{ShakePlan, ShakeRequest};
use vlab::scene::{CyclesSpec, Scene};

const PYTHON_MODULES: &str = "import numpy, pytest, pandas, tqdm";

fn python() -> &'static str {
    if cfg!(windows) { "python" } else { "python3" }
}

/// Where cargo puts what this run built: target/<profile>/ (the test is
/// target/<profile>/deps/package-<hash>).
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
fn vlab_command() -> Option<PathBuf> {
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

/// The energy per cycle the library gives for the request the tests' short
/// shake makes (`vlab.shake(40, 20, seed=3, beds=1, cycles=8,
/// steady_cycles=4, rig="ideal", cache=False)`), every bit of it.
fn library_energy_per_cycle_j() -> f64 {
    let mut scene = Scene::thesis();
    scene.simulation.seed = 3;
    scene.drive.cycles = CyclesSpec::Count(8);
    scene.drive.steady_cycles = 4;
    let request = ShakeRequest {
        rig: "ideal".into(),
        beds: 1,
        ..ShakeRequest::new(scene, 40.0, 20.0)
    };
    let outcome = ShakePlan::new(request)
        .expect("a valid request")
        .run(&BedSource::Settle, 1, &mut [], &mut |_| {})
        .expect("the shake runs");
    outcome.summary().dem.energy_per_cycle_j
}

#[test]
fn the_python_package_passes_its_tests() {
    let ready = Command::new(python())
        .args(["-c", PYTHON_MODULES])
        .output()
        .is_ok_and(|o| o.status.success());
    if !ready {
        let missing = format!("{} with numpy, pytest, pandas and tqdm", python());
        assert!(
            std::env::var_os("CI").is_none(),
            "{missing} is needed on CI (.ci/run installs it)"
        );
        eprintln!("skipped: {missing} is not available");
        return;
    }
    let here = Path::new(env!("CARGO_MANIFEST_DIR"));
    let stage = Path::new(env!("CARGO_TARGET_TMPDIR")).join("python-package");
    let package = stage.join("vlab");
    let _ = std::fs::remove_dir_all(&stage);
    std::fs::create_dir_all(&package).expect("make the staging folder");
    std::fs::copy(here.join("vlab/__init__.py"), package.join("__init__.py"))
        .expect("stage __init__.py");
    let (built, loaded) = compiled_library();
    std::fs::copy(&built, package.join(loaded))
        .unwrap_or_else(|e| panic!("stage {}: {e}", built.display()));
    let expected = library_energy_per_cycle_j();
    let mut pytest = Command::new(python());
    pytest
        .args(["-m", "pytest", "-q", "-rs", "-p", "no:cacheprovider"])
        .arg(here.join("tests"))
        .env("PYTHONPATH", &stage)
        .env("PYTHONDONTWRITEBYTECODE", "1")
        .env("VLAB_EXPECTED_ENERGY_J", format!("{expected:?}"))
        .current_dir(&stage);
    let cli = vlab_command();
    if let Some(cli) = &cli {
        pytest.env("VLAB", cli);
    }
    let out = pytest.output().expect("run pytest");
    let said = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "pytest failed:\n{said}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    // Every test ran, but those that compare with the command where there
    // is no binary (their skip reason names VLAB; `-rs` lists the reasons).
    let skipped: Vec<&str> = said
        .lines()
        .filter(|l| l.starts_with("SKIPPED"))
        .filter(|l| cli.is_some() || !l.contains("VLAB, the vlab binary"))
        .collect();
    assert!(
        skipped.is_empty(),
        "{} skipped (the vlab command {}):\n{said}",
        skipped.len(),
        if cli.is_some() {
            "built"
        } else {
            "not built: cargo test --workspace builds it"
        }
    );
    eprintln!("{}", said.lines().last().unwrap_or_default());
}
