//! `vlab sweep optimum`: the optimum Γ of several sweeps, one point each,
//! against a number that tells them apart (a shape's aspect ratio, hole
//! ratio or sphericity, a fill ratio): the figure of Terzioglu's thesis
//! Fig. 8.11–8.12 (Γ_optimum against the shape), with each point's ± from
//! its seeds ([`vlab::study::sweep_peak`]).

use std::io::Write as _;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use clap::Args;

use vlab::atomic_write::{OutputDir, write_atomic};
use vlab::signals::{ErrorSeries, LogXPlot, plot_log_x};
use vlab::study::sweep::SweepFile;
use vlab::study::sweep_peak::{SeriesPeak, series_peaks};

#[derive(Debug, Clone, Args)]
pub struct OptimumArgs {
    /// One point: `SERIES@X=SWEEP`, the series it belongs to (its legend),
    /// its x (positive) and a sweep.csv or its folder; e.g.
    /// `prolates@1.5=sweep-prolate15`. Give one per sweep.
    #[arg(long = "point", value_name = "SERIES@X=SWEEP", required = true)]
    points: Vec<String>,
    /// Frequency of the series to read from each sweep (Hz) [default: the
    /// sweep's only one].
    #[arg(long = "freq", value_name = "HZ")]
    freq_hz: Option<f64>,
    /// Label of the x axis.
    #[arg(long = "x-label", default_value = "x")]
    x_label: String,
    /// Folder for optimum.csv and its plot (SVG and PNG).
    #[arg(long, value_name = "DIR", required = true)]
    out: PathBuf,
}

/// One sweep's optimum.
struct Point {
    series: String,
    x: f64,
    sweep: PathBuf,
    peak: SeriesPeak,
}

pub fn run(a: OptimumArgs) -> Result<()> {
    let mut points = Vec::new();
    for text in &a.points {
        let (series, x, path) = parse_point(text)?;
        let sweep = if path.is_dir() {
            path.join("sweep.csv")
        } else {
            path
        };
        let file = SweepFile::read(&sweep)?;
        let peak = pick_series(series_peaks(&file), a.freq_hz)
            .with_context(|| format!("--point {text}"))?;
        points.push(Point {
            series,
            x,
            sweep,
            peak,
        });
    }
    let made = OutputDir::prepare(&a.out)
        .with_context(|| format!("cannot create output folder {}", a.out.display()))?;
    made.keep_if_ok(write_csv(&a.out.join("optimum.csv"), &points))?;
    let plot = optimum_plot(&points, &a.x_label);
    for ext in ["svg", "png"] {
        let path = a.out.join(format!("optimum.{ext}"));
        plot_log_x(&path, &plot).with_context(|| format!("cannot draw {}", path.display()))?;
    }
    print_table(&points, &a.out);
    Ok(())
}

/// `SERIES@X=PATH`.
fn parse_point(text: &str) -> Result<(String, f64, PathBuf)> {
    let bad = || {
        anyhow::anyhow!(
            "--point {text}: must be SERIES@X=SWEEP (a legend, a positive number and a sweep.csv or its folder), e.g. prolates@1.5=sweep-prolate15"
        )
    };
    let (left, path) = text.split_once('=').ok_or_else(bad)?;
    let (series, x) = left.rsplit_once('@').ok_or_else(bad)?;
    let x: f64 = x.trim().parse().map_err(|_| bad())?;
    if series.trim().is_empty() || path.is_empty() || !(x.is_finite() && x > 0.0) {
        return Err(bad());
    }
    Ok((series.trim().to_string(), x, PathBuf::from(path)))
}

/// The series at `freq_hz`, or the only one.
fn pick_series(peaks: Vec<SeriesPeak>, freq_hz: Option<f64>) -> Result<SeriesPeak> {
    let freqs: Vec<String> = peaks.iter().map(|p| format!("{} Hz", p.freq_hz)).collect();
    let mut chosen: Vec<SeriesPeak> = peaks
        .into_iter()
        .filter(|p| freq_hz.is_none_or(|f| p.freq_hz == f))
        .collect();
    match chosen.len() {
        1 => Ok(chosen.remove(0)),
        0 => bail!(
            "the sweep has no series{} with an ok row (it has: {})",
            freq_hz.map_or(String::new(), |f| format!(" at {f} Hz")),
            if freqs.is_empty() {
                "none".into()
            } else {
                freqs.join(", ")
            }
        ),
        n => bail!(
            "the sweep has {n} series ({}): choose one with --freq, or a sweep of one fill ratio and orientation",
            freqs.join(", ")
        ),
    }
}

/// The optimum Γ of a point and its ± (NaN when not known): the seeds' mean
/// and standard error when at least two seeds peak inside the grid, else
/// the peak of the seeds' mean curve.
fn optimum(p: &SeriesPeak) -> (f64, f64) {
    match (p.gamma_mean, p.gamma_stderr, p.of_mean) {
        (Some(m), Some(se), _) => (m, se),
        (_, _, Some(peak)) => (peak.gamma, f64::NAN),
        _ => (f64::NAN, f64::NAN),
    }
}

/// A point whose curve peaks at the grid's end (or not at all) has no
/// optimum to plot; the table says so.
fn beyond(p: &SeriesPeak) -> bool {
    p.of_mean.is_none_or(|m| m.at_edge)
}

/// What to say of a point's peak beside its number.
fn caveat(p: &SeriesPeak) -> &'static str {
    match p.of_mean {
        Some(peak) if peak.at_edge => "beyond the grid",
        Some(peak) if peak.overshoots => "jumps: between the neighbours",
        Some(_) => "",
        None => "no peak",
    }
}

fn write_csv(path: &Path, points: &[Point]) -> Result<()> {
    write_atomic(path, |w| {
        writeln!(
            w,
            "series,x,gamma_optimum,gamma_optimum_se,seeds,peak_efficiency,caveat,sweep"
        )?;
        for p in points {
            let (g, se) = optimum(&p.peak);
            writeln!(
                w,
                "{},{},{g},{se},{},{},{},{}",
                p.series,
                p.x,
                p.peak.per_seed.iter().flatten().count(),
                p.peak.of_mean.map_or(f64::NAN, |m| m.efficiency),
                caveat(&p.peak),
                p.sweep.display()
            )?;
        }
        Ok(())
    })
    .with_context(|| format!("cannot write {}", path.display()))
}

fn optimum_plot(points: &[Point], x_label: &str) -> LogXPlot {
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
                .filter(|p| p.series == *name && !beyond(&p.peak))
                .map(|p| {
                    let (g, se) = optimum(&p.peak);
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

fn print_table(points: &[Point], out: &Path) {
    println!(
        "{:<14} {:>8} {:>14} {:>6} {:>10}  note",
        "series", "x", "Gamma_opt", "seeds", "peak eff."
    );
    for p in points {
        let (g, se) = optimum(&p.peak);
        let pm = if se.is_finite() {
            format!("{g:.2} +- {se:.2}")
        } else {
            format!("{g:.2} +- n/a")
        };
        println!(
            "{:<14} {:>8} {:>14} {:>6} {:>10.3}  {}",
            p.series,
            p.x,
            pm,
            p.peak.per_seed.iter().flatten().count(),
            p.peak.of_mean.map_or(f64::NAN, |m| m.efficiency),
            caveat(&p.peak)
        );
    }
    println!("wrote {}/optimum.csv and optimum.svg/png", out.display());
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_point_is_a_series_a_positive_x_and_a_sweep() {
        let (s, x, p) = parse_point("prolates@1.5=sweeps/p15").expect("parses");
        assert_eq!(
            (s.as_str(), x, p),
            ("prolates", 1.5, PathBuf::from("sweeps/p15"))
        );
        for bad in [
            "prolates=p",
            "prolates@0=p",
            "@1=p",
            "a@1=",
            "a@x=p",
            "a@-2=p",
        ] {
            let e = parse_point(bad).expect_err(bad).to_string();
            assert!(e.contains("SERIES@X=SWEEP"), "{bad}: {e}");
        }
    }
}
