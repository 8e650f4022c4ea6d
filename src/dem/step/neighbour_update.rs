//! The neighbour update: the Verlet pair list (Section 3.4 of Terzioglu's
//! thesis, [`crate::dem::neighbours`]) is rebuilt when some particle drifted
//! more than half the skin from where it was built, which the drift reports
//! ([`super::integrate::KickSums::moved_far`]), or when it was built for
//! another number of particles. Otherwise the list, and every contact
//! history on it, carries over.
//!
//! A bed of more than one block ([`super::block_size::spans_blocks`]) is
//! renumbered in space at each rebuild ([`crate::dem::ordering`]): the
//! particles, their wall contacts and what they dissipated move to their new
//! numbers, and the pair list carries every history over under them. The
//! sub-spheres of a rigid body are ordered by where the body is, so they
//! stay together.

use crate::dem::contact::ContactState;
use crate::dem::neighbours::NeighbourList;
use crate::dem::ordering::{Renumbering, is_identity, space_order};
use crate::dem::particles::Particles;

use super::block_size::spans_blocks;

/// What a renumbering moves besides the particles and the pair list,
/// borrowed from the world field by field.
pub struct PerParticle<'a> {
    /// Contact state of particle `i` with wall `w` at `i * n_walls + w`.
    pub wall_states: &'a mut Vec<ContactState>,
    /// Overlap of particle `i` with wall `w` at the previous step (m).
    pub wall_gaps: &'a mut Vec<f64>,
    pub n_walls: usize,
    /// Energy each particle dissipated (J), while tracked.
    pub dissipation_j: Option<&'a mut Vec<f64>>,
}

/// Scratch of the renumbering, kept between rebuilds.
#[derive(Debug, Clone, Default)]
pub struct OrderScratch {
    keys: Vec<(u64, u32, u32)>,
    order: Vec<u32>,
    /// Each particle's position, or its body's centre for a sub-sphere.
    at_body: Vec<glam::DVec3>,
    /// The renumbering's cycles, applied to every array in place.
    cycles: Renumbering,
}

/// Rebuilds `list` for `particles` if it may miss a contact now,
/// renumbering a bed of several blocks in space first.
pub fn update(
    list: &mut NeighbourList,
    particles: &mut Particles,
    others: PerParticle,
    scratch: &mut OrderScratch,
    moved_far: bool,
) {
    if moved_far || list.reference().len() != particles.len() {
        rebuild(list, particles, others, scratch);
    }
}

/// Rebuilds `list` for `particles`, renumbering a bed of several blocks in
/// space first.
fn rebuild(
    list: &mut NeighbourList,
    particles: &mut Particles,
    others: PerParticle,
    scratch: &mut OrderScratch,
) {
    if !spans_blocks(particles.len()) {
        list.rebuild(&particles.position, &particles.radius, &particles.clump);
        return;
    }
    let cell_m = list.cell_m(particles.max_radius_m());
    let OrderScratch {
        keys,
        order,
        at_body,
        cycles,
    } = scratch;
    let placed = if particles.clumps.is_empty() {
        &particles.position
    } else {
        // A body's sub-spheres are ordered where its centre is, so that they
        // stay together in the arrays (ties by id keep them in id order).
        at_body.clear();
        at_body.extend_from_slice(&particles.position);
        let c = &particles.clumps;
        for b in 0..c.len() {
            for slot in c.slots(b) {
                at_body[c.index[slot] as usize] = c.position[b];
            }
        }
        &*at_body
    };
    space_order(placed, &particles.id, cell_m, keys, order);
    if is_identity(order) {
        list.rebuild(&particles.position, &particles.radius, &particles.clump);
        return;
    }
    cycles.find(order);
    particles.renumber_by(cycles, order);
    // A world being built has no wall contacts yet: they are read afresh.
    if others.wall_states.len() == order.len() * others.n_walls {
        cycles.apply_rows(others.wall_states, order, others.n_walls);
        cycles.apply_rows(others.wall_gaps, order, others.n_walls);
    }
    if let Some(d) = others.dissipation_j {
        cycles.apply(d, order);
    }
    list.rebuild_renumbered(
        &particles.position,
        &particles.radius,
        &particles.clump,
        Some(order),
    );
}
