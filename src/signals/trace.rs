//! Multichannel, uniformly sampled records: what a DAQ or an oscilloscope
//! hands the lab.
//!
//! A [`Trace`] is a sample rate, the time of its first sample and a set of
//! named channels of equal length, each with its physical unit (SI: `N`,
//! `m/s^2`, ...), plus free-form [`TraceMetadata`] (rig, drive, transducer
//! sensitivities). No thesis equation lives here; this is the container the
//! analyses of eq. 7.3-7.5 (drop test) and 7.8-7.12 (Yang power) read from.
//!
//! Sample `i` is taken at `start_time_s + i / sample_rate_hz`; the record
//! covers `len() / sample_rate_hz` seconds. Samples are always finite:
//! [`Trace::add_channel`] refuses NaN and infinities, and [`Trace::validate`]
//! re-checks a trace whose public fields were edited by hand.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use super::error::{InvalidParameter, Result, SignalsError, all_finite, positive_finite};

/// One named signal of a [`Trace`].
#[derive(Debug, Clone, PartialEq)]
pub struct Channel {
    /// Channel name, unique within its trace (e.g. `force`).
    pub name: String,
    /// Physical unit of the samples (e.g. `N`, `m/s^2`); empty if unknown.
    pub unit: String,
    /// Samples in `unit`, one per sample period.
    pub samples: Vec<f64>,
}

/// A transducer sensitivity, e.g. 10.2 mV/(m/s^2), kept for provenance.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Sensitivity {
    /// Numerical value in `unit`.
    pub value: f64,
    /// Unit of the sensitivity, e.g. `mV/(m/s^2)` or `mV/N`.
    pub unit: String,
}

/// Where a trace came from and under which conditions it was taken.
///
/// Every field has a default, so `{}` is a valid metadata JSON object;
/// unknown keys are rejected (put free-form data into `extra`).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct TraceMetadata {
    /// Who or what produced the record (`vlab shake`, `oscilloscope`, ...).
    pub source: String,
    /// Rig name (e.g. `thesis-shaker`, `drop-test`).
    pub rig: String,
    /// Drive frequency of a harmonic test, in Hz.
    pub drive_freq_hz: Option<f64>,
    /// Dimensionless drive acceleration amplitude Gamma (peak acceleration / g).
    pub gamma: Option<f64>,
    /// Transducer sensitivities by channel name.
    pub sensitivities: BTreeMap<String, Sensitivity>,
    /// Anything else, as JSON values.
    pub extra: BTreeMap<String, serde_json::Value>,
}

/// A multichannel, uniformly sampled record.
#[derive(Debug, Clone, PartialEq)]
pub struct Trace {
    /// Samples per second, positive and finite.
    pub sample_rate_hz: f64,
    /// Time of sample 0, in s.
    pub start_time_s: f64,
    /// Channels, all of the same length, with unique names.
    pub channels: Vec<Channel>,
    /// Provenance and test conditions.
    pub metadata: TraceMetadata,
}

impl Trace {
    /// An empty trace; `sample_rate_hz` must be positive and finite,
    /// `start_time_s` finite.
    pub fn new(sample_rate_hz: f64, start_time_s: f64) -> Result<Self> {
        positive_finite("sample_rate_hz", sample_rate_hz, "Hz")?;
        if !start_time_s.is_finite() {
            return Err(SignalsError::from(InvalidParameter::new(
                "start_time_s",
                start_time_s,
                "s",
                "finite",
            )));
        }
        Ok(Self {
            sample_rate_hz,
            start_time_s,
            channels: Vec::new(),
            metadata: TraceMetadata::default(),
        })
    }

    /// Appends a channel. The name must be non-empty and new, the length equal
    /// to that of the channels already present, and every sample finite.
    pub fn add_channel(
        &mut self,
        name: impl Into<String>,
        unit: impl Into<String>,
        samples: Vec<f64>,
    ) -> Result<()> {
        let name = name.into();
        if name.trim().is_empty() {
            return Err(SignalsError::BadChannelName {
                name,
                problem: "empty".into(),
            });
        }
        if self.channels.iter().any(|c| c.name == name) {
            return Err(SignalsError::BadChannelName {
                name,
                problem: "already used in this trace".into(),
            });
        }
        if let Some(first) = self.channels.first()
            && first.samples.len() != samples.len()
        {
            return Err(SignalsError::LengthMismatch {
                first: format!("channel '{}'", first.name),
                first_len: first.samples.len(),
                second: format!("new channel '{name}'"),
                second_len: samples.len(),
            });
        }
        all_finite(&name, &samples)?;
        self.channels.push(Channel {
            name,
            unit: unit.into(),
            samples,
        });
        Ok(())
    }

    /// The channel called `name`.
    pub fn channel(&self, name: &str) -> Result<&Channel> {
        self.channels
            .iter()
            .find(|c| c.name == name)
            .ok_or_else(|| SignalsError::ChannelNotFound {
                name: name.to_string(),
                available: self.channel_names().join(", "),
            })
    }

    /// Channel names in order.
    pub fn channel_names(&self) -> Vec<&str> {
        self.channels.iter().map(|c| c.name.as_str()).collect()
    }

    /// Samples per channel (0 for a trace without channels).
    pub fn len(&self) -> usize {
        self.channels.first().map_or(0, |c| c.samples.len())
    }

    /// True when the trace holds no samples.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Sample period, in s.
    pub fn sample_period_s(&self) -> f64 {
        1.0 / self.sample_rate_hz
    }

    /// Duration covered by the record, `len() / sample_rate_hz`, in s.
    pub fn duration_s(&self) -> f64 {
        self.len() as f64 / self.sample_rate_hz
    }

    /// Time of sample `i`, `start_time_s + i / sample_rate_hz`, in s.
    pub fn time_s(&self, i: usize) -> f64 {
        self.start_time_s + i as f64 / self.sample_rate_hz
    }

    /// The record from its first sample at or after `t_s` (on its own time
    /// axis) to the end, with the time axis moved so that `t_s` becomes 0.
    pub fn from_time(&self, t_s: f64) -> Trace {
        let fs = self.sample_rate_hz;
        let skip = self.first_at(t_s);
        let mut start = self.start_time_s + skip as f64 / fs - t_s;
        if (start * fs).abs() < 1e-6 {
            start = 0.0;
        }
        self.samples(skip, self.len(), start)
    }

    /// The index of the first sample at or after `t_s` (the length past the
    /// end); within a millionth of a sample of `t_s` counts as at it.
    fn first_at(&self, t_s: f64) -> usize {
        let k = ((t_s - self.start_time_s) * self.sample_rate_hz - 1e-6).ceil();
        (k.max(0.0) as usize).min(self.len())
    }

    /// Samples `first..end` of every channel, the first at `start_time_s`.
    fn samples(&self, first: usize, end: usize, start_time_s: f64) -> Trace {
        Trace {
            sample_rate_hz: self.sample_rate_hz,
            start_time_s,
            channels: self
                .channels
                .iter()
                .map(|c| Channel {
                    name: c.name.clone(),
                    unit: c.unit.clone(),
                    samples: c.samples[first..end].to_vec(),
                })
                .collect(),
            metadata: self.metadata.clone(),
        }
    }

    /// The samples from the first at or after `from_s` to the last before
    /// `to_s` (on its own time axis, which the window keeps).
    pub fn window(&self, from_s: f64, to_s: f64) -> Trace {
        let (first, end) = (self.first_at(from_s), self.first_at(to_s));
        let start_time_s = self.start_time_s + first as f64 / self.sample_rate_hz;
        self.samples(first, end.max(first), start_time_s)
    }

    /// Re-checks the invariants: rate positive and finite, start time finite,
    /// names unique and non-empty, lengths equal, every sample finite.
    pub fn validate(&self) -> Result<()> {
        Trace::new(self.sample_rate_hz, self.start_time_s)?;
        let mut seen = std::collections::BTreeSet::new();
        for c in &self.channels {
            let problem = if c.name.trim().is_empty() {
                Some("empty")
            } else if !seen.insert(c.name.as_str()) {
                Some("already used in this trace")
            } else {
                None
            };
            if let Some(problem) = problem {
                return Err(SignalsError::BadChannelName {
                    name: c.name.clone(),
                    problem: problem.into(),
                });
            }
            if c.samples.len() != self.len() {
                return Err(SignalsError::LengthMismatch {
                    first: format!("channel '{}'", self.channels[0].name),
                    first_len: self.len(),
                    second: format!("channel '{}'", c.name),
                    second_len: c.samples.len(),
                });
            }
            all_finite(&c.name, &c.samples)?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn two_channel() -> Trace {
        let mut t = Trace::new(1000.0, 0.5).expect("valid rate");
        t.add_channel("force", "N", vec![1.0, 2.0, 3.0])
            .expect("first channel");
        t.add_channel("acceleration", "m/s^2", vec![0.0, -1.0, 0.5])
            .expect("second channel");
        t
    }

    #[test]
    fn rejects_bad_sample_rates_with_the_parameter_named() {
        for bad in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            let err = Trace::new(bad, 0.0).expect_err("must reject");
            let msg = err.to_string();
            assert!(msg.contains("sample_rate_hz"), "{msg}");
            assert!(msg.contains("positive and finite"), "{msg}");
        }
        assert!(Trace::new(1.0, f64::NAN).is_err());
    }

    #[test]
    fn times_and_duration() {
        let t = two_channel();
        assert_eq!(t.len(), 3);
        // Exact: 0.5 + 2/1000 is computed the same way the method does.
        assert_eq!(t.time_s(2), 0.5 + 2.0 / 1000.0);
        assert_eq!(t.duration_s(), 3.0 / 1000.0);
        assert_eq!(t.channel_names(), vec!["force", "acceleration"]);
    }

    #[test]
    fn add_channel_checks_length_uniqueness_and_finiteness() {
        let mut t = two_channel();
        assert!(matches!(
            t.add_channel("short", "N", vec![1.0]),
            Err(SignalsError::LengthMismatch { .. })
        ));
        assert!(matches!(
            t.add_channel("force", "N", vec![1.0, 2.0, 3.0]),
            Err(SignalsError::BadChannelName { .. })
        ));
        let err = t
            .add_channel("v", "m/s", vec![1.0, f64::NAN, 3.0])
            .expect_err("NaN");
        assert_eq!(
            err.to_string(),
            "channel 'v' sample 1 is NaN: samples must be finite"
        );
        assert_eq!(t.channels.len(), 2, "failed adds must not modify the trace");
    }

    #[test]
    fn a_window_keeps_its_samples_and_their_times() {
        let t = two_channel();
        // Samples at 0.500, 0.501, 0.502 s: [0.501, 0.502) holds the middle.
        let w = t.window(0.501, 0.502);
        assert_eq!(w.channel("force").expect("kept").samples, vec![2.0]);
        assert_eq!(w.start_time_s, t.time_s(1));
        // Past either end: clipped; reversed: empty.
        assert_eq!(t.window(0.0, 9.0).channels, t.channels);
        assert!(t.window(0.502, 0.501).is_empty());
    }

    #[test]
    fn channel_lookup_names_what_exists() {
        let t = two_channel();
        assert_eq!(t.channel("force").expect("exists").unit, "N");
        let msg = t.channel("velocity").expect_err("absent").to_string();
        assert!(
            msg.contains("'velocity'") && msg.contains("force, acceleration"),
            "{msg}"
        );
    }

    #[test]
    fn validate_finds_hand_made_damage() {
        let mut t = two_channel();
        assert!(t.validate().is_ok());
        t.channels[1].samples[2] = f64::INFINITY;
        let msg = t.validate().expect_err("inf").to_string();
        assert!(msg.contains("'acceleration' sample 2 is inf"), "{msg}");
        let mut t = two_channel();
        t.channels[1].samples.pop();
        assert!(matches!(
            t.validate(),
            Err(SignalsError::LengthMismatch { .. })
        ));
        let mut t = two_channel();
        t.channels[1].name = "force".into();
        assert!(matches!(
            t.validate(),
            Err(SignalsError::BadChannelName { .. })
        ));
    }

    #[test]
    fn metadata_defaults_and_rejects_unknown_keys() {
        let m: TraceMetadata = serde_json::from_str("{}").expect("empty object is valid");
        assert_eq!(m, TraceMetadata::default());
        assert!(serde_json::from_str::<TraceMetadata>(r#"{"rigg": "x"}"#).is_err());
    }
}
