//! One transducer and its conditioner channel as a rig file describes it:
//! [`ChannelSpec`], the same fields for every quantity (sensitivity, noise,
//! conditioner gain, AC coupling, anti-alias low-pass, skew, sampling), with
//! the quantity `Q` ([`Acceleration`], [`Force`]) naming its keys and units.
//!
//! The keys carry the quantity's unit, as every rig-file key carries its
//! unit: `[accelerometer]` has `sensitivity_v_per_mps2` and `noise_rms_mps2`,
//! `[force]` has `sensitivity_v_per_n` and `noise_rms_n`; a key of the other
//! quantity is refused as unknown.
//!
//! Two types describe a channel, one derived from the other:
//! [`ChannelSpec<Q>`] is the rig-file section, typed by its quantity so that
//! serde knows its keys and an accelerometer section cannot stand where a
//! force section is expected; [`ChannelParams`] is the same channel with the
//! quantity turned into data (its name, units and keys as text), made only by
//! [`ChannelSpec::params`] and never read from a file, so that the channel
//! (`channel.rs`), the DAQ and validation run one code path for both
//! quantities. The channel's response and its checks live on
//! [`ChannelParams`] alone.
//!
//! This file imports nothing else of the rig's specs: the shaker and drop
//! rigs (`spec.rs`, `drop_spec.rs`) build on it.

use std::f64::consts::PI;
use std::fmt;
use std::marker::PhantomData;

use realfft::num_complex::Complex64;
use serde::de::{self, MapAccess, Visitor};
use serde::ser::SerializeStruct;
use serde::{Deserialize, Deserializer, Serialize, Serializer};

use super::error::{InvalidParameter, RigError, finite, non_negative, positive};
use super::filter::{MAX_LOW_PASS_ORDER, butterworth_response, high_pass_response};
use crate::maths;

/// How a channel turns its filtered signal into samples.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Sampling {
    /// Track-and-hold at the (skewed) sample instant, linearly interpolated
    /// between DEM steps.
    #[default]
    Point,
    /// Mean over the DEM steps nearest the (skewed) sample instant, a window
    /// of one sample period centred on it: no phase lag, and an impulsive
    /// force does not alias.
    Boxcar,
}

/// An anti-alias low-pass.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LowPassSpec {
    /// -3 dB cutoff, Hz.
    pub cutoff_hz: f64,
    /// Butterworth order, 1..=8.
    pub order: u32,
}

/// The quantity a channel measures: its trace channel, units and rig-file keys.
pub trait ChannelQuantity: Copy + Default + PartialEq + fmt::Debug {
    /// Trace channel name (`acceleration`, `force`).
    const NAME: &'static str;
    /// Physical unit (`m/s^2`, `N`).
    const UNIT: &'static str;
    /// Unit of the sensitivity (`V/(m/s^2)`, `V/N`).
    const SENSITIVITY_UNIT: &'static str;
    /// Rig-file section (`accelerometer`, `force`).
    const SECTION: &'static str;
    /// Key of the sensitivity in that section.
    const SENSITIVITY_KEY: &'static str;
    /// Key of the input-referred noise in that section.
    const NOISE_KEY: &'static str;
    /// Every key of the section, in the order they are written.
    const FIELDS: &'static [&'static str];
}

/// An accelerometer on the enclosure, m/s^2.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Acceleration;

impl ChannelQuantity for Acceleration {
    const NAME: &'static str = "acceleration";
    const UNIT: &'static str = "m/s^2";
    const SENSITIVITY_UNIT: &'static str = "V/(m/s^2)";
    const SECTION: &'static str = "accelerometer";
    const SENSITIVITY_KEY: &'static str = "sensitivity_v_per_mps2";
    const NOISE_KEY: &'static str = "noise_rms_mps2";
    const FIELDS: &'static [&'static str] = &[
        "sensitivity_v_per_mps2",
        "noise_rms_mps2",
        "conditioner_gain",
        "high_pass_hz",
        "low_pass",
        "sample_skew_s",
        "sampling",
    ];
}

/// A force transducer, N.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Force;

impl ChannelQuantity for Force {
    const NAME: &'static str = "force";
    const UNIT: &'static str = "N";
    const SENSITIVITY_UNIT: &'static str = "V/N";
    const SECTION: &'static str = "force";
    const SENSITIVITY_KEY: &'static str = "sensitivity_v_per_n";
    const NOISE_KEY: &'static str = "noise_rms_n";
    const FIELDS: &'static [&'static str] = &[
        "sensitivity_v_per_n",
        "noise_rms_n",
        "conditioner_gain",
        "high_pass_hz",
        "low_pass",
        "sample_skew_s",
        "sampling",
    ];
}

/// A transducer of quantity `Q` and its conditioner channel.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ChannelSpec<Q> {
    /// Transducer sensitivity, V per unit of `Q` (`Q::SENSITIVITY_KEY`).
    pub sensitivity: f64,
    /// White noise referred to the input, rms, in units of `Q`, added per
    /// sample (`Q::NOISE_KEY`; default 0).
    pub noise_rms: f64,
    /// Conditioner gain, V/V (default 1).
    pub conditioner_gain: f64,
    /// AC-coupling high-pass corner, Hz; 0 = DC-coupled (default).
    pub high_pass_hz: f64,
    /// Anti-alias low-pass; absent = none.
    pub low_pass: Option<LowPassSpec>,
    /// Channel samples at `t_k + sample_skew_s`, s (default 0).
    pub sample_skew_s: f64,
    /// Sampling method.
    pub sampling: Sampling,
    /// The quantity (no data).
    pub quantity: Q,
}

impl<Q: ChannelQuantity> ChannelSpec<Q> {
    /// The channel in common terms.
    pub fn params(&self) -> ChannelParams {
        ChannelParams {
            name: Q::NAME,
            unit: Q::UNIT,
            sensitivity_unit: Q::SENSITIVITY_UNIT,
            section: Q::SECTION,
            sensitivity_key: Q::SENSITIVITY_KEY,
            noise_key: Q::NOISE_KEY,
            sensitivity: self.sensitivity,
            noise_rms: self.noise_rms,
            conditioner_gain: self.conditioner_gain,
            high_pass_hz: self.high_pass_hz,
            low_pass: self.low_pass,
            sample_skew_s: self.sample_skew_s,
            sampling: self.sampling,
        }
    }
}

/// One measurement channel, in common terms: what the channel (`channel.rs`)
/// runs, made by [`ChannelSpec::params`].
#[derive(Debug, Clone, PartialEq)]
pub struct ChannelParams {
    /// Trace channel name (`acceleration`, `force`).
    pub name: &'static str,
    /// Physical unit of the channel (`m/s^2`, `N`).
    pub unit: &'static str,
    /// Unit of the sensitivity (`V/(m/s^2)`, `V/N`).
    pub sensitivity_unit: &'static str,
    /// Rig-file section (`accelerometer`, `force`), for messages.
    pub section: &'static str,
    /// Keys of the sensitivity and the noise in that section.
    pub sensitivity_key: &'static str,
    pub noise_key: &'static str,
    /// Transducer sensitivity, V per physical unit.
    pub sensitivity: f64,
    /// Noise rms in physical units, referred to the input.
    pub noise_rms: f64,
    /// Conditioner gain, V/V.
    pub conditioner_gain: f64,
    /// AC-coupling corner, Hz (0 = DC-coupled).
    pub high_pass_hz: f64,
    /// Anti-alias low-pass.
    pub low_pass: Option<LowPassSpec>,
    /// Sample skew, s.
    pub sample_skew_s: f64,
    /// Sampling method.
    pub sampling: Sampling,
}

impl ChannelParams {
    /// Volts at the ADC input per physical unit at the channel input
    /// (sensitivity x conditioner gain).
    pub fn volts_per_unit(&self) -> f64 {
        self.sensitivity * self.conditioner_gain
    }

    /// The channel's analogue response at `freq_hz` (sampled at
    /// `sample_rate_hz`): high-pass x low-pass x skew `exp(j w tau)` x (boxcar
    /// sampling) `sin(pi f / fs) / (pi f / fs)`. Sensitivity and gain excluded:
    /// 1 means the trace reproduces the input.
    pub fn response(&self, freq_hz: f64, sample_rate_hz: f64) -> Complex64 {
        let mut h = high_pass_response(self.high_pass_hz, freq_hz);
        if let Some(lp) = self.low_pass {
            h *= butterworth_response(lp.order, lp.cutoff_hz, freq_hz);
        }
        h *= Complex64::from_polar(1.0, 2.0 * PI * freq_hz * self.sample_skew_s);
        if self.sampling == Sampling::Boxcar && freq_hz > 0.0 {
            let x = PI * freq_hz / sample_rate_hz;
            h *= maths::sin(x) / x;
        }
        h
    }

    /// Checks every value for a DAQ sampling at `sample_rate_hz`; the error
    /// names the rig-file key, its unit and valid range.
    pub fn validate(&self, sample_rate_hz: f64) -> Result<(), RigError> {
        let key = |k: &str| format!("{}.{k}", self.section);
        positive(
            &key(self.sensitivity_key),
            self.sensitivity,
            self.sensitivity_unit,
        )?;
        non_negative(&key(self.noise_key), self.noise_rms, self.unit)?;
        positive(&key("conditioner_gain"), self.conditioner_gain, "V/V")?;
        non_negative(&key("high_pass_hz"), self.high_pass_hz, "Hz")?;
        if let Some(lp) = self.low_pass {
            positive(&key("low_pass.cutoff_hz"), lp.cutoff_hz, "Hz")?;
            if !(1..=MAX_LOW_PASS_ORDER).contains(&lp.order) {
                return Err(RigError::from(InvalidParameter::new(
                    key("low_pass.order"),
                    lp.order,
                    "",
                    format!("an integer in 1..={MAX_LOW_PASS_ORDER}"),
                )));
            }
            if lp.cutoff_hz <= self.high_pass_hz {
                return Err(RigError::from(InvalidParameter::new(
                    key("low_pass.cutoff_hz"),
                    lp.cutoff_hz,
                    "Hz",
                    format!(
                        "above the high-pass corner {} Hz ({})",
                        self.high_pass_hz,
                        key("high_pass_hz")
                    ),
                )));
            }
        }
        finite(&key("sample_skew_s"), self.sample_skew_s, "s")?;
        let period = 1.0 / sample_rate_hz;
        if self.sample_skew_s.abs() >= 0.5 * period {
            return Err(RigError::from(InvalidParameter::new(
                key("sample_skew_s"),
                self.sample_skew_s,
                "s",
                format!(
                    "less than half a sample period ({} s at daq.sample_rate_hz = {} Hz) in magnitude",
                    0.5 * period,
                    sample_rate_hz
                ),
            )));
        }
        Ok(())
    }
}

impl<Q: ChannelQuantity> Serialize for ChannelSpec<Q> {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        let mut st = s.serialize_struct(Q::SECTION, Q::FIELDS.len())?;
        st.serialize_field(Q::SENSITIVITY_KEY, &self.sensitivity)?;
        st.serialize_field(Q::NOISE_KEY, &self.noise_rms)?;
        st.serialize_field("conditioner_gain", &self.conditioner_gain)?;
        st.serialize_field("high_pass_hz", &self.high_pass_hz)?;
        match &self.low_pass {
            Some(lp) => st.serialize_field("low_pass", lp)?,
            None => st.skip_field("low_pass")?,
        }
        st.serialize_field("sample_skew_s", &self.sample_skew_s)?;
        st.serialize_field("sampling", &self.sampling)?;
        st.end()
    }
}

impl<'de, Q: ChannelQuantity> Deserialize<'de> for ChannelSpec<Q> {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        d.deserialize_struct(Q::SECTION, Q::FIELDS, ChannelVisitor(PhantomData))
    }
}

/// Reads a channel section's keys, refusing unknown and repeated ones.
struct ChannelVisitor<Q>(PhantomData<Q>);

impl<'de, Q: ChannelQuantity> Visitor<'de> for ChannelVisitor<Q> {
    type Value = ChannelSpec<Q>;

    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "the [{}] section of a rig", Q::SECTION)
    }

    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<Self::Value, A::Error> {
        fn once<T, E: de::Error>(slot: &mut Option<T>, key: &'static str, v: T) -> Result<(), E> {
            if slot.is_some() {
                return Err(E::duplicate_field(key));
            }
            *slot = Some(v);
            Ok(())
        }
        let mut sensitivity = None;
        let mut noise_rms = None;
        let mut conditioner_gain = None;
        let mut high_pass_hz = None;
        let mut low_pass = None;
        let mut sample_skew_s = None;
        let mut sampling = None;
        while let Some(key) = map.next_key::<String>()? {
            match key.as_str() {
                k if k == Q::SENSITIVITY_KEY => {
                    once(&mut sensitivity, Q::SENSITIVITY_KEY, map.next_value()?)?
                }
                k if k == Q::NOISE_KEY => once(&mut noise_rms, Q::NOISE_KEY, map.next_value()?)?,
                "conditioner_gain" => {
                    once(&mut conditioner_gain, "conditioner_gain", map.next_value()?)?
                }
                "high_pass_hz" => once(&mut high_pass_hz, "high_pass_hz", map.next_value()?)?,
                "low_pass" => once(&mut low_pass, "low_pass", map.next_value()?)?,
                "sample_skew_s" => once(&mut sample_skew_s, "sample_skew_s", map.next_value()?)?,
                "sampling" => once(&mut sampling, "sampling", map.next_value()?)?,
                other => return Err(de::Error::unknown_field(other, Q::FIELDS)),
            }
        }
        Ok(ChannelSpec {
            sensitivity: sensitivity.ok_or_else(|| de::Error::missing_field(Q::SENSITIVITY_KEY))?,
            noise_rms: noise_rms.unwrap_or(0.0),
            conditioner_gain: conditioner_gain.unwrap_or(1.0),
            high_pass_hz: high_pass_hz.unwrap_or(0.0),
            low_pass: low_pass.unwrap_or(None),
            sample_skew_s: sample_skew_s.unwrap_or(0.0),
            sampling: sampling.unwrap_or_default(),
            quantity: Q::default(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[derive(Debug, Serialize, Deserialize, PartialEq)]
    struct Both {
        accelerometer: ChannelSpec<Acceleration>,
        force: ChannelSpec<Force>,
    }

    #[test]
    fn keys_carry_the_quantitys_unit_and_round_trip() {
        let text = "[accelerometer]\nsensitivity_v_per_mps2 = 0.01\n\n[force]\nsensitivity_v_per_n = 0.1\nnoise_rms_n = 0.002\nlow_pass = { cutoff_hz = 5000.0, order = 4 }\n";
        let both: Both = toml::from_str(text).expect("parses");
        assert_eq!(both.accelerometer.sensitivity, 0.01);
        assert_eq!(both.accelerometer.conditioner_gain, 1.0);
        assert_eq!(both.force.noise_rms, 0.002);
        assert_eq!(both.force.low_pass.map(|l| l.order), Some(4));
        let printed = toml::to_string_pretty(&both).expect("prints");
        assert!(printed.contains("sensitivity_v_per_n = 0.1"), "{printed}");
        assert!(!printed.contains("low_pass = {") || printed.contains("cutoff_hz"));
        assert_eq!(toml::from_str::<Both>(&printed).expect("reads back"), both);
        // The other quantity's key, a key twice, a missing sensitivity.
        let wrong =
            "[accelerometer]\nsensitivity_v_per_n = 0.01\n\n[force]\nsensitivity_v_per_n = 0.1\n";
        let err = toml::from_str::<Both>(wrong).expect_err("force key in the accelerometer");
        assert!(err.to_string().contains("sensitivity_v_per_n"), "{err}");
        let missing =
            "[accelerometer]\nnoise_rms_mps2 = 0.0\n\n[force]\nsensitivity_v_per_n = 0.1\n";
        let err = toml::from_str::<Both>(missing).expect_err("no sensitivity");
        assert!(err.to_string().contains("sensitivity_v_per_mps2"), "{err}");
    }
}
