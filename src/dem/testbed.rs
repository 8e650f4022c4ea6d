//! A bed of many spheres built without pouring: the workload of the speed
//! benchmarks and of the thread-count tests.
//!
//! `n` acrylic spheres of 2 mm (the large beds) sit on a simple cubic
//! lattice, 0.05 % of a diameter apart, inside a closed cylinder about as
//! tall as wide, each with a random velocity of 0.3 m/s, under gravity. The
//! first steps are a burst of collisions, but they scatter the lattice: after
//! a thousand steps a sphere touches about 0.1 others (a settled poured bed:
//! about 2.3, measured by `vlab bench`, docs/performance.md), so a lattice
//! step mostly tests gaps and is several times cheaper than a step of a
//! dense bed at rest. It is the workload of a loose, agitated bed, built in
//! no time; `vlab bench --poured` times poured, settled beds beside it.

use glam::DVec3;

use super::contact::ContactLaw;
use super::error::DemError;
use super::material::Material;
use super::particles::Particles;
use super::restitution::RestitutionMode;
use super::timestep::shortest_contact_s;
use super::walls::Walls;
use super::world::{Numerics, World};
use crate::maths;

/// Sphere diameter of the bed (m).
pub const BED_DIAMETER_M: f64 = 0.002;

/// A lattice bed of `n` spheres (see the module docs), restitution 0.86 and
/// friction `friction` at every contact; random velocities from `seed`.
pub fn lattice_bed(n: usize, friction: f64, seed: u64) -> Result<World, DemError> {
    let r = 0.5 * BED_DIAMETER_M;
    let spacing = BED_DIAMETER_M * 1.0005;
    // Height about twice the radius: n s³ = 2π R³.
    let cyl_r = spacing * maths::cbrt(n as f64 / (2.0 * std::f64::consts::PI)) + 2.0 * r;
    let clear = 1.05 * r;
    let reach = cyl_r - clear;
    let half = (reach / spacing).floor() as i64;
    let mut layer = Vec::new();
    for iy in -half..=half {
        for ix in -half..=half {
            let (x, y) = (ix as f64 * spacing, iy as f64 * spacing);
            if x * x + y * y <= reach * reach {
                layer.push((x, y));
            }
        }
    }
    let m = Material::ACRYLIC;
    let mut rng = SplitMix(seed);
    let mut particles = Particles::default();
    let mut z = clear;
    'fill: loop {
        for &(x, y) in &layer {
            if particles.len() == n {
                break 'fill;
            }
            let dir = DVec3::new(rng.signed(), rng.signed(), rng.signed()).normalize_or_zero();
            particles.push(
                DVec3::new(x, y, z),
                0.3 * dir,
                DVec3::ZERO,
                r,
                m.density_kgm3,
            );
        }
        z += spacing;
    }
    let top = z + clear + 2.0 * spacing;
    let walls = Walls::closed_cylinder(cyl_r, top);
    let pp = ContactLaw::new(&m, &m, 0.86, friction, RestitutionMode::Exact);
    let pw = pp;
    let dt = shortest_contact_s(&pp, &pw, r, m.density_kgm3, 1.0) / 25.0;
    World::new(
        particles,
        walls,
        pp,
        pw,
        DVec3::new(0.0, 0.0, -9.81),
        Numerics::with_dt(dt),
    )
}

/// SplitMix64: a small portable generator, enough for the velocities of a
/// benchmark bed.
struct SplitMix(u64);

impl SplitMix {
    fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [-1, 1).
    fn signed(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 / (1u64 << 52) as f64 - 1.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_bed_has_its_spheres_inside_and_steps() {
        let mut w = lattice_bed(500, 0.52, 3).expect("bed");
        assert_eq!(w.particles.len(), 500);
        // The spheres touch their neighbours at once and reach the walls,
        // 0.05 r away at 0.3 m/s, within some 300 steps.
        let mut touched_walls = false;
        for _ in 0..1000 {
            w.step(0.0).expect("step");
            touched_walls |= w.contact_counts().1 > 0;
        }
        assert!(w.contact_counts().0 > 0);
        assert!(touched_walls);
    }
}
