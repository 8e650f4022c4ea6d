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
//!
//! # No silent wrong number
//!
//! Eq. 7.12 gives a number for any drive frequency and any phase table, so
//! the inputs are checked against what the record itself says, and a
//! disagreement is refused ([`AnalysisError`]) or warned about, with the
//! figures that disagree and the option that overrides:
//!
//! - a given `freq_hz` more than [`FREQ_TOLERANCE`] (relative) away from the
//!   metadata's `drive_freq_hz`, or from the fundamental of the
//!   acceleration's spectrum ([`spectrum_fundamental_hz`]: the peak of its
//!   Hann-windowed spectrum, refined between bins; on a record of few
//!   periods, whose peak the negative-frequency image pulls aside, the
//!   tolerance widens to [`SPECTRUM_TOLERANCE_BINS`] of a bin), is refused unless
//!   `force_freq`: a 40 Hz record read at 41 Hz loses 7 % of its power. A
//!   metadata frequency the spectrum contradicts is used, with a warning;
//! - a calibration of another rig than the record's (both named) is refused
//!   unless `force_calibration`; a drive frequency outside the frequencies
//!   the table was measured at is warned about (its phase error there is
//!   extrapolated);
//! - the drive periods the record holds beyond the whole ones used are
//!   reported, and warned about from [`DROPPED_PERIODS_WARNING`] of a period.

use realfft::num_complex::Complex64;
use serde::Serialize;

use super::calibration::PhaseCalibration;
use super::error::SignalsError;
use super::power::{
    ForcePolarity, HarmonicPower, PhaseCorrection, PolarityVerdict, PowerOptions, efficiency,
    period_powers, yang_power_of_trace,
};
use super::spectrum::amplitude_spectrum;
use super::trace::Trace;
use crate::warning::Warning;

/// Largest relative difference between a given drive frequency and the one
/// the record states (metadata) or shows (spectrum) that is taken as the same
/// frequency. A 40 Hz record read 0.5 % off loses about 1.5 % of its power.
pub const FREQ_TOLERANCE: f64 = 0.005;
/// Fraction of the spectrum's bin (`sample_rate_hz / samples`) the given
/// frequency may differ from its fundamental, when that exceeds
/// [`FREQ_TOLERANCE`]: a record of two periods finds its fundamental within
/// about 1/70 of a bin, seven periods (the reference record) far closer.
pub const SPECTRUM_TOLERANCE_BINS: f64 = 0.05;
/// Fraction of a drive period left out at the record's end from which a
/// warning says so (below it the result still reports it).
pub const DROPPED_PERIODS_WARNING: f64 = 0.1;

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
    /// Use `freq_hz` even where the record's metadata or spectrum says
    /// another frequency (a warning then says so).
    pub force_freq: bool,
    /// Amplitude Γ, for the efficiency [default: the metadata's].
    pub gamma: Option<f64>,
    /// Particle mass (kg), for the efficiency [default: the metadata's].
    pub particle_mass_kg: Option<f64>,
    /// The rig's phase-error table; `None`: no phase correction.
    pub calibration: Option<PhaseCalibration>,
    /// The table's name in the result (its file), `"none"` without one.
    pub calibration_name: String,
    /// Apply `calibration` even when it names another rig than the record
    /// (a warning then says so).
    pub force_calibration: bool,
    /// Use the force as recorded, without detecting a reversed polarity
    /// (a student's exercise: what a flipped sign does to the result).
    pub as_recorded: bool,
}

impl Default for AnalysisOptions {
    fn default() -> Self {
        AnalysisOptions {
            force_channel: "force".into(),
            accel_channel: "acceleration".into(),
            freq_hz: None,
            force_freq: false,
            gamma: None,
            particle_mass_kg: None,
            calibration: None,
            calibration_name: "none".into(),
            force_calibration: false,
            as_recorded: false,
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
    /// A calibration measured at the drive frequency.
    CalibrationAtDrive,
    /// `freq_hz`, with `force_freq`: the drive frequency the record shows.
    Freq,
    /// `force_freq`: use a drive frequency the record contradicts.
    ForceFreq,
    /// `force_calibration`: apply another rig's calibration.
    ForceCalibration,
}

/// A warning of an analysis, and the input that would lift it.
pub type AnalysisWarning = Warning<AnalysisInput>;

/// Why an analysis was refused.
#[derive(Debug, thiserror::Error)]
pub enum AnalysisError {
    /// The record could not be read or analysed.
    #[error(transparent)]
    Signals(#[from] SignalsError),
    /// The given drive frequency contradicts the record.
    #[error("{}; set force_freq to use it anyway", .0.figures())]
    FreqContradicts(FreqCheck),
    /// The calibration belongs to another rig than the record.
    #[error("{}; set force_calibration to apply it anyway", .0.figures())]
    OtherRig(RigCheck),
}

impl AnalysisError {
    /// The input that overrides a refusal, if one does.
    pub fn overridden_by(&self) -> Option<AnalysisInput> {
        match self {
            AnalysisError::Signals(_) => None,
            AnalysisError::FreqContradicts(_) => Some(AnalysisInput::ForceFreq),
            AnalysisError::OtherRig(_) => Some(AnalysisInput::ForceCalibration),
        }
    }

    /// The refusal's figures without the override (for a caller that names
    /// the override its own way); the error's text for other errors.
    pub fn figures(&self) -> String {
        match self {
            AnalysisError::Signals(e) => e.to_string(),
            AnalysisError::FreqContradicts(c) => c.figures(),
            AnalysisError::OtherRig(c) => c.figures(),
        }
    }
}

/// A drive frequency and what the record says about it.
#[derive(Debug, Clone, PartialEq)]
pub struct FreqCheck {
    /// The frequency given (Hz).
    pub freq_hz: f64,
    /// The metadata's `drive_freq_hz`, if any.
    pub metadata_freq_hz: Option<f64>,
    /// The acceleration spectrum's fundamental, if one could be found (Hz).
    pub spectrum_freq_hz: Option<f64>,
    /// How far from the fundamental a frequency still agrees with it (Hz).
    pub spectrum_tolerance_hz: f64,
}

impl FreqCheck {
    /// The figures that disagree, in words.
    pub fn figures(&self) -> String {
        let mut said = Vec::new();
        if let Some(m) = self.metadata_freq_hz {
            said.push(format!("its metadata's drive_freq_hz is {m} Hz"));
        }
        if let Some(s) = self.spectrum_freq_hz {
            said.push(format!(
                "its acceleration spectrum's fundamental is {s:.2} Hz (agreement within {:.2} Hz)",
                self.spectrum_tolerance_hz
            ));
        }
        format!(
            "freq_hz = {} Hz contradicts the record: {} (the metadata must agree within {} %; a wrong drive frequency biases the power)",
            self.freq_hz,
            said.join(" and "),
            100.0 * FREQ_TOLERANCE
        )
    }
}

/// A calibration's rig and the record's.
#[derive(Debug, Clone, PartialEq)]
pub struct RigCheck {
    /// The rig the calibration table was measured on.
    pub calibration_rig: String,
    /// The rig the record's metadata names.
    pub trace_rig: String,
}

impl RigCheck {
    /// The two rigs, in words.
    pub fn figures(&self) -> String {
        format!(
            "the calibration was measured on rig '{}' but the record was taken on rig '{}': its phase error is another rig's",
            self.calibration_rig, self.trace_rig
        )
    }
}

/// What Yang's method made of a record.
#[derive(Debug, Serialize)]
pub struct Analysis {
    pub drive_freq_hz: f64,
    /// Where the drive frequency came from: `"given"` or `"metadata"`.
    pub drive_freq_source: &'static str,
    /// The metadata's drive frequency, if any (Hz).
    pub metadata_freq_hz: Option<f64>,
    /// The acceleration spectrum's fundamental, if found (Hz).
    pub spectrum_freq_hz: Option<f64>,
    pub power_w: f64,
    /// One-sigma error of `power_w` (W): Yang's power of each whole period
    /// alone, their mean's error over the record
    /// ([`crate::stats::series_mean`]: AR(1) with its finite-length
    /// inflation, or of pairs of periods where they alternate); `None`
    /// ("not known") below [`crate::stats::MIN_SERIES_VALUES`] periods. It is
    /// the record's own: one bed, one window, nothing of another packing.
    pub power_stderr_w: Option<f64>,
    pub energy_per_cycle_j: f64,
    pub energy_per_cycle_stderr_j: Option<f64>,
    pub efficiency: Option<f64>,
    pub efficiency_stderr: Option<f64>,
    /// The periods' power alternates from period to period (period 2).
    pub periods_alternate: bool,
    pub phase_correction_rad: f64,
    pub calibration: String,
    /// How the phase error is carried to the harmonics.
    pub harmonics_correction: String,
    pub force_polarity: PolarityVerdict,
    /// Whole drive periods analysed.
    pub n_periods: usize,
    /// The analysed window: its first sample and its length.
    pub window_start: usize,
    pub n_samples: usize,
    /// Drive periods the record holds (`record samples f / fs`).
    pub record_periods: f64,
    /// Samples at the record's end left out to keep whole periods.
    pub dropped_samples: usize,
    pub per_harmonic: Vec<HarmonicPower>,
    pub warnings: Vec<AnalysisWarning>,
}

/// The drive frequency an analysis uses, where it came from, and warnings.
struct DriveFreq {
    freq_hz: f64,
    source: &'static str,
    check: FreqCheck,
}

/// Whether `a` and `b` are the same frequency within [`FREQ_TOLERANCE`].
fn same_freq(a: f64, b: f64) -> bool {
    (a - b).abs() <= FREQ_TOLERANCE * b.abs()
}

/// The drive frequency of `trace` under `options`, checked against the
/// metadata and the spectrum (see the module docs).
fn drive_freq(
    trace: &Trace,
    options: &AnalysisOptions,
    warnings: &mut Vec<AnalysisWarning>,
) -> Result<DriveFreq, AnalysisError> {
    let metadata = trace.metadata.drive_freq_hz;
    let accel = &trace.channel(&options.accel_channel)?.samples;
    let spectrum = spectrum_fundamental_hz(accel, trace.sample_rate_hz);
    let bin_hz = trace.sample_rate_hz / accel.len().max(1) as f64;
    let tolerance_hz = |f: f64| (FREQ_TOLERANCE * f).max(SPECTRUM_TOLERANCE_BINS * bin_hz);
    let off_spectrum = |f: f64| spectrum.is_some_and(|s| (f - s).abs() > tolerance_hz(s));
    let Some(given) = options.freq_hz else {
        let m = metadata.ok_or(SignalsError::NotInMetadata {
            what: "drive frequency",
            metadata_key: "drive_freq_hz",
            parameter: "freq_hz",
        })?;
        if let Some(s) = spectrum.filter(|_| off_spectrum(m)) {
            warnings.push(AnalysisWarning::advising(
                format!(
                    "the metadata's drive_freq_hz {m} Hz is used, but the acceleration spectrum's fundamental is {s:.2} Hz: if the drive ran there, give freq_hz = {s:.2} with force_freq"
                ),
                AnalysisInput::Freq,
            ));
        }
        let check = FreqCheck {
            freq_hz: m,
            metadata_freq_hz: metadata,
            spectrum_freq_hz: spectrum,
            spectrum_tolerance_hz: spectrum.map_or(0.0, tolerance_hz),
        };
        return Ok(DriveFreq {
            freq_hz: m,
            source: "metadata",
            check,
        });
    };
    let check = FreqCheck {
        freq_hz: given,
        metadata_freq_hz: metadata,
        spectrum_freq_hz: spectrum,
        spectrum_tolerance_hz: spectrum.map_or(0.0, tolerance_hz),
    };
    let contradicted = metadata.is_some_and(|m| !same_freq(given, m)) || off_spectrum(given);
    if contradicted {
        if !options.force_freq {
            return Err(AnalysisError::FreqContradicts(check));
        }
        warnings.push(AnalysisWarning::from(format!(
            "{}; used as forced",
            check.figures()
        )));
    }
    Ok(DriveFreq {
        freq_hz: given,
        source: "given",
        check,
    })
}

/// Refuses (or, forced, warns about) a calibration of another rig than the
/// record's; both names must be known to disagree.
fn check_rig(
    trace: &Trace,
    options: &AnalysisOptions,
    warnings: &mut Vec<AnalysisWarning>,
) -> Result<(), AnalysisError> {
    let Some(table) = &options.calibration else {
        return Ok(());
    };
    let (cal, rec) = (table.rig.trim(), trace.metadata.rig.trim());
    if cal.is_empty() || rec.is_empty() {
        warnings.push(AnalysisWarning::from(format!(
            "the calibration's rig cannot be checked against the record's: {} names no rig; a table of another rig can move the power by several percent (the thesis rig's 5 mrad is 4.4 % at 40 Hz, Gamma 20)",
            if rec.is_empty() { "the record" } else { "the calibration" }
        )));
        return Ok(());
    }
    if cal == rec {
        return Ok(());
    }
    let check = RigCheck {
        calibration_rig: cal.to_string(),
        trace_rig: rec.to_string(),
    };
    if !options.force_calibration {
        return Err(AnalysisError::OtherRig(check));
    }
    warnings.push(AnalysisWarning::from(format!(
        "{}; applied as forced",
        check.figures()
    )));
    Ok(())
}

/// A warning when `freq_hz` lies outside the frequencies `table` was measured at.
fn calibration_range_warning(table: &PhaseCalibration, freq_hz: f64) -> Option<AnalysisWarning> {
    let (lo, hi) = (table.points.first()?.freq_hz, table.points.last()?.freq_hz);
    if freq_hz >= lo * (1.0 - FREQ_TOLERANCE) && freq_hz <= hi * (1.0 + FREQ_TOLERANCE) {
        return None;
    }
    let range = if lo == hi {
        format!("{lo} Hz alone")
    } else {
        format!("{lo} to {hi} Hz")
    };
    let how = match &table.model {
        Some(_) => "beyond the support of the high-pass + skew model fitted to them".to_string(),
        None => {
            let end = if freq_hz < lo { lo } else { hi };
            format!("as a pure delay through {end} Hz")
        }
    };
    Some(AnalysisWarning::advising(
        format!(
            "the drive frequency {freq_hz} Hz lies outside the calibrated range ({range}): its phase error {:.3} mrad is extrapolated {how}, and the power may be off by several percent; calibrate at the drive frequency",
            1e3 * table.phase_error_at(freq_hz)
        ),
        AnalysisInput::CalibrationAtDrive,
    ))
}

/// Yang's method on `trace` with `options` (see the module docs).
///
/// Over 80 lines: the report filled field by field from Yang's power, the
/// period-by-period spread and the record's metadata, each figure from the ones
/// before.
pub fn analyse_trace(trace: &Trace, options: &AnalysisOptions) -> Result<Analysis, AnalysisError> {
    let mut warnings: Vec<AnalysisWarning> = Vec::new();
    let drive = drive_freq(trace, options, &mut warnings)?;
    check_rig(trace, options, &mut warnings)?;
    let freq = drive.freq_hz;
    let table = options.calibration.as_ref();
    let power_options = PowerOptions {
        phase_correction: table.map_or(PhaseCorrection::None, PhaseCorrection::Table),
        force_polarity: if options.as_recorded {
            ForcePolarity::AsRecorded
        } else {
            ForcePolarity::Detect
        },
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
    let (periods, periods_alternate) = crate::stats::series_mean(&period_powers(
        &trace.channel(&options.force_channel)?.samples,
        &trace.channel(&options.accel_channel)?.samples,
        trace.sample_rate_hz,
        freq,
        r.window_start,
        r.n_periods,
        &PowerOptions {
            force_polarity: if r.force_polarity.reversed {
                ForcePolarity::Reversed
            } else {
                ForcePolarity::AsRecorded
            },
            ..power_options
        },
    )?);
    // The per-period figures' error, carried to the whole record's power.
    let power_stderr_w = periods.stderr;
    let per_watt = |x: f64| x / r.power_w.abs().max(f64::MIN_POSITIVE);
    let n_total = trace.len();
    let record_periods = n_total as f64 * freq / trace.sample_rate_hz;
    let dropped_samples = n_total - r.n_samples;
    warnings.extend(
        [&options.force_channel, &options.accel_channel]
            .iter()
            .filter_map(|c| clipping_warning(trace, c))
            .map(AnalysisWarning::from),
    );
    warnings.extend(dropped_periods_warning(
        record_periods,
        r.n_periods,
        dropped_samples,
    ));
    warnings.extend(input_warnings(eta.is_some(), table, freq));
    if r.force_polarity.reversed {
        warnings.push(polarity_note(&r.force_polarity).into());
    }
    Ok(Analysis {
        drive_freq_hz: freq,
        drive_freq_source: drive.source,
        metadata_freq_hz: drive.check.metadata_freq_hz,
        spectrum_freq_hz: drive.check.spectrum_freq_hz,
        power_w: r.power_w,
        power_stderr_w,
        energy_per_cycle_j: r.energy_per_cycle_j,
        energy_per_cycle_stderr_j: power_stderr_w.map(|e| e / freq),
        efficiency: eta,
        efficiency_stderr: eta.and_then(|e| power_stderr_w.map(|pe| e.abs() * per_watt(pe))),
        periods_alternate,
        phase_correction_rad: r.phase_correction_rad,
        calibration: options.calibration_name.clone(),
        harmonics_correction: harmonics_correction(table),
        force_polarity: r.force_polarity,
        n_periods: r.n_periods,
        window_start: r.window_start,
        n_samples: r.n_samples,
        record_periods,
        dropped_samples,
        per_harmonic: r.per_harmonic,
        warnings,
    })
}

/// A warning when whole periods left [`DROPPED_PERIODS_WARNING`] of a period
/// or more of the record out.
fn dropped_periods_warning(
    record_periods: f64,
    n_periods: usize,
    dropped_samples: usize,
) -> Option<AnalysisWarning> {
    let dropped = record_periods - n_periods as f64;
    (dropped >= DROPPED_PERIODS_WARNING).then(|| {
        AnalysisWarning::from(format!(
            "the record holds {record_periods:.2} drive periods: {n_periods} whole periods were used and the last {dropped:.2} periods ({dropped_samples} samples, {:.0} % of the record) left out",
            100.0 * dropped / record_periods
        ))
    })
}

/// Warnings about what the caller did not give: the efficiency's inputs, a
/// calibration, one covering the drive frequency and more than one frequency.
fn input_warnings(
    has_efficiency: bool,
    table: Option<&PhaseCalibration>,
    freq_hz: f64,
) -> Vec<AnalysisWarning> {
    let mut warnings = Vec::new();
    if !has_efficiency {
        warnings.push(AnalysisWarning::advising(
            "no efficiency: it needs gamma and particle_mass_kg (or both in the trace's metadata)",
            AnalysisInput::GammaAndMass,
        ));
    }
    let Some(table) = table else {
        warnings.push(AnalysisWarning::advising(
            "no phase correction: give the rig's calibration to subtract its phase error (thesis Fig. 7.9)",
            AnalysisInput::Calibration,
        ));
        return warnings;
    };
    warnings.extend(calibration_range_warning(table, freq_hz));
    if table.model.is_none() {
        warnings.push(AnalysisWarning::advising(
            "the calibration holds one frequency: its phase error is carried to the harmonics as a pure delay; calibrate at several (the drive and its 4th and 16th harmonics) to fit the rig's high-pass + skew",
            AnalysisInput::CalibrationFrequencies,
        ));
    }
    warnings
}

/// The fundamental of `x` sampled at `sample_rate_hz` (Hz): the largest bin
/// of its mean-removed, Hann-windowed spectrum, refined to the maximum of the
/// windowed transform's magnitude within a bin either side (golden-section
/// search). `None` for a record shorter than 16 samples, without a peak, or
/// holding less than two periods of it.
pub fn spectrum_fundamental_hz(x: &[f64], sample_rate_hz: f64) -> Option<f64> {
    let n = x.len();
    if n < 16 || !(sample_rate_hz.is_finite() && sample_rate_hz > 0.0) {
        return None;
    }
    let mean = x.iter().sum::<f64>() / n as f64;
    let tau = 2.0 * std::f64::consts::PI;
    let windowed: Vec<f64> = x
        .iter()
        .enumerate()
        .map(|(i, &v)| (v - mean) * 0.5 * (1.0 - (tau * i as f64 / n as f64).cos()))
        .collect();
    let spectrum = amplitude_spectrum(&windowed).ok()?;
    let (peak, top) = spectrum
        .iter()
        .enumerate()
        .skip(1)
        .map(|(k, c)| (k, c.norm()))
        .fold((0, 0.0), |best, kc| if kc.1 > best.1 { kc } else { best });
    // Below bin 2 the record holds less than two periods of its peak, the
    // window's main lobe reaches DC, and the analysis refuses it anyway.
    if peak < 2 || top <= 0.0 {
        return None;
    }
    // |sum w x e^(-j 2 pi f i / fs)|, by a rotating phasor.
    let magnitude = |bin: f64| {
        let step = Complex64::from_polar(1.0, -tau * bin / n as f64);
        let mut phasor = Complex64::new(1.0, 0.0);
        let mut sum = Complex64::new(0.0, 0.0);
        for &v in &windowed {
            sum += phasor * v;
            phasor *= step;
        }
        sum.norm()
    };
    let (mut a, mut b) = (peak as f64 - 1.0, peak as f64 + 1.0);
    let ratio = (5f64.sqrt() - 1.0) / 2.0;
    let (mut c, mut d) = (b - ratio * (b - a), a + ratio * (b - a));
    let (mut mc, mut md) = (magnitude(c), magnitude(d));
    for _ in 0..40 {
        if mc > md {
            (b, d, md) = (d, c, mc);
            c = b - ratio * (b - a);
            mc = magnitude(c);
        } else {
            (a, c, mc) = (c, d, md);
            d = a + ratio * (b - a);
            md = magnitude(d);
        }
    }
    Some(0.5 * (a + b) * sample_rate_hz / n as f64)
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

    /// `periods` periods of a 40 kHz record at `freq_hz`: a = cos + a third
    /// harmonic + a little deterministic noise, f = 0.3 a + 2 v (a damper).
    fn drive_record(freq_hz: f64, periods: f64, metadata_freq_hz: Option<f64>) -> Trace {
        let fs = 40_000.0;
        let w = 2.0 * std::f64::consts::PI * freq_hz;
        let n = (periods * fs / freq_hz).round() as usize;
        let t = |i: usize| i as f64 / fs;
        let noise = |i: usize| 0.02 * (((i * 7919) % 1000) as f64 / 500.0 - 1.0);
        let accel: Vec<f64> = (0..n)
            .map(|i| 196.2 * (w * t(i)).cos() + 20.0 * (3.0 * w * t(i)).sin() + noise(i))
            .collect();
        let force: Vec<f64> = (0..n)
            .map(|i| 0.3 * 196.2 * (w * t(i)).cos() + 2.0 * 196.2 / w * (w * t(i)).sin())
            .collect();
        let mut trace = Trace::new(fs, 0.0).expect("trace");
        trace.add_channel("force", "N", force).expect("force");
        trace
            .add_channel("acceleration", "m/s^2", accel)
            .expect("acceleration");
        trace.metadata.drive_freq_hz = metadata_freq_hz;
        trace.metadata.rig = "thesis-shaker".into();
        trace
    }

    fn table(rig: &str, freqs_hz: &[f64]) -> PhaseCalibration {
        PhaseCalibration {
            version: super::super::calibration::CALIBRATION_VERSION,
            rig: rig.into(),
            note: String::new(),
            points: freqs_hz
                .iter()
                .map(|&f| super::super::calibration::CalibrationEntry {
                    freq_hz: f,
                    phase_error_rad: 1e-4 * f,
                    n_amplitudes: 1,
                    spread_rad: 0.0,
                })
                .collect(),
            force_polarity_reversed: false,
            model: None,
        }
    }

    #[test]
    fn the_spectrum_finds_the_fundamental_of_short_and_long_records() {
        for periods in [2.0, 3.7, 7.0, 40.0] {
            for freq in [40.0, 41.0, 163.3] {
                let r = drive_record(freq, periods, None);
                let got = spectrum_fundamental_hz(
                    &r.channel("acceleration").expect("a").samples,
                    40_000.0,
                )
                .expect("a peak");
                // Within half of what the check tolerates.
                let bin_hz = freq / periods;
                let tolerance = (FREQ_TOLERANCE * freq).max(SPECTRUM_TOLERANCE_BINS * bin_hz);
                assert!(
                    (got - freq).abs() < 0.5 * tolerance,
                    "{periods} periods of {freq} Hz: {got} Hz"
                );
            }
        }
        assert_eq!(spectrum_fundamental_hz(&[0.0; 100], 1000.0), None);
        assert_eq!(spectrum_fundamental_hz(&[1.0; 10], 1000.0), None);
        let one_period: Vec<f64> = (0..100)
            .map(|i| (std::f64::consts::TAU * i as f64 / 100.0).sin())
            .collect();
        assert_eq!(spectrum_fundamental_hz(&one_period, 1000.0), None);
    }

    #[test]
    fn a_freq_the_record_contradicts_is_refused_unless_forced() {
        let r = drive_record(40.0, 7.0, Some(40.0));
        let ok = analyse_trace(&r, &AnalysisOptions::default()).expect("metadata");
        assert_eq!((ok.drive_freq_source, ok.dropped_samples), ("metadata", 0));
        let at = |f: f64, force: bool| {
            let options = AnalysisOptions {
                freq_hz: Some(f),
                force_freq: force,
                ..AnalysisOptions::default()
            };
            analyse_trace(&r, &options)
        };
        assert_eq!(at(40.0, false).expect("agrees").drive_freq_source, "given");
        let e = at(41.0, false).expect_err("contradicts");
        assert_eq!(e.overridden_by(), Some(AnalysisInput::ForceFreq));
        let text = e.to_string();
        for word in ["41 Hz", "40 Hz", "40.00 Hz", "force_freq"] {
            assert!(text.contains(word), "{text}: no '{word}'");
        }
        let forced = at(41.0, true).expect("forced");
        assert_eq!(forced.drive_freq_hz, 41.0);
        assert!(
            forced
                .warnings
                .iter()
                .any(|w| w.text.contains("used as forced")),
            "{:?}",
            forced.warnings
        );
        // Without metadata the spectrum alone contradicts.
        let bare = drive_record(40.0, 7.0, None);
        let options = AnalysisOptions {
            freq_hz: Some(41.0),
            ..AnalysisOptions::default()
        };
        assert!(matches!(
            analyse_trace(&bare, &options),
            Err(AnalysisError::FreqContradicts(FreqCheck {
                metadata_freq_hz: None,
                spectrum_freq_hz: Some(_),
                ..
            }))
        ));
        // Metadata the spectrum contradicts: used, with a warning.
        let off = drive_record(41.0, 7.0, Some(40.0));
        let w = analyse_trace(&off, &AnalysisOptions::default()).expect("metadata used");
        assert!(
            w.warnings
                .iter()
                .any(|w| w.advice == Some(AnalysisInput::Freq) && w.text.contains("41.00 Hz")),
            "{:?}",
            w.warnings
        );
    }

    #[test]
    fn another_rigs_calibration_is_refused_and_a_range_miss_warned() {
        let r = drive_record(40.0, 7.0, Some(40.0));
        let with = |cal: PhaseCalibration, force: bool| {
            let options = AnalysisOptions {
                calibration: Some(cal),
                force_calibration: force,
                ..AnalysisOptions::default()
            };
            analyse_trace(&r, &options)
        };
        let e = with(table("ideal", &[40.0]), false).expect_err("other rig");
        let text = e.to_string();
        assert!(
            text.contains("'ideal'") && text.contains("'thesis-shaker'"),
            "{text}"
        );
        assert_eq!(e.overridden_by(), Some(AnalysisInput::ForceCalibration));
        let forced = with(table("ideal", &[40.0]), true).expect("forced");
        assert!(
            forced
                .warnings
                .iter()
                .any(|w| w.text.contains("applied as forced"))
        );
        let own = with(table("thesis-shaker", &[40.0]), false).expect("own rig");
        assert!(
            !own.warnings
                .iter()
                .any(|w| w.advice == Some(AnalysisInput::CalibrationAtDrive))
        );
        let far = with(table("thesis-shaker", &[160.0]), false).expect("own rig");
        let w = far
            .warnings
            .iter()
            .find(|w| w.advice == Some(AnalysisInput::CalibrationAtDrive))
            .expect("range warning");
        assert!(
            w.text.contains("40 Hz")
                && w.text.contains("160 Hz alone")
                && w.text.contains("4.000 mrad"),
            "{}",
            w.text
        );
        let mut fitted = table("thesis-shaker", &[160.0, 640.0]);
        fitted.model = fitted.fit_model();
        let w = with(fitted, false).expect("own rig");
        assert!(
            w.warnings
                .iter()
                .any(|w| w.text.contains("160 to 640 Hz") && w.text.contains("beyond the support")),
            "{:?}",
            w.warnings
        );
    }

    #[test]
    fn periods_left_out_are_said() {
        let r = drive_record(40.0, 3.7, Some(40.0));
        let a = analyse_trace(&r, &AnalysisOptions::default()).expect("analyses");
        assert_eq!((a.n_periods, a.dropped_samples), (3, 700));
        assert!((a.record_periods - 3.7).abs() < 1e-9);
        let w = a
            .warnings
            .iter()
            .find(|w| w.text.contains("left out"))
            .expect("a warning");
        assert!(
            w.text.contains("3.70 drive periods")
                && w.text.contains("3 whole periods")
                && w.text.contains("0.70 periods (700 samples"),
            "{}",
            w.text
        );
        let whole = drive_record(40.0, 4.0, Some(40.0));
        let a = analyse_trace(&whole, &AnalysisOptions::default()).expect("analyses");
        assert_eq!(a.dropped_samples, 0);
        assert!(!a.warnings.iter().any(|w| w.text.contains("left out")));
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
