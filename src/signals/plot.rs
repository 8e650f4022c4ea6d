//! Small plots of x-y data: time traces, COR against impact speed,
//! efficiency against Gamma on a log axis with error bars and marker lines,
//! and heat maps of a value over two lists of conditions. No thesis equation
//! lives here.
//!
//! The file's extension picks the format: `.svg` (plotters' SVG backend,
//! rendered into a string) or `.png` (plotters' bitmap backend, rendered to a
//! hidden temporary file next to the target). Either is then put in place
//! atomically ([`crate::atomic_write`]), so a failed plot never leaves half a
//! file. Text is laid out, and drawn in PNGs, with DejaVu Sans, embedded in the
//! binary by the `dejavu` crate (Bitstream Vera licence) and registered with
//! plotters' `ab_glyph` renderer as "sans-serif": no system font is needed; an
//! SVG viewer draws the text with its own sans-serif font. Every point is
//! drawn: decimate long traces before plotting them.

use std::path::Path;

use plotters::coord::Shift;
use plotters::coord::combinators::{BindKeyPoints, LogCoord, WithKeyPoints};
use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};

use super::error::{Result, SignalsError};
use crate::atomic_write::write_bytes_atomic;

type DrawResult = std::result::Result<(), Box<dyn std::error::Error>>;

/// Registers the embedded font with plotters, once.
fn register_font() {
    static ONCE: std::sync::Once = std::sync::Once::new();
    ONCE.call_once(|| {
        // DejaVu Sans is a valid TrueType font; were it not, text would fail
        // to draw and the plot would report it.
        let _ = plotters::style::register_font(
            "sans-serif",
            FontStyle::Normal,
            dejavu::sans::regular(),
        );
    });
}

/// A figure that can draw itself on any plotters backend.
trait Figure {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult
    where
        DB::ErrorType: 'static;
}

/// Draws `figure` into `path`, SVG or PNG by the extension, atomically.
fn write_figure(path: &Path, size: (u32, u32), figure: &impl Figure) -> Result<()> {
    register_font();
    let plot_err = |message: String| SignalsError::Plot {
        path: path.to_path_buf(),
        message,
    };
    let io_err = |source: std::io::Error| SignalsError::Io {
        path: path.to_path_buf(),
        source,
    };
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    match ext.as_deref() {
        Some("svg") => {
            let mut svg = String::new();
            {
                let root = SVGBackend::with_string(&mut svg, size).into_drawing_area();
                figure.draw(&root).map_err(|e| plot_err(e.to_string()))?;
            }
            write_bytes_atomic(path, svg.as_bytes()).map_err(io_err)
        }
        Some("png") => {
            let name = path
                .file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_default();
            let tmp = path.with_file_name(format!(".{name}.tmp-{}.png", std::process::id()));
            let drawn = {
                let root = BitMapBackend::new(&tmp, size).into_drawing_area();
                figure.draw(&root).map_err(|e| plot_err(e.to_string()))
            };
            let moved = drawn.and_then(|()| std::fs::rename(&tmp, path).map_err(io_err));
            if moved.is_err() {
                let _ = std::fs::remove_file(&tmp);
            }
            moved
        }
        _ => Err(plot_err(
            "the file name must end in .svg or .png".to_string(),
        )),
    }
}

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

/// Writes a plot of `series` to `path` (SVG or PNG by its extension,
/// atomically). Axis ranges cover all points with a 5 % margin; at least one
/// point is needed and every point must be finite.
pub fn plot_xy_svg(
    path: &Path,
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[Series],
) -> Result<()> {
    plot_xy_svg_spanning(path, title, x_label, y_label, series, 0.0)
}

/// [`plot_xy_svg`] with a y axis at least `min_y_span` tall, centred on the
/// points: a scatter of 0.05 % around a restitution of 0.91 then shows as
/// the flat line it is, not as a trend across the whole plot.
pub fn plot_xy_svg_spanning(
    path: &Path,
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[Series],
    min_y_span: f64,
) -> Result<()> {
    check_finite(path, series)?;
    let all = series.iter().flat_map(|s| s.points.iter().copied());
    let Some((x_range, mut y_range)) = ranges(all) else {
        return Err(SignalsError::Plot {
            path: path.to_path_buf(),
            message: "no points to plot".into(),
        });
    };
    let span = y_range.end - y_range.start;
    if span < min_y_span {
        let mid = 0.5 * (y_range.start + y_range.end);
        y_range = (mid - 0.5 * min_y_span)..(mid + 0.5 * min_y_span);
    }
    let y_range = with_legend_room(series, &x_range, y_range);
    let figure = XyFigure {
        title,
        x_label,
        y_label,
        series,
        x_range,
        y_range,
    };
    write_figure(path, PLOT_SIZE_PX, &figure)
}

fn check_finite(path: &Path, series: &[Series]) -> Result<()> {
    for s in series {
        if let Some(i) = s
            .points
            .iter()
            .position(|(x, y)| !(x.is_finite() && y.is_finite()))
        {
            return Err(SignalsError::Plot {
                path: path.to_path_buf(),
                message: format!(
                    "series '{}' point {i} is ({}, {}): points must be finite",
                    s.name, s.points[i].0, s.points[i].1
                ),
            });
        }
    }
    Ok(())
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

struct XyFigure<'a> {
    title: &'a str,
    x_label: &'a str,
    y_label: &'a str,
    series: &'a [Series],
    x_range: Range,
    y_range: Range,
}

impl Figure for XyFigure<'_> {
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult
    where
        DB::ErrorType: 'static,
    {
        root.fill(&WHITE)?;
        let (width_px, _) = root.dim_in_pixel();
        let mut chart = ChartBuilder::on(root)
            .caption(
                self.title,
                ("sans-serif", title_font_px(self.title, width_px, 24)),
            )
            .margin(12)
            .x_label_area_size(48)
            .y_label_area_size(72)
            .build_cartesian_2d(self.x_range.clone(), self.y_range.clone())?;
        chart
            .configure_mesh()
            .x_desc(self.x_label)
            .y_desc(self.y_label)
            .draw()?;
        // Lines first, then points over them: a measured point on its line
        // still shows. Each series keeps the colour of its place in the list.
        let lines_then_points = self
            .series
            .iter()
            .enumerate()
            .filter(|(_, s)| s.style == SeriesStyle::Line)
            .chain(
                self.series
                    .iter()
                    .enumerate()
                    .filter(|(_, s)| s.style == SeriesStyle::Points),
            );
        for (i, s) in lines_then_points {
            let color = Palette99::pick(i).to_rgba();
            let drawn = match s.style {
                SeriesStyle::Line => chart.draw_series(LineSeries::new(
                    s.points.iter().copied(),
                    color.stroke_width(2),
                ))?,
                SeriesStyle::Points => chart
                    .draw_series(s.points.iter().map(|&p| Circle::new(p, 4, color.filled())))?,
            };
            drawn
                .label(s.name.as_str())
                .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], color));
        }
        if self.series.iter().any(|s| !s.name.is_empty()) {
            chart
                .configure_series_labels()
                .position(emptiest_corner(self.series, &self.x_range, &self.y_range).0)
                .background_style(WHITE.mix(0.8))
                .border_style(BLACK)
                .draw()?;
        }
        root.present()?;
        Ok(())
    }
}

/// The caption's font size (px): `preferred`, or smaller so that `title`
/// fits `width_px` (DejaVu Sans averages about 0.55 em a character; a PNG's
/// text is wider than the SVG viewer's).
fn title_font_px(title: &str, width_px: u32, preferred: u32) -> u32 {
    let chars = title.chars().count().max(1) as f64;
    let fits = (f64::from(width_px) - 24.0) / (0.55 * chars);
    (fits.floor() as u32).clamp(12, preferred)
}

/// The legend box's share of the plot area (width, height) for the named
/// series of `series`: about 20 px a row and 7 px a character, and the
/// gap plotters leaves at the corner, of an 800 × 600 figure's plot area
/// of about 700 × 500 px.
fn legend_share(series: &[Series]) -> (f64, f64) {
    let named = series.iter().filter(|s| !s.name.is_empty());
    let rows = named.clone().count() as f64;
    let chars = named.map(|s| s.name.chars().count()).max().unwrap_or(0) as f64;
    (
        ((chars * 7.0 + 70.0) / 700.0).min(0.9),
        ((rows * 20.0 + 32.0) / 500.0).min(0.9),
    )
}

/// The corner of the plot where the legend hides the fewest points, and how
/// many it hides there: each corner's box (the legend's size,
/// [`legend_share`]) counts the points of the series in it, and the lines'
/// points sampled along each segment.
fn emptiest_corner(series: &[Series], x: &Range, y: &Range) -> (SeriesLabelPosition, usize) {
    let (w, h) = (x.end - x.start, y.end - y.start);
    let (across, up) = legend_share(series);
    let mut samples: Vec<(f64, f64)> = Vec::new();
    for s in series {
        samples.extend(&s.points);
        if s.style == SeriesStyle::Line {
            for seg in s.points.windows(2) {
                let ((x0, y0), (x1, y1)) = (seg[0], seg[1]);
                samples.extend((1..64).map(|k| {
                    let t = k as f64 / 64.0;
                    (x0 + t * (x1 - x0), y0 + t * (y1 - y0))
                }));
            }
        }
    }
    let count = |right: bool, upper: bool| {
        samples
            .iter()
            .filter(|&&(px, py)| {
                let u = (px - x.start) / w;
                let v = (py - y.start) / h;
                (if right { u > 1.0 - across } else { u < across })
                    && (if upper { v > 1.0 - up } else { v < up })
            })
            .count()
    };
    [
        (SeriesLabelPosition::UpperRight, true, true),
        (SeriesLabelPosition::UpperLeft, false, true),
        (SeriesLabelPosition::LowerRight, true, false),
        (SeriesLabelPosition::LowerLeft, false, false),
    ]
    .into_iter()
    .map(|(c, right, upper)| (c, count(right, upper)))
    .min_by_key(|&(_, n)| n)
    .unwrap_or((SeriesLabelPosition::UpperRight, 0))
}

/// `y` with room on top for the legend when every corner of the plot holds
/// data: the range grows upwards until the legend's rows clear the highest
/// point, so the legend lies over none.
fn with_legend_room(series: &[Series], x: &Range, y: Range) -> Range {
    if !series.iter().any(|s| !s.name.is_empty()) || emptiest_corner(series, x, &y).1 == 0 {
        return y;
    }
    let (_, up) = legend_share(series);
    let span = y.end - y.start;
    y.start..y.end + span * up / (1.0 - up) * 1.1
}

/// Points with a symmetric error on y, drawn as a line through the points
/// with vertical error bars.
#[derive(Debug, Clone, PartialEq)]
pub struct ErrorSeries {
    pub name: String,
    /// (x, y, half-width of the error bar); a NaN half-width draws no bar.
    pub points: Vec<(f64, f64, f64)>,
    /// Palette index of the colour (series sharing one keep one colour).
    pub color: usize,
    /// Line through the points (else points only).
    pub line: bool,
}

/// How a [`MarkerLine`] or a [`HeatOverlay`] is dashed, so that two kinds of
/// line in one colour (close- and loose-packing predictions) stay apart.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum LineDash {
    /// Long dashes: 10 px drawn, 5 px gap.
    #[default]
    Long,
    /// Short dashes, nearly dots: 3 px drawn, 4 px gap.
    Short,
}

impl LineDash {
    /// (drawn, gap) in pixels.
    fn pattern(self) -> (u32, u32) {
        match self {
            LineDash::Long => (10, 5),
            LineDash::Short => (3, 4),
        }
    }
}

/// A labelled vertical line at `x` (dashed), e.g. a predicted optimum.
#[derive(Debug, Clone, PartialEq)]
pub struct MarkerLine {
    pub name: String,
    pub x: f64,
    pub color: usize,
    pub dash: LineDash,
}

/// A plot with a logarithmic x axis.
#[derive(Debug, Clone, PartialEq)]
pub struct LogXPlot {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    pub series: Vec<ErrorSeries>,
    pub markers: Vec<MarkerLine>,
    /// Horizontal reference level drawn as a thin grey line (e.g. 0.3), if any.
    pub reference_y: Option<f64>,
    /// The y axis starts at zero (an efficiency); else it spans the points
    /// (an optimum amplitude between 20 and 30).
    pub y_from_zero: bool,
}

/// Width of the legend panel right of a [`LogXPlot`]'s data area (px).
pub const LOG_X_LEGEND_WIDTH_PX: u32 = 200;

/// Size of a [`LogXPlot`] (px): [`PLOT_SIZE_PX`] and the legend panel.
pub const LOG_X_SIZE_PX: (u32, u32) = (PLOT_SIZE_PX.0 + LOG_X_LEGEND_WIDTH_PX, PLOT_SIZE_PX.1);

/// Writes a [`LogXPlot`] (SVG or PNG by the extension). x must be positive;
/// non-finite points are left out; at least one point is needed. The legend
/// is drawn in a panel right of the data area, so it never hides a point.
pub fn plot_log_x(path: &Path, plot: &LogXPlot) -> Result<()> {
    let pts = || {
        plot.series
            .iter()
            .flat_map(|s| s.points.iter())
            .filter(|p| p.0 > 0.0 && p.0.is_finite() && p.1.is_finite())
    };
    let (mut xmin, mut xmax) = (f64::INFINITY, f64::NEG_INFINITY);
    let (mut ymin, mut ymax) = (f64::INFINITY, f64::NEG_INFINITY);
    for &(x, y, e) in pts() {
        let e = if e.is_finite() { e } else { 0.0 };
        xmin = xmin.min(x);
        xmax = xmax.max(x);
        ymin = ymin.min(y - e);
        ymax = ymax.max(y + e);
    }
    for m in plot.markers.iter().filter(|m| m.x > 0.0 && m.x.is_finite()) {
        xmin = xmin.min(m.x);
        xmax = xmax.max(m.x);
    }
    if !xmin.is_finite() || !ymin.is_finite() {
        return Err(SignalsError::Plot {
            path: path.to_path_buf(),
            message: "no points to plot".into(),
        });
    }
    if let Some(r) = plot.reference_y {
        ymin = ymin.min(r);
        ymax = ymax.max(r);
    }
    let y_range = if plot.y_from_zero {
        pad(ymin.min(0.0), ymax)
    } else {
        pad(ymin, ymax)
    };
    let x_range = (xmin / 1.25)..(xmax * 1.25);
    write_figure(
        path,
        LOG_X_SIZE_PX,
        &LogXFigure {
            plot,
            x_range,
            y_range,
        },
    )
}

/// A log axis over `range` labelled at round numbers: 1, 2, 3, 5 times
/// the powers of ten, or, on a range too short for three of those (Γ 12 to
/// 44), 1, 1.5, 2, 3, 4, 5, 7, or, shorter still (a sphericity of 0.7 to
/// 1), every tenth; a light grid line at the other whole
/// numbers of each decade. (Left to itself a log axis inside one decade
/// labels nothing.)
fn log_axis(range: &Range) -> WithKeyPoints<LogCoord<f64>> {
    let (bold, light) = log_ticks(range.start, range.end);
    range
        .clone()
        .log_scale()
        .with_key_points(bold)
        .with_light_points(light)
}

/// The labelled and the light ticks of [`log_axis`] within `lo..hi`.
pub fn log_ticks(lo: f64, hi: f64) -> (Vec<f64>, Vec<f64>) {
    let within = |mantissas: &[f64]| -> Vec<f64> {
        let (first, last) = (lo.log10().floor() as i32, hi.log10().ceil() as i32);
        (first..=last)
            .flat_map(|e| mantissas.iter().map(move |m| m * 10f64.powi(e)))
            .map(|x| (x * 1e9).round() / 1e9)
            .filter(|&x| x >= lo && x <= hi)
            .collect()
    };
    let mut bold = within(&[1.0, 2.0, 3.0, 5.0]);
    if bold.len() < 3 {
        bold = within(&[1.0, 1.5, 2.0, 3.0, 4.0, 5.0, 7.0]);
    }
    if bold.len() < 3 {
        bold = within(&[1.0, 1.2, 1.5, 2.0, 2.5, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0]);
    }
    let light = within(&[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0])
        .into_iter()
        .filter(|x| !bold.contains(x))
        .collect();
    (bold, light)
}

struct LogXFigure<'a> {
    plot: &'a LogXPlot,
    x_range: Range,
    y_range: Range,
}

/// What a legend entry's sample looks like.
#[derive(Debug, Clone, Copy)]
enum LegendSample {
    /// A line through points (circles), width 2.
    LineWithPoints(RGBAColor),
    /// A filled triangle.
    Triangle(RGBAColor),
    /// A dashed line.
    Dashed(RGBAColor, LineDash, u32),
    /// A thin solid line.
    Thin(RGBAColor),
}

/// Draws `sample` over `x0..x0 + LEGEND_SAMPLE_PX` at height `y` of `area`.
fn draw_legend_sample<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    sample: LegendSample,
    x0: i32,
    y: i32,
) -> DrawResult
where
    DB::ErrorType: 'static,
{
    let x1 = x0 + LEGEND_SAMPLE_PX;
    match sample {
        LegendSample::LineWithPoints(c) => {
            area.draw(&PathElement::new(vec![(x0, y), (x1, y)], c.stroke_width(2)))?;
            area.draw(&Circle::new(((x0 + x1) / 2, y), 3, c.filled()))?;
        }
        LegendSample::Triangle(c) => {
            area.draw(&TriangleMarker::new(
                ((x0 + x1) / 2, y),
                8,
                c.stroke_width(2),
            ))?;
        }
        LegendSample::Dashed(c, dash, width) => {
            let (on, off) = dash.pattern();
            let mut x = x0;
            while x < x1 {
                let end = (x + on as i32).min(x1);
                area.draw(&PathElement::new(
                    vec![(x, y), (end, y)],
                    c.stroke_width(width),
                ))?;
                x += (on + off) as i32;
            }
        }
        LegendSample::Thin(c) => {
            area.draw(&PathElement::new(vec![(x0, y), (x1, y)], c.stroke_width(1)))?;
        }
    }
    Ok(())
}

/// Length of a legend entry's sample (px).
const LEGEND_SAMPLE_PX: i32 = 30;
/// Height of a legend line (px).
const LEGEND_LINE_PX: i32 = 19;

/// The chart of a [`LogXPlot`]: logarithmic x, linear y.
type LogXChart<'a, DB> =
    ChartContext<'a, DB, Cartesian2d<WithKeyPoints<LogCoord<f64>>, RangedCoordf64>>;

/// A legend of a [`LogXPlot`]: each entry's name and sample, in drawing order.
type LogXLegend = Vec<(String, LegendSample)>;

impl Figure for LogXFigure<'_> {
    /// In the order the figure is drawn (the SVG's element order is the order
    /// of the calls): mesh, series, markers, reference level, legend panel.
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult
    where
        DB::ErrorType: 'static,
    {
        let p = self.plot;
        root.fill(&WHITE)?;
        let (w, _) = root.dim_in_pixel();
        let body = root.titled(p.title.as_str(), ("sans-serif", 22))?;
        let (main, side) = body.split_horizontally(w - LOG_X_LEGEND_WIDTH_PX);
        let mut chart = ChartBuilder::on(&main)
            .margin(12)
            .x_label_area_size(48)
            .y_label_area_size(64)
            .build_cartesian_2d(log_axis(&self.x_range), self.y_range.clone())?;
        chart
            .configure_mesh()
            .x_desc(p.x_label.as_str())
            .y_desc(p.y_label.as_str())
            .x_label_formatter(&|x| format!("{x}"))
            .max_light_lines(2)
            .draw()?;
        let mut legend = LogXLegend::new();
        for s in &p.series {
            draw_error_series(&mut chart, s, &mut legend)?;
        }
        self.draw_markers(&mut chart, &mut legend)?;
        self.draw_reference(&mut chart, &mut legend)?;
        if !legend.is_empty() {
            draw_legend_panel(&side, &legend)?;
        }
        root.present()?;
        Ok(())
    }
}

impl LogXFigure<'_> {
    /// The marker lines, dashed across the y range.
    fn draw_markers<DB: DrawingBackend>(
        &self,
        chart: &mut LogXChart<'_, DB>,
        legend: &mut LogXLegend,
    ) -> DrawResult
    where
        DB::ErrorType: 'static,
    {
        let (y0, y1) = (self.y_range.start, self.y_range.end);
        for m in &self.plot.markers {
            let color = Palette99::pick(m.color).to_rgba();
            let (on, off) = m.dash.pattern();
            chart.draw_series(DashedLineSeries::new(
                [(m.x, y0), (m.x, y1)],
                on,
                off,
                color.stroke_width(2),
            ))?;
            legend.push((m.name.clone(), LegendSample::Dashed(color, m.dash, 2)));
        }
        Ok(())
    }

    /// The reference level, if any, across the x range.
    fn draw_reference<DB: DrawingBackend>(
        &self,
        chart: &mut LogXChart<'_, DB>,
        legend: &mut LogXLegend,
    ) -> DrawResult
    where
        DB::ErrorType: 'static,
    {
        if let Some(r) = self.plot.reference_y {
            // Darker than the grid, so the level reads as a line of its own.
            let grey = RGBColor(90, 90, 90).to_rgba();
            chart.draw_series(LineSeries::new(
                [(self.x_range.start, r), (self.x_range.end, r)],
                grey.stroke_width(1),
            ))?;
            legend.push((format!("efficiency {r}"), LegendSample::Thin(grey)));
        }
        Ok(())
    }
}

/// One series of a [`LogXPlot`] (its points with positive finite x and finite
/// y; none drawn when there are none): a line with points or triangles, then
/// its error bars.
fn draw_error_series<DB: DrawingBackend>(
    chart: &mut LogXChart<'_, DB>,
    s: &ErrorSeries,
    legend: &mut LogXLegend,
) -> DrawResult
where
    DB::ErrorType: 'static,
{
    let color = Palette99::pick(s.color).to_rgba();
    let ok: Vec<(f64, f64, f64)> = s
        .points
        .iter()
        .copied()
        .filter(|q| q.0 > 0.0 && q.0.is_finite() && q.1.is_finite())
        .collect();
    if ok.is_empty() {
        return Ok(());
    }
    if s.line {
        chart.draw_series(LineSeries::new(
            ok.iter().map(|q| (q.0, q.1)),
            color.stroke_width(2),
        ))?;
        chart.draw_series(
            ok.iter()
                .map(|q| Circle::new((q.0, q.1), 3, color.filled())),
        )?;
        legend.push((s.name.clone(), LegendSample::LineWithPoints(color)));
    } else {
        // Hollow and larger than the line's dots, so that a point on the
        // line (a measurement that agrees with the DEM) still shows.
        chart.draw_series(
            ok.iter()
                .map(|q| TriangleMarker::new((q.0, q.1), 8, color.stroke_width(2))),
        )?;
        legend.push((s.name.clone(), LegendSample::Triangle(color)));
    }
    chart.draw_series(ok.iter().filter(|q| q.2.is_finite() && q.2 > 0.0).map(|q| {
        ErrorBar::new_vertical(q.0, q.1 - q.2, q.1, q.1 + q.2, color.stroke_width(1), 8)
    }))?;
    Ok(())
}

/// The legend of a [`LogXPlot`], framed, in its own panel `side` right of
/// the data area.
fn draw_legend_panel<DB: DrawingBackend>(
    side: &DrawingArea<DB, Shift>,
    legend: &LogXLegend,
) -> DrawResult
where
    DB::ErrorType: 'static,
{
    let (x0, top) = (8, 14);
    let bottom = top + LEGEND_LINE_PX * legend.len() as i32 + 6;
    side.draw(&Rectangle::new(
        [(2, top - 10), (LOG_X_LEGEND_WIDTH_PX as i32 - 6, bottom)],
        BLACK.stroke_width(1),
    ))?;
    let font = ("sans-serif", 13)
        .into_font()
        .color(&BLACK)
        .pos(Pos::new(HPos::Left, VPos::Center));
    for (k, (name, sample)) in legend.iter().enumerate() {
        let y = top + LEGEND_LINE_PX * k as i32;
        draw_legend_sample(side, *sample, x0, y)?;
        side.draw(&Text::new(
            name.clone(),
            (x0 + LEGEND_SAMPLE_PX + 6, y),
            font.clone(),
        ))?;
    }
    Ok(())
}

/// One cell of a [`HeatMap`].
#[derive(Debug, Clone, PartialEq)]
pub struct HeatCell {
    /// Column and row (0-based; row 0 at the bottom).
    pub col: usize,
    pub row: usize,
    /// The value coloured; None draws a hatched grey cell.
    pub value: Option<f64>,
    /// Text written in the cell (one or two short lines, '\n' between).
    pub text: String,
}

/// Dashed segments over a [`HeatMap`], in cell coordinates (column c spans
/// x = c..c + 1, row r spans y = r..r + 1), e.g. a predicted amplitude
/// marked across each frequency's column.
#[derive(Debug, Clone, PartialEq)]
pub struct HeatOverlay {
    pub name: String,
    pub segments: Vec<[(f64, f64); 2]>,
    pub color: RgbColor,
    pub dash: LineDash,
}

/// A colour, for callers that do not use plotters.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RgbColor(pub u8, pub u8, pub u8);

/// A value over columns × rows of conditions, coloured, with text in each cell.
#[derive(Debug, Clone, PartialEq)]
pub struct HeatMap {
    pub title: String,
    pub x_label: String,
    pub y_label: String,
    pub columns: Vec<String>,
    pub rows: Vec<String>,
    pub cells: Vec<HeatCell>,
    /// Name of the value, on the colour bar.
    pub value_label: String,
    /// Values mapped to the ends of the colour scale.
    pub value_range: (f64, f64),
    pub overlays: Vec<HeatOverlay>,
    /// A note under the plot (e.g. a legend of the cell texts).
    pub footnote: String,
}

/// Size of a [`HeatMap`] (px).
pub const HEAT_MAP_SIZE_PX: (u32, u32) = (900, 730);

/// Writes a [`HeatMap`] (SVG or PNG by the extension). The overlays' legend
/// is drawn under the map, above the footnote, so it never hides a cell.
pub fn plot_heat_map(path: &Path, map: &HeatMap) -> Result<()> {
    if map.columns.is_empty() || map.rows.is_empty() {
        return Err(SignalsError::Plot {
            path: path.to_path_buf(),
            message: "a heat map needs at least one column and one row".into(),
        });
    }
    write_figure(path, HEAT_MAP_SIZE_PX, &HeatFigure(map))
}

struct HeatFigure<'a>(&'a HeatMap);

/// Room under a heat map's axis label for the legend and the footnote (px).
const HEAT_MAP_BOTTOM_PX: u32 = 64;
/// Height of the legend line above the figure's bottom edge (px); the
/// footnote is at 20.
const HEAT_MAP_LEGEND_FROM_BOTTOM_PX: i32 = 46;

/// Viridis, sampled at 6 stops and interpolated linearly; `t` in 0..1.
fn viridis(t: f64) -> RGBColor {
    const STOPS: [(f64, f64, f64); 6] = [
        (68.0, 1.0, 84.0),
        (65.0, 68.0, 135.0),
        (42.0, 120.0, 142.0),
        (34.0, 168.0, 132.0),
        (122.0, 209.0, 81.0),
        (253.0, 231.0, 37.0),
    ];
    let t = if t.is_finite() {
        t.clamp(0.0, 1.0)
    } else {
        0.0
    };
    let x = t * (STOPS.len() - 1) as f64;
    let i = (x.floor() as usize).min(STOPS.len() - 2);
    let f = x - i as f64;
    let (a, b) = (STOPS[i], STOPS[i + 1]);
    let mix = |p: f64, q: f64| (p + (q - p) * f).round() as u8;
    RGBColor(mix(a.0, b.0), mix(a.1, b.1), mix(a.2, b.2))
}

/// The chart of a heat map: cell coordinates on both axes.
type HeatChart<'a, DB> = ChartContext<'a, DB, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

impl Figure for HeatFigure<'_> {
    /// In the order the figure is drawn (the SVG's element order is the order
    /// of the calls): cells, hatching, overlays, cell texts, overlay legend,
    /// tick names, footnote, colour bar.
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult
    where
        DB::ErrorType: 'static,
    {
        let m = self.0;
        let (nc, nr) = (m.columns.len() as f64, m.rows.len() as f64);
        root.fill(&WHITE)?;
        let (w, h) = root.dim_in_pixel();
        let (main, bar) = root.split_horizontally(w - 110);
        let mut chart = ChartBuilder::on(&main)
            .caption(m.title.as_str(), ("sans-serif", 22))
            .margin(12)
            .margin_bottom(HEAT_MAP_BOTTOM_PX)
            .x_label_area_size(56)
            .y_label_area_size(72)
            .build_cartesian_2d(0f64..nc, 0f64..nr)?;
        chart
            .configure_mesh()
            .disable_mesh()
            .x_labels(0)
            .y_labels(0)
            .x_desc(m.x_label.as_str())
            .y_desc(m.y_label.as_str())
            .draw()?;
        self.draw_cells(&mut chart)?;
        self.draw_overlays(&mut chart)?;
        self.draw_cell_texts(&mut chart)?;
        self.draw_overlay_legend(root, h as i32 - HEAT_MAP_LEGEND_FROM_BOTTOM_PX)?;
        self.draw_tick_names(root, &chart)?;
        if !m.footnote.is_empty() {
            root.draw(&Text::new(
                m.footnote.clone(),
                (12, h as i32 - 20),
                ("sans-serif", 13)
                    .into_font()
                    .color(&BLACK)
                    .pos(Pos::new(HPos::Left, VPos::Center)),
            ))?;
        }
        draw_colour_bar(&bar, self.0.value_range, &self.0.value_label, &HEAT_BAR)?;
        root.present()?;
        Ok(())
    }
}

/// Where `v` falls on a colour scale spanning `range` (0 at its low end, 1 at
/// its high).
fn colour_position((lo, hi): (f64, f64), v: f64) -> f64 {
    (v - lo) / (hi - lo).max(f64::MIN_POSITIVE)
}

impl HeatFigure<'_> {
    /// Where `v` falls on the colour scale (0 at its low end, 1 at its high).
    fn scale(&self, v: f64) -> f64 {
        colour_position(self.0.value_range, v)
    }

    /// The cells, coloured by value, then the cells without one hatched.
    fn draw_cells<DB: DrawingBackend>(&self, chart: &mut HeatChart<'_, DB>) -> DrawResult
    where
        DB::ErrorType: 'static,
    {
        let m = self.0;
        chart.draw_series(m.cells.iter().map(|c| {
            let (x, y) = (c.col as f64, c.row as f64);
            let fill = match c.value {
                Some(v) if v.is_finite() => viridis(self.scale(v)).filled(),
                _ => RGBColor(215, 215, 215).filled(),
            };
            Rectangle::new([(x, y), (x + 1.0, y + 1.0)], fill)
        }))?;
        for c in m
            .cells
            .iter()
            .filter(|c| !c.value.is_some_and(f64::is_finite))
        {
            let (x, y) = (c.col as f64, c.row as f64);
            for k in 1..4 {
                let f = k as f64 / 4.0;
                chart.draw_series(LineSeries::new(
                    [(x + f, y), (x, y + f)],
                    RGBColor(160, 160, 160).stroke_width(1),
                ))?;
                chart.draw_series(LineSeries::new(
                    [(x + 1.0, y + f), (x + f, y + 1.0)],
                    RGBColor(160, 160, 160).stroke_width(1),
                ))?;
            }
        }
        Ok(())
    }

    /// The overlays, drawn before the cell texts so a line never hides a label.
    fn draw_overlays<DB: DrawingBackend>(&self, chart: &mut HeatChart<'_, DB>) -> DrawResult
    where
        DB::ErrorType: 'static,
    {
        for o in &self.0.overlays {
            let color = RGBColor(o.color.0, o.color.1, o.color.2);
            let (on, off) = o.dash.pattern();
            for seg in &o.segments {
                chart.draw_series(DashedLineSeries::new(
                    seg.iter().copied(),
                    on,
                    off,
                    color.stroke_width(3),
                ))?;
            }
        }
        Ok(())
    }

    /// Each cell's text, centred, white on dark cells, on a patch of the
    /// cell's own colour, so that an overlay line crossing the cell stops
    /// short of the text instead of striking through it.
    fn draw_cell_texts<DB: DrawingBackend>(&self, chart: &mut HeatChart<'_, DB>) -> DrawResult
    where
        DB::ErrorType: 'static,
    {
        let (w_px, h_px) = chart.plotting_area().dim_in_pixel();
        let cols = self.0.cells.iter().map(|c| c.col + 1).max().unwrap_or(1);
        let rows = self.0.cells.iter().map(|c| c.row + 1).max().unwrap_or(1);
        let (cell_w, cell_h) = (
            f64::from(w_px.max(1)) / cols as f64,
            f64::from(h_px.max(1)) / rows as f64,
        );
        for c in &self.0.cells {
            let dark = c
                .value
                .is_some_and(|v| v.is_finite() && self.scale(v) < 0.6);
            let color = if dark { WHITE } else { BLACK };
            let lines: Vec<&str> = c.text.lines().collect();
            let n = lines.len() as f64;
            if let Some(v) = c.value.filter(|v| v.is_finite()) {
                // About 7.5 px a character and 16 px a line at 13 px.
                let chars = lines.iter().map(|l| l.chars().count()).max().unwrap_or(0);
                let half_w = ((chars as f64 * 7.5 + 6.0) / cell_w).min(1.0) / 2.0;
                let half_h = ((16.0 * n + 2.0) / cell_h).min(1.0) / 2.0;
                let (cx, cy) = (c.col as f64 + 0.5, c.row as f64 + 0.5);
                chart.draw_series(std::iter::once(Rectangle::new(
                    [(cx - half_w, cy - half_h), (cx + half_w, cy + half_h)],
                    viridis(self.scale(v)).filled(),
                )))?;
            }
            for (k, line) in lines.iter().enumerate() {
                let dy = (k as f64 - (n - 1.0) / 2.0) * 0.22;
                let style = ("sans-serif", 13)
                    .into_font()
                    .color(&color)
                    .pos(Pos::new(HPos::Center, VPos::Center));
                chart.draw_series(std::iter::once(Text::new(
                    line.to_string(),
                    (c.col as f64 + 0.5, c.row as f64 + 0.5 - dy),
                    style,
                )))?;
            }
        }
        Ok(())
    }

    /// The overlays' legend, one line at height `legend_y` (px) under the
    /// map, above the footnote.
    fn draw_overlay_legend<DB: DrawingBackend>(
        &self,
        root: &DrawingArea<DB, Shift>,
        legend_y: i32,
    ) -> DrawResult
    where
        DB::ErrorType: 'static,
    {
        let mut x = 12;
        let font = ("sans-serif", 13)
            .into_font()
            .color(&BLACK)
            .pos(Pos::new(HPos::Left, VPos::Center));
        for o in self.0.overlays.iter().filter(|o| !o.segments.is_empty()) {
            let color = RGBColor(o.color.0, o.color.1, o.color.2).to_rgba();
            draw_legend_sample(root, LegendSample::Dashed(color, o.dash, 3), x, legend_y)?;
            x += LEGEND_SAMPLE_PX + 6;
            root.draw(&Text::new(o.name.clone(), (x, legend_y), font.clone()))?;
            let (tw, _) = root.estimate_text_size(&o.name, &font)?;
            x += tw as i32 + 24;
        }
        Ok(())
    }

    /// Column and row names at the cell centres.
    fn draw_tick_names<DB: DrawingBackend>(
        &self,
        root: &DrawingArea<DB, Shift>,
        chart: &HeatChart<'_, DB>,
    ) -> DrawResult
    where
        DB::ErrorType: 'static,
    {
        let m = self.0;
        let tick = ("sans-serif", 14).into_font();
        for (i, name) in m.columns.iter().enumerate() {
            let (px, py) = chart.backend_coord(&(i as f64 + 0.5, 0.0));
            root.draw(&Text::new(
                name.clone(),
                (px, py + 6),
                tick.clone()
                    .color(&BLACK)
                    .pos(Pos::new(HPos::Center, VPos::Top)),
            ))?;
        }
        for (j, name) in m.rows.iter().enumerate() {
            let (px, py) = chart.backend_coord(&(0.0, j as f64 + 0.5));
            root.draw(&Text::new(
                name.clone(),
                (px - 6, py),
                tick.clone()
                    .color(&BLACK)
                    .pos(Pos::new(HPos::Right, VPos::Center)),
            ))?;
        }
        Ok(())
    }
}

/// One panel of a [`PanelStrip`]: circles in data units, over a rectangle.
#[derive(Debug, Clone, PartialEq)]
pub struct CirclePanel {
    pub title: String,
    /// Opposite corners of the outline drawn behind the circles (data units).
    pub outline: [(f64, f64); 2],
    /// (x, y, radius, value), drawn in order (last on top).
    pub circles: Vec<(f64, f64, f64, f64)>,
}

/// Panels side by side sharing axes and a colour scale (e.g. views of a bed
/// at several phases of a cycle).
#[derive(Debug, Clone, PartialEq)]
pub struct PanelStrip {
    pub title: String,
    pub panels: Vec<CirclePanel>,
    /// Data ranges of every panel (equal scales keep circles round).
    pub x_range: (f64, f64),
    pub y_range: (f64, f64),
    pub value_label: String,
    pub value_range: (f64, f64),
    pub footnote: String,
}

/// Writes a [`PanelStrip`] (SVG or PNG by the extension).
pub fn plot_panel_strip(path: &Path, strip: &PanelStrip) -> Result<()> {
    let n = strip.panels.len().max(1) as u32;
    let (xw, yh) = (
        strip.x_range.1 - strip.x_range.0,
        strip.y_range.1 - strip.y_range.0,
    );
    if !(xw > 0.0 && yh > 0.0) || strip.panels.is_empty() {
        return Err(SignalsError::Plot {
            path: path.to_path_buf(),
            message: "a panel strip needs panels and positive ranges".into(),
        });
    }
    // More than four panels go on two rows, each panel larger.
    let (rows, cols) = strip_grid(n);
    let panel_w = 260u32;
    let panel_h = ((panel_w - 20) as f64 * yh / xw) as u32 + 50;
    write_figure(
        path,
        (cols * panel_w + 110, rows * panel_h + 100),
        &StripFigure(strip),
    )
}

/// Rows and columns of a strip of `n` panels.
fn strip_grid(n: u32) -> (u32, u32) {
    let rows = if n > 4 { 2 } else { 1 };
    (rows, n.div_ceil(rows))
}

struct StripFigure<'a>(&'a PanelStrip);

impl Figure for StripFigure<'_> {
    /// Panel by panel in drawing order, then the colour bar and the footnote
    /// (the SVG's element order is the order of the calls).
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> DrawResult
    where
        DB::ErrorType: 'static,
    {
        let s = self.0;
        root.fill(&WHITE)?;
        let (w, h) = root.dim_in_pixel();
        let titled = root.titled(s.title.as_str(), ("sans-serif", 20))?;
        let (body, foot) = titled.split_vertically(h as i32 - 70);
        let (panels_area, bar) = body.split_horizontally(w as i32 - 110);
        let (rows, cols) = strip_grid(s.panels.len() as u32);
        let areas = panels_area.split_evenly((rows as usize, cols as usize));
        for (area, panel) in areas.iter().zip(&s.panels) {
            self.draw_panel(area, panel)?;
        }
        draw_colour_bar(&bar, self.0.value_range, &self.0.value_label, &STRIP_BAR)?;
        for (k, line) in s.footnote.lines().enumerate() {
            foot.draw(&Text::new(
                line.to_string(),
                (12, 14 + 18 * k as i32),
                ("sans-serif", 13)
                    .into_font()
                    .color(&BLACK)
                    .pos(Pos::new(HPos::Left, VPos::Center)),
            ))?;
        }
        root.present()?;
        Ok(())
    }
}

impl StripFigure<'_> {
    /// Where `v` falls on the colour scale (0 at its low end, 1 at its high).
    fn scale(&self, v: f64) -> f64 {
        colour_position(self.0.value_range, v)
    }

    /// One panel in `area`: its outline, filled and framed, then its circles,
    /// coloured by value and outlined.
    fn draw_panel<DB: DrawingBackend>(
        &self,
        area: &DrawingArea<DB, Shift>,
        panel: &CirclePanel,
    ) -> DrawResult
    where
        DB::ErrorType: 'static,
    {
        let s = self.0;
        let mut chart = ChartBuilder::on(area)
            .caption(panel.title.as_str(), ("sans-serif", 14))
            .margin(6)
            .build_cartesian_2d(s.x_range.0..s.x_range.1, s.y_range.0..s.y_range.1)?;
        let [a, b] = panel.outline;
        chart.draw_series(std::iter::once(Rectangle::new(
            [a, b],
            RGBColor(235, 235, 235).filled(),
        )))?;
        chart.draw_series(std::iter::once(Rectangle::new(
            [a, b],
            BLACK.stroke_width(2),
        )))?;
        let (x0, _) = chart.backend_coord(&(s.x_range.0, s.y_range.0));
        let (x1, _) = chart.backend_coord(&(s.x_range.1, s.y_range.0));
        let px_per_unit = (x1 - x0) as f64 / (s.x_range.1 - s.x_range.0);
        chart.draw_series(panel.circles.iter().map(|&(x, y, r, v)| {
            let px = ((r * px_per_unit).round() as i32).max(1);
            Circle::new((x, y), px, viridis(self.scale(v)).filled())
        }))?;
        chart.draw_series(panel.circles.iter().map(|&(x, y, r, _)| {
            let px = ((r * px_per_unit).round() as i32).max(1);
            Circle::new((x, y), px, RGBColor(40, 40, 40).stroke_width(1))
        }))?;
        Ok(())
    }
}

/// Where a colour bar sits in its area (pixels) and its fonts' sizes.
struct ColourBarLayout {
    /// The scale's top edge, and its bottom edge's distance from the
    /// area's bottom.
    top: i32,
    bottom_margin: i32,
    /// The scale's right edge (its left is at 10) and where the ticks start.
    right: i32,
    tick_x: i32,
    tick_font: u32,
    /// The name's left edge, and its height above the scale's top.
    label_x: i32,
    label_above: i32,
    label_font: u32,
}

/// The heat map's colour bar.
const HEAT_BAR: ColourBarLayout = ColourBarLayout {
    top: 60,
    bottom_margin: 100,
    right: 40,
    tick_x: 46,
    tick_font: 13,
    label_x: 10,
    label_above: 24,
    label_font: 14,
};

/// The panel strip's colour bar.
const STRIP_BAR: ColourBarLayout = ColourBarLayout {
    top: 30,
    bottom_margin: 20,
    right: 35,
    tick_x: 40,
    tick_font: 12,
    label_x: 5,
    label_above: 16,
    label_font: 13,
};

/// The colour bar in `bar`: the viridis scale over `(lo, hi)`, its frame,
/// five value ticks and the value's name `label`.
fn draw_colour_bar<DB: DrawingBackend>(
    bar: &DrawingArea<DB, Shift>,
    (lo, hi): (f64, f64),
    label: &str,
    at: &ColourBarLayout,
) -> DrawResult
where
    DB::ErrorType: 'static,
{
    let (_, bh) = bar.dim_in_pixel();
    let (top, bottom) = (at.top, bh as i32 - at.bottom_margin);
    let steps = 100;
    for k in 0..steps {
        let t0 = k as f64 / steps as f64;
        let y_a = bottom - ((bottom - top) as f64 * t0) as i32;
        let y_b = bottom - ((bottom - top) as f64 * (t0 + 1.0 / steps as f64)) as i32;
        bar.draw(&Rectangle::new(
            [(10, y_b - 1), (at.right, y_a)],
            viridis(t0).filled(),
        ))?;
    }
    bar.draw(&Rectangle::new(
        [(10, top), (at.right, bottom)],
        BLACK.stroke_width(1),
    ))?;
    for k in 0..=4 {
        let t = k as f64 / 4.0;
        let y = bottom - ((bottom - top) as f64 * t) as i32;
        bar.draw(&Text::new(
            format!("{:.2}", lo + t * (hi - lo)),
            (at.tick_x, y),
            ("sans-serif", at.tick_font)
                .into_font()
                .color(&BLACK)
                .pos(Pos::new(HPos::Left, VPos::Center)),
        ))?;
    }
    bar.draw(&Text::new(
        label.to_string(),
        (at.label_x, top - at.label_above),
        ("sans-serif", at.label_font)
            .into_font()
            .color(&BLACK)
            .pos(Pos::new(HPos::Left, VPos::Center)),
    ))?;
    Ok(())
}

/// Each channel of `trace` against time, as `{stem}-{channel}.svg` and
/// `.png` in `dir` (which must exist), titled `{title}: {channel}`: what
/// `vlab plot` draws of a record that is not a sweep. The files drawn, in
/// order.
pub fn plot_channels(
    trace: &super::Trace,
    title: &str,
    dir: &Path,
    stem: &str,
) -> Result<Vec<std::path::PathBuf>> {
    let mut drawn = Vec::new();
    for ch in &trace.channels {
        let points: Vec<(f64, f64)> = ch
            .samples
            .iter()
            .enumerate()
            .map(|(i, &y)| (trace.time_s(i), y))
            .collect();
        let name = ch.name.replace(['/', ' '], "_");
        let series = [Series {
            name: String::new(),
            points,
            style: SeriesStyle::Line,
        }];
        for ext in ["svg", "png"] {
            let path = dir.join(format!("{stem}-{name}.{ext}"));
            let y = format!("{} [{}]", ch.name, ch.unit);
            plot_xy_svg(
                &path,
                &format!("{title}: {}", ch.name),
                "time (s)",
                &y,
                &series,
            )?;
            drawn.push(path);
        }
    }
    Ok(drawn)
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

    /// Over 80 lines: one test per kind of plot in turn, each a few lines
    /// drawing it and reading the file back.
    #[test]
    fn log_plots_and_heat_maps_render_as_svg_and_png() {
        let dir = std::env::temp_dir().join(format!("vlab-plot-more-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("dir");
        let plot = LogXPlot {
            title: "efficiency".into(),
            x_label: "Gamma".into(),
            y_label: "eta".into(),
            series: vec![ErrorSeries {
                name: "DEM 40 Hz".into(),
                points: vec![(1.0, 0.01, f64::NAN), (3.0, 0.5, 0.02), (20.0, 0.8, 0.01)],
                color: 0,
                line: true,
            }],
            markers: vec![MarkerLine {
                name: "CP onset".into(),
                x: 22.3,
                color: 0,
                dash: LineDash::Long,
            }],
            reference_y: Some(0.3),
            y_from_zero: true,
        };
        let map = HeatMap {
            title: "map".into(),
            x_label: "f".into(),
            y_label: "Gamma".into(),
            columns: vec!["20".into(), "40".into()],
            rows: vec!["1".into(), "3".into()],
            cells: vec![
                HeatCell {
                    col: 0,
                    row: 0,
                    value: Some(0.1),
                    text: "S\n0.10".into(),
                },
                HeatCell {
                    col: 1,
                    row: 1,
                    value: None,
                    text: "rig".into(),
                },
            ],
            value_label: "eta".into(),
            value_range: (0.0, 1.0),
            overlays: vec![HeatOverlay {
                name: "CP".into(),
                segments: vec![[(0.0, 1.2), (1.0, 1.2)]],
                color: RgbColor(255, 0, 0),
                dash: LineDash::Long,
            }],
            footnote: "S solid-like".into(),
        };
        for ext in ["svg", "png"] {
            let p = dir.join(format!("eff.{ext}"));
            plot_log_x(&p, &plot).expect("log plot");
            let m = dir.join(format!("map.{ext}"));
            plot_heat_map(&m, &map).expect("heat map");
            let bytes = std::fs::read(&p).expect("read");
            if ext == "png" {
                assert_eq!(&bytes[1..4], b"PNG");
            } else {
                let svg = String::from_utf8(bytes).expect("utf8");
                assert!(svg.contains("CP onset") && svg.contains("DEM 40 Hz"));
            }
        }
        // The cell's text sits on a patch of the cell's colour drawn after
        // the overlay line, so the line stops short of the text.
        let svg = std::fs::read_to_string(dir.join("map.svg")).expect("map.svg");
        let c = viridis(0.1);
        let cell_fill = format!("fill=\"#{:02X}{:02X}{:02X}\"", c.0, c.1, c.2);
        let line_at = svg.find("stroke=\"#FF0000\"").expect("the overlay");
        let patch_at = svg.rfind(&cell_fill).expect("the cell's colour");
        assert!(patch_at > line_at, "no patch over the overlay");
        let leftovers: Vec<_> = std::fs::read_dir(&dir)
            .expect("list")
            .filter_map(|e| e.ok())
            .filter(|e| e.file_name().to_string_lossy().starts_with('.'))
            .collect();
        assert!(leftovers.is_empty(), "temporary files left");
        assert!(plot_log_x(&dir.join("x.pdf"), &plot).is_err());
        std::fs::remove_dir_all(dir).ok();
    }

    /// The x and y of every `<text>` element of `svg` whose content is `name`.
    fn text_positions(svg: &str, name: &str) -> Vec<(f64, f64)> {
        let mut out = Vec::new();
        for chunk in svg.split("<text").skip(1) {
            let Some((attrs, rest)) = chunk.split_once('>') else {
                continue;
            };
            // plotters writes the text on a line of its own.
            if rest.split('<').next().map(str::trim) != Some(name) {
                continue;
            }
            let attr = |key: &str| -> Option<f64> {
                let at = attrs.find(&format!(" {key}=\""))? + key.len() + 3;
                attrs[at..].split('"').next()?.parse().ok()
            };
            if let (Some(x), Some(y)) = (attr("x"), attr("y")) {
                out.push((x, y));
            }
        }
        out
    }

    /// The legends stay out of the data: a log plot's entries start right of
    /// its data area (the legend panel is the last
    /// `LOG_X_LEGEND_WIDTH_PX`), a heat map's below its cells (the
    /// bottom `HEAT_MAP_BOTTOM_PX` hold the legend and the footnote); exact
    /// pixel bounds. One test over both figures: the fixtures are its
    /// length, and each assertion reads against the fixture above it.
    ///
    /// Over 80 lines: one test drawing each kind of plot and checking where its
    /// legend lands; the kinds share the checks.
    #[test]
    fn legends_are_drawn_outside_the_data_area() {
        let dir = std::env::temp_dir().join(format!("vlab-plot-legend-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("dir");
        let plot = LogXPlot {
            title: "efficiency".into(),
            x_label: "Gamma".into(),
            y_label: "eta".into(),
            series: vec![ErrorSeries {
                name: "DEM 40 Hz".into(),
                points: vec![(1.0, 0.01, f64::NAN), (30.0, 0.6, 0.01), (40.0, 0.45, 0.01)],
                color: 0,
                line: true,
            }],
            markers: vec![
                MarkerLine {
                    name: "CP onset 40 Hz".into(),
                    x: 22.3,
                    color: 0,
                    dash: LineDash::Long,
                },
                MarkerLine {
                    name: "LP onset 40 Hz".into(),
                    x: 12.5,
                    color: 0,
                    dash: LineDash::Short,
                },
            ],
            reference_y: Some(0.3),
            y_from_zero: true,
        };
        let path = dir.join("eff.svg");
        plot_log_x(&path, &plot).expect("log plot");
        let svg = std::fs::read_to_string(&path).expect("read");
        let data_right = f64::from(LOG_X_SIZE_PX.0 - LOG_X_LEGEND_WIDTH_PX);
        for name in [
            "DEM 40 Hz",
            "CP onset 40 Hz",
            "LP onset 40 Hz",
            "efficiency 0.3",
        ] {
            let at = text_positions(&svg, name);
            assert_eq!(at.len(), 1, "{name}: {at:?}");
            assert!(at[0].0 > data_right, "{name} at x = {} px", at[0].0);
        }
        // The two kinds of onset are dashed differently.
        assert_ne!(LineDash::Long.pattern(), LineDash::Short.pattern());

        let map = HeatMap {
            title: "map".into(),
            x_label: "f".into(),
            y_label: "Gamma".into(),
            columns: vec!["20".into(), "40".into()],
            rows: vec!["1".into(), "40".into()],
            cells: vec![HeatCell {
                col: 1,
                row: 1,
                value: Some(0.45),
                text: "BB".into(),
            }],
            value_label: "eta".into(),
            value_range: (0.0, 1.0),
            overlays: vec![
                HeatOverlay {
                    name: "close packing".into(),
                    segments: vec![[(1.0, 1.5), (2.0, 1.5)]],
                    color: RgbColor(255, 0, 0),
                    dash: LineDash::Long,
                },
                HeatOverlay {
                    name: "loose packing".into(),
                    segments: vec![[(0.0, 0.8), (1.0, 0.8)]],
                    color: RgbColor(255, 0, 0),
                    dash: LineDash::Short,
                },
            ],
            footnote: "note".into(),
        };
        let path = dir.join("map.svg");
        plot_heat_map(&path, &map).expect("heat map");
        let svg = std::fs::read_to_string(&path).expect("read");
        let cells_bottom = f64::from(HEAT_MAP_SIZE_PX.1 - HEAT_MAP_BOTTOM_PX);
        let legend = ["close packing", "loose packing"].map(|name| {
            let at = text_positions(&svg, name);
            assert_eq!(at.len(), 1, "{name}: {at:?}");
            assert!(at[0].1 > cells_bottom, "{name} at y = {} px", at[0].1);
            at[0]
        });
        assert!(legend[1].0 > legend[0].0, "side by side: {legend:?}");
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

    /// A log axis within one decade (the sweep's Γ 15-35, padded to 12-44)
    /// is labelled at round numbers, not left bare; a wide one at 1-2-3-5.
    #[test]
    fn a_log_axis_is_labelled_at_round_numbers_even_inside_a_decade() {
        let (bold, light) = log_ticks(12.0, 44.0);
        assert_eq!(bold, vec![15.0, 20.0, 30.0, 40.0]);
        assert!(!light.iter().any(|x| bold.contains(x)));
        let (bold, _) = log_ticks(0.68, 1.25);
        assert_eq!(bold, vec![0.7, 0.8, 0.9, 1.0, 1.2]);
        let (bold, _) = log_ticks(0.8, 120.0);
        assert_eq!(
            bold,
            vec![1.0, 2.0, 3.0, 5.0, 10.0, 20.0, 30.0, 50.0, 100.0]
        );
    }

    /// The legend goes to the corner the data leave free: points high on
    /// the right push it elsewhere, a flat line through the middle leaves
    /// the upper corners free.
    #[test]
    fn the_legend_takes_the_corner_the_data_leave_free() {
        let (x, y) = (0.0..1.0, 0.0..1.0);
        let high_right = Series {
            name: "a".into(),
            points: vec![(0.98, 0.98), (0.95, 0.97), (0.99, 0.95)],
            style: SeriesStyle::Points,
        };
        let (c, _) = emptiest_corner(std::slice::from_ref(&high_right), &x, &y);
        assert!(!matches!(c, SeriesLabelPosition::UpperRight));
        let (c, hidden) = emptiest_corner(&[flat_line(), high_right], &x, &y);
        assert!(matches!(c, SeriesLabelPosition::UpperLeft), "{c:?}");
        assert_eq!(hidden, 0);
    }

    /// Data in every corner (a sine over whole periods): the y axis grows
    /// on top until the legend's corner is empty; a plot with a free
    /// corner keeps its range.
    #[test]
    fn a_full_plot_makes_room_on_top_for_its_legend() {
        let sine = Series {
            name: "acceleration".into(),
            points: (0..=200)
                .map(|k| {
                    let t = k as f64 / 100.0;
                    (t, (2.0 * std::f64::consts::PI * 2.0 * t).sin())
                })
                .collect(),
            style: SeriesStyle::Line,
        };
        let x = 0.0..2.0;
        let y = -1.05..1.05;
        assert!(emptiest_corner(std::slice::from_ref(&sine), &x, &y).1 > 0);
        let roomy = with_legend_room(std::slice::from_ref(&sine), &x, y.clone());
        assert_eq!(roomy.start, y.start);
        assert!(roomy.end > y.end);
        assert_eq!(
            emptiest_corner(std::slice::from_ref(&sine), &x, &roomy).1,
            0
        );
        let kept = with_legend_room(std::slice::from_ref(&flat_line()), &(0.0..1.0), 0.0..1.0);
        assert_eq!(kept, 0.0..1.0);
    }

    fn flat_line() -> Series {
        Series {
            name: "b".into(),
            points: vec![(0.0, 0.5), (1.0, 0.5)],
            style: SeriesStyle::Line,
        }
    }

    #[test]
    fn a_long_title_gets_a_smaller_font() {
        assert_eq!(title_font_px("short", 800, 24), 24);
        let long =
            "thesis damper, 40 Hz, Gamma 20: rig thesis-shaker record (cf. thesis Fig. 7.12)";
        let px = title_font_px(long, 800, 24);
        assert!(
            px < 24 && 0.55 * px as f64 * long.chars().count() as f64 <= 776.0,
            "{px}"
        );
    }
}
