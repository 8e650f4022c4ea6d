//! The refusals: what stops a run as numerically unsound, and the diagnosis
//! it is stopped with.
//!
//! Per contact, as the force stage evaluates it ([`Limits::check`]): a
//! collision resolved in fewer time steps than asked (its Hertz duration,
//! eq. 5.10 of Terzioglu's thesis, over the step), an overlap deeper than
//! asked, a particle whose centre is past a wall. Per step: a position that
//! is not finite after the drift. Every few thousand steps: energy books
//! that no longer close ([`energy_closes`], the balance of eq. 6.4 against
//! what the integration made or lost). The fastest approach at contact
//! onset is kept too ([`ImpactSpeeds`]), to hold against the yield velocity
//! of eq. 5.26 (the model's validity, Section 5.5.4).

use super::contacts::{ContactAt, ContactResult};
use crate::dem::error::DemError;
use crate::dem::ledger::{LedgerBalance, LedgerSnapshot};

/// Largest normal approach speeds at contact onset (m/s), to hold against the
/// yield velocity of thesis eq. 5.26 (the model's validity, Section 5.5.4).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct ImpactSpeeds {
    pub particle_particle_mps: f64,
    pub particle_wall_mps: f64,
}

/// Why a contact stops the run.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Refusal {
    /// Resolved in fewer steps than `min_steps_per_collision`.
    Unresolved,
    /// Deeper than `max_overlap_ratio`.
    Overlap,
    /// The particle's centre is past the wall.
    Escaped,
}

/// The contact that stopped the run, what it computed and why it stops it
/// (boxed when returned: it is large, and rare).
pub type Refused = (ContactAt, ContactResult, Refusal);

/// What the stability checks refuse, and whether dissipation is booked per
/// particle, for the contacts of a step.
#[derive(Debug, Clone, Copy)]
pub struct Limits {
    pub min_steps_per_collision: f64,
    pub max_overlap_ratio: f64,
    pub per_particle: bool,
}

impl Limits {
    /// A collision resolved in too few steps or an excessive overlap stops
    /// the run.
    #[inline(always)]
    pub fn check(&self, out: &ContactResult) -> Result<(), Refusal> {
        if out.steps_per_collision < self.min_steps_per_collision {
            Err(Refusal::Unresolved)
        } else if out.overlap_ratio > self.max_overlap_ratio {
            Err(Refusal::Overlap)
        } else {
            Ok(())
        }
    }
}

/// Where a run stands when a check fails, for the diagnosis.
#[derive(Debug, Clone, Copy)]
pub struct Diagnosis<'a> {
    /// Simulated time before the step (s).
    pub time_s: f64,
    /// Steps taken before the step.
    pub steps: u64,
    /// The world's time step (s).
    pub dt_s: f64,
    /// The overlap limit, as a fraction of the smaller radius.
    pub max_overlap_ratio: f64,
    /// The walls' names, by wall number.
    pub wall_names: &'a [&'static str],
    /// The particles' ids, by their place in the arrays: a diagnosis names
    /// a particle by its id.
    pub ids: &'a [u32],
}

impl Diagnosis<'_> {
    /// Human-readable name of a contact, for diagnoses.
    fn contact_name(&self, at: ContactAt) -> String {
        match at {
            ContactAt::Pair(i, j) => {
                let (a, b) = (self.id(i), self.id(j));
                format!("particle-particle ({}, {})", a.min(b), a.max(b))
            }
            ContactAt::Wall(i, w) => {
                format!("particle-{} (particle {})", self.wall_names[w], self.id(i))
            }
        }
    }

    /// The id of the particle at place `k` of the arrays.
    fn id(&self, k: usize) -> usize {
        self.ids.get(k).map_or(k, |&id| id as usize)
    }

    /// The error that stops the run at the contact a step of `dt` (0 for a
    /// pure evaluation) refused.
    pub fn refusal(&self, (at, out, why): &Refused, dt: f64) -> DemError {
        match why {
            Refusal::Unresolved => {
                let duration_s = out.steps_per_collision * dt;
                DemError::UnresolvedCollision {
                    time_s: self.time_s + dt,
                    step: self.steps + 1,
                    contact: self.contact_name(*at),
                    speed_mps: out.onset_speed_mps,
                    duration_s,
                    steps: out.steps_per_collision,
                    dt_s: dt,
                    suggested_dt_s: duration_s / 20.0,
                }
            }
            Refusal::Overlap => DemError::ExcessiveOverlap {
                time_s: self.time_s + dt,
                step: self.steps + 1,
                contact: self.contact_name(*at),
                overlap_percent: 100.0 * out.overlap_ratio,
                limit_percent: 100.0 * self.max_overlap_ratio,
                speed_mps: out.approach_mps,
                dt_s: self.dt_s,
            },
            Refusal::Escaped => {
                let (i, w) = match *at {
                    ContactAt::Wall(i, w) | ContactAt::Pair(i, w) => (i, w),
                };
                DemError::Escaped {
                    time_s: self.time_s + dt,
                    step: self.steps + 1,
                    particle: self.id(i),
                    wall: self.wall_names[w].to_string(),
                    dt_s: self.dt_s,
                }
            }
        }
    }

    /// The error that stops the run when particle `particle` left the finite
    /// numbers in the drift of a step of `dt`.
    pub fn nonfinite(&self, particle: usize, dt: f64) -> DemError {
        DemError::NonFinite {
            time_s: self.time_s + dt,
            step: self.steps + 1,
            particle: self.id(particle),
            dt_s: dt,
        }
    }
}

/// Checks that the energy books still close between the `baseline` and
/// `now` (at `time_s`, after `step` steps of `dt_s`): energy the integration
/// made or lost (its own channel plus the residual) above 2 % of the energy
/// in play (kinetic + elastic + dissipated + |work in|) means the
/// integration has gone wrong, typically energy growing without any input
/// because the step is too coarse.
pub fn energy_closes(
    baseline: &LedgerSnapshot,
    now: &LedgerSnapshot,
    (time_s, step, dt_s): (f64, u64, f64),
) -> Result<(), DemError> {
    let b = LedgerBalance::between(baseline, now);
    let in_play = now.stored.kinetic_j()
        + now.stored.elastic_j()
        + baseline.stored.kinetic_j()
        + baseline.stored.elastic_j()
        + b.dissipated_j.abs()
        + b.work_in_j.abs();
    let unaccounted = b.residual_j.abs() + b.integrator_j.abs();
    if in_play > 0.0 && unaccounted > 0.02 * in_play {
        return Err(DemError::EnergyNotConserved {
            time_s,
            step,
            residual_j: b.residual_j - b.integrator_j,
            percent: 100.0 * unaccounted / in_play,
            dt_s,
        });
    }
    Ok(())
}
