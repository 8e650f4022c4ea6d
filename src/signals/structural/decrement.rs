//! The logarithmic decrement of a free decay: one positive peak per cycle,
//! refined sub-sample by a parabola, and the loss factor between successive
//! peaks with its error (the module docs of [`super`]).

use super::*;

/// One damping estimate at one vibration amplitude.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct DecayPoint {
    /// Time the estimate belongs to, s from the first sample (midpoint of the
    /// peak pair, or centre of the fit window).
    pub time_s: f64,
    /// Vibration amplitude there, in the unit of the signal (geometric mean
    /// of the peak pair, or of the envelope over the window).
    pub amplitude: f64,
    /// Damped vibration frequency `ω_d / 2π` there, Hz.
    pub freq_hz: f64,
    /// Loss factor `η = 2ζ`, with `ζ = σ / ω_n` the viscous damping ratio of
    /// the SDOF decay with the measured decay rate `σ` and damped frequency
    /// `ω_d` (`ω_n² = ω_d² + σ²`). Negative for a growing oscillation.
    pub loss_factor: f64,
    /// Its one-sigma error from the record's noise around the estimate
    /// (the peak fits' or the envelope fit's residuals, see
    /// [`log_decrement`] and [`envelope_decay`]); NaN where the fit has too
    /// few samples to tell.
    pub loss_factor_stderr: f64,
}

/// Peaks below `NOISE_FLOOR_REL` × the largest sample of the record are
/// ignored by [`log_decrement`].
pub const NOISE_FLOOR_REL: f64 = 1e-3;

/// Hysteresis of the lobe detector of [`log_decrement`], as a fraction of the
/// neighbouring peak: a positive lobe ends when the signal falls below
/// `−LOBE_HYSTERESIS_REL × (its largest sample)`, and the next begins when
/// it rises above `+LOBE_HYSTERESIS_REL × (the last peak)` (never less than
/// the noise floor). Noise cannot split a lobe while it stays below that
/// level; successive peaks may fall by up to a factor 1 / 0.2 = 5 (ζ up to
/// about 0.25).
pub const LOBE_HYSTERESIS_REL: f64 = 0.2;

/// A positive lobe of a record: samples `start..end` (end exclusive), whose
/// largest sample is at `max_index`.
#[derive(Debug, Clone, Copy)]
pub(super) struct Lobe {
    start: usize,
    end: usize,
    max_index: usize,
}

/// The complete positive lobes of `x` (Schmitt trigger with the thresholds of
/// [`LOBE_HYSTERESIS_REL`]): a lobe whose rise or fall is not in the record
/// (one cut by the start or the end) is left out, because its largest sample
/// need not be a peak.
pub(super) fn positive_lobes(x: &[f64], floor: f64) -> Vec<Lobe> {
    let mut lobes = Vec::new();
    let mut arm = floor;
    let mut current: Option<Lobe> = None;
    for (i, &v) in x.iter().enumerate() {
        match current.as_mut() {
            Some(lobe) => {
                if v > x[lobe.max_index] {
                    lobe.max_index = i;
                }
                let release = (LOBE_HYSTERESIS_REL * x[lobe.max_index]).max(floor);
                if v < -release {
                    lobe.end = i;
                    if lobe.start > 0 {
                        lobes.push(*lobe);
                    }
                    arm = release;
                    current = None;
                }
            }
            None => {
                if v > arm {
                    current = Some(Lobe {
                        start: i,
                        end: i,
                        max_index: i,
                    });
                }
            }
        }
    }
    lobes
}

/// The sub-sample peak of a lobe: a least-squares parabola through the
/// samples within `±h` of its largest sample, `h = max(1, 2/9 of the fall
/// from that sample to the lobe's end)`: the trigger releases a fifth of
/// the crest below zero, 0.28 period after it, so `h` is about 1/16 period
/// and the same for every lobe. (It was an eighth of the lobe's length,
/// which is longer for the first lobe, armed at the noise floor rather
/// than a fifth of the last crest: that crest's wider window leaned
/// another way, and the first period read 6.8e-5 short on the dashpot
/// host.) For `h = 1` this is the classical parabolic interpolation through
/// the 3 samples around the maximum; for densely sampled records the wider
/// fit averages measurement noise instead of letting the noisiest sample
/// set the peak (which biases every peak up by about two noise standard
/// deviations). The crest's flattening over the window is taken out
/// ([`crest_flattening`]); a decaying crest's lean still puts the vertex
/// `ζθ²/5ω` late (θ the phase over `h`), the same for every crest, so the
/// periods keep it out. Returns `(fractional sample index, peak value, its
/// one-sigma error (from [`peak_height_stderr`]), how far the parabola falls
/// from the crest to the window's edge)`.
pub(super) fn refine_peak(x: &[f64], lobe: &Lobe) -> (f64, f64, f64, f64) {
    let m = lobe.max_index;
    let h = (2 * (lobe.end - m) / 9).max(1);
    let lo = m.saturating_sub(h).max(lobe.start.saturating_sub(1));
    let hi = (m + h).min(lobe.end).min(x.len() - 1);
    let scale = h as f64;
    let u_of = |i: usize| ((lo + i) as f64 - m as f64) / scale;
    let us = || (0..=hi - lo).map(u_of);
    let (a, r) = normal_equations(us().zip(&x[lo..=hi]).map(|(u, &v)| ([1.0, u, u * u], v)));
    let height_stderr = peak_height_stderr(&x[lo..=hi], u_of, a);
    let fallback = (m as f64, x[m], height_stderr, 0.0);
    let Some([c0, c1, c2]) = solve(a, r) else {
        return fallback;
    };
    if c2 >= 0.0 {
        return fallback;
    }
    let u_lo = (lo as f64 - m as f64) / scale;
    let u_hi = (hi as f64 - m as f64) / scale;
    let u = (-c1 / (2.0 * c2)).clamp(u_lo, u_hi);
    let height = c0 + c1 * u + c2 * u * u;
    let flattening = crest_flattening(a, us(), u, -2.0 * c2 / height);
    (
        m as f64 + u * scale,
        height / (1.0 - flattening),
        height_stderr,
        -c2,
    )
}

/// How far a least-squares parabola over abscissae `us` (normal matrix
/// `parabola`) reads a sinusoid's crest at
/// `crest` low, as a fraction of it: near its crest `cos θ(u − u*) = 1 −
/// θ²(u − u*)²/2 + θ⁴(u − u*)⁴/24 − …`, and the fit takes the quartic
/// term's projection on `{1, u, u²}`, which at the crest is `−3/35` of
/// `θ⁴/24` over a dense symmetric window (`θ⁴/280`; `theta_sq` = `θ²`,
/// from the fit's own curvature). Over ±1/16 period that is 8.5e-5 of the
/// crest: the decrement's ratios lose it, but a crest's height (and the
/// energy per cycle, from its square) kept it (the dashpot host's energies
/// read 0.013 % low on average on an ideal rig, several times their
/// `+-`). The sextic term is below 1e-5 of it.
fn crest_flattening(
    parabola: [[f64; 3]; 3],
    us: impl Iterator<Item = f64>,
    crest: f64,
    theta_sq: f64,
) -> f64 {
    if !(theta_sq.is_finite() && theta_sq > 0.0) {
        return 0.0;
    }
    let (_, quartic) = normal_equations(us.map(|u| ([1.0, u, u * u], (u - crest).powi(4))));
    let Some([q0, q1, q2]) = solve(parabola, quartic) else {
        return 0.0;
    };
    -theta_sq * theta_sq / 24.0 * (q0 + q1 * crest + q2 * crest * crest)
}

/// One-sigma error of a peak's height from the parabola fit over `window`
/// (abscissae `u_of(i)`, normal matrix `parabola`): the noise variance from
/// the residuals of a quartic over the same samples
/// ([`residual_noise_variance`]; a quartic follows a sinusoid's crest over
/// ±1/16 period to 5e-6 of its height, so what is left is noise, not the
/// parabola's own misfit) times the parabola's intercept variance per unit
/// noise (the crest is at `u ≈ 0`). NaN for fewer than 8 samples.
pub(super) fn peak_height_stderr(
    window: &[f64],
    u_of: impl Fn(usize) -> f64,
    parabola: [[f64; 3]; 3],
) -> f64 {
    if window.len() < 8 {
        return f64::NAN;
    }
    let basis = |i: usize| {
        let u = u_of(i);
        [1.0, u, u * u, u * u * u, u * u * u * u]
    };
    let rows = || window.iter().enumerate().map(|(i, &v)| (basis(i), v));
    let Some(c) = least_squares(rows()) else {
        return f64::NAN;
    };
    let residuals = fit_residuals(rows(), &c);
    match (
        residual_noise_variance(&residuals, 5),
        inverse_diagonal(parabola, 0),
    ) {
        (Some(noise), Some(v00)) => (noise * v00).sqrt(),
        _ => f64::NAN,
    }
}

/// The step of a quantised record: the smallest positive difference
/// between successive samples, when nearly all the differences are whole
/// multiples of it (an ADC's record moves by whole codes); 0 otherwise (not
/// quantised, or filtered after quantising), or when it is below a
/// millionth of the record's range.
pub fn quantisation_step(x: &[f64]) -> f64 {
    let range = x.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
    let moves: Vec<f64> = x
        .windows(2)
        .map(|w| (w[1] - w[0]).abs())
        .filter(|d| *d > 1e-12 * range)
        .collect();
    let step = moves.iter().copied().fold(f64::INFINITY, f64::min);
    if !(step.is_finite() && step > 1e-6 * range) {
        return 0.0;
    }
    let on_grid = moves
        .iter()
        .filter(|d| {
            let codes = *d / step;
            (codes - codes.round()).abs() < 1e-3
        })
        .count();
    if on_grid as f64 >= 0.99 * moves.len() as f64 {
        step
    } else {
        0.0
    }
}

/// Loss factor from the **logarithmic decrement** of a free decay.
///
/// `x` is a free decay (one mode dominant) with **zero mean**: the function
/// removes nothing, and a DC offset `d` biases every ratio
/// `(x_i + d) / (x_{i+1} + d)`; subtract the rest level first.
///
/// Peaks: the record is split into positive lobes by a Schmitt trigger (see
/// [`LOBE_HYSTERESIS_REL`]), one peak per lobe, so noise ripples are not
/// taken for peaks; lobes cut by the start or end of the record are left
/// out. Each peak is refined to sub-sample time and height by a parabola
/// (the 3-sample parabolic interpolation when a lobe spans fewer than 16
/// samples, a least-squares parabola over ±1/16 period when densely
/// sampled, see the note on noise below). Peaks below the noise floor
/// [`NOISE_FLOOR_REL`] × the largest sample are ignored.
///
/// For each pair of peaks in successive cycles (`x_i` at `t_i`, `x_{i+1}` at
/// `t_{i+1}`): `δ = ln(x_i / x_{i+1})`, `ζ = δ / sqrt(4π² + δ²)`, `η = 2ζ`;
/// `amplitude = sqrt(x_i x_{i+1})`, `time_s = (t_i + t_{i+1}) / 2`,
/// `freq_hz = 1 / (t_{i+1} − t_i)`. For viscous decay this `η` is exact (the
/// peaks of `A e^(−σt) cos(ω_d t)` are `sqrt(1 − ζ²)` × the envelope, a
/// factor that cancels in `δ`).
///
/// Noise: with measurement noise of standard deviation `s` on peaks of
/// height `a`, each `δ` scatters by about `2.1 s / (a sqrt(2h + 1))`, `h`
/// the half-width of the peak fit in samples (about a sixteenth of the
/// samples per period; 0.19 s/a at 1000 samples per period) — compare with
/// `δ ≈ πη`. For low damping take the median of the points, or use
/// [`envelope_decay`]. Each point's `loss_factor_stderr` is that scatter
/// for the noise the record carries around its two peaks: each peak's
/// height error from the residuals of a quartic over its fit window
/// ([`peak_height_stderr`]: white noise, or the correlated disturbance an
/// impact leaves on a crest) and, for a quantised record, a uniform error
/// over one step (`q² / 12`, `q` the smallest move between successive
/// samples) averaged over the `K ≥ 1` codes the crest falls by across its
/// window, the two peaks independent,
/// `σ_η = (dη/dδ) sqrt((σ₀/x₀)² + (σ₁/x₁)²)`. It is the error of reading
/// this record, not a spread over repeated decays.
///
/// Errors: `sample_rate_hz` not positive, fewer than 3 samples, a non-finite
/// sample, or fewer than 2 peaks in successive cycles.
pub fn log_decrement(x: &[f64], sample_rate_hz: f64) -> Result<Vec<DecayPoint>> {
    log_decrement_quantised(x, sample_rate_hz, quantisation_step(x))
}

/// [`log_decrement`] of a record digitised with step `step` (in the unit of
/// `x`; 0 for none) and filtered since, so that its samples no longer sit
/// on the codes [`quantisation_step`] looks for: the crests still carry the
/// converter's error. (`vlab host decay` undoes the accelerometer's AC
/// coupling before the decrement; read from the undone record, the step
/// was lost, and below Γ 2 the dashpot host's points scattered three times
/// their `+-` over six noise seeds, against half of it with the step.)
///
/// Errors: as [`log_decrement`], and `step` negative or not finite.
pub fn log_decrement_quantised(
    x: &[f64],
    sample_rate_hz: f64,
    step: f64,
) -> Result<Vec<DecayPoint>> {
    check_sample_rate(sample_rate_hz)?;
    if !(step.is_finite() && step >= 0.0) {
        return Err(invalid(
            "step",
            step,
            "(unit of x)",
            "must be finite and at least 0 (0: not quantised)",
        ));
    }
    check_min_len("x", x, 3, "log_decrement")?;
    check_finite("x", x)?;
    let largest = x.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let floor = NOISE_FLOOR_REL * largest.max(0.0);
    if largest <= 0.0 {
        return Err(StructuralError::TooFewPeaks { peaks: 0, floor });
    }
    let lobes = positive_lobes(x, floor);
    // A quantised record's crest that falls by `K` codes over its fit window
    // crosses about `K` code boundaries: its quantisation error, uniform
    // over a code (`q² / 12`) on each stretch, averages over about `K`
    // stretches. A small crest sits on one code for the whole window, and
    // whatever the fit averages keeps up to half a code of error; a large
    // one crosses hundreds and the error is white, in the residuals.
    let q = step;
    // (lobe number, time s, peak value, its error) of the peaks above the
    // floor.
    let peaks: Vec<(usize, f64, f64, f64)> = lobes
        .iter()
        .enumerate()
        .filter_map(|(number, lobe)| {
            let (index, value, stderr, fall) = refine_peak(x, lobe);
            let codes = if q > 0.0 { (fall / q).max(1.0) } else { 1.0 };
            let stderr = (stderr * stderr + q * q / 12.0 / codes).sqrt();
            (value >= floor).then_some((number, index / sample_rate_hz, value, stderr))
        })
        .collect();
    let points: Vec<DecayPoint> = peaks
        .windows(2)
        .filter(|pair| pair[1].0 == pair[0].0 + 1)
        .map(|pair| {
            let (_, t0, x0, e0) = pair[0];
            let (_, t1, x1, e1) = pair[1];
            let delta = (x0 / x1).ln();
            // dη/dδ = 2 (2π)² / (δ² + 4π²)^(3/2); the peaks' errors independent.
            let d_eta = 2.0 * (2.0 * PI).powi(2) / delta.hypot(2.0 * PI).powi(3);
            DecayPoint {
                time_s: 0.5 * (t0 + t1),
                amplitude: (x0 * x1).sqrt(),
                freq_hz: 1.0 / (t1 - t0),
                loss_factor: loss_factor_from_decrement(delta),
                loss_factor_stderr: d_eta * (e0 / x0).hypot(e1 / x1),
            }
        })
        .collect();
    if points.is_empty() {
        return Err(StructuralError::TooFewPeaks {
            peaks: peaks.len(),
            floor,
        });
    }
    Ok(points)
}
