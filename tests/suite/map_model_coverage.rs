//! Does the map-based model's claimed range hold the coupled DEM where it
//! was not set? The range (`amplitude_low_m` to `amplitude_high_m` of
//! `vlab host predict`) is the map's own (its efficiency anywhere between
//! neighbouring points, each ± its error) widened by the model's floor,
//! `vlab::host::map_model::MODEL_FLOOR_REL`, which was set on one run
//! only: the thesis damper on plate-40hz at 5 N
//! (`signals/reference/host-frf/`). Here the kept coupled-DEM runs at 3 N
//! and 8 N on the same plate and at 5 N on the beam, which it never saw,
//! are held to it; and the same map refined at the onset by sweeps of its
//! own (`signals/reference/host-map-onset/`) must narrow the range.
//!
//! A range is not a one-sigma error: it should hold nearly every point.
//! The criterion is 90 % of the points the model answers (a point the
//! DEM drove beyond the map's Γ, where the model warns that it guesses, is
//! a refusal with its reason, not an answer). Measured when written
//! (2026-11-28): 3 N 16 of 17 (37 Hz lies 0.5 % below the range), 8 N 15
//! of 16 answered (42 Hz, where the DEM bounces at Γ 18.5 and the model
//! settles at Γ 16.7, lies 5.6 % above it; 39 Hz, Γ 40.3, refused); the
//! beam at 5 N 7 of 9 (at its sharp resonance the DEM lies 6.3 % below the
//! range at 40 Hz and 6.4 % above it at 40.5 Hz, in 30 cycles not settled
//! at either, though 40 Hz passed the 5 % steadiness check): 38 of 42 in
//! all, 90.5 %, at the criterion's edge. Before the range took the points'
//! neighbours the model's ± was its points' errors alone (0.1-0.4 % on the
//! flat top) and held 2 of the 17 points at 5 N. The same runs with three
//! beds a frequency, the range held to the beds' mean ± its error, and the
//! beam's resonance settled over 100 cycles, are the last test here.

#![cfg(all(feature = "cli", feature = "plot"))]

use crate::common;

use std::collections::BTreeMap;
use std::path::Path;

use common::{Scratch, stderr, vlab};

/// Columns of a CSV (comment lines skipped) by name, each row's values.
fn columns(path: &Path) -> BTreeMap<String, Vec<String>> {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut lines = text.lines().filter(|l| !l.starts_with('#'));
    let header: Vec<String> = lines
        .next()
        .expect("a header")
        .split(',')
        .map(str::to_string)
        .collect();
    let mut out: BTreeMap<String, Vec<String>> =
        header.iter().map(|h| (h.clone(), Vec::new())).collect();
    for line in lines {
        for (h, v) in header.iter().zip(line.split(',')) {
            out.get_mut(h).expect("a column").push(v.to_string());
        }
    }
    out
}

fn floats(c: &BTreeMap<String, Vec<String>>, name: &str) -> Vec<f64> {
    c[name]
        .iter()
        .map(|v| v.parse().unwrap_or_else(|_| panic!("{name}: {v}")))
        .collect()
}

/// The plate's map, one seed a condition.
const MAP: &[&str] = &["signals/reference/host-map/sweep.csv"];

/// The same map refined at the bed's onset: Γ 11-14 at 37 Hz, 14-17 at
/// 40 Hz and 17-20 at 43 Hz, three seeds each.
const REFINED_MAP: &[&str] = &[
    "signals/reference/host-map/sweep.csv",
    "signals/reference/host-map-onset/sweep-37hz.csv",
    "signals/reference/host-map-onset/sweep-40hz.csv",
    "signals/reference/host-map-onset/sweep-43hz.csv",
];

/// One frequency of a coupled-DEM stepped sine: the damper's amplitude,
/// its one-sigma error (zero for one bed, whose spread is not known) and
/// the Γ it reached.
struct DemPoint {
    freq_hz: f64,
    amplitude_m: f64,
    stderr_m: f64,
    gamma: f64,
}

/// The points of a kept one-bed run's `frf.csv`.
fn one_bed(kept: &str) -> Vec<DemPoint> {
    let dem = columns(&Path::new(env!("CARGO_MANIFEST_DIR")).join(kept));
    let (freqs, amplitude, gamma) = (
        floats(&dem, "freq_hz"),
        floats(&dem, "amplitude_m"),
        floats(&dem, "gamma"),
    );
    (0..freqs.len())
        .map(|k| DemPoint {
            freq_hz: freqs[k],
            amplitude_m: amplitude[k],
            stderr_m: 0.0,
            gamma: gamma[k],
        })
        .collect()
}

/// The points of a kept run of several beds (`--beds`), from its
/// `frf.json`: each the beds' mean, its error their spread's.
fn beds(kept: &str) -> Vec<DemPoint> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(kept);
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{kept}: {e}"));
    let json: serde_json::Value = serde_json::from_str(&text).expect("JSON");
    let number = |p: &serde_json::Value, key: &str| p[key].as_f64().expect(key);
    json["measured"]["points"]
        .as_array()
        .expect("points")
        .iter()
        .map(|p| {
            assert!(
                p["bed_to_bed"]["source"] == "ensemble"
                    && p["bed_to_bed"]["beds"].as_u64() >= Some(3),
                "{kept}: {}",
                p["bed_to_bed"]
            );
            DemPoint {
                freq_hz: number(p, "freq_hz"),
                amplitude_m: number(p, "amplitude_m"),
                stderr_m: number(p, "amplitude_stderr_m"),
                gamma: number(p, "gamma"),
            }
        })
        .collect()
}

/// How a kept coupled-DEM run fares against the prediction of the same
/// stepped sine from `map`.
struct Coverage {
    held: usize,
    answered: usize,
    misses: Vec<String>,
    /// The ranges' mean width over the answered points, relative to the
    /// DEM's amplitude.
    mean_width_rel: f64,
}

/// The points of a coupled-DEM run (`label` names it) the prediction of
/// the same stepped sine holds, and those it answers: held where the
/// range meets the DEM's amplitude ± its error.
fn coverage(
    dir: &Scratch,
    map: &[&str],
    dem: &[DemPoint],
    label: &str,
    host: &str,
    force_n: &str,
) -> Coverage {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let list: Vec<String> = dem.iter().map(|p| p.freq_hz.to_string()).collect();
    let out = format!("predict-{host}-{force_n}-{}", map.len());
    let mut args: Vec<String> = ["--quiet", "host", "predict", "--host", host]
        .map(String::from)
        .to_vec();
    for file in map {
        args.push("--map".into());
        args.push(root.join(file).to_string_lossy().into_owned());
    }
    for a in [
        "--freq",
        &list.join(","),
        "--force-n",
        force_n,
        "--out",
        &out,
    ] {
        args.push(a.to_string());
    }
    let run = vlab(&dir.0, &args.iter().map(String::as_str).collect::<Vec<_>>());
    assert!(run.status.success(), "{}", stderr(&run));
    let predicted = columns(&dir.path(&format!("{out}/predict.csv")));
    let (low, high) = (
        floats(&predicted, "amplitude_low_m"),
        floats(&predicted, "amplitude_high_m"),
    );
    let freqs: Vec<f64> = dem.iter().map(|p| p.freq_hz).collect();
    assert_eq!(floats(&predicted, "freq_hz"), freqs, "{label}");
    let (mut held, mut answered, mut misses, mut width) = (0, 0, Vec::new(), 0.0);
    for (k, p) in dem.iter().enumerate() {
        // The map's top is Gamma 30 at every frequency: beyond it the
        // command warns that the model guesses.
        if p.gamma > 30.0 {
            continue;
        }
        answered += 1;
        width += (high[k] - low[k]) / p.amplitude_m;
        if p.amplitude_m + p.stderr_m >= low[k] && p.amplitude_m - p.stderr_m <= high[k] {
            held += 1;
        } else {
            misses.push(format!(
                "{} Hz: DEM {:.4} +- {:.4} mm outside {:.4}..{:.4} mm",
                p.freq_hz,
                p.amplitude_m * 1e3,
                p.stderr_m * 1e3,
                low[k] * 1e3,
                high[k] * 1e3
            ));
        }
    }
    Coverage {
        held,
        answered,
        misses,
        mean_width_rel: width / answered as f64,
    }
}

/// The points held and answered over `runs` (kept file, host, force in
/// N), each read by `read`, against `map`; each run must be answered at 8
/// points at least.
fn out_of_sample(
    dir: &Scratch,
    map: &[&str],
    runs: &[(&str, &str, &str)],
    read: fn(&str) -> Vec<DemPoint>,
) -> (usize, usize) {
    let mut total = (0, 0);
    for (kept, host, force) in runs {
        let c = coverage(dir, map, &read(kept), kept, host, force);
        eprintln!("{kept}: {} of {} held; {:?}", c.held, c.answered, c.misses);
        assert!(c.answered >= 8, "{kept}: {} points answered", c.answered);
        total = (total.0 + c.held, total.1 + c.answered);
    }
    total
}

#[test]
fn the_claimed_range_holds_the_coupled_dem_where_it_was_set_and_beyond() {
    let dir = Scratch::new("map-model-coverage");
    // Where the floor was set: every point.
    let kept = "signals/reference/host-frf/frf.csv";
    let c = coverage(&dir, MAP, &one_bed(kept), kept, "plate-40hz", "5");
    assert_eq!((c.held, c.answered), (17, 17), "{:?}", c.misses);
    // Out of sample.
    let runs = [
        (
            "signals/reference/host-frf-levels/force-3N/frf.csv",
            "plate-40hz",
            "3",
        ),
        (
            "signals/reference/host-frf-levels/force-8N/frf.csv",
            "plate-40hz",
            "8",
        ),
        ("signals/reference/host-frf-beam/frf.csv", "beam-2mode", "5"),
    ];
    let total = out_of_sample(&dir, MAP, &runs, one_bed);
    assert!(
        total.0 as f64 >= 0.9 * total.1 as f64,
        "{} of {} out-of-sample points held",
        total.0,
        total.1
    );
}

#[test]
fn a_map_refined_at_the_onset_narrows_the_range() {
    // The map's points at 37, 40 and 43 Hz straddle the bed's onset three
    // Γ apart (14 and 17 at 40 Hz: efficiency 0.19 and 0.87), and the range
    // takes anything between. Refined there (`--map` given again: a sweep
    // of Γ 14-17 at 40 Hz and its neighbours' over seeds 1-3, which finds
    // the onset between Γ 15 and 16, one seed switching at 16), the range
    // must narrow by a tenth at least at 3 and 5 N (measured 2026-11-29:
    // 11.4 % to 9.6 % of the DEM's amplitude at 5 N, 11.2 % to 9.1 % at
    // 3 N) and still hold every point of the run that set the model's
    // floor. Out of sample it held 37 of 42 (88 %; the coarse map 38): the
    // 8 N run at 41.5 Hz falls 1.3 % below the narrower range; the
    // coupled runs are one bed each, whose spread is not in the range.
    let dir = Scratch::new("map-model-refined");
    for (kept, force, in_sample) in [
        ("signals/reference/host-frf/frf.csv", "5", true),
        (
            "signals/reference/host-frf-levels/force-3N/frf.csv",
            "3",
            false,
        ),
    ] {
        let dem = one_bed(kept);
        let coarse = coverage(&dir, MAP, &dem, kept, "plate-40hz", force);
        let fine = coverage(&dir, REFINED_MAP, &dem, kept, "plate-40hz", force);
        eprintln!(
            "{force} N: mean range {:.1} % of the DEM's amplitude, refined {:.1} %; held {} and {} of {}",
            100.0 * coarse.mean_width_rel,
            100.0 * fine.mean_width_rel,
            coarse.held,
            fine.held,
            fine.answered
        );
        assert!(
            fine.mean_width_rel < 0.9 * coarse.mean_width_rel,
            "{force} N: {} against {}",
            fine.mean_width_rel,
            coarse.mean_width_rel
        );
        if in_sample {
            assert_eq!(fine.held, fine.answered, "{force} N: {:?}", fine.misses);
        }
    }
}

/// Three beds at every frequency (`--beds 3`) in place of one, at the
/// forces and on the hosts above: the DEM's amplitude is the beds' mean
/// with its error (their spread's, Student's t on two degrees of freedom),
/// and a point is held where the model's range meets that mean ± its
/// error. The criterion, fixed before the runs: every point at 5 N (the
/// force the model's floor was set on, though not on these beds) and 90 %
/// of the points out of sample, on either map. Measured (2026-11-29),
/// the same on both maps: 5 N 17 of 17; 3 N 16 of 17 (37 Hz, Γ 3.7,
/// 0.6627 ± 0.0010 mm, lies 0.3 % below the range: the beds agree, the
/// model does not); 8 N 16 of 16 answered (42 Hz, missed by the one bed,
/// is held by three); the beam 7 of 9. The beam's two misses (40 and
/// 40.5 Hz) were records that had not settled in 30 cycles at the beam's
/// sharp resonance: with 100 (`beam-settled/`, 39.5-40.5 Hz) the DEM at
/// 40 Hz reads 0.4527 mm/N where it read 0.370, and all three points lie
/// within the range, as this test asks: 39 of 42 out of sample on the 30
/// cycles, 41 of 42 with the beam settled. Settled only so far: at 100
/// cycles the command still calls 40 Hz not steady, and from rest the beam
/// creeps by 0.3 % a cycle at cycle 150 (docs/host.md, section 5).
#[test]
fn the_claimed_range_meets_the_beds_mean_and_spread() {
    let dir = Scratch::new("map-model-beds");
    for (name, map) in [("coarse", MAP), ("refined", REFINED_MAP)] {
        let kept = "signals/reference/host-frf-beds/force-5N/frf.json";
        let c = coverage(&dir, map, &beds(kept), kept, "plate-40hz", "5");
        eprintln!(
            "{name} map, {kept}: {} of {} held; {:?}",
            c.held, c.answered, c.misses
        );
        assert_eq!((c.held, c.answered), (17, 17), "{name}: {:?}", c.misses);
        let runs = [
            (
                "signals/reference/host-frf-beds/force-3N/frf.json",
                "plate-40hz",
                "3",
            ),
            (
                "signals/reference/host-frf-beds/force-8N/frf.json",
                "plate-40hz",
                "8",
            ),
            (
                "signals/reference/host-frf-beds/beam/frf.json",
                "beam-2mode",
                "5",
            ),
        ];
        let total = out_of_sample(&dir, map, &runs, beds);
        assert!(
            total.0 as f64 >= 0.9 * total.1 as f64,
            "{name} map: {} of {} out-of-sample points held",
            total.0,
            total.1
        );
        let kept = "signals/reference/host-frf-beds/beam-settled/frf.json";
        let c = coverage(&dir, map, &beds(kept), kept, "beam-2mode", "5");
        assert_eq!((c.held, c.answered), (3, 3), "{name}: {:?}", c.misses);
    }
}

/// The map's two branches at 40 Hz, the bed carried up and back down in Γ
/// (`vlab sweep --up-down`, kept in `signals/reference/host-map-updown/`):
/// at Γ 17 a bed carried up is still convective where one carried down
/// still bounces (two seeds of three), above it the branches agree. In
/// place of the onset sweep from rest, the up branch lifts the model's
/// flat top at 5 N to Γ 16.7-17.6 and misses the coupled DEM's 39 and
/// 39.5 Hz (three beds, each frequency started afresh as the map's
/// conditions are), the down branch misses 39 Hz; the map from rest holds
/// all 17. Which branch a map is measured on matters on the top, and the
/// stepped sine that starts afresh is the map from rest's.
#[test]
fn the_maps_branches_part_at_the_onset_and_the_fresh_map_meets_the_fresh_dem() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let side = columns(&root.join("signals/reference/host-map-updown/updown.csv"));
    let gamma = floats(&side, "gamma");
    let apart = |g: f64| {
        (0..gamma.len())
            .filter(|&k| gamma[k] == g && side["apart"][k] == "true")
            .count()
    };
    assert_eq!(apart(17.0), 2, "{side:?}");
    assert_eq!(apart(18.0) + apart(20.0), 0, "{side:?}");
    let down_at_17: Vec<f64> = (0..gamma.len())
        .filter(|&k| gamma[k] == 17.0)
        .map(|k| floats(&side, "efficiency_down")[k])
        .collect();
    assert!(down_at_17.iter().all(|e| *e > 0.7), "{down_at_17:?}");

    let kept = "signals/reference/host-frf-beds/force-5N/frf.json";
    let dem = beds(kept);
    let branch = |file: &'static str| {
        [
            "signals/reference/host-map/sweep.csv",
            "signals/reference/host-map-onset/sweep-37hz.csv",
            "signals/reference/host-map-onset/sweep-43hz.csv",
            file,
        ]
    };
    let mut held = Vec::new();
    for (name, map) in [
        ("from rest", REFINED_MAP.to_vec()),
        (
            "up",
            branch("signals/reference/host-map-updown/up/sweep.csv").to_vec(),
        ),
        (
            "down",
            branch("signals/reference/host-map-updown/down/sweep.csv").to_vec(),
        ),
    ] {
        let dir = Scratch::new(&format!("map-model-branch-{}", name.replace(' ', "-")));
        let c = coverage(&dir, &map, &dem, kept, "plate-40hz", "5");
        eprintln!("{name}: {} of {} held; {:?}", c.held, c.answered, c.misses);
        held.push((c.held, c.misses));
    }
    assert_eq!(held[0].0, 17, "{:?}", held[0].1);
    assert_eq!(held[1].0, 15, "{:?}", held[1].1);
    assert!(
        held[1].1[0].starts_with("39 Hz") && held[1].1[1].starts_with("39.5 Hz"),
        "{:?}",
        held[1].1
    );
    assert_eq!(held[2].0, 16, "{:?}", held[2].1);

    // The prediction says which branch its map is, first; a map from rest
    // says nothing of branches.
    let dir = Scratch::new("map-model-branch-words");
    let said = |maps: &[&str], out: &str| {
        let mut args = vec!["host", "predict", "--freq", "40", "--force-n", "5"];
        let paths: Vec<String> = maps
            .iter()
            .map(|m| root.join(m).to_string_lossy().into_owned())
            .collect();
        for p in &paths {
            args.extend(["--map", p.as_str()]);
        }
        args.extend(["--out", out]);
        let run = vlab(&dir.0, &args);
        assert!(run.status.success(), "{}", stderr(&run));
        let json: serde_json::Value = serde_json::from_str(
            &std::fs::read_to_string(dir.path(&format!("{out}/predict.json"))).expect("json"),
        )
        .expect("JSON");
        (stderr(&run), json["warnings"].clone())
    };
    let (text, listed) = said(
        &branch("signals/reference/host-map-updown/up/sweep.csv"),
        "up",
    );
    assert!(text.contains("the up branch of a sweep carried"), "{text}");
    assert!(
        listed[0]
            .as_str()
            .is_some_and(|w| w.contains("the up branch")),
        "{listed}"
    );
    let (text, _) = said(REFINED_MAP, "rest");
    assert!(!text.contains("branch"), "{text}");
}
