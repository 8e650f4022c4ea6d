//! One contact: Hertz normal force, Mindlin tangential spring history, restitution
//! damping, Coulomb slip, and the energy each of them stores or dissipates.
//!
//! Normal (thesis eq. 5.7, 5.21, 5.32): `f_el = 4/3 E* √R* δ^{3/2}`, damping
//! `f_d = c_n δ̇` with `c_n = 2 √(5/6) β √(2 E* √(R* δ) m*)`; the total
//! `f_n = max(0, f_el + f_d)` never pulls (the clamp discussed in Section 5.5.3).
//!
//! Tangential (eq. 5.15, 5.22, 5.24, 5.33, with the erratum of eq. 3.9: the spring
//! stretch is the *vector* tangential displacement, not the integral of its speed):
//! a spring history `ξ` is created when the contact opens, rotated into the current
//! tangent plane every step (keeping its length), incremented by the relative
//! tangential displacement, and gives `F_t = -k_t ξ - c_t v_t` with the Mindlin
//! stiffness `k_t = 8 G* √(R* δ)` and `c_t = 2 √(5/6) β √(k_t m*)`. When
//! `|F_t| > μ f_n` the contact slips: `F_t` is scaled back to `μ f_n` (eq. 5.16) and
//! the spring is shortened, if needed, so that it carries no more than `μ f_n`
//! (it is never lengthened). The history is dropped when the bodies separate.
//!
//! Energy bookkeeping (thesis eq. 6.4, evaluated so that it is consistent with the
//! velocity-Verlet integrator): over a step the contact forces act on the relative
//! displacement with the trapezoidal average of their values at the two ends of
//! the step, which is exactly what the integrator feeds into the kinetic energy.
//! - normal dissipation: `½ (f_d,prev + f_d) (δ - δ_prev)`, where `f_d = f_n - f_el`
//!   includes the clamp;
//! - tangential dissipation: the work the tangential force takes from the relative
//!   motion minus the change of the energy stored in the spring, `½ k_t |ξ|²`. That
//!   is friction slip plus tangential damping, less the *stiffness work*
//!   `½ (k_t - k_t,prev) |ξ|²`: because the Mindlin stiffness follows the overlap
//!   while ξ is held, the spring gains energy no force put in while the contact is
//!   loaded and loses it while unloading. The model (eq. 5.15 with k_t of eq. 5.24)
//!   is not conservative; over an oblique impact this term is several per cent of
//!   the loss. The dissipation reported is the net loss, so that it is exactly what
//!   the walls must supply in steady state (what Yang's method measures); the
//!   stiffness work is reported on its own for transparency.

use glam::DVec3;

use super::material::{Material, effective_shear_pa, effective_youngs_pa};
use super::restitution::RestitutionMode;

/// Constants of one kind of contact (a pair of materials with its e and μ).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactLaw {
    /// Equivalent Young's modulus E* (Pa), eq. 5.6.
    pub e_star_pa: f64,
    /// Equivalent shear modulus G* (Pa), eq. 5.14.
    pub g_star_pa: f64,
    /// Coefficient of friction μ (-).
    pub friction: f64,
    /// Configured normal restitution e (-).
    pub restitution: f64,
    /// Damping factor β (-), from `restitution` by the chosen mode.
    pub damping_factor: f64,
    hertz_coeff: f64,
    damping_coeff: f64,
    tangential_damping_ratio: f64,
    shear_coeff: f64,
}

impl ContactLaw {
    /// Law for bodies of materials `a` and `b` with restitution `e` and friction `mu`.
    pub fn new(a: &Material, b: &Material, e: f64, mu: f64, mode: RestitutionMode) -> Self {
        let e_star = effective_youngs_pa(a, b);
        let g_star = effective_shear_pa(a, b);
        let beta = mode.damping_factor(e);
        ContactLaw {
            e_star_pa: e_star,
            g_star_pa: g_star,
            friction: mu,
            restitution: e,
            damping_factor: beta,
            hertz_coeff: 4.0 / 3.0 * e_star,
            // c_n = 2 √(5/6) β √(2 E*) · √(√(R* δ) m*)
            damping_coeff: 2.0 * (5.0f64 / 6.0).sqrt() * beta * (2.0 * e_star).sqrt(),
            // c_t / c_n = √(k_t / S_n) = √(8 G* / 2 E*)
            tangential_damping_ratio: (4.0 * g_star / e_star).sqrt(),
            shear_coeff: 8.0 * g_star,
        }
    }

    /// Hertz elastic normal force (N) at overlap `delta_m`, eq. 5.7.
    pub fn hertz_force_n(&self, r_star_m: f64, delta_m: f64) -> f64 {
        self.hertz_coeff * (r_star_m * delta_m).sqrt() * delta_m
    }

    /// Elastic energy (J) of a Hertz contact: ∫ f_el dδ = 8/15 E* √R* δ^{5/2}.
    pub fn hertz_energy_j(&self, r_star_m: f64, delta_m: f64) -> f64 {
        0.4 * self.hertz_force_n(r_star_m, delta_m) * delta_m
    }

    /// Mindlin tangential stiffness k_t = 8 G* √(R* δ) (N/m), eq. 5.24.
    pub fn tangential_stiffness_npm(&self, r_star_m: f64, delta_m: f64) -> f64 {
        self.shear_coeff * (r_star_m * delta_m).sqrt()
    }

    /// Normal damping coefficient c_n (N s/m), eq. 5.32.
    pub fn normal_damping_nspm(&self, r_star_m: f64, m_star_kg: f64, delta_m: f64) -> f64 {
        self.damping_coeff * ((r_star_m * delta_m).sqrt() * m_star_kg).sqrt()
    }
}

/// What a contact remembers from one step to the next.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct ContactState {
    /// Tangential spring stretch ξ (m), in the tangent plane.
    pub xi: DVec3,
    /// Tangential force on body `i` at the previous step (N).
    pub ft_prev: DVec3,
    /// Damping part of the normal force at the previous step (N), clamp included.
    pub fd_prev: f64,
    /// Overlap at the previous step (m); negative is a gap.
    pub delta_prev: f64,
    /// Tangential stiffness at the previous step (N/m); zero when apart.
    pub kt_prev: f64,
}

impl ContactState {
    /// A state for bodies that are `delta_m` apart (negative) and not touching.
    pub fn apart(delta_m: f64) -> Self {
        ContactState {
            delta_prev: delta_m,
            ..Default::default()
        }
    }

    /// Elastic energy stored in the contact now (J): (normal, tangential).
    pub fn stored_energy_j(&self, law: &ContactLaw, r_star_m: f64) -> (f64, f64) {
        if self.delta_prev <= 0.0 {
            return (0.0, 0.0);
        }
        (
            law.hertz_energy_j(r_star_m, self.delta_prev),
            0.5 * self.kt_prev * self.xi.length_squared(),
        )
    }
}

/// Result of evaluating a contact over one step.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct ContactOutput {
    /// Total contact force on body `i` (N).
    pub force_on_i: DVec3,
    /// Tangential part of `force_on_i` (N), for the torque.
    pub tangential_on_i: DVec3,
    /// Normal force magnitude f_n ≥ 0 (N).
    pub normal_force_n: f64,
    /// Energy dissipated by normal damping during the step (J).
    pub dissipated_normal_j: f64,
    /// Net energy lost through the tangential channel during the step (J): slip
    /// plus tangential damping less the stiffness work.
    pub dissipated_tangential_j: f64,
    /// Energy the change of k_t added to the spring (J); already subtracted from
    /// `dissipated_tangential_j`, reported for transparency.
    pub stiffness_work_j: f64,
}

/// Rotates the spring stretch into the tangent plane of `n`, keeping its length.
fn rotate_into_plane(xi: DVec3, n: DVec3) -> DVec3 {
    let len_sq = xi.length_squared();
    if len_sq == 0.0 {
        return xi;
    }
    let projected = xi - xi.dot(n) * n;
    let proj_sq = projected.length_squared();
    if proj_sq == 0.0 {
        return DVec3::ZERO;
    }
    projected * (len_sq / proj_sq).sqrt()
}

/// Where and how fast a contact is, this step.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactGeometry {
    /// Equivalent radius R* (m).
    pub r_star_m: f64,
    /// Equivalent mass m* (kg).
    pub m_star_kg: f64,
    /// Overlap now (m); negative: apart.
    pub delta_m: f64,
    /// Unit normal from body `i` towards body `j` (or the wall).
    pub normal: DVec3,
    /// Velocity of `i`'s contact point minus that of `j` over the step (m/s).
    pub v_rel: DVec3,
}

/// Evaluates one contact over a step of `dt_s`: updates `state` and returns forces
/// and energies. A frictionless law keeps no tangential history.
#[inline]
pub fn evaluate_contact(
    law: &ContactLaw,
    geometry: &ContactGeometry,
    dt_s: f64,
    state: &mut ContactState,
) -> ContactOutput {
    let ContactGeometry {
        r_star_m,
        m_star_kg,
        delta_m,
        normal: n,
        v_rel,
    } = *geometry;
    let v_n = v_rel.dot(n);
    let v_t = v_rel - v_n * n;
    let ds = v_t * dt_s;
    let mut out = ContactOutput::default();

    if delta_m <= 0.0 {
        if state.delta_prev > 0.0 {
            // The contact opened during this step. The integrator applied the last
            // forces over half of the step; their work closes the books.
            out.dissipated_normal_j = 0.5 * state.fd_prev * (delta_m - state.delta_prev);
            let stored = 0.5 * state.kt_prev * state.xi.length_squared();
            out.dissipated_tangential_j = -0.5 * state.ft_prev.dot(ds) + stored;
            out.stiffness_work_j = -stored;
        }
        *state = ContactState::apart(delta_m);
        return out;
    }

    // Normal: Hertz spring plus restitution damping, never attractive.
    let sqrt_rd = (r_star_m * delta_m).sqrt();
    let f_el = law.hertz_coeff * sqrt_rd * delta_m;
    let c_n = law.damping_coeff * (sqrt_rd * m_star_kg).sqrt();
    let f_n = (f_el + c_n * v_n).max(0.0);
    let f_d = f_n - f_el;
    out.normal_force_n = f_n;
    out.dissipated_normal_j = 0.5 * (state.fd_prev + f_d) * (delta_m - state.delta_prev);

    // Tangential: Mindlin spring with vector history, damping, Coulomb slip.
    let mut ft = DVec3::ZERO;
    let mut k_t = 0.0;
    if law.friction > 0.0 {
        k_t = law.shear_coeff * sqrt_rd;
        let c_t = c_n * law.tangential_damping_ratio;
        let xi_rot = rotate_into_plane(state.xi, n);
        let xi_sq = xi_rot.length_squared();
        let xi_trial = xi_rot + ds;
        let f_trial = -k_t * xi_trial - c_t * v_t;
        let cap = law.friction * f_n;
        let f_trial_sq = f_trial.length_squared();
        let xi_new = if f_trial_sq > cap * cap {
            // Slip: the force is μ f_n along the trial force (eq. 5.16). The spring
            // only ever shrinks, to carry at most μ f_n; it is never stretched
            // beyond the accumulated displacement (at contact onset the cap is set
            // by damping, ∝ δ^{1/4}, while k_t ∝ δ^{1/2}).
            ft = f_trial * (cap / f_trial_sq.sqrt());
            let spring = k_t * xi_trial.length();
            if spring > cap {
                xi_trial * (cap / spring)
            } else {
                xi_trial
            }
        } else {
            ft = f_trial;
            xi_trial
        };
        let taken = -0.5 * (state.ft_prev + ft).dot(ds);
        let stored_before = 0.5 * state.kt_prev * xi_sq;
        out.dissipated_tangential_j = taken - (0.5 * k_t * xi_new.length_squared() - stored_before);
        out.stiffness_work_j = 0.5 * (k_t - state.kt_prev) * xi_sq;
        state.xi = xi_new;
    }

    state.ft_prev = ft;
    state.fd_prev = f_d;
    state.delta_prev = delta_m;
    state.kt_prev = k_t;
    out.tangential_on_i = ft;
    out.force_on_i = ft - f_n * n;
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn acrylic_law(e: f64, mu: f64) -> ContactLaw {
        let a = Material::ACRYLIC;
        ContactLaw::new(&a, &a, e, mu, RestitutionMode::Thesis)
    }

    #[test]
    fn damping_matches_thesis_eq_5_32_and_5_33() {
        // Eq. 5.32: c_n = -√5 ln e/√(ln²e+π²) √(k_n m*), k_n = 4/3 E* √(R* δ);
        // eq. 5.33: c_t = -√(10/3) (same factor) √(k_t m*).
        let law = acrylic_law(0.86, 0.5);
        let (r, m, d): (f64, f64, f64) = (1.25e-3, 3.9e-5, 2e-6);
        let beta = law.damping_factor;
        let k_n = 4.0 / 3.0 * law.e_star_pa * (r * d).sqrt();
        let c_n_thesis = 5f64.sqrt() * beta * (k_n * m).sqrt();
        let c_n = law.normal_damping_nspm(r, m, d);
        assert!((c_n - c_n_thesis).abs() / c_n < 1e-12);
        let k_t = law.tangential_stiffness_npm(r, d);
        let c_t_thesis = (10.0f64 / 3.0).sqrt() * beta * (k_t * m).sqrt();
        let c_t = c_n * law.tangential_damping_ratio;
        assert!((c_t - c_t_thesis).abs() / c_t < 1e-12);
    }

    #[test]
    fn normal_force_never_pulls() {
        let law = acrylic_law(0.3, 0.0);
        let mut st = ContactState::apart(0.0);
        st.delta_prev = 1e-6;
        // Separating fast at a tiny overlap: damping would pull, the clamp forbids it.
        let g = ContactGeometry {
            r_star_m: 1e-3,
            m_star_kg: 1e-4,
            delta_m: 1e-9,
            normal: DVec3::Z,
            v_rel: -DVec3::Z * 5.0,
        };
        let out = evaluate_contact(&law, &g, 1e-7, &mut st);
        assert_eq!(out.normal_force_n, 0.0);
        assert_eq!(out.force_on_i, DVec3::ZERO);
    }

    #[test]
    fn history_rotates_with_the_contact_keeping_its_length() {
        let xi = DVec3::new(1e-6, 0.0, 0.0);
        let n = DVec3::new(0.1, 0.0, 1.0).normalize();
        let r = rotate_into_plane(xi, n);
        assert!(r.dot(n).abs() < 1e-20);
        assert!((r.length() - 1e-6).abs() < 1e-18);
    }

    #[test]
    fn sticking_contact_stores_slipping_contact_dissipates() {
        let law = acrylic_law(1.0, 0.5); // no damping
        let (r, m, d, dt) = (1.25e-3, 3.9e-5, 1e-6, 1e-7);
        let f_n = law.hertz_force_n(r, d);
        let mut st = ContactState::apart(d);
        st.delta_prev = d;
        let v = DVec3::new(1e-3, 0.0, 0.0);
        let g = ContactGeometry {
            r_star_m: r,
            m_star_kg: m,
            delta_m: d,
            normal: DVec3::Z,
            v_rel: v,
        };
        // A small tangential creep sticks: no dissipation, force = -k_t ξ.
        let out = evaluate_contact(&law, &g, dt, &mut st);
        let k_t = law.tangential_stiffness_npm(r, d);
        assert!((out.tangential_on_i.x + k_t * 1e-10).abs() < 1e-12 * k_t);
        assert!(out.dissipated_tangential_j.abs() < 1e-25);
        // Keep pushing until the spring reaches μ f_n: then it slides at μ f_n.
        for _ in 0..100_000 {
            evaluate_contact(&law, &g, dt, &mut st);
        }
        let out = evaluate_contact(&law, &g, dt, &mut st);
        assert!((out.tangential_on_i.length() - 0.5 * f_n).abs() < 1e-12 * f_n);
        // Steady sliding dissipates μ f_n |v| dt per step.
        let expect = 0.5 * f_n * 1e-3 * dt;
        assert!((out.dissipated_tangential_j - expect).abs() < 1e-9 * expect);
    }
}
