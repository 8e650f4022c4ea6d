//! The fixed blocks every loop of a step is cut into. Blocks are fixed, not
//! one per thread, so that partial sums (the power of the half kicks, the
//! books of the contacts) are the same for any number of threads; on one
//! core the blocks run one after the other in the same order.

/// Particles per block of the particle loops (kick, drift, gravity, walls,
/// gather).
pub const PARTICLE_BLOCK: usize = 1024;
/// Pairs per block of the pair loop.
pub const PAIR_BLOCK: usize = 4096;
