//! The Python package `vlab` passes its tests (python/tests/test_*.py)
//! with the compiled half this cargo run built: the package is staged in a
//! folder of its own (python/vlab/ and the library, named as Python loads
//! it) and pytest runs on it, nothing installed anywhere. Python needs numpy,
//! pytest, pytest-xdist, pandas and tqdm (`python3 -m pip install -r
//! python/requirements-test.txt`); without them the test
//! fails on CI (the `CI` variable set; .ci/run installs them) and elsewhere
//! says what is missing and passes.

use crate::ci_counts;
use crate::common;

use std::path::Path;
use std::process::Command;

use ci_counts::tell_ci;
use common::{python, python_has, stage_package, vlab_command};
use vlab::experiment::bed::cache::BedSource;
use vlab::experiment::shake_plan::{ShakePlan, ShakeRequest};
use vlab::scene::{CyclesSpec, Scene};

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
    if !python_has("numpy, pytest, xdist, pandas, tqdm") {
        return;
    }
    let here = Path::new(env!("CARGO_MANIFEST_DIR"));
    let stage = stage_package("python-package");
    let expected = library_energy_per_cycle_j();
    let mut pytest = Command::new(python());
    pytest
        .args(["-m", "pytest", "-q", "-rs", "-p", "no:cacheprovider"])
        // Two workers (pytest-xdist), each taking whole files, so a
        // module's shared shake (its fixture) runs once.
        .args(["-n", "2", "--dist", "loadfile"])
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
    let summary = said.lines().last().unwrap_or_default();
    eprintln!("{summary}");
    tell_ci(&format!("python package (pytest): {summary}"));
}
