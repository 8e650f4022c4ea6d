//! The motional-phase heuristic pinned on the reference sweep (issue 11,
//! item 3): `signals/reference/sweep-thesis/sweep.csv` (the thesis damper at
//! 20, 40 and 80 Hz, Γ 1–40, seeds 1–3, 8-cycle protocol) stores each row's
//! indicators and the name the heuristic gave them. Naming every row again
//! with this vlab's thresholds, which is what `vlab sweep relabel` does,
//! must change nothing (a threshold tuned by accident shows up here, with the
//! rows it renamed), and at 40 Hz every seed must name Γ 1 solid-like and
//! Γ 30 a bouncing bed, as the issue asks. Exact: names are compared as text.

use std::path::Path;

use vlab::study::phases::{MotionalPhase, PhaseThresholds};
use vlab::study::sweep::{RowStatus, SweepFile, SweepRow, phase_name};

fn reference() -> SweepFile {
    let path =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("signals/reference/sweep-thesis/sweep.csv");
    SweepFile::read(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

fn describe(r: &SweepRow) -> String {
    let c = &r.condition;
    format!("{} Hz Gamma {} seed {}", c.freq_hz, c.gamma, c.seed)
}

#[test]
fn relabelling_the_reference_sweep_changes_no_row() {
    let stored = reference();
    let ok: Vec<&SweepRow> = stored
        .rows
        .iter()
        .filter(|r| r.status == RowStatus::Ok)
        .collect();
    // 3 frequencies x 10 amplitudes x 3 seeds, less 20 Hz Γ 20-40 (beyond the
    // rig's stroke): 81 ok rows, each with its indicators and a known name.
    assert_eq!(ok.len(), 81, "ok rows of the reference sweep");
    for r in &ok {
        assert!(r.indicators.is_some(), "{}: no indicators", describe(r));
        assert!(r.phase.is_some(), "{}: no phase", describe(r));
    }
    let mut relabelled = stored.clone();
    let changed = relabelled.relabel(&PhaseThresholds::default());
    let renamed: Vec<String> = stored
        .rows
        .iter()
        .zip(&relabelled.rows)
        .filter(|(a, b)| a.phase != b.phase)
        .map(|(a, b)| {
            format!(
                "{}: {} -> {}",
                describe(a),
                phase_name(a.phase),
                phase_name(b.phase)
            )
        })
        .collect();
    assert!(
        renamed.is_empty() && changed == 0,
        "the heuristic renames {changed} reference rows: {}",
        renamed.join("; ")
    );
}

#[test]
fn forty_hertz_gamma_1_is_solid_like_and_gamma_30_a_bouncing_bed_for_every_seed() {
    let mut file = reference();
    file.relabel(&PhaseThresholds::default());
    let seeds = file.header.grid.seeds.clone();
    assert_eq!(seeds, vec![1, 2, 3]);
    for (gamma, expected) in [
        (1.0, MotionalPhase::SolidLike),
        (30.0, MotionalPhase::BouncingBed),
    ] {
        for &seed in &seeds {
            let row = file
                .rows
                .iter()
                .find(|r| {
                    let c = &r.condition;
                    c.freq_hz == 40.0 && c.gamma == gamma && c.seed == seed
                })
                .unwrap_or_else(|| panic!("no row for 40 Hz Gamma {gamma} seed {seed}"));
            assert_eq!(row.status, RowStatus::Ok, "{}", describe(row));
            assert_eq!(row.phase, Some(expected), "{}", describe(row));
        }
    }
}
