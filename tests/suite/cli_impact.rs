//! `vlab impact` end to end: the JSON keys of the issue and the contact trace.

#![cfg(all(feature = "cli", feature = "plot"))]

use crate::common;

use common::{Scratch, stderr, vlab};
use vlab::signals::read_csv;

#[test]
fn impact_json_and_trace() {
    let dir = Scratch::new("impact");
    let out = vlab(
        &dir.0,
        &[
            "impact",
            "--material",
            "steel",
            "--against",
            "sphere",
            "--speed-mps",
            "1",
            "--cor",
            "0.9",
            "--trace",
            "contact.csv",
            "--json",
        ],
    );
    assert!(out.status.success(), "{}", stderr(&out));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON on stdout");
    for key in [
        "contact_duration_s",
        "max_overlap_m",
        "max_normal_force_n",
        "normal_restitution",
        "rebound_speed_mps",
        "rebound_angle_deg",
        "rebound_spin_rad_s",
        "dissipated_j",
    ] {
        assert!(v[key].is_f64(), "{key} missing");
    }
    let e = v["normal_restitution"].as_f64().expect("e");
    assert!((e - 0.9).abs() < 0.0045, "{e}");
    let trace = read_csv(&dir.path("contact.csv")).expect("trace parses");
    let overlap = &trace.channel("overlap").expect("overlap").samples;
    let peak = overlap.iter().copied().fold(0.0, f64::max);
    assert!((peak - v["max_overlap_m"].as_f64().expect("overlap")).abs() < 1e-15);
}
