//! A multi-sphere body pressed onto a flat plate, quasi-statically: its
//! normal and tangential force-deformation curves (Terzioglu's thesis,
//! Section 5.4.3–5.4.4, Fig. 5.8 and 5.10, where the same bodies are set
//! against FEM).
//!
//! The body is held in its orientation and the plate pressed onto it along
//! the body's axis: **horizontal** presses a prolate across its long axis
//! (its body y) and an oblate or a toroid along its axis of symmetry (body
//! z, a toroid lying flat); **vertical** presses a prolate along its long
//! axis (body x, end-on) and an oblate or a toroid across (body x, a toroid
//! standing on its rim). Each sub-sphere that the plate reaches carries the
//! contact law's Hertz force at its own overlap (eq. 5.7); the body's force
//! is their sum. Held at a normal deformation, the plate then slides across
//! and each touching sub-sphere's Mindlin spring with Coulomb slip (eq.
//! 5.13–5.16, the DEM's own kernel) carries the tangential force. No time
//! enters: this is the multi-sphere model's own response, what the DEM
//! computes at rest.
//!
//! **The toroid's ripples** (eq. 5.18–5.19): lying flat, a toroid of n
//! sub-spheres touches the plate at n points, with the union's surface
//! dipping between them by `b − √(b² − (a sin(π/n))²)` (the exact chord;
//! eq. 5.19 writes `a π / n`, its small-angle form). Pressed deeper than
//! that, the multi-sphere body is stiffer than the smooth torus, whose
//! contact is a line: the thesis' limit of validity.

use glam::DVec3;
use serde::Serialize;

use crate::dem::clumps::ClumpTemplate;
use crate::dem::contact::{ContactLaw, mindlin_coulomb};
use crate::scene::particle_shape::ShapeKind;

pub mod outcome;

/// Which way the plate presses the body.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum PressConfig {
    Horizontal,
    Vertical,
}

impl PressConfig {
    /// The direction, in the body's principal frame, from the plate into
    /// the body, and the direction the plate slides in for the tangential
    /// curve.
    pub fn axes(self, shape: ShapeKind) -> (DVec3, DVec3) {
        match (self, shape) {
            (PressConfig::Horizontal, ShapeKind::Prolate) => (DVec3::Y, DVec3::X),
            (PressConfig::Vertical, ShapeKind::Prolate) => (DVec3::X, DVec3::Y),
            (PressConfig::Horizontal, _) => (DVec3::Z, DVec3::X),
            (PressConfig::Vertical, _) => (DVec3::X, DVec3::Y),
        }
    }

    /// Its name.
    pub fn as_str(self) -> &'static str {
        match self {
            PressConfig::Horizontal => "horizontal",
            PressConfig::Vertical => "vertical",
        }
    }
}

/// One point of a normal curve.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct NormalPoint {
    /// Plate travel since first touch (m).
    pub deformation_m: f64,
    /// Normal force of the plate on the body (N).
    pub force_n: f64,
    /// Sub-spheres the plate touches.
    pub touching: usize,
}

/// One point of a tangential curve.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct TangentialPoint {
    /// Plate slide since the normal load was set (m).
    pub displacement_m: f64,
    /// Tangential force of the plate on the body, along the slide (N).
    pub force_n: f64,
}

/// The sub-spheres' heights above the plate at first touch (m), along
/// `normal` (from the plate into the body): a sub-sphere at 0 touches
/// first.
pub fn heights_m(template: &ClumpTemplate, normal: DVec3) -> Vec<f64> {
    let raw: Vec<f64> = template
        .offsets_m
        .iter()
        .zip(&template.radii_m)
        .map(|(o, r)| o.dot(normal) - r)
        .collect();
    let lowest = raw.iter().copied().fold(f64::INFINITY, f64::min);
    raw.iter().map(|h| h - lowest).collect()
}

/// The normal force on the body (N) and the sub-spheres touching when the
/// plate has travelled `deformation_m` past first touch.
pub fn normal_force_n(
    law: &ContactLaw,
    template: &ClumpTemplate,
    heights_m: &[f64],
    deformation_m: f64,
) -> (f64, usize) {
    let mut force = 0.0;
    let mut touching = 0;
    for (h, r) in heights_m.iter().zip(&template.radii_m) {
        let overlap = deformation_m - h;
        if overlap > 0.0 {
            force += law.hertz_force_n(*r, overlap);
            touching += 1;
        }
    }
    (force, touching)
}

/// The normal curve: `points` deformations evenly from 0 to
/// `max_deformation_m`.
pub fn normal_curve(
    law: &ContactLaw,
    template: &ClumpTemplate,
    normal: DVec3,
    max_deformation_m: f64,
    points: usize,
) -> Vec<NormalPoint> {
    let heights = heights_m(template, normal);
    (0..=points)
        .map(|k| {
            let d = max_deformation_m * k as f64 / points as f64;
            let (force_n, touching) = normal_force_n(law, template, &heights, d);
            NormalPoint {
                deformation_m: d,
                force_n,
                touching,
            }
        })
        .collect()
}

/// The tangential curve at normal deformation `preload_m`: the plate slides
/// along `slide` in `points` steps up to `max_slide_m`; each touching
/// sub-sphere's spring grows by the step and slips at μ times its normal
/// force.
pub fn tangential_curve(
    law: &ContactLaw,
    template: &ClumpTemplate,
    (normal, slide): (DVec3, DVec3),
    preload_m: f64,
    (max_slide_m, points): (f64, usize),
) -> Vec<TangentialPoint> {
    let heights = heights_m(template, normal);
    let touching: Vec<(f64, f64)> = heights
        .iter()
        .zip(&template.radii_m)
        .filter(|(h, _)| preload_m > **h)
        .map(|(h, r)| (*r, preload_m - h))
        .collect();
    let mut springs = vec![DVec3::ZERO; touching.len()];
    let step = slide * (max_slide_m / points as f64);
    let mut out = vec![TangentialPoint {
        displacement_m: 0.0,
        force_n: 0.0,
    }];
    for k in 1..=points {
        let mut force = DVec3::ZERO;
        for ((r, overlap), xi) in touching.iter().zip(springs.iter_mut()) {
            let k_t = law.tangential_stiffness_npm(*r, *overlap);
            let cap = law.friction * law.hertz_force_n(*r, *overlap);
            // The plate moves by `step` against the body: the contact point
            // of the body slides by `-step` relative to the plate.
            let (f, new_xi) = mindlin_coulomb(k_t, 0.0, cap, *xi, -step, DVec3::ZERO);
            *xi = new_xi;
            force += f;
        }
        out.push(TangentialPoint {
            displacement_m: max_slide_m * k as f64 / points as f64,
            force_n: force.dot(slide),
        });
    }
    out
}

/// The depth of the dips between a flat toroid's sub-spheres (m): the
/// exact form, `b − √(b² − (a sin(π/n))²)`, and eq. 5.19's small-angle
/// form `b − √(b² − (a π / n)²)`, for `n` sub-spheres of the tube's radius
/// `b_m` on the centre circle of radius `a_m`.
pub fn toroid_ripple_m(a_m: f64, b_m: f64, n: usize) -> (f64, f64) {
    let half_chord = a_m * (std::f64::consts::PI / n as f64).sin();
    let small_angle = a_m * std::f64::consts::PI / n as f64;
    let dip = |c: f64| b_m - (b_m * b_m - c * c).max(0.0).sqrt();
    (dip(half_chord), dip(small_angle))
}

/// The body's half-size along `normal` (m): from its centre to the plate
/// at first touch.
pub fn half_size_m(template: &ClumpTemplate, normal: DVec3) -> f64 {
    template
        .offsets_m
        .iter()
        .zip(&template.radii_m)
        .map(|(o, r)| r - o.dot(normal))
        .fold(0.0, f64::max)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dem::{Material, RestitutionMode};

    fn law() -> ContactLaw {
        let m = Material::ACRYLIC;
        ContactLaw::new(&m, &m, 0.86, 0.52, RestitutionMode::Exact)
    }

    /// A ring of n equal sub-spheres lying flat: every sub-sphere touches at
    /// once, so the force is n times one sphere's Hertz force at every
    /// deformation (to 1e-12; the thesis' theory line of Fig. 5.10a). A sum
    /// that missed sub-spheres at a tie, or took the overlap from the
    /// body's centre, fails.
    #[test]
    fn a_flat_ring_is_n_times_hertz() {
        let (a, b, n) = (0.003, 0.00115, 50);
        let offsets: Vec<DVec3> = (0..n)
            .map(|k| {
                let phi = std::f64::consts::TAU * k as f64 / n as f64;
                DVec3::new(a * phi.cos(), a * phi.sin(), 0.0)
            })
            .collect();
        let t = ClumpTemplate {
            offsets_m: offsets,
            radii_m: vec![b; n],
            mass_kg: 1e-4,
            inertia_kgm2: DVec3::ONE * 1e-9,
        };
        let law = law();
        let curve = normal_curve(&law, &t, DVec3::Z, 0.1 * b, 50);
        for p in &curve[1..] {
            let expect = n as f64 * law.hertz_force_n(b, p.deformation_m);
            assert_eq!(p.touching, n);
            assert!((p.force_n / expect - 1.0).abs() < 1e-12, "{p:?}");
        }
    }

    /// The tangential curve of one sphere under a normal preload starts at
    /// the Mindlin stiffness `8 G* √(R δ)` and saturates at μ times the
    /// normal force (eq. 5.13–5.16): within 1e-9 of both. A spring that
    /// slid the wrong way gives a negative force.
    #[test]
    fn one_sphere_slides_as_mindlin_and_coulomb_say() {
        let r = 0.002;
        let t = ClumpTemplate::sphere(r, 1190.0);
        let law = law();
        let delta = 1e-6;
        let curve = tangential_curve(&law, &t, (DVec3::Z, DVec3::X), delta, (1e-5, 1000));
        let k_t = law.tangential_stiffness_npm(r, delta);
        let first = curve[1];
        assert!((first.force_n / (k_t * first.displacement_m) - 1.0).abs() < 1e-9);
        let cap = law.friction * law.hertz_force_n(r, delta);
        let last = curve.last().expect("points");
        assert!((last.force_n / cap - 1.0).abs() < 1e-9, "{last:?} {cap}");
    }

    /// Eq. 5.19 against the exact dip: for the thesis' toroid (a 3 mm, b
    /// 1.15 mm, 50 sub-spheres) both are 15.5 µm within 0.2 %, 0.0135 of the
    /// tube radius and 2.6e-3 of the toroid's 6 mm across (the thesis'
    /// "about 2.5e-3"); the small-angle form is the larger (its chord is).
    #[test]
    fn the_ripple_of_the_thesis_toroid() {
        let (exact, eq_5_19) = toroid_ripple_m(0.003, 0.00115, 50);
        assert!((exact - 15.5e-6).abs() < 0.1e-6, "{exact}");
        assert!(eq_5_19 > exact && (eq_5_19 / exact - 1.0) < 2e-3);
        assert!((exact / 0.006 - 2.6e-3).abs() < 0.05e-3);
    }
}
