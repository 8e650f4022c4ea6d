//! `vlab sweep optimum`: the optimum Γ of several sweeps, one point each,
//! against a number that tells them apart (a shape's aspect ratio, hole
//! ratio or sphericity, a fill ratio): the figure of Terzioglu's thesis
//! Fig. 8.11–8.12 (Γ_optimum against the shape), with each point's ± from
//! its seeds ([`vlab::study::sweep_optimum`]).

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use clap::Args;

use vlab::atomic_write::OutputDir;
use vlab::study::sweep::SweepFile;
use vlab::study::sweep_optimum::{OptimumPoint, pick_series, write_optimum};
use vlab::study::sweep_peak::series_peaks;

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
        points.push(OptimumPoint {
            series,
            x,
            sweep,
            peak,
        });
    }
    let made = OutputDir::prepare(&a.out)
        .with_context(|| format!("cannot create output folder {}", a.out.display()))?;
    let written = write_optimum(&a.out, &points, &a.x_label)
        .with_context(|| format!("writing into {}", a.out.display()));
    made.keep_if_ok(written)?;
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

fn print_table(points: &[OptimumPoint], out: &Path) {
    println!(
        "{:<14} {:>8} {:>14} {:>6} {:>10}  note",
        "series", "x", "Gamma_opt", "seeds", "peak eff."
    );
    for p in points {
        let (g, se) = p.optimum();
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
            p.seeds(),
            p.peak_efficiency(),
            p.caveat()
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
