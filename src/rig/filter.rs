//! The signal conditioner's analogue filters, discretised for the DEM step.
//!
//! Two filter types, both of textbook form:
//!
//! - AC coupling: a first-order high-pass `H(s) = s / (s + w_c)`, corner
//!   `f_c = w_c / 2 pi`; phase lead `atan(f_c / f)`;
//! - anti-alias: a Butterworth low-pass of order `n`, `|H(jw)|^2 = 1 / (1 + (w/w_c)^(2n))`,
//!   realised as cascaded sections with the Butterworth pole pairs
//!   `Q_k = 1 / (2 cos theta_k)` (plus one first-order section for odd `n`).
//!
//! Each analogue section is discretised by the plain bilinear (Tustin)
//! transform `s = (2 / T) (1 - z^-1) / (1 + z^-1)`, without pre-warping: the
//! digital response at `f` equals the analogue response at
//! `tan(pi f T) / (pi T)`, i.e. at the drive frequencies (T = 1-5 us) the
//! frequency is off by `(w T)^2 / 12 < 1e-6` relative, and the digital filters
//! reproduce the analogue in-band responses ([`high_pass_response`],
//! [`butterworth_response`]) that [`crate::rig::RigSpec::expected_phase_error_rad`]
//! uses. (Pre-warping the corner instead would scale every in-band frequency
//! by `(w_c T)^2 / 12`, 3e-4 for a 10 kHz corner at 1 us; the price of not
//! doing so is a corner that lands that much low, 9.997 kHz for 10 kHz.)
//!
//! Sections run in transposed direct form II in f64, which stays accurate with
//! poles within 1e-6 of z = 1 (a 0.2 Hz corner at 1 MHz). A filter can be
//! started in the steady state of a constant input ([`Biquad::settle_dc`]), as a
//! conditioner that has been on for hours would be.

use std::f64::consts::PI;

use crate::maths;
use realfft::num_complex::Complex64;

/// Highest supported low-pass order.
pub const MAX_LOW_PASS_ORDER: u32 = 8;

/// One second-order (or, with `b2 = a2 = 0`, first-order) digital section,
/// `H(z) = (b0 + b1 z^-1 + b2 z^-2) / (1 + a1 z^-1 + a2 z^-2)`.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Biquad {
    b0: f64,
    b1: f64,
    b2: f64,
    a1: f64,
    a2: f64,
    s1: f64,
    s2: f64,
}

impl Biquad {
    /// Passes `x` straight through.
    pub fn identity() -> Self {
        Biquad {
            b0: 1.0,
            ..Default::default()
        }
    }

    /// Tustin first-order high-pass with corner `corner_hz`, step `dt_s`.
    pub fn high_pass_1(corner_hz: f64, dt_s: f64) -> Self {
        let k = 2.0 / dt_s;
        let wa = analogue_corner(corner_hz);
        let b0 = k / (k + wa);
        Biquad {
            b0,
            b1: -b0,
            a1: (wa - k) / (k + wa),
            ..Default::default()
        }
    }

    /// Tustin first-order low-pass with corner `corner_hz`, step `dt_s`.
    pub fn low_pass_1(corner_hz: f64, dt_s: f64) -> Self {
        let k = 2.0 / dt_s;
        let wa = analogue_corner(corner_hz);
        let b0 = wa / (k + wa);
        Biquad {
            b0,
            b1: b0,
            a1: (wa - k) / (k + wa),
            ..Default::default()
        }
    }

    /// Tustin second-order low-pass `w^2 / (s^2 + (w/Q) s + w^2)`.
    pub fn low_pass_2(corner_hz: f64, q: f64, dt_s: f64) -> Self {
        let k = 2.0 / dt_s;
        let w = analogue_corner(corner_hz);
        let (kk, ww, kw) = (k * k, w * w, k * w / q);
        let a0 = kk + kw + ww;
        Biquad {
            b0: ww / a0,
            b1: 2.0 * ww / a0,
            b2: ww / a0,
            a1: (2.0 * ww - 2.0 * kk) / a0,
            a2: (kk - kw + ww) / a0,
            ..Default::default()
        }
    }

    /// One step: input `x`, returns the output.
    #[inline]
    pub fn process(&mut self, x: f64) -> f64 {
        let y = self.b0 * x + self.s1;
        self.s1 = self.b1 * x - self.a1 * y + self.s2;
        self.s2 = self.b2 * x - self.a2 * y;
        y
    }

    /// Sets the state to the steady state of the constant input `x` (as if
    /// `x` had been applied forever) and returns the steady output.
    pub fn settle_dc(&mut self, x: f64) -> f64 {
        let gain = (self.b0 + self.b1 + self.b2) / (1.0 + self.a1 + self.a2);
        let y = gain * x;
        self.s2 = self.b2 * x - self.a2 * y;
        self.s1 = y - self.b0 * x;
        y
    }

    /// Frequency response at `freq_hz` for step `dt_s`.
    pub fn response(&self, freq_hz: f64, dt_s: f64) -> Complex64 {
        let z1 = Complex64::from_polar(1.0, -2.0 * PI * freq_hz * dt_s);
        let z2 = z1 * z1;
        (self.b0 + z1 * self.b1 + z2 * self.b2) / (1.0 + z1 * self.a1 + z2 * self.a2)
    }
}

/// Analogue corner, rad/s (no pre-warping; see the module docs).
fn analogue_corner(corner_hz: f64) -> f64 {
    2.0 * PI * corner_hz
}

/// Quality factors of the Butterworth pole pairs of order `order`, and
/// whether a first-order section is needed (odd order).
pub fn butterworth_sections(order: u32) -> (Vec<f64>, bool) {
    let n = f64::from(order);
    let pairs = order / 2;
    let odd = order % 2 == 1;
    let qs = (1..=pairs)
        .map(|k| {
            let k = f64::from(k);
            let theta = if odd {
                k * PI / n
            } else {
                (2.0 * k - 1.0) * PI / (2.0 * n)
            };
            1.0 / (2.0 * maths::cos(theta))
        })
        .collect();
    (qs, odd)
}

/// Analogue first-order high-pass response `jw / (jw + w_c)` at `freq_hz`;
/// 1 for `corner_hz = 0` (DC-coupled).
pub fn high_pass_response(corner_hz: f64, freq_hz: f64) -> Complex64 {
    if corner_hz == 0.0 {
        return Complex64::new(1.0, 0.0);
    }
    let jw = Complex64::new(0.0, freq_hz);
    jw / (jw + corner_hz)
}

/// Analogue Butterworth low-pass response of `order` and `cutoff_hz` at `freq_hz`.
pub fn butterworth_response(order: u32, cutoff_hz: f64, freq_hz: f64) -> Complex64 {
    let (qs, odd) = butterworth_sections(order);
    let s = Complex64::new(0.0, freq_hz / cutoff_hz);
    let mut h = Complex64::new(1.0, 0.0);
    for q in qs {
        h /= s * s + s / q + 1.0;
    }
    if odd {
        h /= s + 1.0;
    }
    h
}

/// A cascade of at most `MAX_LOW_PASS_ORDER / 2 + 1` sections, stored inline so
/// that running it never allocates.
#[derive(Debug, Clone, Copy)]
pub struct Cascade {
    sections: [Biquad; 6],
    len: usize,
}

impl Cascade {
    /// An empty cascade (passes its input through).
    pub fn new() -> Self {
        Cascade {
            sections: [Biquad::identity(); 6],
            len: 0,
        }
    }

    /// Appends a section; a cascade holds at most 6 (a high-pass and an
    /// eighth-order low-pass take 5). Returns false when full.
    pub fn push(&mut self, section: Biquad) -> bool {
        if self.len == self.sections.len() {
            return false;
        }
        self.sections[self.len] = section;
        self.len += 1;
        true
    }

    /// Appends a Butterworth low-pass of `order` and `cutoff_hz` for step `dt_s`.
    pub fn push_butterworth(&mut self, order: u32, cutoff_hz: f64, dt_s: f64) -> bool {
        let (qs, odd) = butterworth_sections(order);
        let mut ok = true;
        for q in qs {
            ok &= self.push(Biquad::low_pass_2(cutoff_hz, q, dt_s));
        }
        if odd {
            ok &= self.push(Biquad::low_pass_1(cutoff_hz, dt_s));
        }
        ok
    }

    /// Number of sections.
    pub fn len(&self) -> usize {
        self.len
    }

    /// True when the cascade has no sections.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// One step through every section.
    #[inline]
    pub fn process(&mut self, x: f64) -> f64 {
        self.sections[..self.len]
            .iter_mut()
            .fold(x, |acc, s| s.process(acc))
    }

    /// Steady state for a constant input `x`; returns the steady output.
    pub fn settle_dc(&mut self, x: f64) -> f64 {
        self.sections[..self.len]
            .iter_mut()
            .fold(x, |acc, s| s.settle_dc(acc))
    }

    /// Digital frequency response at `freq_hz` for step `dt_s`.
    pub fn response(&self, freq_hz: f64, dt_s: f64) -> Complex64 {
        self.sections[..self.len]
            .iter()
            .map(|s| s.response(freq_hz, dt_s))
            .product()
    }
}

impl Default for Cascade {
    fn default() -> Self {
        Self::new()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const DT: f64 = 1e-6;

    #[test]
    fn butterworth_magnitude_is_maximally_flat() {
        for order in 1..=MAX_LOW_PASS_ORDER {
            let h = butterworth_response(order, 1000.0, 1000.0);
            assert!((h.norm() - 0.5f64.sqrt()).abs() < 1e-12, "order {order}");
            let h2 = butterworth_response(order, 1000.0, 2000.0);
            let want = 1.0 / (1.0 + 2f64.powi(2 * order as i32)).sqrt();
            assert!((h2.norm() - want).abs() < 1e-12, "order {order}");
        }
    }

    #[test]
    fn digital_sections_match_the_analogue_responses() {
        // Tustin with pre-warping: exact at the corner, warping (wT)^2/12 elsewhere.
        let mut c = Cascade::new();
        assert!(c.push(Biquad::high_pass_1(0.3, DT)));
        assert!(c.push_butterworth(4, 10_000.0, DT));
        for f in [20.0, 40.0, 160.0, 1000.0] {
            let want = high_pass_response(0.3, f) * butterworth_response(4, 10_000.0, f);
            let got = c.response(f, DT);
            assert!((got - want).norm() < 1e-6, "{f} Hz: {got} vs {want}");
        }
        // The corner lands (w_c T)^2 / 12 low: |H| at 10 kHz is a little below 1/sqrt(2).
        let at_corner = c.response(10_000.0, DT).norm();
        assert!((at_corner - 0.5f64.sqrt()).abs() < 1e-3, "{at_corner}");
    }

    #[test]
    fn settle_dc_holds_a_constant_input() {
        let mut c = Cascade::new();
        c.push(Biquad::high_pass_1(0.3, DT));
        c.push_butterworth(3, 5_000.0, DT);
        assert_eq!(c.settle_dc(2.5), 0.0);
        for _ in 0..1000 {
            assert!(c.process(2.5).abs() < 1e-12);
        }
        let mut lp = Cascade::new();
        lp.push_butterworth(4, 5_000.0, DT);
        assert!((lp.settle_dc(2.5) - 2.5).abs() < 1e-12);
        assert!((lp.process(2.5) - 2.5).abs() < 1e-12);
    }
}
