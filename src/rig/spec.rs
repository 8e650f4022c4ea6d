//! Rig descriptions: what lab hardware a virtual test runs on (thesis Section
//! 7.4.2, Fig. 7.7: shaker, accelerometer, force transducer, signal
//! conditioner, digitiser).
//!
//! A rig is a TOML file of `version = 1` with strict keys. The built-in rigs are
//! the files in the top-level `rig/` folder, embedded in the binary:
//!
//! - `thesis-shaker` (the default): a model of the thesis rig, with an
//!   electrodynamic shaker, realistic transducers, conditioner filters, a 16-bit
//!   ADC and the stroke / acceleration limits the thesis reports;
//! - `ideal`: the perfect lab: prescribed motion, no noise, no filters, no phase
//!   error, no quantisation, no limits.
//!
//! [`RigSpec::load`] reads a file that is a complete rig, every required key
//! present (print a built-in with [`RigSpec::to_toml`] and edit it); nothing is
//! merged from a built-in. Keys carry their SI unit in the name.
//!
//! The model's own inter-channel phase error, the quantity the empty-enclosure
//! calibration of Fig. 7.9 estimates, is [`RigSpec::expected_phase_error_rad`].

use realfft::num_complex::Complex64;
use serde::{Deserialize, Serialize};

use super::channel_spec::{Acceleration, ChannelParams, ChannelSpec, Force};
use super::error::{RigError, non_negative, positive};
use super::file::{RigFile, RigKind, check_header, shaker_kind};
use crate::signals::{PhaseErrorModel, wrap_phase_rad};
use crate::validation::{Bound, count_in, in_range, require};

/// Name of the default rig.
pub const DEFAULT_RIG: &str = "thesis-shaker";

/// How the enclosure is moved.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
#[serde(rename_all = "lowercase")]
pub enum ShakerKind {
    /// The enclosure follows u = Gamma g / w^2 sin(w t) exactly (thesis eq. 6.2 / 7.6),
    /// whatever the particles do.
    #[default]
    Prescribed,
    /// A lumped electrodynamic shaker driven by an amplifier; the particles'
    /// force disturbs its motion.
    Electrodynamic,
}

impl ShakerKind {
    /// Lower-case name, as in rig files and on the command line.
    pub fn as_str(self) -> &'static str {
        match self {
            ShakerKind::Prescribed => "prescribed",
            ShakerKind::Electrodynamic => "electrodynamic",
        }
    }
}

impl std::fmt::Display for ShakerKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.as_str())
    }
}

/// A complete rig description.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RigSpec {
    /// File format version; must be [`RIG_VERSION`].
    pub version: u32,
    /// Always `shaker` (optional in files).
    #[serde(default = "shaker_kind")]
    pub kind: RigKind,
    /// Rig name, written into trace metadata.
    pub name: String,
    /// One or two sentences on what this rig is.
    #[serde(default)]
    pub description: String,
    /// The moving part above the force gauge.
    pub enclosure: EnclosureSpec,
    /// The drive.
    pub shaker: ShakerSpec,
    /// Accelerometer on the enclosure base and its conditioner channel.
    pub accelerometer: AccelerometerSpec,
    /// Force transducer between shaker and enclosure and its channel.
    pub force: ForceSpec,
    /// Digitiser.
    pub daq: DaqSpec,
}

/// The mass the force transducer carries.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EnclosureSpec {
    /// Mass above the force gauge (enclosure, lid, accelerometer, transducer
    /// top), kg.
    pub mass_kg: f64,
}

/// The shaker: its kind, its limits and (for an electrodynamic one) its
/// lumped parameters.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ShakerSpec {
    /// Default kind for this rig (a caller may override it).
    #[serde(default)]
    pub kind: ShakerKind,
    /// Largest peak-to-peak displacement, m; absent = no limit.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stroke_pp_m: Option<f64>,
    /// Largest peak acceleration, m/s^2; absent = no limit.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_accel_mps2: Option<f64>,
    /// Lumped electrodynamic model; required for `kind = "electrodynamic"`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub electrodynamic: Option<ElectrodynamicSpec>,
}

/// Lumped parameters of an electrodynamic shaker and its amplifier, and the
/// sine controller that sets the drive level.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ElectrodynamicSpec {
    /// Armature (coil former and table) mass, kg.
    pub armature_mass_kg: f64,
    /// Suspension (flexure) stiffness, N/m.
    pub suspension_stiffness_n_per_m: f64,
    /// Suspension viscous damping, N s/m.
    pub suspension_damping_n_s_per_m: f64,
    /// Force factor Bl, N/A (equal to the back-EMF constant, V s/m).
    pub force_factor_n_per_a: f64,
    /// Coil resistance, ohm.
    pub coil_resistance_ohm: f64,
    /// Coil inductance, H.
    pub coil_inductance_h: f64,
    /// Voltage gain of the power amplifier, V/V.
    pub amplifier_gain_v_per_v: f64,
    /// Adjust the drive once per cycle from the measured fundamental of the
    /// acceleration, as a vibration controller does.
    #[serde(default = "default_true")]
    pub closed_loop: bool,
    /// Fraction of the remaining amplitude / phase error corrected per cycle,
    /// in (0, 1].
    #[serde(default = "default_loop_gain")]
    pub loop_gain: f64,
    /// Fraction of the particle mass counted as rigid payload when the
    /// open-loop drive level is computed, in [0, 1].
    #[serde(default = "default_particle_fraction")]
    pub feedforward_particle_fraction: f64,
}

fn default_true() -> bool {
    true
}

fn default_loop_gain() -> f64 {
    0.5
}

fn default_particle_fraction() -> f64 {
    0.5
}

/// The accelerometer and its conditioner channel (`[accelerometer]`).
pub type AccelerometerSpec = ChannelSpec<Acceleration>;

/// The force transducer and its conditioner channel (`[force]`).
pub type ForceSpec = ChannelSpec<Force>;

/// The digitiser.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DaqSpec {
    /// Samples per second per channel, Hz (thesis: 40 kHz).
    #[serde(default = "default_sample_rate")]
    pub sample_rate_hz: f64,
    /// ADC resolution, bits, 1..=32.
    #[serde(default = "default_bits")]
    pub bits: u32,
    /// ADC input range is +-full_scale_v, V.
    #[serde(default = "default_full_scale")]
    pub full_scale_v: f64,
    /// No quantisation and no clipping.
    #[serde(default)]
    pub ideal_adc: bool,
}

fn default_sample_rate() -> f64 {
    40_000.0
}

fn default_bits() -> u32 {
    16
}

fn default_full_scale() -> f64 {
    10.0
}

impl RigSpec {
    /// The accelerometer channel in common terms.
    pub fn accel_channel(&self) -> ChannelParams {
        self.accelerometer.params()
    }

    /// The force channel in common terms.
    pub fn force_channel(&self) -> ChannelParams {
        self.force.params()
    }

    /// The model's own phase error at `freq_hz`: the phase of the force
    /// channel's response minus that of the acceleration channel's, wrapped
    /// to (-pi, pi], rad. Positive: the recorded force leads. This is what an
    /// ideal empty-enclosure calibration (`signals::estimate_phase_error`)
    /// measures on this rig, and what Yang's power must subtract.
    ///
    /// For first-order high-passes and skews alone it is
    /// `atan(f_cF / f) - atan(f_cA / f) + 2 pi f (tau_F - tau_A)`.
    pub fn expected_phase_error_rad(&self, freq_hz: f64) -> f64 {
        let fs = self.daq.sample_rate_hz;
        let hf = self.force_channel().response(freq_hz, fs);
        let ha = self.accel_channel().response(freq_hz, fs);
        wrap_phase_rad(hf.arg() - ha.arg())
    }

    /// The force channel's response over the accelerometer's at
    /// `freq_hz`: what a ratio of the two records (an accelerance, a
    /// receptance) is multiplied by through the chains, whose argument is
    /// [`Self::expected_phase_error_rad`] and whose magnitude differs from
    /// 1 by the chains' filters (the high-passes: 2.5e-5 at 40 Hz on the
    /// thesis rig, 0.3 % at 5 Hz). Dividing a measured ratio by it takes
    /// both out, as a lab's calibration of its chains does.
    pub fn expected_channel_ratio(&self, freq_hz: f64) -> Complex64 {
        let fs = self.daq.sample_rate_hz;
        self.force_channel().response(freq_hz, fs) / self.accel_channel().response(freq_hz, fs)
    }

    /// The high-pass + skew part of [`Self::expected_phase_error_rad`]
    /// (`signals::phase_model`, eq. M1): all of it when the two channels'
    /// low-passes and sampling are alike, as in the built-in rigs.
    pub fn phase_error_model(&self) -> PhaseErrorModel {
        PhaseErrorModel {
            force_high_pass_hz: self.force.high_pass_hz,
            accel_high_pass_hz: self.accelerometer.high_pass_hz,
            skew_s: self.force.sample_skew_s - self.accelerometer.sample_skew_s,
        }
    }

    /// The same rig driven by `kind` (`shaker.kind`).
    pub fn with_shaker(mut self, kind: ShakerKind) -> RigSpec {
        self.shaker.kind = kind;
        self
    }

    /// The electrodynamic shaker's lumped parameters: the one refusal of an
    /// electrodynamic drive on a rig without them.
    pub fn electrodynamic(&self) -> Result<ElectrodynamicSpec, RigError> {
        self.shaker
            .electrodynamic
            .ok_or_else(|| RigError::MissingSection {
                rig: self.name.clone(),
                section: "shaker.electrodynamic",
                hint: "an electrodynamic drive needs the lumped shaker parameters: use the \
                       prescribed drive or a rig that has them (thesis-shaker)"
                    .into(),
            })
    }

    /// True when the two channels read with no phase error at `freq_hz` and
    /// no noise (the `ideal` rig): an empty-enclosure calibration could only
    /// measure rounding, so none is run and the correction is zero.
    pub fn needs_no_calibration(&self, freq_hz: f64) -> bool {
        let (f, a) = (self.force_channel(), self.accel_channel());
        self.expected_phase_error_rad(freq_hz) == 0.0 && f.noise_rms == 0.0 && a.noise_rms == 0.0
    }
}

impl RigFile for RigSpec {
    const KIND: RigKind = RigKind::Shaker;

    fn validate(&self) -> Result<(), RigError> {
        check_header(self.version, self.kind, Self::KIND, &self.name)?;
        positive("enclosure.mass_kg", self.enclosure.mass_kg, "kg")?;
        let s = &self.shaker;
        if let Some(v) = s.stroke_pp_m {
            positive("shaker.stroke_pp_m", v, "m")?;
        }
        if let Some(v) = s.max_accel_mps2 {
            positive("shaker.max_accel_mps2", v, "m/s^2")?;
        }
        match (&s.electrodynamic, s.kind) {
            (Some(e), _) => e.validate()?,
            (None, ShakerKind::Electrodynamic) => {
                self.electrodynamic()?;
            }
            (None, ShakerKind::Prescribed) => {}
        }
        let d = &self.daq;
        d.validate()?;
        self.accel_channel().validate(d.sample_rate_hz)?;
        self.force_channel().validate(d.sample_rate_hz)?;
        Ok(())
    }
}

impl DaqSpec {
    /// Checks a step of the clock that drives the channels, `step_s` named
    /// `key`: positive and at most one sample period (each sample needs at
    /// least one step).
    pub fn check_step(&self, key: &str, step_s: f64) -> Result<(), RigError> {
        positive(key, step_s, "s")?;
        let period = 1.0 / self.sample_rate_hz;
        require(
            step_s <= period,
            key,
            step_s,
            "s",
            format!(
                "at most one sample period, {period} s at daq.sample_rate_hz = {} Hz",
                self.sample_rate_hz
            ),
        )?;
        Ok(())
    }

    /// Checks sample rate, bits and full scale.
    pub fn validate(&self) -> Result<(), RigError> {
        positive("daq.sample_rate_hz", self.sample_rate_hz, "Hz")?;
        count_in("daq.bits", self.bits, "bits", 1, Some(32))?;
        positive("daq.full_scale_v", self.full_scale_v, "V")?;
        Ok(())
    }
}

impl ElectrodynamicSpec {
    fn validate(&self) -> Result<(), RigError> {
        let k = |name: &str| format!("shaker.electrodynamic.{name}");
        positive(&k("armature_mass_kg"), self.armature_mass_kg, "kg")?;
        non_negative(
            &k("suspension_stiffness_n_per_m"),
            self.suspension_stiffness_n_per_m,
            "N/m",
        )?;
        non_negative(
            &k("suspension_damping_n_s_per_m"),
            self.suspension_damping_n_s_per_m,
            "N s/m",
        )?;
        positive(&k("force_factor_n_per_a"), self.force_factor_n_per_a, "N/A")?;
        positive(&k("coil_resistance_ohm"), self.coil_resistance_ohm, "ohm")?;
        positive(&k("coil_inductance_h"), self.coil_inductance_h, "H")?;
        positive(
            &k("amplifier_gain_v_per_v"),
            self.amplifier_gain_v_per_v,
            "V/V",
        )?;
        in_range(
            &k("loop_gain"),
            self.loop_gain,
            "",
            Bound::Open(0.0),
            Bound::Closed(1.0),
        )?;
        in_range(
            &k("feedforward_particle_fraction"),
            self.feedforward_particle_fraction,
            "",
            Bound::Closed(0.0),
            Bound::Closed(1.0),
        )?;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use std::f64::consts::PI;

    use super::*;
    use crate::rig::builtin_toml;

    fn thesis_text() -> &'static str {
        builtin_toml("thesis-shaker").expect("built in")
    }

    fn parse_err(text: &str) -> String {
        RigSpec::from_toml_str(text, "test.toml")
            .expect_err("must be refused")
            .to_string()
    }

    #[test]
    fn builtins_parse_validate_and_round_trip() {
        assert_eq!(RigSpec::names()[0], DEFAULT_RIG);
        for name in RigSpec::names() {
            let rig = RigSpec::builtin(name).expect("built-in parses");
            assert_eq!(rig.name, name);
            let back = RigSpec::from_toml_str(&rig.to_toml(), "printed").expect("reparses");
            assert_eq!(back, rig, "{name} must survive to_toml");
        }
        let msg = RigSpec::builtin("nope").expect_err("unknown").to_string();
        assert!(msg.contains("thesis-shaker, ideal"), "{msg}");
    }

    #[test]
    fn unknown_key_is_named() {
        let text = thesis_text().replace("[daq]", "[daq]\nsample_rate = 40000.0");
        let msg = parse_err(&text);
        assert!(
            msg.contains("sample_rate") && msg.contains("test.toml"),
            "{msg}"
        );
    }

    #[test]
    fn version_2_is_refused_by_version() {
        let text = thesis_text().replace("version = 1", "version = 2");
        let msg = parse_err(&text);
        assert!(
            msg.contains("version = 2") && msg.contains("version 1"),
            "{msg}"
        );
    }

    #[test]
    fn bad_values_name_key_unit_and_range() {
        let mut rig = RigSpec::builtin("thesis-shaker").expect("built in");
        rig.accelerometer.sensitivity = -0.001;
        let msg = rig.validate().expect_err("negative").to_string();
        assert_eq!(
            msg,
            "accelerometer.sensitivity_v_per_mps2 = -0.001 V/(m/s^2): must be positive and finite"
        );

        let mut rig = RigSpec::builtin("thesis-shaker").expect("built in");
        rig.daq.bits = 0;
        let msg = rig.validate().expect_err("bits 0").to_string();
        assert_eq!(msg, "daq.bits = 0 bits: must be an integer in 1..=32");

        let mut rig = RigSpec::builtin("thesis-shaker").expect("built in");
        rig.daq.sample_rate_hz = 0.0;
        let msg = rig.validate().expect_err("rate 0").to_string();
        assert_eq!(
            msg,
            "daq.sample_rate_hz = 0 Hz: must be positive and finite"
        );

        let mut rig = RigSpec::builtin("thesis-shaker").expect("built in");
        rig.force.sample_skew_s = 1e-4;
        let msg = rig.validate().expect_err("skew").to_string();
        assert!(msg.starts_with("force.sample_skew_s = 0.0001 s"), "{msg}");

        // Through the parser: the origin is named too.
        let text = thesis_text().replace("sensitivity_v_per_n = ", "sensitivity_v_per_n = -");
        let msg = parse_err(&text);
        assert!(
            msg.starts_with("test.toml: force.sensitivity_v_per_n = -") && msg.contains("V/N"),
            "{msg}"
        );
    }

    #[test]
    fn electrodynamic_kind_needs_its_section() {
        let mut rig = RigSpec::builtin("ideal").expect("built in");
        rig.shaker.kind = ShakerKind::Electrodynamic;
        let msg = rig.validate().expect_err("missing").to_string();
        assert!(msg.contains("[shaker.electrodynamic]"), "{msg}");
    }

    #[test]
    fn expected_phase_error_matches_the_closed_form() {
        let rig = RigSpec::builtin("thesis-shaker").expect("built in");
        let (a, f) = (rig.accel_channel(), rig.force_channel());
        for freq in [20.0, 40.0, 160.0] {
            let want = (f.high_pass_hz / freq).atan() - (a.high_pass_hz / freq).atan()
                + 2.0 * PI * freq * (f.sample_skew_s - a.sample_skew_s);
            let got = rig.expected_phase_error_rad(freq);
            // Identical low-passes cancel exactly up to rounding.
            assert!((got - want).abs() < 1e-12, "{freq} Hz: {got} vs {want}");
            // "A fraction of a degree" at the thesis frequencies.
            assert!(got > 0.0 && got.to_degrees() < 1.0, "{freq} Hz: {got}");
        }
        // The high-pass + skew model is all of it, up to the 16th harmonic of
        // 1 kHz (tol 1e-12 rad).
        let model = rig.phase_error_model();
        for freq in [8.0, 40.0, 1000.0, 16_000.0] {
            let d = model.phase_error_at(freq) - rig.expected_phase_error_rad(freq);
            assert!(d.abs() < 1e-12, "{freq} Hz: {d}");
        }
        let ideal = RigSpec::builtin("ideal").expect("built in");
        assert_eq!(ideal.expected_phase_error_rad(40.0), 0.0);
    }

    #[test]
    fn only_a_rig_that_reads_exactly_skips_its_calibration() {
        let ideal = RigSpec::builtin("ideal").expect("built in");
        assert!(ideal.needs_no_calibration(40.0));
        let thesis = RigSpec::builtin("thesis-shaker").expect("built in");
        assert!(!thesis.needs_no_calibration(40.0));
    }
}
