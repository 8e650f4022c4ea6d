//! How the rigid bodies of a bed line up: the orientation order parameter
//! of their symmetry axes against the enclosure's axis.
//!
//! Terzioglu's thesis, Chapter 8, gives no measure of how its prolates and
//! toroids lie in the bed (its Fig. 8.7 shows the beds); this is vlab's own. Each body of
//! revolution has a symmetry axis: the principal axis whose moment of
//! inertia stands apart from the other two (a prolate's long axis, an
//! oblate's or a torus's short one). With `θ` the angle between it and a
//! direction `d` (the cylinder's axis, along which the rig drives),
//!
//! `S = ⟨P₂(cos θ)⟩ = ⟨(3 cos²θ − 1) / 2⟩`
//!
//! over the bodies: 1 when every axis lies along `d`, −½ when every axis lies
//! across it, and 0 for axes pointing every which way (uniform on the
//! sphere, the expected value; a bed of N bodies at random spreads by
//! `√(1/5) / √N`, 0.047 for 90 bodies). The sign of an axis does not matter.

use glam::DVec3;

use super::clumps::Clumps;

/// The cylinder's axis in the world frame, along which the rig drives in
/// either orientation (gravity turns for a horizontal damper, the cylinder
/// does not).
pub const CYLINDER_AXIS: DVec3 = DVec3::Z;

/// Relative difference of principal moments below which a body has no
/// axis that stands apart (a sphere, or a body as round as one).
const ISOTROPIC_REL: f64 = 1e-6;

/// The symmetry axis in the body's principal frame: the unit axis whose
/// moment of `inertia_kgm2` differs most from the mean of the other two;
/// `None` when all three agree to [`ISOTROPIC_REL`].
pub fn symmetry_axis(inertia_kgm2: DVec3) -> Option<DVec3> {
    let m = inertia_kgm2.to_array();
    let apart = |k: usize| (m[k] - 0.5 * (m[(k + 1) % 3] + m[(k + 2) % 3])).abs();
    let k = (0..3).fold(0, |best, k| if apart(k) > apart(best) { k } else { best });
    let scale = m.iter().fold(0.0f64, |a, &b| a.max(b.abs()));
    // NaN moments have no axis either.
    (apart(k) > ISOTROPIC_REL * scale).then_some(DVec3::AXES[k])
}

/// `P₂(cos θ)` of a unit `axis` against a unit `direction`.
pub fn legendre_p2(axis: DVec3, direction: DVec3) -> f64 {
    let c = axis.dot(direction);
    1.5 * c * c - 0.5
}

/// The order parameter `S` of the bodies' symmetry axes against the unit
/// `direction`, over the bodies that have one; `None` when none has.
pub fn order_parameter(clumps: &Clumps, direction: DVec3) -> Option<f64> {
    let (mut sum, mut n) = (0.0, 0usize);
    for b in 0..clumps.len() {
        if let Some(axis) = symmetry_axis(clumps.inertia[b]) {
            sum += legendre_p2(clumps.orientation[b] * axis, direction);
            n += 1;
        }
    }
    (n > 0).then(|| sum / n as f64)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dem::clumps::ClumpTemplate;
    use glam::DQuat;

    /// A prolate-like body: two spheres along x.
    fn rod() -> ClumpTemplate {
        ClumpTemplate {
            offsets_m: vec![DVec3::new(-0.001, 0.0, 0.0), DVec3::new(0.001, 0.0, 0.0)],
            radii_m: vec![0.001; 2],
            mass_kg: 1e-3,
            inertia_kgm2: DVec3::new(4e-10, 1.4e-9, 1.4e-9),
        }
    }

    fn bed(orientations: &[DQuat], template: &ClumpTemplate) -> Clumps {
        let mut c = Clumps::default();
        for (k, q) in orientations.iter().enumerate() {
            let at = DVec3::new(0.01 * k as f64, 0.0, 0.0);
            c.push(template, (at, *q), (DVec3::ZERO, DVec3::ZERO), 2 * k as u32);
        }
        c
    }

    #[test]
    fn the_symmetry_axis_is_the_moment_that_stands_apart() {
        assert_eq!(symmetry_axis(DVec3::new(1.0, 3.0, 3.0)), Some(DVec3::X));
        assert_eq!(symmetry_axis(DVec3::new(2.0, 2.0, 3.5)), Some(DVec3::Z));
        assert_eq!(symmetry_axis(DVec3::new(2.0, 0.5, 2.0)), Some(DVec3::Y));
        assert_eq!(symmetry_axis(DVec3::splat(2.0)), None);
        let sphere = ClumpTemplate::sphere(0.001, 1000.0);
        assert_eq!(symmetry_axis(sphere.inertia_kgm2), None);
    }

    /// Every axis along the direction gives 1, every axis across it −½,
    /// whatever the turn about the axis or its sign.
    #[test]
    fn aligned_and_crosswise_beds_give_one_and_minus_a_half() {
        let rod = rod();
        let along: Vec<DQuat> = (0..6)
            .map(|k| {
                let flip = if k % 2 == 0 {
                    0.0
                } else {
                    std::f64::consts::PI
                };
                DQuat::from_rotation_y(-std::f64::consts::FRAC_PI_2 + flip)
                    * DQuat::from_rotation_x(0.3 * k as f64)
            })
            .collect();
        let s = order_parameter(&bed(&along, &rod), DVec3::Z).expect("bodies with an axis");
        assert!((s - 1.0).abs() < 1e-12, "{s}");
        let across: Vec<DQuat> = (0..6)
            .map(|k| DQuat::from_rotation_z(0.7 * k as f64))
            .collect();
        let s = order_parameter(&bed(&across, &rod), DVec3::Z).expect("bodies with an axis");
        assert!((s + 0.5).abs() < 1e-12, "{s}");
        let spheres = bed(&across, &ClumpTemplate::sphere(0.001, 1000.0));
        assert_eq!(order_parameter(&spheres, DVec3::Z), None);
    }

    /// Axes uniform on the sphere give 0 within the spread of the mean:
    /// 4 000 bodies, σ(P₂) = √(1/5) = 0.447, so 4σ of the mean is 0.028.
    #[test]
    fn axes_at_random_give_zero_within_the_spread_of_the_mean() {
        let mut s = 0x9E37_79B9_7F4A_7C15u64;
        let mut next = || {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (s >> 11) as f64 / (1u64 << 53) as f64
        };
        let n = 4000;
        // Uniform rotations (Shoemake's method).
        let turns: Vec<DQuat> = (0..n)
            .map(|_| {
                let (u1, u2, u3) = (next(), next(), next());
                let tau = std::f64::consts::TAU;
                let (a, b) = ((1.0 - u1).sqrt(), u1.sqrt());
                DQuat::from_xyzw(
                    a * (tau * u2).sin(),
                    a * (tau * u2).cos(),
                    b * (tau * u3).sin(),
                    b * (tau * u3).cos(),
                )
            })
            .collect();
        let s = order_parameter(&bed(&turns, &rod()), DVec3::Z).expect("bodies with an axis");
        let sigma_mean = (1.0f64 / 5.0).sqrt() / (n as f64).sqrt();
        assert!(
            s.abs() < 4.0 * sigma_mean,
            "{s} against 4 sigma {}",
            4.0 * sigma_mean
        );
    }
}
