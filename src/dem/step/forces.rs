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
//! **Blocks.** The particles are cut into the fixed blocks of
//! [`PARTICLE_BLOCK`]; each block sets its particles' weight, adds their
//! wall contacts, then evaluates the pairs of their rows and adds those
//! forces to its own particles ([`super::blocks::pair_rows`]); then each
//! block adds the shares of the pairs that reach it from earlier blocks
//! ([`super::blocks::cross_in`]). On one core the blocks run one after the
//! other, on the threads of a [`super::team::Team`] side by side; a thread writes only what its block
//! owns, and every sum is taken in the same order either way, so the same
//! bits. A bed of one block (the thesis bed) is one serial loop: walls,
//! then the pairs in pair order. The books are then added walls first,
//! block by block ([`super::books`]).
//!
//! **Shared multi-point contacts.** Under a law that shares a body's
//! simultaneous sub-sphere contacts ([`MultiPoint::Shared`]), the stage
//! first counts them, on the caller ([`super::shared_contacts`]), and each
//! block reads its contacts' counts.
//!
//! [`MultiPoint::Shared`]: crate::dem::contact::MultiPoint::Shared

use super::block_size::{PARTICLE_BLOCK, spans_blocks};
use super::blocks::{CrossForce, CrossShares, CrossSlots, CrossSlotsMut, PairRun, pair_rows};
use super::books::{BlockBooks, Books, Kind};
use super::checks::{Limits, Refusal, Refused};
use super::contacts::{
    Bodies, ContactAt, ContactResult, WallGeometry, bodies, law_kind, wall_contact,
};
use super::isa;
use super::shared_contacts::SharedContacts;
use super::team::{Team, for_each_block};
use crate::dem::contact::{ContactLaw, ContactState, MultiPoint};
use crate::dem::neighbours::{Adjacency, NeighbourList, StepView};
use crate::dem::particles::Particles;
use crate::dem::walls::Walls;
use glam::DVec3;

/// Buffers of the force stage, kept from step to step so that the step
/// allocates nothing once they have grown.
#[derive(Debug, Clone, Default)]
pub struct ForceScratch {
    /// Per particle block: the books of its wall contacts.
    wall_books: Vec<BlockBooks>,
    /// Per particle block: the books of its pair contacts.
    pair_books: Vec<BlockBooks>,
    /// Where the pairs into a later block leave their forces.
    cross: CrossSlots,
    /// The counts of shared multi-point contacts, when a law shares them.
    shared: SharedContacts,
}

impl ForceScratch {
    /// The shares the last force stage left for later blocks, when it was
    /// told to defer them and there were several blocks.
    pub fn cross_shares<'a>(
        &'a self,
        neighbours: &'a NeighbourList,
        n_particles: usize,
        torques: bool,
    ) -> Option<CrossShares<'a>> {
        spans_blocks(n_particles).then_some(CrossShares {
            adjacency: neighbours.adjacency(),
            slots: &self.cross,
            torques,
        })
    }
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
    /// The threads to run the blocks on; `None`: one after the other on
    /// the caller.
    pub team: Option<&'a mut Team>,
    /// Leave the shares of the pairs into later blocks for the half kick
    /// that follows to add ([`ForceScratch::cross_shares`]), instead of
    /// adding them here.
    pub defer_cross: bool,
    pub neighbours: &'a mut NeighbourList,
    /// Contact state of particle `i` with wall `w` at `i * n_walls + w`.
    pub wall_states: &'a mut [ContactState],
    /// Overlap of particle `i` with wall `w` at the previous step (m).
    pub wall_gaps: &'a mut [f64],
    pub scratch: &'a mut ForceScratch,
    pub books: Books<'a>,
}

/// What one block of the step owns: its particles' forces and torques and
/// wall contacts, the run of the pair list that is their rows, and its
/// books.
struct BlockJob<'b> {
    /// Its first particle.
    start: usize,
    force: &'b mut [DVec3],
    torque: &'b mut [DVec3],
    wall_states: &'b mut [ContactState],
    wall_gaps: &'b mut [f64],
    run: PairRun<'b>,
    /// Its wall contacts' counts of shared contacts (per particle and wall).
    wall_shared: Option<&'b [u32]>,
    wall_books: &'b mut BlockBooks,
    pair_books: &'b mut BlockBooks,
}

/// Calls `$f::<D, F>($args)` for the law kind `$kind` (damped, frictional).
macro_rules! by_law_kind {
    ($kind:expr, $f:ident($($arg:expr),* $(,)?)) => {
        match $kind {
            (true, true) => $f::<true, true>($($arg),*),
            (true, false) => $f::<true, false>($($arg),*),
            (false, true) => $f::<false, true>($($arg),*),
            (false, false) => $f::<false, false>($($arg),*),
        }
    };
}

impl ForceStage<'_> {
    /// Forces and torques at the current positions, and the force of the
    /// walls. `dt` is the step over which the tangential springs advance and
    /// the ledger accumulates (0 for a pure evaluation that changes no
    /// history). Stops at the first contact a check refuses.
    ///
    /// Over 80 lines: the blocks' disjoint shares of every array are cut here
    /// by hand, and the closure that runs a block must borrow them in the same
    /// place; a helper would have to take all of them.
    pub fn run(self, dt: f64) -> Result<(), Box<Refused>> {
        let ForceStage {
            particles: p,
            walls,
            pp_law,
            pw_law,
            gravity: g,
            limits,
            mut team,
            defer_cross,
            neighbours,
            wall_states,
            wall_gaps,
            scratch,
            mut books,
        } = self;
        *books.wall_force = DVec3::ZERO;
        let n_blocks = p.len().div_ceil(PARTICLE_BLOCK);
        for bk in [&mut scratch.wall_books, &mut scratch.pair_books] {
            if bk.len() < n_blocks {
                bk.resize_with(n_blocks, BlockBooks::default);
            }
        }
        scratch.cross.resize(neighbours.pairs.len());
        let geometry = WallGeometry {
            shapes: &walls.shapes,
            offset: walls.offset(),
            v_wall: walls.velocity(),
            walls,
        };
        let bodies = bodies!(p);
        let StepView {
            pairs,
            adjacency,
            gaps,
            states,
        } = neighbours.step_view();
        // The shared contacts counted, when a law shares them and there are
        // bodies to share them.
        let with_bodies = !p.clumps.is_empty();
        let share_pairs = with_bodies && pp_law.multi_point == MultiPoint::Shared;
        let share_walls = with_bodies && pw_law.multi_point == MultiPoint::Shared;
        if share_pairs {
            scratch.shared.count_pairs(&bodies, &p.clump, pairs, gaps);
        }
        if share_walls {
            scratch
                .shared
                .count_walls(&bodies, &p.clump, &geometry, wall_gaps);
        }
        // The blocks' shares of every per-particle and per-pair array, cut
        // as the blocks are taken (from either end), so that a step
        // allocates nothing for them.
        let n_particles = p.len();
        let n_pairs = adjacency.rows(0, n_particles).end;
        let CrossSlotsMut { acts, force: slots } = scratch.cross.parts_mut();
        let jobs = BlockJobs {
            adjacency,
            n_particles,
            n_walls: geometry.shapes.len(),
            blocks: 0..n_blocks,
            force: &mut p.force[..n_particles],
            torque: &mut p.torque[..n_particles],
            wall_states: &mut wall_states[..n_particles * geometry.shapes.len()],
            wall_gaps: &mut wall_gaps[..n_particles * geometry.shapes.len()],
            pairs: &pairs[..n_pairs],
            gaps: &mut gaps[..n_pairs],
            states: &mut states[..n_pairs],
            acts: &mut acts[..n_pairs],
            slots: &mut slots[..n_pairs],
            pair_shared: share_pairs.then(|| &scratch.shared.pairs[..n_pairs]),
            wall_shared: share_walls
                .then(|| &scratch.shared.walls[..n_particles * geometry.shapes.len()]),
            wall_books: &mut scratch.wall_books[..n_blocks],
            pair_books: &mut scratch.pair_books[..n_blocks],
        };
        let (wall_kind, pair_kind) = (law_kind(&pw_law), law_kind(&pp_law));
        let block = |job: BlockJob<'_>| {
            isa::run(
                #[inline(always)]
                || {
                    by_law_kind!(
                        wall_kind,
                        wall_block(
                            &pw_law,
                            &geometry,
                            &bodies,
                            g,
                            job.start,
                            job.force,
                            job.torque,
                            (job.wall_states, job.wall_gaps, job.wall_shared),
                            (limits, job.wall_books),
                            dt,
                        )
                    );
                    by_law_kind!(
                        pair_kind,
                        pair_rows(
                            &pp_law,
                            &bodies,
                            job.start,
                            job.run,
                            (job.force, job.torque),
                            (&limits, job.pair_books),
                            dt,
                        )
                    );
                },
            )
        };
        for_each_block(team.as_deref_mut(), jobs, block);
        // The shares of the pairs from earlier blocks.
        if n_blocks > 1 && !defer_cross {
            let shares = CrossShares {
                adjacency,
                slots: &scratch.cross,
                torques: pp_law.has_friction(),
            };
            let add = |(c, (f, t)): (usize, (&mut [DVec3], &mut [DVec3]))| {
                shares.add_to(c * PARTICLE_BLOCK, f, t);
            };
            let blocks = p
                .force
                .chunks_mut(PARTICLE_BLOCK)
                .zip(p.torque.chunks_mut(PARTICLE_BLOCK));
            for_each_block(team, blocks.enumerate(), add);
        }
        books.book(Kind::Wall, &scratch.wall_books[..n_blocks], dt)?;
        books.book(Kind::Pair, &scratch.pair_books[..n_blocks], dt)
    }
}

/// The blocks of a force phase not yet taken, and what is left of every
/// array they cut their shares from: a block taken from the front cuts
/// from the front of each, one taken from the back from the back, so the
/// team's caller and first helper can take from opposite ends
/// ([`Team::for_each`]) without a list of jobs being built.
struct BlockJobs<'b> {
    adjacency: &'b Adjacency,
    n_particles: usize,
    n_walls: usize,
    /// The blocks not yet taken.
    blocks: std::ops::Range<usize>,
    force: &'b mut [DVec3],
    torque: &'b mut [DVec3],
    wall_states: &'b mut [ContactState],
    wall_gaps: &'b mut [f64],
    pairs: &'b [(u32, u32)],
    gaps: &'b mut [f64],
    states: &'b mut [ContactState],
    acts: &'b mut [bool],
    slots: &'b mut [CrossForce],
    pair_shared: Option<&'b [u32]>,
    wall_shared: Option<&'b [u32]>,
    wall_books: &'b mut [BlockBooks],
    pair_books: &'b mut [BlockBooks],
}

impl<'b> BlockJobs<'b> {
    /// Block `b`'s job, cut from the front or from the back of what is left.
    fn cut(&mut self, b: usize, from_back: bool) -> BlockJob<'b> {
        let start = b * PARTICLE_BLOCK;
        let len = (self.n_particles - start).min(PARTICLE_BLOCK);
        let n_rows = self.adjacency.rows(start, start + len).len();
        let (wall_len, back) = (len * self.n_walls, from_back);
        let pairs = std::mem::take(&mut self.pairs);
        let (pairs, rest) = match back {
            false => pairs.split_at(n_rows),
            true => {
                let (rest, tail) = pairs.split_at(pairs.len() - n_rows);
                (tail, rest)
            }
        };
        self.pairs = rest;
        BlockJob {
            start,
            force: cut(&mut self.force, len, back),
            torque: cut(&mut self.torque, len, back),
            wall_states: cut(&mut self.wall_states, wall_len, back),
            wall_gaps: cut(&mut self.wall_gaps, wall_len, back),
            run: PairRun {
                pairs,
                gaps: cut(&mut self.gaps, n_rows, back),
                states: cut(&mut self.states, n_rows, back),
                slots: CrossSlotsMut {
                    acts: cut(&mut self.acts, n_rows, back),
                    force: cut(&mut self.slots, n_rows, back),
                },
                shared: cut_shared(&mut self.pair_shared, n_rows, back),
            },
            wall_shared: cut_shared(&mut self.wall_shared, wall_len, back),
            wall_books: &mut cut(&mut self.wall_books, 1, back)[0],
            pair_books: &mut cut(&mut self.pair_books, 1, back)[0],
        }
    }
}

impl<'b> Iterator for BlockJobs<'b> {
    type Item = BlockJob<'b>;

    fn next(&mut self) -> Option<BlockJob<'b>> {
        let b = self.blocks.next()?;
        Some(self.cut(b, false))
    }

    fn size_hint(&self) -> (usize, Option<usize>) {
        self.blocks.size_hint()
    }
}

impl DoubleEndedIterator for BlockJobs<'_> {
    fn next_back(&mut self) -> Option<Self::Item> {
        let b = self.blocks.next_back()?;
        Some(self.cut(b, true))
    }
}

impl ExactSizeIterator for BlockJobs<'_> {}

/// The first `n` of `rest` (`from_back`: the last `n`), leaving the rest.
fn cut<'a, T>(rest: &mut &'a mut [T], n: usize, from_back: bool) -> &'a mut [T] {
    let all = std::mem::take(rest);
    let at = if from_back { all.len() - n } else { n };
    let (front, back) = all.split_at_mut(at);
    if from_back {
        *rest = front;
        back
    } else {
        *rest = back;
        front
    }
}

/// [`cut`] of counts that are read only, when there are any.
fn cut_shared<'a>(rest: &mut Option<&'a [u32]>, n: usize, from_back: bool) -> Option<&'a [u32]> {
    let all = (*rest)?;
    let at = if from_back { all.len() - n } else { n };
    let (front, back) = all.split_at(at);
    *rest = Some(if from_back { front } else { back });
    Some(if from_back { back } else { front })
}

/// The wall contacts of one block: [`wall_loop`] for walls that move
/// together or apart.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn wall_block<const D: bool, const F: bool>(
    law: &ContactLaw,
    walls: &WallGeometry,
    bodies: &Bodies,
    g: DVec3,
    start: usize,
    force: &mut [DVec3],
    torque: &mut [DVec3],
    wall: (&mut [ContactState], &mut [f64], Option<&[u32]>),
    books: (Limits, &mut BlockBooks),
    dt: f64,
) {
    if !walls.moves_apart() {
        wall_loop::<D, F, false>(law, walls, bodies, g, start, force, torque, wall, books, dt)
    } else {
        wall_loop::<D, F, true>(law, walls, bodies, g, start, force, torque, wall, books, dt)
    }
}

/// Gravity and the wall contacts of the particles `start..` of one block:
/// their forces and torques are set, the wall states advanced, and the
/// touching contacts booked in `books`, in (particle, wall) order; a
/// contact that stops the run (an escaped particle, say) ends the block.
/// `shared`: the contacts' counts of shared contacts, when they are shared.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn wall_loop<const D: bool, const F: bool, const OWN: bool>(
    law: &ContactLaw,
    walls: &WallGeometry,
    bodies: &Bodies,
    g: DVec3,
    start: usize,
    force: &mut [DVec3],
    torque: &mut [DVec3],
    (states, gaps, shared): (&mut [ContactState], &mut [f64], Option<&[u32]>),
    (limits, books): (Limits, &mut BlockBooks),
    dt: f64,
) {
    books.clear();
    let n_walls = walls.shapes.len();
    // Room for every contact the block can have (each particle on each
    // wall), made once: no step allocates when a block first reaches a wall.
    books.wall_forces.reserve(force.len() * n_walls);
    if limits.per_particle {
        books.dissipation.reserve(force.len() * n_walls);
    }
    // Read once: copied out of `walls` for every wall of every particle,
    // the offset went through the stack in pieces that the next load
    // could not take whole (a stall of the wider loops of [`super::isa`]).
    let (common_offset, common_v_wall) = (walls.offset, walls.v_wall);
    for (m, (f, t)) in force.iter_mut().zip(torque.iter_mut()).enumerate() {
        let i = start + m;
        *f = g * bodies.mass[i];
        *t = DVec3::ZERO;
        let r = bodies.radius[i];
        let x = bodies.position[i];
        for (w, shape) in walls.shapes.iter().enumerate() {
            let gap = &mut gaps[m * n_walls + w];
            // Without walls of their own motion (the damper), the common
            // offset as a field, as the loop read it before walls could
            // move apart: reading it through `offset_of` cost the thesis drive 5 %.
            let (offset, v_wall) = if OWN {
                (walls.walls.offset_of(w), walls.walls.velocity_of(w))
            } else {
                (common_offset, common_v_wall)
            };
            let dist = shape.distance_m(x, offset);
            if r - dist <= 0.0 && *gap <= 0.0 {
                *gap = r - dist;
                continue;
            }
            let st = &mut states[m * n_walls + w];
            if *gap <= 0.0 {
                // Opening: the contact's books start from the gap.
                st.delta_prev = *gap;
            }
            let normal = shape.normal_from(x, offset);
            let at = ContactAt::Wall(i, w);
            if dist <= 0.0 {
                books.refused = Some((at, ContactResult::default(), Refusal::Escaped));
                return;
            }
            let count = shared.map(|counts| counts[m * n_walls + w]);
            let out = wall_contact::<D, F>(law, bodies, i, dist, normal, v_wall, (dt, count), st);
            *gap = st.delta_prev;
            if !books.add(&limits, at, &out, dt) {
                return;
            }
            books.wall_forces.push((w as u32, out.force_i));
            *f += out.force_i;
            if F {
                *t += out.torque_i;
            }
        }
    }
}
