//! The documentation cannot rot: the `vlab` commands of `docs/tutorial.md` and
//! of `README.md` run, every relative link of `README.md` and `docs/*.md`
//! points to a file (and heading) that exists, and CI runs the test command
//! the README gives. Command lines marked `# takes minutes` are skipped.

#![cfg(all(feature = "cli", feature = "plot"))]

mod common;

use std::collections::HashSet;
use std::path::{Path, PathBuf};
use std::process::Command;

use common::Scratch;

/// The repository's root.
fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// Text of the repository file `name`.
fn read(name: &str) -> String {
    std::fs::read_to_string(root().join(name)).unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// The lines of the fenced blocks tagged `sh` in `text`.
fn sh_lines(text: &str) -> Vec<&str> {
    let mut in_block = false;
    let mut lines = Vec::new();
    for line in text.lines() {
        if line.starts_with("```") {
            in_block = line == "```sh";
            continue;
        }
        if in_block {
            lines.push(line);
        }
    }
    lines
}

/// The `vlab ...` command lines of the `sh` blocks of `text`, without the
/// ones marked `# takes minutes`.
fn vlab_commands(text: &str) -> Vec<String> {
    sh_lines(text)
        .into_iter()
        .filter(|l| l.starts_with("vlab ") && !l.contains("# takes minutes"))
        .map(str::to_string)
        .collect()
}

/// Runs `commands` in order with `sh` in a scratch folder that holds a copy of
/// the reference records (as a reader's checkout does), the test build's
/// `vlab` first on the `PATH` and a scratch cache of settled beds.
fn run_in_order(tag: &str, doc: &str, commands: &[String]) -> Scratch {
    let bin_dir = Path::new(env!("CARGO_BIN_EXE_vlab"))
        .parent()
        .expect("binary folder")
        .to_path_buf();
    let path = format!(
        "{}:{}",
        bin_dir.display(),
        std::env::var("PATH").unwrap_or_default()
    );
    let dir = Scratch::new(tag);
    copy_dir(
        &root().join("signals/reference"),
        &dir.path("signals/reference"),
    );
    for cmd in commands {
        let out = Command::new("sh")
            .args(["-c", &format!("set -e; {cmd}")])
            .env("PATH", &path)
            .env("VLAB_CACHE_DIR", dir.path(".vlab-cache"))
            .current_dir(&dir.0)
            .output()
            .expect("run sh");
        assert!(
            out.status.success(),
            "{doc} command failed: {cmd}\n{}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
    dir
}

#[test]
fn tutorial_commands_run() {
    let commands = vlab_commands(&read("docs/tutorial.md"));
    assert!(
        commands.len() >= 10,
        "found only {} commands",
        commands.len()
    );
    let dir = run_in_order("tutorial", "tutorial", &commands);
    // Step 7's claim: the mis-calibrated rig reads off, the right one does not.
    let read = |p: &str| -> serde_json::Value {
        serde_json::from_str(&std::fs::read_to_string(dir.path(p)).expect(p)).expect("json")
    };
    let good = read("run/summary.json")["measured"]["error_vs_dem_rel"]
        .as_f64()
        .expect("error");
    let wrong = read("wrong/summary.json")["measured"]["error_vs_dem_rel"]
        .as_f64()
        .expect("error");
    assert!(good.abs() < 0.01, "calibrated run off by {good}");
    assert!(wrong.abs() > 0.02, "mis-calibrated run only off by {wrong}");
}

#[test]
fn readme_commands_run() {
    let text = read("README.md");
    let commands = vlab_commands(&text);
    assert!(
        commands.len() >= 4,
        "found only {} commands: {commands:?}",
        commands.len()
    );
    let dir = run_in_order("readme", "README", &commands);
    // The sample output's run wrote where the README says it did.
    assert!(
        text.contains("wrote signals/thesis-40Hz-G20"),
        "README's sample output no longer names its folder"
    );
    assert!(
        dir.path("signals/thesis-40Hz-G20/summary.json").is_file(),
        "the README's shake wrote no signals/thesis-40Hz-G20/summary.json"
    );
}

#[test]
fn ci_runs_the_readme_test_command() {
    let readme = read("README.md");
    let ci = read(".ci/run");
    let readme_cargo: Vec<&str> = sh_lines(&readme)
        .into_iter()
        .filter(|l| l.starts_with("cargo test"))
        .collect();
    let ci_cargo: Vec<&str> = ci.lines().filter(|l| l.starts_with("cargo ")).collect();
    assert_eq!(
        readme_cargo,
        vec!["cargo test --workspace"],
        "the README gives one test command, for vlab and the browser lab's crate"
    );
    assert_eq!(ci_cargo, readme_cargo, ".ci/run and the README disagree");
}

#[test]
fn relative_links_resolve() {
    let mut files = vec![root().join("README.md")];
    for entry in std::fs::read_dir(root().join("docs")).expect("docs/") {
        let path = entry.expect("entry").path();
        if path.extension().is_some_and(|e| e == "md") {
            files.push(path);
        }
    }
    assert!(
        files.len() >= 10,
        "found only {} Markdown files",
        files.len()
    );
    let mut broken = Vec::new();
    let mut checked = 0;
    for file in &files {
        let text = std::fs::read_to_string(file).expect("read Markdown");
        for target in link_targets(&text) {
            if target.contains("://") || target.starts_with("mailto:") {
                continue;
            }
            checked += 1;
            let (path_part, anchor) = match target.split_once('#') {
                Some((p, a)) => (p, Some(a)),
                None => (target.as_str(), None),
            };
            let linked: PathBuf = if path_part.is_empty() {
                file.clone()
            } else {
                file.parent().expect("folder").join(path_part)
            };
            let name = file.strip_prefix(root()).unwrap_or(file).display();
            if !linked.exists() {
                broken.push(format!("{name}: {target} (no such file)"));
                continue;
            }
            if let Some(anchor) = anchor {
                let is_md = linked.extension().is_some_and(|e| e == "md");
                let linked_text = std::fs::read_to_string(&linked).unwrap_or_default();
                if is_md && !heading_anchors(&linked_text).contains(anchor) {
                    broken.push(format!("{name}: {target} (no such heading)"));
                }
            }
        }
    }
    assert!(checked >= 20, "checked only {checked} links");
    assert!(broken.is_empty(), "broken links:\n{}", broken.join("\n"));
}

/// The targets of the inline links and images of `text`, outside fenced
/// blocks and code spans.
fn link_targets(text: &str) -> Vec<String> {
    let mut targets = Vec::new();
    let mut in_fence = false;
    for line in text.lines() {
        if line.trim_start().starts_with("```") {
            in_fence = !in_fence;
            continue;
        }
        if in_fence {
            continue;
        }
        let prose = without_code_spans(line);
        let mut rest = prose.as_str();
        while let Some(i) = rest.find("](") {
            let after = &rest[i + 2..];
            let Some(end) = after.find(')') else { break };
            targets.push(after[..end].trim().to_string());
            rest = &after[end..];
        }
    }
    targets
}

/// `line` with its `code spans` removed.
fn without_code_spans(line: &str) -> String {
    line.split('`').step_by(2).collect::<Vec<_>>().join("")
}

/// The anchors the forge gives the headings of `text`: lower case, code
/// marks and punctuation dropped, spaces as hyphens.
fn heading_anchors(text: &str) -> HashSet<String> {
    let mut anchors = HashSet::new();
    let mut in_fence = false;
    for line in text.lines() {
        if line.trim_start().starts_with("```") {
            in_fence = !in_fence;
            continue;
        }
        if in_fence || !line.starts_with('#') {
            continue;
        }
        let title = line.trim_start_matches('#').trim();
        let anchor: String = title
            .to_lowercase()
            .chars()
            .filter(|c| c.is_alphanumeric() || *c == ' ' || *c == '-' || *c == '_')
            .map(|c| if c == ' ' { '-' } else { c })
            .collect();
        anchors.insert(anchor);
    }
    anchors
}

#[test]
fn anchors_follow_the_forge() {
    let anchors = heading_anchors(
        "# Maps: where, and why\n## The drop test: `vlab drop`\n```sh\n# not a heading\n```\n",
    );
    assert!(anchors.contains("maps-where-and-why"), "{anchors:?}");
    assert!(anchors.contains("the-drop-test-vlab-drop"), "{anchors:?}");
    assert_eq!(anchors.len(), 2, "{anchors:?}");
    assert_eq!(
        link_targets("see [a](b.md#c) and `[x](not-a-link)` and ![f](g.png)"),
        vec!["b.md#c", "g.png"]
    );
}

/// Copies the folder `from` to `to`, recursively.
fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).expect("create folder");
    for entry in std::fs::read_dir(from).expect("read folder") {
        let path = entry.expect("entry").path();
        let target = to.join(path.file_name().expect("name"));
        if path.is_dir() {
            copy_dir(&path, &target);
        } else {
            std::fs::copy(&path, &target).expect("copy");
        }
    }
}
