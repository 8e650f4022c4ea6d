//! The contact-force stage: gravity, the wall contacts and the pair
//! contacts at the current positions, and their books.
//!
//! The resultant force on each sphere is its weight plus its pair and wall
//! contact forces (eq. 3.25 of Terzioglu's thesis), its moment the sum of
//! the contacts' tangential forces on their lever arms (eq. 3.26–3.28); each
//! contact is evaluated by the kernels of [`super::contacts`].
//!
//! **What a step computes is chosen by the scene.** The laws are resolved
//! once per step into an instance of the force loops with or without damping
//! and friction (`D`, `F` below): a law with e = 1 computes no damping, one
//! with μ = 0 no tangential force, no torque and no lever arms.
//!
//! **Threads.** On one core: gravity and the walls, then each pair added to
//! both its particles as soon as it is evaluated, in pair order. On all
//! threads: the pairs first, in the fixed blocks of [`super::blocks`], each
//! leaving its force in its own slot; then one pass over the particles, in
//! fixed blocks, that sets gravity, adds the walls and gathers the pair
//! forces in pair order (the order of the serial loop, so the same bits);
//! then the books, walls first as on one core ([`super::books`]).

use glam::DVec3;
use rayon::prelude::*;

use super::block_size::{PAIR_BLOCK, PARTICLE_BLOCK};
use super::blocks::{PairSlots, gather_block, pair_blocks};
use super::books::{BlockBooks, Books, Kind};
use super::checks::{Limits, Refusal, Refused};
use super::contacts::{
    Bodies, ContactAt, ContactResult, WallGeometry, bodies, law_kind, pair_contact, wall_contact,
};
use crate::dem::contact::{ContactLaw, ContactState};
use crate::dem::neighbours::NeighbourList;
use crate::dem::particles::Particles;
use crate::dem::walls::Walls;

/// Buffers of the force stage, kept from step to step so that the step
/// allocates nothing once they have grown.
#[derive(Debug, Clone, Default)]
pub struct ForceScratch {
    /// Per particle block: the books of its wall contacts.
    wall_books: Vec<BlockBooks>,
    /// Where the pairs leave their forces (parallel step).
    pair_slots: PairSlots,
    /// Per pair block: the books of its contacts.
    pair_books: Vec<BlockBooks>,
    /// Pair blocks of the current step (parallel step).
    pair_blocks: usize,
}

/// What the force stage reads and writes, borrowed from the world field by
/// field.
pub struct ForceStage<'a> {
    pub particles: &'a mut Particles,
    pub walls: &'a Walls,
    /// Particle-particle contact law.
    pub pp_law: ContactLaw,
    /// Particle-wall contact law.
    pub pw_law: ContactLaw,
    /// Gravitational acceleration (m/s²).
    pub gravity: DVec3,
    pub limits: Limits,
    /// Run on all threads, in blocks.
    pub parallel: bool,
    pub neighbours: &'a mut NeighbourList,
    /// Contact state of particle `i` with wall `w` at `i * n_walls + w`.
    pub wall_states: &'a mut [ContactState],
    /// Overlap of particle `i` with wall `w` at the previous step (m).
    pub wall_gaps: &'a mut [f64],
    pub scratch: &'a mut ForceScratch,
    pub books: Books<'a>,
}

/// One block of the particle loop of the wall contacts: its index, forces,
/// torques, wall states and gaps, and books.
type WallBlock<'b> = (
    usize,
    (
        (
            ((&'b mut [DVec3], &'b mut [DVec3]), &'b mut [ContactState]),
            &'b mut [f64],
        ),
        &'b mut BlockBooks,
    ),
);

impl ForceStage<'_> {
    /// Forces and torques at the current positions, and the force of the
    /// walls. `dt` is the step over which the tangential springs advance and
    /// the ledger accumulates (0 for a pure evaluation that changes no
    /// history). Stops at the first contact a check refuses.
    pub fn run(mut self, dt: f64) -> Result<(), Box<Refused>> {
        *self.books.wall_force = DVec3::ZERO;
        if !self.parallel {
            match law_kind(&self.pw_law) {
                (true, true) => self.wall_contacts::<true, true>(dt, None),
                (true, false) => self.wall_contacts::<true, false>(dt, None),
                (false, true) => self.wall_contacts::<false, true>(dt, None),
                (false, false) => self.wall_contacts::<false, false>(dt, None),
            }?;
            return match law_kind(&self.pp_law) {
                (true, true) => self.pair_contacts::<true, true>(dt),
                (true, false) => self.pair_contacts::<true, false>(dt),
                (false, true) => self.pair_contacts::<false, true>(dt),
                (false, false) => self.pair_contacts::<false, false>(dt),
            };
        }
        match law_kind(&self.pp_law) {
            (true, true) => self.pair_blocks::<true, true>(dt),
            (true, false) => self.pair_blocks::<true, false>(dt),
            (false, true) => self.pair_blocks::<false, true>(dt),
            (false, false) => self.pair_blocks::<false, false>(dt),
        }
        let gather = Some(self.pp_law.has_friction());
        match law_kind(&self.pw_law) {
            (true, true) => self.wall_contacts::<true, true>(dt, gather),
            (true, false) => self.wall_contacts::<true, false>(dt, gather),
            (false, true) => self.wall_contacts::<false, true>(dt, gather),
            (false, false) => self.wall_contacts::<false, false>(dt, gather),
        }?;
        let n_blocks = self.scratch.pair_blocks;
        self.books
            .book(Kind::Pair, &self.scratch.pair_books[..n_blocks], dt)
    }

    /// Gravity alone, for a world without walls, and on all threads
    /// (`gather: Some(torques)`) the pair forces gathered.
    fn gravity_only(&mut self, gather: Option<bool>) {
        let g = self.gravity;
        let p = &mut *self.particles;
        for (f, (t, m)) in p.force.iter_mut().zip(p.torque.iter_mut().zip(&p.mass)) {
            *f = g * *m;
            *t = DVec3::ZERO;
        }
        if gather.is_some() {
            let (list, slots) = (&*self.neighbours, &self.scratch.pair_slots);
            p.force
                .par_chunks_mut(PARTICLE_BLOCK)
                .zip(p.torque.par_chunks_mut(PARTICLE_BLOCK))
                .enumerate()
                .for_each(|(c, (f, t))| gather_into(gather, list, slots, c, f, t));
        }
    }

    /// Gravity and the wall contacts, particle by particle in fixed blocks;
    /// what the contacts book is then added up on one thread in contact
    /// order. `gather: Some(torques)`: the step runs on all threads, and each
    /// block then also adds its particles' pair forces (and torques, when
    /// `torques`), which [`Self::pair_blocks`] left one per pair.
    fn wall_contacts<const D: bool, const F: bool>(
        &mut self,
        dt: f64,
        gather: Option<bool>,
    ) -> Result<(), Box<Refused>> {
        if self.walls.is_empty() {
            self.gravity_only(gather);
            return Ok(());
        }
        let g = self.gravity;
        let law = self.pw_law;
        let limits = self.limits;
        let p = &mut *self.particles;
        let (list, slots) = (&*self.neighbours, &self.scratch.pair_slots);
        let walls = WallGeometry {
            shapes: &self.walls.shapes,
            offset: self.walls.offset(),
            v_wall: self.walls.velocity(),
        };
        let bodies = bodies!(p);
        let n_walls = walls.shapes.len();
        let n_blocks = p.force.len().div_ceil(PARTICLE_BLOCK);
        let books = &mut self.scratch.wall_books;
        if books.len() < n_blocks {
            books.resize_with(n_blocks, BlockBooks::default);
        }
        let block = |(c, ((((f, t), st), gaps), bk)): WallBlock<'_>| {
            wall_block::<D, F>(
                &law,
                &walls,
                &bodies,
                g,
                c * PARTICLE_BLOCK,
                f,
                t,
                (st, gaps),
                (limits, bk),
                dt,
            );
            gather_into(gather, list, slots, c, f, t);
        };
        let (states, gaps) = (&mut *self.wall_states, &mut *self.wall_gaps);
        let chunk = PARTICLE_BLOCK * n_walls;
        if gather.is_some() {
            p.force
                .par_chunks_mut(PARTICLE_BLOCK)
                .zip(p.torque.par_chunks_mut(PARTICLE_BLOCK))
                .zip(states.par_chunks_mut(chunk))
                .zip(gaps.par_chunks_mut(chunk))
                .zip(books[..n_blocks].par_iter_mut())
                .enumerate()
                .for_each(block);
        } else {
            p.force
                .chunks_mut(PARTICLE_BLOCK)
                .zip(p.torque.chunks_mut(PARTICLE_BLOCK))
                .zip(states.chunks_mut(chunk))
                .zip(gaps.chunks_mut(chunk))
                .zip(books[..n_blocks].iter_mut())
                .enumerate()
                .for_each(block);
        }
        self.books
            .book(Kind::Wall, &self.scratch.wall_books[..n_blocks], dt)
    }

    /// The pair contacts on one thread, each added to the forces as soon as
    /// it is evaluated, in pair order; the books block by block.
    fn pair_contacts<const D: bool, const F: bool>(&mut self, dt: f64) -> Result<(), Box<Refused>> {
        let law = self.pp_law;
        let limits = self.limits;
        let p = &mut *self.particles;
        let bodies = bodies!(p);
        let (force, torque) = (&mut p.force, &mut p.torque);
        let nl = &mut *self.neighbours;
        let n_blocks = nl.pairs.len().div_ceil(PAIR_BLOCK);
        let books = &mut self.scratch.pair_books;
        if books.len() < n_blocks {
            books.resize_with(n_blocks, BlockBooks::default);
        }
        let blocks = nl
            .pairs
            .chunks(PAIR_BLOCK)
            .zip(nl.gaps.chunks_mut(PAIR_BLOCK))
            .zip(nl.states.chunks_mut(PAIR_BLOCK))
            .zip(books.iter_mut());
        'blocks: for (((pairs, gaps), states), bk) in blocks {
            bk.clear();
            for (&(i, j), (gap, st)) in pairs.iter().zip(gaps.iter_mut().zip(states.iter_mut())) {
                let (i, j) = (i as usize, j as usize);
                let Some(out) = pair_contact::<D, F>(&law, &bodies, i, j, dt, gap, st) else {
                    continue;
                };
                if !bk.add(&limits, ContactAt::Pair(i, j), &out, dt) {
                    break 'blocks;
                }
                force[i] += out.force_i;
                force[j] -= out.force_i;
                if F {
                    torque[i] += out.torque_i;
                    torque[j] += out.torque_j;
                }
            }
        }
        self.books
            .book(Kind::Pair, &self.scratch.pair_books[..n_blocks], dt)
    }

    /// The pair contacts on all threads, in fixed blocks
    /// ([`super::blocks::pair_blocks`]); their books wait in the scratch
    /// until the walls are booked.
    fn pair_blocks<const D: bool, const F: bool>(&mut self, dt: f64) {
        let p = &*self.particles;
        let bodies = bodies!(p);
        let sc = &mut *self.scratch;
        sc.pair_blocks = pair_blocks::<D, F>(
            &self.pp_law,
            &self.limits,
            &bodies,
            self.neighbours,
            &mut sc.pair_slots,
            &mut sc.pair_books,
            dt,
        );
    }
}

/// On all threads (`gather: Some(torques)`), adds to the forces (and
/// torques) of particle block `c` its pair forces; nothing on one core.
#[inline]
fn gather_into(
    gather: Option<bool>,
    list: &NeighbourList,
    slots: &PairSlots,
    c: usize,
    f: &mut [DVec3],
    t: &mut [DVec3],
) {
    match gather {
        Some(true) => gather_block::<true>(list, slots, c * PARTICLE_BLOCK, f, t),
        Some(false) => gather_block::<false>(list, slots, c * PARTICLE_BLOCK, f, t),
        None => {}
    }
}

/// Gravity and the wall contacts of the particles `start..` of one block:
/// their forces and torques are set, the wall states advanced, and the
/// touching contacts booked in `books`, in (particle, wall) order; a
/// contact that stops the run (an escaped particle, say) ends the block.
#[allow(clippy::too_many_arguments)]
#[inline]
fn wall_block<const D: bool, const F: bool>(
    law: &ContactLaw,
    walls: &WallGeometry,
    bodies: &Bodies,
    g: DVec3,
    start: usize,
    force: &mut [DVec3],
    torque: &mut [DVec3],
    (states, gaps): (&mut [ContactState], &mut [f64]),
    (limits, books): (Limits, &mut BlockBooks),
    dt: f64,
) {
    books.clear();
    let n_walls = walls.shapes.len();
    for (m, (f, t)) in force.iter_mut().zip(torque.iter_mut()).enumerate() {
        let i = start + m;
        *f = g * bodies.mass[i];
        *t = DVec3::ZERO;
        let r = bodies.radius[i];
        let x = bodies.position[i];
        for (w, shape) in walls.shapes.iter().enumerate() {
            let gap = &mut gaps[m * n_walls + w];
            let dist = shape.distance_m(x, walls.offset);
            if r - dist <= 0.0 && *gap <= 0.0 {
                *gap = r - dist;
                continue;
            }
            let st = &mut states[m * n_walls + w];
            if *gap <= 0.0 {
                // Opening: the contact's books start from the gap.
                st.delta_prev = *gap;
            }
            let normal = shape.normal_from(x);
            let at = ContactAt::Wall(i, w);
            if dist <= 0.0 {
                books.refused = Some((at, ContactResult::default(), Refusal::Escaped));
                return;
            }
            let out = wall_contact::<D, F>(law, bodies, i, dist, normal, walls.v_wall, dt, st);
            *gap = st.delta_prev;
            if !books.add(&limits, at, &out, dt) {
                return;
            }
            books.wall_forces.push(out.force_i);
            *f += out.force_i;
            if F {
                *t += out.torque_i;
            }
        }
    }
}
