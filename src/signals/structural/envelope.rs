//! The Hilbert envelope of a free decay: the analytic signal by FFT and the
//! decay rate fitted over windows of whole cycles (the module docs of
//! [`super`]).

use super::*;

/// The **analytic signal** `z = x + i H{x}` of a real record, by FFT.
///
/// With `X_k` the DFT of `x` (length `N`), the spectrum of `z` is `X_0` at DC,
/// `2 X_k` for `0 < k < N/2`, `X_{N/2}` at Nyquist (even `N`) and 0 at the
/// negative frequencies; `z` is its inverse DFT. It is computed as
/// `Re z = x` exactly and `Im z = H{x}` from the real inverse FFT of
/// `−i X_k` (zero at DC and Nyquist), which is the same thing.
///
/// The DFT treats the record as one period of a periodic signal: where the
/// record's end does not join smoothly to its start, `H{x}` carries an error
/// near both ends, decaying like `1 / (ωt)²` away from a jump at an extremum
/// of an oscillation (about 1 % of the jump one cycle away) but only like
/// `1 / (ωt)` away from a cut mid-lobe. [`envelope_decay`] zero-pads, cuts
/// at extrema and drops the ends for that reason.
///
/// Errors: fewer than 2 samples or a non-finite sample.
pub fn analytic_signal(x: &[f64]) -> Result<Vec<Complex64>> {
    check_min_len("x", x, 2, "analytic_signal")?;
    check_finite("x", x)?;
    // The last bin is the Nyquist bin for even n (then 2 (bins − 1) = n).
    let n = x.len();
    let last_bin = n / 2;
    let nyquist = (2 * last_bin == n).then_some(last_bin);
    let hilbert = filter_spectrum(x, |k, s| {
        if k == 0 || Some(k) == nyquist {
            Complex64::new(0.0, 0.0)
        } else {
            // −i (a + i b) = b − i a
            Complex64::new(s.im, -s.re)
        }
    })?;
    Ok(x.iter()
        .zip(&hilbert)
        .map(|(&re, &im)| Complex64::new(re, im))
        .collect())
}

/// `x` through its real FFT, each bin `k` replaced by `edit(k, bin)`, and
/// back (scaled by `1/n`, so an edit that keeps every bin returns `x`). The
/// Nyquist bin of an even record is kept real, as a real signal's must be.
pub(super) fn filter_spectrum(
    x: &[f64],
    edit: impl Fn(usize, Complex64) -> Complex64,
) -> Result<Vec<f64>> {
    let n = x.len();
    let mut planner = RealFftPlanner::<f64>::new();
    let forward = planner.plan_fft_forward(n);
    let inverse = planner.plan_fft_inverse(n);
    let mut input = x.to_vec();
    let mut spectrum = forward.make_output_vec();
    forward.process(&mut input, &mut spectrum)?;
    for (k, s) in spectrum.iter_mut().enumerate() {
        *s = edit(k, *s);
    }
    if n % 2 == 0 {
        if let Some(last) = spectrum.last_mut() {
            last.im = 0.0;
        }
    }
    let mut out = inverse.make_output_vec();
    inverse.process(&mut spectrum, &mut out)?;
    let scale = 1.0 / n as f64;
    Ok(out.into_iter().map(|v| v * scale).collect())
}

/// `y`, a record through a first-order high-pass (AC coupling) of corner
/// `corner_hz` that started from rest, with that coupling undone: the
/// input `x = y + w_c ∫ y dt` (trapezoids, the integral nil at the first
/// sample). A decaying signal reads high through the coupling (its gain at
/// `s = −σ + jω` is about `1 + σ w_c / ω²`, and its transient adds to it):
/// the thesis rig's 0.2 Hz corner put a 40 Hz decay's crests 0.05-0.07 %
/// high. `corner_hz = 0` gives `y` back.
pub fn undo_high_pass(y: &[f64], sample_rate_hz: f64, corner_hz: f64) -> Vec<f64> {
    let w_dt = std::f64::consts::TAU * corner_hz / sample_rate_hz;
    let mut integral = 0.0;
    let mut out = Vec::with_capacity(y.len());
    for (k, &v) in y.iter().enumerate() {
        if k > 0 {
            integral += 0.5 * (y[k - 1] + v);
        }
        out.push(v + w_dt * integral);
    }
    out
}

/// `x` band-passed to `[low_hz, high_hz]` without phase shift: its FFT with
/// every bin outside the band set to zero, transformed back (the record's
/// mean goes with the zero bin). What a lab does before a logarithmic
/// decrement of one mode of a structure whose other modes ring too; a
/// decaying mode's spectrum is narrow, so the band's sharp edges cost
/// nothing away from the record's ends.
pub fn band_pass(x: &[f64], sample_rate_hz: f64, low_hz: f64, high_hz: f64) -> Result<Vec<f64>> {
    check_min_len("x", x, 2, "band_pass")?;
    check_finite("x", x)?;
    let bin_hz = sample_rate_hz / x.len() as f64;
    filter_spectrum(x, |k, s| {
        let f = k as f64 * bin_hz;
        if k == 0 || f < low_hz || f > high_hz {
            Complex64::new(0.0, 0.0)
        } else {
            s
        }
    })
}

/// Unwraps a sequence of phases (rad) so that successive values differ by
/// less than π.
pub(super) fn unwrap_phase(phases: impl Iterator<Item = f64>) -> Vec<f64> {
    let mut out: Vec<f64> = Vec::new();
    let mut previous_raw = 0.0;
    for p in phases {
        match out.last().copied() {
            None => out.push(p),
            Some(last) => {
                let d = (p - previous_raw + PI).rem_euclid(2.0 * PI) - PI;
                out.push(last + d);
            }
        }
        previous_raw = p;
    }
    out
}

/// The shortest fit window of [`envelope_decay`], cycles. Over a single
/// cycle the slope and the ripple terms of the fit are correlated by 0.78 and
/// the estimate is too sensitive to end effects (tens of % in the first
/// windows); over two the correlation is 0.39.
pub const MIN_CYCLES_PER_FIT: f64 = 2.0;

/// The analytic signal of `x` zero-padded to twice its length, truncated
/// back to `x.len()`: the FFT's wrap-around then joins the record's end to
/// silence, not to its own (large) start.
pub(super) fn padded_analytic_signal(x: &[f64]) -> Result<Vec<Complex64>> {
    let mut padded = x.to_vec();
    padded.resize(2 * x.len(), 0.0);
    let mut z = analytic_signal(&padded)?;
    z.truncate(x.len());
    Ok(z)
}

/// The samples `first..=last` between the first and the last time the
/// unwrapped phase passes a multiple of π (an extremum of the vibration).
pub(super) fn extremum_cut(phase: &[f64]) -> Option<(usize, usize)> {
    let (&p0, &p1) = (phase.first()?, phase.last()?);
    let k0 = (p0 / PI).ceil() * PI;
    let k1 = (p1 / PI).floor() * PI;
    let first = phase.iter().position(|&p| p >= k0)?;
    let last = phase.iter().rposition(|&p| p <= k1)?;
    (last > first).then_some((first, last))
}

/// Least-squares fit over samples `start..end` of
/// `ln A ≈ a − σ (t − t_c) + p cos φ + q sin φ` (`t_c` the window centre),
/// with the decay rate's error.
pub(super) fn envelope_window_fit(
    ln_envelope: &[f64],
    phase: &[f64],
    start: usize,
    end: usize,
    sample_rate_hz: f64,
) -> Option<EnvelopeFit> {
    let centre = 0.5 * (start + end - 1) as f64;
    let basis = |j: usize| {
        let (s, c) = phase[j].sin_cos();
        [1.0, (j as f64 - centre) / sample_rate_hz, c, s]
    };
    let rows = || (start..end).map(|j| (basis(j), ln_envelope[j]));
    let (normal, r) = normal_equations(rows());
    let coefficients = solve(normal, r)?;
    let residuals = fit_residuals(rows(), &coefficients);
    let slope_stderr = match (
        envelope_noise_variance(&residuals),
        inverse_diagonal(normal, 1),
    ) {
        (Some(noise), Some(v11)) => (noise * v11).sqrt(),
        _ => f64::NAN,
    };
    Some(EnvelopeFit {
        centre_s: centre / sample_rate_hz,
        ln_amplitude: coefficients[0],
        sigma_per_s: -coefficients[1],
        sigma_stderr_per_s: slope_stderr,
    })
}

/// The noise a fit of `ln A` over a window sees, as white-noise-equivalent
/// variance per sample: [`residual_noise_variance`] and once more the
/// residuals' variance. White noise on a record reaches the envelope
/// through the analytic signal: `δ ln A = (n cos ψ + H[n] sin ψ) / A`,
/// whose spectrum below the vibration's frequency is twice its mean (a
/// line of `n` at `f₀ ± f` lands at `f` from both sides, in phase, where
/// `n cos ψ` alone would put half of each), and a slope over a few cycles
/// reads that band. The autocorrelation sum cannot see it (spread thinly
/// over a cycle's lags), so on white noise it says `τ ≈ 1` where the slope
/// feels 2: over 200 noise seeds of a decay at ζ 0.05 with white noise the
/// loss factors scattered 1.5-1.7 times the `+-` without the second term,
/// 1.1-1.2 times with it. Where the residuals are correlated (`τ` large)
/// the added term is a small part.
fn envelope_noise_variance(residuals: &[f64]) -> Option<f64> {
    const PARAMS: usize = 4;
    let correlated = residual_noise_variance(residuals, PARAMS)?;
    let white = residuals.iter().map(|r| r * r).sum::<f64>() / (residuals.len() - PARAMS) as f64;
    Some(correlated + white)
}

/// One window's fit of [`envelope_window_fit`].
pub(super) struct EnvelopeFit {
    centre_s: f64,
    ln_amplitude: f64,
    sigma_per_s: f64,
    /// The decay rate's one-sigma error from the fit's residuals
    /// ([`envelope_noise_variance`]).
    sigma_stderr_per_s: f64,
}

/// Cycles dropped at the start of a decay besides the first fit's span, for
/// the cut's end effect: on the dashpot host's decay (ζ 0.063, an ideal rig)
/// a window two to four cycles from the cut read the loss factor 0.11 % low
/// (five of its `+-`) and the energy per cycle 0.49 % low; three to five
/// cycles from it, 0.03 % and 0.15 % (within its `+-`).
pub const START_CYCLES_DROPPED: f64 = 1.0;

/// Loss factor against amplitude from the **Hilbert envelope** of a free
/// decay.
///
/// `x` is a free decay (one mode dominant) with **zero mean** (nothing is
/// removed). Envelope `A = |z|` and phase `φ = unwrap(arg z)` of the
/// [`analytic_signal`] `z`, instantaneous angular frequency `dφ/dt`.
///
/// End effects, and what is done about them:
///
/// - the record is zero-padded to twice its length before the FFT, so the
///   wrap-around does not carry the large start of a decay onto its small
///   end;
/// - it is cut to begin and end at extrema of the vibration (the first and
///   last samples where `φ`, from a first pass, passes a multiple of π):
///   a record cut mid-lobe leaves a net area of up to `A/ω` whose Hilbert
///   transform decays only like `1/t` into the record (5 % of the local
///   envelope one cycle from the end of a decay, 0.5 % ten cycles away); cut
///   at an extremum the disturbance decays like `1/(ωt)²`;
/// - the last `cycles_per_fit` cycles (by phase advance) of the cut record
///   are dropped, and the first `cycles_per_fit` and [`START_CYCLES_DROPPED`]
///   more: at the start the decay is largest, and the disturbance with it.
///
/// The rest is cut into consecutive windows over which the phase advances
/// by `2π × cycles_per_fit`, starting where the phase passes a multiple of
/// π (so a whole or half number of cycles per fit runs from extremum to
/// extremum, as a decrement's crests do), and in each window:
///
/// - `ln A ≈ a − σ (t − t_c) + p cos φ + q sin φ` by least squares, `t_c`
///   the window centre. The two ripple terms take up the envelope's ripple
///   at the vibration frequency (left by the ends, a DC offset or noise),
///   which would otherwise tilt the fitted line: over `n` whole cycles of
///   period `T` a ripple of relative amplitude `e` tilts it by up to
///   `12 e / (2π n² T)`, comparable with `σ` for light damping;
/// - the decay rate's one-sigma error from the fit's residuals: their
///   variance times their integrated autocorrelation time plus one
///   (`envelope_noise_variance`) times the slope's variance per unit noise;
///   carried to `loss_factor_stderr` by `dη/dσ`;
/// - `ω_d = Δφ / Δt` across the window, the mean instantaneous angular
///   frequency (the damped frequency);
/// - `ζ = σ / ω_n = σ / sqrt(ω_d² + σ²)`, `η = 2ζ`;
/// - `amplitude = e^a`, the ripple-free envelope at the window centre (for
///   whole cycles, the exponential of the window's mean `ln A` less the
///   mean of the fitted ripple), `time_s = t_c`, `freq_hz = ω_d / 2π`.
///
/// Windows with an exactly zero envelope sample are skipped.
///
/// Errors: `sample_rate_hz` not positive, `cycles_per_fit` below
/// [`MIN_CYCLES_PER_FIT`] or not finite, fewer than 8 samples, a non-finite sample, or a record spanning
/// no more than `3 × cycles_per_fit + START_CYCLES_DROPPED` cycles between its first and last
/// extremum.
pub fn envelope_decay(
    x: &[f64],
    sample_rate_hz: f64,
    cycles_per_fit: f64,
) -> Result<Vec<DecayPoint>> {
    check_sample_rate(sample_rate_hz)?;
    if !(cycles_per_fit.is_finite() && cycles_per_fit >= MIN_CYCLES_PER_FIT) {
        return Err(invalid(
            "cycles_per_fit",
            cycles_per_fit,
            "cycles",
            format!(
                "must be finite and at least MIN_CYCLES_PER_FIT = {MIN_CYCLES_PER_FIT} \
                 (over one cycle the slope and the ripple terms of the fit are nearly \
                 collinear)"
            ),
        ));
    }
    check_min_len("x", x, 8, "envelope_decay")?;
    check_finite("x", x)?;
    let need = 3.0 * cycles_per_fit + START_CYCLES_DROPPED;
    let too_few = |phase: &[f64]| StructuralError::TooFewCycles {
        cycles: (phase[phase.len() - 1] - phase[0]) / (2.0 * PI),
        cycles_per_fit,
        need,
    };
    let first_pass = unwrap_phase(padded_analytic_signal(x)?.iter().map(|c| c.arg()));
    let (offset, last) = extremum_cut(&first_pass).ok_or_else(|| too_few(&first_pass))?;
    let z = padded_analytic_signal(&x[offset..=last])?;
    let n = z.len();
    let ln_envelope: Vec<f64> = z.iter().map(|c| c.norm().ln()).collect();
    let phase = unwrap_phase(z.iter().map(|c| c.arg()));
    let span = 2.0 * PI * cycles_per_fit;
    if phase[n - 1] - phase[0] <= need * 2.0 * PI {
        return Err(too_few(&phase));
    }
    // Windows may use samples up to `last_usable` (inclusive): the final
    // `cycles_per_fit` cycles are dropped.
    let last_usable = phase
        .iter()
        .rposition(|&p| phase[n - 1] - p >= span)
        .unwrap_or(0);
    // Windows run between the phases `k0 + j span`, `k0` the first multiple
    // of π a span past the record's start: there the signal's analytic
    // phase is a multiple of π in the interior, where it is exact, not
    // counted from the first sample, where the transform's end effect puts
    // it anywhere (the dashpot host's windows started up to 0.35 cycle
    // from an extremum, so their ends held the host's energy at any phase
    // of its ripple).
    let first_target = ((phase[0] + span + 2.0 * PI * START_CYCLES_DROPPED) / PI).ceil() * PI;
    let crossing = |target: f64, from: usize| {
        phase[from..=last_usable]
            .iter()
            .position(|&p| p >= target)
            .map(|steps| from + steps)
    };
    let mut target = first_target;
    let mut start = crossing(target, 0).unwrap_or(n);
    let mut points = Vec::new();
    while start < last_usable {
        target += span;
        let Some(end) = crossing(target, start) else {
            break;
        };
        let usable = end - start >= 8 && ln_envelope[start..end].iter().all(|v| v.is_finite());
        if let Some(fit) = usable
            .then(|| envelope_window_fit(&ln_envelope, &phase, start, end, sample_rate_hz))
            .flatten()
        {
            let omega_d = (phase[end] - phase[start]) * sample_rate_hz / (end - start) as f64;
            // dη/dσ = 2 ω_d² / (σ² + ω_d²)^(3/2).
            let d_eta = 2.0 * omega_d * omega_d / fit.sigma_per_s.hypot(omega_d).powi(3);
            points.push(DecayPoint {
                time_s: fit.centre_s + offset as f64 / sample_rate_hz,
                amplitude: fit.ln_amplitude.exp(),
                freq_hz: omega_d / (2.0 * PI),
                loss_factor: loss_factor_from_rates(fit.sigma_per_s, omega_d),
                loss_factor_stderr: d_eta * fit.sigma_stderr_per_s,
            });
        }
        start = end;
    }
    Ok(points)
}
