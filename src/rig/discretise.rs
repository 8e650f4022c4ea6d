//! Exact discretisation of a small linear time-invariant system with a
//! zero-order-hold input (used by the electrodynamic shaker).
//!
//! For `z' = A z + b u` with `u` constant over a step of `dt`,
//! `z(t + dt) = Phi z(t) + gamma u` with `Phi = exp(A dt)` and
//! `gamma = integral_0^dt exp(A s) ds b`. Both come from one matrix
//! exponential of the augmented matrix `[[A, b], [0, 0]] dt`, whose top-right
//! column is `gamma` (Van Loan), so `A` need not be invertible. The
//! exponential is computed by scaling and squaring with a Taylor series,
//! accurate to rounding for the small, well-scaled matrices met here.

/// State dimension.
pub const N: usize = 3;
const M: usize = N + 1;

type Mat = [[f64; M]; M];

fn mul(a: &Mat, b: &Mat) -> Mat {
    let mut c = [[0.0; M]; M];
    for i in 0..M {
        for k in 0..M {
            let aik = a[i][k];
            for j in 0..M {
                c[i][j] += aik * b[k][j];
            }
        }
    }
    c
}

fn identity() -> Mat {
    let mut m = [[0.0; M]; M];
    for (i, row) in m.iter_mut().enumerate() {
        row[i] = 1.0;
    }
    m
}

/// exp(m) by scaling and squaring (norm scaled to <= 1/2, 20 Taylor terms).
fn expm(m: &Mat) -> Mat {
    let norm = m
        .iter()
        .map(|row| row.iter().map(|x| x.abs()).sum::<f64>())
        .fold(0.0, f64::max);
    let mut squarings = 0u32;
    let mut scale = 1.0;
    while norm * scale > 0.5 && squarings < 64 {
        scale *= 0.5;
        squarings += 1;
    }
    let mut a = *m;
    for row in a.iter_mut() {
        for x in row.iter_mut() {
            *x *= scale;
        }
    }
    let mut sum = identity();
    let mut term = identity();
    for k in 1..=20 {
        term = mul(&term, &a);
        let inv_k = 1.0 / f64::from(k);
        for row in term.iter_mut() {
            for x in row.iter_mut() {
                *x *= inv_k;
            }
        }
        for i in 0..M {
            for j in 0..M {
                sum[i][j] += term[i][j];
            }
        }
    }
    for _ in 0..squarings {
        sum = mul(&sum, &sum);
    }
    sum
}

/// `(Phi, gamma)` for `z' = A z + b u`, step `dt_s`, `u` held over the step.
pub fn zero_order_hold(a: &[[f64; N]; N], b: &[f64; N], dt_s: f64) -> ([[f64; N]; N], [f64; N]) {
    let mut aug = [[0.0; M]; M];
    for i in 0..N {
        for j in 0..N {
            aug[i][j] = a[i][j] * dt_s;
        }
        aug[i][N] = b[i] * dt_s;
    }
    let e = expm(&aug);
    let mut phi = [[0.0; N]; N];
    let mut gamma = [0.0; N];
    for i in 0..N {
        phi[i][..N].copy_from_slice(&e[i][..N]);
        gamma[i] = e[i][N];
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
        let a = [[0.0, 1.0, 0.0], [-w * w, 0.0, 0.0], [0.0, 0.0, -2.0]];
        let b = [0.0, 1.0, 0.0];
        let dt = 0.7;
        let (phi, g) = zero_order_hold(&a, &b, dt);
        let (s, c) = (w * dt).sin_cos();
        let want = [
            [c, s / w, 0.0],
            [-w * s, c, 0.0],
            [0.0, 0.0, (-2.0 * dt).exp()],
        ];
        for i in 0..N {
            for j in 0..N {
                assert!((phi[i][j] - want[i][j]).abs() < 1e-13, "{i}{j}");
            }
        }
        assert!((g[0] - (1.0 - c) / (w * w)).abs() < 1e-14);
        assert!((g[1] - s / w).abs() < 1e-14);
        assert_eq!(g[2], 0.0);
    }
}
