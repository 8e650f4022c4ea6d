//! Lab files of every common dialect through `vlab analyze` and `vlab cor`:
//! one record written as vlab's CSV, as a spreadsheet's `;`/decimal-comma
//! export and as tab-separated text gives the same figures, whether the
//! dialect is detected or named with `--delimiter` / `--decimal-comma`; what
//! cannot be read is refused naming the file and the line.

mod common;

use std::f64::consts::PI;

use common::{Scratch, refuses_in, stderr, vlab};
use vlab::signals::{Trace, write_csv, write_wav};

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

/// vlab's CSV text rewritten as a spreadsheet would export it: comments
/// dropped, header cells quoted, `sep` between cells, decimal commas when
/// `comma`, CRLF line ends.
fn export(vlab_csv: &str, sep: &str, comma: bool) -> String {
    let mut out = String::new();
    for line in vlab_csv.lines().filter(|l| !l.starts_with('#')) {
        let cells: Vec<String> = if line.starts_with("time") {
            line.split(',').map(|c| format!("\"{c}\"")).collect()
        } else if comma {
            line.split(',').map(|c| c.replace('.', ",")).collect()
        } else {
            line.split(',').map(str::to_string).collect()
        };
        out.push_str(&cells.join(sep));
        out.push_str("\r\n");
    }
    out
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
