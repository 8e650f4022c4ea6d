//! Shared helpers for the `signals` unit tests (seeded noise).

use rand_core::{Rng, SeedableRng};
use rand_xoshiro::Xoshiro256PlusPlus;

/// A seeded, portable generator.
pub(crate) fn rng(seed: u64) -> Xoshiro256PlusPlus {
    Xoshiro256PlusPlus::seed_from_u64(seed)
}

/// One standard normal deviate by Box-Muller (u1 in (0, 1] so ln is finite).
pub(crate) fn gaussian(rng: &mut Xoshiro256PlusPlus) -> f64 {
    let scale = 1.0 / (1u64 << 53) as f64;
    let u1 = ((rng.next_u64() >> 11) as f64 + 1.0) * scale;
    let u2 = (rng.next_u64() >> 11) as f64 * scale;
    (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
}
