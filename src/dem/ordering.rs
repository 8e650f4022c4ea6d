//! Particles ordered in space: the renumbering that keeps spheres that touch
//! close in memory.
//!
//! A poured bed comes out of the pour column in random order, and a shaken
//! bed mixes: particle `i`'s neighbours sit anywhere in the arrays, and a
//! step that reads them misses the cache on most pairs (a poured bed of
//! 5 000 spheres stepped about four times slower per core than a lattice bed
//! of the same size, docs/performance.md). So a bed larger than one block of
//! the step is renumbered each time its neighbour list is rebuilt
//! (thesis Section 3.4: the list is rebuilt when some particle moved half the
//! skin): by the Morton (Z-order) key of the neighbour cell it is in, so
//! that a run of the arrays is a compact lump of space and the fixed blocks
//! of the step ([`crate::dem::step`]) are lumps too, and by id within a cell.
//!
//! The order is a function of the positions and ids alone, not of the order
//! the particles come in: a bed read back from a cache in id order and the
//! bed that was settled are renumbered alike, and drive to the same bits.

use glam::DVec3;

/// Bits per axis of a Morton key: 21, three of them fit a `u64`.
const MORTON_BITS: u32 = 21;

/// The order that puts the particles at `positions` (with ids `ids`) in
/// space order, into `order`: the `k`-th particle of the new numbering is
/// the `order[k]`-th of the current one. Cells are `cell_m` wide from the
/// corner of the particles' bounding box; `keys` is scratch.
pub fn space_order(
    positions: &[DVec3],
    ids: &[u32],
    cell_m: f64,
    keys: &mut Vec<(u64, u32, u32)>,
    order: &mut Vec<u32>,
) {
    let lo = positions
        .iter()
        .fold(DVec3::splat(f64::INFINITY), |lo, p| lo.min(*p));
    let limit = f64::from((1u32 << MORTON_BITS) - 1);
    keys.clear();
    keys.extend(positions.iter().zip(ids).enumerate().map(|(k, (p, &id))| {
        let c = ((*p - lo) / cell_m)
            .floor()
            .clamp(DVec3::ZERO, DVec3::splat(limit));
        (morton_key(c.x as u32, c.y as u32, c.z as u32), id, k as u32)
    }));
    keys.sort_unstable();
    order.clear();
    order.extend(keys.iter().map(|&(_, _, k)| k));
}

/// Interleaves the bits of the cell coordinates `(x, y, z)` (each below
/// 2^21): the Z-order curve, along which cells near in the key are near in
/// space.
pub fn morton_key(x: u32, y: u32, z: u32) -> u64 {
    spread(x) | (spread(y) << 1) | (spread(z) << 2)
}

/// The low 21 bits of `v`, two zero bits between each.
fn spread(v: u32) -> u64 {
    let mut x = u64::from(v) & 0x1f_ffff;
    x = (x | (x << 32)) & 0x1f_0000_0000_ffff;
    x = (x | (x << 16)) & 0x1f_0000_ff00_00ff;
    x = (x | (x << 8)) & 0x100f_00f0_0f00_f00f;
    x = (x | (x << 4)) & 0x10c3_0c30_c30c_30c3;
    x = (x | (x << 2)) & 0x1249_2492_4924_9249;
    x
}

/// True when `order` leaves every particle where it is.
pub fn is_identity(order: &[u32]) -> bool {
    order.iter().enumerate().all(|(k, &o)| o as usize == k)
}

/// A renumbering as its cycles: found once ([`Renumbering::find`]), then
/// applied to every array in place, so that renumbering a bed allocates
/// nothing once the buffers have grown (each value is moved, never
/// computed: the same bits as a copy into a new array).
#[derive(Debug, Clone, Default)]
pub struct Renumbering {
    /// The first index of each cycle of two or more.
    starts: Vec<u32>,
    /// Marks of the search.
    seen: Vec<bool>,
}

impl Renumbering {
    /// The cycles of `order`, a permutation of `0..order.len()` (the `k`-th
    /// of a renumbered array is the `order[k]`-th of the old).
    pub fn find(&mut self, order: &[u32]) {
        self.starts.clear();
        self.seen.clear();
        self.seen.resize(order.len(), false);
        for s in 0..order.len() {
            if self.seen[s] {
                continue;
            }
            let mut k = s;
            while !self.seen[k] {
                self.seen[k] = true;
                k = order[k] as usize;
            }
            if order[s] as usize != s {
                self.starts.push(s as u32);
            }
        }
    }

    /// Renumbers `values` by the cycles found for `order`.
    pub fn apply<T: Copy>(&self, values: &mut [T], order: &[u32]) {
        self.apply_rows(values, order, 1);
    }

    /// Renumbers `values`, `width` entries per particle (a particle's
    /// contacts with each wall): the `k`-th particle's entries of the result
    /// are the `order[k]`-th particle's of the input.
    pub fn apply_rows<T: Copy>(&self, values: &mut [T], order: &[u32], width: usize) {
        debug_assert_eq!(values.len(), order.len() * width);
        for c in 0..width {
            for &s in &self.starts {
                let s = s as usize;
                let first = values[s * width + c];
                let mut k = s;
                loop {
                    let from = order[k] as usize;
                    if from == s {
                        values[k * width + c] = first;
                        break;
                    }
                    values[k * width + c] = values[from * width + c];
                    k = from;
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dem::neighbours::tests::scattered;

    /// The bit interleaving against a slow reference: bit b of x, y, z lands
    /// at 3b, 3b + 1, 3b + 2. A wrong mask constant fails it.
    #[test]
    fn morton_key_interleaves_the_bits() {
        let slow = |x: u32, y: u32, z: u32| {
            (0..MORTON_BITS).fold(0u64, |k, b| {
                k | (u64::from(x >> b & 1) << (3 * b))
                    | (u64::from(y >> b & 1) << (3 * b + 1))
                    | (u64::from(z >> b & 1) << (3 * b + 2))
            })
        };
        for (x, y, z) in [(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1), (5, 9, 3)] {
            assert_eq!(morton_key(x, y, z), slow(x, y, z));
        }
        let max = (1 << MORTON_BITS) - 1;
        assert_eq!(morton_key(max, max, max), u64::MAX >> 1);
        assert_eq!(
            morton_key(12345, 999_999, 2_000_000),
            slow(12345, 999_999, 2_000_000)
        );
    }

    /// The order depends on where the particles are, not on the order they
    /// come in: the same particles shuffled come out in the same id order
    /// (a tie broken by the current number instead of the id fails this).
    #[test]
    fn the_order_is_a_function_of_positions_and_ids() {
        let pos = scattered(2000, 0.05, 3);
        let ids: Vec<u32> = (0..2000).collect();
        let (mut keys, mut order) = (Vec::new(), Vec::new());
        space_order(&pos, &ids, 0.01, &mut keys, &mut order);
        let sorted_ids: Vec<u32> = order.iter().map(|&k| ids[k as usize]).collect();
        // Shuffle by a fixed permutation and order again.
        let shuffle: Vec<u32> = (0..2000u32).map(|k| (k * 7919) % 2000).collect();
        let pos2: Vec<DVec3> = shuffle.iter().map(|&k| pos[k as usize]).collect();
        let ids2: Vec<u32> = shuffle.iter().map(|&k| ids[k as usize]).collect();
        space_order(&pos2, &ids2, 0.01, &mut keys, &mut order);
        let sorted_ids2: Vec<u32> = order.iter().map(|&k| ids2[k as usize]).collect();
        assert_eq!(sorted_ids, sorted_ids2);
        let mut seen = sorted_ids.clone();
        seen.sort_unstable();
        assert_eq!(seen, ids, "a permutation");
    }

    /// After ordering, particles next to each other in the arrays are close
    /// in space: the mean distance between consecutive particles drops from
    /// about half the box (random order) to below 2.5 cells. An order that
    /// sorted by one axis only would leave it near the box's width.
    #[test]
    fn consecutive_particles_are_close_in_space() {
        let pos = scattered(4000, 0.05, 11);
        let ids: Vec<u32> = (0..4000).collect();
        let (mut keys, mut order) = (Vec::new(), Vec::new());
        let cell = 0.004;
        space_order(&pos, &ids, cell, &mut keys, &mut order);
        let mean_step = |p: &[DVec3]| {
            p.windows(2).map(|w| (w[1] - w[0]).length()).sum::<f64>() / (p.len() - 1) as f64
        };
        let ordered: Vec<DVec3> = order.iter().map(|&k| pos[k as usize]).collect();
        assert!(mean_step(&pos) > 0.02, "random order: {}", mean_step(&pos));
        assert!(
            mean_step(&ordered) < 2.5 * cell,
            "space order: {} m",
            mean_step(&ordered)
        );
    }

    #[test]
    fn rows_move_with_their_particle() {
        let mut v = vec![0, 1, 10, 11, 20, 21];
        let mut r = Renumbering::default();
        r.find(&[2, 0, 1]);
        r.apply_rows(&mut v, &[2, 0, 1], 2);
        assert_eq!(v, vec![20, 21, 0, 1, 10, 11]);
        assert!(is_identity(&[0, 1, 2]));
        assert!(!is_identity(&[1, 0, 2]));
    }

    /// In place by cycles, a renumbering gives what a copy in the new order
    /// gives, for permutations of one cycle, several, fixed points and none.
    #[test]
    fn renumbering_in_place_equals_a_copy() {
        let mut x = 0x2545_f491_4f6c_dd1d_u64;
        let mut r = Renumbering::default();
        for n in [0usize, 1, 2, 7, 64, 1000] {
            let mut order: Vec<u32> = (0..n as u32).collect();
            for k in (1..n).rev() {
                x ^= x << 13;
                x ^= x >> 7;
                x ^= x << 17;
                order.swap(k, (x % (k as u64 + 1)) as usize);
            }
            let values: Vec<f64> = (0..n).map(|k| k as f64 * 1.5).collect();
            let copy: Vec<f64> = order.iter().map(|&k| values[k as usize]).collect();
            let mut in_place = values.clone();
            r.find(&order);
            r.apply(&mut in_place, &order);
            assert_eq!(in_place, copy, "n = {n}");
        }
    }
}
