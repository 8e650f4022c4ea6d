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

use glam::{DMat3, DMat4, DVec3};

/// exp(m) by scaling and squaring (infinity norm scaled to <= 1/2, 20 Taylor
/// terms).
fn expm(m: DMat4) -> DMat4 {
    let norm = (0..4)
        .map(|i| m.row(i).abs().element_sum())
        .fold(0.0, f64::max);
    let mut squarings = 0u32;
    let mut scale = 1.0;
    while norm * scale > 0.5 && squarings < 64 {
        scale *= 0.5;
        squarings += 1;
    }
    let a = m * scale;
    let mut sum = DMat4::IDENTITY;
    let mut term = DMat4::IDENTITY;
    for k in 1..=20 {
        term = term * a * (1.0 / f64::from(k));
        sum += term;
    }
    for _ in 0..squarings {
        sum = sum * sum;
    }
    sum
}

/// `(Phi, gamma)` for `z' = A z + b u`, step `dt_s`, `u` held over the step.
pub fn zero_order_hold(a: &DMat3, b: DVec3, dt_s: f64) -> (DMat3, DVec3) {
    let aug = DMat4::from_cols(
        a.x_axis.extend(0.0) * dt_s,
        a.y_axis.extend(0.0) * dt_s,
        a.z_axis.extend(0.0) * dt_s,
        b.extend(0.0) * dt_s,
    );
    let e = expm(aug);
    (DMat3::from_mat4(e), e.w_axis.truncate())
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
}
