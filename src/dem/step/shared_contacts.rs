//! How many sub-sphere contacts each body pair, and each body and wall,
//! touch at this step: the counts a law of shared multi-point contacts
//! ([`MultiPoint::Shared`]) divides each of them by.
//!
//! Terzioglu's thesis models a non-spherical particle as a rigid union of
//! overlapping sub-spheres (Section 4.2) and every sub-sphere contact as a
//! whole Hertz–Mindlin contact (eq. 3.1–3.8, as EDEM does), so two prolates
//! side by side, touching at a dozen sub-sphere pairs, meet a dozen times as
//! stiff as asked and lose more than the restitution says. A shared law
//! gives each of the `n` contacts of one body pair `1/n` of one contact
//! ([`ContactGeometry::share`]). The count is taken here, before the force
//! stage, with the very test the kernels use to decide that a contact
//! touches ([`super::contacts`]), so a count is never zero for a touching
//! contact and never counts one the kernels find apart. A free sphere is a
//! body of its own: a sphere resting in the groove between two sub-spheres
//! of a body shares too. Counting is in integers, so the counts are the same
//! whatever order the contacts are met in and however many threads run.
//!
//! [`MultiPoint::Shared`]: crate::dem::contact::MultiPoint::Shared
//! [`ContactGeometry::share`]: crate::dem::contact::ContactGeometry::share

use super::contacts::{Bodies, WallGeometry};
use crate::dem::clumps::NOT_IN_CLUMP;

/// Per listed pair and per (particle, wall): the count of contacts its body
/// pair (or body and wall) touches at this step, read only for a contact
/// that touches. Kept from step to step so that counting allocates nothing
/// once it has grown.
#[derive(Debug, Clone, Default)]
pub struct SharedContacts {
    /// Per listed pair, in list order.
    pub pairs: Vec<u32>,
    /// Per particle `i` and wall `w`, at `i * n_walls + w`.
    pub walls: Vec<u32>,
    /// The touching contacts of bodies this step: (the two owners, the
    /// contact's index).
    touching: Vec<((u64, u64), u32)>,
}

/// Who a particle belongs to: its body, or itself when it is a free sphere
/// (numbered past every body).
#[inline]
fn owner(clump: &[u32], i: usize) -> u64 {
    match clump[i] {
        NOT_IN_CLUMP => (1u64 << 32) + i as u64,
        b => u64::from(b),
    }
}

impl SharedContacts {
    /// Counts, for every listed pair `(i, j)` that touches at the current
    /// positions (`gaps` as the pair list keeps them from the previous
    /// step), the touching pairs of the same two owners.
    pub fn count_pairs(
        &mut self,
        bodies: &Bodies,
        clump: &[u32],
        pairs: &[(u32, u32)],
        gaps: &[f64],
    ) {
        self.pairs.clear();
        self.pairs.resize(pairs.len(), 1);
        self.touching.clear();
        for (k, (&(i, j), &gap)) in pairs.iter().zip(gaps).enumerate() {
            let (i, j) = (i as usize, j as usize);
            let in_body = clump[i] != NOT_IN_CLUMP || clump[j] != NOT_IN_CLUMP;
            if in_body && pair_touches(bodies, i, j, gap) {
                let (a, b) = (owner(clump, i), owner(clump, j));
                self.touching.push(((a.min(b), a.max(b)), k as u32));
            }
        }
        spread_counts(&mut self.touching, &mut self.pairs);
    }

    /// Counts, for every sub-sphere that touches a wall (`gaps` as the
    /// world keeps them from the previous step), the sub-spheres of its body
    /// that touch the same wall.
    pub fn count_walls(
        &mut self,
        bodies: &Bodies,
        clump: &[u32],
        walls: &WallGeometry,
        gaps: &[f64],
    ) {
        let n_walls = walls.shapes.len();
        self.walls.clear();
        self.walls.resize(gaps.len(), 1);
        self.touching.clear();
        for (i, &body) in clump.iter().enumerate() {
            if body == NOT_IN_CLUMP {
                continue;
            }
            for (w, shape) in walls.shapes.iter().enumerate() {
                let at = i * n_walls + w;
                let dist = shape.distance_m(bodies.position[i], walls.walls.offset_of(w));
                if wall_touches(bodies.radius[i], dist, gaps[at]) {
                    self.touching.push(((u64::from(body), w as u64), at as u32));
                }
            }
        }
        spread_counts(&mut self.touching, &mut self.walls);
    }
}

/// The pair kernel's own test ([`super::contacts::pair_contact`]): a pair
/// touches when it is not skipped as apart and its overlap is positive.
#[inline]
fn pair_touches(b: &Bodies, i: usize, j: usize, gap: f64) -> bool {
    let dist_sq = (b.position[j] - b.position[i]).length_squared();
    let reach = b.radius[i] + b.radius[j];
    if dist_sq >= reach * reach && gap <= 0.0 {
        return false;
    }
    reach - dist_sq.sqrt() > 0.0
}

/// The wall loop's own test ([`super::forces`]): a sphere of radius `r`
/// whose centre is `dist` from the wall touches when its overlap is
/// positive.
#[inline]
fn wall_touches(r: f64, dist: f64, gap: f64) -> bool {
    if r - dist <= 0.0 && gap <= 0.0 {
        return false;
    }
    r - dist > 0.0
}

/// Gives each touching contact the number of touching contacts with its
/// owners: sorted by owners, each run's length.
fn spread_counts(touching: &mut [((u64, u64), u32)], counts: &mut [u32]) {
    touching.sort_unstable_by_key(|&(owners, _)| owners);
    for run in touching.chunk_by(|a, b| a.0 == b.0) {
        for &(_, k) in run {
            counts[k as usize] = run.len() as u32;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dem::walls::Walls;
    use glam::DVec3;

    struct Bed {
        position: Vec<DVec3>,
        velocity: Vec<DVec3>,
        radius: Vec<f64>,
        mass: Vec<f64>,
        clump: Vec<u32>,
    }

    impl Bed {
        fn bodies(&self) -> Bodies<'_> {
            Bodies {
                position: &self.position,
                velocity: &self.velocity,
                angular_velocity: &self.velocity,
                radius: &self.radius,
                mass: &self.mass,
            }
        }
    }

    /// Two rods of three sub-spheres side by side, touching at three
    /// pairs; a free sphere in the groove of the second rod, touching two
    /// of its sub-spheres; another free sphere touching the first free one.
    fn bed() -> Bed {
        let r = 1.0e-3;
        let mut position = Vec::new();
        let mut clump = Vec::new();
        for (b, y) in [(0u32, 0.0), (1, 1.9e-3)] {
            for k in 0..3 {
                position.push(DVec3::new(k as f64 * 1.0e-3, y, 0.0));
                clump.push(b);
            }
        }
        // In the groove of rod 1 between its sub-spheres 0 and 1, above it.
        position.push(DVec3::new(0.5e-3, 1.9e-3 + 1.8e-3, 0.0));
        clump.push(NOT_IN_CLUMP);
        position.push(DVec3::new(0.5e-3, 1.9e-3 + 3.7e-3, 0.0));
        clump.push(NOT_IN_CLUMP);
        let n = position.len();
        Bed {
            position,
            velocity: vec![DVec3::ZERO; n],
            radius: vec![r; n],
            mass: vec![1e-5; n],
            clump,
        }
    }

    /// Every pair once, in index order, as a list would have them.
    fn all_pairs(n: u32) -> Vec<(u32, u32)> {
        (0..n)
            .flat_map(|i| (i + 1..n).map(move |j| (i, j)))
            .collect()
    }

    #[test]
    fn a_body_pair_counts_its_touching_sub_sphere_pairs() {
        let bed = bed();
        let pairs = all_pairs(bed.position.len() as u32);
        let gaps = vec![-1.0; pairs.len()];
        let mut shared = SharedContacts::default();
        shared.count_pairs(&bed.bodies(), &bed.clump, &pairs, &gaps);
        let count = |i: u32, j: u32| {
            let k = pairs.iter().position(|&p| p == (i, j)).expect("listed");
            shared.pairs[k]
        };
        // Rod 0 and rod 1 touch at their three facing pairs (1.9 mm < 2 mm);
        // the diagonal pairs are 2.15 mm apart.
        for k in 0..3 {
            assert_eq!(count(k, k + 3), 3, "facing pair {k}");
        }
        // The free sphere 6 sits on sub-spheres 3 and 4 of rod 1 (1.87 mm).
        assert_eq!(count(3, 6), 2);
        assert_eq!(count(4, 6), 2);
        // Two free spheres: one contact of their own (never counted as a
        // body's, left at 1).
        assert_eq!(count(6, 7), 1);
    }

    #[test]
    fn a_pair_that_was_touching_counts_while_its_overlap_is_positive() {
        let bed = bed();
        let pairs = vec![(0u32, 3u32), (1, 4), (2, 5)];
        // The pair kernel reads a positive gap as "touched last step" and
        // then decides by the overlap alone: the same pairs touch.
        let mut shared = SharedContacts::default();
        shared.count_pairs(&bed.bodies(), &bed.clump, &pairs, &[1e-6; 3]);
        assert_eq!(shared.pairs, vec![3, 3, 3]);
    }

    #[test]
    fn a_body_on_a_wall_counts_its_sub_spheres_on_that_wall() {
        let mut bed = bed();
        // Rod 0 lies on the base of a cylinder; rod 1 lifted clear.
        let walls = Walls::closed_cylinder(20e-3, 30e-3);
        for p in &mut bed.position {
            p.z = 0.9e-3;
            p.x += 1e-3;
        }
        for k in 3..8 {
            bed.position[k].z += 5e-3;
        }
        let n_walls = walls.len();
        let geometry = WallGeometry {
            shapes: &walls.shapes,
            offset: walls.offset(),
            v_wall: walls.velocity(),
            walls: &walls,
        };
        let gaps = vec![-1.0; bed.position.len() * n_walls];
        let mut shared = SharedContacts::default();
        shared.count_walls(&bed.bodies(), &bed.clump, &geometry, &gaps);
        let base = (0..n_walls)
            .find(|&w| walls.shapes[w].distance_m(bed.position[0], walls.offset()) < 1e-3)
            .expect("rod 0 touches a wall");
        for k in 0..3 {
            assert_eq!(shared.walls[k * n_walls + base], 3, "sub-sphere {k}");
        }
    }
}
