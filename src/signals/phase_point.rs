//! One point of the empty-enclosure phase-error table (thesis Section 7.4.2,
//! Fig. 7.9): the phase of the force relative to the acceleration at the drive
//! frequency of an empty-enclosure record, less the `pi/2` a rigid mass gives,
//! `phi_err = wrap((phi_F - phi_V) - pi/2)` ([`super::calibration`] explains
//! the table and the force polarity).
//!
//! It runs Yang's spectra ([`super::power`]) and returns a
//! [`PhaseErrorPoint`] of [`super::calibration`]; the table itself does not
//! depend on Yang's method, so the power can apply a table without an import
//! loop.

use super::calibration::{PhaseErrorPoint, split_polarity};
use super::error::{Result, SignalsError, all_finite};
use super::phase_model::wrap_phase_rad;
use super::power::{PowerWindow, YangPower, plan_window};

/// Measures the phase error of an empty-enclosure record at the drive
/// frequency (largest whole number of drive periods from sample 0).
pub fn estimate_phase_error(
    force: &[f64],
    accel: &[f64],
    sample_rate_hz: f64,
    drive_freq_hz: f64,
) -> Result<PhaseErrorPoint> {
    if force.len() != accel.len() {
        return Err(SignalsError::LengthMismatch {
            first: "force".into(),
            first_len: force.len(),
            second: "acceleration".into(),
            second_len: accel.len(),
        });
    }
    all_finite("force", force)?;
    all_finite("acceleration", accel)?;
    let w = plan_window(
        force.len(),
        sample_rate_hz,
        drive_freq_hz,
        PowerWindow::default(),
    )?;
    let mut est = YangPower::new();
    let (f_spec, a_spec) = est.spectra(&force[..w.n_samples], &accel[..w.n_samples])?;
    let k = w.n_periods;
    let (f_k, a_k) = (f_spec[k], a_spec[k]);
    if a_k.norm() == 0.0 || f_k.norm() == 0.0 {
        return Err(SignalsError::InvalidCalibration {
            reason: format!(
                "no {drive_freq_hz} Hz content in {} (a phase needs a non-zero amplitude)",
                if a_k.norm() == 0.0 {
                    "acceleration"
                } else {
                    "force"
                }
            ),
        });
    }
    // phi_V = phi_A - pi/2, so phi_F - phi_V - pi/2 = phi_F - phi_A.
    let (phase_error_rad, force_polarity_reversed) =
        split_polarity(wrap_phase_rad(f_k.arg() - a_k.arg()));
    Ok(PhaseErrorPoint {
        freq_hz: drive_freq_hz,
        accel_amplitude_mps2: a_k.norm(),
        force_amplitude_n: f_k.norm(),
        phase_error_rad,
        force_polarity_reversed,
    })
}

#[cfg(test)]
mod tests {
    use std::f64::consts::PI;

    use super::*;
    use crate::signals::calibration::PhaseCalibration;
    use crate::signals::power::{PhaseCorrection, PowerOptions, yang_power};

    const FS: f64 = 40_000.0;

    /// Empty enclosure of mass m driven at f with velocity amplitude V; the force
    /// channel is advanced by tau: f(t) = m a(t + tau). v = V sin(wt), a = V w cos(wt).
    fn empty_enclosure(m: f64, f: f64, v_amp: f64, tau: f64, n: usize) -> (Vec<f64>, Vec<f64>) {
        let w = 2.0 * PI * f;
        let t = |i: usize| i as f64 / FS;
        let accel = (0..n).map(|i| v_amp * w * (w * t(i)).cos()).collect();
        let force = (0..n)
            .map(|i| m * v_amp * w * (w * (t(i) + tau)).cos())
            .collect();
        (force, accel)
    }

    #[test]
    fn time_shift_gives_omega_tau_and_its_false_power() {
        // m 0.3 kg, 40 Hz, V 0.78 m/s (about Gamma 20), tau 35 us (0.5 deg).
        let (m, f, v_amp, tau) = (0.3, 40.0, 0.78, 35e-6);
        let w = 2.0 * PI * f;
        let (force, accel) = empty_enclosure(m, f, v_amp, tau, 40_000);
        let p = estimate_phase_error(&force, &accel, FS, f).expect("point");
        // Tolerance 1e-6 rad.
        assert!(
            (p.phase_error_rad - w * tau).abs() < 1e-6,
            "{}",
            p.phase_error_rad
        );
        assert!((p.accel_amplitude_mps2 - v_amp * w).abs() < 1e-9 * v_amp * w);

        // Uncorrected: -1/2 m w V^2 sin(phi_err) (rel. tol 1e-6).
        let raw = yang_power(&force, &accel, FS, f, &PowerOptions::default()).expect("raw");
        let false_power = -0.5 * m * w * v_amp * v_amp * (w * tau).sin();
        assert!(
            (raw.power_w - false_power).abs() < 1e-6 * false_power.abs(),
            "{} vs {false_power}",
            raw.power_w
        );
        // Corrected with the table: ~0 (below 1e-9 of the false power).
        let cal = PhaseCalibration::from_points("test rig", &[p]).expect("table");
        let opts = PowerOptions {
            phase_correction: PhaseCorrection::Table(&cal),
            ..PowerOptions::default()
        };
        let fixed = yang_power(&force, &accel, FS, f, &opts).expect("corrected");
        assert!(
            fixed.power_w.abs() < 1e-9 * false_power.abs(),
            "{}",
            fixed.power_w
        );
        assert!((fixed.phase_correction_rad - w * tau).abs() < 1e-6);
    }

    #[test]
    fn table_averages_over_amplitudes_per_frequency() {
        let mut points = Vec::new();
        for (f, tau) in [(20.0, 40e-6), (40.0, 35e-6), (80.0, 30e-6)] {
            for v_amp in [0.2, 0.5, 0.9] {
                let (force, accel) = empty_enclosure(0.3, f, v_amp, tau, 20_000);
                points.push(estimate_phase_error(&force, &accel, FS, f).expect("point"));
            }
        }
        // Shuffled input order must not matter.
        points.reverse();
        let cal = PhaseCalibration::from_points("rig", &points).expect("table");
        assert_eq!(cal.points.len(), 3);
        for (e, (f, tau)) in cal
            .points
            .iter()
            .zip([(20.0, 40e-6), (40.0, 35e-6), (80.0, 30e-6)])
        {
            assert_eq!(e.freq_hz, f);
            assert_eq!(e.n_amplitudes, 3);
            // Tolerance 1e-6 rad; the three amplitudes agree to rounding.
            assert!((e.phase_error_rad - 2.0 * PI * f * tau).abs() < 1e-6);
            assert!(e.spread_rad < 1e-9);
        }
    }

    #[test]
    fn a_reversed_empty_enclosure_reads_pi_and_is_split_off() {
        // The gauge reaction, f = -m a(t + tau): phase error pi + w tau. The
        // point is flagged and keeps w tau (tol 1e-12 rad against the
        // unflipped record's estimate); the table says so too.
        let (m, f, v_amp, tau) = (0.3, 40.0, 0.78, 35e-6);
        let (force, accel) = empty_enclosure(m, f, v_amp, tau, 40_000);
        let reaction: Vec<f64> = force.iter().map(|x| -x).collect();
        let normal = estimate_phase_error(&force, &accel, FS, f).expect("normal");
        let flipped = estimate_phase_error(&reaction, &accel, FS, f).expect("flipped");
        assert!(!normal.force_polarity_reversed && flipped.force_polarity_reversed);
        assert!((flipped.phase_error_rad - normal.phase_error_rad).abs() < 1e-12);
        let cal = PhaseCalibration::from_points("r", &[flipped]).expect("table");
        assert!(cal.force_polarity_reversed);
        // One rig, one wiring: a table that mixes them is refused.
        let err = PhaseCalibration::from_points("r", &[flipped, normal]).expect_err("mixed");
        assert!(err.to_string().contains("force polarity"), "{err}");
        let (phi, reversed) = split_polarity(PI - 0.01);
        assert!(reversed && (phi + 0.01).abs() < 1e-12, "{phi}");
        assert_eq!(split_polarity(0.01), (0.01, false));
    }

    #[test]
    fn a_silent_record_has_no_phase() {
        let silent = vec![0.0; 4000];
        assert!(estimate_phase_error(&silent, &silent, FS, 40.0).is_err());
    }
}
