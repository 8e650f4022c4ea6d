//! The teaching notebooks (docs/notebooks/*.ipynb) run from top to bottom on
//! the package this cargo run built (staged as python/tests/suite/package.rs
//! stages it, nothing installed): Yang's method by hand, a sweep and its
//! map, the drop test, the host. Each checks its own numbers against the
//! package's with asserts, so a notebook whose arithmetic or whose package
//! call went wrong fails here. Python needs numpy, matplotlib, pandas,
//! nbclient, nbformat and ipykernel (`python3 -m pip install -r
//! python/requirements-test.txt`); without them the test fails on CI (the
//! `CI` variable set; .ci/run installs them) and elsewhere says what is
//! missing and passes.

use crate::ci_counts;
use crate::common;

use std::path::Path;
use std::process::Command;

use ci_counts::tell_ci;
use common::{python, python_has, stage_package, vlab_command};

/// The notebooks the class uses; a notebook in the folder but not here
/// fails the test, so none goes unrun.
const NOTEBOOKS: [&str; 4] = ["yang.ipynb", "sweep.ipynb", "drop.ipynb", "host.ipynb"];

#[test]
fn every_notebook_runs_on_the_package() {
    if !python_has("numpy, matplotlib, pandas, nbclient, nbformat, ipykernel") {
        return;
    }
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../docs/notebooks");
    let mut found: Vec<String> = std::fs::read_dir(&dir)
        .expect("docs/notebooks")
        .filter_map(|e| e.ok()?.file_name().into_string().ok())
        .filter(|n| n.ends_with(".ipynb"))
        .collect();
    found.sort();
    let mut listed: Vec<String> = NOTEBOOKS.iter().map(|s| s.to_string()).collect();
    listed.sort();
    assert_eq!(
        found, listed,
        "docs/notebooks/ holds notebooks this test does not run"
    );
    let stage = stage_package("python-notebooks");
    // Each notebook in a kernel of its own, executed in memory (nothing is
    // written back); the notebooks' asserts compare their numbers.
    let script = r#"
import sys, time, nbformat, nbclient
for name in sys.argv[1:]:
    nb = nbformat.read(name, as_version=4)
    uses = any("import vlab" in "".join(c.source) for c in nb.cells)
    assert uses, name + " does not use the package"
    t = time.time()
    client = nbclient.NotebookClient(
        nb, timeout=600, kernel_name="python3", resources={"metadata": {"path": "."}}
    )
    client.execute()
    print(f"{name} ran in {time.time() - t:.1f} s", flush=True)
"#;
    let mut run = Command::new(python());
    run.arg("-c")
        .arg(script)
        .args(NOTEBOOKS)
        .current_dir(&dir)
        .env("PYTHONPATH", &stage)
        .env("PYTHONDONTWRITEBYTECODE", "1")
        .env("MPLBACKEND", "Agg");
    if let Some(cli) = vlab_command() {
        run.env("VLAB", cli);
    }
    let out = run.output().expect("run python3");
    let said = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "a notebook failed:\n{said}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    eprint!("{said}");
    let ran: Vec<&str> = said.lines().filter(|l| l.contains(" ran in ")).collect();
    assert_eq!(ran.len(), NOTEBOOKS.len());
    tell_ci(&format!(
        "notebooks: {} of {} ran: {}",
        ran.len(),
        NOTEBOOKS.len(),
        ran.join("; ")
    ));
}
