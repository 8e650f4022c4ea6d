//! Issue 11's claims on the thesis damper (vertical, thesis rig, each
//! condition driven until steady), located on the whole Γ grid of the sweep,
//! not on a few Γ picked around the answer:
//!
//! - at 40 Hz the efficiency against Γ has exactly two peaks, both above 0.3:
//!   the fluidisation optimum near Γ 3 (thesis Fig. 6.18a: Γ 1.5 below it,
//!   Γ 3 "about the optimum", Γ 4 beyond it), a global fluidisation, and the
//!   bouncing-bed optimum near Γ 19.6 (the thesis' DEM, Table 6.3), a
//!   bouncing bed;
//! - at 20 Hz one peak, the bouncing-bed optimum near Γ 5.2 (Table 6.3);
//! - at 80 Hz (in the committed sweep) one peak, the fluidisation optimum, at
//!   Γ 3 or lower (the optimum moves to smaller Γ as the frequency rises,
//!   Section 6.4.3.4, Fig. 6.23), and no bouncing bed anywhere on the grid:
//!   the thesis puts its onset at Γ 79.9 (Table 6.3), past the grid's 40;
//! - the phase heuristic names 40 Hz Γ 1 solid-like and 40 Hz Γ 30 a
//!   bouncing bed.
//!
//! The bouncing-bed peaks are also located between grid points, as the
//! thesis located its own (curves fitted through its runs): the vertex of
//! the parabola in log Γ through the peak and its two neighbours lies within
//! 15 % of the thesis' Γ (the committed sweep: about 21 against 19.6 and 5.1
//! against 5.2; 15 % is the gap between the thesis' DEM and its own
//! close-packing estimate, 22.3 at 40 Hz).
//!
//! A peak is a local maximum of the efficiency over the grid (the grid's ends
//! excluded) that stands at least 0.1 above the higher of the lowest points
//! between it and the nearest higher point (or the grid's end) on either
//! side: its prominence. Tolerance of "near": the peak is the grid Γ nearest
//! the thesis' figure in log Γ, i.e. the thesis' optimum lies within half a
//! grid step of it (on the committed grid 1, 1.5, 2, 3, 5, 8, 12, 20, 30, 40:
//! Γ 3 stands for 2.45–3.87, Γ 5 for 3.87–6.32, Γ 20 for 15.5–24.5). A sweep
//! whose peak moves by one grid step, or that grows or loses a peak, fails.
//!
//! Checked on the committed steady sweep (`signals/reference/sweep-steady/`,
//! seeds 1–3, every seed on its own) in `cargo test`, and on a fresh sweep of
//! seed 1 at 20 and 40 Hz on the same grid by a long test (17 conditions of
//! the full scene, 3 more the rig cannot reach: half an hour or more on 2
//! cores), ignored by default:
//!
//! ```sh
//! cargo test --release --test suite maps_thesis:: -- --ignored --nocapture
//! ```

use std::path::Path;

use vlab::scene::Scene;
use vlab::study::phases::MotionalPhase;
use vlab::study::sweep::{RowStatus, Shard, SweepFile, SweepPlan, phase_name, run_sweep};

/// The Γ grid of the committed steady sweep, and of the long test's sweep.
const GAMMAS: [f64; 10] = [1.0, 1.5, 2.0, 3.0, 5.0, 8.0, 12.0, 20.0, 30.0, 40.0];

/// Least prominence of a peak (efficiency).
const PROMINENCE: f64 = 0.1;

/// The rows of `seed` at `freq` that ran, as (Γ, efficiency, phase), in
/// order of Γ; the rig's unreachable conditions are left out, a failed one
/// fails the test.
fn curve(file: &SweepFile, seed: u64, freq: f64) -> Vec<(f64, f64, Option<MotionalPhase>)> {
    let mut rows: Vec<_> = file
        .rows
        .iter()
        .filter(|r| r.condition.seed == seed && r.condition.freq_hz == freq)
        .filter(|r| {
            assert_ne!(
                r.status,
                RowStatus::Failed,
                "{freq} Hz Gamma {} seed {seed}: {}",
                r.condition.gamma,
                r.note
            );
            r.status == RowStatus::Ok
        })
        .map(|r| (r.condition.gamma, r.efficiency, r.phase))
        .collect();
    rows.sort_by(|a, b| a.0.total_cmp(&b.0));
    assert!(
        rows.len() >= 5,
        "{freq} Hz seed {seed}: {} Gamma ran",
        rows.len()
    );
    rows
}

/// The peaks of a curve (see the module docs): (Γ, efficiency, prominence,
/// index), in order of Γ.
fn peaks(curve: &[(f64, f64, Option<MotionalPhase>)]) -> Vec<(f64, f64, f64, usize)> {
    let eta: Vec<f64> = curve.iter().map(|c| c.1).collect();
    let mut found = Vec::new();
    for i in 1..eta.len().saturating_sub(1) {
        if !(eta[i] > eta[i - 1] && eta[i] >= eta[i + 1]) {
            continue;
        }
        // Lowest point on each side before a higher one (or the grid's end).
        let base = |side: &mut dyn Iterator<Item = usize>| {
            side.map(|j| eta[j])
                .take_while(|&e| e <= eta[i])
                .fold(f64::INFINITY, f64::min)
        };
        let left = base(&mut (0..i).rev());
        let right = base(&mut (i + 1..eta.len()));
        let prominence = eta[i] - left.max(right);
        if prominence >= PROMINENCE {
            found.push((curve[i].0, eta[i], prominence, i));
        }
    }
    found
}

/// The Γ of `grid` nearest `gamma` in log Γ.
fn nearest(grid: &[f64], gamma: f64) -> f64 {
    grid.iter()
        .copied()
        .min_by(|a, b| {
            (a.ln() - gamma.ln())
                .abs()
                .total_cmp(&(b.ln() - gamma.ln()).abs())
        })
        .expect("a grid")
}

/// Γ at the vertex of the parabola in log Γ through `points` (Γ, efficiency).
fn parabola_peak(points: [(f64, f64); 3]) -> f64 {
    let [(x0, y0), (x1, y1), (x2, y2)] = points.map(|(g, e)| (g.ln(), e));
    let denom = (x0 - x1) * (x0 - x2) * (x1 - x2);
    let a = (x2 * (y1 - y0) + x1 * (y0 - y2) + x0 * (y2 - y1)) / denom;
    let b = (x2 * x2 * (y0 - y1) + x1 * x1 * (y2 - y0) + x0 * x0 * (y1 - y2)) / denom;
    (-b / (2.0 * a)).exp()
}

/// The bouncing-bed peak at index `i` of `curve`, interpolated: within 15 %
/// of the thesis' Γ.
fn assert_interpolated_peak_near(
    what: &str,
    curve: &[(f64, f64, Option<MotionalPhase>)],
    i: usize,
    thesis_gamma: f64,
) {
    let at = |k: usize| (curve[k].0, curve[k].1);
    let gamma = parabola_peak([at(i - 1), at(i), at(i + 1)]);
    eprintln!("{what}: interpolated peak at Gamma {gamma:.2}, the thesis' {thesis_gamma}");
    assert!(
        (gamma / thesis_gamma - 1.0).abs() < 0.15,
        "{what}: interpolated peak at Gamma {gamma:.2}, the thesis' {thesis_gamma}"
    );
}

/// A peak the thesis puts at Γ `thesis_gamma` in phase `phase`: at the grid Γ
/// nearest it, above 0.3.
fn assert_peak_at(
    what: &str,
    curve: &[(f64, f64, Option<MotionalPhase>)],
    peak: (f64, f64, f64, usize),
    thesis_gamma: f64,
    phase: MotionalPhase,
) {
    let grid: Vec<f64> = curve.iter().map(|c| c.0).collect();
    let expected = nearest(&grid, thesis_gamma);
    let (gamma, eta, _, i) = peak;
    assert_eq!(
        gamma, expected,
        "{what}: peak at Gamma {gamma}, the thesis' {thesis_gamma} is nearest grid Gamma {expected}"
    );
    assert!(eta > 0.3, "{what}: peak efficiency {eta:.3}");
    assert_eq!(
        curve[i].2,
        Some(phase),
        "{what}: the peak at Gamma {gamma} is {}",
        phase_name(curve[i].2)
    );
}

fn describe(peaks: &[(f64, f64, f64, usize)]) -> String {
    peaks
        .iter()
        .map(|p| format!("{:.3} at Gamma {} (prominence {:.3})", p.1, p.0, p.2))
        .collect::<Vec<_>>()
        .join(", ")
}

/// The claims of the module docs, for one seed of `file`, at those of 20, 40
/// and 80 Hz it holds.
fn assert_thesis_claims(file: &SweepFile, seed: u64) {
    let has = |freq: f64| {
        file.rows
            .iter()
            .any(|r| r.condition.seed == seed && r.condition.freq_hz == freq)
    };
    assert!(has(20.0) && has(40.0), "seed {seed}: no 20 or 40 Hz rows");

    let c40 = curve(file, seed, 40.0);
    let p40 = peaks(&c40);
    eprintln!("seed {seed}, 40 Hz: peaks {}", describe(&p40));
    assert_eq!(p40.len(), 2, "seed {seed}, 40 Hz: peaks {}", describe(&p40));
    let what = format!("seed {seed}, 40 Hz");
    assert_peak_at(
        &format!("{what}, fluidisation"),
        &c40,
        p40[0],
        3.0,
        MotionalPhase::GlobalFluidisation,
    );
    assert_peak_at(
        &format!("{what}, bouncing bed"),
        &c40,
        p40[1],
        19.6,
        MotionalPhase::BouncingBed,
    );
    assert_interpolated_peak_near(&format!("{what}, bouncing bed"), &c40, p40[1].3, 19.6);
    let phase_at = |gamma: f64| {
        c40.iter()
            .find(|c| c.0 == gamma)
            .unwrap_or_else(|| panic!("{what}: no Gamma {gamma}"))
            .2
    };
    assert_eq!(phase_at(1.0), Some(MotionalPhase::SolidLike), "{what}");
    assert_eq!(phase_at(30.0), Some(MotionalPhase::BouncingBed), "{what}");

    let c20 = curve(file, seed, 20.0);
    let p20 = peaks(&c20);
    eprintln!("seed {seed}, 20 Hz: peaks {}", describe(&p20));
    assert_eq!(p20.len(), 1, "seed {seed}, 20 Hz: peaks {}", describe(&p20));
    assert_peak_at(
        &format!("seed {seed}, 20 Hz"),
        &c20,
        p20[0],
        5.2,
        MotionalPhase::BouncingBed,
    );
    assert_interpolated_peak_near(&format!("seed {seed}, 20 Hz"), &c20, p20[0].3, 5.2);

    if has(80.0) {
        let c80 = curve(file, seed, 80.0);
        let p80 = peaks(&c80);
        eprintln!("seed {seed}, 80 Hz: peaks {}", describe(&p80));
        assert_eq!(p80.len(), 1, "seed {seed}, 80 Hz: peaks {}", describe(&p80));
        let (gamma, eta, _, i) = p80[0];
        let at_40 = nearest(&c40.iter().map(|c| c.0).collect::<Vec<_>>(), 3.0);
        assert!(
            gamma <= at_40 && gamma >= 2.0,
            "seed {seed}, 80 Hz: fluidisation peak at Gamma {gamma}, not in [2, {at_40}]"
        );
        assert!(eta > 0.3, "seed {seed}, 80 Hz: peak efficiency {eta:.3}");
        assert_eq!(
            c80[i].2,
            Some(MotionalPhase::GlobalFluidisation),
            "seed {seed}, 80 Hz"
        );
        let bouncing: Vec<f64> = c80
            .iter()
            .filter(|c| c.2 == Some(MotionalPhase::BouncingBed))
            .map(|c| c.0)
            .collect();
        assert!(
            bouncing.is_empty(),
            "seed {seed}, 80 Hz: a bouncing bed at Gamma {bouncing:?}, below the thesis' onset 79.9"
        );
    }
}

#[test]
fn the_reference_steady_sweep_has_the_peaks_for_every_seed() {
    let path =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("signals/reference/sweep-steady/sweep.csv");
    let file = SweepFile::read(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    // The whole grid is there for every seed and frequency: a peak cannot
    // hide in a missing row.
    for seed in 1..=3u64 {
        for freq in [20.0, 40.0, 80.0] {
            for gamma in GAMMAS {
                assert!(
                    file.rows.iter().any(|r| r.condition.seed == seed
                        && r.condition.freq_hz == freq
                        && r.condition.gamma == gamma),
                    "no row for {freq} Hz, Gamma {gamma}, seed {seed}"
                );
            }
        }
        assert_thesis_claims(&file, seed);
    }
}

/// The peak finder itself: two peaks of prominence 0.3 (one to the grid's
/// start on its left, one to a higher end on its right) are found, a wiggle
/// of 0.05 and the grid's rising end are not; "nearest" is in log Γ.
#[test]
fn the_peak_finder_finds_prominent_interior_maxima() {
    let c: Vec<(f64, f64, Option<MotionalPhase>)> = [
        (1.0, 0.0),
        (2.0, 0.5),
        (3.0, 0.2),
        (4.0, 0.25),
        (5.0, 0.2),
        (6.0, 0.6),
        (7.0, 0.3),
        (8.0, 0.9),
    ]
    .iter()
    .map(|&(g, e)| (g, e, None))
    .collect();
    let p = peaks(&c);
    let at: Vec<(f64, f64)> = p.iter().map(|p| (p.0, (p.2 * 1e9).round() / 1e9)).collect();
    assert_eq!(at, vec![(2.0, 0.3), (6.0, 0.3)], "{}", describe(&p));
    // y = 1 - (ln G - ln 4)^2 peaks at G = 4.
    let y = |g: f64| 1.0 - (g.ln() - 4f64.ln()).powi(2);
    let vertex = parabola_peak([(2.0, y(2.0)), (3.0, y(3.0)), (8.0, y(8.0))]);
    assert!((vertex - 4.0).abs() < 1e-9, "{vertex}");
    assert_eq!(nearest(&GAMMAS, 19.6), 20.0);
    assert_eq!(nearest(&GAMMAS, 15.0), 12.0);
    assert_eq!(nearest(&GAMMAS, 5.2), 5.0);
}

#[test]
#[ignore = "long: a 20-condition sweep of the thesis scene; run with --ignored"]
fn the_thesis_damper_has_its_efficiency_peaks_where_the_thesis_has_them() {
    let plan = SweepPlan {
        scene: Scene::thesis(),
        rig: "thesis-shaker".into(),
        shaker: None,
        freqs_hz: vec![20.0, 40.0],
        gammas: GAMMAS.to_vec(),
        seeds: vec![1],
        fill_ratios: vec![],
        orientations: vec![],
        beds: vlab::experiment::bed::cache::BedSource::Settle,
        ensemble_beds: 1,
    };
    let dir = std::env::temp_dir().join(format!("vlab-maps-thesis-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("scratch folder");
    let file = run_sweep(&plan, Shard::ALL, &dir, false, &|e| {
        if let vlab::study::sweep::SweepEvent::ConditionDone {
            row, done, total, ..
        } = e
        {
            eprintln!(
                "{done}/{total} {} Hz Gamma {}: {:?} {:.3} {}",
                row.condition.freq_hz,
                row.condition.gamma,
                row.status,
                row.efficiency,
                phase_name(row.phase)
            );
        }
    })
    .expect("the sweep runs");
    std::fs::remove_dir_all(&dir).ok();

    assert_thesis_claims(&file, 1);
}
