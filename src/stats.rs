//! How far to trust a mean of per-cycle figures: the standard error from the
//! cycle-to-cycle spread.
//!
//! A granular bed is chaotic: its dissipation per drive cycle scatters, and
//! successive cycles are correlated (a bed that hit the lid hard comes back
//! differently). The standard error of the mean of `n` cycles is therefore the
//! sample standard deviation over `√n`, inflated for the correlation of
//! neighbouring cycles as for a first-order autoregressive series:
//! `s / √n · √((1 + ρ₁) / (1 − ρ₁))`, with the lag-1 autocorrelation `ρ₁`
//! estimated from the series (from 4 cycles on; clamped to [0, 0.9], since
//! negative correlation only shrinks the error and a larger one cannot be
//! estimated from few cycles). No thesis equation: the thesis reports means
//! over its 5 steady cycles without an error.
//!
//! Also the plain mean and sample standard deviation ([`mean_std`]) of
//! figures that are not a series (restitution over drop-test triples).

use serde::Serialize;

/// A mean with its standard error.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct MeanStderr {
    /// The mean.
    pub mean: f64,
    /// Its standard error (same unit); zero for fewer than 2 values.
    pub stderr: f64,
    /// How many values.
    pub n: usize,
    /// Lag-1 autocorrelation used for the correction (0 below 4 values).
    pub lag1: f64,
}

impl MeanStderr {
    /// Standard error relative to the mean's magnitude (infinite for a zero
    /// mean with a spread, zero for no spread).
    pub fn relative(&self) -> f64 {
        if self.stderr == 0.0 {
            0.0
        } else {
            self.stderr / self.mean.abs()
        }
    }

    /// The same figure scaled by `k` (a unit change, a normalisation).
    pub fn scaled(&self, k: f64) -> MeanStderr {
        MeanStderr {
            mean: self.mean * k,
            stderr: self.stderr * k.abs(),
            ..*self
        }
    }
}

/// A mean with the sample standard deviation of the values.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct MeanStd {
    /// The mean (NaN of no values).
    pub mean: f64,
    /// The sample standard deviation (`n - 1` in the denominator); zero for
    /// fewer than 2 values.
    pub std: f64,
}

/// Mean and sample standard deviation of `xs`.
pub fn mean_std(xs: &[f64]) -> MeanStd {
    let n = xs.len() as f64;
    let mean = xs.iter().sum::<f64>() / n;
    let std = if xs.len() > 1 {
        sample_variance(xs, mean).sqrt()
    } else {
        0.0
    };
    MeanStd { mean, std }
}

/// `sum (x - mean)^2 / (n - 1)` (at least 2 values).
fn sample_variance(xs: &[f64], mean: f64) -> f64 {
    xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (xs.len() - 1) as f64
}

/// Mean and standard error of `xs` (see the module documentation).
pub fn mean_stderr(xs: &[f64]) -> MeanStderr {
    let n = xs.len();
    if n == 0 {
        return MeanStderr::default();
    }
    let mean = xs.iter().sum::<f64>() / n as f64;
    if n < 2 {
        return MeanStderr {
            mean,
            stderr: 0.0,
            n,
            lag1: 0.0,
        };
    }
    let var = sample_variance(xs, mean);
    let lag1 = if n >= 4 && var > 0.0 {
        let c1 = xs
            .windows(2)
            .map(|w| (w[0] - mean) * (w[1] - mean))
            .sum::<f64>()
            / (n - 1) as f64;
        (c1 / var).clamp(0.0, 0.9)
    } else {
        0.0
    };
    MeanStderr {
        mean,
        stderr: (var / n as f64).sqrt() * ((1.0 + lag1) / (1.0 - lag1)).sqrt(),
        n,
        lag1,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn independent_values_give_s_over_root_n() {
        // Alternating values: no positive correlation, s = 1.0328, n = 6.
        let xs = [1.0, 3.0, 1.0, 3.0, 1.0, 3.0];
        let m = mean_stderr(&xs);
        assert_eq!(m.mean, 2.0);
        assert_eq!(m.lag1, 0.0);
        let s = (6.0f64 / 5.0).sqrt();
        assert!((m.stderr - s / 6f64.sqrt()).abs() < 1e-12, "{m:?}");
        assert_eq!(mean_stderr(&[5.0]).stderr, 0.0);
        assert_eq!(mean_stderr(&[]).n, 0);
    }

    #[test]
    fn correlated_values_widen_the_error() {
        // A slow drift is strongly correlated from cycle to cycle.
        let xs: Vec<f64> = (0..20).map(|k| (k as f64 / 6.0).sin()).collect();
        let m = mean_stderr(&xs);
        assert!(m.lag1 > 0.5, "{m:?}");
        let naive = {
            let var = xs.iter().map(|x| (x - m.mean).powi(2)).sum::<f64>() / (xs.len() - 1) as f64;
            (var / xs.len() as f64).sqrt()
        };
        assert!(m.stderr > 1.5 * naive, "{} vs {naive}", m.stderr);
    }

    /// With a fixed seed, white noise of unit variance: the standard error of
    /// 400 values is within 20 % of 1/20 over many draws.
    #[test]
    fn white_noise_error_is_calibrated() {
        let mut state = 12345u64;
        let mut uniform = || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        // Sum of 12 uniforms - 6: near-normal, unit variance.
        let xs: Vec<f64> = (0..400)
            .map(|_| (0..12).map(|_| uniform()).sum::<f64>() - 6.0)
            .collect();
        let m = mean_stderr(&xs);
        assert!((m.stderr / 0.05 - 1.0).abs() < 0.2, "{m:?}");
    }
}
