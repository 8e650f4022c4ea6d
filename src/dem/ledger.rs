//! The energy ledger: where every joule that enters the damper goes.
//!
//! The enclosure walls do work on the particles; that work is stored as kinetic
//! (translational + rotational), gravitational and elastic (normal + tangential
//! spring) energy, or dissipated in contacts (thesis eq. 6.3–6.7), split into
//! particle-particle / particle-wall and normal (impact damping) / tangential
//! (friction slip + tangential damping). Over any interval
//!
//! `work_in = ΔKE + ΔPE + ΔU_elastic + dissipated + residual`
//!
//! where the residual is what the time integration fails to conserve; it is
//! reported, never hidden. The tangential dissipation is the net loss of that
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
    /// (already netted out of the tangential dissipation).
    pub stiffness_work_j: f64,
    /// Energy dissipated in contacts.
    pub dissipated: Dissipation,
}

/// Mechanical energy stored at one instant (J).
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct EnergyState {
    pub kinetic_translational_j: f64,
    pub kinetic_rotational_j: f64,
    pub potential_j: f64,
    pub elastic_normal_j: f64,
    pub elastic_tangential_j: f64,
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
    /// `work_in - ΔKE - ΔPE - ΔU - dissipated`.
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
        LedgerBalance {
            work_in_j,
            stiffness_work_j,
            delta_kinetic_j,
            delta_potential_j,
            delta_elastic_j,
            dissipated_j,
            dissipated,
            residual_j: work_in_j
                - delta_kinetic_j
                - delta_potential_j
                - delta_elastic_j
                - dissipated_j,
        }
    }

    /// |residual| / dissipated, the figure of merit of the integration.
    pub fn residual_relative(&self) -> f64 {
        if self.dissipated_j > 0.0 {
            self.residual_j.abs() / self.dissipated_j
        } else {
            f64::INFINITY
        }
    }
}
