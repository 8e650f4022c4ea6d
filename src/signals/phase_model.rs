//! The measurement chain's phase error across frequency: the force channel's
//! phase minus the acceleration channel's, as the rig's own high-pass filters
//! and inter-channel skew make it. This is the `phi_err(f_k)` that Yang's sum
//! (Terzioglu 2023, eq. 7.12) must subtract in every bin, not only at the
//! drive frequency where the empty enclosure calibrates it (Fig. 7.9).
//!
//! A conditioner's AC coupling is a first-order high-pass `jw / (jw + w_c)`,
//! whose phase lead is `atan(f_c / f)`; a sampling skew `tau` (the force
//! sampled `tau` after the acceleration) leads by `2 pi f tau`. So
//!
//! `phi_err(f) = atan(f_cF / f) - atan(f_cA / f) + 2 pi f tau`,   (M1)
//!
//! the form of [`crate::rig::RigSpec::expected_phase_error_rad`] for a rig
//! whose anti-alias low-passes are alike on both channels (they cancel). At
//! the drive's harmonics the high-pass part falls as `1/k` while the skew grows
//! as `k`: a pure delay extrapolated from the fundamental, `k phi_err(f)`,
//! overstates the error at every harmonic by `(k - 1/k) (atan(f_cF/f) -
//! atan(f_cA/f))`.
//!
//! [`PhaseErrorModel::fit`] finds the model from an empty-enclosure table at
//! two or more frequencies by linear least squares in the first-order form
//! `phi_err(f) = c / f + 2 pi f tau` (M2), `c = f_cF - f_cA`; (M2) differs
//! from (M1) by `(f_cF^3 - f_cA^3) / (3 f^3)`, below 2e-6 rad for sub-hertz
//! corners above 10 Hz. Only the difference of the corners is observable; a
//! fitted model puts it on one channel (the force channel when it leads).
//!
//! [`wrap_phase_rad`], the wrap of every phase difference to (-pi, pi], lives
//! here, below both Yang's power (`power.rs`) and the calibration table
//! (`calibration.rs`), which import it.

use std::f64::consts::PI;

use glam::{DMat2, DVec2};
use serde::{Deserialize, Serialize};

use super::error::{Result, SignalsError};
use crate::validation::{InvalidParameter, finite, non_negative, positive};

/// Relative determinant below which a fit's two frequencies count as one.
const FIT_MIN_SPREAD: f64 = 1e-9;

/// The chain's phase error (M1): high-pass corners of both channels and the
/// force channel's skew relative to the acceleration channel's.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PhaseErrorModel {
    /// Force channel's AC-coupling corner, Hz (0: DC-coupled).
    pub force_high_pass_hz: f64,
    /// Acceleration channel's AC-coupling corner, Hz (0: DC-coupled).
    pub accel_high_pass_hz: f64,
    /// Force sample instant minus acceleration sample instant, s (positive:
    /// the force is sampled late, so it leads).
    pub skew_s: f64,
}

impl PhaseErrorModel {
    /// `phi_err(freq_hz)` of (M1), in rad; 0 at and below 0 Hz.
    pub fn phase_error_at(&self, freq_hz: f64) -> f64 {
        if !(freq_hz > 0.0 && freq_hz.is_finite()) {
            return 0.0;
        }
        high_pass_lead_rad(self.force_high_pass_hz, freq_hz)
            - high_pass_lead_rad(self.accel_high_pass_hz, freq_hz)
            + skew_lead_rad(self.skew_s, freq_hz)
    }

    /// Checks that corners are finite and non-negative and the skew finite;
    /// a refusal names the field.
    pub fn validate(&self) -> std::result::Result<(), InvalidParameter> {
        non_negative("force_high_pass_hz", self.force_high_pass_hz, "Hz")?;
        non_negative("accel_high_pass_hz", self.accel_high_pass_hz, "Hz")?;
        finite("skew_s", self.skew_s, "s")?;
        Ok(())
    }

    /// Least-squares fit of (M2) to `(freq_hz, phase_error_rad)` points at
    /// two or more distinct positive frequencies (see the module docs).
    pub fn fit(points: &[(f64, f64)]) -> Result<Self> {
        let bad = |reason: String| SignalsError::InvalidCalibration { reason };
        for (i, &(f, phi)) in points.iter().enumerate() {
            positive(&format!("points[{i}].freq_hz"), f, "Hz")?;
            finite(&format!("points[{i}].phase_error_rad"), phi, "rad")?;
        }
        // Normal equations of phi = c x + tau y, x = 1/f, y = 2 pi f.
        let (mut sxx, mut sxy, mut syy, mut sxp, mut syp) = (0.0, 0.0, 0.0, 0.0, 0.0);
        for &(f, phi) in points {
            let (x, y) = (1.0 / f, 2.0 * PI * f);
            sxx += x * x;
            sxy += x * y;
            syy += y * y;
            sxp += x * phi;
            syp += y * phi;
        }
        let normal = DMat2::from_cols(DVec2::new(sxx, sxy), DVec2::new(sxy, syy));
        if points.len() < 2 || normal.determinant() <= FIT_MIN_SPREAD * sxx * syy {
            return Err(bad(format!(
                "phase-error fit: needs at least two distinct frequencies, got {}",
                points.len()
            )));
        }
        let DVec2 { x: c_hz, y: skew_s } = normal.inverse() * DVec2::new(sxp, syp);
        Ok(Self {
            force_high_pass_hz: c_hz.max(0.0),
            accel_high_pass_hz: (-c_hz).max(0.0),
            skew_s,
        })
    }
}

/// Phase lead of a first-order high-pass of corner `corner_hz` at `freq_hz`
/// (`freq_hz > 0`), `atan(f_c / f)`, rad.
pub fn high_pass_lead_rad(corner_hz: f64, freq_hz: f64) -> f64 {
    (corner_hz / freq_hz).atan()
}

/// Phase lead of a channel sampled `skew_s` late, `2 pi f tau`, rad.
pub fn skew_lead_rad(skew_s: f64, freq_hz: f64) -> f64 {
    2.0 * PI * freq_hz * skew_s
}

/// Wraps an angle to (-pi, pi].
pub fn wrap_phase_rad(phi: f64) -> f64 {
    let wrapped = phi - 2.0 * PI * ((phi + PI) / (2.0 * PI)).floor();
    // floor puts -pi at -pi; move it to +pi so the range is (-pi, pi].
    if wrapped <= -PI {
        wrapped + 2.0 * PI
    } else {
        wrapped
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const THESIS: PhaseErrorModel = PhaseErrorModel {
        force_high_pass_hz: 0.35,
        accel_high_pass_hz: 0.20,
        skew_s: 5e-6,
    };

    #[test]
    fn high_pass_falls_and_skew_grows_across_harmonics() {
        // At 40 Hz: atan(0.35/40) - atan(0.2/40) + 2 pi 40 5e-6 (tol 1e-15).
        let at_40 = (0.35f64 / 40.0).atan() - (0.2f64 / 40.0).atan() + 2.0 * PI * 40.0 * 5e-6;
        assert!((THESIS.phase_error_at(40.0) - at_40).abs() < 1e-15);
        // The 10th harmonic is far from 10 x the fundamental's error: the
        // high-pass part shrank tenfold, the skew part grew tenfold.
        let at_400 = THESIS.phase_error_at(400.0);
        let hp = (0.35f64 / 40.0).atan() - (0.2f64 / 40.0).atan();
        assert!((at_400 - (hp / 10.0 + 10.0 * 2.0 * PI * 40.0 * 5e-6)).abs() < 1e-7);
        assert!(10.0 * at_40 - at_400 > 0.03, "{at_400} vs {}", 10.0 * at_40);
        assert_eq!(THESIS.phase_error_at(0.0), 0.0);
    }

    #[test]
    fn fit_recovers_corner_difference_and_skew() {
        let points: Vec<(f64, f64)> = [20.0, 40.0, 160.0, 640.0]
            .iter()
            .map(|&f| (f, THESIS.phase_error_at(f)))
            .collect();
        let fit = PhaseErrorModel::fit(&points).expect("fit");
        // Corner difference within 1e-4 Hz (the (M1)-(M2) difference), skew
        // within 1e-10 s; the fitted model reproduces (M1) to 2e-6 rad from
        // 8 Hz to 10 kHz.
        assert!(
            (fit.force_high_pass_hz - 0.15).abs() < 1e-4,
            "{}",
            fit.force_high_pass_hz
        );
        assert_eq!(fit.accel_high_pass_hz, 0.0);
        assert!((fit.skew_s - 5e-6).abs() < 1e-10, "{}", fit.skew_s);
        for f in [20.0, 40.0, 1000.0, 10_000.0] {
            let d = fit.phase_error_at(f) - THESIS.phase_error_at(f);
            assert!(d.abs() < 2e-6, "{f} Hz: {d}");
        }
        let d = fit.phase_error_at(8.0) - THESIS.phase_error_at(8.0);
        assert!(d.abs() < 2e-5, "8 Hz: {d}");
        // An accelerometer that leads puts the corner on its own channel.
        let lead = PhaseErrorModel::fit(&[(20.0, -0.01), (80.0, -0.0025)]).expect("fit");
        assert!(lead.force_high_pass_hz == 0.0 && (lead.accel_high_pass_hz - 0.2).abs() < 1e-12);
    }

    #[test]
    fn fit_needs_two_frequencies() {
        for points in [
            vec![],
            vec![(40.0, 0.005)],
            vec![(40.0, 0.005), (40.0, 0.006)],
        ] {
            let err = PhaseErrorModel::fit(&points).expect_err("underdetermined");
            assert!(err.to_string().contains("two distinct"), "{err}");
        }
        assert!(PhaseErrorModel::fit(&[(0.0, 0.0), (40.0, 0.0)]).is_err());
        let bad = PhaseErrorModel {
            skew_s: f64::NAN,
            ..THESIS
        };
        assert!(bad.validate().is_err());
        THESIS.validate().expect("valid");
    }

    #[test]
    fn wrap_phase_range() {
        for (x, want) in [
            (PI, PI),
            (-PI, PI),
            (3.0 * PI, PI),
            (0.5, 0.5),
            (-0.5 - 2.0 * PI, -0.5),
        ] {
            assert!(
                (wrap_phase_rad(x) - want).abs() < 1e-12,
                "{x} -> {}",
                wrap_phase_rad(x)
            );
        }
    }
}
