//! Closed-form results of Hertz theory for a head-on elastic impact, used as
//! references for the simulated contact and as validity limits.
//!
//! - maximum overlap, thesis eq. 5.8: `δ_max = (15 m* v² / (16 E* √R*))^{2/5}`;
//! - time to maximum overlap, eq. 5.10: `t_max = 1.435 (m*² / (E*² R* v))^{1/5}`;
//!   the contact lasts `2 t_max`;
//! - yield velocity, eq. 5.26 (Johnson): `v_y = √(107 R*³ σ_y⁵ / (E*⁴ m*))`, the
//!   impact speed above which the contact yields and the model's constant
//!   restitution no longer holds (Section 5.5.4).

use crate::maths;

/// Maximum overlap (m) of an elastic impact at approach speed `v_mps`, eq. 5.8.
pub fn max_overlap_m(m_star_kg: f64, e_star_pa: f64, r_star_m: f64, v_mps: f64) -> f64 {
    maths::powf(
        15.0 * m_star_kg * v_mps * v_mps / (16.0 * e_star_pa * r_star_m.sqrt()),
        0.4,
    )
}

/// Duration (s) of an elastic impact, twice eq. 5.10.
pub fn contact_duration_s(m_star_kg: f64, e_star_pa: f64, r_star_m: f64, v_mps: f64) -> f64 {
    2.0 * 1.435
        * maths::powf(
            m_star_kg * m_star_kg / (e_star_pa * e_star_pa * r_star_m * v_mps),
            0.2,
        )
}

/// Peak force (N) of an elastic impact: the Hertz force at the maximum overlap.
pub fn max_force_n(m_star_kg: f64, e_star_pa: f64, r_star_m: f64, v_mps: f64) -> f64 {
    let d = max_overlap_m(m_star_kg, e_star_pa, r_star_m, v_mps);
    4.0 / 3.0 * e_star_pa * r_star_m.sqrt() * maths::powf(d, 1.5)
}

/// Yield velocity (m/s) of eq. 5.26 for yield strength `yield_pa`.
pub fn yield_velocity_mps(m_star_kg: f64, e_star_pa: f64, r_star_m: f64, yield_pa: f64) -> f64 {
    (107.0 * r_star_m.powi(3) * yield_pa.powi(5) / (e_star_pa.powi(4) * m_star_kg)).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dem::material::{
        Material, effective_mass_kg, effective_radius_m, effective_youngs_pa, sphere_mass_kg,
    };

    fn sphere_sphere(mat: &Material, r: f64) -> (f64, f64, f64) {
        let m = sphere_mass_kg(r, mat.density_kgm3);
        (
            effective_mass_kg(m, m),
            effective_youngs_pa(mat, mat),
            effective_radius_m(r, r),
        )
    }

    #[test]
    fn yield_velocities_of_thesis_section_6_2_2() {
        // Thesis: 3.5 m/s for 5 mm acrylic sphere-sphere, 0.15 m/s for steel.
        let (m, e, r) = sphere_sphere(&Material::ACRYLIC, 0.0025);
        let v = yield_velocity_mps(m, e, r, 125e6);
        assert!((v - 3.5).abs() < 0.1, "acrylic {v}");
        let (m, e, r) = sphere_sphere(&Material::STEEL, 0.0025);
        let v = yield_velocity_mps(m, e, r, 1350e6);
        assert!((v - 0.15).abs() < 0.01, "steel {v}");
    }

    #[test]
    fn duration_constant_agrees_with_the_exact_hertz_integral() {
        // Exact: t_c = 2.9432 δ_max / v (from ∫ dδ / √(v² - (16/15) E* √R δ^{5/2} / m)).
        let (m, e, r, v) = (1e-4, 2e9, 1e-3, 1.0);
        let exact = 2.9432 * max_overlap_m(m, e, r, v) / v;
        let eq_5_10 = contact_duration_s(m, e, r, v);
        assert!((eq_5_10 / exact - 1.0).abs() < 1e-3, "{eq_5_10} vs {exact}");
    }
}
