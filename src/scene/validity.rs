//! Where the contact model stops being valid: the yield velocity (thesis eq.
//! 5.26, Johnson), the impact speed above which a contact yields plastically, so
//! that the model's speed-independent restitution no longer describes it (thesis
//! Section 5.5.4; the thesis' reference figures, Section 6.2.2, are 3.5 m/s for
//! 5 mm acrylic spheres against each other and 0.15 m/s for steel).
//!
//! `v_y = sqrt(107 R*^3 sigma_y^5 / (E*^4 m*))` with the pair's equivalent
//! radius, modulus and mass. The yield strength is the weaker body's (the one
//! that yields first); a body without one (a rigid wall) never yields first. A
//! flat wall has `R* = R` and `m* = m` (its curvature is zero and its mass is
//! taken as infinite), as everywhere in vlab.
//!
//! [`yield_warning`] words the warning `vlab drop` prints and `vlab shake` can
//! reuse for any pair type.

use crate::dem::hertz_theory::yield_velocity_mps;
use crate::dem::material::{
    Material, effective_mass_kg, effective_radius_m, effective_youngs_pa, sphere_mass_kg,
};

/// Yield velocities of a damper's two pair types, or the largest impact
/// speeds to hold against them (m/s).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct YieldVelocities {
    pub particle_particle_mps: f64,
    pub particle_wall_mps: f64,
}

/// The yield strength that limits a pair: the smaller of the two that are
/// given, Pa; `None` when neither material has one.
pub fn pair_yield_strength_pa(a: &Material, b: &Material) -> Option<f64> {
    match (a.yield_strength_pa, b.yield_strength_pa) {
        (Some(x), Some(y)) => Some(x.min(y)),
        (x, y) => x.or(y),
    }
}

/// Yield velocity of two identical spheres of `material` and `radius_m`
/// meeting head-on (relative approach speed), m/s; `None` without a yield
/// strength.
pub fn sphere_sphere_yield_velocity_mps(material: &Material, radius_m: f64) -> Option<f64> {
    let y = material.yield_strength_pa?;
    let m = sphere_mass_kg(radius_m, material.density_kgm3);
    Some(yield_velocity_mps(
        effective_mass_kg(m, m),
        effective_youngs_pa(material, material),
        effective_radius_m(radius_m, radius_m),
        y,
    ))
}

/// Yield velocity of a sphere of `sphere` and `radius_m` hitting a flat wall
/// (or plate) of `wall`, m/s; `None` when neither has a yield strength.
pub fn sphere_wall_yield_velocity_mps(
    sphere: &Material,
    wall: &Material,
    radius_m: f64,
) -> Option<f64> {
    let y = pair_yield_strength_pa(sphere, wall)?;
    let m = sphere_mass_kg(radius_m, sphere.density_kgm3);
    Some(yield_velocity_mps(
        m,
        effective_youngs_pa(sphere, wall),
        radius_m,
        y,
    ))
}

/// The warning for an impact at `impact_speed_mps` on the pair `pair` (e.g.
/// "acrylic sphere on the steel plate") whose yield velocity is
/// `yield_velocity_mps`, or `None` when the impact is below it.
pub fn yield_warning(pair: &str, impact_speed_mps: f64, yield_velocity_mps: f64) -> Option<String> {
    (impact_speed_mps > yield_velocity_mps).then(|| {
        format!(
            "impact speed {impact_speed_mps:.3} m/s exceeds the yield velocity {yield_velocity_mps:.3} m/s \
             of the {pair} ({:.1} times; thesis eq. 5.26): the contact yields, and the model's \
             speed-independent restitution no longer describes it (thesis Section 5.5.4)",
            impact_speed_mps / yield_velocity_mps
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    const R: f64 = 0.0025;

    #[test]
    fn thesis_sphere_sphere_figures() {
        // Thesis Section 6.2.2: 3.5 m/s (acrylic, 125 MPa), 0.15 m/s (steel, 1350 MPa).
        let a = sphere_sphere_yield_velocity_mps(&Material::ACRYLIC, R).expect("yield");
        assert!((a - 3.5).abs() < 0.1, "acrylic {a}");
        let s = sphere_sphere_yield_velocity_mps(&Material::STEEL, R).expect("yield");
        assert!((s - 0.15).abs() < 0.01, "steel {s}");
    }

    #[test]
    fn sphere_on_the_drop_rig_plate() {
        let plate = Material {
            density_kgm3: f64::INFINITY,
            ..Material::STEEL
        };
        // Same material: R* and m* double against a flat wall, so v_y ~ sqrt(R*^3 / m*)
        // doubles exactly.
        let steel = sphere_wall_yield_velocity_mps(&Material::STEEL, &plate, R).expect("yield");
        let pair = sphere_sphere_yield_velocity_mps(&Material::STEEL, R).expect("yield");
        assert!((steel / pair - 2.0).abs() < 1e-12, "{steel} vs {pair}");
        assert!(
            (steel - 0.297).abs() < 0.002,
            "steel on steel plate {steel}"
        );
        // Acrylic on steel: acrylic yields first (125 MPa); the stiffer pair
        // (E* 3.76 GPa vs 1.90 GPa) lowers v_y by (1.90 / 3.76)^2 = 0.255.
        let acrylic = sphere_wall_yield_velocity_mps(&Material::ACRYLIC, &plate, R).expect("yield");
        let pp = sphere_sphere_yield_velocity_mps(&Material::ACRYLIC, R).expect("yield");
        let e_pp = effective_youngs_pa(&Material::ACRYLIC, &Material::ACRYLIC);
        let e_pw = effective_youngs_pa(&Material::ACRYLIC, &plate);
        assert!((acrylic / (2.0 * pp * (e_pp / e_pw).powi(2)) - 1.0).abs() < 1e-12);
        assert!(
            (acrylic - 1.81).abs() < 0.01,
            "acrylic on steel plate {acrylic}"
        );
        // A rigid wall has no yield strength: the sphere's counts.
        assert_eq!(
            pair_yield_strength_pa(&Material::ACRYLIC, &Material::rigid()),
            Some(125e6)
        );
        assert_eq!(
            pair_yield_strength_pa(&Material::rigid(), &Material::rigid()),
            None
        );
    }

    #[test]
    fn warning_names_both_figures() {
        assert!(yield_warning("pair", 1.0, 1.79).is_none());
        let w = yield_warning("acrylic sphere on the steel plate", 1.98, 1.79).expect("above");
        assert!(
            w.starts_with("impact speed 1.980 m/s exceeds the yield velocity 1.790 m/s of the acrylic sphere on the steel plate (1.1 times"),
            "{w}"
        );
    }
}
