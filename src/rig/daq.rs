//! The digitiser: two channels sampled together into a [`Trace`] (thesis
//! Section 7.4.2: acceleration and force recorded simultaneously at 40 kHz).
//!
//! [`Daq::push`] is called every DEM step with the time from the drive start,
//! the enclosure's acceleration and the force the transducer carries (see
//! [`super::transducer`]). Samples fall at integer multiples of the sample
//! period from the drive start; those at or after `record_start_s` are kept.
//! The trace's time zero is the record start, so its first sample lies at
//! `start_time_s` in `[0, 1/fs)` after it. [`Daq::finish`] builds the trace,
//! channels `acceleration` (m/s^2) and `force` (N), in physical units, and a
//! [`DaqReport`] that says how much was clipped.

use serde_json::json;

use super::channel::MeasurementChannel;
use super::channel_spec::{ChannelParams, Sampling};
use super::error::{RigError, non_negative};
use super::file::RigFile;
use super::noise::GaussianNoise;
use super::spec::RigSpec;
use crate::signals::{Sensitivity, Trace, TraceMetadata};
use crate::warning::RunWarning;

/// Name of the acceleration channel in the trace.
pub const ACCEL_CHANNEL: &str = "acceleration";
/// Name of the force channel in the trace.
pub const FORCE_CHANNEL: &str = "force";

/// Fewest ADC codes a channel's largest sample should span from zero
/// before [`DaqReport::low_level_warnings`] warns: 32 codes, where one
/// code's uniform error (`q / √12`) is about 1 % of the peak.
pub const LOW_LEVEL_CODES: f64 = 32.0;

/// What the DAQ saw, for the caller's report.
#[derive(Debug, Clone, PartialEq)]
pub struct DaqReport {
    /// Samples per channel in the trace.
    pub samples: usize,
    /// Sample rate, Hz.
    pub sample_rate_hz: f64,
    /// Time of the first sample after the record start, s.
    pub start_time_s: f64,
    /// Every channel, in trace order.
    pub channels: Vec<ChannelReport>,
    /// True when the ADC is ideal (no quantisation, no clipping).
    pub ideal_adc: bool,
}

/// How one channel used its ADC.
#[derive(Debug, Clone, PartialEq)]
pub struct ChannelReport {
    /// Trace channel name.
    pub name: String,
    /// Physical unit of the channel.
    pub unit: String,
    /// Samples clipped at the ADC's limits.
    pub clipped: u64,
    /// Largest |ADC input| as a fraction of full scale.
    pub peak_fraction_of_full_scale: f64,
    /// ADC full scale in the channel's physical unit.
    pub full_scale: f64,
    /// Largest |ADC input| in ADC codes (steps of the converter), of
    /// `full_scale_codes` (`2^(bits − 1)`) from zero to full scale.
    pub peak_codes: f64,
    pub full_scale_codes: f64,
}

impl DaqReport {
    /// True when any sample was clipped.
    pub fn any_clipped(&self) -> bool {
        self.channels.iter().any(|c| c.clipped > 0)
    }

    /// What the record's levels say against it: [`Self::clipping_warnings`]
    /// and [`Self::low_level_warnings`].
    pub fn level_warnings(&self) -> Vec<RunWarning> {
        [self.clipping_warnings(), self.low_level_warnings()].concat()
    }

    /// One sentence per channel whose largest sample is fewer than
    /// [`LOW_LEVEL_CODES`] ADC codes from zero: its quantisation steps are a
    /// large part of the signal and what is read from it can be off by
    /// percents (a host's acceleration at 5 Hz, 1-4 codes, read the
    /// receptance 4 % high). None for an ideal ADC.
    pub fn low_level_warnings(&self) -> Vec<RunWarning> {
        if self.ideal_adc {
            return Vec::new();
        }
        self.channels
            .iter()
            .filter(|c| c.peak_codes < LOW_LEVEL_CODES)
            .map(|c| {
                format!(
                    "{}: the largest sample is {:.1} ADC codes from zero (full scale {:.4} {} over {:.0} codes): the converter's steps are a large part of the signal and what is read from it may be off by percents; raise the conditioner gain in the rig file or the drive amplitude",
                    c.name,
                    c.peak_codes,
                    c.full_scale,
                    c.unit,
                    c.full_scale_codes
                )
                .into()
            })
            .collect()
    }

    /// One sentence per clipped channel, for a loud warning (of two ways
    /// out, gain or amplitude, so no one key lifts it).
    pub fn clipping_warnings(&self) -> Vec<RunWarning> {
        self.channels
            .iter()
            .filter(|c| c.clipped > 0)
            .map(|c| {
                format!(
                    "{}: {} of {} samples clipped at the ADC's limits (full scale {:.4} {}): the \
                     record is distorted; lower the conditioner gain in the rig file or the \
                     drive amplitude",
                    c.name, c.clipped, self.samples, c.full_scale, c.unit
                )
                .into()
            })
            .collect()
    }
}

/// The digitiser and its two channels.
#[derive(Debug, Clone)]
pub struct Daq {
    rig_name: String,
    spec: RigSpec,
    dem_dt_s: f64,
    record_start_s: f64,
    seed: u64,
    accel: MeasurementChannel,
    force: MeasurementChannel,
    pushes: u64,
    last_t: f64,
    non_finite: Option<(&'static str, f64, f64)>,
}

impl Daq {
    /// A DAQ for `spec`, stepped every `dem_dt_s` (at most one sample period),
    /// keeping samples at or after `record_start_s` from the drive start;
    /// noise drawn from `seed` (acceleration: stream 0, force: stream 1).
    pub fn new(
        spec: &RigSpec,
        dem_dt_s: f64,
        record_start_s: f64,
        seed: u64,
    ) -> Result<Daq, RigError> {
        spec.validate()?;
        spec.daq.check_step("dem_dt_s", dem_dt_s)?;
        non_negative("record_start_s", record_start_s, "s")
            .map_err(|e| e.because("time from the drive start"))?;
        let make = |p: &ChannelParams, stream| {
            MeasurementChannel::new(
                p,
                &spec.daq,
                dem_dt_s,
                record_start_s,
                GaussianNoise::new(seed, stream),
            )
        };
        Ok(Daq {
            rig_name: spec.name.clone(),
            accel: make(&spec.accel_channel(), 0)?,
            force: make(&spec.force_channel(), 1)?,
            spec: spec.clone(),
            dem_dt_s,
            record_start_s,
            seed,
            pushes: 0,
            last_t: f64::NAN,
            non_finite: None,
        })
    }

    /// Reserves room for `duration_s` of record so that [`Self::push`] never
    /// allocates.
    pub fn reserve(&mut self, duration_s: f64) {
        self.accel.reserve(duration_s);
        self.force.reserve(duration_s);
    }

    /// Settles both channels' filters at a constant acceleration (m/s^2) and
    /// transducer force (N) before the first [`Self::push`], which otherwise
    /// settles them at its own values: a record that starts with a transient
    /// (a replayed DEM record's drive-start jolt) then passes through the
    /// AC coupling as a transient, not as the level it had settled to
    /// ([`MeasurementChannel::settle_at`]).
    pub fn settle_at(&mut self, enclosure_accel_mps2: f64, transducer_force_n: f64) {
        self.accel.settle_at(enclosure_accel_mps2);
        self.force.settle_at(transducer_force_n);
    }

    /// One DEM step: time from the drive start (s), enclosure acceleration
    /// (m/s^2), force the transducer carries (N). O(1), no allocation after
    /// [`Self::reserve`].
    #[inline]
    pub fn push(&mut self, t_s: f64, enclosure_accel_mps2: f64, transducer_force_n: f64) {
        if self.non_finite.is_some() {
            return;
        }
        if !enclosure_accel_mps2.is_finite() {
            self.non_finite = Some(("the enclosure acceleration", enclosure_accel_mps2, t_s));
            return;
        }
        if !transducer_force_n.is_finite() {
            self.non_finite = Some(("the transducer force", transducer_force_n, t_s));
            return;
        }
        self.accel.push(t_s, enclosure_accel_mps2);
        self.force.push(t_s, transducer_force_n);
        self.pushes += 1;
        self.last_t = t_s;
    }

    /// The model's phase error of this rig at `freq_hz`, rad
    /// ([`RigSpec::expected_phase_error_rad`]).
    pub fn expected_phase_error_rad(&self, freq_hz: f64) -> f64 {
        self.spec.expected_phase_error_rad(freq_hz)
    }

    /// Ends the record. The trace's metadata is `metadata` with the rig name,
    /// the sensitivities and the rig's measurement settings filled in.
    pub fn finish(mut self, metadata: TraceMetadata) -> Result<(Trace, DaqReport), RigError> {
        if let Some((what, value, t_s)) = self.non_finite {
            return Err(RigError::NonFinite { what, value, t_s });
        }
        self.accel.flush();
        self.force.flush();
        let period = 1.0 / self.spec.daq.sample_rate_hz;
        let span = |c: &MeasurementChannel| c.first_k().map(|k| (k, k + c.samples().len() as i64));
        let (k0, k1) = match (span(&self.accel), span(&self.force)) {
            (Some((a0, a1)), Some((f0, f1))) => (a0.max(f0), a1.min(f1)),
            _ => (0, 0),
        };
        if k1 <= k0 {
            let reason = if self.pushes == 0 {
                "push was never called".to_string()
            } else {
                format!(
                    "the last step was at t = {} s but record_start_s = {} s (a sample needs the \
                     steps around its instant)",
                    self.last_t, self.record_start_s
                )
            };
            return Err(RigError::EmptyRecord { reason });
        }
        let cut = |c: &MeasurementChannel| -> Vec<f64> {
            let first = c.first_k().unwrap_or(k0);
            let from = (k0 - first) as usize;
            c.samples()[from..from + (k1 - k0) as usize].to_vec()
        };
        // Time of the first sample from the record start; a record that starts
        // on a sample (whole drive cycles at a whole-hertz rate) starts at 0
        // exactly, not at a rounding error of it.
        let start_time_s = {
            let t = k0 as f64 * period - self.record_start_s;
            let on_grid = (t / period).round() * period + 0.0;
            if (t - on_grid).abs() < 1e-9 * period {
                on_grid
            } else {
                t
            }
        };
        let mut trace = Trace::new(self.spec.daq.sample_rate_hz, start_time_s)?;
        trace.add_channel(ACCEL_CHANNEL, "m/s^2", cut(&self.accel))?;
        trace.add_channel(FORCE_CHANNEL, "N", cut(&self.force))?;
        trace.metadata = self.metadata(metadata);
        let channels = [&self.accel, &self.force];
        let full_scale_codes = 2f64.powi(self.spec.daq.bits as i32 - 1);
        let report = DaqReport {
            samples: trace.len(),
            sample_rate_hz: self.spec.daq.sample_rate_hz,
            start_time_s,
            channels: channels
                .iter()
                .map(|c| ChannelReport {
                    name: c.params().name.to_string(),
                    unit: c.params().unit.to_string(),
                    clipped: c.clipped(),
                    peak_fraction_of_full_scale: c.peak_fraction_of_full_scale(),
                    full_scale: c.full_scale_units(),
                    peak_codes: c.peak_fraction_of_full_scale() * full_scale_codes,
                    full_scale_codes,
                })
                .collect(),
            ideal_adc: self.spec.daq.ideal_adc,
        };
        Ok((trace, report))
    }

    fn metadata(&self, mut m: TraceMetadata) -> TraceMetadata {
        m.rig = self.rig_name.clone();
        let mut describe = |c: &MeasurementChannel| {
            let p = c.params();
            m.sensitivities.insert(
                p.name.to_string(),
                Sensitivity {
                    value: p.sensitivity,
                    unit: p.sensitivity_unit.to_string(),
                },
            );
            json!({
                "unit": p.unit,
                "conditioner_gain": p.conditioner_gain,
                "high_pass_hz": p.high_pass_hz,
                "low_pass": p.low_pass.map(|lp| json!({"cutoff_hz": lp.cutoff_hz, "order": lp.order})),
                "sample_skew_s": p.sample_skew_s,
                "sampling": match p.sampling { Sampling::Point => "point", Sampling::Boxcar => "boxcar" },
                "noise_rms": p.noise_rms,
                "full_scale": c.full_scale_units(),
                "clipped_samples": c.clipped(),
            })
        };
        let accel = describe(&self.accel);
        let force = describe(&self.force);
        let d = &self.spec.daq;
        m.extra.insert(
            "rig_channels".into(),
            json!({ ACCEL_CHANNEL: accel, FORCE_CHANNEL: force }),
        );
        m.extra.insert(
            "rig_adc".into(),
            json!({"bits": d.bits, "full_scale_v": d.full_scale_v, "ideal": d.ideal_adc}),
        );
        m.extra.insert("rig_dem_dt_s".into(), json!(self.dem_dt_s));
        m.extra
            .insert("rig_record_start_s".into(), json!(self.record_start_s));
        m.extra.insert("rig_noise_seed".into(), json!(self.seed));
        if let Some(f) = m.drive_freq_hz.filter(|f| f.is_finite() && *f > 0.0) {
            m.extra.insert(
                "rig_expected_phase_error_rad".into(),
                json!(self.spec.expected_phase_error_rad(f)),
            );
        }
        m
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn trace_layout_metadata_and_report() {
        let rig = RigSpec::builtin("thesis-shaker").expect("built in");
        let mut daq = Daq::new(&rig, 1e-6, 0.010_01, 3).expect("valid");
        daq.reserve(0.03);
        for n in 1..=30_000u32 {
            let t = f64::from(n) * 1e-6;
            daq.push(
                t,
                100.0 * (251.3 * t).sin(),
                25.0 * (251.3 * t).sin() + 2.45,
            );
        }
        let meta = TraceMetadata {
            drive_freq_hz: Some(40.0),
            ..Default::default()
        };
        let (trace, report) = daq.finish(meta).expect("finish");
        assert_eq!(trace.channel_names(), vec![ACCEL_CHANNEL, FORCE_CHANNEL]);
        assert_eq!(trace.channel(FORCE_CHANNEL).expect("force").unit, "N");
        // First sample: 401 x 25 us = 10.025 ms, 15 us after the record start.
        assert!(
            (trace.start_time_s - 15e-6).abs() < 1e-12,
            "{}",
            trace.start_time_s
        );
        assert_eq!(report.samples, trace.len());
        // Up to 30 ms: samples 401..=1200 (the force's skewed instant of 1200
        // lies after the last step, so 1199 is the last common one).
        assert_eq!(trace.len(), 799);
        assert!(!report.any_clipped());
        assert!(report.clipping_warnings().is_empty());
        let m = &trace.metadata;
        assert_eq!(m.rig, "thesis-shaker");
        assert_eq!(m.sensitivities["force"].unit, "V/N");
        assert_eq!(m.sensitivities["acceleration"].value, 0.00102);
        let phi = m.extra["rig_expected_phase_error_rad"]
            .as_f64()
            .expect("number");
        assert_eq!(phi, rig.expected_phase_error_rad(40.0));
        assert_eq!(
            m.extra["rig_channels"]["force"]["sample_skew_s"],
            json!(5e-6)
        );
    }

    #[test]
    fn refusals_name_the_problem() {
        let rig = RigSpec::builtin("ideal").expect("built in");
        let err = Daq::new(&rig, 1e-4, 0.0, 0)
            .expect_err("dt too long")
            .to_string();
        assert!(err.starts_with("dem_dt_s = 0.0001 s"), "{err}");
        let err = Daq::new(&rig, 1e-6, -1.0, 0)
            .expect_err("negative start")
            .to_string();
        assert!(err.starts_with("record_start_s = -1 s"), "{err}");

        let daq = Daq::new(&rig, 1e-6, 1.0, 0).expect("valid");
        let err = daq.finish(TraceMetadata::default()).expect_err("empty");
        assert!(err.to_string().contains("never called"), "{err}");

        let mut daq = Daq::new(&rig, 1e-6, 0.0, 0).expect("valid");
        daq.push(1e-6, 0.0, 0.0);
        daq.push(2e-6, f64::NAN, 0.0);
        let err = daq
            .finish(TraceMetadata::default())
            .expect_err("NaN")
            .to_string();
        assert!(
            err.contains("enclosure acceleration was NaN at t = 0.000002 s"),
            "{err}"
        );
    }

    #[test]
    fn clipping_reaches_the_report() {
        let rig = RigSpec::builtin("thesis-shaker").expect("built in");
        let mut daq = Daq::new(&rig, 1e-6, 0.0, 3).expect("valid");
        // 1000 N through a gauge whose full scale is 446 N.
        for n in 1..=10_000u32 {
            let t = f64::from(n) * 1e-6;
            daq.push(
                t,
                0.0,
                1000.0 * (2.0 * std::f64::consts::PI * 100.0 * t).sin(),
            );
        }
        let (_, report) = daq.finish(TraceMetadata::default()).expect("finish");
        assert!(report.any_clipped());
        let w = report.clipping_warnings();
        assert_eq!(w.len(), 1);
        assert!(
            w[0].text.starts_with("force: ") && w[0].text.contains("446.4286 N"),
            "{}",
            w[0]
        );
    }
}
