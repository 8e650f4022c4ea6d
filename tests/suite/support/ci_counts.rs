//! What the tests beyond Rust ran, for .ci/run to show: each such test (the
//! Python package's, the notebooks', the browser lab's) adds a line to
//! target/tmp/beyond-rust.txt, so the CI log holds their counts and not
//! only a pass.

use std::io::Write;
use std::path::Path;

/// Adds `line` to target/tmp/beyond-rust.txt (a failure to is said, not
/// fatal: the test itself passed).
pub fn tell_ci(line: &str) {
    let path = Path::new(env!("CARGO_TARGET_TMPDIR")).join("beyond-rust.txt");
    let written = std::fs::OpenOptions::new()
        .create(true)
        .append(true)
        .open(&path)
        .and_then(|mut f| writeln!(f, "{line}"));
    if let Err(e) = written {
        eprintln!("cannot add to {}: {e}", path.display());
    }
}
