//! The time step: Rayleigh estimate and stability limit (thesis eq. 3.31–3.32).
//!
//! `Δt_R = π R_min √(ρ/G) / (0.1631 ν + 0.8766)` is the time a Rayleigh surface wave
//! needs to cross a particle. vlab treats it as the stability limit: an explicit
//! step above it is refused. The working step is `S_f Δt_R` with a safety factor
//! `S_f` (typically 0.1–0.4; the thesis used 1e-6 s, i.e. S_f ≈ 0.12 for 5 mm
//! acrylic, whose Δt_R is 8.3e-6 s).

use super::contact::ContactLaw;
use super::hertz_theory;
use super::material::{Material, effective_mass_kg, effective_radius_m, sphere_mass_kg};
use crate::validation::{Bound, Checked, InvalidParameter, in_range};

/// Rayleigh time step (s) of eq. 3.31 for spheres of radius `radius_min_m`.
pub fn rayleigh_time_step_s(material: &Material, radius_min_m: f64) -> f64 {
    let g = material.shear_modulus_pa();
    std::f64::consts::PI * radius_min_m * (material.density_kgm3 / g).sqrt()
        / (0.1631 * material.poisson + 0.8766)
}

/// The shortest Hertz contact (s) of identical spheres of `radius_m` and
/// density `density_kgm3`, against each other (law `pp`) and against a flat
/// wall (law `pw`), at relative impact speed `speed_mps`: twice eq. 5.10 with
/// each law's equivalent modulus.
pub fn shortest_contact_s(
    pp: &ContactLaw,
    pw: &ContactLaw,
    radius_m: f64,
    density_kgm3: f64,
    speed_mps: f64,
) -> f64 {
    let m = sphere_mass_kg(radius_m, density_kgm3);
    shortest_contact_with_mass_s(pp, pw, radius_m, m, speed_mps)
}

/// [`shortest_contact_s`] for contacts of spheres of `radius_m` that move
/// with a mass of `mass_kg`: the sub-spheres of rigid bodies, whose contacts
/// read their body's mass (thesis Section 4.2: the smallest sub-sphere sets
/// the step).
pub fn shortest_contact_with_mass_s(
    pp: &ContactLaw,
    pw: &ContactLaw,
    radius_m: f64,
    m: f64,
    speed_mps: f64,
) -> f64 {
    let pair = hertz_theory::contact_duration_s(
        effective_mass_kg(m, m),
        pp.e_star_pa,
        effective_radius_m(radius_m, radius_m),
        speed_mps,
    );
    let wall = hertz_theory::contact_duration_s(m, pw.e_star_pa, radius_m, speed_mps);
    pair.min(wall)
}

/// Default safety factor on the Rayleigh step when a scene does not fix Δt.
pub const DEFAULT_SAFETY_FACTOR: f64 = 0.2;

/// Checks an explicit time step `dt_s`, named `key`, against the Rayleigh
/// limit `limit_s`.
pub fn check_time_step(key: &str, dt_s: f64, limit_s: f64) -> Checked<f64> {
    let least_s = limit_s / MAX_STEPS_PER_RAYLEIGH;
    in_range(
        key,
        dt_s,
        "s",
        Bound::Closed(least_s),
        Bound::Closed(limit_s),
    )
    .map_err(|e| InvalidParameter {
        valid: format!(
            "at most the stability limit {limit_s:.3e} s (Rayleigh estimate, thesis eq. 3.31; the thesis used 1e-6 s for 5 mm acrylic) and at least a thousandth of it, {least_s:.3e} s (finer gains nothing and a run would not end)"
        ),
        ..e
    })
}

/// Steps a Rayleigh step may be cut into at most: the accuracy study finds
/// the energy per cycle settled by 0.05 of it (20 steps), and a step a
/// thousandth of it already makes a second of drive about 10^8 steps.
pub const MAX_STEPS_PER_RAYLEIGH: f64 = 1000.0;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn thesis_acrylic_rayleigh_step() {
        // docs/design.md, "Reference figures": 8.3e-6 s for 5 mm acrylic
        // (thesis Table 6.1 prints 8.4e-6 s).
        let dt = rayleigh_time_step_s(&Material::ACRYLIC, 0.0025);
        assert!((dt - 8.33e-6).abs() < 0.02e-6, "{dt}");
    }

    #[test]
    fn refuses_step_above_limit() {
        let err = check_time_step("dt_s", 1e-5, 8.3e-6)
            .unwrap_err()
            .to_string();
        assert!(
            err.starts_with("dt_s = 0.00001 s: must be at most the stability limit 8.300e-6 s"),
            "{err}"
        );
        assert!(check_time_step("dt_s", 1e-6, 8.3e-6).is_ok());
        assert!(check_time_step("dt_s", f64::NAN, 8.3e-6).is_err());
        // A step that would never end a run: a thousandth of the limit at
        // least (it was accepted, and a run at 1e-15 s never ended).
        let err = check_time_step("dt_s", 1e-15, 8.3e-6)
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("at least a thousandth of it, 8.300e-9 s"),
            "{err}"
        );
        assert!(check_time_step("dt_s", 8.3e-9, 8.3e-6).is_ok());
    }
}
