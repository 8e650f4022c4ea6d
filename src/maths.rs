//! Transcendental functions with the same bits on every platform.
//!
//! `f64::sin`, `powf`, `exp`, `ln` and their kin call the platform's maths
//! library (glibc on Linux, the system's on macOS and Windows, a port of
//! musl's in WebAssembly), and those differ in the last bit for some
//! arguments. A granular bed is chaotic: one such bit in the pour's time step
//! (a `powf` in the Hertz collision time) or in the drive's `sin_cos` becomes
//! another packing within a few thousand steps, so the browser and the command
//! line gave 0.832 and 0.839 for the same scene and seed. Every call that
//! reaches a DEM state (the pour, the contact laws and their calibration, the
//! shapes' sub-spheres, the drive and the shaker's motion) goes through here
//! instead: the `libm` crate, a pure-Rust port of musl's maths library,
//! computes the same bits wherever it is compiled. (`sqrt` and `mul_add` are
//! correctly rounded by IEEE 754 everywhere and need no such care; glam's own
//! trigonometry takes `libm` through its feature of that name.)

/// `sin x`.
#[inline]
pub fn sin(x: f64) -> f64 {
    libm::sin(x)
}

/// `cos x`.
#[inline]
pub fn cos(x: f64) -> f64 {
    libm::cos(x)
}

/// `(sin x, cos x)`.
#[inline]
pub fn sin_cos(x: f64) -> (f64, f64) {
    libm::sincos(x)
}

/// `e^x`.
#[inline]
pub fn exp(x: f64) -> f64 {
    libm::exp(x)
}

/// The natural logarithm of `x`.
#[inline]
pub fn ln(x: f64) -> f64 {
    libm::log(x)
}

/// `x^y`.
#[inline]
pub fn powf(x: f64, y: f64) -> f64 {
    libm::pow(x, y)
}

/// The cube root of `x`.
#[inline]
pub fn cbrt(x: f64) -> f64 {
    libm::cbrt(x)
}

/// The angle of `(x, y)` from the x axis, in `(-π, π]`.
#[inline]
pub fn atan2(y: f64, x: f64) -> f64 {
    libm::atan2(y, x)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The functions are the ones named (a swapped argument or a wrong
    /// function fails here), and they are musl's, not the platform's: for
    /// these arguments (found by comparing two million random ones)
    /// Debian 12's glibc on x86-64 rounds the other way in the last bit
    /// (`powf` gives 0.17169672530615718, `sin` 0.9853793197223584), so
    /// these functions turned back into `f64::powf` or `f64::sin` fail here
    /// on Linux. (A call site that bypasses this module is caught by the
    /// browser lab's test instead: its state hash would part from the CLI's.)
    #[test]
    fn each_is_its_function_and_keeps_musls_bits() {
        let x = 0.7310585786300049_f64;
        assert!((sin(x) - x.sin()).abs() < 1e-15);
        assert!((cos(x) - x.cos()).abs() < 1e-15);
        assert_eq!(sin_cos(x), (sin(x), cos(x)));
        assert!((exp(x) - x.exp()).abs() < 1e-15);
        assert!((ln(x) - x.ln()).abs() < 1e-15);
        assert!((powf(x, 0.4) - x.powf(0.4)).abs() < 1e-15);
        assert!((cbrt(27.0) - 3.0).abs() < 1e-15);
        assert!((atan2(1.0, 0.0) - std::f64::consts::FRAC_PI_2).abs() < 1e-15);
        assert!(atan2(-1e-300, -1.0) < 0.0);
        assert_eq!(
            powf(7.372376617515272, -0.8820094067558939),
            0.17169672530615715
        );
        assert_eq!(sin(598.3021904202419), 0.9853793197223585);
        assert_eq!(sin_cos(598.3021904202419).0, 0.9853793197223585);
    }
}
