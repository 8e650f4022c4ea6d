//! The figures under `docs/` cannot go stale: each is redrawn by the
//! command its page names, from the data kept in the repository where the
//! run behind it takes minutes, and compared with the file the page shows,
//! byte for byte; and every image under `docs/` must be one of them, so a
//! figure cannot be added without a test that redraws it.
//!
//! The redraws here take a second in all. The figures the pages' own
//! commands draw as they run are compared in `tests/suite/docs.rs`, which runs
//! those commands anyway: the maps (`the_maps_figures_are_what_their_command_draws`),
//! the snapshots (`readme_and_tutorial_commands_run`) and the host's decays and
//! dashpot receptance (`host_chapter_commands_run`).

#![cfg(all(feature = "cli", feature = "plot"))]

use crate::common;

use std::path::{Path, PathBuf};

use common::Scratch;

/// The repository's root.
fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// Every image under `docs/` and the test that redraws it.
const REDRAWN: &[(&str, &str)] = &[
    (
        "docs/figures/browser-lab.png",
        "browser_lab.rs: the_browser_lab_runs_a_shake_and_agrees_with_the_cli",
    ),
    (
        "docs/figures/efficiency.png",
        "docs.rs: the_maps_figures_are_what_their_command_draws",
    ),
    (
        "docs/figures/efficiency.svg",
        "docs.rs: the_maps_figures_are_what_their_command_draws",
    ),
    (
        "docs/figures/map.png",
        "docs.rs: the_maps_figures_are_what_their_command_draws",
    ),
    (
        "docs/figures/map.svg",
        "docs.rs: the_maps_figures_are_what_their_command_draws",
    ),
    (
        "docs/figures/snapshots.png",
        "docs.rs: readme_and_tutorial_commands_run",
    ),
    (
        "docs/figures/snapshots.svg",
        "docs.rs: readme_and_tutorial_commands_run",
    ),
    (
        "docs/figures/host-dashpot-loss-factor.svg",
        "docs.rs: host_chapter_commands_run",
    ),
    (
        "docs/figures/host-dashpot-frf.svg",
        "docs.rs: host_chapter_commands_run",
    ),
    (
        "docs/figures/host-loss-factor.svg",
        "docs.rs: host_chapter_commands_run",
    ),
    (
        "docs/figures/host-frf-magnitude.svg",
        "figures.rs: the_host_receptance_is_redrawn_from_its_kept_run",
    ),
    (
        "docs/figures/accuracy/accuracy.svg",
        "figures.rs: the_accuracy_figures_are_redrawn_from_their_kept_run",
    ),
    (
        "docs/figures/accuracy/accuracy.png",
        "figures.rs: the_accuracy_figures_are_redrawn_from_their_kept_run",
    ),
    (
        "docs/figures/accuracy/impact.svg",
        "figures.rs: the_accuracy_figures_are_redrawn_from_their_kept_run",
    ),
    (
        "docs/figures/accuracy/impact.png",
        "figures.rs: the_accuracy_figures_are_redrawn_from_their_kept_run",
    ),
    (
        "docs/figures/accuracy/yang.svg",
        "figures.rs: the_accuracy_figures_are_redrawn_from_their_kept_run",
    ),
    (
        "docs/figures/accuracy/yang.png",
        "figures.rs: the_accuracy_figures_are_redrawn_from_their_kept_run",
    ),
    (
        "docs/figures/shape-optimum.png",
        "figures.rs: the_shape_optimum_is_redrawn_from_the_study_sweeps",
    ),
    (
        "docs/figures/shear-box-prolates.png",
        "figures.rs: the_shear_box_figures_are_redrawn_from_their_kept_runs",
    ),
    (
        "docs/figures/shear-box-toroids.png",
        "figures.rs: the_shear_box_figures_are_redrawn_from_their_kept_runs",
    ),
    (
        "docs/figures/shape-optimum.svg",
        "figures.rs: the_shape_optimum_is_redrawn_from_the_study_sweeps",
    ),
];

/// Images under `docs/` no test redraws yet, each with the reason; the
/// list may only shrink (it is empty: every figure is redrawn).
const NOT_YET_REDRAWN: &[(&str, &str)] = &[];

/// Runs the test build's `vlab` with `args` in `cwd`; its standard output.
fn vlab_in(cwd: &Path, args: &[&str]) -> String {
    let out = common::vlab(cwd, args);
    assert!(
        out.status.success(),
        "vlab {} failed:\n{}",
        args.join(" "),
        common::stderr(&out)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

#[test]
fn the_accuracy_figures_are_redrawn_from_their_kept_run() {
    let dir = Scratch::new("figures-accuracy");
    let csv = root().join("signals/reference/accuracy-40Hz-G20/accuracy.csv");
    vlab_in(&dir.0, &["plot", &csv.to_string_lossy(), "--out", "drawn"]);
    for name in [
        "accuracy.svg",
        "accuracy.png",
        "impact.svg",
        "impact.png",
        "yang.svg",
        "yang.png",
    ] {
        common::same_figure(
            &dir.path(&format!("drawn/{name}")),
            &format!("docs/figures/accuracy/{name}"),
            "vlab plot signals/reference/accuracy-40Hz-G20/accuracy.csv --out docs/figures/accuracy",
        );
    }
}

#[test]
fn the_host_receptance_is_redrawn_from_its_kept_run() {
    let dir = Scratch::new("figures-host-frf");
    let csv = root().join("signals/reference/host-frf/frf.csv");
    vlab_in(&dir.0, &["plot", &csv.to_string_lossy(), "--out", "drawn"]);
    common::same_figure(
        &dir.path("drawn/frf-magnitude.svg"),
        "docs/figures/host-frf-magnitude.svg",
        "vlab plot signals/reference/host-frf/frf.csv --out host/frf-figure; cp host/frf-figure/frf-magnitude.svg docs/figures/host-frf-magnitude.svg",
    );
}

#[test]
fn the_shear_box_figures_are_redrawn_from_their_kept_runs() {
    let dir = Scratch::new("figures-shear-box");
    for shapes in ["prolates", "toroids"] {
        let json = root().join(format!(
            "signals/reference/shear-box-{shapes}/shear_box.json"
        ));
        let out = format!("drawn-{shapes}");
        vlab_in(&dir.0, &["plot", &json.to_string_lossy(), "--out", &out]);
        common::same_figure(
            &dir.path(&format!("{out}/shear.png")),
            &format!("docs/figures/shear-box-{shapes}.png"),
            &format!(
                "vlab plot signals/reference/shear-box-{shapes}/shear_box.json --out box; cp box/shear.png docs/figures/shear-box-{shapes}.png"
            ),
        );
    }
}

#[test]
fn the_shape_optimum_is_redrawn_from_the_study_sweeps() {
    let dir = Scratch::new("figures-shape-optimum");
    let study = root().join("docs/shape-study");
    let out = dir.path("optimum");
    let out = out.to_string_lossy();
    // The command of docs/shape-study/README.md, run in that folder.
    let readme = std::fs::read_to_string(study.join("README.md")).expect("README");
    let command: String = readme
        .split("```sh\n")
        .nth(1)
        .and_then(|b| b.split("```").next())
        .expect("the README's command")
        .replace("\\\n", " ");
    let args: Vec<&str> = command.split_whitespace().collect();
    assert_eq!(args[..3], ["vlab", "sweep", "optimum"], "{command}");
    let mut args: Vec<String> = unquoted(&args[1..]);
    let k = args.iter().position(|a| a == "--out").expect("--out");
    args[k + 1] = out.to_string();
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    vlab_in(&study, &args);
    for ext in ["png", "svg"] {
        common::same_figure(
            &dir.path(&format!("optimum/optimum.{ext}")),
            &format!("docs/figures/shape-optimum.{ext}"),
            "the command of docs/shape-study/README.md in that folder, then cp optimum/optimum.png optimum/optimum.svg as docs/figures/shape-optimum.png and .svg",
        );
    }
}

/// Shell words joined back where a double-quoted argument was split.
fn unquoted(words: &[&str]) -> Vec<String> {
    let mut out: Vec<String> = Vec::new();
    let mut open = false;
    for w in words {
        if open {
            let last = out.last_mut().expect("an open quote");
            last.push(' ');
            last.push_str(w.trim_end_matches('"'));
            open = !w.ends_with('"');
        } else if let Some(rest) = w.strip_prefix('"') {
            open = !rest.ends_with('"');
            out.push(rest.trim_end_matches('"').to_string());
        } else {
            out.push(w.to_string());
        }
    }
    out
}

/// Every file below `dir` whose extension is an image's.
fn images_below(dir: &Path) -> Vec<PathBuf> {
    let image = |p: &Path| {
        p.extension().and_then(|e| e.to_str()).is_some_and(|e| {
            ["png", "svg", "jpg", "jpeg", "gif", "webp"].contains(&e.to_ascii_lowercase().as_str())
        })
    };
    common::files_below(dir)
        .into_iter()
        .filter(|p| image(p))
        .collect()
}

#[test]
fn every_image_under_docs_is_redrawn_by_a_test() {
    let mut unlisted = Vec::new();
    let mut found = Vec::new();
    for path in images_below(&root().join("docs")) {
        let name = path
            .strip_prefix(root())
            .expect("below the root")
            .to_string_lossy()
            .replace('\\', "/");
        let listed = REDRAWN
            .iter()
            .chain(NOT_YET_REDRAWN)
            .any(|(f, _)| *f == name);
        if !listed {
            unlisted.push(name.clone());
        }
        found.push(name);
    }
    assert!(
        unlisted.is_empty(),
        "images under docs/ that no test redraws: {unlisted:?}; make each with a documented command and add a test that redraws it and compares it with the file (tests/suite/figures.rs), then list it in REDRAWN"
    );
    let gone: Vec<&str> = REDRAWN
        .iter()
        .chain(NOT_YET_REDRAWN)
        .map(|(f, _)| *f)
        .filter(|f| !found.iter().any(|n| n == f))
        .collect();
    assert!(gone.is_empty(), "listed but not under docs/: {gone:?}");
    // Each test named for a figure is one that exists.
    for (figure, test) in REDRAWN {
        let (file, name) = test.split_once(": ").expect("file: test");
        let text = std::fs::read_to_string(root().join("tests/suite").join(file))
            .unwrap_or_else(|e| panic!("{figure}: tests/suite/{file}: {e}"));
        assert!(
            text.contains(&format!("fn {name}()")),
            "{figure}: no test {name} in tests/suite/{file}"
        );
    }
}
