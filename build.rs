//! The physics fingerprint of the settled-bed cache (`src/experiment/bed/cache.rs`).
//!
//! A settled bed's bits depend on the code that settles it, not only on the
//! scene: a change of the contact law, the integrator, the neighbour search,
//! the filling or the settling schedule moves every particle. This script
//! hashes everything that shapes those bits and hands the hash to the crate
//! as `VLAB_PHYSICS_FINGERPRINT`, which the bed cache puts in its key, so a
//! bed settled by other code is never read back:
//!
//! - the sources: every file below `src/dem/`, `src/scene/` and
//!   `src/experiment/bed/` (filling, settling and the cache itself), and
//!   `src/experiment/damper.rs` (the contact laws and gravity that settling
//!   uses) and `src/maths.rs` (the transcendental functions), by their path
//!   relative to
//!   the package (with `/`) and their bytes, in sorted order;
//! - the versions of the crates whose arithmetic or random numbers reach the
//!   bed (`glam`, `libm`, `rand_core`, `rand_xoshiro`), from `Cargo.lock`;
//! - the compiler facts that can change a floating-point result: the rustc
//!   version, the target triple, its enabled target features and the
//!   optimisation level (`powi` is expanded into multiplications when
//!   optimised and is a library call when not, which can differ in the last
//!   bit).
//!
//! The hash is FNV-1a 64 over those bytes, each item preceded by its length,
//! written as 16 hex digits. Any edit of a hashed file changes it, a
//! comment-only edit included: beds are then settled anew once. That is the
//! price of never reading a stale bed.

use std::fs;
use std::path::{Path, PathBuf};
use std::process::Command;

/// Folders whose every file is hashed.
const HASHED_DIRS: [&str; 3] = ["src/dem", "src/scene", "src/experiment/bed"];
/// Single files that are hashed.
const HASHED_FILES: [&str; 2] = ["src/experiment/damper.rs", "src/maths.rs"];
/// Dependencies whose code computes a bed's numbers.
const HASHED_CRATES: [&str; 4] = ["glam", "libm", "rand_core", "rand_xoshiro"];

/// FNV-1a, 64 bits, fed piece by piece.
struct Fnv1a(u64);

impl Fnv1a {
    fn new() -> Self {
        Fnv1a(0xcbf2_9ce4_8422_2325)
    }

    fn bytes(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 ^= u64::from(b);
            self.0 = self.0.wrapping_mul(0x0100_0000_01b3);
        }
    }

    /// One item: its length, then its bytes (so items cannot run together).
    fn item(&mut self, bytes: &[u8]) {
        self.bytes(&(bytes.len() as u64).to_le_bytes());
        self.bytes(bytes);
    }
}

/// Every file below `dir`, recursively.
fn files_below(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(entries) = fs::read_dir(dir) else {
        return;
    };
    for entry in entries.flatten() {
        let path = entry.path();
        if path.is_dir() {
            files_below(&path, out);
        } else {
            out.push(path);
        }
    }
}

/// `name = "x"` followed by `version = "y"` in Cargo.lock: the version of `name`.
fn locked_versions(lock: &str, name: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut lines = lock.lines();
    while let Some(line) = lines.next() {
        if line.trim() == format!("name = \"{name}\"")
            && let Some(v) = lines.next()
        {
            out.push(v.trim().to_string());
        }
    }
    out
}

fn main() {
    let root = PathBuf::from(std::env::var("CARGO_MANIFEST_DIR").unwrap_or_else(|_| ".".into()));
    let mut files: Vec<PathBuf> = HASHED_FILES.iter().map(|f| root.join(f)).collect();
    for dir in HASHED_DIRS {
        files_below(&root.join(dir), &mut files);
        println!("cargo:rerun-if-changed={dir}");
    }
    for f in HASHED_FILES {
        println!("cargo:rerun-if-changed={f}");
    }
    println!("cargo:rerun-if-changed=Cargo.lock");
    println!("cargo:rerun-if-changed=build.rs");
    let mut named: Vec<(String, PathBuf)> = files
        .into_iter()
        .map(|p| {
            let rel = p.strip_prefix(&root).unwrap_or(&p);
            let rel = rel
                .components()
                .map(|c| c.as_os_str().to_string_lossy().into_owned())
                .collect::<Vec<_>>()
                .join("/");
            (rel, p)
        })
        .collect();
    named.sort();
    let mut h = Fnv1a::new();
    for (rel, path) in &named {
        h.item(rel.as_bytes());
        // A file that cannot be read is hashed as missing (its name alone).
        h.item(&fs::read(path).unwrap_or_default());
    }
    let lock = fs::read_to_string(root.join("Cargo.lock")).unwrap_or_default();
    for name in HASHED_CRATES {
        h.item(name.as_bytes());
        for v in locked_versions(&lock, name) {
            h.item(v.as_bytes());
        }
    }
    let rustc = std::env::var("RUSTC").unwrap_or_else(|_| "rustc".into());
    let rustc_version = Command::new(rustc)
        .arg("-V")
        .output()
        .map(|o| String::from_utf8_lossy(&o.stdout).trim().to_string())
        .unwrap_or_default();
    h.item(rustc_version.as_bytes());
    for var in ["TARGET", "CARGO_CFG_TARGET_FEATURE", "OPT_LEVEL"] {
        h.item(var.as_bytes());
        h.item(std::env::var(var).unwrap_or_default().as_bytes());
    }
    println!("cargo:rustc-env=VLAB_PHYSICS_FINGERPRINT={:016x}", h.0);
}
