//! The energy ledger: where every joule that enters the damper goes.
//!
//! The enclosure walls do work on the particles; that work is stored as kinetic
//! (translational + rotational), gravitational and elastic (normal + tangential
//! spring) energy, or dissipated in contacts (thesis eq. 6.3–6.7), split into
//! particle-particle / particle-wall and normal (impact damping) / tangential
//! (friction slip + tangential damping). Over any interval
//!
//! `work_in = ΔKE + ΔPE + ΔU_elastic + dissipated + integrator + residual`
//!
//! - `ΔU_elastic` is the energy the integrator stored in the springs: for the
//!   Hertz spring the trapezoidal work `½ (f_el,prev + f_el) Δδ` it did, not the
//!   exact potential `8/15 E* √R* δ^{5/2}` (they differ by O(Δt²)).
//! - `integrator` is the time integration's own energy error, booked as a named
//!   channel: what the trapezoidal work leaves in a Hertz spring when its
//!   contact opens; the difference, each step, between the work the contact
//!   forces really do on the particles (trapezoid on the drift `v_half Δt`,
//!   `ω_half Δt`) and what the contacts book (their normals and lever arms turn
//!   within a step); and velocity Verlet's shadow term: it conserves
//!   `KE - Σ Δt² |F|² / 8m` (and the rotational analogue), not KE. It falls as
//!   Δt² (4.2x when Δt halves, thesis run); on the thesis run it is 4e-4 of
//!   the dissipated energy at Δt = 1e-6 s.
//! - the `residual` is then rounding (about 1e-14 of the dissipated energy on
//!   the thesis run): it checks that the books are consistent, and it is
//!   reported, never hidden.
//!
//! The tangential dissipation is the net loss of that
//! channel, friction slip plus tangential damping less the `stiffness_work` the
//! Mindlin springs gain because their stiffness follows the overlap (see
//! `contact`); the stiffness work is kept as a separate figure.

use serde::Serialize;

/// Dissipated energy by source (J).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct Dissipation {
    pub pp_normal: f64,
    pub pp_tangential: f64,
    pub pw_normal: f64,
    pub pw_tangential: f64,
}

impl Dissipation {
    /// Sum of all four sources (J).
    pub fn total(&self) -> f64 {
        self.pp_normal + self.pp_tangential + self.pw_normal + self.pw_tangential
    }

    /// Component-wise difference `self - earlier`.
    pub fn since(&self, earlier: &Dissipation) -> Dissipation {
        Dissipation {
            pp_normal: self.pp_normal - earlier.pp_normal,
            pp_tangential: self.pp_tangential - earlier.pp_tangential,
            pw_normal: self.pw_normal - earlier.pw_normal,
            pw_tangential: self.pw_tangential - earlier.pw_tangential,
        }
    }

    /// Every component scaled by `k`.
    pub fn scaled(&self, k: f64) -> Dissipation {
        Dissipation {
            pp_normal: self.pp_normal * k,
            pp_tangential: self.pp_tangential * k,
            pw_normal: self.pw_normal * k,
            pw_tangential: self.pw_tangential * k,
        }
    }
}

/// Cumulative energy flows since the world was created (J).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct Ledger {
    /// Work done by the walls on the particles.
    pub work_in_j: f64,
    /// Energy the change of the Mindlin stiffness added to the tangential springs
    /// (already netted out of the tangential dissipation), and, under shared
    /// multi-point contacts, the change of a shared normal spring's stiffness
    /// when its body pair's count of contacts changed (netted out of the
    /// normal dissipation).
    pub stiffness_work_j: f64,
    /// Energy dissipated in contacts.
    pub dissipated: Dissipation,
    /// Energy the time integration lost (J; negative: created), booked as it
    /// happens: what the trapezoidal work left in each contact's normal spring
    /// when it opened.
    pub integrator_j: f64,
}

/// Mechanical energy stored at one instant (J).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct EnergyState {
    pub kinetic_translational_j: f64,
    pub kinetic_rotational_j: f64,
    pub potential_j: f64,
    pub elastic_normal_j: f64,
    pub elastic_tangential_j: f64,
    /// `Σ Δt² |F|² / (8 m) + Δt² |τ|² / (8 I)`: velocity Verlet conserves
    /// `KE - verlet_shadow_j`, not KE itself, so the kinetic energy it shows
    /// at an instant differs from the work done by this much (J).
    pub verlet_shadow_j: f64,
}

impl EnergyState {
    /// Kinetic energy, translational plus rotational (J).
    pub fn kinetic_j(&self) -> f64 {
        self.kinetic_translational_j + self.kinetic_rotational_j
    }

    /// Elastic energy, normal plus tangential (J).
    pub fn elastic_j(&self) -> f64 {
        self.elastic_normal_j + self.elastic_tangential_j
    }

    /// Total mechanical energy (J).
    pub fn total_j(&self) -> f64 {
        self.kinetic_j() + self.potential_j + self.elastic_j()
    }
}

/// A ledger reading: cumulative flows and stored energy at one instant.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct LedgerSnapshot {
    pub time_s: f64,
    pub flows: Ledger,
    pub stored: EnergyState,
}

/// The balance of an interval between two snapshots (J).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct LedgerBalance {
    pub work_in_j: f64,
    pub stiffness_work_j: f64,
    pub delta_kinetic_j: f64,
    pub delta_potential_j: f64,
    pub delta_elastic_j: f64,
    pub dissipated_j: f64,
    pub dissipated: Dissipation,
    /// Energy the time integration lost over the interval (J).
    pub integrator_j: f64,
    /// `work_in - ΔKE - ΔPE - ΔU - dissipated - integrator`.
    pub residual_j: f64,
}

impl LedgerBalance {
    /// Balance from `start` to `end`.
    pub fn between(start: &LedgerSnapshot, end: &LedgerSnapshot) -> Self {
        let dissipated = end.flows.dissipated.since(&start.flows.dissipated);
        let work_in_j = end.flows.work_in_j - start.flows.work_in_j;
        let stiffness_work_j = end.flows.stiffness_work_j - start.flows.stiffness_work_j;
        let delta_kinetic_j = end.stored.kinetic_j() - start.stored.kinetic_j();
        let delta_potential_j = end.stored.potential_j - start.stored.potential_j;
        let delta_elastic_j = end.stored.elastic_j() - start.stored.elastic_j();
        let dissipated_j = dissipated.total();
        let integrator_j = end.flows.integrator_j
            - start.flows.integrator_j
            - (end.stored.verlet_shadow_j - start.stored.verlet_shadow_j);
        LedgerBalance {
            work_in_j,
            stiffness_work_j,
            delta_kinetic_j,
            delta_potential_j,
            delta_elastic_j,
            dissipated_j,
            dissipated,
            integrator_j,
            residual_j: work_in_j
                - delta_kinetic_j
                - delta_potential_j
                - delta_elastic_j
                - dissipated_j
                - integrator_j,
        }
    }

    /// The energy that flowed: the dissipated energy, or the work put in when
    /// that is larger (a lossless bed dissipates nothing and heats up) (J).
    pub fn energy_flowed_j(&self) -> f64 {
        self.dissipated_j.max(self.work_in_j.abs())
    }

    /// |residual| / [`Self::energy_flowed_j`] (infinite when no energy
    /// flowed). Rounding by construction, since the integration term is the
    /// books' remainder: a check of the bookkeeping code, not of the physics;
    /// [`Self::integrator_relative`] is the energy check.
    pub fn residual_relative(&self) -> f64 {
        self.relative(self.residual_j.abs())
    }

    /// The integration's own energy error / [`Self::energy_flowed_j`]
    /// (positive: it lost energy).
    pub fn integrator_relative(&self) -> f64 {
        self.relative(self.integrator_j)
    }

    fn relative(&self, x_j: f64) -> f64 {
        let scale = self.energy_flowed_j();
        if scale > 0.0 {
            x_j / scale
        } else {
            f64::INFINITY
        }
    }
}
