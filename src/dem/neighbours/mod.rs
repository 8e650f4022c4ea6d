//! Neighbour search: a cell list feeding a Verlet pair list (thesis Section 3.4).
//!
//! Space is cut into cubic cells a little larger than a particle diameter plus a
//! skin (the thesis used about 2.5 R); each particle is checked against the 27
//! cells around it, which is O(N). The pairs closer than `R_i + R_j + skin` are
//! kept in a sorted list that stays valid until some particle has moved more than
//! half the skin, so the grid is rebuilt only every few tens of steps. Each listed
//! pair carries its [`ContactState`] (the tangential spring history); a rebuild
//! hands the states of surviving pairs over to the new list. Pairs are sorted by
//! `(i, j)`, so everything built from the list is independent of thread count.
//!
//! The overlap of every pair at the previous step is also kept on its own,
//! in [`NeighbourList::gaps`] (for a pair apart, minus the squared distance
//! of the centres: no square root for it): a step asks of most listed pairs
//! only whether they are still apart, and reads 8 bytes for it instead of
//! the whole 96-byte contact state.
//!
//! Each rebuild also lays out, for every particle, its row (the pairs
//! `(p, j)`, [`NeighbourList::row`]) and the pairs `(i, p)` that reach it
//! from an earlier block of the step ([`Adjacency::cross_pairs`], in
//! pair order): a block of the step then evaluates the rows of its own
//! particles and adds to them, and the forces that cross from another block
//! are added afterwards, in a fixed order, so that the sums are the same
//! bits for any number of threads ([`crate::dem::step`]).
//!
//! A bed with rigid bodies is searched body by body instead ([`by_body`]):
//! the same pairs, without looking at the many pairs of one body's
//! sub-spheres, which never form a pair.

mod by_body;

use glam::DVec3;

use super::clumps::NOT_IN_CLUMP;
use super::contact::ContactState;
use super::step::block_size::PARTICLE_BLOCK;
use by_body::ByBody;

/// The parts of a [`NeighbourList`] a step of the pair contacts reads and
/// writes, borrowed apart ([`NeighbourList::step_view`]).
pub struct StepView<'a> {
    pub pairs: &'a [(u32, u32)],
    pub adjacency: &'a Adjacency,
    pub gaps: &'a mut [f64],
    pub states: &'a mut [ContactState],
}

/// Each particle's pairs on the list: its row, and the pairs that reach it
/// from an earlier block of the step.
#[derive(Debug, Clone, Default)]
pub struct Adjacency {
    /// Pairs `(p, j)` of particle `p`: `row_start[p]..row_start[p + 1]`.
    row_start: Vec<u32>,
    /// Pairs `(i, p)` of particle `p` with `i` in an earlier block, in
    /// increasing pair order: `cross[cross_start[p]..cross_start[p + 1]]`.
    cross_start: Vec<u32>,
    cross: Vec<u32>,
}

impl Adjacency {
    /// The pairs `(p, j)` of particle `p`: a run of the pair list.
    #[inline]
    pub fn row(&self, p: usize) -> std::ops::Range<usize> {
        self.row_start[p] as usize..self.row_start[p + 1] as usize
    }

    /// The pairs of the rows of particles `s..e`: a run of the pair list.
    #[inline]
    pub fn rows(&self, s: usize, e: usize) -> std::ops::Range<usize> {
        self.row_start[s] as usize..self.row_start[e] as usize
    }

    /// The pairs `(i, p)` of particle `p` whose `i` is in an earlier block
    /// of the step than `p` ([`PARTICLE_BLOCK`]), in increasing pair order.
    #[inline]
    pub fn cross_pairs(&self, p: usize) -> &[u32] {
        &self.cross[self.cross_start[p] as usize..self.cross_start[p + 1] as usize]
    }
}

/// Verlet pair list with per-pair contact history.
#[derive(Debug, Clone, Default)]
pub struct NeighbourList {
    /// Pairs `(i, j)` with `i < j`, sorted.
    pub pairs: Vec<(u32, u32)>,
    /// Contact state of each pair, same order as `pairs`. Its `delta_prev`
    /// is current only while the pair touches (`gaps[k] > 0`); a pair apart
    /// has the state of [`ContactState::apart`] and its distance in `gaps`.
    pub states: Vec<ContactState>,
    /// What a step needs to know of each pair from the previous one, same
    /// order as `pairs`, always current: the overlap (m) of a pair that
    /// touched; for a pair apart, minus the squared distance of the centres
    /// (m², so never positive), which the step has without a square root
    /// and turns into the gap only when the pair touches
    /// ([`crate::dem::step::contacts::gap_from_code`]).
    pub gaps: Vec<f64>,
    skin_m: f64,
    /// Each particle's row and pairs from earlier blocks.
    adjacency: Adjacency,
    reference: Vec<DVec3>,
    rebuilds: u64,
    // Scratch reused between rebuilds.
    cell_start: Vec<u32>,
    cell_items: Vec<u32>,
    cell_of: Vec<u32>,
    fill: Vec<u32>,
    new_pairs: Vec<(u32, u32)>,
    new_states: Vec<ContactState>,
    new_gaps: Vec<f64>,
    row: Vec<u32>,
    /// The search of a bed of rigid bodies, body by body.
    by_body: ByBody,
    /// The units near one unit, in that search.
    near_units: Vec<u32>,
}

impl NeighbourList {
    /// An empty list with the given skin (m).
    pub fn new(skin_m: f64) -> Self {
        NeighbourList {
            skin_m,
            ..Default::default()
        }
    }

    /// Skin distance (m).
    pub fn skin_m(&self) -> f64 {
        self.skin_m
    }

    /// Changes the skin; takes effect at the next [`Self::rebuild`], which keeps
    /// the state of every pair still listed.
    pub fn set_skin_m(&mut self, skin_m: f64) {
        self.skin_m = skin_m;
    }

    /// How many times the list was built.
    pub fn rebuilds(&self) -> u64 {
        self.rebuilds
    }

    /// What a step reads and writes of the list, borrowed apart: the pairs
    /// and their j slots, and the gaps and contact states it advances.
    pub fn step_view(&mut self) -> StepView<'_> {
        StepView {
            pairs: &self.pairs,
            adjacency: &self.adjacency,
            gaps: &mut self.gaps,
            states: &mut self.states,
        }
    }

    /// Each particle's row and pairs from earlier blocks.
    pub fn adjacency(&self) -> &Adjacency {
        &self.adjacency
    }

    /// The pairs `(p, j)` of particle `p`: a run of the pair list.
    #[inline]
    pub fn row(&self, p: usize) -> std::ops::Range<usize> {
        self.adjacency.row(p)
    }

    /// Where the particles were when the list was last built: a particle
    /// that has travelled more than half the skin from there
    /// ([`Self::rebuild_travel_sq_m2`]) may meet a pair not listed.
    pub fn reference(&self) -> &[DVec3] {
        &self.reference
    }

    /// The squared travel (m²) from [`Self::reference`] beyond which the list
    /// must be rebuilt: (skin / 2)².
    pub fn rebuild_travel_sq_m2(&self) -> f64 {
        0.25 * self.skin_m * self.skin_m
    }

    /// True when some particle moved more than half the skin since the last
    /// build (or the particle count changed), so that a new contact could be
    /// missed. A step asks this of each particle as it moves it instead.
    pub fn needs_rebuild(&self, positions: &[DVec3]) -> bool {
        let limit_sq = self.rebuild_travel_sq_m2();
        positions.len() != self.reference.len()
            || positions
                .iter()
                .zip(&self.reference)
                .any(|(p, r)| (*p - *r).length_squared() > limit_sq)
    }

    /// Lays out the rows and the pairs from earlier blocks of every particle
    /// (see [`Self::row`], [`Self::cross_pairs`]): counting sorts of the pair
    /// ends, filled in pair order.
    fn build_adjacency(&mut self, n: usize) {
        let a = &mut self.adjacency;
        a.row_start.clear();
        a.row_start.resize(n + 1, 0);
        a.cross_start.clear();
        a.cross_start.resize(n + 1, 0);
        let crosses = |i: u32, j: u32| i as usize / PARTICLE_BLOCK != j as usize / PARTICLE_BLOCK;
        for &(i, j) in &self.pairs {
            a.row_start[i as usize + 1] += 1;
            if crosses(i, j) {
                a.cross_start[j as usize + 1] += 1;
            }
        }
        for p in 0..n {
            a.row_start[p + 1] += a.row_start[p];
            a.cross_start[p + 1] += a.cross_start[p];
        }
        a.cross.clear();
        a.cross.resize(a.cross_start[n] as usize, 0);
        self.fill.clear();
        self.fill.extend_from_slice(&a.cross_start[..n]);
        for (k, &(i, j)) in self.pairs.iter().enumerate() {
            if crosses(i, j) {
                let at = &mut self.fill[j as usize];
                a.cross[*at as usize] = k as u32;
                *at += 1;
            }
        }
    }

    /// Rebuilds the pair list from scratch with a cell grid; carries over the state
    /// of pairs that were already listed. New pairs start apart. Two
    /// sub-spheres of one rigid body (`clump`, [`crate::dem::clumps`]; empty
    /// when there are none) never form a pair.
    pub fn rebuild(&mut self, positions: &[DVec3], radii: &[f64], clump: &[u32]) {
        self.rebuild_renumbered(positions, radii, clump, None);
    }

    /// [`Self::rebuild`] after the particles were renumbered: particle `k`
    /// now was particle `old_of_new[k]` when the list was last built (`None`:
    /// not renumbered). Each surviving pair keeps its state under its new
    /// numbers; a pair whose ends swapped order (its body `i` is now the
    /// second) has its vector history turned to the other body's view.
    pub fn rebuild_renumbered(
        &mut self,
        positions: &[DVec3],
        radii: &[f64],
        clump: &[u32],
        old_of_new: Option<&[u32]>,
    ) {
        let n = positions.len();
        self.rebuilds += 1;
        self.reference.clear();
        self.reference.extend_from_slice(positions);
        self.new_pairs.clear();
        self.new_states.clear();
        self.new_gaps.clear();
        if n < 2 {
            self.pairs.clear();
            self.states.clear();
            self.gaps.clear();
            self.build_adjacency(n);
            return;
        }
        let has_bodies = clump.iter().any(|&c| c != NOT_IN_CLUMP);
        let grid = if has_bodies {
            self.search_by_body(positions, radii, clump);
            None
        } else {
            let grid = Grid::around(positions, radii, self.skin_m);
            self.sort_into_cells(&grid, positions);
            Some(grid)
        };
        self.list_pairs(grid.as_ref(), (positions, radii), old_of_new);
        std::mem::swap(&mut self.pairs, &mut self.new_pairs);
        std::mem::swap(&mut self.states, &mut self.new_states);
        std::mem::swap(&mut self.gaps, &mut self.new_gaps);
        self.build_adjacency(n);
    }

    /// The width of the cells the list is built on for particles of largest
    /// radius `r_max_m` (m): one cutoff, `2 R_max + skin`.
    pub fn cell_m(&self, r_max_m: f64) -> f64 {
        2.0 * r_max_m + self.skin_m
    }

    /// Where pair `(i, j)` (old numbers, either order) is on the list as it
    /// was last built for `n` particles, and whether its ends are swapped
    /// there.
    fn old_slot(&self, n: usize, i: u32, j: u32) -> Option<(usize, bool)> {
        if self.adjacency.row_start.len() != n + 1 {
            return None;
        }
        let (lo, hi, swapped) = if i < j { (i, j, false) } else { (j, i, true) };
        let row = self.row(lo as usize);
        let start = row.start;
        self.pairs[row]
            .binary_search_by_key(&hi, |&(_, b)| b)
            .ok()
            .map(|k| (start + k, swapped))
    }

    /// Counting sort of the particles into the cells of `grid`: the
    /// particles of cell `c` are `cell_items[cell_start[c]..cell_start[c + 1]]`.
    fn sort_into_cells(&mut self, grid: &Grid, positions: &[DVec3]) {
        let n_cells = grid.len();
        self.cell_start.clear();
        self.cell_start.resize(n_cells + 1, 0);
        self.cell_of.clear();
        for p in positions {
            let c = grid.index(grid.coords(*p));
            self.cell_of.push(c as u32);
            self.cell_start[c + 1] += 1;
        }
        group_by_key(
            &self.cell_of,
            &mut self.cell_start,
            &mut self.cell_items,
            &mut self.fill,
        );
    }

    /// The pairs of a bed with rigid bodies, found body by body
    /// ([`by_body`]): the units (bodies and free spheres) on a cell grid of
    /// their own, each unit's neighbours from the 27 cells around it, and
    /// the sub-sphere pairs of each two neighbouring units; laid out by rows
    /// for [`Self::list_pairs`].
    fn search_by_body(&mut self, positions: &[DVec3], radii: &[f64], clump: &[u32]) {
        let n_units = self.by_body.group_units(positions, radii, clump);
        let mut by_body = std::mem::take(&mut self.by_body);
        let mut near_units = std::mem::take(&mut self.near_units);
        let grid = Grid::around(&by_body.centre, &by_body.radius, self.skin_m);
        self.sort_into_cells(&grid, &by_body.centre);
        by_body.clear();
        for u in 0..n_units {
            self.fill_row(&grid, &by_body.centre, &by_body.radius, u);
            near_units.clear();
            near_units.extend_from_slice(&self.row);
            for &v in &near_units {
                by_body.pairs_of_units((u, v as usize), positions, radii, self.skin_m);
            }
        }
        by_body.lay_out_rows(positions.len());
        self.by_body = by_body;
        self.near_units = near_units;
    }

    /// The pairs `i < j` within the cutoff, sorted by `(i, j)`, into the new
    /// list, each pair with the state it had on the old list (found in its
    /// row there, under its old numbers `old_of_new`), or apart if it is
    /// new. Each particle's row comes from the 27 cells of `grid` around
    /// it, or, without a grid, from the body-by-body search
    /// ([`Self::search_by_body`]).
    fn list_pairs(
        &mut self,
        grid: Option<&Grid>,
        (positions, radii): (&[DVec3], &[f64]),
        old_of_new: Option<&[u32]>,
    ) {
        let n = positions.len();
        let old_number = |k: u32| old_of_new.map_or(k, |o| o[k as usize]);
        for i in 0..n {
            let pi = positions[i];
            match grid {
                // Only a bed without bodies is searched on the grid: no
                // pair of one body to drop.
                Some(grid) => self.fill_row(grid, positions, radii, i),
                None => {
                    self.row.clear();
                    self.row.extend_from_slice(self.by_body.row(i));
                }
            }
            for r in 0..self.row.len() {
                let j = self.row[r];
                let key = (i as u32, j);
                let found = self.old_slot(n, old_number(i as u32), old_number(j));
                let (state, overlap) = match found {
                    Some((k, swapped)) => {
                        let mut st = self.states[k];
                        if swapped {
                            st.xi = -st.xi;
                            st.ft_prev = -st.ft_prev;
                        }
                        (st, self.gaps[k])
                    }
                    None => {
                        let ju = j as usize;
                        let dist_sq = (positions[ju] - pi).length_squared();
                        let gap = dist_sq.sqrt() - radii[i] - radii[ju];
                        // A pair apart keeps its code, as the step does.
                        let kept = if gap < 0.0 { -gap } else { -dist_sq };
                        (ContactState::apart(-gap), kept)
                    }
                };
                self.new_pairs.push(key);
                self.new_states.push(state);
                self.new_gaps.push(overlap);
            }
        }
    }

    /// The particles `j > i` within the cutoff of particle `i`, sorted, into
    /// `row`.
    fn fill_row(&mut self, grid: &Grid, positions: &[DVec3], radii: &[f64], i: usize) {
        let pi = positions[i];
        let (cx, cy, cz) = grid.coords(pi);
        let (nx, ny, nz) = (grid.nx, grid.ny, grid.nz);
        self.row.clear();
        for z in cz.saturating_sub(1)..=(cz + 1).min(nz - 1) {
            for y in cy.saturating_sub(1)..=(cy + 1).min(ny - 1) {
                for x in cx.saturating_sub(1)..=(cx + 1).min(nx - 1) {
                    let c = grid.index((x, y, z));
                    let (s, e) = (self.cell_start[c] as usize, self.cell_start[c + 1] as usize);
                    for &j in &self.cell_items[s..e] {
                        let ju = j as usize;
                        if ju <= i {
                            continue;
                        }
                        let cut = radii[i] + radii[ju] + self.skin_m;
                        if (positions[ju] - pi).length_squared() < cut * cut {
                            self.row.push(j);
                        }
                    }
                }
            }
        }
        self.row.sort_unstable();
    }
}

/// The cell grid of a rebuild: cubic cells `cell` wide from the corner `lo`,
/// `nx` by `ny` by `nz` of them.
struct Grid {
    lo: DVec3,
    cell: f64,
    nx: usize,
    ny: usize,
    nz: usize,
}

impl Grid {
    /// Cells at least one cutoff (`2 R_max + skin`) wide around the
    /// particles; coarser if the box is sparse and huge.
    fn around(positions: &[DVec3], radii: &[f64], skin_m: f64) -> Self {
        let n = positions.len();
        let r_max = radii.iter().copied().fold(0.0, f64::max);
        let (lo, hi) = bounding_box(positions);
        let mut cell = 2.0 * r_max + skin_m;
        let extent = hi - lo;
        let max_cells = (4 * n + 64) as f64;
        loop {
            let dims = (extent / cell).floor() + DVec3::ONE;
            if dims.x * dims.y * dims.z <= max_cells {
                break;
            }
            cell *= 1.25;
        }
        let dims = ((extent / cell).floor() + DVec3::ONE).as_uvec3();
        Grid {
            lo,
            cell,
            nx: dims.x as usize,
            ny: dims.y as usize,
            nz: dims.z as usize,
        }
    }

    /// Number of cells.
    fn len(&self) -> usize {
        self.nx * self.ny * self.nz
    }

    /// The cell a point falls in.
    #[inline]
    fn coords(&self, p: DVec3) -> (usize, usize, usize) {
        let c = ((p - self.lo) / self.cell).floor();
        (
            (c.x as usize).min(self.nx - 1),
            (c.y as usize).min(self.ny - 1),
            (c.z as usize).min(self.nz - 1),
        )
    }

    /// Index of cell `(x, y, z)`.
    #[inline]
    fn index(&self, (x, y, z): (usize, usize, usize)) -> usize {
        (z * self.ny + y) * self.nx + x
    }
}

/// Counting sort of the items `0..keys.len()` by their keys: with `start`
/// holding each key's count at `start[key + 1]` (and zero at `start[0]`),
/// the items of key `k` become `items[start[k]..start[k + 1]]`, in item
/// order; `fill` is scratch.
fn group_by_key(keys: &[u32], start: &mut [u32], items: &mut Vec<u32>, fill: &mut Vec<u32>) {
    let n_keys = start.len() - 1;
    for k in 0..n_keys {
        start[k + 1] += start[k];
    }
    items.clear();
    items.resize(keys.len(), 0);
    fill.clear();
    fill.extend_from_slice(&start[..n_keys]);
    for (i, &k) in keys.iter().enumerate() {
        let at = &mut fill[k as usize];
        items[*at as usize] = i as u32;
        *at += 1;
    }
}

fn bounding_box(positions: &[DVec3]) -> (DVec3, DVec3) {
    let mut lo = DVec3::splat(f64::INFINITY);
    let mut hi = DVec3::splat(f64::NEG_INFINITY);
    for p in positions {
        lo = lo.min(*p);
        hi = hi.max(*p);
    }
    (lo, hi)
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// Brute-force pair search, the oracle for the cell list.
    fn brute_force(positions: &[DVec3], radii: &[f64], skin: f64) -> Vec<(u32, u32)> {
        let mut out = Vec::new();
        for i in 0..positions.len() {
            for j in i + 1..positions.len() {
                let cut = radii[i] + radii[j] + skin;
                if (positions[j] - positions[i]).length_squared() < cut * cut {
                    out.push((i as u32, j as u32));
                }
            }
        }
        out
    }

    /// `n` points spread at random (a fixed LCG) in a cube `box_m` wide.
    pub(crate) fn scattered(n: usize, box_m: f64, seed: u64) -> Vec<DVec3> {
        // Small deterministic LCG; any spread of points will do here.
        let mut s = seed;
        let mut next = || {
            s = s
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (s >> 11) as f64 / (1u64 << 53) as f64
        };
        (0..n)
            .map(|_| DVec3::new(next(), next(), next()) * box_m)
            .collect()
    }

    #[test]
    fn cell_list_finds_exactly_the_brute_force_pairs() {
        for (n, box_m, seed) in [(300, 0.03, 1), (50, 0.2, 2), (2, 5.0, 3), (400, 0.02, 4)] {
            let pos = scattered(n, box_m, seed);
            let radii = vec![0.0025; n];
            let mut list = NeighbourList::new(0.0005);
            list.rebuild(&pos, &radii, &[]);
            assert_eq!(list.pairs, brute_force(&pos, &radii, 0.0005), "n {n}");
        }
    }

    /// The body-by-body search against brute force on a bed of bodies
    /// (chains of overlapping sub-spheres of unequal radii, their particles
    /// interleaved with other bodies' and with free spheres): a filter that
    /// drops a pair within the cutoff, or a pair of one body listed, fails
    /// it.
    #[test]
    fn body_by_body_search_finds_exactly_the_brute_force_pairs_of_other_bodies() {
        for (n_bodies, n_free, box_m, seed) in
            [(120, 40, 0.05, 11), (60, 0, 0.03, 12), (3, 5, 0.008, 13)]
        {
            let centres = scattered(n_bodies + n_free, box_m, seed);
            let axes = scattered(n_bodies, 2.0, seed + 100);
            let (mut pos, mut radii, mut clump) = (Vec::new(), Vec::new(), Vec::new());
            for (b, c) in centres.iter().enumerate() {
                if b < n_bodies {
                    let axis = (axes[b] - DVec3::ONE).normalize_or(DVec3::X);
                    for k in 0..7 {
                        pos.push(*c + axis * (k as f64 - 3.0) * 0.0008);
                        radii.push(0.0015 + 0.0002 * f64::from(3 - (k - 3i32).abs()));
                        clump.push(b as u32);
                    }
                } else {
                    pos.push(*c);
                    radii.push(0.002);
                    clump.push(NOT_IN_CLUMP);
                }
            }
            // Interleave: a fixed shuffle of the particles.
            let n = pos.len();
            let order: Vec<usize> = (0..n).map(|k| (k * 37 + 11) % n).collect();
            assert!(n % 37 != 0);
            let pos: Vec<DVec3> = order.iter().map(|&k| pos[k]).collect();
            let radii: Vec<f64> = order.iter().map(|&k| radii[k]).collect();
            let clump: Vec<u32> = order.iter().map(|&k| clump[k]).collect();
            let skin = 0.0003;
            let expected: Vec<(u32, u32)> = brute_force(&pos, &radii, skin)
                .into_iter()
                .filter(|&(i, j)| {
                    let (a, b) = (clump[i as usize], clump[j as usize]);
                    a == NOT_IN_CLUMP || a != b
                })
                .collect();
            let mut list = NeighbourList::new(skin);
            list.rebuild(&pos, &radii, &clump);
            assert!(!expected.is_empty(), "bodies {n_bodies}: the bed has pairs");
            assert_eq!(list.pairs, expected, "bodies {n_bodies}, free {n_free}");
        }
    }

    /// Rows and the pairs from earlier blocks against a scan of the whole
    /// list, on a bed of several blocks: a pair listed under the wrong end,
    /// or one within a block taken for one that crosses, fails it.
    #[test]
    fn rows_and_crossing_pairs_list_each_particles_pairs_in_pair_order() {
        let n = 3 * PARTICLE_BLOCK;
        let pos = scattered(n, 0.04, 5);
        let radii = vec![0.0025; n];
        let mut list = NeighbourList::new(0.0005);
        list.rebuild(&pos, &radii, &[]);
        let block = |p: u32| p as usize / PARTICLE_BLOCK;
        let mut crossing = 0;
        for p in 0..n {
            let as_i: Vec<usize> = (0..list.pairs.len())
                .filter(|&k| list.pairs[k].0 as usize == p)
                .collect();
            let from_before: Vec<u32> = (0..list.pairs.len() as u32)
                .filter(|&k| {
                    let (i, j) = list.pairs[k as usize];
                    j as usize == p && block(i) < block(j)
                })
                .collect();
            crossing += from_before.len();
            assert_eq!(list.row(p).collect::<Vec<_>>(), as_i, "particle {p}");
            assert_eq!(
                list.adjacency().cross_pairs(p),
                &from_before[..],
                "particle {p}"
            );
        }
        assert!(crossing > 0, "the test bed has pairs across blocks");
    }

    /// A rebuild after a renumbering finds every surviving pair's history
    /// under its new numbers, turned to the other body's view where the
    /// pair's ends swapped order. Losing the history (a lookup under the new
    /// numbers), or not negating it, fails it.
    #[test]
    fn a_renumbered_rebuild_carries_each_history_to_the_pairs_new_numbers() {
        let n = 400;
        let pos = scattered(n, 0.03, 9);
        let radii = vec![0.0025; n];
        let mut list = NeighbourList::new(0.0005);
        list.rebuild(&pos, &radii, &[]);
        for (k, st) in list.states.iter_mut().enumerate() {
            st.xi = DVec3::new(k as f64 + 1.0, 0.0, 0.0);
            st.ft_prev = DVec3::new(0.0, k as f64 + 1.0, 0.0);
            st.u_normal_j = k as f64 + 1.0;
        }
        let before: Vec<((u32, u32), ContactState)> = list
            .pairs
            .iter()
            .copied()
            .zip(list.states.clone())
            .collect();
        // Reverse the numbering: every pair's ends swap order.
        let old_of_new: Vec<u32> = (0..n as u32).rev().collect();
        let moved: Vec<DVec3> = old_of_new.iter().map(|&o| pos[o as usize]).collect();
        list.rebuild_renumbered(&moved, &radii, &[], Some(&old_of_new));
        assert_eq!(list.pairs.len(), before.len());
        for (&(a, b), st) in list.pairs.iter().zip(&list.states) {
            let (oa, ob) = (old_of_new[a as usize], old_of_new[b as usize]);
            let (_, old) = before
                .iter()
                .find(|(p, _)| *p == (ob, oa))
                .expect("the pair, its ends swapped");
            assert_eq!(st.u_normal_j, old.u_normal_j);
            assert_eq!(st.xi, -old.xi);
            assert_eq!(st.ft_prev, -old.ft_prev);
        }
    }

    #[test]
    fn rebuild_keeps_history_of_surviving_pairs() {
        let pos = scattered(200, 0.03, 7);
        let radii = vec![0.0025; 200];
        let mut list = NeighbourList::new(0.0005);
        list.rebuild(&pos, &radii, &[]);
        for (k, st) in list.states.iter_mut().enumerate() {
            st.xi = DVec3::splat(k as f64);
        }
        let before: Vec<_> = list
            .pairs
            .iter()
            .copied()
            .zip(list.states.clone())
            .collect();
        // Nudge one particle far away: its pairs vanish, the rest keep their state.
        let mut moved = pos.clone();
        moved[0] += DVec3::splat(1.0);
        list.rebuild(&moved, &radii, &[]);
        for (pair, st) in list.pairs.iter().zip(&list.states) {
            let old = before
                .iter()
                .find(|(p, _)| p == pair)
                .expect("pair existed");
            assert_eq!(old.1.xi, st.xi);
        }
        assert!(list.pairs.iter().all(|&(i, _)| i != 0));
    }
}
