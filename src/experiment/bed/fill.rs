//! Random, non-overlapping placement of spheres in a cylinder (and of
//! bodies, by their bounding spheres, at random orientations).
//!
//! Random sequential insertion jams near a volume fill of 0.38, so a dense fill
//! such as the thesis' 0.466 cannot be placed inside its closed enclosure. The
//! damper scene therefore inserts into a taller column of the same diameter at a
//! fill of [`COLUMN_FILL`], lets the spheres settle, and closes the lid at the
//! design length (see `damper`). Placement is driven by a seeded xoshiro256++
//! generator, so the same seed gives the same bed on every platform.

use glam::{DQuat, DVec3};
use rand_core::{Rng, SeedableRng};
use rand_xoshiro::Xoshiro256PlusPlus;

use crate::maths;
use crate::scene::SceneError;

/// Fill ratio of the insertion column, safely below the jamming of random
/// sequential insertion (about 0.38).
pub const COLUMN_FILL: f64 = 0.30;

/// A seeded, portable uniform random source.
#[derive(Debug, Clone)]
pub struct SceneRng(Xoshiro256PlusPlus);

impl SceneRng {
    /// Generator for `seed`.
    pub fn new(seed: u64) -> Self {
        SceneRng(Xoshiro256PlusPlus::seed_from_u64(seed))
    }

    /// Uniform in [0, 1), 53 random bits.
    pub fn uniform(&mut self) -> f64 {
        (self.0.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    /// Uniform in [lo, hi).
    pub fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.uniform()
    }
}

/// An orientation drawn uniformly over all rotations (Shoemake's unit
/// quaternion from three uniform numbers): how a body falls into the pour
/// column.
pub fn random_orientation(rng: &mut SceneRng) -> DQuat {
    let (u1, u2, u3) = (rng.uniform(), rng.uniform(), rng.uniform());
    let tau = std::f64::consts::TAU;
    let (a, b) = ((1.0 - u1).sqrt(), u1.sqrt());
    DQuat::from_xyzw(
        a * maths::sin(tau * u2),
        a * maths::cos(tau * u2),
        b * maths::sin(tau * u3),
        b * maths::cos(tau * u3),
    )
    .normalize()
}

/// Places `count` spheres of `radius_m` inside a cylinder around the z axis of
/// inner radius `cylinder_radius_m`, between the planes z = 0 and z = `height_m`,
/// without overlaps (a `clearance_m` gap is kept between spheres and walls).
pub fn insert_in_cylinder(
    count: usize,
    radius_m: f64,
    cylinder_radius_m: f64,
    height_m: f64,
    clearance_m: f64,
    rng: &mut SceneRng,
) -> Result<Vec<DVec3>, SceneError> {
    let reach = cylinder_radius_m - radius_m - clearance_m;
    let (z_lo, z_hi) = (radius_m + clearance_m, height_m - radius_m - clearance_m);
    if reach <= 0.0 || z_hi <= z_lo {
        return Err(SceneError::ParticleTooLarge {
            diameter_m: 2.0 * cylinder_radius_m,
            length_m: height_m,
            particle_m: 2.0 * radius_m,
        });
    }
    // Hash grid with cells at least one diameter wide: overlap checks look
    // at 27 cells. Coarser when particles are tiny against the enclosure,
    // so that the grid stays a few megabytes (a nanometre sphere in the
    // thesis cylinder asked for 10^20 cells and overflowed; a 100 m
    // enclosure asked for 10^14 and aborted). The cells' size changes
    // which cells are searched, never which positions are taken.
    let min_dist = 2.0 * radius_m + clearance_m;
    let max_cells = (64.0 * count as f64).max(1048576.0);
    let mut cell = min_dist;
    let cells_of = |cell: f64| {
        [
            (2.0 * cylinder_radius_m / cell).ceil() + 1.0,
            (2.0 * cylinder_radius_m / cell).ceil() + 1.0,
            (height_m / cell).ceil() + 1.0,
        ]
    };
    while cells_of(cell).iter().product::<f64>() > max_cells {
        cell *= 1.25;
    }
    let dims = cells_of(cell).map(|n| n as usize);
    let index = |p: DVec3| -> [usize; 3] {
        [
            ((p.x + cylinder_radius_m) / cell) as usize,
            ((p.y + cylinder_radius_m) / cell) as usize,
            (p.z / cell) as usize,
        ]
    };
    let mut grid: Vec<Vec<u32>> = vec![Vec::new(); dims[0] * dims[1] * dims[2]];
    let mut placed: Vec<DVec3> = Vec::with_capacity(count);
    let max_attempts = 5000 * count.max(1);
    let mut attempts = 0;
    while placed.len() < count {
        attempts += 1;
        if attempts > max_attempts {
            return Err(SceneError::Insertion {
                placed: placed.len(),
                count,
                column_m: height_m,
            });
        }
        let (x, y) = (rng.range(-reach, reach), rng.range(-reach, reach));
        if x * x + y * y > reach * reach {
            continue;
        }
        let p = DVec3::new(x, y, rng.range(z_lo, z_hi));
        let [cx, cy, cz] = index(p);
        let mut free = true;
        'search: for z in cz.saturating_sub(1)..=(cz + 1).min(dims[2] - 1) {
            for y in cy.saturating_sub(1)..=(cy + 1).min(dims[1] - 1) {
                for x in cx.saturating_sub(1)..=(cx + 1).min(dims[0] - 1) {
                    for &k in &grid[(z * dims[1] + y) * dims[0] + x] {
                        if (placed[k as usize] - p).length_squared() < min_dist * min_dist {
                            free = false;
                            break 'search;
                        }
                    }
                }
            }
        }
        if free {
            grid[(cz * dims[1] + cy) * dims[0] + cx].push(placed.len() as u32);
            placed.push(p);
        }
    }
    Ok(placed)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn thesis_particles_fit_in_the_column_without_overlap() {
        let volume = 358.0 * 4.0 / 3.0 * std::f64::consts::PI * 0.0025f64.powi(3);
        let height = volume / (COLUMN_FILL * std::f64::consts::PI * 0.02 * 0.02);
        let mut rng = SceneRng::new(1);
        let p = insert_in_cylinder(358, 0.0025, 0.02, height, 1e-5, &mut rng).expect("fits");
        assert_eq!(p.len(), 358);
        for i in 0..p.len() {
            assert!(p[i].truncate().length() <= 0.02 - 0.0025);
            assert!(p[i].z >= 0.0025 && p[i].z <= height - 0.0025);
            for j in 0..i {
                assert!((p[i] - p[j]).length() >= 0.005, "overlap {i} {j}");
            }
        }
    }

    #[test]
    fn particles_tiny_against_the_enclosure_need_no_huge_grid() {
        for (radius, cylinder, height) in [(5e-10, 0.02, 0.04), (0.0025, 50.0, 100.0)] {
            let mut rng = SceneRng::new(1);
            let p = insert_in_cylinder(20, radius, cylinder, height, 0.0, &mut rng).expect("fits");
            assert_eq!(p.len(), 20);
        }
    }

    #[test]
    fn same_seed_same_bed_other_seed_other_bed() {
        let a = insert_in_cylinder(50, 0.0025, 0.02, 0.06, 0.0, &mut SceneRng::new(7)).unwrap();
        let b = insert_in_cylinder(50, 0.0025, 0.02, 0.06, 0.0, &mut SceneRng::new(7)).unwrap();
        let c = insert_in_cylinder(50, 0.0025, 0.02, 0.06, 0.0, &mut SceneRng::new(8)).unwrap();
        assert_eq!(a, b);
        assert_ne!(a, c);
    }

    #[test]
    fn overfull_column_is_refused() {
        let err = insert_in_cylinder(400, 0.0025, 0.02, 0.04, 0.0, &mut SceneRng::new(1));
        assert!(err.is_err());
    }
}
