//! The drop rig's hardware at work: the plate on its transducer ([`Plate`])
//! read through one [`MeasurementChannel`] (sensitivity, conditioner filters,
//! sampling, noise, ADC), ticking on a fixed clock (thesis Section 7.3, Fig.
//! 7.3-7.4: the force record from which impacts are found).
//!
//! The rig runs on its own fixed tick, which the scene chooses (a fraction of
//! the contact duration and of the sample period): the channel's filters are
//! discretised at that tick, so it must not change. The scene may step the DEM
//! in longer strides during free flight and tick the rig several times per DEM
//! step with the sphere's force (then zero) held. Each [`DropRig::tick`] is O(1)
//! and does not allocate once [`DropRig::reserve`] has sized the record.
//!
//! The record starts at the release (t = 0), sample `k` at `k / fs`; its single
//! channel is `force` (N), the transducer's reading (compression positive).

use super::file::RigFile;
use serde_json::json;

use super::channel::MeasurementChannel;
use super::channel_spec::Sampling;
use super::drop_spec::DropRigSpec;
use super::error::RigError;
use super::noise::GaussianNoise;
use super::plate::Plate;
use crate::signals::{Sensitivity, Trace, TraceMetadata};

/// Name of the force channel in a drop record.
pub const DROP_FORCE_CHANNEL: &str = "force";

/// What the drop rig saw, for the caller's report.
#[derive(Debug, Clone, PartialEq)]
pub struct DropRigReport {
    /// Samples in the trace.
    pub samples: usize,
    /// Sample rate, Hz.
    pub sample_rate_hz: f64,
    /// Samples clipped at the ADC's limits.
    pub clipped: u64,
    /// Largest |ADC input| as a fraction of full scale.
    pub peak_fraction_of_full_scale: f64,
    /// ADC full scale, N.
    pub full_scale_n: f64,
    /// Largest transducer force before the channel, N.
    pub peak_transducer_force_n: f64,
}

/// Plate, transducer channel and clock of one drop test.
#[derive(Debug, Clone)]
pub struct DropRig {
    spec: DropRigSpec,
    plate: Plate,
    channel: MeasurementChannel,
    tick_s: f64,
    ticks: u64,
    seed: u64,
    peak_force_n: f64,
    non_finite: Option<(f64, f64)>,
}

impl DropRig {
    /// The rig of `spec` ticking every `tick_s` (at most one sample period),
    /// channel noise from `seed`. The plate starts at rest and the channel
    /// takes its first sample at t = 0.
    pub fn new(spec: &DropRigSpec, tick_s: f64, seed: u64) -> Result<DropRig, RigError> {
        spec.validate()?;
        spec.daq.check_step("tick_s", tick_s)?;
        let mut channel = MeasurementChannel::new(
            &spec.force_channel(),
            &spec.daq,
            tick_s,
            0.0,
            GaussianNoise::new(seed, 0),
        )?;
        channel.push(0.0, 0.0);
        Ok(DropRig {
            spec: spec.clone(),
            plate: Plate::from_spec(spec)?,
            channel,
            tick_s,
            ticks: 0,
            seed,
            peak_force_n: 0.0,
            non_finite: None,
        })
    }

    /// Reserves room for `duration_s` of record.
    pub fn reserve(&mut self, duration_s: f64) {
        self.channel.reserve(duration_s);
    }

    /// One tick with the sphere's force on the plate `force_on_plate_n` (along
    /// +z, negative while it pushes down) held over it; returns the plate's
    /// displacement at the end of the tick, m.
    #[inline]
    pub fn tick(&mut self, force_on_plate_n: f64) -> f64 {
        let x = self.plate.advance(self.tick_s, force_on_plate_n);
        self.ticks += 1;
        let t = self.time_s();
        let f = self.plate.transducer_force_n();
        if !f.is_finite() || !force_on_plate_n.is_finite() {
            if self.non_finite.is_none() {
                self.non_finite = Some((force_on_plate_n, t));
            }
            return x;
        }
        self.peak_force_n = self.peak_force_n.max(f.abs());
        self.channel.push(t, f);
        x
    }

    /// Time of the last tick from the release, s.
    #[inline]
    pub fn time_s(&self) -> f64 {
        self.ticks as f64 * self.tick_s
    }

    /// Ticks taken.
    pub fn ticks(&self) -> u64 {
        self.ticks
    }

    /// The tick, s.
    pub fn tick_s(&self) -> f64 {
        self.tick_s
    }

    /// The plate.
    pub fn plate(&self) -> &Plate {
        &self.plate
    }

    /// The rig description.
    pub fn spec(&self) -> &DropRigSpec {
        &self.spec
    }

    /// Ends the record: the trace (channel `force`, N, from t = 0) with
    /// `metadata` completed by the rig's settings, and a report.
    pub fn finish(mut self, metadata: TraceMetadata) -> Result<(Trace, DropRigReport), RigError> {
        if let Some((value, t_s)) = self.non_finite {
            return Err(RigError::NonFinite {
                what: "the force on the plate",
                value,
                t_s,
            });
        }
        self.channel.flush();
        let samples = self.channel.samples().to_vec();
        if samples.len() < 2 {
            return Err(RigError::EmptyRecord {
                reason: format!(
                    "{} samples after {} s of ticks",
                    samples.len(),
                    self.time_s()
                ),
            });
        }
        let fs = self.spec.daq.sample_rate_hz;
        let start = self.channel.first_k().unwrap_or(0) as f64 / fs;
        let mut trace = Trace::new(fs, start)?;
        trace.add_channel(DROP_FORCE_CHANNEL, "N", samples)?;
        trace.metadata = self.metadata(metadata);
        let report = DropRigReport {
            samples: trace.len(),
            sample_rate_hz: fs,
            clipped: self.channel.clipped(),
            peak_fraction_of_full_scale: self.channel.peak_fraction_of_full_scale(),
            full_scale_n: self.channel.full_scale_units(),
            peak_transducer_force_n: self.peak_force_n,
        };
        Ok((trace, report))
    }

    fn metadata(&self, mut m: TraceMetadata) -> TraceMetadata {
        let p = self.channel.params();
        m.rig = self.spec.name.clone();
        m.sensitivities.insert(
            DROP_FORCE_CHANNEL.to_string(),
            Sensitivity {
                value: p.sensitivity,
                unit: p.sensitivity_unit.to_string(),
            },
        );
        m.extra.insert(
            "rig_channels".into(),
            json!({ DROP_FORCE_CHANNEL: {
                "unit": p.unit,
                "conditioner_gain": p.conditioner_gain,
                "high_pass_hz": p.high_pass_hz,
                "low_pass": p.low_pass.map(|lp| json!({"cutoff_hz": lp.cutoff_hz, "order": lp.order})),
                "sampling": match p.sampling { Sampling::Point => "point", Sampling::Boxcar => "boxcar" },
                "noise_rms": p.noise_rms,
                "full_scale": self.channel.full_scale_units(),
                "clipped_samples": self.channel.clipped(),
            }}),
        );
        let d = &self.spec.daq;
        m.extra.insert(
            "rig_adc".into(),
            json!({"bits": d.bits, "full_scale_v": d.full_scale_v, "ideal": d.ideal_adc}),
        );
        m.extra.insert(
            "rig_plate".into(),
            json!({
                "mass_kg": self.plate.mass_kg(),
                "natural_freq_hz": self.plate.natural_freq_hz(),
                "damping_ratio": self.plate.damping_ratio(),
            }),
        );
        m.extra.insert("rig_tick_s".into(), json!(self.tick_s));
        m.extra.insert("rig_noise_seed".into(), json!(self.seed));
        m
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rig::DROP_RIG;

    #[test]
    fn a_hammer_blow_is_recorded_at_its_time_and_the_rest_is_noise() {
        let spec = DropRigSpec::builtin(DROP_RIG).expect("built in");
        let tick = 0.3125e-6;
        let mut rig = DropRig::new(&spec, tick, 5).expect("valid");
        rig.reserve(0.02);
        let (t0, width, j) = (0.010, 30e-6, 1e-4);
        let n = (0.02 / tick).round() as u64;
        for _ in 0..n {
            let t = rig.time_s() + 0.5 * tick;
            let f = if (t0..t0 + width).contains(&t) {
                -j / width
            } else {
                0.0
            };
            rig.tick(f);
        }
        let (trace, report) = rig.finish(TraceMetadata::default()).expect("record");
        assert_eq!(trace.start_time_s, 0.0);
        assert_eq!(trace.len(), 4001, "0 to 20 ms at 200 kHz");
        assert_eq!(report.clipped, 0);
        let x = &trace.channel(DROP_FORCE_CHANNEL).expect("force").samples;
        // Before the blow: noise of 5 mN rms (quantisation step 13.6 mN adds
        // its 3.9 mN in quadrature); 2000 samples, so within 10 %.
        let quiet = &x[..1990];
        let rms = (quiet.iter().map(|v| v * v).sum::<f64>() / quiet.len() as f64).sqrt();
        let want = (0.005f64.powi(2) + (20.0 / 65536.0 / 0.0225f64).powi(2) / 12.0).sqrt();
        assert!((rms / want - 1.0).abs() < 0.1, "rms {rms} vs {want}");
        // The first sample above 0.5 N lies within the first pulse.
        let first = x.iter().position(|&v| v > 0.5).expect("blow recorded");
        let t = trace.time_s(first);
        assert!(t > t0 && t < t0 + 60e-6, "first sample above 0.5 N at {t}");
        // The peak is near J w_n less the damping: 5-6.3 N.
        let peak = x.iter().copied().fold(0.0, f64::max);
        assert!(peak > 4.5 && peak < 6.4, "{peak}");
    }

    #[test]
    fn tick_longer_than_a_sample_is_refused() {
        let spec = DropRigSpec::builtin(DROP_RIG).expect("built in");
        let err = DropRig::new(&spec, 1e-5, 1).expect_err("too coarse");
        assert!(err.to_string().starts_with("tick_s = 0.00001 s"), "{err}");
    }
}
