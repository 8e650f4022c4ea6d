//! Helpers for the end-to-end tests of the `vlab` binary.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::sync::atomic::{AtomicUsize, Ordering};

static NEXT: AtomicUsize = AtomicUsize::new(0);

/// A scratch folder removed when dropped.
pub struct Scratch(pub PathBuf);

impl Scratch {
    pub fn new(tag: &str) -> Self {
        let n = NEXT.fetch_add(1, Ordering::Relaxed);
        let dir = std::env::temp_dir().join(format!("vlab-test-{tag}-{}-{n}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).expect("scratch dir");
        Scratch(dir)
    }

    pub fn path(&self, name: &str) -> PathBuf {
        self.0.join(name)
    }

    pub fn write(&self, name: &str, text: &str) -> PathBuf {
        let p = self.path(name);
        std::fs::write(&p, text).expect("write scratch file");
        p
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// Runs `vlab` with `args` in folder `cwd`.
pub fn vlab(cwd: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_vlab"))
        .args(args)
        .current_dir(cwd)
        // Settled beds go to the test's own scratch folder, never the user's cache.
        .env("VLAB_CACHE_DIR", cwd.join(".vlab-cache"))
        .output()
        .expect("run vlab")
}

/// Standard error as text.
pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Parses a JSON file.
pub fn json(path: &Path) -> serde_json::Value {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    serde_json::from_str(&text).expect("valid JSON")
}

/// Every file below `dir`, recursively.
pub fn files_below(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    if let Ok(entries) = std::fs::read_dir(dir) {
        for e in entries.flatten() {
            let p = e.path();
            if p.is_dir() {
                out.extend(files_below(&p));
            } else {
                out.push(p);
            }
        }
    }
    out
}

/// Runs `args` in `dir` and checks the refusal: a non-zero exit, a first line of
/// standard error that starts with `error:` and mentions every word of
/// `must_mention`, and no new file in `dir`. Returns that line.
pub fn refuses_in(dir: &Scratch, args: &[&str], must_mention: &[&str]) -> String {
    let before = files_below(&dir.0);
    let out = vlab(&dir.0, args);
    assert!(!out.status.success(), "{args:?} should fail");
    let err = stderr(&out);
    let first = err.lines().next().unwrap_or("").to_string();
    assert!(first.starts_with("error:"), "{args:?}: {err}");
    for word in must_mention {
        assert!(
            first.contains(word),
            "{args:?}: '{first}' does not mention '{word}'"
        );
    }
    assert_eq!(files_below(&dir.0), before, "{args:?} wrote files");
    first
}
