//! The energy books of the contacts (Terzioglu's thesis eq. 6.4, evaluated
//! as velocity Verlet applies the forces; the ledger itself is
//! [`crate::dem::ledger`]).
//!
//! What the contacts dissipate and store is summed per fixed block of
//! contacts (the walls of [`PARTICLE_BLOCK`] particles, or [`PAIR_BLOCK`]
//! pairs), in contact order within a block, into a [`BlockBooks`]; the block
//! sums are added to the ledger in block order ([`Books::book`]), on one core
//! and on many alike: no thread waits for a sum over every contact of the
//! step. The force of the walls on the particles, which drives an
//! electrodynamic shaker, is still summed contact by contact in order.
//!
//! The collisions are tallied the same way: the fewest steps a collision
//! that began this step will take (the Hertz duration at its approach speed,
//! eq. 5.10, over the step: what the time-step rule planned) and the fewest
//! a collision that ended this step took, counted step by step in its
//! contact state, and of those that ended the one planned the fewest (the
//! fastest) with its count; minima, so the same whatever the blocks.
//!
//! At the end of the step [`close_step`] books the work the walls did and,
//! as the integrator's own channel, whatever the work the contact forces
//! really did differs from what the contacts booked.
//!
//! [`PARTICLE_BLOCK`]: super::block_size::PARTICLE_BLOCK
//! [`PAIR_BLOCK`]: super::block_size::PAIR_BLOCK

use glam::DVec3;

use super::checks::{ImpactSpeeds, Limits, Refused};
use super::contacts::{ContactAt, ContactResult};
use crate::dem::ledger::Ledger;

/// Which kind of contact a block of books holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    Pair,
    Wall,
}

/// What the contacts of one block book over a step, summed in contact order
/// ([`Books::book`] adds the blocks to the ledger in block order). Aligned
/// to two cache lines, so that threads adding up neighbouring blocks never
/// write the same line.
#[derive(Debug, Clone)]
#[repr(align(128))]
pub struct BlockBooks {
    pub normal_j: f64,
    pub tangential_j: f64,
    pub stiffness_work_j: f64,
    pub integrator_j: f64,
    pub stored_change_j: f64,
    /// Fastest approach at contact onset (m/s).
    pub fastest_onset_mps: f64,
    /// Fewest steps an opening collision takes, as the Hertz duration at its
    /// approach speed predicts (what the time-step rule plans with).
    pub planned_steps: f64,
    /// Fewest steps a collision that ended took, counted; `u32::MAX` when
    /// none ended.
    pub fewest_counted_steps: u32,
    /// Of the collisions that ended, the one planned the fewest steps (the
    /// fastest): (planned, counted); the fewest counted among equals.
    pub fastest_counted: (f32, u32),
    /// Walls: each touching contact's wall and force on its particle, in
    /// order (their sum, the force of the walls, is taken contact by
    /// contact).
    pub wall_forces: Vec<(u32, DVec3)>,
    /// While dissipation is booked per particle: each contact's particles
    /// (the second unused for a wall) and dissipation (J), in order.
    pub dissipation: Vec<(u32, u32, f64)>,
    /// The first contact of the block that stops the run.
    pub refused: Option<Refused>,
}

impl Default for BlockBooks {
    fn default() -> Self {
        BlockBooks {
            normal_j: 0.0,
            tangential_j: 0.0,
            stiffness_work_j: 0.0,
            integrator_j: 0.0,
            stored_change_j: 0.0,
            fastest_onset_mps: 0.0,
            planned_steps: f64::INFINITY,
            fewest_counted_steps: u32::MAX,
            fastest_counted: (f32::INFINITY, u32::MAX),
            wall_forces: Vec::new(),
            dissipation: Vec::new(),
            refused: None,
        }
    }
}

impl BlockBooks {
    /// Empties the books for a new step, keeping the buffers.
    pub fn clear(&mut self) {
        let (mut forces, mut dissipation) = (
            std::mem::take(&mut self.wall_forces),
            std::mem::take(&mut self.dissipation),
        );
        forces.clear();
        dissipation.clear();
        *self = BlockBooks {
            wall_forces: forces,
            dissipation,
            ..BlockBooks::default()
        };
    }

    /// Checks contact `at` and books it; false (and the contact kept as the
    /// block's refusal) when it stops the run.
    #[inline(always)]
    pub fn add(&mut self, limits: &Limits, at: ContactAt, out: &ContactResult, dt: f64) -> bool {
        if let Err(why) = limits.check(out) {
            self.refused = Some((at, *out, why));
            return false;
        }
        self.fastest_onset_mps = self.fastest_onset_mps.max(out.onset_speed_mps);
        self.planned_steps = self.planned_steps.min(out.steps_per_collision);
        if out.counted_steps > 0 {
            let counted = (out.counted_planned_steps, out.counted_steps);
            self.fewest_counted_steps = self.fewest_counted_steps.min(counted.1);
            self.fastest_counted = faster(self.fastest_counted, counted);
        }
        if dt > 0.0 {
            self.normal_j += out.dissipated_normal_j;
            self.tangential_j += out.dissipated_tangential_j;
            self.stiffness_work_j += out.stiffness_work_j;
            self.integrator_j += out.integrator_j;
            self.stored_change_j += out.stored_change_j;
            if limits.per_particle {
                let e = out.dissipated_normal_j + out.dissipated_tangential_j;
                let (i, j) = match at {
                    ContactAt::Pair(i, j) => (i as u32, j as u32),
                    ContactAt::Wall(i, _) => (i as u32, u32::MAX),
                };
                self.dissipation.push((i, j, e));
            }
        }
        true
    }
}

/// The steps of one counted collision: planned when it began (the Hertz
/// duration at its approach speed over the step), and counted.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CollisionSteps {
    pub planned_steps: f32,
    pub counted_steps: u32,
}

/// The collision planned the fewest steps of `a` and `b`, (planned,
/// counted); of two planned alike, the one counted fewest. A minimum in a
/// total order, so the same whatever order the contacts come in.
#[inline(always)]
fn faster(a: (f32, u32), b: (f32, u32)) -> (f32, u32) {
    if b.0 < a.0 || (b.0 == a.0 && b.1 < a.1) {
        b
    } else {
        a
    }
}

/// Where the books of a step's contacts go: the world's ledger and records,
/// borrowed field by field.
pub struct Books<'a> {
    /// The cumulative energy flows.
    pub ledger: &'a mut Ledger,
    /// Change of the energy stored in the contacts over the step (J).
    pub stored_change_j: &'a mut f64,
    /// Fastest approach at contact onset, by kind of contact.
    pub impact_speeds: &'a mut ImpactSpeeds,
    /// Fewest steps an opening collision will take, as planned (the Hertz
    /// duration at its approach speed over the step).
    pub planned_steps_per_contact: &'a mut f64,
    /// Fewest steps a collision that ended took, counted; `None` while none
    /// ended.
    pub fewest_counted_steps_per_contact: &'a mut Option<u32>,
    /// Of the collisions that ended, the one planned the fewest steps.
    pub fastest_collision: &'a mut Option<CollisionSteps>,
    /// Force of the walls on the particles this step (N).
    pub wall_force: &'a mut DVec3,
    /// The same, wall by wall, in the order of the walls.
    pub wall_force_by_wall: &'a mut [DVec3],
    /// Energy each particle's contacts dissipated (J), while tracked.
    pub per_particle_j: Option<&'a mut [f64]>,
}

impl Books<'_> {
    /// Adds the books of the blocks of one kind of contact to the ledger, in
    /// block order, and stops the run at the first contact a block refused.
    pub fn book(&mut self, kind: Kind, blocks: &[BlockBooks], dt: f64) -> Result<(), Box<Refused>> {
        for b in blocks {
            if dt > 0.0 {
                let (normal, tangential) = match kind {
                    Kind::Pair => {
                        let d = &mut self.ledger.dissipated;
                        (&mut d.pp_normal, &mut d.pp_tangential)
                    }
                    Kind::Wall => {
                        let d = &mut self.ledger.dissipated;
                        (&mut d.pw_normal, &mut d.pw_tangential)
                    }
                };
                *normal += b.normal_j;
                *tangential += b.tangential_j;
                self.ledger.stiffness_work_j += b.stiffness_work_j;
                self.ledger.integrator_j += b.integrator_j;
                *self.stored_change_j += b.stored_change_j;
            }
            let fastest = match kind {
                Kind::Pair => &mut self.impact_speeds.particle_particle_mps,
                Kind::Wall => &mut self.impact_speeds.particle_wall_mps,
            };
            *fastest = fastest.max(b.fastest_onset_mps);
            *self.planned_steps_per_contact = self.planned_steps_per_contact.min(b.planned_steps);
            if b.fewest_counted_steps < u32::MAX {
                let fewest = &mut *self.fewest_counted_steps_per_contact;
                *fewest =
                    Some(fewest.map_or(b.fewest_counted_steps, |n| n.min(b.fewest_counted_steps)));
                let (planned, counted) = match *self.fastest_collision {
                    Some(c) => faster((c.planned_steps, c.counted_steps), b.fastest_counted),
                    None => b.fastest_counted,
                };
                *self.fastest_collision = Some(CollisionSteps {
                    planned_steps: planned,
                    counted_steps: counted,
                });
            }
            if kind == Kind::Wall {
                for &(w, f) in &b.wall_forces {
                    *self.wall_force += f;
                    self.wall_force_by_wall[w as usize] += f;
                }
            }
            if let (Some(per), true) = (self.per_particle_j.as_deref_mut(), dt > 0.0) {
                for &(i, j, e) in &b.dissipation {
                    if kind == Kind::Pair {
                        per[i as usize] += 0.5 * e;
                        per[j as usize] += 0.5 * e;
                    } else {
                        per[i as usize] += e;
                    }
                }
            }
            if let Some(refused) = b.refused {
                return Err(Box::new(refused));
            }
        }
        Ok(())
    }
}

/// Closes the books of a step: the work the walls did on the particles
/// (`work_in_j`, the trapezoid of their force over the stroke) is booked as
/// input, and what the contacts booked since `before` (stored, dissipated,
/// left over at opening) is held against the work their forces really did,
/// `contact_work_j`, as velocity Verlet applied them: the difference is
/// energy the discrete integration made or lost (the contact normal and
/// lever arms turn within a step, which the per-contact books do not see),
/// and goes to the integrator's channel.
pub fn close_step(
    ledger: &mut Ledger,
    before: &Ledger,
    stored_change_j: f64,
    contact_work_j: f64,
    work_in_j: f64,
) {
    ledger.work_in_j += work_in_j;
    let booked_j = stored_change_j
        + (ledger.dissipated.total() - before.dissipated.total())
        + (ledger.integrator_j - before.integrator_j);
    ledger.integrator_j += -(contact_work_j - work_in_j + booked_j);
}
