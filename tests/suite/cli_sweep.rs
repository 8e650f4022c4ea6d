//! `vlab sweep`, `sweep merge`, `predict`, `plot` and `shake --dump` end to
//! end, on a tiny scene (30 spheres, 4 cycles) so that the mechanics take
//! seconds: unreachable conditions marked, a killed sweep resumed computing
//! only what is missing, shards merged equal to the unsharded sweep row for
//! row, refusals, plots redrawn from the CSV, a ParaView dump read back.

#![cfg(all(feature = "cli", feature = "plot"))]

use crate::common;

use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use common::{Scratch, TINY_SCENE, stderr, vlab};

const SWEEP: [&str; 8] = [
    "--freq",
    "20,40",
    "--gamma",
    "1,3,15",
    "--seeds",
    "1,2",
    "--scene",
    "tiny.toml",
];

/// The data rows of a sweep file with the wall-time column blanked (the
/// only column that differs between two runs of one sweep).
fn rows_without_wall_time(path: &Path) -> Vec<String> {
    let text = std::fs::read_to_string(path).expect("sweep.csv");
    let mut lines = text.lines().filter(|l| !l.starts_with('#'));
    let header: Vec<&str> = lines.next().expect("header row").split(',').collect();
    let wall = header
        .iter()
        .position(|h| *h == "wall_time_s")
        .expect("wall_time_s column");
    lines
        .map(|l| {
            let mut cells: Vec<&str> = l.split(',').collect();
            cells[wall] = "";
            cells.join(",")
        })
        .collect()
}

fn header_lines(path: &Path) -> Vec<String> {
    std::fs::read_to_string(path)
        .expect("sweep.csv")
        .lines()
        .filter(|l| l.starts_with('#') && !l.starts_with("# shard"))
        .map(String::from)
        .collect()
}

fn run(dir: &Path, extra: &[&str]) -> std::process::Output {
    let mut args = vec!["sweep"];
    args.extend_from_slice(&SWEEP);
    args.extend_from_slice(extra);
    vlab(dir, &args)
}

#[test]
fn sweep_marks_resumes_shards_and_merges() {
    let dir = Scratch::new("sweep");
    dir.write("tiny.toml", TINY_SCENE);

    // The whole sweep at once.
    let a = run(&dir.0, &["--out", "all"]);
    assert!(a.status.success(), "{}", stderr(&a));
    // Two seeds give an error from their spread; never a NaN in the table.
    let table = String::from_utf8_lossy(&a.stdout);
    // Each frequency's curve has its peak read off (a log-parabola, or at
    // the grid's end).
    assert_eq!(
        table.matches("  peak at fill 0.208, vertical, ").count(),
        2,
        "{table}"
    );
    assert!(
        table.contains(" +- 0.") && !table.contains("NaN"),
        "{table}"
    );
    let all = dir.path("all/sweep.csv");
    let rows = rows_without_wall_time(&all);
    assert_eq!(rows.len(), 12, "{rows:#?}");
    // 20 Hz, Gamma 15 is beyond the thesis rig's stroke: marked, not dropped.
    let unreachable: Vec<&String> = rows
        .iter()
        .filter(|r| r.contains(",unreachable,"))
        .collect();
    assert_eq!(unreachable.len(), 2, "{rows:#?}");
    assert!(
        unreachable.iter().all(|r| r.contains(",20,15,")),
        "{unreachable:#?}"
    );
    assert!(unreachable[0].contains("stroke"), "{}", unreachable[0]);
    assert_eq!(rows.iter().filter(|r| r.contains(",ok,")).count(), 10);
    for plot in ["efficiency.svg", "efficiency.png", "map.svg", "map.png"] {
        assert!(dir.path("all").join(plot).is_file(), "{plot}");
    }

    // `sweep optimum` reads one series' optimum off each sweep given: a
    // sweep of two frequencies needs --freq, and says which it has.
    let opt = |extra: &[&str]| {
        let mut args = vec!["sweep", "optimum", "--point", "tiny@1=all", "--out", "opt"];
        args.extend_from_slice(extra);
        vlab(&dir.0, &args)
    };
    let two = opt(&[]);
    assert!(!two.status.success());
    assert!(
        stderr(&two).contains("2 series (20 Hz, 40 Hz)") && stderr(&two).contains("--freq"),
        "{}",
        stderr(&two)
    );
    assert!(!dir.path("opt").exists());
    let one = opt(&["--freq", "40"]);
    assert!(one.status.success(), "{}", stderr(&one));
    let csv = std::fs::read_to_string(dir.path("opt/optimum.csv")).expect("optimum.csv");
    let row = csv.lines().nth(1).expect("a row");
    assert!(row.starts_with("tiny,1,"), "{csv}");
    assert!(row.contains(",2,"), "two seeds: {csv}");
    assert!(dir.path("opt/optimum.svg").is_file());

    // A second run into the same folder is refused without --resume, and a
    // resume with other lists is refused.
    let again = run(&dir.0, &["--out", "all"]);
    assert!(!again.status.success());
    assert!(stderr(&again).contains("--resume"), "{}", stderr(&again));
    let other = vlab(
        &dir.0,
        &[
            "sweep",
            "--freq",
            "40",
            "--gamma",
            "1,3",
            "--scene",
            "tiny.toml",
            "--out",
            "all",
            "--resume",
        ],
    );
    assert!(!other.status.success());
    assert!(
        stderr(&other).contains("another sweep"),
        "{}",
        stderr(&other)
    );

    // Killed halfway, then resumed: only the missing conditions run, and the
    // result is the uninterrupted sweep's.
    let mut child = Command::new(env!("CARGO_BIN_EXE_vlab"))
        .args(["sweep"])
        .args(SWEEP)
        .args(["--out", "killed", "--threads", "1"])
        .current_dir(&dir.0)
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("start sweep");
    let partial = dir.path("killed/sweep.csv");
    let started = Instant::now();
    loop {
        let n = std::fs::read_to_string(&partial)
            .map(|t| t.lines().filter(|l| l.contains(",ok,")).count())
            .unwrap_or(0);
        if n >= 3 {
            break;
        }
        assert!(
            started.elapsed() < Duration::from_secs(300),
            "the sweep wrote no rows"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
    child.kill().expect("kill the sweep");
    let _ = child.wait();
    let before = rows_without_wall_time(&partial);
    assert!(
        before.len() < 12,
        "the kill came too late: {} rows",
        before.len()
    );
    let resumed = run(&dir.0, &["--out", "killed", "--resume"]);
    assert!(resumed.status.success(), "{}", stderr(&resumed));
    let log = stderr(&resumed);
    let already = format!("{} already in sweep.csv", before.len());
    assert!(log.contains(&already), "expected '{already}' in {log}");
    let computed = log.lines().filter(|l| l.contains("Hz Gamma")).count();
    assert_eq!(computed + before.len(), 12, "{log}");
    for r in &before {
        assert!(
            rows.contains(r),
            "a row computed before the kill differs: {r}"
        );
    }
    assert_eq!(rows_without_wall_time(&partial), rows);

    // Three shards, merged: the unsharded sweep, row for row.
    for i in 1..=3 {
        let shard = format!("{i}/3");
        let out = format!("shard{i}");
        let s = run(&dir.0, &["--shard", &shard, "--out", &out]);
        assert!(s.status.success(), "{}", stderr(&s));
    }
    let merged = vlab(
        &dir.0,
        &[
            "sweep", "merge", "shard1", "shard2", "shard3", "--out", "merged",
        ],
    );
    assert!(merged.status.success(), "{}", stderr(&merged));
    let m = dir.path("merged/sweep.csv");
    assert_eq!(rows_without_wall_time(&m), rows);
    assert_eq!(header_lines(&m), header_lines(&all));

    // Merge refuses a missing shard and a shard of another sweep.
    let missing = vlab(
        &dir.0,
        &["sweep", "merge", "shard1", "shard3", "--out", "m2"],
    );
    assert!(!missing.status.success());
    assert!(
        stderr(&missing).contains("shard 2/3 missing"),
        "{}",
        stderr(&missing)
    );
    let o = vlab(
        &dir.0,
        &[
            "sweep",
            "--freq",
            "40",
            "--gamma",
            "1",
            "--scene",
            "tiny.toml",
            "--shard",
            "2/3",
            "--out",
            "othershard",
        ],
    );
    assert!(o.status.success(), "{}", stderr(&o));
    let mixed = vlab(
        &dir.0,
        &[
            "sweep",
            "merge",
            "shard1",
            "othershard",
            "shard3",
            "--out",
            "m3",
        ],
    );
    assert!(!mixed.status.success());
    assert!(
        stderr(&mixed).contains("different sweeps"),
        "{}",
        stderr(&mixed)
    );
    assert!(!dir.path("m2").exists() && !dir.path("m3").exists());

    // `vlab plot` redraws the plots from the CSV alone, identically.
    let p = vlab(&dir.0, &["plot", "all/sweep.csv", "--out", "redrawn"]);
    assert!(p.status.success(), "{}", stderr(&p));
    for plot in ["efficiency.svg", "map.svg"] {
        let a = std::fs::read(dir.path("all").join(plot)).expect("plot");
        let b = std::fs::read(dir.path("redrawn").join(plot)).expect("redrawn plot");
        assert!(a == b, "{plot} redrawn differs");
    }
}

#[test]
fn predict_reproduces_table_6_3() {
    let dir = Scratch::new("predict");
    let out = vlab(&dir.0, &["predict", "--freq", "20,40,80", "--json"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("json");
    let table = [
        ("close_packing_gamma", [5.6, 22.3, 89.2]),
        ("loose_packing_gamma", [3.1, 12.5, 49.9]),
    ];
    for (key, want) in table {
        let got = v[key].as_array().expect(key);
        for (g, w) in got.iter().zip(want) {
            let g = g.as_f64().expect("number");
            assert!((g - w).abs() / w < 0.01, "{key}: {g} vs {w}");
        }
    }
    let bad = vlab(&dir.0, &["predict", "--freq", "40", "--fill-ratio", "0.64"]);
    assert!(!bad.status.success());
    assert!(
        stderr(&bad).starts_with("error: --fill-ratio = 0.64: must be"),
        "{}",
        stderr(&bad)
    );
}

/// A bed fuller than loose packing (vlab settles to about 0.57) still has a
/// close-packing clearance: predicted, with the loose-packing estimate said
/// not to apply.
#[test]
fn predict_takes_fills_up_to_close_packing() {
    let dir = Scratch::new("predict-full");
    let out = vlab(&dir.0, &["predict", "--freq", "40", "--fill-ratio", "0.57"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("loose-packing estimate stops applying") && text.contains("0.55"),
        "{text}"
    );
    // h = (1 - 0.57 / 0.64) 0.04 m = 4.375 mm; Gamma = (80 pi)^2 h / (9.81 pi) = 8.967.
    assert!(text.contains("4.38 mm with close packing"), "{text}");
    let out = vlab(
        &dir.0,
        &["predict", "--freq", "40", "--fill-ratio", "0.57", "--json"],
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("json");
    let cp = v["close_packing_gamma"][0].as_f64().expect("CP");
    assert!((cp - 8.967).abs() < 0.001, "{cp}");
    assert!(v["loose_packing_gamma"].is_null(), "{v}");
    assert!(v["loose_packing_note"].is_string(), "{v}");
}

#[test]
fn shake_dump_is_readable_vtk_and_snapshots_are_drawn() {
    let dir = Scratch::new("dump");
    dir.write("tiny.toml", TINY_SCENE);
    let out = vlab(
        &dir.0,
        &[
            "--quiet",
            "shake",
            "--beds",
            "1",
            "--scene",
            "tiny.toml",
            "--freq",
            "40",
            "--gamma",
            "8",
            "--out",
            "run",
            "--dump",
            "vtk",
            "--dump-every-s",
            "0.025",
            "--snapshots",
        ],
    );
    assert!(out.status.success(), "{}", stderr(&out));
    let pvd = std::fs::read_to_string(dir.path("vtk/particles.pvd")).expect("pvd");
    let frames = pvd.matches("<DataSet ").count();
    assert!((4..=5).contains(&frames), "{pvd}");
    let vtk = vlab_vtk(&dir.path("vtk/particles-00003.vtp"));
    assert_eq!(vtk.0, 30);
    for name in [
        "velocity",
        "speed",
        "spin",
        "radius",
        "contact_count",
        "dissipation_rate_w",
    ] {
        assert!(
            vtk.1.iter().any(|n| n == name),
            "{name} missing: {:?}",
            vtk.1
        );
    }
    assert!(vtk.2 > 0.0, "no dissipation booked between frames");
    let enc = vlab_vtk(&dir.path("vtk/enclosure-00000.vtp"));
    assert_eq!(enc.0, 64);
    for f in ["snapshots.svg", "snapshots.png"] {
        assert!(dir.path("run").join(f).is_file(), "{f}");
    }
}

/// Points, point-data names and the summed dissipation rate of a .vtp file,
/// read back through the dump's own reader.
fn vlab_vtk(path: &Path) -> (usize, Vec<String>, f64) {
    let vtk = vlab::export::vtk_dump::read_vtp(path)
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let points = vtk
        .arrays
        .iter()
        .find(|a| a.section == "Points")
        .expect("points");
    assert_eq!(points.values.len(), 3 * vtk.n_points);
    let names = vtk
        .arrays
        .iter()
        .filter(|a| a.section == "PointData")
        .map(|a| a.name.clone())
        .collect();
    let rate = vtk
        .point_data("dissipation_rate_w")
        .map_or(0.0, |a| a.values.iter().sum());
    (vtk.n_points, names, rate)
}

/// `--beds 2` drives every condition as an ensemble of two beds: its rows
/// say so (`beds` 2, `se_from` beds, the header's `# beds: 2`), the table
/// says where each +- comes from; one bed's rows say `window`, or
/// `not_known` for a window too short.
#[test]
fn a_sweep_of_ensembles_says_how_its_errors_are_known() {
    let dir = Scratch::new("sweep-beds");
    dir.write("tiny.toml", TINY_SCENE);
    let sweep = |beds: &str, out: &str, extra: &[&str]| {
        let mut args = vec![
            "sweep",
            "--freq",
            "40",
            "--gamma",
            "3",
            "--scene",
            "tiny.toml",
            "--beds",
            beds,
            "--out",
            out,
        ];
        args.extend_from_slice(extra);
        vlab(&dir.0, &args)
    };
    let two = sweep("2", "two", &[]);
    assert!(two.status.success(), "{}", stderr(&two));
    let text = std::fs::read_to_string(dir.path("two/sweep.csv")).expect("sweep.csv");
    assert!(text.contains("\n# beds: 2\n"), "{text}");
    let header = text
        .lines()
        .find(|l| !l.starts_with('#'))
        .expect("a header row");
    let names: Vec<&str> = header.split(',').collect();
    let row: Vec<&str> = text.lines().last().expect("a row").split(',').collect();
    let cell = |name: &str| row[names.iter().position(|n| *n == name).expect(name)];
    assert_eq!((cell("beds"), cell("se_from")), ("2", "beds"), "{text}");
    let table = String::from_utf8_lossy(&two.stdout);
    assert!(
        table.contains("+- from") && table.contains(" beds "),
        "{table}"
    );

    // One bed's 2 kept cycles have no error: not known; its 32 have the
    // window's, said to leave out other packings (32: should the bed
    // alternate from cycle to cycle its error is that of 16 pairs).
    let short = sweep("1", "short", &[]);
    assert!(short.status.success(), "{}", stderr(&short));
    let table = String::from_utf8_lossy(&short.stdout);
    assert!(
        table.contains("+- not known") && table.contains("not_known"),
        "{table}"
    );
    let one = sweep("1", "one", &["--cycles", "36", "--steady-cycles", "32"]);
    assert!(one.status.success(), "{}", stderr(&one));
    let table = String::from_utf8_lossy(&one.stdout);
    assert!(
        table.contains(" window ") && table.contains("leaves out how far another packing"),
        "{table}"
    );
    let refused = sweep("0", "none", &[]);
    assert!(!refused.status.success());
    assert!(stderr(&refused).contains("--beds"), "{}", stderr(&refused));
}

/// `--up-down` carries the bed from each Γ to the next: the first condition
/// up starts from the settled bed as an ordinary sweep's does (the same
/// row), every later one from where the last left it (not the ordinary
/// sweep's row), the top is one run on both branches, the branches differ
/// below it, the numbers do not depend on the thread count, and what a
/// carried sweep cannot do is refused before any work.
#[test]
fn a_sweep_up_and_down_carries_the_bed() {
    let dir = Scratch::new("sweep-updown");
    dir.write("tiny.toml", TINY_SCENE);
    let sweep = |threads: &str, out: &str, extra: &[&str]| {
        let mut args = vec![
            "--threads",
            threads,
            "sweep",
            "--freq",
            "40",
            "--gamma",
            "1,3,15",
            "--seeds",
            "1,2",
            "--scene",
            "tiny.toml",
            "--out",
            out,
        ];
        args.extend_from_slice(extra);
        vlab(&dir.0, &args)
    };
    let plain = sweep("2", "plain", &[]);
    assert!(plain.status.success(), "{}", stderr(&plain));
    let carried = sweep("2", "carried", &["--up-down"]);
    assert!(carried.status.success(), "{}", stderr(&carried));
    let one_thread = sweep("1", "carried-1", &["--up-down"]);
    assert!(one_thread.status.success(), "{}", stderr(&one_thread));

    let plain = rows_without_wall_time(&dir.path("plain/sweep.csv"));
    let up = rows_without_wall_time(&dir.path("carried/up/sweep.csv"));
    let down = rows_without_wall_time(&dir.path("carried/down/sweep.csv"));
    // Rows by (Γ, seed): the condition's columns lead each row.
    let row = |rows: &[String], gamma: &str, seed: &str| -> String {
        rows.iter()
            .find(|r| {
                let c: Vec<&str> = r.split(',').collect();
                c[3] == gamma && c[4] == seed
            })
            .unwrap_or_else(|| panic!("no row at Gamma {gamma} seed {seed} in {rows:?}"))
            .clone()
    };
    for seed in ["1", "2"] {
        assert_eq!(row(&up, "1", seed), row(&plain, "1", seed));
        assert_ne!(row(&up, "3", seed), row(&plain, "3", seed));
        assert_ne!(row(&up, "15", seed), row(&plain, "15", seed));
        assert_eq!(row(&up, "15", seed), row(&down, "15", seed));
        assert_ne!(row(&up, "3", seed), row(&down, "3", seed));
        assert_ne!(row(&up, "1", seed), row(&down, "1", seed));
    }
    assert_eq!(
        up,
        rows_without_wall_time(&dir.path("carried-1/up/sweep.csv"))
    );
    assert_eq!(
        down,
        rows_without_wall_time(&dir.path("carried-1/down/sweep.csv"))
    );
    let text = std::fs::read_to_string(dir.path("carried/down/sweep.csv")).expect("sweep.csv");
    assert!(text.contains("\n# carried: down\n"), "{text}");
    // Both branches side by side: 3 Γ × 2 seeds, the top with no difference.
    let side = std::fs::read_to_string(dir.path("carried/updown.csv")).expect("updown.csv");
    assert_eq!(side.lines().count(), 7, "{side}");
    assert!(
        side.lines()
            .filter(|l| l.contains(",40,15,"))
            .all(|l| l.split(',').nth(11) == Some("0")),
        "{side}"
    );
    let table = String::from_utf8_lossy(&carried.stdout);
    assert!(table.contains("up and down in Gamma"), "{table}");

    // Refused before any work, by the flag.
    for (extra, flag) in [
        (&["--up-down", "--beds", "2"][..], "--beds"),
        (&["--up-down", "--resume"][..], "--resume"),
    ] {
        let o = sweep("2", "refused", extra);
        assert!(!o.status.success(), "{extra:?}");
        assert!(stderr(&o).contains(flag), "{extra:?}: {}", stderr(&o));
    }
    let mut args = vec![
        "sweep",
        "--freq",
        "40",
        "--gamma",
        "3",
        "--scene",
        "tiny.toml",
    ];
    args.extend(["--up-down", "--out", "refused"]);
    let o = vlab(&dir.0, &args);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("--gamma"), "{}", stderr(&o));
    assert!(!dir.path("refused").exists());
}
