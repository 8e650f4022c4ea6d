//! The bed cache from the command line: a second shake of the same scene and
//! seed reads the settled bed instead of settling it, and measures the same
//! numbers; a damaged entry is rebuilt with a warning; `vlab cache` lists and
//! clears it.

#![cfg(all(feature = "cli", feature = "plot"))]

use crate::common;

use common::{Scratch, TIMING_KEYS, json, run_summary, small_scene, stderr, vlab, without_keys};

fn shake(dir: &Scratch, out: &str, extra: &[&str]) -> std::process::Output {
    let mut args = vec![
        "--quiet",
        "shake",
        "--beds",
        "1",
        "--scene",
        "small.toml",
        "--freq",
        "40",
        "--gamma",
        "10",
        "--rig",
        "ideal",
    ];
    args.extend_from_slice(extra);
    run_summary(dir, &args, out).0
}

/// The summary without what depends on the machine or on where the bed came from.
fn physics(dir: &Scratch, out: &str) -> serde_json::Value {
    let s = json(&dir.path(&format!("{out}/summary.json")));
    let s = without_keys(s, &TIMING_KEYS);
    without_keys(s, &["bed_from_cache"])
}

fn list(dir: &Scratch) -> String {
    let o = vlab(&dir.0, &["cache", "list"]);
    assert!(o.status.success(), "{}", stderr(&o));
    String::from_utf8_lossy(&o.stdout).into_owned()
}

#[test]
fn a_cached_bed_gives_the_same_run_and_a_damaged_one_is_rebuilt() {
    let dir = Scratch::new("cache");
    dir.write("small.toml", &small_scene(3, 2, ""));
    let cache = dir.path(".vlab-cache");

    // --no-cache neither reads nor writes the cache.
    shake(&dir, "plain", &["--no-cache"]);
    assert!(list(&dir).contains("no cached beds"), "{}", list(&dir));

    shake(&dir, "cold", &[]);
    let cold = json(&dir.path("cold/summary.json"));
    assert_eq!(cold["bed_from_cache"], false);
    let listed = list(&dir);
    assert!(
        listed.contains("1 cached beds") && listed.contains("150 particles"),
        "{listed}"
    );

    let warm_out = shake(&dir, "warm", &[]);
    let warm = json(&dir.path("warm/summary.json"));
    assert_eq!(warm["bed_from_cache"], true);
    // No word about the cache (--quiet still prints the run's own warnings,
    // such as this short drive's unsteadiness).
    let err = stderr(&warm_out);
    assert!(
        err.lines()
            .all(|l| !l.contains("cache") && !l.contains("was not used")),
        "{err}"
    );
    assert_eq!(physics(&dir, "cold"), physics(&dir, "warm"));
    assert_eq!(physics(&dir, "plain"), physics(&dir, "warm"));
    let read = |out: &str| std::fs::read(dir.path(&format!("{out}/kinematics.csv"))).expect("csv");
    assert!(read("cold") == read("warm"), "kinematics differ");

    // Damage the entry: the run warns, settles anew, and keeps the new bed.
    let entry = std::fs::read_dir(&cache)
        .expect("cache folder")
        .filter_map(Result::ok)
        .map(|e| e.path())
        .find(|p| p.extension().is_some_and(|x| x == "vbed"))
        .expect("a bed file");
    let mut bytes = std::fs::read(&entry).expect("read");
    let mid = bytes.len() / 2;
    bytes[mid] ^= 0xff;
    std::fs::write(&entry, &bytes).expect("damage");
    assert!(list(&dir).contains("unreadable"), "{}", list(&dir));
    let o = vlab(
        &dir.0,
        &[
            "shake",
            "--beds",
            "1",
            "--scene",
            "small.toml",
            "--freq",
            "40",
            "--gamma",
            "10",
            "--rig",
            "ideal",
            "--out",
            "rebuilt",
        ],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let err = stderr(&o);
    assert!(
        err.contains("was not used") && err.contains("checksum"),
        "{err}"
    );
    let rebuilt = json(&dir.path("rebuilt/summary.json"));
    assert_eq!(rebuilt["bed_from_cache"], false);
    assert!(rebuilt["warnings"].to_string().contains("was not used"));
    assert_eq!(
        physics(&dir, "cold")["dem"],
        physics(&dir, "rebuilt")["dem"]
    );
    assert!(!list(&dir).contains("unreadable"));

    let o = vlab(&dir.0, &["cache", "path"]);
    assert_eq!(
        String::from_utf8_lossy(&o.stdout).trim(),
        cache.display().to_string()
    );
    let o = vlab(&dir.0, &["cache", "clear"]);
    assert!(String::from_utf8_lossy(&o.stdout).contains("removed 1 cached beds"));
    assert!(list(&dir).contains("no cached beds"));
}
