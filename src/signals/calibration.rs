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
//! # Force polarity
//!
//! A lab that records the gauge's reaction (the force the enclosure exerts on
//! the gauge) has `f = -m_enc a`: the measured phase error is near `pi`. A
//! point with `|phi_err| > pi/2` is taken as such a record: it is flagged
//! ([`PhaseErrorPoint::force_polarity_reversed`]) and its error is stored
//! without the `pi`, `wrap(phi_err - pi)`, so that the table describes the
//! chain and the polarity separately (Yang's power detects and corrects the
//! polarity of each record on its own: [`super::power::ForcePolarity`]).
//!
//! # Across frequency
//!
//! `estimate_phase_error` (`phase_point.rs`) measures one point (that file
//! runs Yang's spectra, so this one stays below Yang's power, `power.rs`,
//! which applies the table); [`PhaseCalibration::from_points`]
//! averages the points of each frequency over the amplitudes tested (the
//! thesis' amplitude-averaged error) into a table and, from two or more
//! frequencies, fits the chain's high-pass + skew model
//! ([`super::phase_model`], eq. M1). [`PhaseCalibration::phase_error_at`]
//! evaluates the table at any frequency, e.g. at every harmonic of the drive:
//!
//! - with a model: the model, plus the table's residual from it interpolated
//!   linearly between table frequencies (held at the end values outside), so
//!   the table's own points are reproduced exactly and the harmonics follow
//!   the rig's high-pass (falling as `1/f`) and skew (growing as `f`);
//! - with a single frequency (no model can be fitted): as a pure time delay
//!   through the point, `phi(f) = phi_1 f / f_1`, which overstates the error
//!   at the harmonics of a rig with AC coupling; calibrate at several
//!   frequencies (the drive and a few of its harmonics) to avoid it.
//!
//! Tables are saved as JSON (atomically) with a `version` field and strict
//! field checking; version 1 files (no polarity, no model) are read, and a
//! model is fitted to them when they hold two or more frequencies.

use std::f64::consts::PI;
use std::path::Path;

use serde::{Deserialize, Serialize};

use super::error::{Result, SignalsError};
use super::phase_model::PhaseErrorModel;
use super::phase_model::wrap_phase_rad;
use crate::atomic_write::write_bytes_atomic;
use crate::validation::{finite, positive};

/// Version written into calibration JSON files (2: polarity and model).
pub const CALIBRATION_VERSION: u32 = 2;

/// Oldest version read (1: no polarity, no model).
pub const OLDEST_CALIBRATION_VERSION: u32 = 1;

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
    /// `phi_err` at the drive frequency, in rad, in (-pi, pi], without the
    /// `pi` of a reversed force.
    pub phase_error_rad: f64,
    /// True when the record's force was the gauge reaction (measured phase
    /// error near `pi`; see the module docs).
    #[serde(default)]
    pub force_polarity_reversed: bool,
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
    /// True when the empty enclosure's force was the gauge reaction.
    #[serde(default)]
    pub force_polarity_reversed: bool,
    /// High-pass + skew model fitted to the points (two or more frequencies).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub model: Option<PhaseErrorModel>,
}

/// Splits an empty-enclosure phase error `phi` in (-pi, pi] into the chain's
/// error and the polarity: `|phi| > pi/2` is a reversed force, whose chain
/// error is `wrap(phi - pi)`.
pub fn split_polarity(phi_rad: f64) -> (f64, bool) {
    if phi_rad.abs() > PI / 2.0 {
        (wrap_phase_rad(phi_rad - PI), true)
    } else {
        (phi_rad, false)
    }
}

impl PhaseCalibration {
    /// Builds a table from measured points: points within
    /// [`SAME_FREQ_REL_TOL`] of each other are one frequency, averaged over
    /// amplitudes (circular mean; spread = sample std about it).
    pub fn from_points(rig: impl Into<String>, points: &[PhaseErrorPoint]) -> Result<Self> {
        for (i, p) in points.iter().enumerate() {
            positive(&format!("points[{i}].freq_hz"), p.freq_hz, "Hz")?;
            finite(
                &format!("points[{i}].phase_error_rad"),
                p.phase_error_rad,
                "rad",
            )?;
        }
        let force_polarity_reversed = points.first().is_some_and(|p| p.force_polarity_reversed);
        if let Some((i, _)) = points
            .iter()
            .enumerate()
            .find(|(_, p)| p.force_polarity_reversed != force_polarity_reversed)
        {
            return Err(SignalsError::InvalidCalibration {
                reason: format!(
                    "point {i} ({} Hz) has the force polarity {} but point 0 has it {}: one rig,                      one wiring; check the force channel's sign",
                    points[i].freq_hz,
                    polarity_word(points[i].force_polarity_reversed),
                    polarity_word(force_polarity_reversed)
                ),
            });
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
        let mut cal = Self {
            version: CALIBRATION_VERSION,
            rig: rig.into(),
            note: String::new(),
            points: entries,
            force_polarity_reversed,
            model: None,
        };
        cal.validate()?;
        cal.model = cal.fit_model();
        Ok(cal)
    }

    /// The high-pass + skew model through the table's points, `None` below
    /// two frequencies.
    pub fn fit_model(&self) -> Option<PhaseErrorModel> {
        let points: Vec<(f64, f64)> = self
            .points
            .iter()
            .map(|p| (p.freq_hz, p.phase_error_rad))
            .collect();
        PhaseErrorModel::fit(&points).ok()
    }

    /// Checks version, ordering and finiteness.
    pub fn validate(&self) -> Result<()> {
        let bad = |reason: String| Err(SignalsError::InvalidCalibration { reason });
        if !(OLDEST_CALIBRATION_VERSION..=CALIBRATION_VERSION).contains(&self.version) {
            return bad(format!(
                "version {} is not supported (this vlab reads versions \
                 {OLDEST_CALIBRATION_VERSION} to {CALIBRATION_VERSION})",
                self.version
            ));
        }
        if let Some(model) = &self.model {
            model.validate().map_err(|e| e.within("model"))?;
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

    /// The phase error at `freq_hz`, in rad (see the module docs): the model
    /// plus the interpolated residual when there is a model, else linear
    /// between points and a pure delay through the nearest end point outside.
    /// `freq_hz <= 0` gives 0.
    pub fn phase_error_at(&self, freq_hz: f64) -> f64 {
        if freq_hz <= 0.0 || !freq_hz.is_finite() || self.points.is_empty() {
            return 0.0;
        }
        match &self.model {
            Some(model) => {
                let residual = |f: f64, phi: f64| phi - model.phase_error_at(f);
                model.phase_error_at(freq_hz) + interpolate_held(&self.points, freq_hz, residual)
            }
            None => self.delay_interpolation(freq_hz),
        }
    }

    /// Linear between points, `phi_end f / f_end` outside.
    fn delay_interpolation(&self, freq_hz: f64) -> f64 {
        let (first, last) = (&self.points[0], &self.points[self.points.len() - 1]);
        if freq_hz <= first.freq_hz {
            return first.phase_error_rad * freq_hz / first.freq_hz;
        }
        if freq_hz >= last.freq_hz {
            return last.phase_error_rad * freq_hz / last.freq_hz;
        }
        interpolate_held(&self.points, freq_hz, |_, phi| phi)
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
        let mut cal: Self = serde_json::from_str(&text).map_err(|source| SignalsError::Json {
            path: path.to_path_buf(),
            source,
        })?;
        cal.validate()?;
        if cal.model.is_none() {
            cal.model = cal.fit_model();
        }
        Ok(cal)
    }
}

/// `value(f, phi)` of the points, linear in frequency between them and held
/// at the end values outside (`points` non-empty, frequencies increasing).
fn interpolate_held(
    points: &[CalibrationEntry],
    freq_hz: f64,
    value: impl Fn(f64, f64) -> f64,
) -> f64 {
    let at = |p: &CalibrationEntry| value(p.freq_hz, p.phase_error_rad);
    let hi = points.partition_point(|p| p.freq_hz <= freq_hz);
    if hi == 0 {
        return at(&points[0]);
    }
    if hi == points.len() {
        return at(&points[hi - 1]);
    }
    let (a, b) = (&points[hi - 1], &points[hi]);
    let t = (freq_hz - a.freq_hz) / (b.freq_hz - a.freq_hz);
    at(a) + t * (at(b) - at(a))
}

fn polarity_word(reversed: bool) -> &'static str {
    if reversed { "reversed" } else { "as recorded" }
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
    use crate::signals::phase_model::PhaseErrorModel;

    #[test]
    fn spread_is_the_sample_std_about_the_mean() {
        let pt = |phase| PhaseErrorPoint {
            freq_hz: 40.0,
            accel_amplitude_mps2: 1.0,
            force_amplitude_n: 1.0,
            phase_error_rad: phase,
            force_polarity_reversed: false,
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
            force_polarity_reversed: false,
            model: None,
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
            force_polarity_reversed: false,
        };
        let mut cal =
            PhaseCalibration::from_points("thesis-shaker", &[pt(40.0, 0.0087), pt(20.0, 0.004)])
                .expect("table");
        cal.note = "empty enclosure, 2 frequencies".into();
        cal.save_json(&path).expect("save");
        let back = PhaseCalibration::load_json(&path).expect("load");
        assert_eq!(back, cal);

        let text = std::fs::read_to_string(&path).expect("read");
        std::fs::write(&path, text.replace("\"version\": 2", "\"version\": 3")).expect("w");
        let err = PhaseCalibration::load_json(&path).expect_err("version 3");
        assert!(err.to_string().contains("version 3"), "{err}");
        std::fs::write(&path, text.replace("\"rig\"", "\"extra\": 1, \"rig\"")).expect("w");
        assert!(matches!(
            PhaseCalibration::load_json(&path),
            Err(SignalsError::Json { .. })
        ));
        std::fs::remove_dir_all(dir).ok();
    }

    #[test]
    fn several_frequencies_give_the_high_pass_and_skew_at_the_harmonics() {
        // Points from the thesis rig's model at 40, 160 and 640 Hz: the table
        // fits it and gives its phase error at every harmonic of 40 Hz to
        // 1e-6 rad, where the one-point table's pure delay is off by
        // 0.00375 (k - 1/k) rad.
        let truth = PhaseErrorModel {
            force_high_pass_hz: 0.35,
            accel_high_pass_hz: 0.2,
            skew_s: 5e-6,
        };
        let pt = |f: f64| PhaseErrorPoint {
            freq_hz: f,
            accel_amplitude_mps2: 100.0,
            force_amplitude_n: 25.0,
            phase_error_rad: truth.phase_error_at(f),
            force_polarity_reversed: false,
        };
        let cal = PhaseCalibration::from_points("r", &[pt(40.0), pt(160.0), pt(640.0)]).expect("t");
        assert!(cal.model.is_some());
        let one = PhaseCalibration::from_points("r", &[pt(40.0)]).expect("t");
        assert!(one.model.is_none());
        for k in [1.0, 2.0, 3.0, 10.0, 50.0] {
            let f = 40.0 * k;
            assert!(
                (cal.phase_error_at(f) - truth.phase_error_at(f)).abs() < 1e-6,
                "{f} Hz"
            );
            let delay_err = one.phase_error_at(f) - truth.phase_error_at(f);
            let hp = truth.phase_error_at(40.0) - 2.0 * PI * 40.0 * 5e-6;
            assert!(
                (delay_err - hp * (k - 1.0 / k)).abs() < 1e-5,
                "{f} Hz: {delay_err}"
            );
        }
        // The table's own points come back exactly (tol 1e-15 rad).
        for p in &cal.points {
            assert!((cal.phase_error_at(p.freq_hz) - p.phase_error_rad).abs() < 1e-15);
        }
    }

    #[test]
    fn a_version_1_file_is_read_and_fitted() {
        let dir = std::env::temp_dir().join(format!("vlab-cal-v1-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("dir");
        let path = dir.join("cal.json");
        let v1 = r#"{"version": 1, "rig": "old", "note": "", "points": [
            {"freq_hz": 20.0, "phase_error_rad": 0.008, "n_amplitudes": 3, "spread_rad": 0.0},
            {"freq_hz": 160.0, "phase_error_rad": 0.006, "n_amplitudes": 3, "spread_rad": 0.0}]}"#;
        std::fs::write(&path, v1).expect("write");
        let cal = PhaseCalibration::load_json(&path).expect("version 1");
        std::fs::remove_dir_all(dir).ok();
        assert!(!cal.force_polarity_reversed);
        // The model passes within (c/f)^3/3 of both points (1e-6 rad), the
        // table through them (1e-15 rad).
        let model = cal.model.expect("fitted on load");
        for (f, phi) in [(20.0, 0.008), (160.0, 0.006)] {
            assert!((model.phase_error_at(f) - phi).abs() < 1e-6, "{f} Hz");
            assert!((cal.phase_error_at(f) - phi).abs() < 1e-15, "{f} Hz");
        }
    }

    #[test]
    fn bad_points_are_rejected() {
        let pt = PhaseErrorPoint {
            freq_hz: f64::NAN,
            accel_amplitude_mps2: 1.0,
            force_amplitude_n: 1.0,
            phase_error_rad: 0.0,
            force_polarity_reversed: false,
        };
        assert!(PhaseCalibration::from_points("r", &[pt]).is_err());
        assert!(PhaseCalibration::from_points("r", &[]).is_err());
    }
}
