//! The H1 and H2 frequency-response functions with coherence by Welch
//! averaging (the module docs of [`super`]).

use super::*;

/// Data window of [`welch_frf`] blocks.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Window {
    /// Periodic Hann window `w_n = ½ (1 − cos(2π n / N))`: for random
    /// signals (low leakage).
    Hann,
    /// No window (`w_n = 1`): for signals periodic in the block (burst
    /// random, periodic chirp, multisine on bins).
    Rectangular,
}

impl Window {
    /// The `len` window coefficients.
    pub fn coefficients(self, len: usize) -> Vec<f64> {
        match self {
            Window::Hann => (0..len)
                .map(|n| 0.5 * (1.0 - (2.0 * PI * n as f64 / len as f64).cos()))
                .collect(),
            Window::Rectangular => vec![1.0; len],
        }
    }
}

/// A frequency-response function estimated by Welch averaging.
#[derive(Debug, Clone, PartialEq)]
pub struct Frf {
    /// Bin frequencies `k fs / block_len`, `k = 0 ..= block_len / 2`, Hz.
    pub freq_hz: Vec<f64>,
    /// `H1 = G_xy / G_xx` (output unit per input unit). Unbiased by
    /// uncorrelated noise on the output; biased low by noise on the input.
    /// NaN where `G_xx = 0`.
    pub h1: Vec<Complex64>,
    /// `H2 = G_yy / G_yx`. Unbiased by uncorrelated noise on the input;
    /// biased high by noise on the output. NaN where `G_xy = 0`.
    pub h2: Vec<Complex64>,
    /// Ordinary coherence `γ² = |G_xy|² / (G_xx G_yy)`, in `[0, 1]` up to
    /// rounding; 0 where `G_xx G_yy = 0`. Exactly 1 (to rounding) for a
    /// single block, whatever the signals.
    pub coherence: Vec<f64>,
    /// Number of averaged blocks `n_d`.
    pub blocks: usize,
    /// The input's and the output's auto-spectra, `⟨|X_k|²⟩` and
    /// `⟨|Y_k|²⟩` over the blocks (windowed, unscaled: the units of the
    /// records squared times samples).
    pub auto_spectra: [Vec<f64>; 2],
    /// The window's power `Σ w_n²` over a block.
    pub window_power: f64,
    /// The variance per sample (input, output; in the records' units
    /// squared) of the part of each record's error that every block
    /// repeats: a periodic excitation with one period per block repeats its
    /// samples, and with them the rounding to the converter's codes that
    /// the channels' noise does not dither away
    /// ([`dithered_rounding_variance`]), which averaging cannot take out
    /// and the coherence cannot see. `[0, 0]` (the default of
    /// [`welch_frf`]) for blocks whose signals differ.
    pub repeated_error_variance: [f64; 2],
}

/// The variance of the part of a converter's rounding error that stays
/// when the same signal is recorded again with fresh noise: step `q`,
/// white Gaussian noise of rms `noise_rms` added before rounding (both in
/// the record's units), a signal that crosses many codes. The rounding
/// error is a sawtooth of the input, `Σ_k (q / πk) (−1)^k sin(2πk v / q)`;
/// averaged over the noise each harmonic keeps `exp(−2π² k² σ² / q²)` of
/// itself, so the repeated part's variance is `Σ_k q² / (2π² k²)
/// exp(−4π² k² σ² / q²)`: `q² / 12` without noise, 20 % of it at the
/// thesis accelerometer's `σ / q` of 0.17, under 0.5 % above 0.35.
pub fn dithered_rounding_variance(step: f64, noise_rms: f64) -> f64 {
    if step == 0.0 {
        return 0.0;
    }
    let r = noise_rms / step;
    if r == 0.0 {
        return step * step / 12.0;
    }
    let r2 = r * r;
    // Terms past `k = 5 / (2π r)` are below e^(−25) of their noiseless
    // value.
    let last = (5.0 / (2.0 * PI * r)).ceil().clamp(8.0, 1e6) as u64;
    (1..=last)
        .map(|k| {
            let k2 = (k * k) as f64;
            (-4.0 * PI * PI * k2 * r2).exp() / k2
        })
        .sum::<f64>()
        * step
        * step
        / (2.0 * PI * PI)
}

impl Frf {
    /// Bendat & Piersol's normalised random error of `|H|` at bin `k`,
    /// `sqrt(1 − γ²) / (|γ| sqrt(2 n))` (one standard deviation, relative),
    /// with `n = n_d − 1`, not their `n_d`: the coherence is estimated from
    /// the same `n_d` blocks, and the power it leaves unexplained (`1 − γ²`)
    /// has lost one block's degrees of freedom to the fitted `H`, so with
    /// `n_d` the error reads `sqrt((n_d − 1)/n_d)` low on average. On the
    /// dashpot host's periodic random test (5 periods) it did: an rms z of
    /// 1.4 over six channel-noise seeds. Even so the error of a few blocks
    /// is itself uncertain (the z-scores follow Student's t with `2 (n_d −
    /// 1)` degrees of freedom, rms `sqrt(ν / (ν − 2))`: 1.15 at 5 blocks).
    /// The formula assumes independent blocks; with overlap (50 % Hann)
    /// they are partly correlated. Infinite where `γ² = 0`; NaN with one
    /// block (nothing to estimate it from: a swept sine's) or if `k` is out
    /// of range.
    ///
    /// With [`Frf::repeated_error_variance`] set, the records' error that
    /// every block repeats ([`Frf::repeated_quantisation_rel`]) adds to it
    /// in quadrature.
    pub fn magnitude_stderr_rel(&self, k: usize) -> f64 {
        let Some(&gamma2) = self.coherence.get(k) else {
            return f64::NAN;
        };
        if self.blocks < 2 {
            return f64::NAN;
        }
        let independent = (self.blocks - 1) as f64;
        let random = (1.0 - gamma2).max(0.0).sqrt() / (gamma2.sqrt() * (2.0 * independent).sqrt());
        random.hypot(self.repeated_quantisation_rel(k))
    }

    /// The relative error of `|H|` at bin `k` from the records' errors that
    /// every block repeats ([`Frf::repeated_error_variance`], `v_x` and
    /// `v_y` per sample, white): their DFT at a bin has `E|E_k|² = Σ w_n²
    /// v`, half of it along the line (what moves `|H|`), so `σ² = Σ w²
    /// (v_x / ⟨|X_k|²⟩ + v_y / ⟨|Y_k|²⟩) / 2`, not divided by the blocks.
    /// White is what a dither makes of the rounding: on the dashpot host's
    /// periodic random test at 16 bits (`σ / q` 0.17 on the acceleration)
    /// the mean squared error of `|H1|` over the mean squared `+-` was
    /// 0.94 with this term and 1.32 without; at 14 and 12 bits, the codes
    /// barely dithered, it was 2.4 and 4.0 with it: the undithered rounding
    /// of a signal one resonance dominates gathers at that resonance's
    /// harmonics, and the `+-` is too small there.
    /// 0 where none is set; NaN out of range.
    pub fn repeated_quantisation_rel(&self, k: usize) -> f64 {
        let [vx, vy] = self.repeated_error_variance;
        let (Some(&gxx), Some(&gyy)) = (self.auto_spectra[0].get(k), self.auto_spectra[1].get(k))
        else {
            return f64::NAN;
        };
        let part = |v: f64, g: f64| if v == 0.0 { 0.0 } else { v / g };
        (0.5 * self.window_power * (part(vx, gxx) + part(vy, gyy))).sqrt()
    }
}

/// **H1 / H2 FRF and coherence by Welch averaging** of an input (force, `x`)
/// and an output (response, `y`) record.
///
/// The records are cut into blocks of `block_len` samples, successive blocks
/// starting `round((1 − overlap) block_len)` samples apart (at least 1); as
/// many blocks as fit are used (`blocks`). Each block is multiplied by the
/// window and transformed (`X_k`, `Y_k`); no mean or trend is removed. The
/// averages `G_xx = ⟨|X_k|²⟩`, `G_yy = ⟨|Y_k|²⟩`, `G_xy = ⟨conj(X_k) Y_k⟩`
/// give `H1 = G_xy / G_xx`, `H2 = G_yy / G_yx` (`G_yx = conj(G_xy)`) and
/// `γ² = |G_xy|² / (G_xx G_yy)`; the scale factors of a one-sided spectral
/// density cancel in all three. Bins `k = 0 ..= block_len / 2` at
/// `k sample_rate_hz / block_len`.
///
/// Bias (Hann window): at a resonance of half-power bandwidth `B_r`, the
/// peak of `|H|` is biased low by about `(B_e / B_r)² / 3` (Bendat &
/// Piersol), `B_e = 1.5 Δf` the window's noise bandwidth and `Δf` the bin
/// spacing: 2 % with 6.5 bins per half-power bandwidth. Choose `block_len`
/// accordingly.
///
/// Errors: lengths differ, `sample_rate_hz` not positive, `block_len` below 8
/// or above the record length, `overlap` outside `[0, 1)`, non-finite samples.
///
/// Over 80 lines: Welch's estimate in one pass, the checks, the window, the
/// blocks' auto- and cross-spectra, then H1, H2 and the coherence, which share
/// the block buffers.
pub fn welch_frf(
    input: &[f64],
    output: &[f64],
    sample_rate_hz: f64,
    block_len: usize,
    overlap: f64,
    window: Window,
) -> Result<Frf> {
    check_same_len("input", input, "output", output)?;
    check_sample_rate(sample_rate_hz)?;
    if block_len < 8 || block_len > input.len() {
        return Err(invalid(
            "block_len",
            block_len as f64,
            "samples",
            format!(
                "must be at least 8 and at most the record length ({} samples)",
                input.len()
            ),
        ));
    }
    if !(overlap.is_finite() && (0.0..1.0).contains(&overlap)) {
        return Err(invalid(
            "overlap",
            overlap,
            "(fraction of block_len)",
            "must be in [0, 1)",
        ));
    }
    check_finite("input", input)?;
    check_finite("output", output)?;

    let step = (((1.0 - overlap) * block_len as f64).round() as usize).max(1);
    let blocks = (input.len() - block_len) / step + 1;
    let w = window.coefficients(block_len);
    let mut planner = RealFftPlanner::<f64>::new();
    let fft = planner.plan_fft_forward(block_len);
    let mut buffer = fft.make_input_vec();
    let mut scratch = fft.make_scratch_vec();
    let mut xs = fft.make_output_vec();
    let mut ys = fft.make_output_vec();
    let bins = xs.len();
    let mut gxx = vec![0.0; bins];
    let mut gyy = vec![0.0; bins];
    let mut gxy = vec![Complex64::new(0.0, 0.0); bins];
    for b in 0..blocks {
        let range = b * step..b * step + block_len;
        for ((o, &v), &wn) in buffer.iter_mut().zip(&input[range.clone()]).zip(&w) {
            *o = v * wn;
        }
        fft.process_with_scratch(&mut buffer, &mut xs, &mut scratch)?;
        for ((o, &v), &wn) in buffer.iter_mut().zip(&output[range]).zip(&w) {
            *o = v * wn;
        }
        fft.process_with_scratch(&mut buffer, &mut ys, &mut scratch)?;
        for k in 0..bins {
            gxx[k] += xs[k].norm_sqr();
            gyy[k] += ys[k].norm_sqr();
            gxy[k] += xs[k].conj() * ys[k];
        }
    }
    let nan = Complex64::new(f64::NAN, f64::NAN);
    let h1 = gxy
        .iter()
        .zip(&gxx)
        .map(|(&g, &a)| if a > 0.0 { g / a } else { nan })
        .collect();
    let h2 = gxy
        .iter()
        .zip(&gyy)
        .map(|(&g, &b)| {
            if g.norm_sqr() > 0.0 {
                Complex64::new(b, 0.0) / g.conj()
            } else {
                nan
            }
        })
        .collect();
    let coherence = (0..bins)
        .map(|k| {
            let denominator = gxx[k] * gyy[k];
            if denominator > 0.0 {
                gxy[k].norm_sqr() / denominator
            } else {
                0.0
            }
        })
        .collect();
    let freq_hz = (0..bins)
        .map(|k| k as f64 * sample_rate_hz / block_len as f64)
        .collect();
    let mean = |g: Vec<f64>| g.into_iter().map(|v| v / blocks as f64).collect();
    Ok(Frf {
        freq_hz,
        h1,
        h2,
        coherence,
        blocks,
        auto_spectra: [mean(gxx), mean(gyy)],
        window_power: w.iter().map(|v| v * v).sum(),
        repeated_error_variance: [0.0, 0.0],
    })
}
