//! The stages of one DEM step, each in its own file, in the order
//! [`World::step`](super::World::step) calls them (the resultant loads of
//! eq. 3.25–3.28 in Terzioglu's thesis, Section 3.5, integrated in time as
//! Section 3.6 does):
//!
//! 1. [`integrate`]: first half of velocity Verlet, kick and drift (the
//!    symplectic replacement of the explicit Euler of eq. 3.29–3.30) of the
//!    free spheres, then [`clump_motion`] of the rigid multi-sphere bodies
//!    (eq. 4.3–4.7, with the gyroscopic term), which places their
//!    sub-spheres;
//! 2. [`drive`]: the walls move to the prescribed displacement for the end
//!    of the step;
//! 3. [`neighbour_update`]: the Verlet pair list is rebuilt when some
//!    particle moved more than half the skin (Section 3.4), a large bed
//!    renumbered in space with it;
//! 4. [`forces`]: gravity and the contact forces at the new positions
//!    (eq. 3.25–3.28), one contact at a time by the kernels of [`contacts`]
//!    (eq. 3.1–3.8, 3.12–3.14), block by block ([`blocks`]); under a law
//!    of shared multi-point contacts, after [`shared_contacts`] has counted
//!    each body pair's touching sub-sphere contacts;
//! 5. [`integrate`] again: the second half kick, each block first adding
//!    the forces that cross into it from earlier blocks; then the bodies'
//!    ([`clump_motion`]), from the resultants of their sub-spheres' forces;
//! 6. [`books`]: what the contacts dissipated and stored, block by block,
//!    and the step's energy balance (eq. 6.4);
//! 7. [`checks`]: the refusals (a collision resolved in too few steps, an
//!    excessive overlap, an escaped particle, a position that is not finite,
//!    energy books that no longer close).
//!
//! The stages are plain functions over the world's plain state structs,
//! borrowed field by field; none of them imports the world. Loops are cut
//! into the fixed blocks of [`block_size`], so that every sum is taken in the
//! same order whatever the number of threads, and [`thread_choice`] decides
//! by timing whether they run on one core or on all.

pub mod block_size;
pub mod blocks;
pub mod books;
pub mod checks;
pub mod clump_motion;
pub mod contacts;
pub mod drive;
pub mod forces;
pub mod integrate;
pub mod isa;
pub mod neighbour_update;
pub mod shared_contacts;
pub mod team;
pub mod thread_choice;
pub mod wake;
pub mod workspace;

/// The primitives [`wake`] is written against: std's here, `loom`'s in the
/// model test that includes it.
mod sync {
    pub use std::sync::atomic::{AtomicBool, AtomicU64, AtomicUsize, Ordering};
    pub use std::sync::{Condvar, Mutex};
}
