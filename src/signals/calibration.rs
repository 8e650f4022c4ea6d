//! Phase calibration on the empty enclosure (thesis Section 7.4.2, Fig. 7.9):
//! the phase error that eq. 7.12 must subtract before it is summed.
//!
//! An empty rigid enclosure obeys `f = m_enc a`, so its force leads its
//! velocity by exactly +90 deg and takes no power. Whatever the measured
//! `phi_F - phi_V` at the drive frequency exceeds `pi/2` by is the rig's phase
//! error (transducer and conditioner phase, connection flexibility, ...):
//!
//! `phi_err(f) = wrap((phi_F - phi_V)_measured - pi/2)`, wrapped to (-pi, pi].
//!
//! Uncorrected, it shows up as a false power `-1/2 m_enc w V^2 sin(phi_err)`
//! (positive `phi_err`: force leads by more than 90 deg, power reads low).
//! With the phase conventions of [`super::spectrum`], a force channel that is
//! *advanced* by `tau` relative to the acceleration channel
//! (`f(t) = m a(t + tau)`) gives `phi_err = w tau`.
//!
//! [`estimate_phase_error`] measures one point; [`PhaseCalibration::from_points`]
//! averages the points of each frequency over the amplitudes tested (the
//! thesis' amplitude-averaged error) into a table, and
//! [`PhaseCalibration::phase_error_at`] interpolates it:
//!
//! - between table frequencies: linearly in frequency;
//! - below the first / above the last: as a pure time delay through the
//!   nearest point, `phi(f) = phi_end f / f_end` (a delay is the usual
//!   source of an inter-channel phase error, and it gives 0 at DC rather than
//!   an arbitrary constant). Far outside the table this can grow large:
//!   calibrate the frequencies you test.
//!
//! Tables are saved as JSON (atomically) with a `version` field and strict
//! field checking.

use std::f64::consts::PI;
use std::path::Path;

use serde::{Deserialize, Serialize};

use super::error::{Result, SignalsError};
use super::power::{PowerWindow, YangPower, plan_window, wrap_phase_rad};
use crate::atomic_write::write_bytes_atomic;

/// Version written into, and required of, calibration JSON files.
pub const CALIBRATION_VERSION: u32 = 1;

/// Relative tolerance within which two calibration points count as the same
/// frequency when building a table.
pub const SAME_FREQ_REL_TOL: f64 = 1e-6;

/// One empty-enclosure measurement.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PhaseErrorPoint {
    /// Drive frequency, in Hz.
    pub freq_hz: f64,
    /// Acceleration amplitude at the drive frequency, in m/s^2.
    pub accel_amplitude_mps2: f64,
    /// Force amplitude at the drive frequency, in N.
    pub force_amplitude_n: f64,
    /// `phi_err` at the drive frequency, in rad, in (-pi, pi].
    pub phase_error_rad: f64,
}

/// The amplitude-averaged phase error at one frequency.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CalibrationEntry {
    /// Frequency, in Hz.
    pub freq_hz: f64,
    /// Circular mean of the phase errors measured at this frequency, in rad.
    pub phase_error_rad: f64,
    /// Number of amplitudes averaged.
    pub n_amplitudes: usize,
    /// Sample standard deviation (n - 1) of those errors about their mean, in
    /// rad; 0 for a single amplitude.
    pub spread_rad: f64,
}

/// A phase-error table for one rig, sorted by frequency.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PhaseCalibration {
    /// File format version, [`CALIBRATION_VERSION`].
    pub version: u32,
    /// Rig the table belongs to.
    pub rig: String,
    /// Free text: when, how, by whom.
    #[serde(default)]
    pub note: String,
    /// Entries in strictly increasing frequency.
    pub points: Vec<CalibrationEntry>,
}

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
    super::error::all_finite("force", force)?;
    super::error::all_finite("acceleration", accel)?;
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
    let phase_error_rad = wrap_phase_rad(f_k.arg() - a_k.arg());
    Ok(PhaseErrorPoint {
        freq_hz: drive_freq_hz,
        accel_amplitude_mps2: a_k.norm(),
        force_amplitude_n: f_k.norm(),
        phase_error_rad,
    })
}

impl PhaseCalibration {
    /// Builds a table from measured points: points within
    /// [`SAME_FREQ_REL_TOL`] of each other are one frequency, averaged over
    /// amplitudes (circular mean; spread = sample std about it).
    pub fn from_points(rig: impl Into<String>, points: &[PhaseErrorPoint]) -> Result<Self> {
        for (i, p) in points.iter().enumerate() {
            if !(p.freq_hz.is_finite() && p.freq_hz > 0.0 && p.phase_error_rad.is_finite()) {
                return Err(SignalsError::InvalidCalibration {
                    reason: format!(
                        "point {i}: frequency {} Hz must be positive and finite, phase error {} rad finite",
                        p.freq_hz, p.phase_error_rad
                    ),
                });
            }
        }
        let mut sorted: Vec<PhaseErrorPoint> = points.to_vec();
        sorted.sort_by(|a, b| a.freq_hz.total_cmp(&b.freq_hz));
        let mut entries = Vec::new();
        let mut group: Vec<PhaseErrorPoint> = Vec::new();
        for p in sorted {
            if let Some(first) = group.first()
                && (p.freq_hz - first.freq_hz).abs() > SAME_FREQ_REL_TOL * first.freq_hz
            {
                entries.push(average(&group));
                group.clear();
            }
            group.push(p);
        }
        if !group.is_empty() {
            entries.push(average(&group));
        }
        let cal = Self {
            version: CALIBRATION_VERSION,
            rig: rig.into(),
            note: String::new(),
            points: entries,
        };
        cal.validate()?;
        Ok(cal)
    }

    /// Checks version, ordering and finiteness.
    pub fn validate(&self) -> Result<()> {
        let bad = |reason: String| Err(SignalsError::InvalidCalibration { reason });
        if self.version != CALIBRATION_VERSION {
            return bad(format!(
                "version {} is not supported (this vlab reads version {CALIBRATION_VERSION})",
                self.version
            ));
        }
        if self.points.is_empty() {
            return bad("the table has no points".into());
        }
        for (i, p) in self.points.iter().enumerate() {
            if !(p.freq_hz.is_finite() && p.freq_hz > 0.0) {
                return bad(format!(
                    "point {i}: freq_hz = {} Hz must be positive and finite",
                    p.freq_hz
                ));
            }
            if !(p.phase_error_rad.is_finite() && p.phase_error_rad.abs() <= PI) {
                return bad(format!(
                    "point {i}: phase_error_rad = {} rad must be finite and within [-pi, pi]",
                    p.phase_error_rad
                ));
            }
            if !(p.spread_rad.is_finite() && p.spread_rad >= 0.0) {
                return bad(format!(
                    "point {i}: spread_rad = {} rad must be >= 0",
                    p.spread_rad
                ));
            }
            if i > 0 && p.freq_hz <= self.points[i - 1].freq_hz {
                return bad(format!(
                    "point {i}: frequencies must increase strictly ({} Hz after {} Hz)",
                    p.freq_hz,
                    self.points[i - 1].freq_hz
                ));
            }
        }
        Ok(())
    }

    /// The phase error at `freq_hz`, in rad: linear between table points, a
    /// pure time delay through the nearest end point outside them (see the
    /// module docs). `freq_hz <= 0` gives 0.
    pub fn phase_error_at(&self, freq_hz: f64) -> f64 {
        let pts = &self.points;
        let (Some(first), Some(last)) = (pts.first(), pts.last()) else {
            return 0.0;
        };
        if freq_hz <= 0.0 || !freq_hz.is_finite() {
            return 0.0;
        }
        if freq_hz <= first.freq_hz {
            return first.phase_error_rad * freq_hz / first.freq_hz;
        }
        if freq_hz >= last.freq_hz {
            return last.phase_error_rad * freq_hz / last.freq_hz;
        }
        // First point strictly above freq_hz; 1 <= hi < len here.
        let hi = pts.partition_point(|p| p.freq_hz <= freq_hz);
        let (a, b) = (&pts[hi - 1], &pts[hi]);
        let t = (freq_hz - a.freq_hz) / (b.freq_hz - a.freq_hz);
        a.phase_error_rad + t * (b.phase_error_rad - a.phase_error_rad)
    }

    /// Writes the table as pretty JSON, atomically.
    pub fn save_json(&self, path: &Path) -> Result<()> {
        self.validate()?;
        let mut text = serde_json::to_string_pretty(self).map_err(|source| SignalsError::Json {
            path: path.to_path_buf(),
            source,
        })?;
        text.push('\n');
        write_bytes_atomic(path, text.as_bytes()).map_err(|source| SignalsError::Io {
            path: path.to_path_buf(),
            source,
        })
    }

    /// Reads and validates a table written by [`Self::save_json`].
    pub fn load_json(path: &Path) -> Result<Self> {
        let text = std::fs::read_to_string(path).map_err(|source| SignalsError::Io {
            path: path.to_path_buf(),
            source,
        })?;
        let cal: Self = serde_json::from_str(&text).map_err(|source| SignalsError::Json {
            path: path.to_path_buf(),
            source,
        })?;
        cal.validate()?;
        Ok(cal)
    }
}

/// Circular mean and spread of one frequency's points (non-empty).
fn average(group: &[PhaseErrorPoint]) -> CalibrationEntry {
    let n = group.len();
    let (s, c) = group.iter().fold((0.0, 0.0), |(s, c), p| {
        (s + p.phase_error_rad.sin(), c + p.phase_error_rad.cos())
    });
    let mean = s.atan2(c);
    let spread_rad = if n > 1 {
        let ss: f64 = group
            .iter()
            .map(|p| wrap_phase_rad(p.phase_error_rad - mean).powi(2))
            .sum();
        (ss / (n - 1) as f64).sqrt()
    } else {
        0.0
    };
    let freq_hz = group.iter().map(|p| p.freq_hz).sum::<f64>() / n as f64;
    CalibrationEntry {
        freq_hz,
        phase_error_rad: wrap_phase_rad(mean),
        n_amplitudes: n,
        spread_rad,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
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
    fn spread_is_the_sample_std_about_the_mean() {
        let pt = |phase| PhaseErrorPoint {
            freq_hz: 40.0,
            accel_amplitude_mps2: 1.0,
            force_amplitude_n: 1.0,
            phase_error_rad: phase,
        };
        let cal = PhaseCalibration::from_points("r", &[pt(0.01), pt(0.02), pt(0.03)]).expect("t");
        // Small angles: circular mean ~ arithmetic 0.02, std ~ 0.01 (tol 1e-6).
        assert!((cal.points[0].phase_error_rad - 0.02).abs() < 1e-6);
        assert!((cal.points[0].spread_rad - 0.01).abs() < 1e-6);
        // Near +-pi the circular mean does not average to 0.
        let cal = PhaseCalibration::from_points("r", &[pt(PI - 0.01), pt(-PI + 0.01)]).expect("t");
        assert!((cal.points[0].phase_error_rad.abs() - PI).abs() < 1e-9);
    }

    #[test]
    fn interpolation_and_delay_extrapolation() {
        let entry = |f: f64, phi: f64| CalibrationEntry {
            freq_hz: f,
            phase_error_rad: phi,
            n_amplitudes: 1,
            spread_rad: 0.0,
        };
        let cal = PhaseCalibration {
            version: CALIBRATION_VERSION,
            rig: "r".into(),
            note: String::new(),
            points: vec![entry(20.0, 0.01), entry(40.0, 0.03), entry(80.0, 0.05)],
        };
        cal.validate().expect("valid");
        // Exact arithmetic expectations, tol 1e-15.
        let close = |a: f64, b: f64| (a - b).abs() < 1e-15;
        assert!(close(cal.phase_error_at(30.0), 0.02));
        assert!(close(cal.phase_error_at(60.0), 0.04));
        assert!(close(cal.phase_error_at(40.0), 0.03));
        assert!(close(cal.phase_error_at(10.0), 0.005)); // delay through 20 Hz
        assert!(close(cal.phase_error_at(160.0), 0.1)); // delay through 80 Hz
        assert_eq!(cal.phase_error_at(0.0), 0.0);
    }

    #[test]
    fn json_round_trip_and_strict_loading() {
        let dir = std::env::temp_dir().join(format!("vlab-cal-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("dir");
        let path = dir.join("cal.json");
        let pt = |f, phi| PhaseErrorPoint {
            freq_hz: f,
            accel_amplitude_mps2: 100.0,
            force_amplitude_n: 30.0,
            phase_error_rad: phi,
        };
        let mut cal =
            PhaseCalibration::from_points("thesis-shaker", &[pt(40.0, 0.0087), pt(20.0, 0.004)])
                .expect("table");
        cal.note = "empty enclosure, 2 frequencies".into();
        cal.save_json(&path).expect("save");
        let back = PhaseCalibration::load_json(&path).expect("load");
        assert_eq!(back, cal);

        let text = std::fs::read_to_string(&path).expect("read");
        std::fs::write(&path, text.replace("\"version\": 1", "\"version\": 2")).expect("w");
        let err = PhaseCalibration::load_json(&path).expect_err("version 2");
        assert!(err.to_string().contains("version 2"), "{err}");
        std::fs::write(&path, text.replace("\"rig\"", "\"extra\": 1, \"rig\"")).expect("w");
        assert!(matches!(
            PhaseCalibration::load_json(&path),
            Err(SignalsError::Json { .. })
        ));
        std::fs::remove_dir_all(dir).ok();
    }

    #[test]
    fn bad_points_are_rejected() {
        let pt = PhaseErrorPoint {
            freq_hz: f64::NAN,
            accel_amplitude_mps2: 1.0,
            force_amplitude_n: 1.0,
            phase_error_rad: 0.0,
        };
        assert!(PhaseCalibration::from_points("r", &[pt]).is_err());
        assert!(PhaseCalibration::from_points("r", &[]).is_err());
        let silent = vec![0.0; 4000];
        assert!(estimate_phase_error(&silent, &silent, FS, 40.0).is_err());
    }
}
