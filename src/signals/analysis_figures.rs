//! The figures of a record analysed by Yang's method
//! ([`super::analysis`]): the force-displacement loop over the analysed
//! window, whose area is the energy per cycle (Terzioglu's thesis, eq.
//! 7.8), with the drive frequency's part phase-corrected as an ellipse, and
//! the drive frequency's phasors (eq. 7.7's loss angle). `vlab analyze
//! --plots` draws them.

use std::f64::consts::PI;
use std::path::Path;

use super::analysis::Analysis;
use super::error::Result;
use super::hysteresis::{ForceLoop, force_loop};
use super::plot::{Series, SeriesStyle, plot_xy_svg, plot_xy_svg_spanning};
use super::power::HarmonicPower;
use super::trace::Trace;

/// The record's force-displacement loop over the analysed window (with the
/// drive frequency's part, phase-corrected, as an ellipse) and the drive
/// frequency's phasors, as SVG and PNG (`loop`, `phasor`) in `dir`, which
/// must exist.
pub fn draw_analysis_figures(
    trace: &Trace,
    r: &Analysis,
    (force_channel, accel_channel): (&str, &str),
    dir: &Path,
) -> Result<ForceLoop> {
    let window = r.window_start..r.window_start + r.n_samples;
    let sign = if r.force_polarity.reversed { -1.0 } else { 1.0 };
    let force: Vec<f64> = trace.channel(force_channel)?.samples[window.clone()]
        .iter()
        .map(|f| sign * f)
        .collect();
    let accel = &trace.channel(accel_channel)?.samples[window];
    let l = force_loop(&force, accel, trace.sample_rate_hz, r.n_periods)?;
    let series = loop_series(r, &l);
    let loop_title = "Force against displacement: the loop's area is the energy per cycle";
    let phasor = r.per_harmonic.first().map(phasor_series);
    for ext in ["svg", "png"] {
        plot_xy_svg(
            &dir.join(format!("loop.{ext}")),
            loop_title,
            "enclosure displacement (mm)",
            "force on the damper (N)",
            &series,
        )?;
        if let Some(p) = &phasor {
            plot_xy_svg_spanning(
                &dir.join(format!("phasor.{ext}")),
                "Drive-frequency phasors (velocity along x, each to unit length)",
                "in phase with the velocity",
                "90 degrees ahead of the velocity",
                p,
                1.3,
            )?;
        }
    }
    Ok(l)
}

/// The loop of the record and the drive frequency's part of it,
/// phase-corrected, as an ellipse (displacement in mm, force in N).
fn loop_series(r: &Analysis, l: &ForceLoop) -> Vec<Series> {
    let mut series = vec![Series {
        name: format!(
            "record, {} cycles: {:.4} J per cycle enclosed",
            r.n_periods, l.energy_per_cycle_j
        ),
        points: l
            .displacement_m
            .iter()
            .zip(&l.force_n)
            .map(|(x, f)| (x * 1e3, *f))
            .collect(),
        style: SeriesStyle::Line,
    }];
    if let Some(h) = r.per_harmonic.first() {
        let (x1, f1) = (h.velocity_amp_mps / (2.0 * PI * h.freq_hz), h.force_amp_n);
        // The force leads the velocity by the phase, the velocity the
        // displacement by 90 degrees.
        let lead = h.phase_rad + 0.5 * PI;
        series.push(Series {
            name: format!(
                "drive frequency, phase-corrected: {:.4} J per cycle",
                h.power_w / h.freq_hz
            ),
            points: (0..=200)
                .map(|k| {
                    let t = 2.0 * PI * k as f64 / 200.0;
                    (x1 * t.cos() * 1e3, f1 * (t + lead).cos())
                })
                .collect(),
            style: SeriesStyle::Line,
        });
    }
    series
}

/// The velocity, the force as measured and the force as phase-corrected at
/// the drive frequency, each a unit line from the origin: the force leads
/// the velocity by 90 degrees minus the loss angle.
fn phasor_series(h: &HarmonicPower) -> Vec<Series> {
    let arrow = |name: String, angle: f64| Series {
        name,
        points: vec![(0.0, 0.0), (angle.cos(), angle.sin())],
        style: SeriesStyle::Line,
    };
    let loss = 0.5 * PI - h.phase_rad;
    vec![
        arrow("velocity".into(), 0.0),
        arrow(
            format!(
                "force, {:.2} deg ahead: loss angle {:.2} deg",
                h.phase_rad.to_degrees(),
                loss.to_degrees()
            ),
            h.phase_rad,
        ),
    ]
}
