//! The pair search of a bed of rigid bodies, body by body: a broad phase on
//! the bodies' bounding spheres before any sub-sphere pair is looked at.
//!
//! A body of many overlapping sub-spheres (the 51 of a prolate, thesis
//! Section 4.3) fills the cells around each of its sub-spheres with its own
//! sub-spheres, which the sphere search of [`super::NeighbourList`] checks
//! and then drops (two sub-spheres of one body never form a pair). Here the
//! cell grid holds bodies instead: each body (or free sphere) is a *unit*
//! with a bounding sphere; two units whose bounding spheres come within the
//! skin are the only ones whose sub-spheres can; of those, only the
//! sub-spheres within the skin of the other unit's bounding sphere are
//! paired, and each such pair is kept by the very test the sphere search
//! makes. The list is the same set of pairs, the same bits: only fewer
//! candidates are looked at.
//!
//! Why the filters lose no pair: with `c`, `R` a unit's centre and bounding
//! radius (`|p_b − c_V| + r_b ≤ R_V` for each of its sub-spheres `b`), a
//! pair within the cutoff, `|p_a − p_b| < r_a + r_b + s`, has
//! `|p_a − c_V| < R_V + r_a + s` and `|c_U − c_V| < R_U + R_V + s` by the
//! triangle inequality. The bounding radii are widened by a relative 1e-9
//! so that rounding cannot break either inequality.

use glam::DVec3;

use super::group_by_key;
use crate::dem::clumps::NOT_IN_CLUMP;

/// Relative widening of a bounding radius against rounding.
const BOUND_MARGIN: f64 = 1e-9;

/// Scratch of the body-by-body search, kept between rebuilds.
#[derive(Debug, Clone, Default)]
pub struct ByBody {
    /// Per unit, its first member in `members`: the members of unit `u`
    /// are `members[member_start[u]..member_start[u + 1]]`.
    member_start: Vec<u32>,
    members: Vec<u32>,
    /// Per particle: its unit.
    unit: Vec<u32>,
    /// Per unit: the centre (m) and radius (m) of its bounding sphere.
    pub(super) centre: Vec<DVec3>,
    pub(super) radius: Vec<f64>,
    /// The pairs found, `(i, j)` with `i < j`, before they are laid out.
    found: Vec<(u32, u32)>,
    /// The pairs found, by rows: particle `i`'s partners `j`, sorted, are
    /// `partners[row_start[i]..row_start[i + 1]]`.
    row_start: Vec<u32>,
    partners: Vec<u32>,
    /// The members of two units that pass the other's bounding sphere.
    near_u: Vec<u32>,
    near_v: Vec<u32>,
    fill: Vec<u32>,
}

impl ByBody {
    /// Particle `i`'s partners `j > i`, sorted, as the last
    /// [`Self::pairs_of_units`] found them.
    pub fn row(&self, i: usize) -> &[u32] {
        &self.partners[self.row_start[i] as usize..self.row_start[i + 1] as usize]
    }

    /// Groups the particles into units, each body one and each free sphere
    /// (`clump[i] == NOT_IN_CLUMP`) one of its own, and gives each unit its
    /// bounding sphere: centred on the middle of its sub-spheres' centres,
    /// reaching the farthest sub-sphere's surface. Returns the number of
    /// units.
    pub fn group_units(&mut self, positions: &[DVec3], radii: &[f64], clump: &[u32]) -> usize {
        let n_bodies = clump
            .iter()
            .filter(|&&c| c != NOT_IN_CLUMP)
            .map(|&c| c as usize + 1)
            .max()
            .unwrap_or(0);
        let n_free = clump.iter().filter(|&&c| c == NOT_IN_CLUMP).count();
        let n_units = n_bodies + n_free;
        // Each particle's unit: its body, or the next free sphere's number.
        let mut next_free = n_bodies;
        let mut unit_of = |c: u32| -> usize {
            if c == NOT_IN_CLUMP {
                next_free += 1;
                next_free - 1
            } else {
                c as usize
            }
        };
        self.unit.clear();
        self.unit.extend(clump.iter().map(|&c| unit_of(c) as u32));
        // Counting sort of the particles by unit.
        self.member_start.clear();
        self.member_start.resize(n_units + 1, 0);
        for &u in &self.unit {
            self.member_start[u as usize + 1] += 1;
        }
        group_by_key(
            &self.unit,
            &mut self.member_start,
            &mut self.members,
            &mut self.fill,
        );
        self.centre.clear();
        self.radius.clear();
        for u in 0..n_units {
            let own = self.members_of(u);
            let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
            for &i in own {
                lo = lo.min(positions[i as usize]);
                hi = hi.max(positions[i as usize]);
            }
            // A body number without sub-spheres (none is made so) would
            // have no box: it sits at the origin with nothing to pair.
            let c = if own.is_empty() {
                DVec3::ZERO
            } else {
                0.5 * (lo + hi)
            };
            let r = own
                .iter()
                .map(|&i| (positions[i as usize] - c).length() + radii[i as usize])
                .fold(0.0, f64::max);
            self.centre.push(c);
            self.radius.push(r * (1.0 + BOUND_MARGIN));
        }
        n_units
    }

    /// The members of unit `u`.
    fn members_of(&self, u: usize) -> &[u32] {
        &self.members[self.member_start[u] as usize..self.member_start[u + 1] as usize]
    }

    /// Starts a search: no pair found yet.
    pub fn clear(&mut self) {
        self.found.clear();
    }

    /// Adds the pairs within the cutoff `r_i + r_j + skin_m` between the
    /// sub-spheres of units `u` and `v` (whose bounding spheres are within
    /// the skin): first each unit's members near the other's bounding
    /// sphere, then every pair of those, by the sphere search's own test.
    pub fn pairs_of_units(
        &mut self,
        (u, v): (usize, usize),
        positions: &[DVec3],
        radii: &[f64],
        skin_m: f64,
    ) {
        let near = |own: &[u32], c: DVec3, r: f64, out: &mut Vec<u32>| {
            out.clear();
            for &a in own {
                let reach = r + radii[a as usize] + skin_m;
                if (positions[a as usize] - c).length_squared() < reach * reach {
                    out.push(a);
                }
            }
        };
        let (mut near_u, mut near_v) = (
            std::mem::take(&mut self.near_u),
            std::mem::take(&mut self.near_v),
        );
        near(
            self.members_of(u),
            self.centre[v],
            self.radius[v],
            &mut near_u,
        );
        if !near_u.is_empty() {
            near(
                self.members_of(v),
                self.centre[u],
                self.radius[u],
                &mut near_v,
            );
            for &a in &near_u {
                for &b in &near_v {
                    let (i, j) = if a < b { (a, b) } else { (b, a) };
                    let (iu, ju) = (i as usize, j as usize);
                    // The very bits of the sphere search's test.
                    let cut = radii[iu] + radii[ju] + skin_m;
                    if (positions[ju] - positions[iu]).length_squared() < cut * cut {
                        self.found.push((i, j));
                    }
                }
            }
        }
        self.near_u = near_u;
        self.near_v = near_v;
    }

    /// Lays the pairs found out by rows for `n` particles, each row sorted
    /// ([`Self::row`]).
    pub fn lay_out_rows(&mut self, n: usize) {
        self.row_start.clear();
        self.row_start.resize(n + 1, 0);
        for &(i, _) in &self.found {
            self.row_start[i as usize + 1] += 1;
        }
        for p in 0..n {
            self.row_start[p + 1] += self.row_start[p];
        }
        self.partners.clear();
        self.partners.resize(self.found.len(), 0);
        self.fill.clear();
        self.fill.extend_from_slice(&self.row_start[..n]);
        for &(i, j) in &self.found {
            let at = &mut self.fill[i as usize];
            self.partners[*at as usize] = j;
            *at += 1;
        }
        for p in 0..n {
            let (s, e) = (self.row_start[p] as usize, self.row_start[p + 1] as usize);
            self.partners[s..e].sort_unstable();
        }
    }
}
