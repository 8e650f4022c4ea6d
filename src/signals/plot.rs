//! Small SVG plots of x-y data: time traces, COR against impact speed,
//! efficiency against Gamma. No thesis equation lives here.
//!
//! Plots are rendered by plotters' SVG backend into a string, then written
//! with [`crate::atomic_write`], so a failed plot never leaves half an SVG.
//! Text is laid out with plotters' built-in size estimate (no font files are
//! needed); the viewer's sans-serif font draws it. Every point is drawn:
//! decimate long traces before plotting them.

use std::path::Path;

use plotters::prelude::*;

use super::error::{Result, SignalsError};
use crate::atomic_write::write_bytes_atomic;

/// Plot size in pixels.
pub const PLOT_SIZE_PX: (u32, u32) = (800, 600);

/// How a series is drawn.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SeriesStyle {
    /// Points joined by straight lines, in order.
    Line,
    /// A small circle per point.
    Points,
}

/// One named set of (x, y) points.
#[derive(Debug, Clone, PartialEq)]
pub struct Series {
    /// Legend text.
    pub name: String,
    /// Points, all finite.
    pub points: Vec<(f64, f64)>,
    /// Line or points.
    pub style: SeriesStyle,
}

/// Writes an SVG plot of `series` to `path` (atomically). Axis ranges cover
/// all points with a 5 % margin; at least one point is needed and every point
/// must be finite.
pub fn plot_xy_svg(
    path: &Path,
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[Series],
) -> Result<()> {
    let plot_err = |message: String| SignalsError::Plot {
        path: path.to_path_buf(),
        message,
    };
    for s in series {
        if let Some(i) = s
            .points
            .iter()
            .position(|(x, y)| !(x.is_finite() && y.is_finite()))
        {
            return Err(plot_err(format!(
                "series '{}' point {i} is ({}, {}): points must be finite",
                s.name, s.points[i].0, s.points[i].1
            )));
        }
    }
    let all = series.iter().flat_map(|s| s.points.iter().copied());
    let Some((x_range, y_range)) = ranges(all) else {
        return Err(plot_err("no points to plot".into()));
    };

    let mut svg = String::new();
    render(&mut svg, title, x_label, y_label, series, x_range, y_range)
        .map_err(|e| plot_err(e.to_string()))?;
    write_bytes_atomic(path, svg.as_bytes()).map_err(|source| SignalsError::Io {
        path: path.to_path_buf(),
        source,
    })
}

type Range = std::ops::Range<f64>;

/// Padded x and y ranges of the points, or None when there are none.
fn ranges(points: impl Iterator<Item = (f64, f64)>) -> Option<(Range, Range)> {
    let mut it = points.peekable();
    let &(x0, y0) = it.peek()?;
    let (mut xmin, mut xmax, mut ymin, mut ymax) = (x0, x0, y0, y0);
    for (x, y) in it {
        xmin = xmin.min(x);
        xmax = xmax.max(x);
        ymin = ymin.min(y);
        ymax = ymax.max(y);
    }
    Some((pad(xmin, xmax), pad(ymin, ymax)))
}

/// Widens [lo, hi] by 5 % each side; a single value gets +-5 % of itself (or +-1).
fn pad(lo: f64, hi: f64) -> Range {
    let span = hi - lo;
    let margin = if span > 0.0 {
        0.05 * span
    } else if lo != 0.0 {
        0.05 * lo.abs()
    } else {
        1.0
    };
    (lo - margin)..(hi + margin)
}

fn render(
    svg: &mut String,
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[Series],
    x_range: Range,
    y_range: Range,
) -> std::result::Result<(), Box<dyn std::error::Error>> {
    let root = SVGBackend::with_string(svg, PLOT_SIZE_PX).into_drawing_area();
    root.fill(&WHITE)?;
    let mut chart = ChartBuilder::on(&root)
        .caption(title, ("sans-serif", 24))
        .margin(12)
        .x_label_area_size(48)
        .y_label_area_size(72)
        .build_cartesian_2d(x_range, y_range)?;
    chart
        .configure_mesh()
        .x_desc(x_label)
        .y_desc(y_label)
        .draw()?;
    for (i, s) in series.iter().enumerate() {
        let color = Palette99::pick(i).to_rgba();
        let drawn = match s.style {
            SeriesStyle::Line => chart.draw_series(LineSeries::new(
                s.points.iter().copied(),
                color.stroke_width(2),
            ))?,
            SeriesStyle::Points => {
                chart.draw_series(s.points.iter().map(|&p| Circle::new(p, 3, color.filled())))?
            }
        };
        drawn
            .label(s.name.as_str())
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], color));
    }
    if series.iter().any(|s| !s.name.is_empty()) {
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .draw()?;
    }
    root.present()?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn writes_an_svg_with_title_labels_and_legend() {
        let dir = std::env::temp_dir().join(format!("vlab-plot-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("dir");
        let path = dir.join("cor.svg");
        let series = [
            Series {
                name: "smooth".into(),
                points: vec![(0.5, 0.91), (0.8, 0.905), (1.1, 0.915)],
                style: SeriesStyle::Points,
            },
            Series {
                name: "mean".into(),
                points: vec![(0.5, 0.91), (1.1, 0.91)],
                style: SeriesStyle::Line,
            },
        ];
        plot_xy_svg(
            &path,
            "COR vs impact velocity",
            "impact speed [m/s]",
            "COR [-]",
            &series,
        )
        .expect("plot");
        let svg = std::fs::read_to_string(&path).expect("read");
        assert!(svg.starts_with("<svg"), "{}", &svg[..40.min(svg.len())]);
        for text in [
            "COR vs impact velocity",
            "impact speed [m/s]",
            "smooth",
            "mean",
            "<circle",
        ] {
            assert!(svg.contains(text), "missing {text}");
        }
        std::fs::remove_dir_all(dir).ok();
    }

    #[test]
    fn refuses_empty_and_non_finite_input() {
        let path = std::env::temp_dir().join("vlab-plot-never-written.svg");
        assert!(plot_xy_svg(&path, "t", "x", "y", &[]).is_err());
        let bad = Series {
            name: "s".into(),
            points: vec![(0.0, 1.0), (1.0, f64::NAN)],
            style: SeriesStyle::Line,
        };
        let err = plot_xy_svg(&path, "t", "x", "y", &[bad]).expect_err("NaN");
        assert!(err.to_string().contains("series 's' point 1"), "{err}");
        assert!(!path.exists());
        // A single point still gets a usable range.
        assert_eq!(pad(2.0, 2.0), 1.9..2.1);
        assert_eq!(pad(0.0, 0.0), -1.0..1.0);
    }
}
