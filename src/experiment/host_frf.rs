//! The host's frequency response with the damper, measured as a lab
//! measures it (thesis Section 2.3.1): a stepped sine (each frequency driven
//! to steady state, the response's fundamental against the force's; the
//! half-power loss factor and the peak against the host without particles;
//! the power-input method) or a periodic random force (H1 and H2 with their
//! coherence, Welch-averaged over whole periods of the force).
//!
//! Every stepped-sine point also carries the truth over its record: the
//! damper's fundamental amplitude, the power the excitation put in, what the
//! host's own damping took, the work the host did on the damper and what the
//! damper dissipated, so the power-input estimate of the damper's
//! dissipation, `P_in − ½ c₁ ω² |X_d / φ₁(d)|²` (`c₁` the first mode's, from the bare host's
//! modal test), is checked against the DEM, and so is Yang's
//! structure-independent figure at the same frequency and Γ where a sweep's
//! map is given (the CLI).

use std::f64::consts::TAU;

use rayon::prelude::*;
use realfft::num_complex::Complex64;
use serde::Serialize;

use super::bed_cache::BedSource;
use super::host_test::{HostRun, HostTest, run_host_test};
use crate::host::Excitation;
use crate::rig::{ACCEL_CHANNEL, FORCE_CHANNEL};
use crate::scene::{Scene, SceneError};
use crate::signals::SignalsError;
use crate::signals::structural::{
    Frf, HalfPower, Window, half_power, power_input_w, sine_component, welch_frf,
};
use crate::validation::{Bound, InvalidParameter, count_in, in_range};

/// Harmonics the power-input method sums.
pub const POWER_HARMONICS: usize = 10;

/// How a stepped sine is run: each frequency from a steady response of the
/// host ([`super::host_test::particles_guess`] with particles),
/// `settle_cycles` to settle, then `record_cycles` measured.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SteppedSine {
    pub freqs_hz: Vec<f64>,
    pub force_n: f64,
    pub settle_cycles: u32,
    pub record_cycles: u32,
}

impl SteppedSine {
    /// Checks the plan: frequencies positive and at most 5 kHz, a positive
    /// force, at least 4 cycles recorded.
    pub fn validate(&self) -> Result<(), InvalidParameter> {
        count_in(
            "freqs_hz",
            self.freqs_hz.len(),
            "frequencies",
            1,
            Some(1000),
        )?;
        for f in &self.freqs_hz {
            in_range(
                "freq_hz",
                *f,
                "Hz",
                Bound::Open(0.0),
                Bound::Closed(5_000.0),
            )?;
        }
        in_range(
            "force_n",
            self.force_n,
            "N",
            Bound::Open(0.0),
            Bound::Closed(1e4),
        )?;
        count_in(
            "settle_cycles",
            self.settle_cycles,
            "cycles",
            0,
            Some(10_000),
        )?;
        count_in(
            "record_cycles",
            self.record_cycles,
            "cycles",
            4,
            Some(10_000),
        )?;
        Ok(())
    }
}

/// One stepped-sine point: the lab's measurement and the truth.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct FrfPoint {
    pub freq_hz: f64,
    /// Receptance at the damper per force at the drive (m/N), from the lab's
    /// channels: the acceleration's fundamental over `−ω²` against the
    /// force's.
    pub receptance_re: f64,
    pub receptance_im: f64,
    /// The damper's displacement amplitude, measured (m), and its Γ.
    pub amplitude_m: f64,
    pub gamma: f64,
    /// The same from the truth record (m).
    pub true_amplitude_m: f64,
    /// Power-input method: `⟨F v_e⟩` from the force channel and the drive
    /// point's velocity (W).
    pub power_input_w: f64,
    /// Its one-sigma error from the spread of the record's periods (W).
    pub power_input_stderr_w: f64,
    /// The damper's dissipation by the power-input method,
    /// `P_in − ½ c₁ ω² |X_d / φ₁(d)|²` (W).
    pub damper_power_w: f64,
    /// Truth over the record (W): the excitation's power, the host's own
    /// damping, the work the host did on the damper, the damper's
    /// dissipation (the DEM's ledger or the dashpot's).
    pub true_input_w: f64,
    pub true_host_w: f64,
    pub true_damper_work_w: f64,
    pub true_damper_w: f64,
    /// Change of the host's stored energy over the record per second (W):
    /// the power-input method assumes none.
    pub host_energy_drift_w: f64,
    /// The record is steady: the drift within 5 % of the input power (a
    /// granular damper's impacts move the host's energy from cycle to cycle
    /// by a few per cent even in steady state).
    pub steady: bool,
    pub steps: u64,
    pub wall_time_s: f64,
}

impl FrfPoint {
    /// The measured receptance.
    pub fn receptance(&self) -> Complex64 {
        Complex64::new(self.receptance_re, self.receptance_im)
    }
}

/// A stepped sine's points and what the lab reads off them.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SteppedSineResult {
    pub points: Vec<FrfPoint>,
    /// Largest measured receptance magnitude and its frequency.
    pub peak_freq_hz: f64,
    pub peak_m_per_n: f64,
    /// Half-power bandwidth of the measured receptance; `None` when a −3 dB
    /// crossing is outside the frequencies (the message says which).
    pub half_power: Option<HalfPower>,
    pub half_power_note: Option<String>,
    pub wall_time_s: f64,
}

/// Rates over a record from `i0` to the end of a cumulative column (per s).
fn rate(v: &[f64], i0: usize, span_s: f64) -> f64 {
    (v[v.len() - 1] - v[i0]) / span_s
}

/// One stepped-sine point of `run` (driven at `freq_hz`), its record from
/// `record_from_s` on.
fn measure_point(
    run: &HostRun,
    test: &HostTest,
    freq_hz: f64,
    record_from_s: f64,
    g_mps2: f64,
) -> Result<FrfPoint, SceneError> {
    let trace = run.trace.from_time(record_from_s);
    let rate_hz = trace.sample_rate_hz;
    let accel = &trace.channel(ACCEL_CHANNEL)?.samples;
    let force = &trace.channel(FORCE_CHANNEL)?.samples;
    let omega = TAU * freq_hz;
    let a = sine_component(accel, rate_hz, freq_hz).map_err(SignalsError::from)?;
    let f = sine_component(force, rate_hz, freq_hz).map_err(SignalsError::from)?;
    let x = a / (-omega * omega);
    let h = x / f;
    let r = &run.record;
    let i0 = r.time_s.partition_point(|t| *t < record_from_s - 1e-9);
    let true_x =
        sine_component(&r.displacement_m[i0..], rate_hz, freq_hz).map_err(SignalsError::from)?;
    // The drive point's acceleration: the damper's own where the drive is at
    // the damper (an impedance head's accelerometer), else the truth's
    // velocity differentiated (an ideal accelerometer at the drive point).
    let at_damper = test
        .host
        .modes
        .iter()
        .all(|m| m.shape_at_drive == m.shape_at_damper);
    let drive_accel: Vec<f64>;
    let (f_in, a_in): (&[f64], &[f64]) = if at_damper {
        (force, accel)
    } else {
        // d v / dt by central differences at the sample rate.
        let v = &r.drive_velocity_mps[i0..];
        let n = v.len().min(force.len());
        drive_accel = (0..n)
            .map(|k| {
                let (lo, hi) = (k.saturating_sub(1), (k + 1).min(n - 1));
                (v[hi] - v[lo]) * rate_hz / (hi - lo).max(1) as f64
            })
            .collect();
        (&force[..n], &drive_accel)
    };
    let power =
        power_input_w(f_in, a_in, rate_hz, freq_hz, POWER_HARMONICS).map_err(SignalsError::from)?;
    // Its ± : the same method on each period alone, the periods' spread
    // (crate::stats::mean_stderr), as Yang's method's is.
    // At least one whole period in each chunk (the method takes the
    // longest whole number of periods of it).
    let per_period = (rate_hz / freq_hz).ceil() as usize;
    let periods: Vec<f64> = (0..f_in.len() / per_period.max(1))
        .filter_map(|k| {
            let r = k * per_period..(k + 1) * per_period;
            power_input_w(
                &f_in[r.clone()],
                &a_in[r],
                rate_hz,
                freq_hz,
                POWER_HARMONICS,
            )
            .ok()
        })
        .collect();
    let power_stderr = crate::stats::mean_stderr(&periods)
        .stderr
        .unwrap_or(f64::NAN);
    let span = r.time_s[r.time_s.len() - 1] - r.time_s[i0];
    // Whole periods apart, the stored energy's ripple cancels.
    let periods = (span * freq_hz).floor();
    let i_end = (i0 + (periods / freq_hz * rate_hz).round() as usize).min(r.time_s.len() - 1);
    let drift = (r.host_energy_j[i_end] - r.host_energy_j[i0]) / (r.time_s[i_end] - r.time_s[i0]);
    let true_input = rate(&r.excitation_work_j, i0, span);
    // The bare host's own damping at this amplitude, as its modal test
    // gives it: the first mode's `c_r` on its modal velocity `ω X_d / φ_d`,
    // `X_d` as the lab measured it.
    let host_power = test.host.first_mode().map_or(0.0, |m| {
        let q = x.norm() / m.shape_at_damper;
        0.5 * m.damping_n_s_per_m() * omega * omega * q * q
    });
    Ok(FrfPoint {
        freq_hz,
        receptance_re: h.re,
        receptance_im: h.im,
        amplitude_m: x.norm(),
        gamma: a.norm() / g_mps2,
        true_amplitude_m: true_x.norm(),
        power_input_w: power,
        power_input_stderr_w: power_stderr,
        damper_power_w: power - host_power,
        true_input_w: true_input,
        true_host_w: rate(&r.host_dissipated_j, i0, span),
        true_damper_work_w: rate(&r.damper_work_in_j, i0, span)
            + rate(&r.dashpot_dissipated_j, i0, span),
        true_damper_w: rate(&r.damper_dissipated_j, i0, span)
            + rate(&r.dashpot_dissipated_j, i0, span),
        host_energy_drift_w: drift,
        steady: drift.abs() <= 0.05 * true_input.abs(),
        steps: run.steps,
        wall_time_s: run.wall_time_s,
    })
}

/// Runs the stepped sine `plan` of `test` (its excitation replaced by each
/// sine), the frequencies in parallel, each from the same settled bed.
pub fn run_stepped_sine(
    scene: &Scene,
    beds: &BedSource,
    test: &HostTest,
    plan: &SteppedSine,
    done: &(dyn Fn(&FrfPoint) + Sync),
) -> Result<SteppedSineResult, SceneError> {
    plan.validate()?;
    let started = crate::clock::Stopwatch::start();
    // Settle (or read) the bed once, before the frequencies share it.
    if test.damper == super::host_test::Damper::Particles {
        beds.settle(scene, &mut |_| {})?;
    }
    let g = scene.simulation.gravity_mps2;
    let points: Vec<FrfPoint> = plan
        .freqs_hz
        .par_iter()
        .map(|f| {
            let period = 1.0 / f;
            let mut t = test.clone();
            t.excitation = Excitation::Sine {
                freq_hz: *f,
                force_n: plan.force_n,
            };
            t.start_steady = true;
            t.duration_s = f64::from(plan.settle_cycles + plan.record_cycles) * period;
            let run = run_host_test(scene, beds, &t, &mut |_| {})?;
            let point = measure_point(&run, &t, *f, f64::from(plan.settle_cycles) * period, g)?;
            done(&point);
            Ok(point)
        })
        .collect::<Result<Vec<_>, SceneError>>()?;
    let (peak_freq_hz, peak_m_per_n) = points
        .iter()
        .map(|p| (p.freq_hz, p.receptance().norm()))
        .fold(
            (f64::NAN, 0.0),
            |best, p| if p.1 > best.1 { p } else { best },
        );
    let freqs: Vec<f64> = points.iter().map(|p| p.freq_hz).collect();
    let mags: Vec<f64> = points.iter().map(|p| p.receptance().norm()).collect();
    let step = freqs.windows(2).map(|w| w[1] - w[0]).fold(0.0, f64::max);
    let (half_power, half_power_note) = match half_power(&freqs, &mags) {
        Ok(h) if h.f_high_hz - h.f_low_hz < 2.0 * step => (
            None,
            Some(format!(
                "the half-power band ({:.3} Hz by interpolation) is narrower than two frequency steps ({step} Hz): step finer around {:.2} Hz",
                h.f_high_hz - h.f_low_hz,
                h.peak_freq_hz
            )),
        ),
        Ok(h) => (Some(h), None),
        Err(e) => (None, Some(e.to_string())),
    };
    Ok(SteppedSineResult {
        points,
        peak_freq_hz,
        peak_m_per_n,
        half_power,
        half_power_note,
        wall_time_s: started.elapsed().as_secs_f64(),
    })
}

/// H1, H2 and coherence of a periodic random test: blocks of one period of
/// the force (rectangular window: no leakage), the first period dropped
/// (the transient); receptance = accelerance over `−ω²`.
pub fn random_frf(run: &HostRun, period_s: f64) -> Result<Frf, SceneError> {
    let trace = run.trace.from_time(period_s);
    let rate_hz = trace.sample_rate_hz;
    let accel = &trace.channel(ACCEL_CHANNEL)?.samples;
    let force = &trace.channel(FORCE_CHANNEL)?.samples;
    let block = (period_s * rate_hz).round() as usize;
    let mut frf = welch_frf(force, accel, rate_hz, block, 0.0, Window::Rectangular)
        .map_err(SignalsError::from)?;
    for (k, f) in frf.freq_hz.iter().enumerate() {
        let w2 = (TAU * f).powi(2);
        if w2 > 0.0 {
            frf.h1[k] /= -w2;
            frf.h2[k] /= -w2;
        }
    }
    Ok(frf)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::experiment::host_test::Damper;
    use crate::host::{HostSpec, Payload};
    use crate::host::{Point, receptance};
    use crate::rig::{RigFile, RigSpec};

    fn test_of(damper: Damper, host: &str) -> HostTest {
        HostTest {
            host: HostSpec::builtin(host).expect("built in"),
            damper,
            excitation: Excitation::Release { x0_m: 1e-3 },
            duration_s: 1.0,
            start_steady: true,
            rig: RigSpec::builtin("thesis-shaker").expect("built in"),
            noise_seed: 5,
        }
    }

    #[test]
    fn a_stepped_sine_on_a_dashpot_host_recovers_its_frf_and_loss_factor() {
        // plate-40hz with a 10 N s/m dashpot: zeta = 0.003 + 10 / 251.3 =
        // 0.0428. Through the rig's channels: each point's receptance within
        // 1 % and 0.02 rad of the analytical one; the half-power loss factor
        // within 3 % of 2 zeta (0.25 Hz steps, linear interpolation); the
        // power-input estimate of the dashpot's power within 3 % of what it
        // dissipated (the truth), at every point.
        let test = test_of(Damper::Dashpot { n_s_per_m: 10.0 }, "plate-40hz");
        let freqs: Vec<f64> = (0..=48).map(|k| 34.0 + 0.25 * f64::from(k)).collect();
        let plan = SteppedSine {
            freqs_hz: freqs,
            force_n: 2.0,
            settle_cycles: 0,
            record_cycles: 20,
        };
        let result = run_stepped_sine(&Scene::thesis(), &BedSource::Settle, &test, &plan, &|_| {})
            .expect("runs");
        let m = test.host.modes[0];
        let zeta = m.damping_ratio + 10.0 / (2.0 * (m.stiffness() * m.modal_mass_kg).sqrt());
        let payload = Payload {
            mass_kg: 0.0,
            dashpot_n_s_per_m: 10.0,
        };
        for p in &result.points {
            let w = TAU * p.freq_hz;
            let s = Complex64::new(-w * w * payload.mass_kg, w * payload.dashpot_n_s_per_m);
            let want = receptance(&test.host, w, s, Point::Drive, Point::Damper);
            let got = p.receptance();
            assert!(
                (got.norm() / want.norm() - 1.0).abs() < 0.01,
                "{p:?} against {want}"
            );
            assert!(((got / want).arg()).abs() < 0.02, "{p:?} against {want}");
            assert!(
                (p.damper_power_w / p.true_damper_w - 1.0).abs() < 0.03,
                "{p:?}"
            );
        }
        let hp = result.half_power.expect("both crossings inside");
        assert!(
            (hp.loss_factor / (2.0 * zeta) - 1.0).abs() < 0.03,
            "{hp:?} against {}",
            2.0 * zeta
        );
    }

    #[test]
    fn a_periodic_random_test_gives_h1_h2_and_coherence_of_the_dashpot_host() {
        // 20-60 Hz at 1 N rms, 1 s periods, 6 s: every line within 36-44 Hz
        // with |H1| within 5 % of the analytical receptance, H1 / H2 = coherence
        // above 0.95 (the channels' noise is all that is not linear).
        let mut test = test_of(Damper::Dashpot { n_s_per_m: 10.0 }, "plate-40hz");
        test.excitation = Excitation::parse("random:20:60:1:1:4").expect("valid");
        test.duration_s = 6.0;
        test.start_steady = false;
        let run =
            run_host_test(&Scene::thesis(), &BedSource::Settle, &test, &mut |_| {}).expect("runs");
        let frf = random_frf(&run, 1.0).expect("frf");
        let mut checked = 0;
        for (k, f) in frf.freq_hz.iter().enumerate() {
            if !(36.0..=44.0).contains(f) {
                continue;
            }
            let w = TAU * f;
            let want = receptance(
                &test.host,
                w,
                Complex64::new(0.0, 10.0 * w),
                Point::Drive,
                Point::Damper,
            );
            assert!(
                (frf.h1[k].norm() / want.norm() - 1.0).abs() < 0.05,
                "{f} Hz: {} against {}",
                frf.h1[k],
                want
            );
            assert!(frf.coherence[k] > 0.95, "{f} Hz: {}", frf.coherence[k]);
            checked += 1;
        }
        assert_eq!(checked, 9);
    }
}
