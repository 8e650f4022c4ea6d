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

/// A small, quick damper (150 spheres of the thesis scene, settled for
/// 0.02 s) driven `cycles` cycles of which the last `steady_cycles` are kept;
/// `simulation` is more lines of its `[simulation]` table (or empty).
pub fn small_scene(cycles: u32, steady_cycles: u32, simulation: &str) -> String {
    format!(
        "\n[particles]\ncount = 150\n[simulation]\nsettle_s = 0.02\n{simulation}\
         [drive]\ncycles = {cycles}\nsteady_cycles = {steady_cycles}\n"
    )
}

/// A tiny scene (30 spheres, 4 cycles) on which a sweep's mechanics take
/// seconds.
pub const TINY_SCENE: &str = r#"
name = "tiny"
[particles]
count = 30
[enclosure]
inner_diameter_m = 0.02
inner_length_m = 0.03
[simulation]
dt_s = 4e-6
settle_s = 0.05
[drive]
cycles = 4
steady_cycles = 2
"#;

/// Runs `vlab ARGS --out OUT` in `dir`, which must succeed, and returns the
/// run's output and its `OUT/summary.json`.
pub fn run_summary(dir: &Scratch, args: &[&str], out: &str) -> (Output, serde_json::Value) {
    let mut all = args.to_vec();
    all.extend(["--out", out]);
    let o = vlab(&dir.0, &all);
    assert!(o.status.success(), "{all:?}: {}", stderr(&o));
    let summary = json(&dir.path(&format!("{out}/summary.json")));
    (o, summary)
}

/// The wall-clock keys of a shake's `summary.json` (they differ between two
/// runs of the same physics).
pub const TIMING_KEYS: [&str; 5] = [
    "wall_time_s",
    "particle_steps_per_s",
    "settle_wall_time_s",
    "rig_wall_time_s",
    "threads",
];

/// `summary` without `keys`, each of which it must have.
pub fn without_keys(mut summary: serde_json::Value, keys: &[&str]) -> serde_json::Value {
    let obj = summary.as_object_mut().expect("a JSON object");
    for key in keys {
        assert!(obj.remove(*key).is_some(), "{key} missing");
    }
    summary
}

/// Fails unless the file `drawn` equals the repository's `shown` (a path
/// from its root) byte for byte, naming the command that redraws it.
pub fn same_figure(drawn: &Path, shown: &str, redraw: &str) {
    let drawn = std::fs::read(drawn).unwrap_or_else(|e| panic!("{}: {e}", drawn.display()));
    let kept = std::fs::read(Path::new(env!("CARGO_MANIFEST_DIR")).join(shown))
        .unwrap_or_else(|e| panic!("{shown}: {e}"));
    assert!(
        drawn == kept,
        "{shown} is not what its command draws now: redraw it with `{redraw}`"
    );
}
