//! The optimum Γ of several sweeps, one point each, against a number that
//! tells them apart (a shape's aspect ratio, hole ratio or sphericity, a
//! fill ratio): the figure of Terzioglu's thesis, Fig. 8.11–8.12 (Γ_optimum
//! against the shape), with each point's ± from its seeds
//! ([`super::sweep_peak`]), its table (`optimum.csv`) and its plot.
//! `vlab sweep optimum` parses the points and prints the table.

use std::io::Write as _;
use std::path::{Path, PathBuf};

use crate::atomic_write::write_atomic;
#[cfg(feature = "plot")]
use crate::signals::{ErrorSeries, LogXPlot};

use super::sweep_peak::SeriesPeak;

/// One sweep's optimum: the series it belongs to (its legend), its x and
/// the sweep it was read from.
#[derive(Debug, Clone)]
pub struct OptimumPoint {
    pub series: String,
    pub x: f64,
    pub sweep: PathBuf,
    pub peak: SeriesPeak,
}

/// Why a sweep gives no point.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PickError {
    #[error("the sweep has no series{} with an ok row (it has: {})", at(*freq_hz), list(series))]
    NoSeries {
        freq_hz: Option<f64>,
        series: Vec<String>,
    },
    #[error("the sweep has {} series ({}): choose one with --freq, or a sweep of one fill ratio and orientation", series.len(), series.join(", "))]
    Several { series: Vec<String> },
}

fn at(freq_hz: Option<f64>) -> String {
    freq_hz.map_or(String::new(), |f| format!(" at {f} Hz"))
}

fn list(series: &[String]) -> String {
    match series.is_empty() {
        true => "none".into(),
        false => series.join(", "),
    }
}

/// Of a sweep's series, the one at `freq_hz`, or the only one.
pub fn pick_series(peaks: Vec<SeriesPeak>, freq_hz: Option<f64>) -> Result<SeriesPeak, PickError> {
    let freqs: Vec<String> = peaks.iter().map(|p| format!("{} Hz", p.freq_hz)).collect();
    let mut chosen: Vec<SeriesPeak> = peaks
        .into_iter()
        .filter(|p| freq_hz.is_none_or(|f| p.freq_hz == f))
        .collect();
    match chosen.len() {
        1 => Ok(chosen.remove(0)),
        0 => Err(PickError::NoSeries {
            freq_hz,
            series: freqs,
        }),
        _ => Err(PickError::Several { series: freqs }),
    }
}

impl OptimumPoint {
    /// The optimum Γ and its ± (NaN when not known): the seeds' mean and
    /// standard error when at least two seeds peak inside the grid, else
    /// the peak of the seeds' mean curve.
    pub fn optimum(&self) -> (f64, f64) {
        let p = &self.peak;
        match (p.gamma_mean, p.gamma_stderr, p.of_mean) {
            (Some(m), Some(se), _) => (m, se),
            (_, _, Some(peak)) => (peak.gamma, f64::NAN),
            _ => (f64::NAN, f64::NAN),
        }
    }

    /// A curve that peaks at the grid's end (or not at all) has no optimum
    /// to plot; the table says so.
    pub fn beyond(&self) -> bool {
        self.peak.of_mean.is_none_or(|m| m.at_edge)
    }

    /// What to say of the peak beside its number.
    pub fn caveat(&self) -> &'static str {
        match self.peak.of_mean {
            Some(peak) if peak.at_edge => "beyond the grid",
            Some(peak) if peak.overshoots => "jumps: between the neighbours",
            Some(_) => "",
            None => "no peak",
        }
    }

    /// Seeds that peaked.
    pub fn seeds(&self) -> usize {
        self.peak.per_seed.iter().flatten().count()
    }

    /// The efficiency at the peak of the seeds' mean curve (NaN without).
    pub fn peak_efficiency(&self) -> f64 {
        self.peak.of_mean.map_or(f64::NAN, |m| m.efficiency)
    }
}

/// `optimum.csv`: one row per point.
pub fn optimum_csv(points: &[OptimumPoint]) -> String {
    let mut csv = String::from(
        "series,x,gamma_optimum,gamma_optimum_se,seeds,peak_efficiency,caveat,sweep\n",
    );
    for p in points {
        let (g, se) = p.optimum();
        csv.push_str(&format!(
            "{},{},{g},{se},{},{},{},{}\n",
            p.series,
            p.x,
            p.seeds(),
            p.peak_efficiency(),
            p.caveat(),
            p.sweep.display()
        ));
    }
    csv
}

/// The plot: each series' optimum against x, with its ±, the points
/// beyond the grid left out.
#[cfg(feature = "plot")]
pub fn optimum_plot(points: &[OptimumPoint], x_label: &str) -> LogXPlot {
    let mut names: Vec<&str> = Vec::new();
    for p in points {
        if !names.contains(&p.series.as_str()) {
            names.push(&p.series);
        }
    }
    let series = names
        .iter()
        .enumerate()
        .map(|(color, name)| {
            let mut pts: Vec<(f64, f64, f64)> = points
                .iter()
                .filter(|p| p.series == *name && !p.beyond())
                .map(|p| {
                    let (g, se) = p.optimum();
                    (p.x, g, se)
                })
                .collect();
            pts.sort_by(|a, b| a.0.total_cmp(&b.0));
            ErrorSeries {
                name: name.to_string(),
                points: pts,
                color,
                line: true,
            }
        })
        .collect();
    LogXPlot {
        title: "Optimum amplitude (bouncing-bed onset), +- from seeds".into(),
        x_label: x_label.into(),
        y_label: "Gamma_optimum".into(),
        series,
        markers: Vec::new(),
        reference_y: None,
        y_from_zero: false,
    }
}

/// Writes `optimum.csv` and, with plots, `optimum.svg` and `optimum.png`
/// into `dir`, which must exist, each file atomically.
pub fn write_optimum(
    dir: &Path,
    points: &[OptimumPoint],
    x_label: &str,
) -> Result<(), crate::scene::SceneError> {
    let fail = |path: PathBuf| move |source| crate::scene::SceneError::Write { path, source };
    let path = dir.join("optimum.csv");
    let csv = optimum_csv(points);
    write_atomic(&path, |w| w.write_all(csv.as_bytes())).map_err(fail(path))?;
    #[cfg(feature = "plot")]
    {
        let plot = optimum_plot(points, x_label);
        for ext in ["svg", "png"] {
            let path = dir.join(format!("optimum.{ext}"));
            crate::signals::plot_log_x(&path, &plot)
                .map_err(|e| std::io::Error::other(e.to_string()))
                .map_err(fail(path))?;
        }
    }
    #[cfg(not(feature = "plot"))]
    let _ = x_label;
    Ok(())
}
