//! The neighbour update: the Verlet pair list (Section 3.4 of Terzioglu's
//! thesis, [`crate::dem::neighbours`]) is rebuilt when some particle drifted
//! more than half the skin from where it was built, which the drift reports
//! ([`super::integrate::KickSums::moved_far`]), or when it was built for
//! another number of particles. Otherwise the list, and every contact
//! history on it, carries over.

use crate::dem::neighbours::NeighbourList;
use crate::dem::particles::Particles;

/// Rebuilds `list` for `particles` if it may miss a contact now.
pub fn update(list: &mut NeighbourList, particles: &Particles, moved_far: bool) {
    if moved_far || list.reference().len() != particles.len() {
        list.rebuild(&particles.position, &particles.radius);
    }
}
