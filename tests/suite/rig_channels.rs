//! End to end through the rig and the lab's post-processing: known motions and
//! forces go into a rig's DAQ, the trace comes out, and `signals` (Yang's
//! power, eq. 7.9-7.12; the empty-enclosure calibration of Fig. 7.9) must
//! recover the power that was put in, with and without the rig's phase error.

use std::f64::consts::PI;

use vlab::drive::Drive;
use vlab::rig::{
    ACCEL_CHANNEL, Daq, EnclosureMotion, FORCE_CHANNEL, RigFile, RigSpec, Shaker, ShakerKind,
    transducer_force_n,
};
use vlab::signals::{
    PhaseCorrection, PowerOptions, Trace, TraceMetadata, estimate_phase_error, yang_power_of_trace,
};

const G: f64 = 9.81;
const DT: f64 = 1e-6;
const M_ENC: f64 = 0.25;

/// 40 Hz, Gamma 20: a = -A sin wt, v = V cos wt.
const FREQ: f64 = 40.0;
const GAMMA: f64 = 20.0;

fn w() -> f64 {
    2.0 * PI * FREQ
}

fn v_amp() -> f64 {
    GAMMA * G / w()
}

/// Pushes `duration_s` of the synthetic enclosure a = -A sin wt with the
/// gauge force m_enc a + f_d cos wt + W into `rig`, recording from `start_s`.
fn synthetic(rig: &RigSpec, f_d: f64, start_s: f64, duration_s: f64, seed: u64) -> Trace {
    synthetic_at(rig, DT, f_d, start_s, duration_s, seed)
}

/// [`synthetic`] with DEM step `dt_s`.
fn synthetic_at(
    rig: &RigSpec,
    dt_s: f64,
    f_d: f64,
    start_s: f64,
    duration_s: f64,
    seed: u64,
) -> Trace {
    let mut daq = Daq::new(rig, dt_s, start_s, seed).expect("valid DAQ");
    daq.reserve(duration_s - start_s);
    let steps = (duration_s / dt_s).round() as u64;
    let amp = GAMMA * G;
    for n in 1..=steps {
        let t = n as f64 * dt_s;
        let (s, c) = (w() * t).sin_cos();
        let a = -amp * s;
        daq.push(t, a, M_ENC * a + f_d * c + M_ENC * G);
    }
    let meta = TraceMetadata {
        drive_freq_hz: Some(FREQ),
        gamma: Some(GAMMA),
        ..Default::default()
    };
    let (trace, report) = daq.finish(meta).expect("finish");
    assert!(!report.any_clipped(), "{report:?}");
    trace
}

fn power(trace: &Trace, correction: PhaseCorrection<'_>) -> f64 {
    let options = PowerOptions {
        phase_correction: correction,
        ..Default::default()
    };
    yang_power_of_trace(trace, FORCE_CHANNEL, ACCEL_CHANNEL, FREQ, &options)
        .expect("power")
        .power_w
}

/// F_d for 1 W of true power: P = F_d V / 2.
fn f_d_for_one_watt() -> f64 {
    2.0 / v_amp()
}

#[test]
fn ideal_rig_gives_the_true_power() {
    let rig = RigSpec::builtin("ideal").expect("built in");
    let f_d = f_d_for_one_watt();
    let trace = synthetic(&rig, f_d, 0.025, 0.225, 1);
    assert_eq!(trace.len(), 8000, "8 whole periods");
    assert_eq!(trace.start_time_s, 0.0);
    let p = power(&trace, PhaseCorrection::None);
    // Both channels are boxcar means over 25 steps of 1 us centred on the
    // sample: the same real gain sin(25 x) / (25 sin x), x = w dt / 2, on each.
    let x = w() * DT / 2.0;
    let gain = (25.0 * x).sin() / (25.0 * x.sin());
    let want = 0.5 * f_d * v_amp() * gain * gain;
    assert!((p / want - 1.0).abs() < 1e-6, "P = {p} W, want {want} W");
    assert!((p - 1.0).abs() < 1e-5, "P = {p} W");
}

#[test]
fn ideal_rig_with_a_step_that_does_not_divide_the_sample_period() {
    // A Rayleigh-derived DEM step, 1.7 us: boxcar windows hold 14 or 15 steps
    // and their centres wander by up to dt/2 around the sample instants, a
    // jitter with no systematic phase.
    let rig = RigSpec::builtin("ideal").expect("built in");
    let f_d = f_d_for_one_watt();
    let trace = synthetic_at(&rig, 1.7e-6, f_d, 0.025, 0.225, 1);
    let p = power(&trace, PhaseCorrection::None);
    assert!((p - 1.0).abs() < 1e-4, "P = {p} W");
    let empty = synthetic_at(&rig, 1.7e-6, 0.0, 0.025, 0.225, 1);
    let p0 = power(&empty, PhaseCorrection::None);
    assert!(p0.abs() < 1e-4, "empty enclosure takes {p0} W");
}

#[test]
fn same_seed_same_bits() {
    let rig = RigSpec::builtin("thesis-shaker").expect("built in");
    let a = synthetic(&rig, 1.0, 0.01, 0.03, 9);
    let b = synthetic(&rig, 1.0, 0.01, 0.03, 9);
    let c = synthetic(&rig, 1.0, 0.01, 0.03, 10);
    let bits = |t: &Trace| -> Vec<u64> {
        t.channels
            .iter()
            .flat_map(|ch| ch.samples.iter().map(|x| x.to_bits()))
            .collect()
    };
    assert_eq!(bits(&a), bits(&b));
    assert_ne!(bits(&a), bits(&c), "another seed, other noise");
}

#[test]
fn thesis_rig_phase_error_leaks_the_enclosure_term_and_calibration_removes_it() {
    let rig = RigSpec::builtin("thesis-shaker").expect("built in");
    let phi = rig.expected_phase_error_rad(FREQ);
    let f_d = f_d_for_one_watt();
    let p_true = 0.5 * f_d * v_amp();
    // 4 cycles of run-in, then 8 recorded: as a short DEM run would.
    let (start, end) = (0.1, 0.3);

    // Uncorrected: the enclosure term leaks -1/2 m_enc w V^2 sin(phi) (~ -0.1 W).
    let damped = synthetic(&rig, f_d, start, end, 2);
    let p_raw = power(&damped, PhaseCorrection::None);
    let leak = -0.5 * M_ENC * w() * v_amp().powi(2) * phi.sin();
    assert!(
        leak.abs() > 0.05 * p_true,
        "the test needs a visible leak: {leak}"
    );
    let err = p_raw - p_true;
    assert!(
        (err / leak - 1.0).abs() < 0.1,
        "error {err} W vs predicted {leak} W"
    );

    // The lab's remedy: measure the phase error on the empty enclosure of the
    // same rig (another noise seed), subtract it.
    let empty = synthetic(&rig, 0.0, start, end, 3);
    let point = estimate_phase_error(
        &empty.channel(FORCE_CHANNEL).expect("force").samples,
        &empty.channel(ACCEL_CHANNEL).expect("accel").samples,
        empty.sample_rate_hz,
        FREQ,
    )
    .expect("calibration");
    assert!(
        (point.phase_error_rad - phi).abs() < 2e-4,
        "calibration {} rad vs the rig's {phi} rad",
        point.phase_error_rad
    );
    let p_cal = power(&damped, PhaseCorrection::Constant(point.phase_error_rad));
    assert!(
        (p_cal / p_true - 1.0).abs() < 0.01,
        "calibrated {p_cal} W vs true {p_true} W (uncorrected {p_raw} W)"
    );
}

/// Drives the thesis rig's electrodynamic shaker with a viscous "damper"
/// (F_p = -c v) on the enclosure; returns the trace and the true mean power
/// c mean(v^2) over the recorded span.
fn electrodynamic_run(c_n_s_per_m: f64, start_s: f64, end_s: f64, seed: u64) -> (Trace, f64) {
    let rig = RigSpec::builtin("thesis-shaker").expect("built in");
    let drive = Drive::new(FREQ, GAMMA, G).expect("valid drive");
    let mut shaker =
        Shaker::new(&rig, ShakerKind::Electrodynamic, &drive, M_ENC, 0.0).expect("within limits");
    let mut daq = Daq::new(&rig, DT, start_s, seed).expect("valid DAQ");
    let steps = (end_s / DT).round() as u64;
    let (mut f_p, mut work, mut n_rec) = (0.0, 0.0, 0u64);
    for n in 1..=steps {
        let t = n as f64 * DT;
        shaker.advance(t, DT, f_p);
        let k = shaker.kinematics();
        let force = transducer_force_n(M_ENC, k.acceleration_mps2, f_p, M_ENC * G);
        daq.push(t, k.acceleration_mps2, force);
        if t > start_s {
            work += -f_p * k.velocity_mps;
            n_rec += 1;
        }
        f_p = -c_n_s_per_m * k.velocity_mps;
    }
    let report = shaker.report();
    assert!(
        (report.achieved_gamma.expect("whole cycles") / GAMMA - 1.0).abs() < 0.01,
        "{report:?}"
    );
    let (trace, daq_report) = daq.finish(TraceMetadata::default()).expect("finish");
    assert!(!daq_report.any_clipped());
    (trace, work / n_rec as f64)
}

#[test]
fn electrodynamic_chain_measures_a_known_dissipation_after_calibration() {
    let rig = RigSpec::builtin("thesis-shaker").expect("built in");
    let (start, end) = (0.1, 0.3);
    let (empty, p_empty) = electrodynamic_run(0.0, start, end, 4);
    assert_eq!(p_empty, 0.0);
    let point = estimate_phase_error(
        &empty.channel(FORCE_CHANNEL).expect("force").samples,
        &empty.channel(ACCEL_CHANNEL).expect("accel").samples,
        empty.sample_rate_hz,
        FREQ,
    )
    .expect("calibration");
    let phi = rig.expected_phase_error_rad(FREQ);
    assert!(
        (point.phase_error_rad - phi).abs() < 2e-4,
        "{point:?} vs {phi}"
    );

    // c = 3.3 N s/m dissipates ~1 W at V = 0.78 m/s.
    let (damped, p_true) = electrodynamic_run(3.3, start, end, 5);
    assert!((p_true - 1.0).abs() < 0.05, "true power {p_true} W");
    let p = power(&damped, PhaseCorrection::Constant(point.phase_error_rad));
    assert!(
        (p / p_true - 1.0).abs() < 0.01,
        "measured {p} W vs true {p_true} W"
    );
}
