//! Elastic materials and the effective (pair) properties of a contact.
//!
//! Thesis Section 5.2 and 5.3: a contact between bodies `i` and `j` is described by
//! the equivalent radius (eq. 5.5), Young's modulus (eq. 5.6, with the erratum: the
//! factor is `1 - ν²`, not `(1 - ν)²`), mass (eq. 5.9) and shear modulus (eq. 5.14).
//! A flat wall has zero curvature, so a sphere-wall contact has `R* = R` and
//! `m* = m`. A rigid wall has infinite moduli and contributes no compliance.

use serde::{Deserialize, Serialize};

#[cfg(doc)]
use crate::validation::InvalidParameter;
use crate::validation::{Bound, Checked, in_range, positive};

/// An isotropic elastic material.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Material {
    /// Young's modulus E (Pa). `f64::INFINITY` marks a rigid body.
    pub youngs_pa: f64,
    /// Poisson's ratio ν (-), in (-1, 0.5).
    pub poisson: f64,
    /// Density ρ (kg/m³).
    pub density_kgm3: f64,
    /// Yield strength (Pa), used only for the yield-velocity check (eq. 5.26).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub yield_strength_pa: Option<f64>,
}

impl Material {
    /// Acrylic (PMMA), thesis Table 6.2.
    pub const ACRYLIC: Material = Material {
        youngs_pa: 3.3e9,
        poisson: 0.37,
        density_kgm3: 1190.0,
        yield_strength_pa: Some(125e6),
    };
    /// Steel, thesis Table 5.1 (yield strength 1350 MPa, Section 5.5.4).
    pub const STEEL: Material = Material {
        youngs_pa: 206e9,
        poisson: 0.3,
        density_kgm3: 7860.0,
        yield_strength_pa: Some(1350e6),
    };
    /// Aluminium, thesis Table 5.2.
    pub const ALUMINIUM: Material = Material {
        youngs_pa: 70e9,
        poisson: 0.3,
        density_kgm3: 2699.0,
        yield_strength_pa: Some(100e6),
    };

    /// A rigid body: no compliance, only its Poisson ratio is irrelevant.
    pub const fn rigid() -> Material {
        Material {
            youngs_pa: f64::INFINITY,
            poisson: 0.0,
            density_kgm3: f64::INFINITY,
            yield_strength_pa: None,
        }
    }

    /// Shear modulus G = E / (2 (1 + ν)) (Pa).
    pub fn shear_modulus_pa(&self) -> f64 {
        self.youngs_pa / (2.0 * (1.0 + self.poisson))
    }

    /// Normal compliance term (1 - ν²)/E of eq. 5.6 (1/Pa); zero for a rigid body.
    pub fn normal_compliance(&self) -> f64 {
        (1.0 - self.poisson * self.poisson) / self.youngs_pa
    }

    /// Tangential compliance term (2 - ν)/G of eq. 5.14 (1/Pa); zero for a rigid body.
    pub fn shear_compliance(&self) -> f64 {
        (2.0 - self.poisson) / self.shear_modulus_pa()
    }

    /// Checks that the constants are physical; a refusal names the field (add
    /// the key of the table it sits in with [`InvalidParameter::within`]).
    pub fn validate(&self) -> Checked<()> {
        positive("youngs_pa", self.youngs_pa, "Pa")?;
        in_range(
            "poisson",
            self.poisson,
            "",
            Bound::Open(-1.0),
            Bound::Open(0.5),
        )?;
        positive("density_kgm3", self.density_kgm3, "kg/m^3")?;
        if let Some(y) = self.yield_strength_pa {
            positive("yield_strength_pa", y, "Pa")?;
        }
        Ok(())
    }
}

/// Equivalent Young's modulus E* of eq. 5.6 (corrected: `1 - ν²`), in Pa.
pub fn effective_youngs_pa(a: &Material, b: &Material) -> f64 {
    1.0 / (a.normal_compliance() + b.normal_compliance())
}

/// Equivalent shear modulus G* of eq. 5.14, in Pa.
pub fn effective_shear_pa(a: &Material, b: &Material) -> f64 {
    1.0 / (a.shear_compliance() + b.shear_compliance())
}

/// Equivalent radius R* of eq. 5.5 (m); pass `f64::INFINITY` for a flat wall.
pub fn effective_radius_m(r_i: f64, r_j: f64) -> f64 {
    1.0 / (1.0 / r_i + 1.0 / r_j)
}

/// Equivalent mass m* of eq. 5.9 (kg); pass `f64::INFINITY` for a wall.
pub fn effective_mass_kg(m_i: f64, m_j: f64) -> f64 {
    1.0 / (1.0 / m_i + 1.0 / m_j)
}

/// Mass of a sphere of radius `radius_m` (kg).
pub fn sphere_mass_kg(radius_m: f64, density_kgm3: f64) -> f64 {
    density_kgm3 * 4.0 / 3.0 * std::f64::consts::PI * radius_m.powi(3)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn acrylic_pair_moduli() {
        let a = Material::ACRYLIC;
        // E* = E / (2 (1 - ν²)) for identical materials.
        let e_star = effective_youngs_pa(&a, &a);
        assert!((e_star - 3.3e9 / (2.0 * (1.0 - 0.37 * 0.37))).abs() < 1e-3);
        // G* = G / (2 (2 - ν)).
        let g_star = effective_shear_pa(&a, &a);
        let g = 3.3e9 / (2.0 * 1.37);
        assert!((g_star - g / (2.0 * 1.63)).abs() < 1e-3);
    }

    #[test]
    fn rigid_wall_adds_no_compliance() {
        let s = Material::STEEL;
        let e_star = effective_youngs_pa(&s, &Material::rigid());
        assert!((e_star - 206e9 / (1.0 - 0.09)).abs() / e_star < 1e-14);
        assert_eq!(effective_radius_m(0.0025, f64::INFINITY), 0.0025);
        assert_eq!(effective_mass_kg(1.5, f64::INFINITY), 1.5);
    }

    #[test]
    fn thesis_particle_mass() {
        // 358 spheres of 5 mm acrylic weigh 0.0279 kg (docs/design.md, "Reference figures").
        let total = 358.0 * sphere_mass_kg(0.0025, 1190.0);
        assert!((total - 0.0279).abs() < 0.00005, "{total}");
    }

    #[test]
    fn validation_names_field_and_range() {
        let mut m = Material::ACRYLIC;
        m.poisson = 0.7;
        let err = m.validate().unwrap_err().within("particles.material");
        assert_eq!(
            err.to_string(),
            "particles.material.poisson = 0.7: must be in (-1, 0.5)"
        );
    }
}
