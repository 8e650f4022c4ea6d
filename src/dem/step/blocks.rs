//! The pair contacts of one block of particles, and the forces that cross
//! into a block from earlier ones.
//!
//! A block owns its particles `s..e` ([`PARTICLE_BLOCK`] of them, a lump of
//! the bed once it is ordered in space) and their rows of the pair list
//! (the pairs `(i, j)`, `i` in the block): it advances those contacts'
//! states and adds their forces (eq. 3.25–3.28 of Terzioglu's thesis) to
//! its own particles as it goes ([`pair_rows`]). A pair whose second
//! particle is in a later block leaves that particle's share in the pair's
//! slot, and the later block adds it once every block has run
//! ([`cross_in`]). So each particle's force is summed in a fixed order —
//! gravity and its walls, its pairs within the block in pair order, then
//! the pairs that reach it from earlier blocks in pair order — whichever
//! thread runs which block, and no thread writes memory another block owns.
//!
//! [`PARTICLE_BLOCK`]: super::block_size::PARTICLE_BLOCK

use glam::DVec3;

use super::books::BlockBooks;
use super::checks::Limits;
use super::contacts::{Bodies, ContactAt, pair_contact};
use crate::dem::contact::{ContactLaw, ContactState};
use crate::dem::neighbours::Adjacency;

/// What a pair that crosses into a later block leaves for it: the force on
/// its first particle (the second gets the opposite) and the torque on the
/// second.
#[derive(Debug, Clone, Copy, Default)]
pub struct CrossForce {
    force_i: DVec3,
    torque_j: DVec3,
}

/// Where the pairs that cross into a later block leave their forces, each in
/// the slot of its place on the pair list (a block writes only the slots of
/// its own rows).
#[derive(Debug, Clone, Default)]
pub struct CrossSlots {
    /// Per pair: whether it acts this step (touches, or stopped touching).
    acts: Vec<bool>,
    /// Per pair: its forces, written only when it acts.
    force: Vec<CrossForce>,
}

impl CrossSlots {
    /// Room for `n_pairs` pairs.
    pub fn resize(&mut self, n_pairs: usize) {
        self.acts.resize(n_pairs, false);
        self.force.resize(n_pairs, CrossForce::default());
    }

    /// All the slots, to be cut into the blocks' runs.
    pub fn parts_mut(&mut self) -> CrossSlotsMut<'_> {
        CrossSlotsMut {
            acts: &mut self.acts,
            force: &mut self.force,
        }
    }
}

/// The slots of a run of the pair list, borrowed apart.
pub struct CrossSlotsMut<'a> {
    pub acts: &'a mut [bool],
    pub force: &'a mut [CrossForce],
}

/// The contact histories and gaps of a run of the pair list, borrowed apart.
pub struct PairRun<'a> {
    /// The pairs of the run.
    pub pairs: &'a [(u32, u32)],
    pub gaps: &'a mut [f64],
    pub states: &'a mut [ContactState],
    pub slots: CrossSlotsMut<'a>,
    /// Under a law of shared multi-point contacts: per pair, the count of
    /// contacts its bodies touch at ([`super::shared_contacts`]).
    pub shared: Option<&'a [u32]>,
}

/// The pair contacts of the rows of particles `start..start + force.len()`
/// (the run of the pair list in `run`): states advanced, books added in
/// pair order, each force added to the block's particles as it comes, a
/// pair into a later block leaving its second particle's share in its slot.
/// A contact that stops the run ends the block.
#[inline(always)]
pub fn pair_rows<const D: bool, const F: bool>(
    law: &ContactLaw,
    bodies: &Bodies,
    start: usize,
    run: PairRun,
    (force, torque): (&mut [DVec3], &mut [DVec3]),
    (limits, books): (&Limits, &mut BlockBooks),
    dt: f64,
) {
    books.clear();
    let end = start + force.len();
    // Room for every listed pair's dissipation, made as the list grows: no
    // step allocates for the books of its contacts.
    if limits.per_particle {
        books.dissipation.reserve(run.pairs.len());
    }
    let shared = run.shared;
    // Two instances: without shared contacts the count is none at compile
    // time, and the loop is the one it was before counts existed.
    match shared {
        None => pair_loop::<D, F>(
            law,
            bodies,
            (start, end),
            run,
            (force, torque),
            (limits, books),
            (dt, |_| None),
        ),
        Some(counts) => pair_loop::<D, F>(
            law,
            bodies,
            (start, end),
            run,
            (force, torque),
            (limits, books),
            (dt, |k| Some(counts[k])),
        ),
    }
}

/// The loop of [`pair_rows`] over the pairs of the rows `start..end`,
/// `count(k)` giving the `k`-th pair's count of shared contacts, if any
/// (the run's own counts are not read here).
#[inline(always)]
fn pair_loop<const D: bool, const F: bool>(
    law: &ContactLaw,
    bodies: &Bodies,
    (start, end): (usize, usize),
    run: PairRun,
    (force, torque): (&mut [DVec3], &mut [DVec3]),
    (limits, books): (&Limits, &mut BlockBooks),
    (dt, count): (f64, impl Fn(usize) -> Option<u32>),
) {
    let PairRun {
        pairs,
        gaps,
        states,
        slots,
        ..
    } = run;
    let history = gaps.iter_mut().zip(states.iter_mut());
    let out_slots = slots.acts.iter_mut().zip(slots.force.iter_mut());
    for (k, ((&(i, j), (gap, st)), (act, slot))) in
        pairs.iter().zip(history).zip(out_slots).enumerate()
    {
        let (i, j) = (i as usize, j as usize);
        let out = pair_contact::<D, F>(law, bodies, (i, j), (dt, count(k)), gap, st);
        let crosses = j >= end;
        if crosses {
            *act = out.is_some();
        }
        let Some(out) = out else {
            continue;
        };
        if !books.add(limits, ContactAt::Pair(i, j), &out, dt) {
            return;
        }
        force[i - start] += out.force_i;
        if F {
            torque[i - start] += out.torque_i;
        }
        if crosses {
            *slot = CrossForce {
                force_i: out.force_i,
                torque_j: out.torque_j,
            };
        } else {
            force[j - start] -= out.force_i;
            if F {
                torque[j - start] += out.torque_j;
            }
        }
    }
}

/// The shares a step's pairs left for later blocks, to be added to their
/// particles' forces before those are used: at the end of the force stage,
/// or by the half kick that follows it, block by block
/// ([`super::integrate`]), which saves the threads a pass and a wait.
#[derive(Clone, Copy)]
pub struct CrossShares<'a> {
    pub adjacency: &'a Adjacency,
    pub slots: &'a CrossSlots,
    /// The pairs have torques (their law has friction).
    pub torques: bool,
}

impl CrossShares<'_> {
    /// Adds to the forces (and torques) of particles `start..` the shares
    /// their pairs from earlier blocks left, each particle's in pair order.
    #[inline]
    pub fn add_to(&self, start: usize, force: &mut [DVec3], torque: &mut [DVec3]) {
        if self.torques {
            cross_in::<true>(self.adjacency, self.slots, start, force, torque);
        } else {
            cross_in::<false>(self.adjacency, self.slots, start, force, torque);
        }
    }
}

/// Adds to the forces (and torques, `F`) of particles `start..` the shares
/// their pairs from earlier blocks left in `slots`, each particle's in pair
/// order.
#[inline]
fn cross_in<const F: bool>(
    list: &Adjacency,
    slots: &CrossSlots,
    start: usize,
    force: &mut [DVec3],
    torque: &mut [DVec3],
) {
    for (m, (f, t)) in force.iter_mut().zip(torque.iter_mut()).enumerate() {
        for &k in list.cross_pairs(start + m) {
            let k = k as usize;
            if !slots.acts[k] {
                continue;
            }
            let c = &slots.force[k];
            *f -= c.force_i;
            if F {
                *t += c.torque_j;
            }
        }
    }
}
