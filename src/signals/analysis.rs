//! Yang's method on a whole lab record, as `vlab analyze` runs it: the
//! dissipated power and energy per cycle (thesis eq. 7.8-7.12), the
//! efficiency (eq. 7.7) when the amplitude and particle mass are known, the
//! phase correction of a calibration table (at the drive and, through its
//! high-pass + skew model, at the harmonics), the force polarity (a record
//! whose force is the gauge reaction is detected and corrected), and the
//! warnings a lab user must see: flat tops of a clipped ADC, what was left
//! out and why.
//!
//! Values not given in [`AnalysisOptions`] come from the record's metadata
//! (`drive_freq_hz`, `gamma`, `particle_mass_kg`, `gravity_mps2`).

use serde::Serialize;

use super::calibration::PhaseCalibration;
use super::error::{Result, SignalsError};
use super::power::{
    ForcePolarity, HarmonicPower, PhaseCorrection, PolarityVerdict, PowerOptions, efficiency,
    yang_power_of_trace,
};
use super::trace::Trace;
use crate::warning::Warning;

/// What to analyse and with what; `None` values come from the record's
/// metadata.
#[derive(Debug, Clone)]
pub struct AnalysisOptions {
    /// Force channel (N).
    pub force_channel: String,
    /// Acceleration channel (m/s^2).
    pub accel_channel: String,
    /// Drive frequency (Hz) [default: the metadata's `drive_freq_hz`].
    pub freq_hz: Option<f64>,
    /// Amplitude Γ, for the efficiency [default: the metadata's].
    pub gamma: Option<f64>,
    /// Particle mass (kg), for the efficiency [default: the metadata's].
    pub particle_mass_kg: Option<f64>,
    /// The rig's phase-error table; `None`: no phase correction.
    pub calibration: Option<PhaseCalibration>,
    /// The table's name in the result (its file), `"none"` without one.
    pub calibration_name: String,
}

impl Default for AnalysisOptions {
    fn default() -> Self {
        AnalysisOptions {
            force_channel: "force".into(),
            accel_channel: "acceleration".into(),
            freq_hz: None,
            gamma: None,
            particle_mass_kg: None,
            calibration: None,
            calibration_name: "none".into(),
        }
    }
}

/// An input whose absence an analysis warns about.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum AnalysisInput {
    /// `gamma` and `particle_mass_kg`: the efficiency.
    GammaAndMass,
    /// `calibration`: the phase correction.
    Calibration,
    /// A calibration at several frequencies: the model at the harmonics.
    CalibrationFrequencies,
}

/// A warning of an analysis, and the input that would lift it.
pub type AnalysisWarning = Warning<AnalysisInput>;

/// What Yang's method made of a record.
#[derive(Debug, Serialize)]
pub struct Analysis {
    pub drive_freq_hz: f64,
    pub power_w: f64,
    pub energy_per_cycle_j: f64,
    pub efficiency: Option<f64>,
    pub phase_correction_rad: f64,
    pub calibration: String,
    /// How the phase error is carried to the harmonics.
    pub harmonics_correction: String,
    pub force_polarity: PolarityVerdict,
    pub n_periods: usize,
    pub n_samples: usize,
    pub per_harmonic: Vec<HarmonicPower>,
    pub warnings: Vec<AnalysisWarning>,
}

/// Yang's method on `trace` with `options` (see the module docs).
pub fn analyse_trace(trace: &Trace, options: &AnalysisOptions) -> Result<Analysis> {
    let freq =
        options
            .freq_hz
            .or(trace.metadata.drive_freq_hz)
            .ok_or(SignalsError::NotInMetadata {
                what: "drive frequency",
                metadata_key: "drive_freq_hz",
                parameter: "freq_hz",
            })?;
    let table = options.calibration.as_ref();
    let power_options = PowerOptions {
        phase_correction: table.map_or(PhaseCorrection::None, PhaseCorrection::Table),
        force_polarity: ForcePolarity::Detect,
        ..PowerOptions::default()
    };
    let r = yang_power_of_trace(
        trace,
        &options.force_channel,
        &options.accel_channel,
        freq,
        &power_options,
    )?;
    let extra_f64 = |key: &str| trace.metadata.extra.get(key).and_then(|v| v.as_f64());
    let gamma = options.gamma.or(trace.metadata.gamma);
    let mass = options.particle_mass_kg.or(extra_f64("particle_mass_kg"));
    let g = extra_f64("gravity_mps2").unwrap_or(super::STANDARD_GRAVITY_MPS2);
    let eta = match (gamma, mass) {
        (Some(gamma), Some(m)) => Some(efficiency(r.energy_per_cycle_j, m, gamma, freq, g)?),
        _ => None,
    };
    let mut warnings: Vec<AnalysisWarning> = [&options.force_channel, &options.accel_channel]
        .iter()
        .filter_map(|c| clipping_warning(trace, c))
        .map(AnalysisWarning::from)
        .collect();
    if eta.is_none() {
        warnings.push(AnalysisWarning::advising(
            "no efficiency: it needs gamma and particle_mass_kg (or both in the trace's metadata)",
            AnalysisInput::GammaAndMass,
        ));
    }
    if table.is_none() {
        warnings.push(AnalysisWarning::advising(
            "no phase correction: give the rig's calibration to subtract its phase error (thesis Fig. 7.9)",
            AnalysisInput::Calibration,
        ));
    }
    if r.force_polarity.reversed {
        warnings.push(polarity_note(&r.force_polarity).into());
    }
    if table.is_some_and(|t| t.model.is_none()) {
        warnings.push(AnalysisWarning::advising(
            "the calibration holds one frequency: its phase error is carried to the harmonics as a pure delay; calibrate at several (the drive and its 4th and 16th harmonics) to fit the rig's high-pass + skew",
            AnalysisInput::CalibrationFrequencies,
        ));
    }
    Ok(Analysis {
        drive_freq_hz: freq,
        power_w: r.power_w,
        energy_per_cycle_j: r.energy_per_cycle_j,
        efficiency: eta,
        phase_correction_rad: r.phase_correction_rad,
        calibration: options.calibration_name.clone(),
        harmonics_correction: harmonics_correction(table),
        force_polarity: r.force_polarity,
        n_periods: r.n_periods,
        n_samples: r.n_samples,
        per_harmonic: r.per_harmonic,
        warnings,
    })
}

/// What the calibration does at the harmonics, in words.
fn harmonics_correction(table: Option<&PhaseCalibration>) -> String {
    match table {
        None => "none".into(),
        Some(t) => match &t.model {
            Some(m) => format!(
                "high-pass + skew model fitted to {} frequencies: net high-pass corner {:.3} Hz, skew {:.3} us",
                t.points.len(),
                m.force_high_pass_hz - m.accel_high_pass_hz,
                1e6 * m.skew_s
            ),
            None => "pure delay through the one calibrated frequency".into(),
        },
    }
}

/// The sentence that says a record's force was the gauge reaction.
fn polarity_note(v: &PolarityVerdict) -> String {
    format!(
        "force polarity reversed: corrected (the drive bin's complex power lies at {:.1} deg, where the gauge reaction puts it; a force on the enclosure lies near +90 deg)",
        v.drive_power_angle_rad.to_degrees()
    )
}

/// A warning when channel `channel` of `trace` looks clipped ([`clipping`]).
pub fn clipping_warning(trace: &Trace, channel: &str) -> Option<String> {
    let x = &trace.channel(channel).ok()?.samples;
    clipping(x).map(|c| {
        format!(
            "channel '{channel}' looks clipped: {} samples sit at its extreme value {} (runs of up to {}), {:.0} times as many as at the level just below: the power is distorted",
            c.at_peak, c.peak, c.longest_run, c.excess
        )
    })
}

/// Flat tops found by [`clipping`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Clipping {
    /// The extreme value.
    pub peak: f64,
    /// Samples at it.
    pub at_peak: usize,
    /// Longest run of samples at it.
    pub longest_run: usize,
    /// Samples at the extreme over samples at the next level in.
    pub excess: f64,
}

/// Flat tops at a record's extreme values. A smooth wave that the ADC
/// quantised also repeats its top code a few samples running (a 40 Hz sine at
/// 40 kHz and 16 bits stays within one code of its peak for 3-4 samples), but
/// no more often than the codes just below it; a clipped one piles everything
/// beyond full scale onto the extreme code. So: runs of at least 3 at the
/// extreme, and at least 4 times as many samples there as at the next level in.
pub fn clipping(x: &[f64]) -> Option<Clipping> {
    // An ADC's codes are not symmetric (-2^15 ..= 2^15 - 1): each end separately.
    flat_top(x, 1.0).or_else(|| flat_top(x, -1.0))
}

/// [`clipping`] at the top of `sign * x`.
fn flat_top(x: &[f64], sign: f64) -> Option<Clipping> {
    const CLIP_EXCESS: f64 = 4.0;
    let top = x.iter().fold(f64::NEG_INFINITY, |m, &v| m.max(sign * v));
    if top <= 0.0 || !top.is_finite() {
        return None;
    }
    let next = x
        .iter()
        .map(|&v| sign * v)
        .filter(|&a| a < top)
        .fold(f64::NEG_INFINITY, f64::max);
    let at_next = x.iter().filter(|&&v| sign * v == next).count();
    let (mut longest, mut run, mut at_top) = (0, 0, 0);
    for &v in x {
        if sign * v == top {
            at_top += 1;
            run += 1;
            longest = longest.max(run);
        } else {
            run = 0;
        }
    }
    let excess = at_top as f64 / at_next.max(1) as f64;
    (longest >= 3 && excess >= CLIP_EXCESS).then_some(Clipping {
        peak: sign * top,
        at_peak: at_top,
        longest_run: longest,
        excess,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A sine of `amplitude` (in full scales) at 40 Hz, 40 kHz, through a
    /// 16-bit ADC that clips at its extreme codes.
    fn adc_sine(amplitude: f64) -> Vec<f64> {
        let lsb = 2.0 / 65536.0;
        (0..40_000)
            .map(|i| {
                let v = amplitude * (2.0 * std::f64::consts::PI * 40.0 * i as f64 / 40_000.0).sin();
                ((v / lsb).round() * lsb).clamp(-1.0, 1.0 - lsb)
            })
            .collect()
    }

    #[test]
    fn a_quantised_sine_is_not_called_clipped_and_a_clipped_one_is() {
        // Within one code of its peak for several samples, yet not clipped.
        for amplitude in [0.05, 0.5, 0.99] {
            assert_eq!(
                clipping(&adc_sine(amplitude)),
                None,
                "amplitude {amplitude}"
            );
        }
        // Unquantised floats: a single sample at the top.
        let smooth: Vec<f64> = (0..4000).map(|i| (i as f64 * 0.0063).sin()).collect();
        assert_eq!(clipping(&smooth), None);
        // 2 % over full scale: about 12 % of each period flat at the limits.
        let c = clipping(&adc_sine(1.02)).expect("clipped");
        assert!(c.longest_run > 50 && c.excess > 10.0, "{c:?}");
    }
}
