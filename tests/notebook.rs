//! The teaching notebook `docs/notebooks/yang.ipynb` (Yang's method with
//! numpy on the reference record, checked against `vlab analyze` inside
//! the notebook) runs from top to bottom, when Python has numpy,
//! matplotlib, nbclient, nbformat and ipykernel
//! (`python3 -m pip install -r python/requirements-test.txt`). Without them
//! the test fails on CI (the `CI` variable set; .ci/run installs them) and
//! elsewhere says what is missing and passes.

use std::process::Command;

const MODULES: &str = "import numpy, matplotlib, nbclient, nbformat, ipykernel";

#[test]
fn the_yang_notebook_runs_and_agrees_with_analyze() {
    let python_ready = Command::new("python3")
        .args(["-c", MODULES])
        .output()
        .is_ok_and(|o| o.status.success());
    if !python_ready {
        let missing = "python3 with numpy, matplotlib, nbclient, nbformat and ipykernel";
        assert!(
            std::env::var_os("CI").is_none(),
            "{missing} is needed on CI (.ci/run installs it)"
        );
        eprintln!("skipped: {missing} is not available");
        return;
    }
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/docs/notebooks");
    // Executes a copy in memory; the notebook's own asserts compare its
    // numbers with vlab's.
    let script = "import nbformat, nbclient\n\
nb = nbformat.read('yang.ipynb', as_version=4)\n\
nbclient.NotebookClient(nb, timeout=300, kernel_name='python3', resources={'metadata': {'path': '.'}}).execute()\n";
    let out = Command::new("python3")
        .args(["-c", script])
        .current_dir(dir)
        .env("VLAB", env!("CARGO_BIN_EXE_vlab"))
        .output()
        .expect("run python3");
    assert!(
        out.status.success(),
        "the notebook failed:\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
}
