//! The measurement chain against DEM truth (issue: rig and measurement).
//!
//! One settled thesis bed is shared by the tests; each drives a copy of it.

use std::sync::OnceLock;

use vlab::experiment::bed::settle::{SettledBed, prepare_drive, settle_bed};
use vlab::experiment::measurement::{
    CalibrationSource, ShakeExperiment, ShakeSetup, analyse, run_measured_shake,
};
use vlab::rig::{ACCEL_CHANNEL, RigFile, RigSpec, ShakerKind};
use vlab::scene::{CyclesSpec, Scene};
use vlab::signals::{PhaseCorrection, read_csv, write_csv};

fn bed() -> &'static (Scene, SettledBed) {
    static BED: OnceLock<(Scene, SettledBed)> = OnceLock::new();
    BED.get_or_init(|| {
        let scene = Scene::thesis();
        let bed = settle_bed(&scene, &mut |_| {}).expect("bed settles");
        (scene, bed)
    })
}

fn measure(
    rig: &str,
    shaker: ShakerKind,
    freq_hz: f64,
    gamma: f64,
    cycles: u32,
    steady: u32,
) -> ShakeExperiment {
    let (scene, bed) = bed();
    let mut scene = scene.clone();
    scene.drive.cycles = CyclesSpec::Count(cycles);
    scene.drive.steady_cycles = steady;
    let drive = scene.drive(freq_hz, gamma).expect("valid drive");
    let dt = scene.drive_dt_s(&drive);
    let mut world = prepare_drive(bed, &scene, dt).expect("ready to drive");
    let setup = ShakeSetup {
        rig: RigSpec::builtin(rig)
            .expect("built-in rig")
            .with_shaker(shaker),
        drive,
        noise_seed: scene.simulation.seed,
        calibration: CalibrationSource::OnTheFly,
    };
    run_measured_shake(&scene, &mut world, &setup, &mut |_| {}).expect("measured run")
}

/// Prescribed shaker through the thesis rig, calibration applied: measured
/// energy per cycle within 2 % of the DEM's dissipated energy per cycle. The
/// transient is as long as the bed needs to be steady at each condition (the
/// ledger shows it: at 160 Hz, Gamma 3, about 80 cycles); over the record the
/// measurement chain itself is checked against the DEM's input work to 1 %.
/// Without the calibration the error is the enclosure mass's leak,
/// -1/2 m_enc w V^2 sin(phi_err), within 10 %.
#[test]
fn prescribed_thesis_rig_recovers_dem_dissipation() {
    for (freq, gamma, cycles, steady) in [
        (40.0, 20.0, 8, 5),
        (20.0, 5.0, 8, 5),
        (40.0, 3.0, 20, 10),
        (160.0, 3.0, 160, 80),
    ] {
        let e = measure(
            "thesis-shaker",
            ShakerKind::Prescribed,
            freq,
            gamma,
            cycles,
            steady,
        );
        let m = &e.measured;
        let truth = e.outcome.energy_per_cycle_j;
        eprintln!(
            "{freq} Hz, Gamma {gamma}, {cycles} cycles ({steady} recorded): DEM {truth:.4e} J/cycle, measured {:+.3} % (vs input work {:+.3} %), uncorrected {:+.2} % (predicted leak {:+.2} %), efficiency DEM {:.3} measured {:.3}",
            100.0 * m.error_vs_dem_rel,
            100.0 * m.error_vs_dem_work_rel,
            100.0 * m.uncorrected_error_vs_dem_rel,
            100.0 * m.predicted_leak_per_cycle_j / truth,
            e.outcome.efficiency,
            m.efficiency
        );
        assert!(
            m.error_vs_dem_rel.abs() < 0.02,
            "{freq} Hz, Gamma {gamma}: measured {:.4e} J vs DEM {truth:.4e} J ({:+.2} %)",
            m.energy_per_cycle_j,
            100.0 * m.error_vs_dem_rel
        );
        assert!(
            m.error_vs_dem_work_rel.abs() < 0.01,
            "{freq} Hz, Gamma {gamma}: chain {:+.3} %",
            100.0 * m.error_vs_dem_work_rel
        );
        let leak = m.uncorrected_energy_per_cycle_j - m.energy_per_cycle_j;
        let rel = leak / m.predicted_leak_per_cycle_j - 1.0;
        assert!(
            rel.abs() < 0.10,
            "{freq} Hz, Gamma {gamma}: uncorrected error {leak:.3e} J vs predicted {:.3e} J",
            m.predicted_leak_per_cycle_j
        );
        assert!(m.clipping.is_empty(), "{:?}", m.clipping);
    }
}

/// The perfect lab: the DFT power of the written trace.csv equals the DEM truth
/// within 1 % (no phase error, no noise, no quantisation).
#[test]
fn ideal_rig_trace_file_gives_dem_truth() {
    let e = measure("ideal", ShakerKind::Prescribed, 40.0, 20.0, 8, 5);
    let dir = std::env::temp_dir().join(format!("vlab-ideal-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("dir");
    let path = dir.join("trace.csv");
    write_csv(&path, &e.trace).expect("write");
    let back = read_csv(&path).expect("read");
    std::fs::remove_dir_all(&dir).ok();
    let p = analyse(&back, 40.0, PhaseCorrection::None).expect("analyse");
    let truth = e.outcome.energy_per_cycle_j;
    let rel = p.energy_per_cycle_j / truth - 1.0;
    assert!(
        rel.abs() < 0.01,
        "ideal rig: {:.5e} J vs DEM {truth:.5e} J",
        p.energy_per_cycle_j
    );
    assert_eq!(
        p.energy_per_cycle_j,
        e.measured.uncorrected_energy_per_cycle_j
    );
}

/// The electrodynamic shaker: the particles' collective collisions show in the
/// acceleration (thesis Fig. 7.12), and the measurement is as good as its
/// chain allows.
///
/// The measured energy per cycle differs from the DEM's dissipation by two
/// parts: the chain (measured against the work the enclosure put in) and the
/// bed's unsteadiness over the record (work in against dissipation, which
/// the DEM ledger gives exactly). The chain's known errors here: the on-the-fly
/// calibration leaves a few µrad of the rig's 5 mrad phase error (measured
/// 6 µrad), whose leak is that fraction of the uncorrected -4.35 % (about
/// 0.005 %), and the noise and quantisation of the sensors, as much again.
/// So the chain is held to 0.05 %, five times the +0.010 % it measures; a
/// calibration off by 1 % of the phase error leaks 0.044 %, one that is
/// skipped -4.35 %. The total against the DEM is held to the bed's own
/// unsteadiness (+0.155 % over these 5 cycles) plus that 0.05 %
/// (measured +0.165 %).
#[test]
fn electrodynamic_shaker_shows_impacts_and_measures_to_its_chain() {
    let e = measure(
        "thesis-shaker",
        ShakerKind::Electrodynamic,
        40.0,
        20.0,
        8,
        5,
    );
    let m = &e.measured;
    eprintln!(
        "electrodynamic, 40 Hz, Gamma 20: measured {:+.4} % vs DEM = chain {:+.4} % and the bed's unsteadiness {:+.4} %; phase correction {:.4} mrad for the rig's {:.4} mrad; uncorrected {:+.3} %",
        100.0 * m.error_vs_dem_rel,
        100.0 * m.error_vs_dem_work_rel,
        100.0 * m.unsteadiness_rel,
        1e3 * m.phase_correction_rad,
        1e3 * m.rig_phase_error_rad,
        100.0 * m.uncorrected_error_vs_dem_rel
    );
    const CHAIN: f64 = 5e-4;
    assert!(
        m.error_vs_dem_work_rel.abs() < CHAIN,
        "chain: measured {:+.4} % vs the DEM's work in",
        100.0 * m.error_vs_dem_work_rel
    );
    assert!(
        m.error_vs_dem_rel.abs() < m.unsteadiness_rel.abs() + CHAIN,
        "measured {:+.4} % vs DEM, the bed's unsteadiness {:+.4} %",
        100.0 * m.error_vs_dem_rel,
        100.0 * m.unsteadiness_rel
    );
    // Remove the fundamental (least squares at 40 Hz): what remains is the
    // disturbance of the motion by the impacts.
    let a = &e
        .trace
        .channel(ACCEL_CHANNEL)
        .expect("acceleration")
        .samples;
    let fs = e.trace.sample_rate_hz;
    let w = 2.0 * std::f64::consts::PI * 40.0;
    let (mut ss, mut sc, mut ys, mut yc) = (0.0, 0.0, 0.0, 0.0);
    for (i, &y) in a.iter().enumerate() {
        let (s, c) = (w * i as f64 / fs).sin_cos();
        ss += s * s;
        sc += c * c;
        ys += y * s;
        yc += y * c;
    }
    let (bs, bc) = (ys / ss, yc / sc);
    let peak_residual = a
        .iter()
        .enumerate()
        .map(|(i, &y)| {
            let (s, c) = (w * i as f64 / fs).sin_cos();
            (y - bs * s - bc * c).abs()
        })
        .fold(0.0, f64::max);
    let gamma_g = 20.0 * 9.81;
    assert!(
        peak_residual > 0.10 * gamma_g,
        "impact disturbance {peak_residual:.1} m/s^2 of {gamma_g} m/s^2"
    );
    // The prescribed motion has no such disturbance beyond the sensor's noise.
    let quiet = measure("ideal", ShakerKind::Prescribed, 40.0, 20.0, 8, 5);
    let a0 = &quiet
        .trace
        .channel(ACCEL_CHANNEL)
        .expect("acceleration")
        .samples;
    let max_dev = a0
        .iter()
        .enumerate()
        .map(|(i, &y)| (y + gamma_g * (w * (i as f64 / fs + quiet.trace.start_time_s)).sin()).abs())
        .fold(0.0, f64::max);
    assert!(
        max_dev < 0.01 * gamma_g,
        "prescribed motion deviates by {max_dev} m/s^2"
    );
}
