//! One measurement channel of the rig (thesis Section 7.4.2, Fig. 7.7 items
//! 3, 4, 6, 7): transducer, signal conditioner, digitiser.
//!
//! The chain, run once per DEM step:
//!
//! 1. physical quantity `x` (m/s^2 or N) x transducer sensitivity (V per unit)
//!    x conditioner gain (V/V) = volts `v`;
//! 2. AC-coupling first-order high-pass (corner in Hz, 0 = DC-coupled), then
//!    the anti-alias Butterworth low-pass, both discretised by Tustin at the
//!    DEM step ([`super::filter`]); the filters start in the steady state of
//!    a constant input, as a conditioner that has been on for hours (the static
//!    weight on the force gauge causes no start transient): the level given to
//!    [`MeasurementChannel::settle_at`] before the first push, else the first
//!    input;
//! 3. sampling at the DAQ rate, sample `k` at `t_k + skew`, `t_k = k / fs`:
//!    [`Sampling::Point`] interpolates linearly between the two DEM steps
//!    around the instant; [`Sampling::Boxcar`] averages the DEM steps nearest
//!    the instant (those with `round((t - skew) fs) = k`, a centred window of
//!    one sample period, no phase lag);
//! 4. white Gaussian noise, rms given in physical units referred to the
//!    input, added per sample, so a silent input records exactly that rms
//!    (before quantisation);
//! 5. ADC: `code = round(v / LSB)`, `LSB = 2 FS / 2^bits`, codes clipped to
//!    `-2^(bits-1) ..= 2^(bits-1) - 1` and the clipped samples counted; or an
//!    ideal ADC (no quantisation, no clipping);
//! 6. back to physical units, `code LSB / (gain sensitivity)`, as the lab's
//!    software does with the nominal sensitivity.
//!
//! The "ideal" channel of the `ideal` rig is this chain with no filters, no
//! noise, boxcar sampling and an ideal ADC: the mean of the input over each
//! sample period, centred.
//!
//! [`MeasurementChannel::push`] does O(1) work and does not allocate once
//! [`MeasurementChannel::reserve`] has sized the record.

use super::channel_spec::{ChannelParams, Sampling};
use super::error::{InvalidParameter, RigError, positive};
use super::filter::{Biquad, Cascade};
use super::noise::GaussianNoise;
use super::spec::DaqSpec;

/// The ADC's quantiser.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Adc {
    /// One code step, V.
    pub lsb_v: f64,
    /// Lowest code.
    pub min_code: i64,
    /// Highest code.
    pub max_code: i64,
}

impl Adc {
    /// A `bits`-bit converter of range +-`full_scale_v`; `bits` is clamped to
    /// 1..=32 ([`DaqSpec::validate`] refuses anything else).
    pub fn new(bits: u32, full_scale_v: f64) -> Self {
        let bits = bits.clamp(1, 32);
        let half = 1i64 << (bits - 1);
        Adc {
            lsb_v: 2.0 * full_scale_v / (1u64 << bits) as f64,
            min_code: -half,
            max_code: half - 1,
        }
    }

    /// Quantises `v`: the voltage of its code and whether it was clipped.
    #[inline]
    pub fn convert(&self, v: f64) -> (f64, bool) {
        let code = (v / self.lsb_v).round();
        let clipped = code > self.max_code as f64 || code < self.min_code as f64;
        let code = code.clamp(self.min_code as f64, self.max_code as f64);
        (code * self.lsb_v, clipped)
    }
}

/// One channel: its filters, sampler, noise, ADC and record.
#[derive(Debug, Clone)]
pub struct MeasurementChannel {
    params: ChannelParams,
    dt_s: f64,
    period_s: f64,
    k_start: i64,
    filters: Cascade,
    volts_per_unit: f64,
    noise_v: f64,
    noise: GaussianNoise,
    adc: Option<Adc>,
    full_scale_v: f64,
    started: bool,
    /// The filters were settled by [`Self::settle_at`] before the first push.
    preset: bool,
    prev_t: f64,
    prev_y: f64,
    next_k: i64,
    win_k: i64,
    win_sum: f64,
    win_n: u32,
    win_whole: bool,
    last_t: f64,
    first_k: Option<i64>,
    samples: Vec<f64>,
    clipped: u64,
    peak_v: f64,
}

impl MeasurementChannel {
    /// A channel of `params` digitised by `daq`, stepped every `dem_dt_s`,
    /// keeping samples at or after `record_start_s` (from the drive start),
    /// drawing noise from `noise`. Checks `params` and `daq` first.
    pub fn new(
        params: &ChannelParams,
        daq: &DaqSpec,
        dem_dt_s: f64,
        record_start_s: f64,
        noise: GaussianNoise,
    ) -> Result<Self, RigError> {
        daq.validate()?;
        params.validate(daq.sample_rate_hz)?;
        positive("dem_dt_s", dem_dt_s, "s")?;
        let period_s = 1.0 / daq.sample_rate_hz;
        let mut filters = Cascade::new();
        if params.high_pass_hz > 0.0 {
            filters.push(Biquad::high_pass_1(params.high_pass_hz, dem_dt_s));
        }
        if let Some(lp) = params.low_pass {
            let nyquist = 0.5 / dem_dt_s;
            if lp.cutoff_hz >= nyquist {
                return Err(RigError::from(InvalidParameter::new(
                    format!("{}.low_pass.cutoff_hz", params.section),
                    lp.cutoff_hz,
                    "Hz",
                    format!(
                        "below half the DEM step rate, 1 / (2 dem_dt_s) = {nyquist} Hz, to be \
                         simulated at dem_dt_s = {dem_dt_s} s"
                    ),
                )));
            }
            filters.push_butterworth(lp.order, lp.cutoff_hz, dem_dt_s);
        }
        Ok(MeasurementChannel {
            dt_s: dem_dt_s,
            period_s,
            k_start: (record_start_s / period_s - 1e-9).ceil() as i64,
            filters,
            volts_per_unit: params.volts_per_unit(),
            noise_v: params.noise_rms * params.volts_per_unit(),
            noise,
            adc: (!daq.ideal_adc).then(|| Adc::new(daq.bits, daq.full_scale_v)),
            full_scale_v: daq.full_scale_v,
            started: false,
            preset: false,
            prev_t: 0.0,
            prev_y: 0.0,
            next_k: 0,
            win_k: 0,
            win_sum: 0.0,
            win_n: 0,
            win_whole: false,
            last_t: 0.0,
            first_k: None,
            samples: Vec::new(),
            clipped: 0,
            peak_v: 0.0,
            params: params.clone(),
        })
    }

    /// Reserves room for `duration_s` of record, so that [`Self::push`] does
    /// not allocate.
    pub fn reserve(&mut self, duration_s: f64) {
        if duration_s.is_finite() && duration_s > 0.0 {
            let n = (duration_s / self.period_s).ceil() as usize + 2;
            self.samples.reserve(n.saturating_sub(self.samples.len()));
        }
    }

    /// The channel's parameters.
    pub fn params(&self) -> &ChannelParams {
        &self.params
    }

    /// Settles the filters at the constant input `x` (physical units), as if
    /// the channel had seen it for hours, before the first
    /// [`Self::push`] (which otherwise settles them at its own value). For a
    /// record that starts with a transient, `x` is the level the
    /// conditioner had settled to before it: the record's mean. No effect
    /// once pushing has started.
    pub fn settle_at(&mut self, x: f64) {
        if !self.started {
            self.filters.settle_dc(x * self.volts_per_unit);
            self.preset = true;
        }
    }

    /// Feeds the value `x` (physical units) at time `t_s` (one DEM step after
    /// the previous call).
    #[inline]
    pub fn push(&mut self, t_s: f64, x: f64) {
        let v = x * self.volts_per_unit;
        let skew = self.params.sample_skew_s;
        if !self.started {
            self.started = true;
            if !self.preset {
                self.filters.settle_dc(v);
            }
            self.prev_t = t_s;
            self.next_k = self
                .k_start
                .max(((t_s - skew) / self.period_s).ceil() as i64);
            let k = ((t_s - skew) / self.period_s).round() as i64;
            self.win_k = k;
            // The first window is whole only if the previous step would have
            // belonged to an earlier one.
            self.win_whole = (((t_s - self.dt_s - skew) / self.period_s).round() as i64) < k;
        }
        let y = self.filters.process(v);
        match self.params.sampling {
            Sampling::Point => {
                loop {
                    let s = self.next_k as f64 * self.period_s + skew;
                    if s > t_s {
                        break;
                    }
                    let span = t_s - self.prev_t;
                    let frac = if span > 0.0 {
                        ((s - self.prev_t) / span).clamp(0.0, 1.0)
                    } else {
                        1.0
                    };
                    let value = self.prev_y + frac * (y - self.prev_y);
                    self.emit(self.next_k, value);
                    self.next_k += 1;
                }
                self.prev_t = t_s;
                self.prev_y = y;
            }
            Sampling::Boxcar => {
                let k = ((t_s - skew) / self.period_s).round() as i64;
                if k != self.win_k {
                    self.close_window();
                    self.win_k = k;
                    self.win_whole = true;
                }
                self.win_sum += y;
                self.win_n += 1;
            }
        }
        self.last_t = t_s;
    }

    fn close_window(&mut self) {
        if self.win_whole && self.win_n > 0 {
            let mean = self.win_sum / f64::from(self.win_n);
            self.emit(self.win_k, mean);
        }
        self.win_sum = 0.0;
        self.win_n = 0;
    }

    /// Ends the record: a boxcar window that the next step would have closed
    /// is complete and kept; a partial one is dropped.
    pub fn flush(&mut self) {
        if self.started && self.params.sampling == Sampling::Boxcar {
            let next = ((self.last_t + self.dt_s - self.params.sample_skew_s) / self.period_s)
                .round() as i64;
            if next != self.win_k {
                self.close_window();
            }
            self.win_n = 0;
        }
    }

    #[inline]
    fn emit(&mut self, k: i64, volts: f64) {
        if k < self.k_start {
            return;
        }
        let v = if self.noise_v > 0.0 {
            volts + self.noise_v * self.noise.next_gaussian()
        } else {
            volts
        };
        self.peak_v = self.peak_v.max(v.abs());
        let v = match &self.adc {
            Some(adc) => {
                let (q, clipped) = adc.convert(v);
                self.clipped += u64::from(clipped);
                q
            }
            None => v,
        };
        if self.first_k.is_none() {
            self.first_k = Some(k);
        }
        self.samples.push(v / self.volts_per_unit);
    }

    /// Index `k` (sample time `k / fs` from the drive start) of the first
    /// recorded sample.
    pub fn first_k(&self) -> Option<i64> {
        self.first_k
    }

    /// Recorded samples in physical units, consecutive from [`Self::first_k`].
    pub fn samples(&self) -> &[f64] {
        &self.samples
    }

    /// Recorded samples that hit the ADC's limits.
    pub fn clipped(&self) -> u64 {
        self.clipped
    }

    /// Largest |voltage| at the ADC input (noise included) as a fraction of
    /// full scale.
    pub fn peak_fraction_of_full_scale(&self) -> f64 {
        self.peak_v / self.full_scale_v
    }

    /// Full scale in physical units, `FS / (gain sensitivity)`.
    pub fn full_scale_units(&self) -> f64 {
        self.full_scale_v / self.volts_per_unit
    }

    /// One ADC step in physical units (`None` for an ideal ADC).
    pub fn step_units(&self) -> Option<f64> {
        self.adc.map(|a| a.lsb_v / self.volts_per_unit)
    }

    /// The digital response of this channel's filters at `freq_hz`.
    pub fn filter_response(&self, freq_hz: f64) -> realfft::num_complex::Complex64 {
        self.filters.response(freq_hz, self.dt_s)
    }
}

#[cfg(test)]
mod tests {
    use std::f64::consts::PI;

    use super::*;
    use crate::rig::RigFile;
    use crate::rig::channel_spec::LowPassSpec;
    use crate::rig::spec::RigSpec;

    const DT: f64 = 1e-6;

    fn thesis() -> RigSpec {
        RigSpec::builtin("thesis-shaker").expect("built in")
    }

    /// Runs `input(t)` through a channel for `duration_s` from t = dt.
    fn run(
        params: &ChannelParams,
        daq: &DaqSpec,
        record_start_s: f64,
        duration_s: f64,
        input: impl Fn(f64) -> f64,
    ) -> MeasurementChannel {
        let mut ch =
            MeasurementChannel::new(params, daq, DT, record_start_s, GaussianNoise::new(1, 0))
                .expect("valid channel");
        let steps = (duration_s / DT).round() as u64;
        for n in 1..=steps {
            let t = n as f64 * DT;
            ch.push(t, input(t));
        }
        ch.flush();
        ch
    }

    /// Complex amplitude of `freq_hz` in samples taken at `t0 + i / fs`
    /// (whole periods assumed): `x = Im(X e^{j w t})`.
    fn phasor(samples: &[f64], t0: f64, fs: f64, freq_hz: f64) -> realfft::num_complex::Complex64 {
        let w = 2.0 * PI * freq_hz;
        let (mut s, mut c) = (0.0, 0.0);
        for (i, x) in samples.iter().enumerate() {
            let (sn, cs) = (w * (t0 + i as f64 / fs)).sin_cos();
            s += x * sn;
            c += x * cs;
        }
        let n = samples.len() as f64;
        realfft::num_complex::Complex64::new(2.0 * s / n, 2.0 * c / n)
    }

    fn quiet(mut p: ChannelParams) -> ChannelParams {
        p.noise_rms = 0.0;
        p
    }

    #[test]
    fn ideal_channel_returns_a_sinusoid_exactly() {
        let rig = RigSpec::builtin("ideal").expect("built in");
        let f = 40.0;
        let w = 2.0 * PI * f;
        let ch = run(&rig.force_channel(), &rig.daq, 0.0, 0.1, |t| {
            3.0 * (w * t).sin()
        });
        // The boxcar of 25 steps centred on t_k: gain sin(25 x)/(25 sin x), x = w dt / 2.
        let x = w * DT / 2.0;
        let gain = (25.0 * x).sin() / (25.0 * x.sin());
        assert_eq!(ch.first_k(), Some(1), "sample 0 has no whole window");
        for (i, y) in ch.samples().iter().enumerate() {
            let t = (i + 1) as f64 / 40_000.0;
            let want = 3.0 * gain * (w * t).sin();
            assert!((y - want).abs() < 1e-12, "sample {i}: {y} vs {want}");
        }
        assert_eq!(
            ch.samples().len(),
            3999,
            "0.1 s less the partial first window"
        );
        assert_eq!(ch.clipped(), 0);
    }

    #[test]
    fn thesis_channel_amplitude_and_filter_phase_at_40_hz() {
        let rig = thesis();
        let p = quiet(rig.force_channel());
        let (f, amp) = (40.0, 100.0);
        let w = 2.0 * PI * f;
        // Skip 2 s so the AC coupling's start transient (tau = 0.45 s) has
        // decayed below 1e-4 of the amplitude; analyse 1 s (40 periods).
        let ch = run(&p, &rig.daq, 2.0, 3.0, |t| amp * (w * t).sin());
        let t0 = ch.first_k().expect("samples") as f64 / 40_000.0;
        let got = phasor(&ch.samples()[..40_000], t0, 40_000.0, f);
        let want = p.response(f, 40_000.0);
        // Amplitude within 0.5 % of the input (the filters lose < 1e-4 at 40 Hz).
        assert!((got.norm() / amp - 1.0).abs() < 0.005, "{}", got.norm());
        // Filters (high-pass lead, low-pass lag) and the 5 us skew, against the
        // analogue formula.
        let phase_err = (got.arg() - want.arg()).abs();
        assert!(
            phase_err < 1e-4,
            "phase {} vs {} rad",
            got.arg(),
            want.arg()
        );
        let hp_lp_only = want.arg() - w * p.sample_skew_s;
        let analytic = (0.35f64 / 40.0).atan()
            + super::super::filter::butterworth_response(4, 1e4, 40.0).arg();
        assert!((hp_lp_only - analytic).abs() < 1e-12);
    }

    #[test]
    fn skew_gives_omega_tau() {
        let rig = RigSpec::builtin("ideal").expect("built in");
        let mut p = rig.force_channel();
        p.sampling = Sampling::Point;
        let f = 160.0;
        let w = 2.0 * PI * f;
        for tau in [0.0, 2.5e-6, 5e-6, -7.3e-6] {
            p.sample_skew_s = tau;
            let ch = run(&p, &rig.daq, 0.0, 0.1, |t| (w * t).sin());
            let t0 = ch.first_k().expect("samples") as f64 / 40_000.0;
            let got = phasor(&ch.samples()[..3750], t0, 40_000.0, f);
            // Linear interpolation between 1 us steps: phase error ~ (w dt)^2 / 8.
            assert!(
                (got.arg() - w * tau).abs() < 1e-6,
                "tau {tau}: {}",
                got.arg()
            );
        }
    }

    #[test]
    fn quantisation_step_is_one_lsb_in_physical_units() {
        let rig = thesis();
        let mut p = quiet(rig.accel_channel());
        p.high_pass_hz = 0.0;
        p.low_pass = None;
        let ch = run(&p, &rig.daq, 0.0, 0.01, |t| {
            50.0 * (2.0 * PI * 40.0 * t).sin()
        });
        let lsb = 20.0 / 65536.0;
        let step = lsb / (5.0 * 0.00102);
        assert_eq!(ch.step_units(), Some(step));
        for y in ch.samples() {
            let codes = y / step;
            assert!(
                (codes - codes.round()).abs() < 1e-9,
                "{y} is not on the grid"
            );
        }
        // Within half a step of the input.
        for (i, y) in ch.samples().iter().enumerate() {
            let t = (ch.first_k().expect("k") + i as i64) as f64 / 40_000.0;
            let x = 50.0 * (2.0 * PI * 40.0 * t).sin();
            assert!((y - x).abs() <= 0.5 * step + 1e-9, "{y} vs {x}");
        }
    }

    #[test]
    fn noise_rms_matches_the_spec() {
        let rig = thesis();
        let p = rig.force_channel();
        assert_eq!(p.noise_rms, 0.01);
        // 1 s of silence: 40 000 samples, rms standard error 0.35 %;
        // quantisation adds (0.0136 N)^2 / 12 in quadrature.
        let ch = run(&p, &rig.daq, 0.0, 1.0, |_| 0.0);
        let n = ch.samples().len() as f64;
        let rms = (ch.samples().iter().map(|y| y * y).sum::<f64>() / n).sqrt();
        let step = ch.step_units().expect("quantised");
        let want = (p.noise_rms.powi(2) + step * step / 12.0).sqrt();
        assert!((rms / want - 1.0).abs() < 0.1, "rms {rms} vs {want}");
        assert!((rms / p.noise_rms - 1.0).abs() < 0.1, "rms {rms} vs spec");
    }

    #[test]
    fn clipping_is_counted() {
        let rig = thesis();
        let p = quiet(rig.force_channel());
        let fs_n = 10.0 / (2.0 * 0.0112);
        // A 40 Hz sine of 1.2 x full scale for 0.1 s: clipped while |sin| > 1/1.2.
        let ch = run(&p, &rig.daq, 0.0, 0.1, |t| {
            1.2 * fs_n * (2.0 * PI * 40.0 * t).sin()
        });
        let frac = ch.clipped() as f64 / ch.samples().len() as f64;
        let want = 1.0 - 2.0 / PI * (1.0f64 / 1.2).asin();
        assert!(
            (frac - want).abs() < 0.01,
            "clipped fraction {frac} vs {want}"
        );
        let peak = ch.samples().iter().fold(0.0f64, |m, y| m.max(y.abs()));
        assert!(peak <= fs_n && peak > 0.99 * fs_n, "{peak}");
        assert!(ch.peak_fraction_of_full_scale() > 1.15);
        let below = run(&p, &rig.daq, 0.0, 0.1, |t| {
            0.9 * fs_n * (2.0 * PI * 40.0 * t).sin()
        });
        assert_eq!(below.clipped(), 0);
    }

    #[test]
    fn record_start_and_low_pass_limit() {
        let rig = RigSpec::builtin("ideal").expect("built in");
        let ch = run(&rig.accel_channel(), &rig.daq, 0.0301, 0.05, |_| 1.0);
        // First instant at or after 30.1 ms on the 25 us grid: 1204 x 25 us.
        assert_eq!(ch.first_k(), Some(1204));
        assert!(ch.samples().iter().all(|&y| (y - 1.0).abs() < 1e-12));
        let mut p = rig.accel_channel();
        p.low_pass = Some(LowPassSpec {
            cutoff_hz: 600_000.0,
            order: 2,
        });
        let err = MeasurementChannel::new(&p, &rig.daq, DT, 0.0, GaussianNoise::new(1, 0))
            .expect_err("cutoff above the DEM Nyquist rate");
        assert!(
            err.to_string().contains("accelerometer.low_pass.cutoff_hz"),
            "{err}"
        );
    }
}
