//! Where a sweep's efficiency peaks against Γ: the optimum amplitude of a
//! series (one fill, orientation and frequency), as Terzioglu's thesis reads
//! it from curves fitted through its runs (Table 6.3; Chapter 8's
//! Γ_optimum of each shape, Fig. 8.11–8.14).
//!
//! A parabola in ln Γ through the largest efficiency of the series and its
//! two neighbours on the grid gives the peak's Γ and height. It is fitted to
//! each seed's curve and to the seeds' mean; the ± is the standard error of
//! the per-seed peaks (their spread over √n), so it says how far the peak
//! moves from bed to bed, not how finely the grid resolves it. A largest
//! value at either end of the grid has no neighbour beyond it: the peak lies
//! beyond the grid, and is reported so, not extrapolated. Where the curve
//! jumps between two grid points (a sharp bouncing-bed onset: 0.23 at Γ 25,
//! 0.89 at Γ 30) the parabola overshoots the values it was fitted to, and
//! the peak is marked so: its Γ lies between the neighbours, not at the
//! vertex.

use serde::Serialize;

use crate::scene::Orientation;
use crate::study::sweep::{RowStatus, SweepFile};

/// The peak of one curve.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Peak {
    /// Γ at the peak (the grid point itself when the curve peaks at an end).
    pub gamma: f64,
    /// Efficiency at the peak.
    pub efficiency: f64,
    /// The largest value is at an end of the grid: the peak lies beyond.
    pub at_edge: bool,
    /// The parabola's peak stands more than [`OVERSHOOT_REL`] above the
    /// largest value it was fitted to: the curve jumps (a bouncing-bed
    /// onset between two grid points) rather than rounds, and the peak's Γ
    /// is known only to lie between the largest point's neighbours.
    pub overshoots: bool,
}

/// How far (relative) a fitted peak may stand above the largest value
/// before the fit is said to overshoot.
pub const OVERSHOOT_REL: f64 = 0.01;

/// The peak of `(Γ, efficiency)` points (any order; Γ > 0, distinct): the
/// vertex of the parabola in ln Γ through the largest and its neighbours.
/// `None` for fewer than one finite point.
pub fn log_parabola_peak(points: &[(f64, f64)]) -> Option<Peak> {
    let mut p: Vec<(f64, f64)> = points
        .iter()
        .copied()
        .filter(|(g, e)| g.is_finite() && *g > 0.0 && e.is_finite())
        .collect();
    p.sort_by(|a, b| a.0.total_cmp(&b.0));
    let k = (0..p.len()).max_by(|&a, &b| p[a].1.total_cmp(&p[b].1))?;
    if k == 0 || k + 1 == p.len() {
        return Some(Peak {
            gamma: p[k].0,
            efficiency: p[k].1,
            at_edge: true,
            overshoots: false,
        });
    }
    let (x0, x1, x2) = (p[k - 1].0.ln(), p[k].0.ln(), p[k + 1].0.ln());
    let (y0, y1, y2) = (p[k - 1].1, p[k].1, p[k + 1].1);
    // Newton's form through the three points: divided differences.
    let d01 = (y1 - y0) / (x1 - x0);
    let d12 = (y2 - y1) / (x2 - x1);
    let c = (d12 - d01) / (x2 - x0);
    if c >= 0.0 {
        // Not a maximum (a flat or convex triple): the largest point.
        return Some(Peak {
            gamma: p[k].0,
            efficiency: y1,
            at_edge: false,
            overshoots: false,
        });
    }
    // y = y0 + d01 (x - x0) + c (x - x0)(x - x1); dy/dx = 0 at
    // x* = (x0 + x1)/2 - d01 / (2 c).
    let x = 0.5 * (x0 + x1) - d01 / (2.0 * c);
    let y = y0 + d01 * (x - x0) + c * (x - x0) * (x - x1);
    Some(Peak {
        gamma: x.exp(),
        efficiency: y,
        at_edge: false,
        overshoots: y > y1 * (1.0 + OVERSHOOT_REL),
    })
}

/// The peak of one series of a sweep.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SeriesPeak {
    pub fill_ratio: f64,
    pub orientation: Orientation,
    pub freq_hz: f64,
    /// The peak of the seeds' mean curve.
    pub of_mean: Option<Peak>,
    /// Each seed's peak, in the grid's seed order (none for a seed without
    /// an ok row).
    pub per_seed: Vec<Option<Peak>>,
    /// Mean and standard error of the per-seed peaks' Γ, from at least two
    /// seeds whose peaks lie inside the grid; none otherwise.
    pub gamma_mean: Option<f64>,
    pub gamma_stderr: Option<f64>,
}

/// The peak of every series of `file`, by the DEM efficiency of its ok rows.
pub fn series_peaks(file: &SweepFile) -> Vec<SeriesPeak> {
    let g = &file.header.grid;
    let mut out = Vec::new();
    for &fill_ratio in &g.fill_ratios {
        for &orientation in &g.orientations {
            for &freq_hz in &g.freqs_hz {
                let rows: Vec<_> = file
                    .rows
                    .iter()
                    .filter(|r| {
                        let c = &r.condition;
                        r.status == RowStatus::Ok
                            && c.fill_ratio.to_bits() == fill_ratio.to_bits()
                            && c.orientation == orientation
                            && c.freq_hz.to_bits() == freq_hz.to_bits()
                    })
                    .collect();
                if rows.is_empty() {
                    continue;
                }
                let per_seed: Vec<Option<Peak>> = g
                    .seeds
                    .iter()
                    .map(|&seed| {
                        let pts: Vec<(f64, f64)> = rows
                            .iter()
                            .filter(|r| r.condition.seed == seed)
                            .map(|r| (r.condition.gamma, r.efficiency))
                            .collect();
                        log_parabola_peak(&pts)
                    })
                    .collect();
                let mean_pts: Vec<(f64, f64)> = g
                    .gammas
                    .iter()
                    .filter_map(|&gamma| {
                        let e: Vec<f64> = rows
                            .iter()
                            .filter(|r| r.condition.gamma.to_bits() == gamma.to_bits())
                            .map(|r| r.efficiency)
                            .collect();
                        (!e.is_empty()).then(|| (gamma, e.iter().sum::<f64>() / e.len() as f64))
                    })
                    .collect();
                let inside: Vec<f64> = per_seed
                    .iter()
                    .flatten()
                    .filter(|p| !p.at_edge)
                    .map(|p| p.gamma)
                    .collect();
                let (gamma_mean, gamma_stderr) = mean_and_stderr(&inside);
                out.push(SeriesPeak {
                    fill_ratio,
                    orientation,
                    freq_hz,
                    of_mean: log_parabola_peak(&mean_pts),
                    per_seed,
                    gamma_mean,
                    gamma_stderr,
                });
            }
        }
    }
    out
}

/// Mean and standard error of the mean of `x`, from two values on.
fn mean_and_stderr(x: &[f64]) -> (Option<f64>, Option<f64>) {
    let n = x.len();
    if n < 2 {
        return (None, None);
    }
    let mean = x.iter().sum::<f64>() / n as f64;
    let var = x.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1) as f64;
    (Some(mean), Some((var / n as f64).sqrt()))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Points on an exact parabola in ln Γ with its vertex at Γ 21.2 and
    /// height 0.83 (the thesis damper's 40 Hz peak as docs/maps.md reads
    /// it): the fit returns the vertex to 1e-9 whatever the grid's spacing
    /// and order. A fit in Γ rather than ln Γ, or a vertex formula with a
    /// sign slip, misses it by percent.
    #[test]
    fn an_exact_log_parabola_gives_its_vertex() {
        let (g0, e0, c) = (21.2f64, 0.83, -0.9);
        let f = |g: f64| e0 + c * (g.ln() - g0.ln()).powi(2);
        let pts: Vec<(f64, f64)> = [30.0, 12.0, 20.0, 5.0, 3.0]
            .iter()
            .map(|&g| (g, f(g)))
            .collect();
        let p = log_parabola_peak(&pts).expect("peak");
        assert!(!p.at_edge);
        assert!((p.gamma / g0 - 1.0).abs() < 1e-9, "{p:?}");
        assert!((p.efficiency - e0).abs() < 1e-9, "{p:?}");
    }

    /// A jump at the onset (the toroids of hole ratio 0.05 at 40 Hz: 0.227
    /// at Γ 25, 0.891 at 30, 0.851 at 35) makes the parabola stand above
    /// every point: marked as overshooting; a rounded peak is not.
    #[test]
    fn a_jump_at_the_onset_is_marked_as_overshooting() {
        let jump = log_parabola_peak(&[(25.0, 0.227), (30.0, 0.891), (35.0, 0.851)]);
        assert!(jump.expect("peak").overshoots, "{jump:?}");
        let round = log_parabola_peak(&[(20.0, 0.803), (25.0, 0.834), (30.0, 0.750)]);
        assert!(!round.expect("peak").overshoots, "{round:?}");
    }

    /// A curve still rising at the grid's last Γ peaks beyond it: reported
    /// at that Γ and marked, not extrapolated; an empty or non-finite
    /// series has no peak.
    #[test]
    fn a_peak_at_the_edge_is_marked() {
        let p = log_parabola_peak(&[(3.0, 0.2), (10.0, 0.4), (20.0, 0.8)]).expect("peak");
        assert!(p.at_edge && p.gamma == 20.0, "{p:?}");
        assert!(log_parabola_peak(&[]).is_none());
        assert!(log_parabola_peak(&[(5.0, f64::NAN)]).is_none());
    }

    /// The standard error of per-seed peaks is their spread over √n: 20,
    /// 22 and 24 give 22 ± 1.155; one value gives none.
    #[test]
    fn per_seed_peaks_give_a_mean_and_its_error() {
        let (m, se) = mean_and_stderr(&[20.0, 22.0, 24.0]);
        assert!((m.expect("mean") - 22.0).abs() < 1e-12);
        assert!((se.expect("se") - 2.0 / 3f64.sqrt()).abs() < 1e-12);
        assert_eq!(mean_and_stderr(&[20.0]), (None, None));
    }
}
