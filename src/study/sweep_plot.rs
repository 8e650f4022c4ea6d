//! The plots of a sweep, drawn from its `sweep.csv` alone (so `vlab plot`
//! can redraw them): efficiency against Γ on a log axis, one curve per
//! frequency, DEM (mean over seeds, error bars one standard error) and the
//! rig's measurement, with the bouncing-bed onsets predicted by eq.
//! 6.11–6.13 (thesis Fig. 6.8, 6.12, 7.10); and the efficiency map over
//! frequency × Γ with the heuristic's motional phase in each cell and the
//! onsets drawn across it (Fig. 6.2, 6.4). Close-packing onsets are long
//! dashes, loose-packing ones short dashes, in both plots; the legends sit
//! outside the data (right of the curves, under the map).

use std::path::{Path, PathBuf};

use crate::scene::Orientation;
use crate::signals::{
    ErrorSeries, HeatCell, HeatMap, HeatOverlay, LineDash, LogXPlot, MarkerLine, RgbColor,
    SignalsError, plot_heat_map, plot_log_x,
};
use crate::study::phases::MotionalPhase;
use crate::study::predict::BouncingBedPrediction;
use crate::study::predict::predict_bouncing_bed;
use crate::study::sweep::{ConditionSummary, RowStatus, SweepFile, SweepHeader, summarise};

/// Draws `efficiency.{svg,png}` and `map.{svg,png}` of `file` into `dir`
/// (one pair per fill ratio and orientation, suffixed when there are
/// several); returns the file names written.
pub fn plot_sweep(file: &SweepFile, dir: &Path) -> Result<Vec<PathBuf>, SignalsError> {
    let h = &file.header;
    let summary = summarise(file);
    let groups: Vec<(f64, Orientation)> = h
        .grid
        .fill_ratios
        .iter()
        .flat_map(|&f| h.grid.orientations.iter().map(move |&o| (f, o)))
        .collect();
    let mut written = Vec::new();
    for &(fill, orientation) in &groups {
        let suffix = if groups.len() > 1 {
            format!("-fill{fill}-{}", orientation.as_str())
        } else {
            String::new()
        };
        let rows: Vec<&ConditionSummary> = summary
            .iter()
            .filter(|s| s.fill_ratio.to_bits() == fill.to_bits() && s.orientation == orientation)
            .collect();
        if rows.iter().all(|r| r.n == 0) {
            continue;
        }
        let length = h.length_for_fill_m(fill);
        let prediction = predict_bouncing_bed(&h.grid.freqs_hz, fill, length, h.gravity_mps2).ok();
        let what = format!(
            "{} damper, fill {:.3}, {}",
            h.scene,
            fill,
            orientation.as_str()
        );
        let curve = efficiency_curves(
            &what,
            h.grid.freqs_hz.as_slice(),
            &rows,
            prediction.as_ref(),
        );
        let map = efficiency_map(&what, h, &rows, prediction.as_ref());
        for ext in ["svg", "png"] {
            let e = dir.join(format!("efficiency{suffix}.{ext}"));
            plot_log_x(&e, &curve)?;
            written.push(e);
            let m = dir.join(format!("map{suffix}.{ext}"));
            plot_heat_map(&m, &map)?;
            written.push(m);
        }
    }
    Ok(written)
}

fn efficiency_curves(
    what: &str,
    freqs: &[f64],
    rows: &[&ConditionSummary],
    prediction: Option<&BouncingBedPrediction>,
) -> LogXPlot {
    let mut series = Vec::new();
    let mut markers = Vec::new();
    for (k, &f) in freqs.iter().enumerate() {
        let at: Vec<&&ConditionSummary> = rows
            .iter()
            .filter(|r| r.freq_hz.to_bits() == f.to_bits() && r.n > 0)
            .collect();
        series.push(ErrorSeries {
            name: format!("DEM {f} Hz"),
            points: at
                .iter()
                .map(|r| (r.gamma, r.efficiency, r.efficiency_se))
                .collect(),
            color: k,
            line: true,
        });
        series.push(ErrorSeries {
            name: format!("measured {f} Hz"),
            points: at
                .iter()
                .map(|r| (r.gamma, r.efficiency_measured, f64::NAN))
                .collect(),
            color: k,
            line: false,
        });
        if let Some(p) = prediction {
            markers.push(MarkerLine {
                name: format!("CP onset {f} Hz: {:.1}", p.close_packing_gamma[k]),
                x: p.close_packing_gamma[k],
                color: k,
                dash: LineDash::Long,
            });
            if let Some(lp) = &p.loose_packing_gamma {
                markers.push(MarkerLine {
                    name: format!("LP onset {f} Hz: {:.1}", lp[k]),
                    x: lp[k],
                    color: k,
                    dash: LineDash::Short,
                });
            }
        }
    }
    // Onsets far beyond the swept amplitudes would squeeze the curves.
    let gmax = rows.iter().map(|r| r.gamma).fold(0.0, f64::max);
    markers.retain(|m| m.x <= 1.5 * gmax);
    LogXPlot {
        title: format!("{what}: damping efficiency (eq. 6.8)"),
        x_label: "Gamma (peak enclosure acceleration / g)".into(),
        y_label: "damping efficiency".into(),
        series,
        markers,
        reference_y: Some(0.3),
        y_from_zero: true,
    }
}

fn efficiency_map(
    what: &str,
    h: &SweepHeader,
    rows: &[&ConditionSummary],
    prediction: Option<&BouncingBedPrediction>,
) -> HeatMap {
    // Rows of the map: the amplitudes in ascending order.
    let mut gammas = h.grid.gammas.clone();
    gammas.sort_by(f64::total_cmp);
    gammas.dedup();
    let mut freqs = h.grid.freqs_hz.clone();
    freqs.sort_by(f64::total_cmp);
    freqs.dedup();
    let (cells, hi) = map_cells(rows, &freqs, &gammas);
    let overlays = prediction.map_or_else(Vec::new, |p| {
        onset_overlays(p, &h.grid.freqs_hz, &freqs, &gammas)
    });
    HeatMap {
        title: format!("{what}: efficiency and motional phase"),
        x_label: "drive frequency (Hz)".into(),
        y_label: "Gamma".into(),
        columns: freqs.iter().map(|f| format!("{f}")).collect(),
        rows: gammas.iter().map(|g| format!("{g}")).collect(),
        cells,
        value_label: "efficiency".into(),
        value_range: (0.0, hi.max(0.1)),
        overlays,
        footnote: "phase (a heuristic, vlab::study::phases): S solid-like, LF/GF local/global fluidisation, BB bouncing bed, C convection/Leidenfrost; rig: beyond the rig".into(),
    }
}

/// The map's cells (column: frequency in `freqs`, row: Γ in `gammas`) with
/// the phase's tag and the efficiency, or why there is none; and the largest
/// efficiency.
fn map_cells(rows: &[&ConditionSummary], freqs: &[f64], gammas: &[f64]) -> (Vec<HeatCell>, f64) {
    let mut cells = Vec::new();
    let mut hi: f64 = 0.0;
    for r in rows {
        let col = freqs
            .iter()
            .position(|f| f.to_bits() == r.freq_hz.to_bits());
        let row = gammas.iter().position(|g| g.to_bits() == r.gamma.to_bits());
        let (Some(col), Some(row)) = (col, row) else {
            continue;
        };
        let (value, text) = if r.n > 0 {
            hi = hi.max(r.efficiency);
            let tag = r.phase.map_or("?", MotionalPhase::abbreviation);
            (Some(r.efficiency), format!("{tag}\n{:.2}", r.efficiency))
        } else if r.status == RowStatus::Unreachable {
            (None, "rig".to_string())
        } else {
            (None, r.status.as_str().to_string())
        };
        cells.push(HeatCell {
            col,
            row,
            value,
            text,
        });
    }
    (cells, hi)
}

/// The predicted bouncing-bed onsets `p` (one per frequency of the sweep's
/// `sweep_freqs`) as a segment across each column of the map whose columns
/// are `freqs` and rows `gammas` (log-interpolated between rows).
fn onset_overlays(
    p: &BouncingBedPrediction,
    sweep_freqs: &[f64],
    freqs: &[f64],
    gammas: &[f64],
) -> Vec<HeatOverlay> {
    let mut overlays = Vec::new();
    let lg: Vec<f64> = gammas.iter().map(|g| g.ln()).collect();
    let y_of = |g: f64| -> Option<f64> {
        let x = g.ln();
        if lg.len() < 2 || x < lg[0] || x > lg[lg.len() - 1] {
            return None;
        }
        let k = lg.partition_point(|&v| v <= x).clamp(1, lg.len() - 1);
        let f = (x - lg[k - 1]) / (lg[k] - lg[k - 1]);
        Some((k - 1) as f64 + 0.5 + f)
    };
    let segments = |gs: &[f64]| -> Vec<[(f64, f64); 2]> {
        freqs
            .iter()
            .enumerate()
            .filter_map(|(c, f)| {
                let k = sweep_freqs
                    .iter()
                    .position(|x| x.to_bits() == f.to_bits())?;
                let c = c as f64;
                y_of(gs[k]).map(|y| [(c + 0.05, y), (c + 0.95, y)])
            })
            .collect()
    };
    for (name, gammas, dash) in [
        (
            "bouncing-bed onset, close packing (eq. 6.11-6.13)",
            Some(&p.close_packing_gamma),
            LineDash::Long,
        ),
        (
            "bouncing-bed onset, loose packing",
            p.loose_packing_gamma.as_ref(),
            LineDash::Short,
        ),
    ] {
        // Loose packing has no onset above its own fill (0.55).
        let Some(gammas) = gammas else { continue };
        let segments = segments(gammas);
        if !segments.is_empty() {
            overlays.push(HeatOverlay {
                name: name.into(),
                segments,
                color: RgbColor(230, 30, 30),
                dash,
            });
        }
    }
    overlays
}
