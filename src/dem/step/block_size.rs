//! The fixed blocks every loop of a step is cut into. Blocks are fixed, not
//! one per thread, so that partial sums (the power of the half kicks, the
//! books of the contacts) and the order each particle's forces are added in
//! are the same for any number of threads; on one core the blocks run one
//! after the other in the same order.

/// Particles per block of the step. A bed of one block (the thesis bed, 358
/// spheres) is stepped as one serial loop; larger beds are ordered in space
/// ([`crate::dem::ordering`]) so that a block is a lump of the bed, and
/// their blocks shared among the threads.
pub const PARTICLE_BLOCK: usize = 512;

/// True when `n` particles fill more than one block: such a bed is
/// renumbered in space at each rebuild of its pair list.
pub fn spans_blocks(n: usize) -> bool {
    n > PARTICLE_BLOCK
}
