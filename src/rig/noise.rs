//! Seeded white Gaussian noise for the measurement channels.
//!
//! xoshiro256++ (`rand_xoshiro`), seeded with `seed_from_u64`, gives the same
//! bits on every platform; uniforms are `(next_u64 >> 11) / 2^53` and normal
//! deviates come in pairs by the Box-Muller transform. Each channel draws from
//! its own stream: the rig seed for the first, the same seed advanced by
//! 2^128 steps (`jump`) per further channel, so channels never overlap.

use std::f64::consts::PI;

use crate::maths;
use rand_core::{Rng, SeedableRng};
use rand_xoshiro::Xoshiro256PlusPlus;

/// A deterministic standard-normal source.
#[derive(Debug, Clone)]
pub struct GaussianNoise {
    rng: Xoshiro256PlusPlus,
    spare: Option<f64>,
}

impl GaussianNoise {
    /// Stream `stream` (0, 1, ...) of seed `seed`.
    pub fn new(seed: u64, stream: u32) -> Self {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(seed);
        for _ in 0..stream {
            rng.jump();
        }
        GaussianNoise { rng, spare: None }
    }

    /// Uniform in [0, 1).
    fn uniform(&mut self) -> f64 {
        (self.rng.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    /// One standard normal deviate.
    pub fn next_gaussian(&mut self) -> f64 {
        if let Some(z) = self.spare.take() {
            return z;
        }
        // u1 in (0, 1] so that ln(u1) is finite.
        let u1 = 1.0 - self.uniform();
        let u2 = self.uniform();
        let r = (-2.0 * maths::ln(u1)).sqrt();
        let (s, c) = maths::sin_cos(2.0 * PI * u2);
        self.spare = Some(r * s);
        r * c
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn deterministic_standard_normal_and_independent_streams() {
        let mut a = GaussianNoise::new(7, 0);
        let mut b = GaussianNoise::new(7, 0);
        let mut c = GaussianNoise::new(7, 1);
        let n = 200_000;
        let (mut sum, mut sum2, mut cross) = (0.0, 0.0, 0.0);
        for _ in 0..n {
            let x = a.next_gaussian();
            assert_eq!(x.to_bits(), b.next_gaussian().to_bits());
            let y = c.next_gaussian();
            sum += x;
            sum2 += x * x;
            cross += x * y;
        }
        let n = n as f64;
        // Standard errors: mean 1/sqrt(n) = 0.0022, variance sqrt(2/n) = 0.0032.
        assert!((sum / n).abs() < 0.01, "mean {}", sum / n);
        assert!((sum2 / n - 1.0).abs() < 0.015, "variance {}", sum2 / n);
        assert!((cross / n).abs() < 0.01, "streams correlate: {}", cross / n);
    }
}
