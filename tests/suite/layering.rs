//! The layout's rules, checked on the source: the library's folders form a
//! ladder (cli -> study -> export -> experiment -> scene -> host -> rig ->
//! signals, dem, shape -> the crate-root utilities), no file imports a folder
//! above its own or beside it on its rung, the boundaries docs/design.md
//! names hold (`rig` and `host` never import `dem`: they see the damper only
//! as a force), and inside a folder the files import each other without a
//! loop (docs/design.md, "Layers"). Imports are read as text: every
//! `crate::a::b` path in a file (in `use` lines and in expressions) and
//! every `super::b`. The binary's `src/cli/`, on the top rung, may import
//! any folder; its files are checked for loops only.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

/// The library's folders from the top of the ladder down; a folder may import
/// those at a lower rung only. `signals`, `dem` and `shape` share a rung and
/// must not import each other; the crate-root files (utilities) are the
/// bottom rung.
const LADDER: &[&[&str]] = &[
    &["study"],
    &["export"],
    &["experiment"],
    &["scene"],
    &["host"],
    &["rig"],
    &["signals", "dem", "shape"],
];

/// Imports the ladder allows but the design forbids: (importer, imported).
/// The rig and the host see the damper only as a force on the enclosure,
/// whichever code computed it (what lets `vlab replay` feed another DEM
/// code's record through the rig).
const BOUNDARIES: &[(&str, &str)] = &[("rig", "dem"), ("host", "dem")];

fn rung(module: &str) -> usize {
    LADDER
        .iter()
        .position(|r| r.contains(&module))
        .unwrap_or(LADDER.len())
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).expect("read src") {
        let path = entry.expect("entry").path();
        if path.is_dir() {
            rust_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

/// The module path of a source file relative to `src/`: `dem/step/books.rs`
/// is `["dem", "step", "books"]`, `dem/mod.rs` is `["dem"]`.
fn module_of(rel: &Path) -> Vec<String> {
    let mut parts: Vec<String> = rel
        .iter()
        .map(|p| p.to_string_lossy().trim_end_matches(".rs").to_string())
        .collect();
    if parts.last().is_some_and(|p| p == "mod") {
        parts.pop();
    }
    parts
}

/// The identifier at the start of `s` and the text after it.
fn ident(s: &str) -> (&str, &str) {
    let end = s
        .find(|c: char| !(c.is_alphanumeric() || c == '_'))
        .unwrap_or(s.len());
    (&s[..end], &s[end..])
}

/// The paths a `use` tree or an expression path starting at `s` names, as
/// segments: `a::b::c` is one, `a::{b::c, d}` is `a::b::c` and `a::d`.
fn expand(s: &str) -> Vec<Vec<String>> {
    let (head, rest) = ident(s);
    if head.is_empty() {
        return Vec::new();
    }
    let Some(after) = rest.strip_prefix("::") else {
        return vec![vec![head.to_string()]];
    };
    let tails = if let Some(group) = after.strip_prefix('{') {
        let mut depth = 1;
        let mut items = Vec::new();
        let mut start = 0;
        for (i, c) in group.char_indices() {
            match c {
                '{' => depth += 1,
                '}' => {
                    depth -= 1;
                    if depth == 0 {
                        items.push(&group[start..i]);
                        break;
                    }
                }
                ',' if depth == 1 => {
                    items.push(&group[start..i]);
                    start = i + 1;
                }
                _ => {}
            }
        }
        items
            .iter()
            .flat_map(|item| expand(item.trim_start()))
            .collect()
    } else {
        expand(after)
    };
    if tails.is_empty() {
        return vec![vec![head.to_string()]];
    }
    tails
        .into_iter()
        .map(|mut t| {
            t.insert(0, head.to_string());
            t
        })
        .collect()
}

/// Every `prefix::a::b...` path in `text`, as its segments after the prefix.
fn paths_after(text: &str, prefix: &str) -> Vec<Vec<String>> {
    let mut out = Vec::new();
    let mut rest = text;
    while let Some(i) = rest.find(prefix) {
        let before_ok = rest[..i]
            .chars()
            .last()
            .is_none_or(|c| !(c.is_alphanumeric() || c == '_'));
        rest = &rest[i + prefix.len()..];
        if before_ok {
            out.extend(expand(rest));
        }
    }
    out
}

/// Lines of code only: comments (which may cite a module) left out.
fn code_of(text: &str) -> String {
    text.lines()
        .filter(|l| !l.trim_start().starts_with("//"))
        .collect::<Vec<_>>()
        .join("\n")
}

struct Source {
    module: Vec<String>,
    code: String,
}

fn sources() -> Vec<Source> {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    files.sort();
    files
        .iter()
        .map(|f| Source {
            module: module_of(f.strip_prefix(&src).expect("under src")),
            code: code_of(&std::fs::read_to_string(f).expect("read")),
        })
        .collect()
}

/// Every import in `sources` up the ladder, beside its importer on a rung,
/// or across a boundary, as "file imports path".
fn forbidden_imports(sources: &[Source]) -> Vec<String> {
    let mut found = Vec::new();
    for s in sources {
        let top = s.module[0].as_str();
        if matches!(top, "cli" | "main" | "lib") {
            continue;
        }
        let own = rung(top);
        for p in paths_after(&s.code, "crate::") {
            let theirs = rung(&p[0]);
            let same_rung_other = theirs == own && p[0] != top && own < LADDER.len();
            let across = BOUNDARIES.contains(&(top, p[0].as_str()));
            if theirs < own || same_rung_other || across {
                found.push(format!(
                    "{} imports crate::{}",
                    s.module.join("/"),
                    p.join("::")
                ));
            }
        }
    }
    found.sort();
    found.dedup();
    found
}

#[test]
fn no_folder_imports_a_folder_above_it() {
    let upward = forbidden_imports(&sources());
    assert!(
        upward.is_empty(),
        "imports up the ladder or across a boundary:\n{}",
        upward.join("\n")
    );
}

/// Each kind of import the design forbids, planted in a file of its own,
/// is found: the rig or the host using the DEM, `shape` and `dem` using
/// each other, a folder using one above it; an import down the ladder is not.
#[test]
fn planted_forbidden_imports_are_found() {
    let planted = |module: &str, code: &str| Source {
        module: module.split('/').map(String::from).collect(),
        code: code_of(code),
    };
    for (module, code) in [
        ("rig/shaker", "use crate::dem::World;"),
        ("host/modal", "let w = crate::dem::world::World::new();"),
        ("shape/prolate", "use crate::dem::{Particles, Material};"),
        ("dem/clumps", "use crate::shape::Body;"),
        ("signals/dft", "use crate::rig::Daq;"),
        ("rig/daq", "use crate::host::Host;"),
    ] {
        let found = forbidden_imports(&[planted(module, code)]);
        assert!(!found.is_empty(), "{module}: {code} passed");
    }
    let fine = planted(
        "host/modal",
        "use crate::rig::EnclosureMotion;\nuse crate::stats::x;",
    );
    assert_eq!(forbidden_imports(&[fine]), Vec::<String>::new());
}

/// The files of one folder and which of them each imports.
fn folder_graphs() -> BTreeMap<String, BTreeMap<String, BTreeSet<String>>> {
    let all = sources();
    let mut graphs: BTreeMap<String, BTreeMap<String, BTreeSet<String>>> = BTreeMap::new();
    for s in &all {
        if s.module.len() < 2 {
            continue;
        }
        let folder = s.module[..s.module.len() - 1].join("::");
        let me = s.module.last().expect("file").clone();
        let siblings: BTreeSet<String> = all
            .iter()
            .filter(|o| {
                o.module.len() == s.module.len()
                    && o.module[..o.module.len() - 1] == s.module[..s.module.len() - 1]
            })
            .map(|o| o.module.last().expect("file").clone())
            .collect();
        let mut targets = BTreeSet::new();
        for p in paths_after(&s.code, "crate::") {
            let depth = s.module.len() - 1;
            if p.len() > depth && p[..depth].join("::") == folder && siblings.contains(&p[depth]) {
                targets.insert(p[depth].clone());
            }
        }
        for p in paths_after(&s.code, "super::") {
            if siblings.contains(&p[0]) {
                targets.insert(p[0].clone());
            }
        }
        targets.remove(&me);
        graphs.entry(folder).or_default().insert(me, targets);
    }
    graphs
}

/// A loop in `graph`, if there is one, as the files along it.
fn find_loop(graph: &BTreeMap<String, BTreeSet<String>>) -> Option<Vec<String>> {
    fn visit(
        node: &str,
        graph: &BTreeMap<String, BTreeSet<String>>,
        state: &mut BTreeMap<String, u8>,
        stack: &mut Vec<String>,
    ) -> Option<Vec<String>> {
        state.insert(node.to_string(), 1);
        stack.push(node.to_string());
        for next in graph.get(node).into_iter().flatten() {
            match state.get(next.as_str()).copied().unwrap_or(0) {
                1 => {
                    let start = stack.iter().position(|n| n == next).expect("on stack");
                    let mut cycle = stack[start..].to_vec();
                    cycle.push(next.clone());
                    return Some(cycle);
                }
                0 => {
                    if let Some(c) = visit(next, graph, state, stack) {
                        return Some(c);
                    }
                }
                _ => {}
            }
        }
        stack.pop();
        state.insert(node.to_string(), 2);
        None
    }
    let mut state = BTreeMap::new();
    for node in graph.keys() {
        if state.get(node.as_str()).copied().unwrap_or(0) == 0 {
            if let Some(c) = visit(node, graph, &mut state, &mut Vec::new()) {
                return Some(c);
            }
        }
    }
    None
}

#[test]
fn no_import_loop_inside_a_folder() {
    let loops: Vec<String> = folder_graphs()
        .iter()
        .filter_map(|(folder, g)| find_loop(g).map(|c| format!("{folder}: {}", c.join(" -> "))))
        .collect();
    assert!(loops.is_empty(), "import loops:\n{}", loops.join("\n"));
}

/// The checks can fail: a loop and an upward import planted in text are found.
#[test]
fn the_checks_see_a_planted_loop_and_an_upward_import() {
    let mut g: BTreeMap<String, BTreeSet<String>> = BTreeMap::new();
    g.insert("a".into(), ["b".to_string()].into());
    g.insert("b".into(), ["c".to_string()].into());
    g.insert("c".into(), ["a".to_string()].into());
    assert_eq!(
        find_loop(&g),
        Some(vec!["a".into(), "b".into(), "c".into(), "a".into()])
    );
    g.insert("c".into(), BTreeSet::new());
    assert_eq!(find_loop(&g), None);
    let code = code_of(
        "use crate::study::sweep::run_sweep;\n// crate::cli::x\nlet x = crate::scene::Scene::thesis();",
    );
    let found = paths_after(&code, "crate::");
    assert_eq!(found.len(), 2, "{found:?}");
    assert!(rung(&found[0][0]) < rung("rig"));
    assert_eq!(found[1], vec!["scene", "Scene", "thesis"]);
}
