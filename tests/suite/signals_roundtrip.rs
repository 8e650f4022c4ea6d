//! End to end through files, the way a lab would use `vlab::signals` on its
//! own records: calibrate the phase error on empty-enclosure runs, save the
//! table, store a damper run as CSV and as WAV, read everything back and
//! recover the dissipated power and efficiency.

#![cfg(all(feature = "cli", feature = "plot"))]

use std::f64::consts::PI;
use std::path::PathBuf;

use vlab::signals::{
    PhaseCalibration, PhaseCorrection, PowerOptions, Series, SeriesStyle, Trace, efficiency,
    estimate_phase_error, plot_xy_svg, read_csv, read_wav, write_csv, write_wav,
    yang_power_of_trace,
};

const FS: f64 = 40_000.0;
const G: f64 = 9.81;
const M_ENCLOSURE_KG: f64 = 0.3;
/// The rig's force channel runs this far ahead of the acceleration channel.
const TAU_S: f64 = 35e-6;

fn scratch() -> PathBuf {
    let dir = std::env::temp_dir().join(format!("vlab-signals-it-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("scratch dir");
    dir
}

/// A vertical run at `freq_hz`, `gamma`: enclosure acceleration
/// a = Gamma g cos(wt); the transducer reads m_enc a + damping c v + a
/// reactive third harmonic + the static weight, advanced by TAU_S.
/// Returns the trace and the true dissipated power 1/2 c V^2.
fn run(freq_hz: f64, gamma: f64, damping_ns_per_m: f64, periods: usize) -> (Trace, f64) {
    let w = 2.0 * PI * freq_hz;
    let a_amp = gamma * G;
    let v_amp = a_amp / w;
    let n = (periods as f64 * FS / freq_hz).round() as usize;
    let force_at = |t: f64| {
        M_ENCLOSURE_KG * a_amp * (w * t).cos()
            + damping_ns_per_m * v_amp * (w * t).sin()
            + 0.4 * (3.0 * w * t + 0.3).cos()
            + (M_ENCLOSURE_KG + 0.0279) * G
    };
    let time = |i: usize| i as f64 / FS;
    let mut trace = Trace::new(FS, 0.0).expect("trace");
    trace
        .add_channel(
            "force",
            "N",
            (0..n).map(|i| force_at(time(i) + TAU_S)).collect(),
        )
        .expect("force");
    trace
        .add_channel(
            "acceleration",
            "m/s^2",
            (0..n).map(|i| a_amp * (w * time(i)).cos()).collect(),
        )
        .expect("acceleration");
    trace.metadata.rig = "thesis-shaker".into();
    trace.metadata.drive_freq_hz = Some(freq_hz);
    trace.metadata.gamma = Some(gamma);
    (trace, 0.5 * damping_ns_per_m * v_amp * v_amp)
}

#[test]
fn calibrate_store_reload_and_measure() {
    let dir = scratch();

    // 1. Empty-enclosure calibration at three frequencies and three amplitudes.
    let mut points = Vec::new();
    for freq in [20.0, 40.0, 80.0] {
        for gamma in [5.0, 10.0, 20.0] {
            let (t, _) = run(freq, gamma, 0.0, 8);
            let f = &t.channel("force").expect("force").samples;
            let a = &t.channel("acceleration").expect("accel").samples;
            points.push(estimate_phase_error(f, a, FS, freq).expect("point"));
        }
    }
    let cal_path = dir.join("phase-calibration.json");
    PhaseCalibration::from_points("thesis-shaker", &points)
        .expect("table")
        .save_json(&cal_path)
        .expect("save");
    let cal = PhaseCalibration::load_json(&cal_path).expect("load");
    assert_eq!(cal.points.len(), 3);
    // Each entry is w tau (tol 1e-6 rad); the third harmonic and the static
    // weight sit in other bins and do not disturb it.
    for e in &cal.points {
        assert!((e.phase_error_rad - 2.0 * PI * e.freq_hz * TAU_S).abs() < 1e-6);
    }

    // 2. A damper run at 40 Hz, Gamma 20, true dissipation about 1 W.
    let (trace, true_power_w) = run(40.0, 20.0, 3.3, 40);
    let csv = dir.join("run.csv");
    let wav = dir.join("run.wav");
    write_csv(&csv, &trace).expect("csv");
    write_wav(&wav, &trace).expect("wav");
    let from_csv = read_csv(&csv).expect("read csv");
    let from_wav = read_wav(&wav).expect("read wav");
    assert_eq!(from_csv, trace, "CSV is lossless");
    assert_eq!(from_wav.metadata, trace.metadata);

    let corrected = PowerOptions {
        phase_correction: PhaseCorrection::Table(&cal),
        ..PowerOptions::default()
    };
    let raw = yang_power_of_trace(
        &from_csv,
        "force",
        "acceleration",
        40.0,
        &PowerOptions::default(),
    )
    .expect("raw");
    let fixed = yang_power_of_trace(&from_csv, "force", "acceleration", 40.0, &corrected)
        .expect("corrected");
    // Uncorrected, the 0.5 deg error costs a large share of the answer.
    assert!(
        (raw.power_w - true_power_w).abs() > 0.1 * true_power_w,
        "{}",
        raw.power_w
    );
    // Corrected: exact to 1e-6 relative from CSV (bit-identical samples) ...
    assert!(
        (fixed.power_w - true_power_w).abs() < 1e-6 * true_power_w,
        "{} vs {true_power_w}",
        fixed.power_w
    );
    // ... and to 1e-4 from WAV (f32 rounding of a 60 N mass-term signal).
    let from_wav_power = yang_power_of_trace(&from_wav, "force", "acceleration", 40.0, &corrected)
        .expect("wav power");
    assert!((from_wav_power.power_w - true_power_w).abs() < 1e-4 * true_power_w);

    // 3. Efficiency, eq. 7.7 with eq. 6.10 (tol 1e-12 relative).
    let eta = efficiency(fixed.energy_per_cycle_j, 0.0279, 20.0, 40.0, G).expect("eta");
    let e_max = 4.0 * (20.0 * G / (2.0 * PI * 40.0)).powi(2) * 0.0279;
    assert!((eta - fixed.power_w / 40.0 / e_max).abs() < 1e-12 * eta);

    // 4. A plot of the per-harmonic power.
    let svg = dir.join("harmonics.svg");
    let points: Vec<(f64, f64)> = fixed
        .per_harmonic
        .iter()
        .map(|h| (h.freq_hz, h.power_w))
        .collect();
    plot_xy_svg(
        &svg,
        "power per drive harmonic",
        "frequency [Hz]",
        "power [W]",
        &[Series {
            name: "40 Hz, Gamma 20".into(),
            points,
            style: SeriesStyle::Points,
        }],
    )
    .expect("plot");
    assert!(std::fs::metadata(&svg).expect("svg").len() > 1000);

    // No temporary files are left behind by the atomic writes.
    for entry in std::fs::read_dir(&dir).expect("list") {
        let name = entry
            .expect("entry")
            .file_name()
            .to_string_lossy()
            .into_owned();
        assert!(!name.starts_with('.'), "leftover temporary {name}");
    }
    std::fs::remove_dir_all(dir).ok();
}
