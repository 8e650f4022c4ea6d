//! One-sided, amplitude-normalised spectra of real records (the `F_k`, `A_k`
//! of thesis eq. 7.10-7.11, with the erratum of docs/design.md,
//! "Thesis errata", applied).
//!
//! # Convention (read this first)
//!
//! For `N` real samples `x_0 .. x_{N-1}` the raw DFT is
//! `DFT_k = sum_i x_i exp(-j 2 pi k i / N)` (the forward transform of realfft,
//! no scaling). This module returns, for `k = 0 ..= N/2` (integer division),
//!
//! - `X_0 = DFT_0 / N` (the mean),
//! - `X_k = 2 DFT_k / N` for `0 < k < N/2`,
//! - `X_{N/2} = DFT_{N/2} / N` for even `N` (the Nyquist bin).
//!
//! So a sinusoid `A cos(2 pi f t + phi)` whose frequency sits exactly on bin
//! `k` (`f = k fs / N`) gives `|X_k| = A` and `arg X_k = phi`, where `t = 0`
//! is the **first sample of the analysed window** (not the trace's
//! `start_time_s`). Bin `k` is at `k fs / N` Hz. Phases follow `cos`:
//! a signal that leads by `phi` has `arg X` larger by `phi`.
//!
//! With this scaling the mean product of two real signals over the window is
//! `X_0 Y_0 + sum_{0<k<N/2} Re(X_k conj(Y_k)) / 2` (+ `X_{N/2} Y_{N/2}` for
//! even `N`), which is why thesis eq. 7.9 carries the factor 1/2.
//!
//! [`SpectrumPlan`] plans the real FFT once for a given `N` and keeps the
//! input copy and scratch buffers, so repeated spectra of the same length do
//! not allocate.

use std::sync::Arc;

use realfft::num_complex::Complex64;
use realfft::{RealFftPlanner, RealToComplex};

use super::error::{Result, SignalsError};

/// A planned one-sided amplitude spectrum for records of one length.
pub struct SpectrumPlan {
    fft: Arc<dyn RealToComplex<f64>>,
    input: Vec<f64>,
    scratch: Vec<Complex64>,
}

impl std::fmt::Debug for SpectrumPlan {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SpectrumPlan")
            .field("n_samples", &self.input.len())
            .finish()
    }
}

impl SpectrumPlan {
    /// Plans spectra of `n_samples` real samples (at least 2).
    pub fn new(n_samples: usize) -> Result<Self> {
        if n_samples < 2 {
            return Err(SignalsError::TooFewSamples {
                what: "a spectrum".into(),
                need: 2,
                got: n_samples,
            });
        }
        let fft = RealFftPlanner::<f64>::new().plan_fft_forward(n_samples);
        let input = fft.make_input_vec();
        let scratch = fft.make_scratch_vec();
        Ok(Self {
            fft,
            input,
            scratch,
        })
    }

    /// Number of real samples this plan transforms.
    pub fn n_samples(&self) -> usize {
        self.input.len()
    }

    /// Number of one-sided bins, `N/2 + 1`.
    pub fn n_bins(&self) -> usize {
        self.input.len() / 2 + 1
    }

    /// A zeroed output buffer of the right length for [`Self::process_into`].
    pub fn make_output(&self) -> Vec<Complex64> {
        vec![Complex64::new(0.0, 0.0); self.n_bins()]
    }

    /// Writes the one-sided amplitude spectrum of `samples` into `out`
    /// (length [`Self::n_bins`]). `samples` must have [`Self::n_samples`]
    /// entries; it is not modified.
    pub fn process_into(&mut self, samples: &[f64], out: &mut [Complex64]) -> Result<()> {
        let n = self.input.len();
        if samples.len() != n {
            return Err(SignalsError::LengthMismatch {
                first: "the spectrum plan".into(),
                first_len: n,
                second: "the record".into(),
                second_len: samples.len(),
            });
        }
        if out.len() != self.n_bins() {
            return Err(SignalsError::LengthMismatch {
                first: "one-sided bins of the plan".into(),
                first_len: self.n_bins(),
                second: "the output buffer".into(),
                second_len: out.len(),
            });
        }
        self.input.copy_from_slice(samples);
        self.fft
            .process_with_scratch(&mut self.input, out, &mut self.scratch)
            .map_err(|e| SignalsError::TooFewSamples {
                // Unreachable with the lengths checked above; keep a typed error anyway.
                what: format!("the FFT ({e})"),
                need: n,
                got: samples.len(),
            })?;
        normalise_one_sided(out, n);
        Ok(())
    }

    /// The one-sided amplitude spectrum of `samples`, freshly allocated.
    pub fn process(&mut self, samples: &[f64]) -> Result<Vec<Complex64>> {
        let mut out = self.make_output();
        self.process_into(samples, &mut out)?;
        Ok(out)
    }
}

/// Scales raw DFT bins `0 ..= N/2` to amplitudes (see the module docs).
fn normalise_one_sided(bins: &mut [Complex64], n: usize) {
    let n_f = n as f64;
    let last = bins.len() - 1;
    for (k, x) in bins.iter_mut().enumerate() {
        let is_nyquist = n % 2 == 0 && k == last;
        let scale = if k == 0 || is_nyquist {
            1.0 / n_f
        } else {
            2.0 / n_f
        };
        *x *= scale;
    }
}

/// One-sided amplitude spectrum of `samples` (plans a fresh FFT; use
/// [`SpectrumPlan`] for repeated work).
pub fn amplitude_spectrum(samples: &[f64]) -> Result<Vec<Complex64>> {
    SpectrumPlan::new(samples.len())?.process(samples)
}

/// Frequency of bin `k` of an `n_samples` spectrum at `sample_rate_hz`, in Hz.
pub fn bin_freq_hz(k: usize, n_samples: usize, sample_rate_hz: f64) -> f64 {
    k as f64 * sample_rate_hz / n_samples as f64
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    fn cosine(n: usize, bin: usize, amp: f64, phase: f64) -> Vec<f64> {
        (0..n)
            .map(|i| amp * (2.0 * PI * bin as f64 * i as f64 / n as f64 + phase).cos())
            .collect()
    }

    /// Naive O(N^2) DFT with the same scaling, as an oracle.
    fn naive(x: &[f64]) -> Vec<Complex64> {
        let n = x.len();
        let mut out: Vec<Complex64> = (0..=n / 2)
            .map(|k| {
                x.iter()
                    .enumerate()
                    .fold(Complex64::new(0.0, 0.0), |acc, (i, &v)| {
                        acc + Complex64::from_polar(v, -2.0 * PI * (k * i) as f64 / n as f64)
                    })
            })
            .collect();
        normalise_one_sided(&mut out, n);
        out
    }

    #[test]
    fn cosine_on_a_bin_gives_its_amplitude_and_phase() {
        // Tolerance 1e-12 (absolute on amplitude ~2.5, radians on phase).
        for &(n, bin, amp, phase) in &[
            (1024usize, 7usize, 2.5, 0.3),
            (1000, 40, 1.0, -2.0),
            (999, 13, 0.7, 1.2),
        ] {
            let x = cosine(n, bin, amp, phase);
            let s = amplitude_spectrum(&x).expect("spectrum");
            assert!(
                (s[bin].norm() - amp).abs() < 1e-12,
                "n={n} |X|={}",
                s[bin].norm()
            );
            assert!(
                (s[bin].arg() - phase).abs() < 1e-12,
                "n={n} arg={}",
                s[bin].arg()
            );
            let leak: f64 = s
                .iter()
                .enumerate()
                .filter(|&(k, _)| k != bin)
                .map(|(_, c)| c.norm())
                .fold(0.0, f64::max);
            assert!(leak < 1e-12, "n={n} leakage {leak}");
        }
    }

    #[test]
    fn dc_and_nyquist_are_not_doubled() {
        // x = 1.5 + 0.25 (-1)^i: X_0 = 1.5, X_{N/2} = 0.25 (1e-14).
        let x: Vec<f64> = (0..16)
            .map(|i| 1.5 + if i % 2 == 0 { 0.25 } else { -0.25 })
            .collect();
        let s = amplitude_spectrum(&x).expect("spectrum");
        assert!((s[0].re - 1.5).abs() < 1e-14);
        assert!((s[8].re - 0.25).abs() < 1e-14);
    }

    #[test]
    fn matches_a_naive_dft_for_odd_and_even_lengths() {
        // Deterministic pseudo-random input; agreement to 1e-12 absolute.
        for n in [2usize, 3, 17, 64, 100] {
            let x: Vec<f64> = (0..n)
                .map(|i| ((i * 7919 % 101) as f64 - 50.0) / 13.0)
                .collect();
            let fast = amplitude_spectrum(&x).expect("spectrum");
            let slow = naive(&x);
            for (a, b) in fast.iter().zip(&slow) {
                assert!((a - b).norm() < 1e-12, "n={n}: {a} vs {b}");
            }
        }
    }

    #[test]
    fn plan_is_reusable_and_checks_lengths() {
        let mut plan = SpectrumPlan::new(64).expect("plan");
        let a = plan.process(&cosine(64, 3, 1.0, 0.0)).expect("first");
        let b = plan.process(&cosine(64, 5, 2.0, 0.0)).expect("second");
        assert!((a[3].norm() - 1.0).abs() < 1e-12 && b[3].norm() < 1e-12);
        assert!((b[5].norm() - 2.0).abs() < 1e-12);
        assert!(plan.process(&[0.0; 63]).is_err());
        assert!(SpectrumPlan::new(1).is_err());
        assert_eq!(bin_freq_hz(3, 64, 6400.0), 300.0);
    }
}
