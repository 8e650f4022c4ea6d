//! A fingerprint of a DEM state: the same scene and seed give the same
//! 16 hex digits on one thread or many, natively or in WebAssembly, and a
//! state that moved by one bit anywhere gives others. It is how a run says
//! that it is the run another platform made (`summary.json`'s
//! `state_hash`, the browser lab's page).
//!
//! The hash is FNV-1a 64 over the bits of every sphere's position, velocity
//! and spin in id order (the order the neighbour search keeps them in is an
//! implementation detail), then every body's centre, velocity, orientation
//! and angular momentum. Forces are left out: they are the next step's, and
//! recomputed from these. So are the contacts' tangential spring histories:
//! two states alike but for a spring would hash alike, but their kinematics
//! part within a few steps, so a hash taken at a run's end tells them apart.

use glam::{DQuat, DVec3};

use super::Particles;

/// FNV-1a, 64 bits: a hash whose value does not change between Rust
/// versions or platforms.
pub fn fnv1a64(bytes: &[u8]) -> u64 {
    let mut h = Fnv1a64::new();
    h.bytes(bytes);
    h.finish()
}

/// FNV-1a, 64 bits, fed piece by piece.
#[derive(Debug, Clone, Copy)]
pub struct Fnv1a64(u64);

impl Default for Fnv1a64 {
    fn default() -> Self {
        Self::new()
    }
}

impl Fnv1a64 {
    /// The hash of nothing.
    pub fn new() -> Self {
        Fnv1a64(0xcbf2_9ce4_8422_2325)
    }

    /// Feeds `bytes`.
    pub fn bytes(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 ^= u64::from(b);
            self.0 = self.0.wrapping_mul(0x0100_0000_01b3);
        }
    }

    /// Feeds the bits of `x`, little-endian.
    pub fn f64(&mut self, x: f64) {
        self.bytes(&x.to_bits().to_le_bytes());
    }

    fn vec(&mut self, v: DVec3) {
        for x in v.to_array() {
            self.f64(x);
        }
    }

    fn quat(&mut self, q: DQuat) {
        for x in q.to_array() {
            self.f64(x);
        }
    }

    /// The hash so far.
    pub fn finish(&self) -> u64 {
        self.0
    }
}

/// The state's fingerprint (see the module docs).
pub fn state_hash(particles: &Particles) -> u64 {
    let p = particles.by_id();
    let mut h = Fnv1a64::new();
    h.bytes(&(p.len() as u64).to_le_bytes());
    for i in 0..p.len() {
        h.vec(p.position[i]);
        h.vec(p.velocity[i]);
        h.vec(p.angular_velocity[i]);
    }
    let c = &p.clumps;
    h.bytes(&(c.position.len() as u64).to_le_bytes());
    for k in 0..c.position.len() {
        h.vec(c.position[k]);
        h.vec(c.velocity[k]);
        h.quat(c.orientation[k]);
        h.vec(c.angular_momentum[k]);
    }
    h.finish()
}

/// `hash` as the 16 hex digits a summary prints.
pub fn hex(hash: u64) -> String {
    format!("{hash:016x}")
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dem::testbed;

    #[test]
    fn fnv1a64_is_the_published_function() {
        // The FNV test vectors (Fowler, Noll, Vo): "" and "a".
        assert_eq!(fnv1a64(b""), 0xcbf2_9ce4_8422_2325);
        assert_eq!(fnv1a64(b"a"), 0xaf63_dc4c_8601_ec8c);
        assert_eq!(fnv1a64(b"foobar"), 0x8594_4171_f739_67e8);
    }

    /// One bit of one coordinate changes the hash; the order the spheres
    /// are stored in does not.
    #[test]
    fn one_bit_moves_the_hash_and_the_storage_order_does_not() {
        let world = testbed::lattice_bed(20, 0.3, 7).expect("a bed");
        let p = &world.particles;
        let base = state_hash(p);
        let mut moved = p.clone();
        let v = &mut moved.velocity[7];
        v.y = f64::from_bits(v.y.to_bits() ^ 1);
        assert_ne!(state_hash(&moved), base);
        let mut spun = p.clone();
        spun.angular_velocity[19].z = f64::from_bits(1);
        assert_ne!(state_hash(&spun), base);
        let mut reversed = p.clone();
        reversed.renumber(&(0..p.len() as u32).rev().collect::<Vec<_>>());
        assert_ne!(reversed.position[0], p.position[0]);
        assert_eq!(state_hash(&reversed), base);
        assert_eq!(hex(base).len(), 16);
    }
}
