//! Classical structural-dynamics measurements on recorded channels of a host
//! structure: how much damping it has, at what amplitude, and how it responds
//! to force. These are the methods a lab runs on a structure before and after
//! a granular damper is fitted, on records it captured itself (free decays,
//! random or stepped-sine drives); nothing here knows about the DEM model.
//!
//! SI units throughout: seconds, hertz, newtons, metres; every name carries
//! its unit (`time_s`, `freq_hz`, `sample_rate_hz`, `force_n`). Time `t = 0`
//! is the first sample of the record passed in. All inputs are checked
//! (finite samples, ranges) and every failure is a [`StructuralError`] whose
//! message names the parameter, its unit and its valid range.
//!
//! # Damping measures
//!
//! All damping estimates are reported as a loss factor `η = 2ζ`, where `ζ`
//! is the viscous damping ratio of the single-degree-of-freedom (SDOF) free
//! decay `x = A e^(−σt) cos(ω_d t)` that has the measured decay rate `σ` and
//! damped angular frequency `ω_d`: `ω_n² = ω_d² + σ²`, `ζ = σ / ω_n`. For
//! light damping `η` equals the structural loss factor (energy dissipated per
//! radian of vibration over peak stored energy) at resonance.
//!
//! # Methods
//!
//! - [`log_decrement`] — **logarithmic decrement** of a free decay: one
//!   positive peak `x_i` per cycle (sub-sample, parabola fit),
//!   `δ = ln(x_i / x_{i+1})` for successive peaks, `ζ = δ / sqrt(4π² + δ²)`
//!   (exact for viscous SDOF decay, since `δ = σ T_d = 2πζ / sqrt(1 − ζ²)`),
//!   `η = 2ζ`.
//! - [`analytic_signal`], [`envelope_decay`] — **Hilbert envelope**: the
//!   analytic signal `z = x + i H{x}` by FFT, envelope `A = |z|`, phase
//!   `φ = unwrap(arg z)`; over windows of whole cycles, least squares
//!   `ln A ≈ a − σ (t − t_c) + p cos φ + q sin φ` (the last two take up the
//!   envelope's ripple), `ω_d = Δφ / Δt`, `ζ = σ / sqrt(ω_d² + σ²)`,
//!   `η = 2ζ`.
//! - [`welch_frf`] — **H1 / H2 frequency-response function with coherence by
//!   Welch averaging**: per block `X_k`, `Y_k` of the windowed input (force)
//!   and output (response); `G_xx = ⟨|X|²⟩`, `G_yy = ⟨|Y|²⟩`,
//!   `G_xy = ⟨conj(X) Y⟩`, `H1 = G_xy / G_xx`, `H2 = G_yy / G_yx` with
//!   `G_yx = conj(G_xy)`, `γ² = |G_xy|² / (G_xx G_yy)`. H1 is unbiased by
//!   noise on the output, H2 by noise on the input; `H1 / H2 = γ²`.
//!   [`Frf::magnitude_stderr_rel`] is Bendat & Piersol's random error of
//!   `|H|`: `sqrt(1 − γ²) / (|γ| sqrt(2 (n_d − 1)))` (their `n_d` less the
//!   block the fitted `H` takes from the coherence's estimate).
//! - [`half_power`] — **half-power bandwidth**: peak `f_peak` of a receptance
//!   magnitude, the −3 dB (`1/√2`) crossings `f_low`, `f_high` either side,
//!   `η = (f_high − f_low) / f_peak`.
//! - [`sine_component`] — **stepped-sine response**: least-squares fit of
//!   `a cos ωt + b sin ωt + c` over the longest whole number of periods;
//!   the complex amplitude is `a − i b = A e^(iφ)` for `A cos(ωt + φ)`. One
//!   stepped-sine FRF point is `H(f) = Y / X` of two such amplitudes.
//! - [`fit_modes`] — **modal fit of a multi-mode receptance**: peaks picked
//!   by prominence, one mode's inverse line fit for each start, then
//!   Levenberg–Marquardt of `H = Σ_r A_r / (ω_r² − ω² + 2iζ_r ω_r ω)` (plus
//!   residual terms) over the band, with one-sigma errors from the fit's
//!   covariance (Ewins, *Modal Testing*; module `modal_fit`).
//! - [`power_input_w`] — **power-input method**: mean power delivered by a
//!   periodic force, `P = ⟨F v⟩ = Σ_k ½ Re(F_k conj(V_k))`, with the velocity
//!   harmonics `V_k = A_k / (i ω_k)` from the measured acceleration. In steady
//!   state this is the power the structure (and damper) dissipates.
//!
//! # Conventions
//!
//! Complex amplitudes follow `cos`: `Z = A e^(iφ)` stands for
//! `A cos(2π f t + φ)`; a response that lags the force has a smaller `arg`.
//! FRF phases therefore follow `H = 1 / (k − mω² + icω)` (phase −π/2 at
//! resonance for receptance).

use std::f64::consts::PI;

use realfft::RealFftPlanner;
use realfft::num_complex::Complex64;

mod decrement;
mod envelope;
mod half_power;
mod modal_fit;
mod sine;
#[cfg(test)]
mod tests;
mod welch;

pub use decrement::*;
pub use envelope::*;
pub use half_power::*;
pub use modal_fit::*;
pub use sine::*;
pub use welch::*;

/// Result alias of this module.
pub type Result<T> = std::result::Result<T, StructuralError>;

/// Everything that can go wrong in a structural measurement.
#[derive(Debug, thiserror::Error)]
pub enum StructuralError {
    /// A scalar parameter is outside its valid range (the crate's one
    /// refusal, [`crate::validation::InvalidParameter`]).
    #[error("{0}")]
    InvalidParameter(#[from] crate::validation::InvalidParameter),
    /// A sample is NaN or infinite.
    #[error("{name}[{index}] = {value}: samples of {name} must be finite")]
    NonFiniteSample {
        /// Name of the input sequence.
        name: &'static str,
        /// Zero-based sample index.
        index: usize,
        /// The offending value.
        value: f64,
    },
    /// Two sequences that must have equal length do not.
    #[error(
        "{first} has {first_len} samples but {second} has {second_len}: they must have equal length"
    )]
    LengthMismatch {
        /// Name of the first sequence.
        first: &'static str,
        /// Its length.
        first_len: usize,
        /// Name of the second sequence.
        second: &'static str,
        /// Its length.
        second_len: usize,
    },
    /// A sequence is too short for the analysis.
    #[error("{name} has {got} samples: {what} needs at least {need} samples")]
    TooFewSamples {
        /// Name of the input sequence.
        name: &'static str,
        /// Number of samples given.
        got: usize,
        /// Minimum number of samples.
        need: usize,
        /// The analysis.
        what: &'static str,
    },
    /// A record holds less than one period of the analysis frequency.
    #[error(
        "{name} has {len} samples = {periods:.4} periods of freq_hz = {freq_hz} Hz at \
         sample_rate_hz = {sample_rate_hz} Hz: {what} needs at least 1 whole period"
    )]
    TooFewPeriods {
        /// Name of the input sequence.
        name: &'static str,
        /// Number of samples given.
        len: usize,
        /// Periods of `freq_hz` the record spans.
        periods: f64,
        /// The analysis frequency, Hz.
        freq_hz: f64,
        /// The sample rate, Hz.
        sample_rate_hz: f64,
        /// The analysis.
        what: &'static str,
    },
    /// A free decay shows fewer than two peaks in successive cycles.
    #[error(
        "x has {peaks} positive peak(s) above the noise floor {floor} (NOISE_FLOOR_REL = \
         {NOISE_FLOOR_REL} x the largest sample), none of them in successive cycles: \
         log_decrement needs at least 2 peaks in successive cycles"
    )]
    TooFewPeaks {
        /// Complete positive lobes whose peak is above the floor.
        peaks: usize,
        /// The noise floor, in the unit of `x`.
        floor: f64,
    },
    /// A record spans too few cycles for the envelope fit.
    #[error(
        "x spans {cycles:.3} cycles (phase advance of its analytic signal): envelope_decay with \
         cycles_per_fit = {cycles_per_fit} cycles needs more than {need} cycles \
         (cycles_per_fit dropped at each end for end effects, and START_CYCLES_DROPPED \
         more at the start, plus one fit window)"
    )]
    TooFewCycles {
        /// Cycles in the record.
        cycles: f64,
        /// The requested window length, cycles.
        cycles_per_fit: f64,
        /// Cycles needed.
        need: f64,
    },
    /// The magnitude does not fall to the half-power level on one side.
    #[error(
        "half_power: magnitude does not fall to the half-power level {level} (peak {peak} / √2) \
         on the {side} side of the peak at {peak_freq_hz} Hz within freq_hz = \
         [{min_freq_hz}, {max_freq_hz}] Hz: widen the frequency range on that side"
    )]
    NoHalfPowerCrossing {
        /// `"low-frequency"` or `"high-frequency"`.
        side: &'static str,
        /// The peak frequency, Hz.
        peak_freq_hz: f64,
        /// The peak magnitude.
        peak: f64,
        /// The half-power level `peak / √2`.
        level: f64,
        /// Lowest frequency given, Hz.
        min_freq_hz: f64,
        /// Highest frequency given, Hz.
        max_freq_hz: f64,
    },
    /// A modal fit was asked for more modes than the FRF has peaks.
    #[error(
        "modal fit: {asked} mode(s) asked for but |H| has {found} peak(s) (local maxima) within \
         freq_hz = [{min_freq_hz}, {max_freq_hz}] Hz: ask for fewer modes or widen the band"
    )]
    TooFewResonances {
        /// Modes asked for.
        asked: usize,
        /// Local maxima of the magnitude.
        found: usize,
        /// Lowest frequency given, Hz.
        min_freq_hz: f64,
        /// Highest frequency given, Hz.
        max_freq_hz: f64,
    },
    /// A modal fit could not be solved.
    #[error("modal fit: {reason}")]
    ModalFitFailed {
        /// What went wrong, and what to try.
        reason: String,
    },
    /// The FFT library refused a buffer (cannot happen with the buffers built
    /// here; kept as an error rather than a panic).
    #[error("internal FFT error: {0}")]
    Fft(#[from] realfft::FftError),
}

// ---------------------------------------------------------------------------
// Validation helpers
// ---------------------------------------------------------------------------

/// The crate's refusal of `value` for `name`: `requirement` is the valid
/// range in words, with or without a leading "must be".
fn invalid(name: &str, value: f64, unit: &str, requirement: impl Into<String>) -> StructuralError {
    let requirement: String = requirement.into();
    let valid = requirement
        .strip_prefix("must be ")
        .unwrap_or(&requirement)
        .to_string();
    crate::validation::InvalidParameter::new(name, value, unit, valid).into()
}

fn check_sample_rate(sample_rate_hz: f64) -> Result<()> {
    if sample_rate_hz.is_finite() && sample_rate_hz > 0.0 {
        Ok(())
    } else {
        Err(invalid(
            "sample_rate_hz",
            sample_rate_hz,
            "Hz",
            "must be positive and finite",
        ))
    }
}

/// Checks `0 < freq_hz < sample_rate_hz / 2` (call after [`check_sample_rate`]).
fn check_analysis_freq(freq_hz: f64, sample_rate_hz: f64) -> Result<()> {
    let nyquist_hz = 0.5 * sample_rate_hz;
    if freq_hz.is_finite() && freq_hz > 0.0 && freq_hz < nyquist_hz {
        Ok(())
    } else {
        Err(invalid(
            "freq_hz",
            freq_hz,
            "Hz",
            format!(
                "must be in (0, {nyquist_hz}) Hz, i.e. positive and below the Nyquist \
                 frequency sample_rate_hz / 2"
            ),
        ))
    }
}

fn check_finite(name: &'static str, x: &[f64]) -> Result<()> {
    match x.iter().position(|v| !v.is_finite()) {
        None => Ok(()),
        Some(index) => Err(StructuralError::NonFiniteSample {
            name,
            index,
            value: x[index],
        }),
    }
}

fn check_min_len(name: &'static str, x: &[f64], need: usize, what: &'static str) -> Result<()> {
    if x.len() >= need {
        Ok(())
    } else {
        Err(StructuralError::TooFewSamples {
            name,
            got: x.len(),
            need,
            what,
        })
    }
}

fn check_same_len(first: &'static str, a: &[f64], second: &'static str, b: &[f64]) -> Result<()> {
    if a.len() == b.len() {
        Ok(())
    } else {
        Err(StructuralError::LengthMismatch {
            first,
            first_len: a.len(),
            second,
            second_len: b.len(),
        })
    }
}

// ---------------------------------------------------------------------------
// Small numerical helpers
// ---------------------------------------------------------------------------

/// Solves the `N`×`N` system `m v = r` by Gaussian elimination with partial
/// pivoting; `None` if singular.
fn solve<const N: usize>(mut m: [[f64; N]; N], mut r: [f64; N]) -> Option<[f64; N]> {
    for col in 0..N {
        let pivot = (col..N).max_by(|&i, &j| m[i][col].abs().total_cmp(&m[j][col].abs()))?;
        if m[pivot][col] == 0.0 || !m[pivot][col].is_finite() {
            return None;
        }
        m.swap(col, pivot);
        r.swap(col, pivot);
        let pivot_row = m[col];
        for row in col + 1..N {
            let f = m[row][col] / pivot_row[col];
            for (dst, &src) in m[row][col..].iter_mut().zip(&pivot_row[col..]) {
                *dst -= f * src;
            }
            r[row] -= f * r[col];
        }
    }
    let mut v = [0.0; N];
    for row in (0..N).rev() {
        let known: f64 = m[row][row + 1..]
            .iter()
            .zip(&v[row + 1..])
            .map(|(a, b)| a * b)
            .sum();
        v[row] = (r[row] - known) / m[row][row];
    }
    v.iter().all(|x| x.is_finite()).then_some(v)
}

/// Least-squares coefficients of `y ≈ Σ_i c_i basis_i` from the rows
/// `(basis, y)`: accumulates and solves the normal equations.
fn least_squares<const N: usize>(rows: impl Iterator<Item = ([f64; N], f64)>) -> Option<[f64; N]> {
    let (a, r) = normal_equations(rows);
    solve(a, r)
}

/// The normal equations `(XᵀX, Xᵀy)` of the rows `(basis, y)`.
fn normal_equations<const N: usize>(
    rows: impl Iterator<Item = ([f64; N], f64)>,
) -> ([[f64; N]; N], [f64; N]) {
    let mut a = [[0.0_f64; N]; N];
    let mut r = [0.0_f64; N];
    for (basis, y) in rows {
        for ((a_row, r_i), &b_i) in a.iter_mut().zip(r.iter_mut()).zip(&basis) {
            for (a_ij, &b_j) in a_row.iter_mut().zip(&basis) {
                *a_ij += b_i * b_j;
            }
            *r_i += b_i * y;
        }
    }
    (a, r)
}

/// The residuals `y − Σ_i c_i basis_i` of the rows `(basis, y)` after a fit
/// with `coefficients`.
fn fit_residuals<const N: usize>(
    rows: impl Iterator<Item = ([f64; N], f64)>,
    coefficients: &[f64; N],
) -> Vec<f64> {
    rows.map(|(basis, y)| {
        y - basis
            .iter()
            .zip(coefficients)
            .map(|(b, c)| b * c)
            .sum::<f64>()
    })
    .collect()
}

/// The `i`-th diagonal element of `a⁻¹` (`a` the normal matrix `XᵀX` of a
/// fit: a coefficient's variance per unit noise variance).
fn inverse_diagonal<const N: usize>(a: [[f64; N]; N], i: usize) -> Option<f64> {
    let mut e = [0.0; N];
    e[i] = 1.0;
    solve(a, e).map(|v| v[i])
}

/// The noise variance a fit's `residuals` (of a fit with `params`
/// coefficients) say the samples carry, as white-noise-equivalent variance
/// per sample: `s² τ`, `s²` the residuals' variance over `n − params` and
/// `τ = 1 + 2 Σ ρ_k` their integrated autocorrelation time, summed over the
/// lags up to the first non-positive autocorrelation (at most `n / 4`).
/// White noise gives `τ ≈ 1`; what the fit's model misses (an impact's
/// ringing, a ripple) is correlated from sample to sample and counts for
/// more than its variance, as it does in a coefficient's error. `None` with
/// fewer than `params + 3` residuals.
fn residual_noise_variance(residuals: &[f64], params: usize) -> Option<f64> {
    let n = residuals.len();
    if n < params + 3 {
        return None;
    }
    let sum_sq: f64 = residuals.iter().map(|r| r * r).sum();
    let s2 = sum_sq / (n - params) as f64;
    if sum_sq == 0.0 {
        return Some(0.0);
    }
    let mut tau = 1.0;
    for k in 1..=n / 4 {
        let c: f64 = residuals[..n - k]
            .iter()
            .zip(&residuals[k..])
            .map(|(a, b)| a * b)
            .sum();
        let rho = c / sum_sq;
        if rho <= 0.0 {
            break;
        }
        tau += 2.0 * rho;
    }
    Some(s2 * tau)
}

/// The loss factor `η = 2ζ` of a viscous SDOF decay with decay rate
/// `sigma_per_s` and damped angular frequency `omega_d_rad_s`:
/// `ζ = σ / sqrt(ω_d² + σ²)`.
fn loss_factor_from_rates(sigma_per_s: f64, omega_d_rad_s: f64) -> f64 {
    2.0 * sigma_per_s / sigma_per_s.hypot(omega_d_rad_s)
}

/// The loss factor `η = 2ζ` from a logarithmic decrement per cycle `δ`:
/// `ζ = δ / sqrt(4π² + δ²)`.
fn loss_factor_from_decrement(delta: f64) -> f64 {
    2.0 * delta / delta.hypot(2.0 * PI)
}

/// Phase of `cycles` cycles in radians, reduced to one cycle first so that
/// the sine and cosine of long records keep full precision.
fn phase_rad(cycles: f64) -> f64 {
    2.0 * PI * cycles.fract()
}

/// Number of samples in the longest whole number of periods of `freq_hz`
/// from the start of a record of `len` samples: the samples with
/// `t_n = n / sample_rate_hz < n_p / freq_hz`, `n_p = floor(len f / fs)`.
/// A period count or sample count within 1e-9 of an integer is taken as
/// that integer, so a record of exactly whole periods keeps all of them.
fn whole_period_len(
    name: &'static str,
    len: usize,
    sample_rate_hz: f64,
    freq_hz: f64,
    what: &'static str,
) -> Result<usize> {
    let periods = len as f64 * freq_hz / sample_rate_hz;
    let whole = (periods + 1e-9).floor();
    if whole < 1.0 {
        return Err(StructuralError::TooFewPeriods {
            name,
            len,
            periods,
            freq_hz,
            sample_rate_hz,
            what,
        });
    }
    let exact = whole * sample_rate_hz / freq_hz;
    let nearest = exact.round();
    let samples = if (exact - nearest).abs() <= 1e-9 * exact.max(1.0) {
        nearest
    } else {
        exact.ceil()
    };
    Ok((samples as usize).min(len))
}
