//! The plots of the studies: log10 axes drawn by the crate's linear x-y
//! plot, so every point must be positive.

use std::path::Path;

use super::{AccuracyRow, PlotLabels};
use crate::scene::SceneError;
use crate::signals::{Series, SeriesStyle, plot_xy_svg};

fn select<'a>(
    rows: &'a [AccuracyRow],
    study: &'a str,
    parameter: &'a str,
    quantity: &'a str,
) -> impl Iterator<Item = &'a AccuracyRow> + 'a {
    rows.iter()
        .filter(move |r| r.study == study && r.parameter == parameter && r.quantity == quantity)
}

fn series(name: &str, style: SeriesStyle, points: Vec<(f64, f64)>) -> Option<Series> {
    let points: Vec<(f64, f64)> = points
        .into_iter()
        .filter(|(x, y)| *x > 0.0 && *y > 0.0 && x.is_finite() && y.is_finite())
        .map(|(x, y)| (x.log10(), y.log10()))
        .collect();
    (!points.is_empty()).then(|| Series {
        name: name.into(),
        points,
        style,
    })
}

/// Writes the plots; returns their file names.
pub fn write_plots(
    dir: &Path,
    rows: &[AccuracyRow],
    labels: &PlotLabels,
) -> Result<Vec<String>, SceneError> {
    let mut files = vec![accuracy_plot(dir, rows, labels)?];
    files.extend(impact_plot(dir, rows, labels)?);
    files.extend(yang_plot(dir, rows, labels)?);
    Ok(files
        .into_iter()
        .flat_map(|svg| {
            let png = svg.replace(".svg", ".png");
            [svg, png]
        })
        .collect())
}

/// Draws `name.svg` and `name.png` in `dir`.
fn svg_and_png(
    dir: &Path,
    name: &str,
    title: &str,
    x_label: &str,
    y_label: &str,
    series: &[Series],
) -> Result<(), crate::signals::SignalsError> {
    for ext in ["svg", "png"] {
        plot_xy_svg(
            &dir.join(format!("{name}.{ext}")),
            title,
            x_label,
            y_label,
            series,
        )?;
    }
    Ok(())
}

/// `accuracy.svg`: every study's error against its run time.
///
/// Over 80 lines: one figure's series, a few lines each, that share the
/// axes' range; split, the range and the rows would be passed to each.
fn accuracy_plot(
    dir: &Path,
    rows: &[AccuracyRow],
    labels: &PlotLabels,
) -> Result<String, SceneError> {
    let dem_q = "energy_per_cycle_j";
    let wall_err = |r: &AccuracyRow| (r.wall_s, r.error_rel.abs());
    let wall_se = |r: &AccuracyRow| (r.wall_s, r.stderr_rel);
    let dt_rows: Vec<&AccuracyRow> = select(rows, "dem", "dt_over_rayleigh", dem_q).collect();
    let cyc: Vec<&AccuracyRow> = select(rows, "dem", "steady_cycles", dem_q).collect();
    let all_wall: Vec<f64> = rows
        .iter()
        .filter(|r| r.study != "impact" && r.wall_s > 0.0)
        .map(|r| r.wall_s)
        .collect();
    let (w0, w1) = all_wall
        .iter()
        .fold((f64::INFINITY, 0.0f64), |(a, b), &w| (a.min(w), b.max(w)));
    let spread = labels.seed_spread_rel;
    let mut main = vec![
        series(
            "DEM time step: |error| vs finest step",
            SeriesStyle::Points,
            dt_rows.iter().map(|r| wall_err(r)).collect(),
        ),
        series(
            "DEM time step: standard error of that",
            SeriesStyle::Line,
            dt_rows.iter().map(|r| wall_se(r)).collect(),
        ),
        series(
            "DEM time step: integrator energy error",
            SeriesStyle::Points,
            select(rows, "dem", "dt_over_rayleigh", "integrator_rel")
                .map(wall_err)
                .collect(),
        ),
        series(
            "DEM cycles: standard error of the mean",
            SeriesStyle::Line,
            cyc.iter().map(|r| wall_se(r)).collect(),
        ),
        series(
            "DEM cycles: rms error of blocks",
            SeriesStyle::Points,
            select(rows, "dem", "steady_cycles", "block_rms_rel")
                .map(wall_err)
                .collect(),
        ),
        series(
            "DEM seeds: |mean - pooled mean|",
            SeriesStyle::Points,
            select(rows, "dem", "seed", dem_q).map(wall_err).collect(),
        ),
        series(
            "Yang vs work in, same cycles (the chain): |error| by record length",
            SeriesStyle::Points,
            select(rows, "yang", "record_periods", "energy_per_cycle_vs_work_j")
                .map(wall_err)
                .collect(),
        ),
        series(
            "work in vs DEM dissipation (the bed's unsteadiness): |error| by record length",
            SeriesStyle::Points,
            select(rows, "yang", "record_periods", "work_in_per_cycle_j")
                .map(wall_err)
                .collect(),
        ),
        series(
            "Yang vs DEM, same cycles (chain and unsteadiness): |error| by record length",
            SeriesStyle::Points,
            select(rows, "yang", "record_periods", dem_q)
                .map(wall_err)
                .collect(),
        ),
    ];
    if spread.is_finite() && w1 > w0 {
        main.push(series(
            "seed-to-seed spread (sd of seed means)",
            SeriesStyle::Line,
            vec![(w0, spread), (w1, spread)],
        ));
    }
    let main: Vec<Series> = main.into_iter().flatten().collect();
    let title = format!(
        "{} damper, {} Hz, Gamma {}: error against run time",
        labels.scene, labels.freq_hz, labels.gamma
    );
    svg_and_png(
        dir,
        "accuracy",
        &title,
        "log10 wall-clock time (s)",
        "log10 relative error",
        &main,
    )?;
    Ok("accuracy.svg".to_string())
}

/// `impact.svg`: the collision's errors against its resolution (none
/// without points).
fn impact_plot(
    dir: &Path,
    rows: &[AccuracyRow],
    labels: &PlotLabels,
) -> Result<Option<String>, SceneError> {
    let imp = |q: &str, name: &str| {
        series(
            name,
            SeriesStyle::Line,
            select(rows, "impact", "steps_per_contact", q)
                .map(|r| (r.value, r.error_rel.abs()))
                .collect(),
        )
    };
    let impact: Vec<Series> = [
        imp("max_overlap_m", "max overlap vs eq. 5.8"),
        imp("contact_duration_s", "duration vs eq. 5.10"),
        imp(
            "contact_duration_exact_s",
            "duration vs exact Hertz integral",
        ),
        imp("restitution", "restitution vs configured e"),
        imp("elastic_restitution", "restitution of e = 1 vs 1"),
    ]
    .into_iter()
    .flatten()
    .collect();
    if !impact.is_empty() {
        svg_and_png(
            dir,
            "impact",
            &format!(
                "one collision at {:.2} m/s against Hertz theory",
                labels.impact_speed_mps
            ),
            "log10 steps per contact",
            "log10 |relative error|",
            &impact,
        )?;
        return Ok(Some("impact.svg".to_string()));
    }
    Ok(None)
}

/// `yang.svg`: Yang's error against the chain's settings (none without
/// points).
fn yang_plot(
    dir: &Path,
    rows: &[AccuracyRow],
    labels: &PlotLabels,
) -> Result<Option<String>, SceneError> {
    let dem_q = "energy_per_cycle_j";
    let yang: Vec<Series> = [
        series(
            "noise factor (x rig rms)",
            SeriesStyle::Points,
            select(rows, "yang", "noise_factor", dem_q)
                .map(|r| (r.value, r.error_rel.abs()))
                .collect(),
        ),
        series(
            "residual phase error (mrad)",
            SeriesStyle::Points,
            select(rows, "yang", "residual_phase_mrad", dem_q)
                .map(|r| (r.value, r.error_rel.abs()))
                .collect(),
        ),
        series(
            "ADC: 2^(16 - bits)",
            SeriesStyle::Points,
            select(rows, "yang", "adc_bits", dem_q)
                .map(|r| (2f64.powf(16.0 - r.value), r.error_rel.abs()))
                .collect(),
        ),
    ]
    .into_iter()
    .flatten()
    .collect();
    if !yang.is_empty() {
        svg_and_png(
            dir,
            "yang",
            &format!(
                "Yang's estimate vs DEM truth, {} periods, chain settings",
                labels.baseline_record_periods
            ),
            "log10 setting (as in the legend)",
            "log10 |relative error|",
            &yang,
        )?;
        return Ok(Some("yang.svg".to_string()));
    }
    Ok(None)
}
