//! Lab files through `vlab analyze`, `vlab cor` and `vlab::signals`:
//!
//! - CSV of every common dialect: one record written as vlab's CSV, as a
//!   spreadsheet's `;`/decimal-comma export and as tab-separated text gives the
//!   same figures, whether the dialect is detected or named with `--delimiter`
//!   / `--decimal-comma`; what cannot be read is refused naming file and line.
//! - TDMS: the small files of `tests/fixtures/tdms/` (made once with nptdms by
//!   `make_tdms.py` there) are read or refused with the reason, and so are
//!   byte-patched copies in layouts the reader must not misread.

#![cfg(all(feature = "cli", feature = "plot"))]

use crate::common;
use crate::support::spreadsheet;

use std::f64::consts::PI;

use std::path::{Path, PathBuf};

use common::{Scratch, refuses_in, stderr, vlab};
use spreadsheet::export;
use vlab::signals::{
    SignalsError, TdmsErrorKind, Trace, read_csv, read_tdms, read_trace, write_csv, write_wav,
};

const FS: f64 = 40_000.0;

/// Four periods of a 40 Hz run: a = A cos wt, f = m a + c v + a reactive third
/// harmonic. Returns the trace and the true power 1/2 c V^2, in W.
fn record() -> (Trace, f64) {
    let (f_hz, a_amp, m_kg, c_ns_per_m) = (40.0, 196.2, 0.3, 3.3);
    let w = 2.0 * PI * f_hz;
    let v_amp = a_amp / w;
    let n = (4.0 * FS / f_hz) as usize;
    let t = |i: usize| i as f64 / FS;
    let mut trace = Trace::new(FS, 0.0).expect("trace");
    trace
        .add_channel(
            "force",
            "N",
            (0..n)
                .map(|i| {
                    m_kg * a_amp * (w * t(i)).cos()
                        + c_ns_per_m * v_amp * (w * t(i)).sin()
                        + 0.4 * (3.0 * w * t(i)).cos()
                })
                .collect(),
        )
        .expect("force");
    trace
        .add_channel(
            "acceleration",
            "m/s^2",
            (0..n).map(|i| a_amp * (w * t(i)).cos()).collect(),
        )
        .expect("acceleration");
    (trace, 0.5 * c_ns_per_m * v_amp * v_amp)
}

fn json_out(dir: &Scratch, args: &[&str]) -> serde_json::Value {
    let out = vlab(&dir.0, args);
    assert!(out.status.success(), "{args:?}: {}", stderr(&out));
    serde_json::from_slice(&out.stdout).expect("JSON on stdout")
}

fn power_of(dir: &Scratch, file: &str, extra: &[&str]) -> f64 {
    let mut args = vec!["analyze", file, "--freq", "40", "--json"];
    args.extend_from_slice(extra);
    json_out(dir, &args)["power_w"].as_f64().expect("power_w")
}

#[test]
fn analyze_reads_every_dialect_detected_or_named() {
    let dir = Scratch::new("dialects");
    let (trace, true_power_w) = record();
    write_csv(&dir.path("vlab.csv"), &trace).expect("write");
    let text = std::fs::read_to_string(dir.path("vlab.csv")).expect("read");
    let reference = power_of(&dir, "vlab.csv", &[]);
    // The record is exact to the DFT's rounding (tol 1e-9 relative).
    assert!(
        (reference - true_power_w).abs() < 1e-9 * true_power_w,
        "{reference} vs {true_power_w}"
    );
    let dialects: [(&str, &str, bool, &[&str]); 4] = [
        (
            "semicolon-comma.csv",
            ";",
            true,
            &["--delimiter", ";", "--decimal-comma"],
        ),
        (
            "tab-comma.csv",
            "\t",
            true,
            &["--delimiter", "tab", "--decimal-comma"],
        ),
        ("tab-point.csv", "\t", false, &["--delimiter", "\t"]),
        ("quoted-comma-point.csv", ",", false, &["--delimiter", ","]),
    ];
    for (file, sep, comma, named) in dialects {
        dir.write(file, &export(&text, sep, comma));
        // The same digits give the same f64 samples, hence the same power
        // bit for bit: no tolerance.
        assert_eq!(power_of(&dir, file, &[]), reference, "{file} detected");
        assert_eq!(power_of(&dir, file, named), reference, "{file} named");
    }
}

/// A force record at 50 kHz: 40 us half-sine impacts of 10 N at `onsets_s`.
fn bounce_csv(onsets_s: &[f64]) -> String {
    let fs = 50_000.0;
    let mut text = String::from("time [s],force [N]\n");
    for i in 0..(0.8 * fs) as usize {
        let t = i as f64 / fs;
        let x: f64 = onsets_s
            .iter()
            .map(|&t0| t - t0)
            .filter(|s| (0.0..40e-6).contains(s))
            .map(|s| 10.0 * (PI * s / 40e-6).sin())
            .sum::<f64>()
            + 0.01 * (((i * 7919) % 1000) as f64 / 500.0 - 1.0);
        text.push_str(&format!("{t},{x}\n"));
    }
    text
}

#[test]
fn cor_reads_a_semicolon_export_detected_or_named() {
    let dir = Scratch::new("cor-dialects");
    let onsets = [0.05, 0.25, 0.43, 0.592, 0.7378];
    let text = bounce_csv(&onsets);
    dir.write("bounce.csv", &text);
    dir.write("bounce-eu.csv", &export(&text, ";", true));
    let cor = |args: &[&str]| json_out(&dir, args)["cor_mean"].as_f64().expect("cor_mean");
    let reference = cor(&["cor", "bounce.csv", "--json"]);
    // Gaps 0.2, 0.18, 0.162, 0.1458: COR 0.9 to the 20 us sampling (tol 1e-3).
    assert!((reference - 0.9).abs() < 1e-3, "{reference}");
    assert_eq!(cor(&["cor", "bounce-eu.csv", "--json"]), reference);
    assert_eq!(
        cor(&[
            "cor",
            "bounce-eu.csv",
            "--delimiter",
            ";",
            "--decimal-comma",
            "--json"
        ]),
        reference
    );
}

#[test]
fn unreadable_dialects_are_refused_with_file_and_line() {
    let dir = Scratch::new("dialect-errors");
    let (trace, _) = record();
    write_csv(&dir.path("vlab.csv"), &trace).expect("write");
    write_wav(&dir.path("run.wav"), &trace).expect("wav");
    let text = std::fs::read_to_string(dir.path("vlab.csv")).expect("read");
    dir.write("eu.csv", &export(&text, ";", true));
    // The wrong separator, named: the header is one cell.
    refuses_in(
        &dir,
        &["analyze", "eu.csv", "--freq", "40", "--delimiter", ","],
        &["eu.csv", "line 1", "time column"],
    );
    // Decimal commas in a comma-separated file cannot be read.
    dir.write(
        "ambiguous.csv",
        "time [s],force [N],acceleration [m/s^2]\n0,0,1\n0,000025,1,5,2\n",
    );
    refuses_in(
        &dir,
        &["analyze", "ambiguous.csv", "--freq", "40"],
        &["ambiguous.csv", "line 3", "decimal commas", "--delimiter"],
    );
    // Two decimal marks: the line that decided the first is named.
    dir.write(
        "mixed.csv",
        "time [s];force [N];acceleration [m/s^2]\n0;0,5;1\n0.000025;1;2\n",
    );
    refuses_in(
        &dir,
        &["cor", "mixed.csv"],
        &["mixed.csv", "line 3", "line 2 ('0,5')"],
    );
    // Dialect options on a file that is not a CSV.
    refuses_in(
        &dir,
        &["analyze", "run.wav", "--decimal-comma"],
        &["--decimal-comma", "run.wav", "not a .csv"],
    );
    refuses_in(
        &dir,
        &["analyze", "eu.csv", "--delimiter", "|"],
        &["--delimiter", "',', ';' or tab"],
    );
}

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures/tdms")
        .join(name)
}

/// The record the fixtures were cut from: its first 200 samples.
fn source_head() -> Trace {
    let mut t = read_csv(
        &Path::new(env!("CARGO_MANIFEST_DIR")).join("signals/reference/thesis-40Hz-G20/trace.csv"),
    )
    .expect("reference CSV");
    for c in &mut t.channels {
        c.samples.truncate(200);
    }
    t
}

fn tdms_kind(path: &Path) -> TdmsErrorKind {
    match read_tdms(path) {
        Err(SignalsError::Tdms { kind, .. }) => kind,
        other => panic!("{}: expected a TDMS refusal, got {other:?}", path.display()),
    }
}

#[test]
fn tdms_f64_and_f32_channels_read_with_names_units_and_rate() {
    let source = source_head();
    let t = read_trace(&fixture("float32.tdms")).expect("float32.tdms");
    assert_eq!(t.sample_rate_hz, 40_000.0, "1 / wf_increment, whole hertz");
    assert_eq!(t.start_time_s.to_bits(), source.start_time_s.to_bits());
    assert_eq!(t.channel_names(), ["acceleration", "force"]);
    assert_eq!(t.channels[0].unit, "m/s^2");
    assert_eq!(t.channels[1].unit, "N");
    // f32 acceleration: the CSV value rounded to f32, widened exactly.
    let rounded: Vec<f64> = source.channels[0]
        .samples
        .iter()
        .map(|&x| f64::from(x as f32))
        .collect();
    assert_eq!(t.channels[0].samples, rounded);
    // f64 force: bit for bit.
    let bits = |x: &[f64]| x.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
    assert_eq!(
        bits(&t.channels[1].samples),
        bits(&source.channels[1].samples)
    );
    // No vlab_metadata property: empty metadata.
    assert_eq!(t.metadata, Default::default());
}

#[test]
fn tdms_files_without_a_usable_record_are_refused_with_the_reason() {
    let msg = |name: &str| read_tdms(&fixture(name)).expect_err(name).to_string();
    assert!(matches!(
        tdms_kind(&fixture("no-increment.tdms")),
        TdmsErrorKind::BadTiming { .. }
    ));
    let m = msg("no-increment.tdms");
    assert!(
        m.contains("no-increment.tdms") && m.contains("wf_increment"),
        "{m}"
    );
    match tdms_kind(&fixture("unequal-lengths.tdms")) {
        TdmsErrorKind::UnequalLength {
            first_len: 200,
            len: 199,
            ..
        } => {}
        other => panic!("{other:?}"),
    }
    assert!(matches!(
        tdms_kind(&fixture("two-groups.tdms")),
        TdmsErrorKind::SeveralGroups { count: 2, .. }
    ));
    match tdms_kind(&fixture("integer.tdms")) {
        TdmsErrorKind::UnsupportedDataType { channel, .. } => assert_eq!(channel, "adc_codes"),
        other => panic!("{other:?}"),
    }
}

#[test]
fn tdms_layouts_the_reader_would_misread_are_refused() {
    let dir = Scratch::new("tdms-layouts");
    let good = std::fs::read(fixture("float32.tdms")).expect("fixture");
    let patched = |name: &str, patch: &dyn Fn(&mut Vec<u8>)| {
        let mut bytes = good.clone();
        patch(&mut bytes);
        let path = dir.path(name);
        std::fs::write(&path, bytes).expect("write");
        tdms_kind(&path)
    };
    // Table-of-contents flags of the first (only) segment, bytes 4..8.
    for (bit, layout) in [(5, "interleaved"), (6, "big-endian"), (7, "DAQmx")] {
        match patched("flag.tdms", &|b| b[4] |= 1 << bit) {
            TdmsErrorKind::UnsupportedLayout {
                offset: 0,
                layout: l,
            } => {
                assert!(l.contains(layout), "{l}")
            }
            other => panic!("bit {bit}: {other:?}"),
        }
    }
    // A segment that claims 8 raw bytes more than its channels hold.
    let more = patched("more.tdms", &|b| {
        let next = u64::from_le_bytes(b[12..20].try_into().expect("8 bytes")) + 8;
        b[12..20].copy_from_slice(&next.to_le_bytes());
        b.extend_from_slice(&[0; 8]);
    });
    match more {
        TdmsErrorKind::RawDataUnaccounted {
            in_segments,
            in_channels,
        } => assert_eq!(in_segments, in_channels + 8),
        other => panic!("{other:?}"),
    }
    assert!(matches!(
        patched("cut.tdms", &|b| b.truncate(b.len() - 10)),
        TdmsErrorKind::Truncated { offset: 0, .. }
    ));
    assert!(matches!(
        patched("text.tdms", &|b| *b = b"time [s],x [m]\n0,1\n".to_vec()),
        TdmsErrorKind::NotTdms { offset: 0, .. }
    ));
    // A second segment glued on that is not one.
    assert!(matches!(
        patched("tail.tdms", &|b| b.extend_from_slice(b"garbage")),
        TdmsErrorKind::NotTdms { .. }
    ));
}
