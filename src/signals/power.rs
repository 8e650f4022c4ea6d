//! Power dissipated in a harmonically driven damper, by Yang's
//! structure-independent method (thesis Section 7.4.2, eq. 7.8-7.12, with
//! the erratum of docs/design.md, "Thesis errata": the factor 1/2 belongs to
//! amplitude-normalised one-sided spectra, `|X_k| = 2 |DFT_k| / N`), and the
//! damping efficiency of eq. 7.7 / 6.10.
//!
//! # Inputs and sign convention
//!
//! - `force`: the force the shaker applies to the damper, in N, i.e. what the
//!   transducer between shaker and enclosure reads (positive along the
//!   accelerometer's positive axis);
//! - `accel`: the enclosure's acceleration, in m/s^2, same axis;
//! - `sample_rate_hz`, `drive_freq_hz`.
//!
//! Power flowing from the shaker into the damper is positive. An empty rigid
//! enclosure (`f = m a`) takes no power: its force leads its velocity by
//! exactly +90 deg.
//!
//! # Method
//!
//! 1. Pick a window holding a whole number of drive periods
//!    ([`plan_window`]): by default the largest number that fits from the
//!    window start, `N = round(n_periods fs / f)` samples; the residual
//!    `N f / fs - n_periods` (in periods) is reported so the caller can judge
//!    leakage. Fewer than two periods is an error (an explicit window may
//!    hold one: a record's per-period series is Yang's power of each period
//!    on its own). Nothing is detrended; the
//!    DC bin is simply excluded.
//! 2. One-sided amplitude spectra `F_k`, `A_k` (see [`super::spectrum`]);
//!    `V_k = A_k / (j w_k)` for `k >= 1` (eq. 7.11), `w_k = 2 pi k fs / N`:
//!    each bin is integrated at its own frequency, never at `k` times the
//!    nominal drive frequency, which differs from it whenever the window is
//!    not a whole number of drive periods (an explicit window, or a shaker
//!    that ran off its nominal frequency). With `w_k` the sum equals the
//!    time-domain mean of `f v` over the window exactly (below).
//! 3. `P = sum_k 1/2 |F_k| |V_k| cos(phi_F_k - phi_V_k - phi_err(f_k))`
//!    (eq. 7.12 less the calibrated phase error of Fig. 7.9, evaluated at each
//!    bin's own frequency: see [`PhaseCorrection`] and
//!    [`super::phase_model`] for how it varies across harmonics), over
//!    `1 <= k < N/2` ([`BinSelection::AllBins`], the thesis' sum) or over the
//!    drive harmonics only ([`BinSelection::DriveHarmonics`]). The Nyquist
//!    bin of an even `N` is left out: a sampled real sequence at exactly
//!    fs/2 has no defined velocity phase, and without correction its term is
//!    identically zero.
//! 4. `E_cycle = P / f` (eq. 7.8, `2 pi P / w`).
//!
//! # Force polarity
//!
//! A lab that records the gauge's reaction instead of the force on the
//! enclosure hands over `-f`: every term of eq. 7.12 changes sign and the
//! damper seems to deliver power. [`ForcePolarity::Detect`] looks at the complex power `S = F_1 conj(V_1) e^(-j phi_err) / 2` of the
//! drive bin: a passive damper on an enclosure of mass takes power
//! (`Re S >= 0`) and looks like a mass (`Im S > 0`), so `S` lies in the
//! first quadrant, and the gauge reaction puts it in the third. The record is
//! taken as reversed when `Re S + Im S < 0`, the line halfway between, and the
//! force is negated ([`PowerResult::force_polarity`] says so). The default,
//! [`ForcePolarity::AsRecorded`], takes the force as given (a synthetic or
//! active record may lie anywhere) but still reports whether the record looks
//! reversed; `vlab analyze` and a measured shake detect. On the empty
//! enclosure the same flip reads as a phase error near `pi`
//! (`estimate_phase_error`, `phase_point.rs`).
//!
//! For signals whose content lies on bins below Nyquist, `P` equals the
//! time-domain mean of `f(t) v(t)` over the window ([`mean_power_time_domain`]),
//! where `v` is the zero-mean integral of `a`.

use std::f64::consts::PI;

use realfft::num_complex::Complex64;

use super::calibration::PhaseCalibration;
use super::error::{InvalidParameter, Result, SignalsError, all_finite, positive_finite};
use super::phase_model::PhaseErrorModel;
use super::spectrum::{SpectrumPlan, bin_freq_hz};
use super::trace::Trace;

/// Phase error `phi_err(f)` subtracted from `phi_F - phi_V` in each bin.
#[derive(Debug, Clone, Copy, Default)]
pub enum PhaseCorrection<'a> {
    /// No correction.
    #[default]
    None,
    /// The same phase error, in rad, at every frequency (the thesis applies
    /// the error measured at the drive frequency).
    Constant(f64),
    /// A pure time delay of the force channel relative to the acceleration
    /// channel, in s: `phi_err(f) = 2 pi f tau`.
    TimeDelay(f64),
    /// An empty-enclosure calibration table, evaluated per bin
    /// ([`PhaseCalibration::phase_error_at`]: its fitted high-pass + skew
    /// model when it holds two or more frequencies).
    Table(&'a PhaseCalibration),
    /// The chain's high-pass + skew model (eq. M1 of
    /// [`super::phase_model`]), e.g. from a rig description.
    Model(PhaseErrorModel),
}

impl PhaseCorrection<'_> {
    /// The phase error at `freq_hz`, in rad.
    pub fn phase_error_at(&self, freq_hz: f64) -> f64 {
        match self {
            PhaseCorrection::None => 0.0,
            PhaseCorrection::Constant(rad) => *rad,
            PhaseCorrection::TimeDelay(tau_s) => 2.0 * PI * freq_hz * tau_s,
            PhaseCorrection::Table(cal) => cal.phase_error_at(freq_hz),
            PhaseCorrection::Model(model) => model.phase_error_at(freq_hz),
        }
    }

    fn validate(&self) -> Result<()> {
        let (name, value, unit) = match self {
            PhaseCorrection::Model(model) => return Ok(model.validate()?),
            PhaseCorrection::Constant(rad) => ("phase_correction_rad", *rad, "rad"),
            PhaseCorrection::TimeDelay(s) => ("phase_correction_delay_s", *s, "s"),
            _ => return Ok(()),
        };
        if value.is_finite() {
            Ok(())
        } else {
            Err(SignalsError::from(InvalidParameter::new(
                name, value, unit, "finite",
            )))
        }
    }
}

/// Whether the force channel is negated before the power is summed (see the
/// module docs, "Force polarity").
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum ForcePolarity {
    /// Decide from the drive bin's complex power: negate when `Re S + Im S < 0`
    /// (what `vlab analyze` and a measured shake do).
    Detect,
    /// The record's force is the force on the enclosure: use it as it is (the
    /// default of the pure function; [`PolarityVerdict::looks_reversed`]
    /// still says when it does not look so).
    #[default]
    AsRecorded,
    /// The record's force is the gauge reaction: negate it.
    Reversed,
}

/// How the force polarity was settled for one analysis.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct PolarityVerdict {
    /// True when the force was negated before the sum.
    pub reversed: bool,
    /// True when [`ForcePolarity::Detect`] decided it, false when given.
    pub detected: bool,
    /// True when the drive bin looks like a gauge reaction, whether or not
    /// the force was negated for it.
    pub looks_reversed: bool,
    /// `arg S` of the drive bin as recorded (phase-corrected, not negated),
    /// rad: near `+pi/2` for a normal record, near `-pi/2` for a reversed one.
    pub drive_power_angle_rad: f64,
}

/// True when the drive bin's complex power `s` (as recorded) lies on the
/// gauge-reaction side of `Re S + Im S = 0` (see the module docs).
pub fn looks_reversed(s: Complex64) -> bool {
    s.re + s.im < 0.0
}

/// One bin's complex power `F conj(V) e^(-j phi_err) / 2`, with
/// `V = A / (j w)` integrated at the bin's own frequency `freq_hz` (eq. 7.11)
/// and the phase error `phase_error_rad` removed (eq. 7.12, Fig. 7.9); its
/// real part is the bin's power in W. `freq_hz > 0`.
pub fn bin_power(
    force: Complex64,
    accel: Complex64,
    freq_hz: f64,
    phase_error_rad: f64,
) -> Complex64 {
    let omega_rad_s = 2.0 * PI * freq_hz;
    // conj(V) = conj(A / (j w)) = j conj(A) / w
    let f_conj_v = force * Complex64::new(0.0, 1.0) * accel.conj() / omega_rad_s;
    let rotated = if phase_error_rad == 0.0 {
        f_conj_v
    } else {
        f_conj_v * Complex64::from_polar(1.0, -phase_error_rad)
    };
    0.5 * rotated
}

/// Which bins enter the power sum.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum BinSelection {
    /// Every bin `1 <= k < N/2` (thesis eq. 7.12).
    #[default]
    AllBins,
    /// Only bins at multiples of the drive bin.
    DriveHarmonics,
}

/// Which samples are analysed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PowerWindow {
    /// The largest whole number of drive periods starting at sample `start`.
    Auto {
        /// First sample of the window.
        start: usize,
    },
    /// Exactly `len` samples from `start`; the caller vouches for whole periods
    /// (the residual is still reported).
    Explicit {
        /// First sample of the window.
        start: usize,
        /// Window length in samples.
        len: usize,
    },
}

impl Default for PowerWindow {
    fn default() -> Self {
        PowerWindow::Auto { start: 0 }
    }
}

/// Options of [`yang_power`].
#[derive(Debug, Clone, Copy)]
pub struct PowerOptions<'a> {
    /// Analysis window.
    pub window: PowerWindow,
    /// Bins summed.
    pub bins: BinSelection,
    /// Phase error subtracted per bin.
    pub phase_correction: PhaseCorrection<'a>,
    /// Whether to negate the force.
    pub force_polarity: ForcePolarity,
    /// How many drive harmonics to list in [`PowerResult::per_harmonic`].
    pub n_harmonics: usize,
}

impl Default for PowerOptions<'_> {
    fn default() -> Self {
        Self {
            window: PowerWindow::default(),
            bins: BinSelection::default(),
            phase_correction: PhaseCorrection::None,
            force_polarity: ForcePolarity::AsRecorded,
            n_harmonics: 20,
        }
    }
}

/// The window actually analysed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WindowPlan {
    /// First sample.
    pub start: usize,
    /// Number of samples `N`.
    pub n_samples: usize,
    /// Whole drive periods in the window (nearest integer to `N f / fs`).
    pub n_periods: usize,
    /// `N f / fs - n_periods`: how far the window is from a whole number of
    /// periods, in periods (0 when the drive period is a whole number of
    /// samples). Leakage grows with its magnitude.
    pub residual_periods: f64,
}

/// One drive harmonic's share of the power.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct HarmonicPower {
    /// Harmonic number (1 = drive).
    pub harmonic: usize,
    /// Bin frequency, in Hz.
    pub freq_hz: f64,
    /// Force amplitude `|F_k|`, in N.
    pub force_amp_n: f64,
    /// Velocity amplitude `|V_k|`, in m/s.
    pub velocity_amp_mps: f64,
    /// `phi_F - phi_V - phi_err` (the force as corrected for polarity),
    /// wrapped to (-pi, pi], in rad.
    pub phase_rad: f64,
    /// `1/2 |F_k| |V_k| cos(phase_rad)`, in W.
    pub power_w: f64,
}

/// Result of [`yang_power`].
#[derive(Debug, Clone, PartialEq)]
pub struct PowerResult {
    /// Mean power into the damper over the window, in W.
    pub power_w: f64,
    /// Energy dissipated per drive cycle, `P / f` (eq. 7.8), in J.
    pub energy_per_cycle_j: f64,
    /// Whole drive periods in the window.
    pub n_periods: usize,
    /// Samples in the window.
    pub n_samples: usize,
    /// First sample of the window.
    pub window_start: usize,
    /// Window length minus a whole number of periods, in periods.
    pub residual_periods: f64,
    /// Bin of the drive frequency in the window's spectrum.
    pub drive_bin: usize,
    /// Phase error subtracted at the drive bin, in rad.
    pub phase_correction_rad: f64,
    /// Whether the force was negated, and why.
    pub force_polarity: PolarityVerdict,
    /// The first drive harmonics (up to `n_harmonics`, below Nyquist).
    pub per_harmonic: Vec<HarmonicPower>,
}

/// Chooses the analysis window (see the module docs). `n_total` is the record
/// length in samples.
pub fn plan_window(
    n_total: usize,
    sample_rate_hz: f64,
    drive_freq_hz: f64,
    window: PowerWindow,
) -> Result<WindowPlan> {
    positive_finite("sample_rate_hz", sample_rate_hz, "Hz")?;
    positive_finite("drive_freq_hz", drive_freq_hz, "Hz")?;
    if drive_freq_hz >= sample_rate_hz / 2.0 {
        return Err(SignalsError::from(InvalidParameter::new(
            "drive_freq_hz",
            drive_freq_hz,
            "Hz",
            format!(
                "below the Nyquist frequency sample_rate_hz / 2 = {} Hz",
                sample_rate_hz / 2.0
            ),
        )));
    }
    let periods_in = |n: usize| n as f64 * drive_freq_hz / sample_rate_hz;
    let too_few = |n: usize| SignalsError::TooFewPeriods {
        periods: periods_in(n),
        drive_freq_hz,
        n_samples: n,
        sample_rate_hz,
    };
    let (start, n_samples, n_periods) = match window {
        PowerWindow::Explicit { start, len } => {
            if start.checked_add(len).is_none_or(|end| end > n_total) {
                return Err(SignalsError::WindowOutOfRange {
                    start,
                    len,
                    available: n_total,
                });
            }
            // One period is enough for a window the caller chose: the
            // per-period series a record's standard error comes from.
            let n_periods = periods_in(len).round();
            if n_periods < 1.0 {
                return Err(too_few(len));
            }
            (start, len, n_periods as usize)
        }
        PowerWindow::Auto { start } => {
            let available = n_total
                .checked_sub(start)
                .ok_or(SignalsError::WindowOutOfRange {
                    start,
                    len: 0,
                    available: n_total,
                })?;
            let samples_per_period = sample_rate_hz / drive_freq_hz;
            // A hair of slack so that e.g. 3 periods of exactly 4000 samples
            // are not lost to rounding in the division.
            let mut n_periods = (periods_in(available) + 1e-9).floor() as usize;
            let mut n_samples = (n_periods as f64 * samples_per_period).round() as usize;
            while n_samples > available && n_periods > 0 {
                n_periods -= 1;
                n_samples = (n_periods as f64 * samples_per_period).round() as usize;
            }
            if n_periods < 2 {
                return Err(too_few(available));
            }
            (start, n_samples, n_periods)
        }
    };
    Ok(WindowPlan {
        start,
        n_samples,
        n_periods,
        residual_periods: periods_in(n_samples) - n_periods as f64,
    })
}

/// Settles the polarity from `choice` and the drive bin's complex power `s`
/// as recorded.
fn polarity_verdict(choice: ForcePolarity, s: Complex64) -> PolarityVerdict {
    let (reversed, detected) = match choice {
        ForcePolarity::Detect => (looks_reversed(s), true),
        ForcePolarity::AsRecorded => (false, false),
        ForcePolarity::Reversed => (true, false),
    };
    PolarityVerdict {
        reversed,
        detected,
        looks_reversed: looks_reversed(s),
        drive_power_angle_rad: s.arg(),
    }
}

/// Reusable Yang power estimator: keeps the FFT plan and the two spectrum
/// buffers between calls with the same window length.
#[derive(Debug, Default)]
pub struct YangPower {
    plan: Option<SpectrumPlan>,
    force_spec: Vec<Complex64>,
    accel_spec: Vec<Complex64>,
}

impl YangPower {
    /// An estimator with nothing planned yet.
    pub fn new() -> Self {
        Self::default()
    }

    /// Plans (or reuses) the FFT for `n` samples and fills both spectra from
    /// the window.
    pub(crate) fn spectra(
        &mut self,
        force: &[f64],
        accel: &[f64],
    ) -> Result<(&[Complex64], &[Complex64])> {
        let n = force.len();
        if self.plan.as_ref().is_some_and(|p| p.n_samples() != n) {
            self.plan = None;
        }
        let plan = match &mut self.plan {
            Some(plan) => plan,
            slot => {
                let plan = SpectrumPlan::new(n)?;
                self.force_spec = plan.make_output();
                self.accel_spec = plan.make_output();
                slot.insert(plan)
            }
        };
        plan.process_into(force, &mut self.force_spec)?;
        plan.process_into(accel, &mut self.accel_spec)?;
        Ok((&self.force_spec, &self.accel_spec))
    }

    /// Yang's power; see [`yang_power`].
    pub fn compute(
        &mut self,
        force: &[f64],
        accel: &[f64],
        sample_rate_hz: f64,
        drive_freq_hz: f64,
        options: &PowerOptions<'_>,
    ) -> Result<PowerResult> {
        check_pair(force, "force", accel, "acceleration")?;
        options.phase_correction.validate()?;
        let w = plan_window(force.len(), sample_rate_hz, drive_freq_hz, options.window)?;
        let range = w.start..w.start + w.n_samples;
        let (f_spec, a_spec) = self.spectra(&force[range.clone()], &accel[range])?;

        let n = w.n_samples;
        let drive_bin = (n as f64 * drive_freq_hz / sample_rate_hz).round() as usize;
        // Bins 1 ..= last; the Nyquist bin of an even N is excluded.
        let end = n.div_ceil(2);
        let freq_of = |k: usize| bin_freq_hz(k, n, sample_rate_hz);
        let as_recorded = |k: usize| {
            let freq = freq_of(k);
            bin_power(
                f_spec[k],
                a_spec[k],
                freq,
                options.phase_correction.phase_error_at(freq),
            )
        };
        let force_polarity = polarity_verdict(options.force_polarity, as_recorded(drive_bin));
        let sign = if force_polarity.reversed { -1.0 } else { 1.0 };
        let term = |k: usize| sign * as_recorded(k);
        let power_w = match options.bins {
            BinSelection::AllBins => (1..end).map(|k| term(k).re).sum::<f64>(),
            BinSelection::DriveHarmonics => (1..)
                .map(|h| h * drive_bin)
                .take_while(|&k| k < end)
                .map(|k| term(k).re)
                .sum::<f64>(),
        };
        let per_harmonic = (1..=options.n_harmonics)
            .map(|h| (h, h * drive_bin))
            .take_while(|&(_, k)| k < end)
            .map(|(harmonic, k)| {
                let t = term(k);
                HarmonicPower {
                    harmonic,
                    freq_hz: freq_of(k),
                    force_amp_n: f_spec[k].norm(),
                    velocity_amp_mps: a_spec[k].norm() / (2.0 * PI * freq_of(k)),
                    phase_rad: t.arg(),
                    power_w: t.re,
                }
            })
            .collect();
        Ok(PowerResult {
            power_w,
            energy_per_cycle_j: power_w / drive_freq_hz,
            n_periods: w.n_periods,
            n_samples: n,
            window_start: w.start,
            residual_periods: w.residual_periods,
            drive_bin,
            phase_correction_rad: options.phase_correction.phase_error_at(freq_of(drive_bin)),
            force_polarity,
            per_harmonic,
        })
    }
}

/// Yang's power (W) of each of `n_periods` whole drive periods from sample
/// `start`, each analysed alone with `options` (its window replaced):
/// the series whose spread says how far to trust the record's mean.
/// Periods start on whole periods rounded to a sample: at drive
/// frequencies that do not divide the sample rate (1024 Hz at 40 kHz:
/// 39.06 samples) a period is one to within half a sample.
pub fn period_powers(
    force: &[f64],
    accel: &[f64],
    sample_rate_hz: f64,
    drive_freq_hz: f64,
    start: usize,
    n_periods: usize,
    options: &PowerOptions<'_>,
) -> Result<Vec<f64>> {
    let period_samples = sample_rate_hz / drive_freq_hz;
    let len = force.len().min(accel.len());
    let mut yang = YangPower::new();
    let mut powers = Vec::with_capacity(n_periods);
    for p in 0..n_periods {
        let a = start + (p as f64 * period_samples).round() as usize;
        let b = (start + ((p + 1) as f64 * period_samples).round() as usize).min(len);
        if b <= a {
            break;
        }
        let one = PowerOptions {
            window: PowerWindow::Explicit {
                start: a,
                len: b - a,
            },
            phase_correction: options.phase_correction,
            force_polarity: options.force_polarity,
            bins: options.bins,
            n_harmonics: options.n_harmonics,
        };
        powers.push(
            yang.compute(force, accel, sample_rate_hz, drive_freq_hz, &one)?
                .power_w,
        );
    }
    Ok(powers)
}

/// Yang's structure-independent power (eq. 7.8-7.12): `force` in N (shaker on
/// damper), `accel` in m/s^2 (enclosure), both sampled at `sample_rate_hz`.
/// Plans a fresh FFT; keep a [`YangPower`] for repeated calls.
pub fn yang_power(
    force: &[f64],
    accel: &[f64],
    sample_rate_hz: f64,
    drive_freq_hz: f64,
    options: &PowerOptions<'_>,
) -> Result<PowerResult> {
    YangPower::new().compute(force, accel, sample_rate_hz, drive_freq_hz, options)
}

/// [`yang_power`] on two channels of a trace.
pub fn yang_power_of_trace(
    trace: &Trace,
    force_channel: &str,
    accel_channel: &str,
    drive_freq_hz: f64,
    options: &PowerOptions<'_>,
) -> Result<PowerResult> {
    yang_power(
        &trace.channel(force_channel)?.samples,
        &trace.channel(accel_channel)?.samples,
        trace.sample_rate_hz,
        drive_freq_hz,
        options,
    )
}

/// Largest energy a damper can dissipate per cycle (thesis eq. 6.10),
/// `4 (Gamma g / w)^2 M`, in J.
pub fn max_energy_per_cycle_j(
    particle_mass_kg: f64,
    gamma: f64,
    freq_hz: f64,
    g_mps2: f64,
) -> Result<f64> {
    positive_finite("particle_mass_kg", particle_mass_kg, "kg")?;
    positive_finite("gamma", gamma, "1")?;
    positive_finite("freq_hz", freq_hz, "Hz")?;
    positive_finite("g_mps2", g_mps2, "m/s^2")?;
    let peak_velocity = gamma * g_mps2 / (2.0 * PI * freq_hz);
    Ok(4.0 * peak_velocity * peak_velocity * particle_mass_kg)
}

/// Damping efficiency `E_cycle / E_max` (thesis eq. 7.7 with eq. 6.10).
pub fn efficiency(
    energy_per_cycle_j: f64,
    particle_mass_kg: f64,
    gamma: f64,
    freq_hz: f64,
    g_mps2: f64,
) -> Result<f64> {
    if !energy_per_cycle_j.is_finite() {
        return Err(SignalsError::from(InvalidParameter::new(
            "energy_per_cycle_j",
            energy_per_cycle_j,
            "J",
            "finite",
        )));
    }
    Ok(energy_per_cycle_j / max_energy_per_cycle_j(particle_mass_kg, gamma, freq_hz, g_mps2)?)
}

/// Time-domain mean of `force * velocity`, in W: the oracle for [`yang_power`]
/// when both are known on the same whole-period window.
pub fn mean_power_time_domain(force: &[f64], velocity: &[f64]) -> Result<f64> {
    check_pair(force, "force", velocity, "velocity")?;
    let sum: f64 = force.iter().zip(velocity).map(|(f, v)| f * v).sum();
    Ok(sum / force.len() as f64)
}

fn check_pair(a: &[f64], a_name: &str, b: &[f64], b_name: &str) -> Result<()> {
    if a.len() != b.len() {
        return Err(SignalsError::LengthMismatch {
            first: a_name.into(),
            first_len: a.len(),
            second: b_name.into(),
            second_len: b.len(),
        });
    }
    if a.is_empty() {
        return Err(SignalsError::TooFewSamples {
            what: format!("{a_name} and {b_name}"),
            need: 1,
            got: 0,
        });
    }
    all_finite(a_name, a)?;
    all_finite(b_name, b)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::signals::phase_model::wrap_phase_rad;
    use crate::signals::testutil::{gaussian, rng};

    const FS: f64 = 40_000.0;
    const F_DRIVE: f64 = 40.0;

    fn omega() -> f64 {
        2.0 * PI * F_DRIVE
    }

    /// (amplitude, phase) per harmonic h = 1, 2, ... of the drive.
    fn harmonics(n: usize, parts: &[(usize, f64, f64)], dc: f64) -> Vec<f64> {
        (0..n)
            .map(|i| {
                let t = i as f64 / FS;
                dc + parts
                    .iter()
                    .map(|&(h, amp, ph)| amp * (h as f64 * omega() * t + ph).cos())
                    .sum::<f64>()
            })
            .collect()
    }

    /// Exact velocity of `harmonics(parts)` as acceleration: zero-mean integral.
    fn velocity_of(n: usize, parts: &[(usize, f64, f64)]) -> Vec<f64> {
        (0..n)
            .map(|i| {
                let t = i as f64 / FS;
                parts
                    .iter()
                    .map(|&(h, amp, ph)| {
                        let w = h as f64 * omega();
                        amp / w * (w * t + ph).sin()
                    })
                    .sum::<f64>()
            })
            .collect()
    }

    /// Mean of F_h cos(hwt + phi) * (A_h / (h w)) sin(hwt + theta) = 1/2 F A/(h w) sin(theta - phi).
    fn expected_power(force: &[(usize, f64, f64)], accel: &[(usize, f64, f64)]) -> f64 {
        let mut p = 0.0;
        for &(hf, f, phi) in force {
            for &(ha, a, theta) in accel {
                if hf == ha {
                    p += 0.5 * f * a / (ha as f64 * omega()) * (theta - phi).sin();
                }
            }
        }
        p
    }

    fn rel_err(a: f64, b: f64) -> f64 {
        (a - b).abs() / b.abs()
    }

    #[test]
    fn single_sinusoid_gives_the_closed_form_power() {
        // f = F cos(wt + phi), a = A cos(wt): v = (A/w) sin(wt), so
        // P = 1/2 F (A/w) cos(phi + pi/2) = -1/2 F A sin(phi) / w. Rel. tol 1e-9.
        let (f_amp, a_amp, phi) = (10.0, 100.0, -PI / 4.0);
        let n = 10_000; // 10 periods
        let force = harmonics(n, &[(1, f_amp, phi)], 0.0);
        let accel = harmonics(n, &[(1, a_amp, 0.0)], 0.0);
        let r = yang_power(&force, &accel, FS, F_DRIVE, &PowerOptions::default()).expect("power");
        let expected = -0.5 * f_amp * a_amp * phi.sin() / omega();
        assert!(
            rel_err(r.power_w, expected) < 1e-9,
            "{} vs {expected}",
            r.power_w
        );
        assert!(rel_err(r.energy_per_cycle_j, expected / F_DRIVE) < 1e-9);
        assert_eq!(
            (r.n_periods, r.n_samples, r.drive_bin, r.window_start),
            (10, 10_000, 10, 0)
        );
        assert_eq!(r.residual_periods, 0.0);
        let h1 = &r.per_harmonic[0];
        assert!(rel_err(h1.force_amp_n, f_amp) < 1e-9);
        assert!(rel_err(h1.velocity_amp_mps, a_amp / omega()) < 1e-9);
        // phi_F - phi_V = phi - (-pi/2)
        assert!((h1.phase_rad - wrap_phase_rad(phi + PI / 2.0)).abs() < 1e-9);
        assert!(rel_err(h1.power_w, expected) < 1e-9);
    }

    #[test]
    fn several_harmonics_and_a_static_force_sum_correctly() {
        // DC (static weight) must not contribute; harmonics add. Rel. tol 1e-9.
        let force = [(1, 12.0, 0.4), (2, 3.0, -1.1), (3, 1.5, 2.0), (7, 0.3, 0.2)];
        let accel = [
            (1, 90.0, 0.1),
            (2, 20.0, 0.3),
            (3, 5.0, -0.5),
            (5, 2.0, 1.0),
        ];
        let n = 8_000;
        let f = harmonics(n, &force, 2.94);
        let a = harmonics(n, &accel, 0.0);
        let r = yang_power(&f, &a, FS, F_DRIVE, &PowerOptions::default()).expect("power");
        let expected = expected_power(&force, &accel);
        assert!(
            rel_err(r.power_w, expected) < 1e-9,
            "{} vs {expected}",
            r.power_w
        );
        let listed: f64 = r.per_harmonic.iter().map(|h| h.power_w).sum();
        assert!(rel_err(listed, expected) < 1e-9);
        assert_eq!(r.per_harmonic.len(), 20);
        assert_eq!(r.per_harmonic[6].harmonic, 7);
        assert!((r.per_harmonic[6].freq_hz - 280.0).abs() < 1e-9);
    }

    #[test]
    fn dft_power_equals_time_domain_mean_of_f_times_v() {
        // v is the exact integral of a; both over the same whole periods. Abs tol
        // 1e-9 relative to the power.
        let force = [(1, 5.0, 1.0), (2, 2.0, 0.0), (4, 1.0, -2.5)];
        let accel = [
            (1, 40.0, 0.0),
            (2, 30.0, 1.0),
            (4, 10.0, -2.0),
            (6, 3.0, 0.0),
        ];
        let n = 6_000;
        let f = harmonics(n, &force, 0.0);
        let a = harmonics(n, &accel, 0.0);
        let v = velocity_of(n, &accel);
        let dft = yang_power(&f, &a, FS, F_DRIVE, &PowerOptions::default()).expect("power");
        let time = mean_power_time_domain(&f, &v).expect("mean");
        assert!(
            rel_err(dft.power_w, time) < 1e-9,
            "{} vs {time}",
            dft.power_w
        );
    }

    #[test]
    fn a_record_that_is_not_whole_periods_is_trimmed() {
        // 30 Hz at 40 kHz: 1333.33 samples per period. 5000 samples hold 3.75
        // periods; 3 periods are exactly 4000 samples, so the power is exact (1e-9).
        let f_drive = 30.0;
        let w = 2.0 * PI * f_drive;
        let n = 5000;
        let t = |i: usize| i as f64 / FS;
        let force: Vec<f64> = (0..n).map(|i| 4.0 * (w * t(i) + 0.7).cos()).collect();
        let accel: Vec<f64> = (0..n).map(|i| 50.0 * (w * t(i)).cos()).collect();
        let r = yang_power(&force, &accel, FS, f_drive, &PowerOptions::default()).expect("power");
        assert_eq!((r.n_periods, r.n_samples), (3, 4000));
        assert_eq!(r.residual_periods, 0.0);
        let expected = -0.5 * 4.0 * 50.0 * 0.7f64.sin() / w;
        assert!(
            rel_err(r.power_w, expected) < 1e-9,
            "{} vs {expected}",
            r.power_w
        );

        // 5500 samples: 4 periods -> round(5333.33) = 5333 samples, residual
        // 5333 * 30 / 40000 - 4 = -0.00025 periods (tol 1e-12).
        let plan = plan_window(5500, FS, f_drive, PowerWindow::default()).expect("plan");
        assert_eq!((plan.n_periods, plan.n_samples), (4, 5333));
        assert!((plan.residual_periods + 0.00025).abs() < 1e-12);
    }

    #[test]
    fn explicit_window_and_window_errors() {
        let n = 10_000;
        let force = harmonics(n, &[(1, 1.0, 0.3)], 0.0);
        let accel = harmonics(n, &[(1, 10.0, 0.0)], 0.0);
        let opts = PowerOptions {
            window: PowerWindow::Explicit {
                start: 2_500,
                len: 5_000,
            },
            ..PowerOptions::default()
        };
        let r = yang_power(&force, &accel, FS, F_DRIVE, &opts).expect("power");
        assert_eq!(
            (r.window_start, r.n_samples, r.n_periods),
            (2_500, 5_000, 5)
        );
        let expected = -0.5 * 10.0 * 0.3f64.sin() / omega();
        assert!(rel_err(r.power_w, expected) < 1e-9);

        let bad = PowerOptions {
            window: PowerWindow::Explicit {
                start: 6_000,
                len: 5_000,
            },
            ..PowerOptions::default()
        };
        assert!(matches!(
            yang_power(&force, &accel, FS, F_DRIVE, &bad),
            Err(SignalsError::WindowOutOfRange { .. })
        ));
        // 1.5 periods only.
        let err = yang_power(
            &force[..1500],
            &accel[..1500],
            FS,
            F_DRIVE,
            &PowerOptions::default(),
        )
        .expect_err("too short");
        assert!(
            err.to_string().contains("at least 2 whole periods"),
            "{err}"
        );
        let err = yang_power(&force, &accel, FS, 30_000.0, &PowerOptions::default())
            .expect_err("above Nyquist");
        assert!(err.to_string().contains("Nyquist"), "{err}");
        assert!(
            yang_power(
                &force,
                &accel[..9_999],
                FS,
                F_DRIVE,
                &PowerOptions::default()
            )
            .is_err()
        );
        let mut nan = force.clone();
        nan[1234] = f64::NAN;
        let err = yang_power(&nan, &accel, FS, F_DRIVE, &PowerOptions::default()).expect_err("NaN");
        assert_eq!(
            err.to_string(),
            "channel 'force' sample 1234 is NaN: samples must be finite"
        );
    }

    #[test]
    fn drive_harmonics_only_ignores_other_bins() {
        // A 60 Hz component (1.5 x drive) in both channels carries power that the
        // all-bins sum counts and the harmonics-only sum does not. Rel. tol 1e-9.
        let n = 20_000; // 20 periods of 40 Hz, 30 of 60 Hz
        let t = |i: usize| i as f64 / FS;
        let w2 = 2.0 * PI * 60.0;
        let force: Vec<f64> = (0..n)
            .map(|i| 2.0 * (omega() * t(i) + 0.5).cos() + 1.0 * (w2 * t(i) - 1.0).cos())
            .collect();
        let accel: Vec<f64> = (0..n)
            .map(|i| 30.0 * (omega() * t(i)).cos() + 20.0 * (w2 * t(i)).cos())
            .collect();
        let p_drive = -0.5 * 2.0 * 30.0 * 0.5f64.sin() / omega();
        let p_other = -0.5 * 1.0 * 20.0 * (-1.0f64).sin() / w2;
        let all = yang_power(&force, &accel, FS, F_DRIVE, &PowerOptions::default()).expect("all");
        let harm = yang_power(
            &force,
            &accel,
            FS,
            F_DRIVE,
            &PowerOptions {
                bins: BinSelection::DriveHarmonics,
                ..PowerOptions::default()
            },
        )
        .expect("harmonics");
        assert!(rel_err(all.power_w, p_drive + p_other) < 1e-9);
        assert!(rel_err(harm.power_w, p_drive) < 1e-9);
    }

    #[test]
    fn white_noise_at_ten_percent_rms_moves_power_by_less_than_one_percent() {
        // 200 periods; noise RMS = 10 % of each signal's RMS, seeded. Tol 1 %.
        let n = 200_000;
        let (f_amp, a_amp, phi) = (10.0, 100.0, -PI / 3.0);
        let mut rng = rng(0x5EED);
        let f_rms = f_amp / 2f64.sqrt();
        let a_rms = a_amp / 2f64.sqrt();
        let force: Vec<f64> = harmonics(n, &[(1, f_amp, phi)], 0.0)
            .into_iter()
            .map(|x| x + 0.1 * f_rms * gaussian(&mut rng))
            .collect();
        let accel: Vec<f64> = harmonics(n, &[(1, a_amp, 0.0)], 0.0)
            .into_iter()
            .map(|x| x + 0.1 * a_rms * gaussian(&mut rng))
            .collect();
        let r = yang_power(&force, &accel, FS, F_DRIVE, &PowerOptions::default()).expect("power");
        let expected = -0.5 * f_amp * a_amp * phi.sin() / omega();
        assert!(
            rel_err(r.power_w, expected) < 0.01,
            "{} vs {expected}",
            r.power_w
        );
        // The test can fail: the clean answer differs from a wrong phase by far more.
        assert!(
            rel_err(
                -0.5 * f_amp * a_amp * (phi + 0.05).sin() / omega(),
                expected
            ) > 0.01
        );
    }

    #[test]
    fn constant_and_delay_corrections_rotate_the_phase() {
        // Correcting by exactly the phase offset of a force that is in phase with
        // velocity except for +0.2 rad restores P = 1/2 F V. Rel. tol 1e-9.
        let n = 4_000;
        let v_amp = 0.5;
        let a_amp = v_amp * omega();
        let err_rad = 0.2;
        // v = (A/w) sin(wt) = V cos(wt - pi/2); a force in phase with v but
        // leading by err_rad: F cos(wt - pi/2 + err_rad).
        let force = harmonics(n, &[(1, 3.0, -PI / 2.0 + err_rad)], 0.0);
        let accel = harmonics(n, &[(1, a_amp, 0.0)], 0.0);
        let opts = PowerOptions {
            phase_correction: PhaseCorrection::Constant(err_rad),
            ..PowerOptions::default()
        };
        let r = yang_power(&force, &accel, FS, F_DRIVE, &opts).expect("power");
        assert!(rel_err(r.power_w, 0.5 * 3.0 * v_amp) < 1e-9);
        assert_eq!(r.phase_correction_rad, err_rad);
        let tau = err_rad / omega();
        let opts = PowerOptions {
            phase_correction: PhaseCorrection::TimeDelay(tau),
            ..PowerOptions::default()
        };
        let r = yang_power(&force, &accel, FS, F_DRIVE, &opts).expect("power");
        assert!(rel_err(r.power_w, 0.5 * 3.0 * v_amp) < 1e-9);
        let bad = PowerOptions {
            phase_correction: PhaseCorrection::Constant(f64::NAN),
            ..PowerOptions::default()
        };
        assert!(yang_power(&force, &accel, FS, F_DRIVE, &bad).is_err());
    }

    #[test]
    fn efficiency_follows_eq_6_10() {
        // 40 Hz, Gamma 20, M = 0.0279 kg: E_max = 4 (20 g / w)^2 M. Rel. tol 1e-12.
        let g = 9.81;
        let e_max = 4.0 * (20.0 * g / omega()).powi(2) * 0.0279;
        let eta = efficiency(0.3 * e_max, 0.0279, 20.0, F_DRIVE, g).expect("eta");
        assert!((eta - 0.3).abs() < 1e-12);
        let err = efficiency(1.0, 0.0, 20.0, F_DRIVE, g).expect_err("zero mass");
        assert!(err.to_string().contains("particle_mass_kg = 0 kg"), "{err}");
    }

    #[test]
    fn a_window_that_is_not_whole_periods_integrates_each_bin_at_its_own_frequency() {
        // Nominal drive 40 Hz, explicit window of 10 100 samples: 10.1 nominal
        // periods, so the drive bin (10) sits at 39.604 Hz, not 40 Hz. The
        // signals hold bins 10, 20 and 30 exactly (a shaker that ran 1 % slow).
        // Dividing each bin by its own w_k gives the closed form to 1e-9;
        // dividing by k x the nominal w would be 1 % low.
        let n = 10_100;
        let opts = PowerOptions {
            window: PowerWindow::Explicit { start: 0, len: n },
            ..PowerOptions::default()
        };
        let f_bin = |k: usize| k as f64 * FS / n as f64;
        let wave = |parts: &[(usize, f64, f64)]| -> Vec<f64> {
            (0..n)
                .map(|i| {
                    let t = i as f64 / FS;
                    parts
                        .iter()
                        .map(|&(k, amp, ph)| amp * (2.0 * PI * f_bin(k) * t + ph).cos())
                        .sum()
                })
                .collect()
        };
        let force = [(10, 6.0, 0.9), (20, 2.0, -0.4), (30, 1.0, 2.1)];
        let accel = [(10, 150.0, 0.0), (20, 40.0, 0.5), (30, 12.0, -1.0)];
        let (f, a) = (wave(&force), wave(&accel));
        let r = yang_power(&f, &a, FS, F_DRIVE, &opts).expect("power");
        assert_eq!((r.drive_bin, r.n_periods), (10, 10));
        assert!((r.residual_periods - 0.1).abs() < 1e-12);
        let closed_form = |w_of: &dyn Fn(usize) -> f64| -> f64 {
            force
                .iter()
                .zip(&accel)
                .map(|(&(k, fa, phi), &(_, aa, theta))| {
                    0.5 * fa * aa / w_of(k) * (theta - phi).sin()
                })
                .sum()
        };
        let exact = closed_form(&|k| 2.0 * PI * f_bin(k));
        let nominal = closed_form(&|k| k as f64 / 10.0 * omega());
        assert!(rel_err(r.power_w, exact) < 1e-9, "{} vs {exact}", r.power_w);
        assert!(
            rel_err(nominal, exact) > 0.005,
            "the test tells the two apart"
        );
        assert!((r.per_harmonic[0].freq_hz - f_bin(10)).abs() < 1e-9);
        // And it is the time-domain mean of f v, v the exact integral of a.
        let v: Vec<f64> = (0..n)
            .map(|i| {
                let t = i as f64 / FS;
                accel
                    .iter()
                    .map(|&(k, amp, ph)| {
                        let w = 2.0 * PI * f_bin(k);
                        amp / w * (w * t + ph).sin()
                    })
                    .sum()
            })
            .collect();
        let time = mean_power_time_domain(&f, &v).expect("mean");
        assert!(rel_err(r.power_w, time) < 1e-9, "{} vs {time}", r.power_w);
    }

    /// An enclosure of 0.25 kg with a viscous load of 7 N s/m (about the
    /// thesis damper at 40 Hz, Gamma 20) and a 2nd harmonic.
    fn damper_record(n: usize) -> (Vec<f64>, Vec<f64>, f64) {
        let (m, c) = (0.25, 7.0);
        let accel = [(1, 196.0, 0.0), (2, 30.0, 0.7)];
        let a = harmonics(n, &accel, 0.0);
        let v = velocity_of(n, &accel);
        let f = a.iter().zip(&v).map(|(a, v)| m * a + c * v).collect();
        let truth = accel
            .iter()
            .map(|&(h, amp, _)| 0.5 * c * (amp / (h as f64 * omega())).powi(2))
            .sum();
        (f, a, truth)
    }

    #[test]
    fn a_reversed_force_is_detected_said_and_corrected() {
        // The gauge reaction (-f) gives the same power, bit for bit (negation
        // is exact through the DFT), and says it was reversed; forced
        // AsRecorded it shows the damper delivering the power.
        let n = 8_000;
        let (f, a, truth) = damper_record(n);
        let flipped: Vec<f64> = f.iter().map(|x| -x).collect();
        let opts = PowerOptions {
            force_polarity: ForcePolarity::Detect,
            ..PowerOptions::default()
        };
        let normal = yang_power(&f, &a, FS, F_DRIVE, &opts).expect("normal");
        let reversed = yang_power(&flipped, &a, FS, F_DRIVE, &opts).expect("reversed");
        assert!(
            rel_err(normal.power_w, truth) < 1e-9,
            "{} vs {truth}",
            normal.power_w
        );
        assert_eq!(reversed.power_w, normal.power_w);
        assert_eq!(reversed.per_harmonic, normal.per_harmonic);
        assert!(!normal.force_polarity.reversed && normal.force_polarity.detected);
        assert!(reversed.force_polarity.reversed && reversed.force_polarity.detected);
        // Force leads velocity by atan(m w / c) = 83.6 deg; reversed, by -96.4 deg.
        let lead = (0.25 * omega() / 7.0).atan();
        assert!((normal.force_polarity.drive_power_angle_rad - lead).abs() < 1e-9);
        assert!((reversed.force_polarity.drive_power_angle_rad - (lead - PI)).abs() < 1e-9);
        let as_recorded = PowerOptions {
            force_polarity: ForcePolarity::AsRecorded,
            ..PowerOptions::default()
        };
        let raw = yang_power(&flipped, &a, FS, F_DRIVE, &as_recorded).expect("raw");
        assert_eq!(raw.power_w, -normal.power_w);
        assert!(!raw.force_polarity.reversed && !raw.force_polarity.detected);
        assert!(raw.force_polarity.looks_reversed);
        assert_eq!(
            PowerOptions::default().force_polarity,
            ForcePolarity::AsRecorded
        );
        // The empty enclosure (f = m a) is not taken for reversed; its reaction is.
        let empty: Vec<f64> = a.iter().map(|a| 0.25 * a).collect();
        let e = yang_power(&empty, &a, FS, F_DRIVE, &opts).expect("empty");
        assert!(!e.force_polarity.reversed && e.power_w.abs() < 1e-9);
        let reaction: Vec<f64> = empty.iter().map(|x| -x).collect();
        assert!(
            yang_power(&reaction, &a, FS, F_DRIVE, &opts)
                .expect("reaction")
                .force_polarity
                .reversed
        );
    }

    #[test]
    fn a_model_correction_is_evaluated_at_each_bin() {
        // The force channel leads by the high-pass + skew model at every
        // harmonic; correcting with the same model restores the viscous power
        // (rel. tol 1e-9), where the pure delay through the drive frequency
        // does not.
        let model = PhaseErrorModel {
            force_high_pass_hz: 0.35,
            accel_high_pass_hz: 0.2,
            skew_s: 5e-6,
        };
        let n = 8_000;
        let (m, c) = (0.25, 7.0);
        let accel = [(1, 196.0, 0.0), (3, 60.0, 0.7), (5, 30.0, -0.3)];
        let a = harmonics(n, &accel, 0.0);
        // f = m a + c v, each harmonic advanced by phi_err(h f).
        let force: Vec<(usize, f64, f64)> = accel
            .iter()
            .map(|&(h, amp, ph)| {
                let w = h as f64 * omega();
                let z = Complex64::new(m, -c / w) * Complex64::from_polar(amp, ph);
                let lead = model.phase_error_at(h as f64 * F_DRIVE);
                (h, z.norm(), z.arg() + lead)
            })
            .collect();
        let f = harmonics(n, &force, 0.0);
        let truth: f64 = accel
            .iter()
            .map(|&(h, amp, _)| 0.5 * c * (amp / (h as f64 * omega())).powi(2))
            .sum();
        let with = |correction| PowerOptions {
            phase_correction: correction,
            force_polarity: ForcePolarity::Detect,
            ..PowerOptions::default()
        };
        let r = yang_power(&f, &a, FS, F_DRIVE, &with(PhaseCorrection::Model(model))).expect("m");
        assert!(rel_err(r.power_w, truth) < 1e-9, "{} vs {truth}", r.power_w);
        // The pure delay through 40 Hz overstates the error by
        // 0.00375 (k - 1/k) rad at harmonic k: the harmonics' power (mass-like
        // reactive power 27 and 45 times the dissipated) comes out about 30 %
        // high.
        let at_harmonics =
            |r: &PowerResult| -> f64 { r.per_harmonic.iter().skip(1).map(|h| h.power_w).sum() };
        let truth_harmonics = truth - 0.5 * c * (196.0 / omega()).powi(2);
        assert!(rel_err(at_harmonics(&r), truth_harmonics) < 1e-9);
        let tau = model.phase_error_at(F_DRIVE) / omega();
        let d = yang_power(&f, &a, FS, F_DRIVE, &with(PhaseCorrection::TimeDelay(tau))).expect("d");
        let delay_err = rel_err(at_harmonics(&d), truth_harmonics);
        assert!(delay_err > 0.2, "{delay_err}");
        assert!(
            rel_err(d.power_w, truth) > 0.002,
            "{} vs {truth}",
            d.power_w
        );
        let bad = PhaseErrorModel {
            skew_s: f64::INFINITY,
            ..model
        };
        assert!(yang_power(&f, &a, FS, F_DRIVE, &with(PhaseCorrection::Model(bad))).is_err());
    }

    #[test]
    fn reusable_estimator_gives_the_same_bits() {
        let n = 4_000;
        let f = harmonics(n, &[(1, 1.0, 0.1), (3, 0.5, 0.2)], 0.0);
        let a = harmonics(n, &[(1, 9.0, 0.0), (3, 2.0, 0.7)], 0.0);
        let mut est = YangPower::new();
        let first = est
            .compute(&f, &a, FS, F_DRIVE, &PowerOptions::default())
            .expect("1");
        let again = est
            .compute(&f, &a, FS, F_DRIVE, &PowerOptions::default())
            .expect("2");
        let fresh = yang_power(&f, &a, FS, F_DRIVE, &PowerOptions::default()).expect("3");
        assert_eq!(first, again);
        assert_eq!(first, fresh);
    }
}
