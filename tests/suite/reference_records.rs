//! The reference records of `signals/reference/` through `vlab analyze` and
//! `vlab cor`, run exactly as its README prints the commands: every format of
//! the 40 Hz record (CSV, WAV, `;`/decimal-comma CSV, TDMS) gives the same
//! power, each figure agrees with the README's within its printed digits, and
//! the semicolon record is the documented conversion of the CSV.

#![cfg(all(feature = "cli", feature = "plot"))]

use crate::common;
use crate::support::spreadsheet;

use std::path::{Path, PathBuf};

use common::{stderr, vlab};
use vlab::signals::{Trace, read_trace};

fn reference(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("signals/reference")
        .join(rel)
}

/// The cells of a README figures row (one whose second cell is a `vlab`
/// command) whose first cell starts with `` `record` ``; `nth` picks among
/// several such rows.
fn readme_row(record: &str, nth: usize) -> Vec<String> {
    let text = std::fs::read_to_string(reference("README.md")).expect("README.md");
    let start = format!("| `{record}`");
    text.lines()
        .filter(|l| l.starts_with(&start))
        .map(|l| {
            l.trim_matches('|')
                .split(" | ")
                .map(|c| c.trim().trim_matches('`').to_string())
                .collect::<Vec<_>>()
        })
        .filter(|cells| cells.get(1).is_some_and(|c| c.starts_with("vlab ")))
        .nth(nth)
        .unwrap_or_else(|| panic!("README has no figures row {nth} for {record}"))
}

/// Runs a README command (`vlab ...`, in signals/reference/) with `--json`.
fn run_json(command: &str) -> serde_json::Value {
    let mut args: Vec<&str> = command.split_whitespace().collect();
    assert_eq!(args.remove(0), "vlab", "{command}");
    args.push("--json");
    let out = vlab(&reference(""), &args);
    assert!(out.status.success(), "{command}: {}", stderr(&out));
    serde_json::from_slice(&out.stdout).expect("JSON")
}

/// `value` agrees with the README's `printed` figure within half a unit of
/// its last printed digit (2.2613e0: 5e-5).
fn agrees(value: f64, printed: &str, what: &str) {
    let p: f64 = printed
        .parse()
        .unwrap_or_else(|_| panic!("{what}: README figure '{printed}'"));
    let (mantissa, exp) = printed.split_once('e').unwrap_or((printed, "0"));
    let decimals = mantissa.split_once('.').map_or(0, |(_, d)| d.len()) as i32;
    let exp: i32 = exp.parse().expect("exponent");
    let half_unit = 0.5 * 10f64.powi(exp - decimals);
    assert!(
        (value - p).abs() <= half_unit * (1.0 + 1e-9),
        "{what}: vlab gives {value}, the README prints {printed}"
    );
}

fn num(v: &serde_json::Value, key: &str) -> f64 {
    v[key]
        .as_f64()
        .unwrap_or_else(|| panic!("{key} missing in {v}"))
}

#[test]
fn the_semicolon_record_is_the_documented_conversion_of_the_csv() {
    let csv = std::fs::read_to_string(reference("thesis-40Hz-G20/trace.csv")).expect("csv");
    let expected = spreadsheet::export(&csv, ";", true);
    let path = reference("thesis-40Hz-G20/trace-semicolon.csv");
    if std::env::var_os("VLAB_WRITE_REFERENCE").is_some() {
        std::fs::write(&path, &expected).expect("write the semicolon record");
    }
    let committed = std::fs::read(&path).expect("semicolon record");
    assert!(
        committed == expected.as_bytes(),
        "{} is not export(trace.csv, \";\", true); rewrite it with \
         VLAB_WRITE_REFERENCE=1 cargo test --release --test suite reference_records::",
        path.display()
    );
}

#[test]
fn every_format_of_the_40hz_record_gives_the_readme_power() {
    let records = [
        "thesis-40Hz-G20/trace.csv",
        "thesis-40Hz-G20/trace.wav",
        "thesis-40Hz-G20/trace-semicolon.csv",
        "thesis-40Hz-G20/trace.tdms",
    ];
    let mut power = Vec::new();
    for record in records {
        let row = readme_row(record, 0);
        let r = run_json(&row[1]);
        agrees(num(&r, "power_w"), &row[2], &format!("{record} power"));
        agrees(
            num(&r, "energy_per_cycle_j"),
            &row[3],
            &format!("{record} energy per cycle"),
        );
        match r["efficiency"].as_f64() {
            Some(eta) => agrees(eta, &row[4], &format!("{record} efficiency")),
            None => assert_eq!(row[4], "unknown", "{record}"),
        }
        assert_eq!(num(&r, "n_samples"), 7000.0, "{record}");
        power.push(num(&r, "power_w"));
    }
    let csv = power[0];
    // CSV, semicolon CSV and TDMS hold the same f64 samples (checked below):
    // the same power to the DFT's rounding, 1e-9 relative (in fact equal).
    for (record, p) in records.iter().zip(&power).skip(2) {
        assert!((p - csv).abs() <= 1e-9 * csv, "{record}: {p} vs CSV {csv}");
    }
    // The WAV holds the 16-bit ADC codes, exact in f32; each sample comes back
    // within one f64 rounding of the CSV's (checked below), so the power
    // agrees to the DFT's rounding: 1e-12 relative (measured: equal).
    assert!(
        (power[1] - csv).abs() <= 1e-12 * csv,
        "WAV {} vs CSV {csv}",
        power[1]
    );

    // Without the calibration: the leak of the enclosure mass.
    let row = readme_row("thesis-40Hz-G20/trace.csv", 1);
    let r = run_json(&row[1]);
    agrees(num(&r, "power_w"), &row[2], "uncalibrated power");
    agrees(
        num(&r, "energy_per_cycle_j"),
        &row[3],
        "uncalibrated energy",
    );
    agrees(num(&r, "efficiency"), &row[4], "uncalibrated efficiency");
}

#[test]
fn the_formats_hold_the_same_samples() {
    let read = |rel: &str| read_trace(&reference(rel)).unwrap_or_else(|e| panic!("{e}"));
    let csv = read("thesis-40Hz-G20/trace.csv");
    let bits = |t: &Trace| {
        t.channels
            .iter()
            .map(|c| {
                let b: Vec<u64> = c.samples.iter().map(|x| x.to_bits()).collect();
                (c.name.clone(), c.unit.clone(), b)
            })
            .collect::<Vec<_>>()
    };
    for rel in [
        "thesis-40Hz-G20/trace-semicolon.csv",
        "thesis-40Hz-G20/trace.tdms",
    ] {
        let t = read(rel);
        assert_eq!(t.sample_rate_hz, 40_000.0, "{rel}");
        assert_eq!(bits(&t), bits(&csv), "{rel}");
    }
    // The TDMS keeps the exact start and the metadata; the spreadsheet export
    // has neither (its time column starts at 0).
    let tdms = read("thesis-40Hz-G20/trace.tdms");
    assert_eq!(tdms.start_time_s.to_bits(), csv.start_time_s.to_bits());
    assert_eq!(tdms.metadata, csv.metadata);
    assert_eq!(
        read("thesis-40Hz-G20/trace-semicolon.csv").start_time_s,
        0.0
    );
    // The WAV: within one rounding (2^-52 relative) of each CSV sample. The
    // CSV holds code * lsb, the WAV code / 2^15 (exact in f32) and the full
    // scale 2^15 * lsb (each rounded once in f64); their product differs from
    // the CSV's by at most one unit in the last place. This needs the sidecar's
    // full scale read back exactly (serde_json's float_roundtrip).
    let wav = read("thesis-40Hz-G20/trace.wav");
    assert_eq!(wav.metadata, csv.metadata);
    for (w, c) in wav.channels.iter().zip(&csv.channels) {
        assert_eq!((&w.name, &w.unit), (&c.name, &c.unit));
        for (i, (a, b)) in w.samples.iter().zip(&c.samples).enumerate() {
            assert!(
                (a - b).abs() <= f64::EPSILON * b.abs(),
                "{} sample {i}: WAV {a} vs CSV {b}",
                c.name
            );
        }
    }
}

#[test]
fn cor_on_the_drop_record_gives_the_readme_figures() {
    let row = readme_row("drop-acrylic-smooth/force-h2mm.csv", 0);
    let r = run_json(&row[1]);
    let count = |key: &str| r[key].as_array().expect(key).len().to_string();
    assert_eq!(count("impacts"), row[2]);
    assert_eq!(count("cor_per_triple"), row[3]);
    agrees(num(&r, "cor_mean"), &row[4], "COR mean");
    agrees(num(&r, "cor_std"), &row[5], "COR std");
    assert_eq!(num(&r, "sample_rate_hz"), 200_000.0);
}
