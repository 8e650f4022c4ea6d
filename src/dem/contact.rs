//! One contact: the contact law and its sub-models, as small pure functions,
//! and the energy each of them stores or dissipates.
//!
//! A [`ContactLaw`] is built once per kind of contact from a [`ContactParams`]
//! (restitution, friction, restitution mode) and composes three sub-models,
//! the way LAMMPS' granular pair style composes named ones:
//!
//! - normal: Hertz, [`hertz_force_n`] (thesis eq. 5.7);
//! - damping: [`NormalDamping::Restitution`], [`normal_damping_nspm`] (eq. 5.32;
//!   with the no-pull clamp [`clamped_normal_force_n`], Section 5.5.3), or
//!   [`NormalDamping::Elastic`] when e = 1;
//! - tangential: [`Tangential::MindlinCoulomb`], [`mindlin_coulomb`] (eq. 5.15,
//!   5.16, 5.24, 5.33, with the erratum of eq. 3.9: the spring stretch is the
//!   *vector* tangential displacement), or [`Tangential::Frictionless`] when
//!   μ = 0, which keeps no history;
//! - multi-point: [`MultiPoint::Independent`], every sub-sphere contact of a
//!   rigid body a whole contact (the thesis' multi-sphere model, Section 4.2,
//!   EDEM's), or [`MultiPoint::Shared`], the `n` sub-sphere contacts a body
//!   pair (or a body and a wall) touch at at once each carrying `1/n` of one
//!   contact: the law with E*, G* and m* scaled by `1/n`
//!   ([`ContactGeometry::share`]), so that `n` alike contacts side by side
//!   make one contact of the asked stiffness, damping and restitution.
//!
//! Normal: `f_el = 4/3 E* √R* δ^{3/2}`, damping `f_d = c_n δ̇` with
//! `c_n = 2 √(5/6) β √(2 E* √(R* δ) m*)`; the total `f_n = max(0, f_el + f_d)`
//! never pulls.
//!
//! Tangential: a spring history `ξ` is created when the contact opens, rotated
//! into the current tangent plane every step (keeping its length), incremented
//! by the relative tangential displacement, and gives `F_t = -k_t ξ - c_t v_t`
//! with the Mindlin stiffness `k_t = 8 G* √(R* δ)` and `c_t = 2 √(5/6) β √(k_t m*)`.
//! When `|F_t| > μ f_n` the contact slips: `F_t` is scaled back to `μ f_n` (eq.
//! 5.16) and the spring is shortened, if needed, so that it carries no more than
//! `μ f_n` (it is never lengthened). The history is dropped when the bodies
//! separate.
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
use serde::{Deserialize, Serialize};

use super::material::{Material, effective_shear_pa, effective_youngs_pa};
use super::restitution::RestitutionMode;

/// How a contact turns restitution into damping (thesis Section 5.5.3).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum NormalDamping {
    /// `e = 1`: no damping is computed at all.
    Elastic,
    /// The restitution dashpot of eq. 5.32 (and 5.33 tangentially):
    /// `c = 2 √(5/6) β √(S m*)`.
    Restitution {
        /// `2 √(5/6) β √(2 E*)`, so that `c_n = coeff √(√(R* δ) m*)`.
        coeff: f64,
    },
}

/// The tangential sub-model.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Tangential {
    /// `μ = 0`: no tangential force and no history.
    Frictionless,
    /// Mindlin no-slip spring `k_t = 8 G* √(R* δ)` (eq. 5.24) with a vector
    /// history, tangential damping (eq. 5.33), capped by Coulomb slip (eq. 5.16).
    MindlinCoulomb {
        /// `8 G*`, so that `k_t = shear_coeff √(R* δ)`.
        shear_coeff: f64,
        /// `c_t / c_n = √(k_t / S_n) = √(4 G* / E*)`.
        damping_ratio: f64,
        /// Coefficient of friction μ.
        friction: f64,
    },
}

/// How the sub-sphere contacts a rigid body touches another body (or a
/// wall) at, at the same time, combine.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum MultiPoint {
    /// Each sub-sphere contact is a whole Hertz–Mindlin contact calibrated
    /// on the two bodies' masses: the thesis' multi-sphere model (Section
    /// 4.2, as EDEM's). A body pair touching at `n` sub-spheres is up to
    /// `n` times as stiff, and loses more, than asked.
    #[default]
    Independent,
    /// The `n` sub-sphere contacts a body pair (or a body and a wall) touch
    /// at, counted every step, share one contact: each is the law with E*,
    /// G* and m* scaled by `1/n` (its whole force scaled by `1/n`).
    Shared,
}

impl MultiPoint {
    /// True for the thesis' model (the default, left out of printed scenes).
    pub fn is_independent(&self) -> bool {
        *self == MultiPoint::Independent
    }

    /// The name a scene file gives it.
    pub fn as_str(self) -> &'static str {
        match self {
            MultiPoint::Independent => "independent",
            MultiPoint::Shared => "shared",
        }
    }
}

/// What a scene says about one kind of contact: restitution, friction and how
/// the damping is derived from the restitution.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactParams {
    /// Normal coefficient of restitution e, in (0, 1].
    pub restitution: f64,
    /// Coefficient of friction μ, ≥ 0.
    pub friction: f64,
    /// How β follows from e.
    pub mode: RestitutionMode,
}

/// The contact law of one kind of contact (a pair of materials with its e and
/// μ), built once from its [`ContactParams`]: the Hertz normal spring, a damping
/// sub-model and a tangential sub-model, each chosen by what the spec needs
/// (as LAMMPS' granular pair style composes named sub-models). A law with
/// `e = 1` computes no damping; one with `μ = 0` keeps no tangential history.
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
    /// `4/3 E*`: the Hertz force is `hertz_coeff √(R* δ) δ` (eq. 5.7).
    hertz_coeff: f64,
    pub damping: NormalDamping,
    pub tangential: Tangential,
    /// How a body's simultaneous sub-sphere contacts combine.
    pub multi_point: MultiPoint,
}

impl ContactLaw {
    /// Law for bodies of materials `a` and `b` with restitution `e` and friction `mu`.
    pub fn new(a: &Material, b: &Material, e: f64, mu: f64, mode: RestitutionMode) -> Self {
        Self::from_spec(
            a,
            b,
            &ContactParams {
                restitution: e,
                friction: mu,
                mode,
            },
        )
    }

    /// Law for bodies of materials `a` and `b` as `spec` describes it.
    pub fn from_spec(a: &Material, b: &Material, spec: &ContactParams) -> Self {
        Self::assemble(
            effective_youngs_pa(a, b),
            effective_shear_pa(a, b),
            spec.mode.damping_factor(spec.restitution),
            spec.restitution,
            spec.friction,
        )
    }

    /// The same law with both moduli scaled by `factor` (a softer or stiffer
    /// spring of the same restitution and friction).
    pub fn with_stiffness_scaled(&self, factor: f64) -> Self {
        Self {
            multi_point: self.multi_point,
            ..Self::assemble(
                self.e_star_pa * factor,
                self.g_star_pa * factor,
                self.damping_factor,
                self.restitution,
                self.friction,
            )
        }
    }

    /// The same law without friction.
    pub fn without_friction(&self) -> Self {
        Self {
            multi_point: self.multi_point,
            ..Self::assemble(
                self.e_star_pa,
                self.g_star_pa,
                self.damping_factor,
                self.restitution,
                0.0,
            )
        }
    }

    /// The same law with its sub-sphere contacts combined as `multi_point` says.
    pub fn with_multi_point(self, multi_point: MultiPoint) -> Self {
        Self {
            multi_point,
            ..self
        }
    }

    /// The law of moduli `e_star`, `g_star`, damping factor `beta`.
    fn assemble(e_star: f64, g_star: f64, beta: f64, restitution: f64, friction: f64) -> Self {
        let damping = if beta > 0.0 {
            NormalDamping::Restitution {
                // c_n = 2 √(5/6) β √(2 E*) · √(√(R* δ) m*)
                coeff: 2.0 * (5.0f64 / 6.0).sqrt() * beta * (2.0 * e_star).sqrt(),
            }
        } else {
            NormalDamping::Elastic
        };
        let tangential = if friction > 0.0 {
            Tangential::MindlinCoulomb {
                shear_coeff: 8.0 * g_star,
                damping_ratio: (4.0 * g_star / e_star).sqrt(),
                friction,
            }
        } else {
            Tangential::Frictionless
        };
        ContactLaw {
            e_star_pa: e_star,
            g_star_pa: g_star,
            friction,
            restitution,
            damping_factor: beta,
            hertz_coeff: 4.0 / 3.0 * e_star,
            damping,
            tangential,
            multi_point: MultiPoint::Independent,
        }
    }

    /// The sub-models by name, e.g. `hertz + restitution + mindlin-coulomb`.
    pub fn describe(&self) -> String {
        let damping = match self.damping {
            NormalDamping::Elastic => "elastic",
            NormalDamping::Restitution { .. } => "restitution",
        };
        let tangential = match self.tangential {
            Tangential::Frictionless => "frictionless",
            Tangential::MindlinCoulomb { .. } => "mindlin-coulomb",
        };
        match self.multi_point {
            MultiPoint::Independent => format!("hertz + {damping} + {tangential}"),
            MultiPoint::Shared => format!("hertz + {damping} + {tangential}, shared multi-point"),
        }
    }

    /// True when the law has a tangential force (and so spins the particles).
    pub fn has_friction(&self) -> bool {
        matches!(self.tangential, Tangential::MindlinCoulomb { .. })
    }

    /// Hertz elastic normal force (N) at overlap `delta_m`, eq. 5.7.
    pub fn hertz_force_n(&self, r_star_m: f64, delta_m: f64) -> f64 {
        hertz_force_n(self.hertz_coeff, (r_star_m * delta_m).sqrt(), delta_m)
    }

    /// Elastic energy (J) of a Hertz contact: ∫ f_el dδ = 8/15 E* √R* δ^{5/2}.
    pub fn hertz_energy_j(&self, r_star_m: f64, delta_m: f64) -> f64 {
        0.4 * self.hertz_force_n(r_star_m, delta_m) * delta_m
    }

    /// Mindlin tangential stiffness k_t = 8 G* √(R* δ) (N/m), eq. 5.24.
    pub fn tangential_stiffness_npm(&self, r_star_m: f64, delta_m: f64) -> f64 {
        8.0 * self.g_star_pa * (r_star_m * delta_m).sqrt()
    }

    /// Normal damping coefficient c_n (N s/m), eq. 5.32.
    pub fn normal_damping_nspm(&self, r_star_m: f64, m_star_kg: f64, delta_m: f64) -> f64 {
        match self.damping {
            NormalDamping::Elastic => 0.0,
            NormalDamping::Restitution { coeff } => {
                normal_damping_nspm(coeff, (r_star_m * delta_m).sqrt(), m_star_kg)
            }
        }
    }

    /// Tangential damping coefficient c_t = c_n √(k_t / S_n) (N s/m), eq. 5.33.
    pub fn tangential_damping_nspm(&self, r_star_m: f64, m_star_kg: f64, delta_m: f64) -> f64 {
        match self.tangential {
            Tangential::Frictionless => 0.0,
            Tangential::MindlinCoulomb { damping_ratio, .. } => {
                damping_ratio * self.normal_damping_nspm(r_star_m, m_star_kg, delta_m)
            }
        }
    }
}

/// Hertz elastic normal force (N), eq. 5.7: `f_el = 4/3 E* √(R* δ) δ`, given
/// `hertz_coeff = 4/3 E*` and `sqrt_rd = √(R* δ)`.
#[inline]
pub fn hertz_force_n(hertz_coeff: f64, sqrt_rd: f64, delta_m: f64) -> f64 {
    hertz_coeff * sqrt_rd * delta_m
}

/// Restitution damping coefficient (N s/m), eq. 5.32:
/// `c_n = 2 √(5/6) β √(2 E* √(R* δ) m*)`, given `coeff = 2 √(5/6) β √(2 E*)`.
#[inline]
pub fn normal_damping_nspm(coeff: f64, sqrt_rd: f64, m_star_kg: f64) -> f64 {
    coeff * (sqrt_rd * m_star_kg).sqrt()
}

/// The normal force magnitude (N): spring plus dashpot at approach speed
/// `v_n_mps` (positive while compressing), never attractive (Section 5.5.3).
#[inline]
pub fn clamped_normal_force_n(f_el: f64, c_n: f64, v_n_mps: f64) -> f64 {
    (f_el + c_n * v_n_mps).max(0.0)
}

/// Mindlin tangential spring with Coulomb slip (eq. 5.15, 5.16, 5.24, 5.33),
/// over one step: the rotated history `xi_rot` grows by the tangential
/// displacement `ds`; the force is `-k_t ξ - c_t v_t`, capped at `cap = μ f_n`.
/// On slip the force is the cap along the trial force and the spring shrinks,
/// if needed, to carry at most the cap; it is never stretched beyond the
/// accumulated displacement (at contact onset the cap is set by damping,
/// ∝ δ^{1/4}, while k_t ∝ δ^{1/2}). Returns (force on body i, new history).
#[inline]
pub fn mindlin_coulomb(
    k_t: f64,
    c_t: f64,
    cap: f64,
    xi_rot: DVec3,
    ds: DVec3,
    v_t: DVec3,
) -> (DVec3, DVec3) {
    let xi_trial = xi_rot + ds;
    let f_trial = -k_t * xi_trial - c_t * v_t;
    let f_trial_sq = f_trial.length_squared();
    if f_trial_sq > cap * cap {
        let ft = f_trial * (cap / f_trial_sq.sqrt());
        let spring = k_t * xi_trial.length();
        let xi = if spring > cap {
            xi_trial * (cap / spring)
        } else {
            xi_trial
        };
        (ft, xi)
    } else {
        (f_trial, xi_trial)
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
    /// Elastic (Hertz) part of the normal force at the previous step (N).
    pub fel_prev: f64,
    /// Elastic energy of the normal spring as the integrator stored it (J):
    /// the trapezoidal work `½ (f_el,prev + f_el) (δ - δ_prev)` summed since
    /// the contact opened, not the exact Hertz potential.
    pub u_normal_j: f64,
    /// Steps this contact has touched so far (the overlap positive at the
    /// end of each), counted from the step it began in; zero when apart, and
    /// for a contact whose beginning was not seen (open when the world was
    /// built or when the counting restarted), which is never counted. Kept
    /// by the step's contact kernels, not by the law.
    pub steps_touching: u32,
    /// Steps the Hertz duration at the approach speed planned for this
    /// collision when it began (while it is counted; an f32 so that the
    /// entry stays 96 bytes).
    pub planned_steps: f32,
}

impl ContactState {
    /// A state for bodies that are `delta_m` apart (negative) and not touching.
    pub fn apart(delta_m: f64) -> Self {
        ContactState {
            delta_prev: delta_m,
            ..Default::default()
        }
    }

    /// Elastic energy stored in the contact now (J): (normal, tangential). The
    /// normal part is the trapezoidal work the integrator did on the Hertz
    /// spring ([`Self::u_normal_j`]); it differs from the exact potential
    /// `8/15 E* √R* δ^{5/2}` by the integrator's error, O(Δt²).
    pub fn stored_energy_j(&self) -> (f64, f64) {
        if self.delta_prev <= 0.0 {
            return (0.0, 0.0);
        }
        (
            self.u_normal_j,
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
    /// Energy the integrator lost in this contact (J), booked when it opens:
    /// what the trapezoidal work left in the normal spring when the overlap is
    /// back to zero (exactly zero for an exact integration).
    pub integrator_j: f64,
    /// Change of the energy stored in the contact over the step (J): normal
    /// (trapezoidal) plus tangential spring.
    pub stored_change_j: f64,
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
    /// The part of one contact this one carries: 1, or `1/n` for one of the
    /// `n` sub-sphere contacts a body pair shares ([`MultiPoint::Shared`]).
    /// Its forces, stiffnesses and stored energies are the whole law's times
    /// this; its spring history and its Hertz duration are the whole law's.
    pub share: f64,
}

/// Evaluates one contact over a step of `dt_s`: updates `state` and returns forces
/// and energies. The law's sub-models are resolved here, once per call; a
/// caller that evaluates many contacts of one law can pick the instance itself
/// with [`evaluate_contact_with`].
#[inline]
pub fn evaluate_contact(
    law: &ContactLaw,
    geometry: &ContactGeometry,
    dt_s: f64,
    state: &mut ContactState,
) -> ContactOutput {
    match (law.damping, law.tangential) {
        (NormalDamping::Restitution { .. }, Tangential::MindlinCoulomb { .. }) => {
            evaluate_contact_with::<true, true>(law, geometry, dt_s, state)
        }
        (NormalDamping::Restitution { .. }, Tangential::Frictionless) => {
            evaluate_contact_with::<true, false>(law, geometry, dt_s, state)
        }
        (NormalDamping::Elastic, Tangential::MindlinCoulomb { .. }) => {
            evaluate_contact_with::<false, true>(law, geometry, dt_s, state)
        }
        (NormalDamping::Elastic, Tangential::Frictionless) => {
            evaluate_contact_with::<false, false>(law, geometry, dt_s, state)
        }
    }
}

/// [`evaluate_contact`] for a law whose damping is present (`DAMPED`) and whose
/// tangential sub-model is Mindlin–Coulomb (`FRICTION`), as the caller knows;
/// the sub-models a law lacks are not computed.
#[inline(always)]
pub fn evaluate_contact_with<const DAMPED: bool, const FRICTION: bool>(
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
        share,
    } = *geometry;
    let v_n = v_rel.dot(n);
    let mut out = ContactOutput::default();
    let (stored_before_n, stored_before_t) = state.stored_energy_j();
    let stored_before = stored_before_n + stored_before_t;

    if delta_m <= 0.0 {
        if state.delta_prev > 0.0 {
            close_opened::<FRICTION>(geometry, v_n, dt_s, state, &mut out);
        }
        *state = ContactState::apart(delta_m);
        out.stored_change_j = -stored_before;
        return out;
    }

    // Normal: Hertz spring plus restitution damping, never attractive; a
    // shared contact's E* and m* scaled by its share (so both by the share;
    // a whole contact's times 1 are its own bits).
    let sqrt_rd = (r_star_m * delta_m).sqrt();
    let f_el = hertz_force_n(law.hertz_coeff, sqrt_rd, delta_m) * share;
    let c_n = match law.damping {
        NormalDamping::Restitution { coeff } if DAMPED => {
            normal_damping_nspm(coeff, sqrt_rd, m_star_kg) * share
        }
        _ => 0.0,
    };
    let f_n = if DAMPED {
        clamped_normal_force_n(f_el, c_n, v_n)
    } else {
        f_el
    };
    let f_d = f_n - f_el;
    out.normal_force_n = f_n;
    if dt_s > 0.0 {
        state.u_normal_j += 0.5 * (state.fel_prev + f_el) * (delta_m - state.delta_prev);
    } else {
        // A pure evaluation (a new world, new laws): the spring holds the exact
        // Hertz energy of the overlap it starts with.
        state.u_normal_j = 0.4 * f_el * delta_m;
    }
    if DAMPED {
        out.dissipated_normal_j = 0.5 * (state.fd_prev + f_d) * (delta_m - state.delta_prev);
    }

    // Tangential: Mindlin spring with vector history, damping, Coulomb slip.
    let (ft, k_t) = if FRICTION {
        let normal = (sqrt_rd, c_n, f_n);
        tangential_step(&law.tangential, geometry, normal, dt_s, state, &mut out)
    } else {
        (DVec3::ZERO, 0.0)
    };

    state.ft_prev = ft;
    state.fd_prev = f_d;
    state.fel_prev = f_el;
    state.delta_prev = delta_m;
    state.kt_prev = k_t;
    out.tangential_on_i = ft;
    out.force_on_i = ft - f_n * n;
    let (stored_n, stored_t) = state.stored_energy_j();
    out.stored_change_j = stored_n + stored_t - stored_before;
    out
}

/// The books of a contact that opened during a step of `dt_s` (its overlap
/// now `geometry.delta_m` ≤ 0, before it `state.delta_prev` > 0): the
/// integrator applied the last forces over half of the step, and their work
/// closes the books. Apart from [`evaluate_contact_with`] to keep it short;
/// always inlined into it.
#[inline(always)]
fn close_opened<const FRICTION: bool>(
    geometry: &ContactGeometry,
    v_n: f64,
    dt_s: f64,
    state: &ContactState,
    out: &mut ContactOutput,
) {
    let (delta_m, n, v_rel) = (geometry.delta_m, geometry.normal, geometry.v_rel);
    out.dissipated_normal_j = 0.5 * state.fd_prev * (delta_m - state.delta_prev);
    out.integrator_j = state.u_normal_j + 0.5 * state.fel_prev * (delta_m - state.delta_prev);
    if FRICTION {
        let ds = (v_rel - v_n * n) * dt_s;
        let stored = 0.5 * state.kt_prev * state.xi.length_squared();
        out.dissipated_tangential_j = -0.5 * state.ft_prev.dot(ds) + stored;
        out.stiffness_work_j = -stored;
    }
}

/// The tangential part of a touching contact over a step of `dt_s`: the
/// Mindlin spring with its vector history rotated into the tangent plane,
/// damping and Coulomb slip (eq. 5.15, 5.16, 5.24, 5.33), given `√(R* δ)`,
/// the normal damping `c_n` and the normal force `f_n`. Advances the history
/// in `state`, books the tangential dissipation and stiffness work in `out`,
/// and returns the tangential force on body `i` and the stiffness k_t.
/// Always inlined into [`evaluate_contact_with`].
#[inline(always)]
fn tangential_step(
    model: &Tangential,
    geometry: &ContactGeometry,
    (sqrt_rd, c_n, f_n): (f64, f64, f64),
    dt_s: f64,
    state: &mut ContactState,
    out: &mut ContactOutput,
) -> (DVec3, f64) {
    let Tangential::MindlinCoulomb {
        shear_coeff,
        damping_ratio,
        friction,
    } = *model
    else {
        return (DVec3::ZERO, 0.0);
    };
    let (n, v_rel) = (geometry.normal, geometry.v_rel);
    let v_n = v_rel.dot(n);
    let v_t = v_rel - v_n * n;
    let ds = v_t * dt_s;
    let k_t = shear_coeff * sqrt_rd * geometry.share;
    let c_t = c_n * damping_ratio;
    let xi_rot = rotate_into_plane(state.xi, n);
    let xi_sq = xi_rot.length_squared();
    let (ft, xi_new) = mindlin_coulomb(k_t, c_t, friction * f_n, xi_rot, ds, v_t);
    let taken = -0.5 * (state.ft_prev + ft).dot(ds);
    let stored_before = 0.5 * state.kt_prev * xi_sq;
    out.dissipated_tangential_j = taken - (0.5 * k_t * xi_new.length_squared() - stored_before);
    out.stiffness_work_j = 0.5 * (k_t - state.kt_prev) * xi_sq;
    state.xi = xi_new;
    (ft, k_t)
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
        let c_t = law.tangential_damping_nspm(r, m, d);
        assert!((c_t - c_t_thesis).abs() / c_t < 1e-12);
    }

    #[test]
    fn the_law_leaves_out_what_its_spec_does_not_need() {
        let a = Material::ACRYLIC;
        let full = ContactLaw::new(&a, &a, 0.86, 0.52, RestitutionMode::Exact);
        assert_eq!(full.describe(), "hertz + restitution + mindlin-coulomb");
        let elastic = ContactLaw::new(&a, &a, 1.0, 0.52, RestitutionMode::Exact);
        assert_eq!(elastic.damping, NormalDamping::Elastic);
        let smooth = ContactLaw::new(&a, &a, 0.86, 0.0, RestitutionMode::Exact);
        assert_eq!(smooth.tangential, Tangential::Frictionless);
        assert!(!smooth.has_friction());
        // A frictionless contact keeps no history and exerts no tangential force.
        let mut st = ContactState::apart(0.0);
        let g = ContactGeometry {
            r_star_m: 1.25e-3,
            m_star_kg: 3.9e-5,
            delta_m: 1e-6,
            normal: DVec3::Z,
            v_rel: DVec3::new(0.3, 0.0, 0.1),
            share: 1.0,
        };
        let out = evaluate_contact(&smooth, &g, 1e-7, &mut st);
        assert_eq!(out.tangential_on_i, DVec3::ZERO);
        assert_eq!(st.xi, DVec3::ZERO);
        // The instance chosen by the law gives the same as the dispatcher.
        let (mut s1, mut s2) = (ContactState::apart(0.0), ContactState::apart(0.0));
        let a1 = evaluate_contact(&full, &g, 1e-7, &mut s1);
        let a2 = evaluate_contact_with::<true, true>(&full, &g, 1e-7, &mut s2);
        assert_eq!(a1, a2);
        assert_eq!(s1, s2);
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
            share: 1.0,
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
            share: 1.0,
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
