//! The bouncing-bed onset, predicted (thesis Section 6.4.1, eq. 6.11–6.13).
//!
//! Sack et al.'s condition for the bouncing bed: the bed, moving at the
//! enclosure's peak velocity between its two collective collisions, crosses the
//! clearance in the time the enclosure takes to turn round, which gives
//!
//! ```text
//! Γ_opt = ω² h / (g π)                      (eq. 6.11)
//! h     = (1 − ν / ν_max) L                 (eq. 6.13, the effective clearance)
//! ```
//!
//! with ν the volume fill ratio, L the enclosure's inner length along the drive
//! and ν_max the densest fill the bed reaches: random close packing (0.64, the
//! thesis' "CP" row) or random loose packing (0.55, "LP", equivalent to eq.
//! 6.12's clearance of a poured bed). A fill from 0.55 up to 0.64 is a real
//! bed (vlab's settling drives beds to 0.57): it has a close-packing
//! clearance, but no loose-packing one, so only the CP estimate is given
//! there and the prediction says why. The thesis found the most efficient
//! amplitude at the onset (Γ_optimum = Γ_bouncing bed) and the CP estimate within
//! 5–12 % of its DEM (Table 6.3, whose "Optimum Amplitude (mm)" columns are Γ
//! values: an erratum). Pure functions, SI units.

use std::f64::consts::PI;

use serde::Serialize;

use crate::validation::{Bound, InvalidParameter, in_range, positive};

pub use crate::scene::packing::{CLOSE_PACKING, LOOSE_PACKING};

/// Effective clearance (m), eq. 6.13: `(1 − fill_ratio / max_fill) length_m`.
/// Zero or negative when the bed is already at `max_fill`.
pub fn effective_clearance_m(fill_ratio: f64, max_fill: f64, length_m: f64) -> f64 {
    (1.0 - fill_ratio / max_fill) * length_m
}

/// Bouncing-bed onset amplitude Γ = ω² h / (g π), eq. 6.11.
pub fn onset_gamma(freq_hz: f64, clearance_m: f64, g_mps2: f64) -> f64 {
    let w = 2.0 * PI * freq_hz;
    w * w * clearance_m / (g_mps2 * PI)
}

/// What `vlab predict` reports for one damper.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BouncingBedPrediction {
    pub fill_ratio: f64,
    pub length_m: f64,
    pub gravity_mps2: f64,
    pub freq_hz: Vec<f64>,
    /// Clearance with close packing, eq. 6.13 with ν_max = 0.64 (m).
    pub close_packing_clearance_m: f64,
    /// Clearance with loose packing, ν_max = 0.55 (m); `None` for a fill at
    /// or above loose packing, where the estimate does not apply.
    pub loose_packing_clearance_m: Option<f64>,
    /// Γ_opt at each frequency, close packing (the thesis' better estimate).
    pub close_packing_gamma: Vec<f64>,
    /// Γ_opt at each frequency, loose packing; `None` where it does not apply.
    pub loose_packing_gamma: Option<Vec<f64>>,
    /// Why the loose-packing estimate is missing, in words (`None` when given).
    pub loose_packing_note: Option<String>,
}

/// Why the loose-packing estimate has no value at `fill_ratio`, if it has none.
pub fn loose_packing_note(fill_ratio: f64) -> Option<String> {
    (fill_ratio >= LOOSE_PACKING).then(|| {
        format!(
            "fill {fill_ratio} is at or above random loose packing ({LOOSE_PACKING}): the loose-packing estimate stops applying there (eq. 6.13 leaves no clearance); the close-packing estimate holds up to {CLOSE_PACKING}"
        )
    })
}

/// Γ_opt with close- and loose-packing clearances at each of `freq_hz`
/// (close packing alone for a fill from loose packing up to close packing),
/// refusing a fill ratio that is not below close packing (no clearance), a
/// non-positive length or gravity, or a non-positive frequency.
pub fn predict_bouncing_bed(
    freq_hz: &[f64],
    fill_ratio: f64,
    length_m: f64,
    gravity_mps2: f64,
) -> Result<BouncingBedPrediction, InvalidParameter> {
    positive("length_m", length_m, "m")?;
    positive("gravity_mps2", gravity_mps2, "m/s^2")?;
    in_range(
        "fill_ratio",
        fill_ratio,
        "",
        Bound::Open(0.0),
        Bound::Open(CLOSE_PACKING),
    )
    .map_err(|e| {
        e.because(&format!(
            "{CLOSE_PACKING} is random close packing: a fuller bed leaves no clearance in eq. 6.13"
        ))
    })?;
    for &f in freq_hz {
        positive("freq_hz", f, "Hz")?;
    }
    let cp = effective_clearance_m(fill_ratio, CLOSE_PACKING, length_m);
    let note = loose_packing_note(fill_ratio);
    let lp = note
        .is_none()
        .then(|| effective_clearance_m(fill_ratio, LOOSE_PACKING, length_m));
    Ok(BouncingBedPrediction {
        fill_ratio,
        length_m,
        gravity_mps2,
        freq_hz: freq_hz.to_vec(),
        close_packing_clearance_m: cp,
        loose_packing_clearance_m: lp,
        close_packing_gamma: freq_hz
            .iter()
            .map(|&f| onset_gamma(f, cp, gravity_mps2))
            .collect(),
        loose_packing_gamma: lp.map(|lp| {
            freq_hz
                .iter()
                .map(|&f| onset_gamma(f, lp, gravity_mps2))
                .collect()
        }),
        loose_packing_note: note,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Thesis Table 6.3 (CP and LP rows; the DEM rows are simulations): fill
    /// ratio, the enclosure length of Table 6.1 that gives it with 358 spheres
    /// of 5 mm, then Γ at 20, 40 and 80 Hz.
    const TABLE_6_3: [(f64, f64, [f64; 3], [f64; 3]); 4] = [
        (0.466, 0.040, [5.6, 22.3, 89.2], [3.1, 12.5, 49.9]),
        (0.415, 0.045, [8.1, 32.4, 130.0], [5.7, 22.6, 90.6]),
        (0.373, 0.050, [10.7, 42.8, 171.0], [8.2, 33.0, 132.0]),
        (0.339, 0.055, [13.3, 53.0, 212.0], [10.8, 43.2, 173.0]),
    ];

    #[test]
    fn reproduces_table_6_3_within_one_percent() {
        for (fill, length, cp, lp) in TABLE_6_3 {
            let p = predict_bouncing_bed(&[20.0, 40.0, 80.0], fill, length, 9.81).expect("valid");
            for k in 0..3 {
                for (got, want, row) in [
                    (p.close_packing_gamma[k], cp[k], "CP"),
                    (
                        p.loose_packing_gamma.as_ref().expect("below LP")[k],
                        lp[k],
                        "LP",
                    ),
                ] {
                    let rel = (got - want).abs() / want;
                    assert!(
                        rel < 0.01,
                        "fill {fill}, {row}, {} Hz: {got:.3} vs Table 6.3 {want} ({:.2} %)",
                        p.freq_hz[k],
                        100.0 * rel
                    );
                }
            }
        }
    }

    #[test]
    fn scales_with_frequency_squared_and_clearance() {
        let h = effective_clearance_m(0.466, CLOSE_PACKING, 0.04);
        assert!((h - 0.010_875).abs() < 1e-12);
        let g20 = onset_gamma(20.0, h, 9.81);
        assert!((onset_gamma(40.0, h, 9.81) / g20 - 4.0).abs() < 1e-12);
        assert!((onset_gamma(20.0, 2.0 * h, 9.81) / g20 - 2.0).abs() < 1e-12);
    }

    #[test]
    fn a_fill_between_loose_and_close_packing_gets_the_close_estimate_alone() {
        // vlab settles the thesis bed to about 0.57; 0.63 is nearly close packed.
        for fill in [LOOSE_PACKING, 0.57, 0.63] {
            let p = predict_bouncing_bed(&[40.0], fill, 0.04, 9.81).expect("below CP");
            let h = effective_clearance_m(fill, CLOSE_PACKING, 0.04);
            assert!(h > 0.0 && p.close_packing_clearance_m == h, "fill {fill}");
            assert_eq!(p.close_packing_gamma, vec![onset_gamma(40.0, h, 9.81)]);
            assert_eq!(p.loose_packing_gamma, None, "fill {fill}");
            assert_eq!(p.loose_packing_clearance_m, None);
            let note = p.loose_packing_note.expect("says why");
            assert!(note.contains("0.55") && note.contains("0.64"), "{note}");
        }
        let below = predict_bouncing_bed(&[40.0], 0.54, 0.04, 9.81).expect("valid");
        assert!(below.loose_packing_gamma.is_some() && below.loose_packing_note.is_none());
    }

    #[test]
    fn refuses_a_bed_with_no_clearance_and_bad_values() {
        for fill in [CLOSE_PACKING, 0.7] {
            let e = predict_bouncing_bed(&[40.0], fill, 0.04, 9.81).expect_err("too full");
            assert_eq!(e.key, "fill_ratio");
        }
        assert!(predict_bouncing_bed(&[40.0], 0.466, 0.0, 9.81).is_err());
        assert!(predict_bouncing_bed(&[-40.0], 0.466, 0.04, 9.81).is_err());
        assert!(predict_bouncing_bed(&[f64::NAN], 0.466, 0.04, 9.81).is_err());
    }
}
