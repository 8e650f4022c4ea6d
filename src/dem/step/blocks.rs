//! The parallel pair blocks and their gather.
//!
//! Above [`AUTO_PARALLEL_MIN_PAIRS`] listed pairs the pair loop is cut into
//! fixed blocks of [`PAIR_BLOCK`] pairs across the threads ([`pair_blocks`]):
//! each pair advances its contact state and leaves its forces (eq. 3.25–3.28
//! of Terzioglu's thesis) in its own slot, and each block sums its books.
//! Then each particle gathers its pair forces in pair order
//! ([`gather_block`]), which is exactly the order the serial loop adds them
//! in, so both ways give the same bits.
//!
//! [`AUTO_PARALLEL_MIN_PAIRS`]: crate::dem::AUTO_PARALLEL_MIN_PAIRS

use glam::DVec3;
use rayon::prelude::*;

use super::block_size::PAIR_BLOCK;
use super::books::BlockBooks;
use super::checks::Limits;
use super::contacts::{Bodies, ContactAt, pair_contact};
use crate::dem::contact::{ContactLaw, ContactState};
use crate::dem::neighbours::{NeighbourList, StepView as NeighbourStep};

/// What a pair contributes to the forces, kept for the gather of the
/// parallel step.
#[derive(Debug, Clone, Copy, Default)]
pub struct PairForce {
    force_i: DVec3,
    torque_i: DVec3,
    torque_j: DVec3,
}

/// Where the pairs of a parallel step leave their forces for the gather,
/// each pair in its own slot (a block writes only its own slots, so no two
/// threads write the same cache line but at a block's ends).
#[derive(Debug, Clone, Default)]
pub struct PairSlots {
    /// Per pair: whether it acts this step (touches, or stopped touching:
    /// the pairs the serial loop adds).
    acts: Vec<bool>,
    /// Per pair: its forces, written only when it acts.
    force: Vec<PairForce>,
}

impl PairSlots {
    fn resize(&mut self, n_pairs: usize) {
        self.acts.resize(n_pairs, false);
        self.force.resize(n_pairs, PairForce::default());
    }
}

/// The pair contacts on all threads, in fixed blocks: each pair advances
/// its state and leaves its forces in its own slots of `slots`, and each
/// block sums its books into `books`. Returns the number of blocks.
pub fn pair_blocks<const D: bool, const F: bool>(
    law: &ContactLaw,
    limits: &Limits,
    bodies: &Bodies,
    list: &mut NeighbourList,
    slots: &mut PairSlots,
    books: &mut Vec<BlockBooks>,
    dt: f64,
) -> usize {
    let n_pairs = list.pairs.len();
    slots.resize(n_pairs);
    let n_blocks = n_pairs.div_ceil(PAIR_BLOCK);
    if books.len() < n_blocks {
        books.resize_with(n_blocks, BlockBooks::default);
    }
    let NeighbourStep {
        pairs,
        gaps,
        states,
    } = list.step_view();
    let PairSlots { acts, force } = slots;
    pairs
        .par_chunks(PAIR_BLOCK)
        .zip(gaps.par_chunks_mut(PAIR_BLOCK))
        .zip(states.par_chunks_mut(PAIR_BLOCK))
        .zip(acts.par_chunks_mut(PAIR_BLOCK))
        .zip(force.par_chunks_mut(PAIR_BLOCK))
        .zip(books[..n_blocks].par_iter_mut())
        .for_each(|(((((pairs, gaps), states), acts), forces), books)| {
            pair_block::<D, F>(
                law,
                bodies,
                pairs,
                (gaps, states),
                (acts, forces),
                (limits, books),
                dt,
            );
        });
    n_blocks
}

/// The pair contacts `start..` of one block: states advanced, whether each
/// pair acts written on both its sides and, when it does, its forces, and
/// its books in `books`; a contact that stops the run ends the block.
#[allow(clippy::too_many_arguments)]
#[inline]
fn pair_block<const D: bool, const F: bool>(
    law: &ContactLaw,
    bodies: &Bodies,
    pairs: &[(u32, u32)],
    (gaps, states): (&mut [f64], &mut [ContactState]),
    (acts, forces): (&mut [bool], &mut [PairForce]),
    (limits, books): (&Limits, &mut BlockBooks),
    dt: f64,
) {
    books.clear();
    let slots = gaps.iter_mut().zip(states);
    let outs = acts.iter_mut().zip(forces);
    for ((&(i, j), (gap, st)), (act, f)) in pairs.iter().zip(slots).zip(outs) {
        let out = pair_contact::<D, F>(law, bodies, i as usize, j as usize, dt, gap, st);
        *act = out.is_some();
        if let Some(out) = out {
            if !books.add(limits, ContactAt::Pair(i as usize, j as usize), &out, dt) {
                return;
            }
            *f = PairForce {
                force_i: out.force_i,
                torque_i: out.torque_i,
                torque_j: out.torque_j,
            };
        }
    }
}

/// Adds to the forces and torques of the particles `start..` of one block
/// the forces of their acting pairs, each particle's in pair order: the
/// pairs, the order, and so the rounding, of the serial loop that adds each
/// acting pair to both its particles.
#[inline]
pub fn gather_block<const F: bool>(
    list: &NeighbourList,
    slots: &PairSlots,
    start: usize,
    force: &mut [DVec3],
    torque: &mut [DVec3],
) {
    for (m, (f, t)) in force.iter_mut().zip(torque.iter_mut()).enumerate() {
        let p = start + m;
        let (mut fa, mut ta) = (*f, *t);
        // Pairs (i, p), i < p, come first in pair order: the j side.
        for &k in list.j_side_pairs(p) {
            let k = k as usize;
            if !slots.acts[k] {
                continue;
            }
            let c = &slots.force[k];
            fa -= c.force_i;
            if F {
                ta += c.torque_j;
            }
        }
        // Then pairs (p, j): the row.
        for k in list.row(p) {
            if !slots.acts[k] {
                continue;
            }
            let c = &slots.force[k];
            fa += c.force_i;
            if F {
                ta += c.torque_i;
            }
        }
        *f = fa;
        *t = ta;
    }
}
