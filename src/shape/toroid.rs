//! The analytical multi-sphere circular toroid (thesis Section 4.4.2,
//! eq. 4.26–4.34): n identical sub-spheres of the tube's radius b, centred
//! on the tube's centre circle of radius a in the xy plane, at angles
//! φᵢ = Δφ (i − 1), Δφ = 2π/n (eq. 4.26, 4.28–4.29). Each touches the tube
//! along the tube's cross-section through its centre.
//!
//! Eq. 4.27 checked: neighbours overlap when their centre distance
//! 2a sin(Δφ/2) (eq. 4.30) is below 2b, i.e. Δφ < 2 asin(b/a), i.e.
//! n > π / asin(b/a). The printed Δφ < 2b/a is the small-angle form of it
//! (sin x < x, so it asks for more spheres than needed: for a/b = 1.1 it
//! wants n >= 4 where n = 3 already overlaps); the exact condition is used.
//!
//! The two-dimensional accuracy check of eq. 4.31–4.34 (the xy cut against
//! the annulus of area 4πab and perimeter 4πa) is computed exactly by
//! [`super::section::disc_union`]: eq. 4.31–4.32 assume only neighbouring
//! spheres overlap, which fails for the thesis' 50 spheres at a/b = 2.

use super::exact::Torus;
use super::section::{Disc, disc_union};
use super::{MultiSphere, ShapeError, SubSphere};
use crate::maths;
use glam::{DVec2, DVec3};
use std::f64::consts::{PI, TAU};

/// The fewest sub-spheres whose neighbours overlap on `torus`'s centre
/// circle: the least n with a sin(π/n) < b (exact eq. 4.27). Neighbours
/// that only touch (within 1e-12 of b, as at a/b = 2 with n = 6) do not
/// count as overlapping: a clump joined at single points is not rigid in
/// the sense the method intends.
pub fn min_subs(torus: &Torus) -> usize {
    let (a, b) = (torus.a_m, torus.b_m);
    let overlaps = |n: usize| a * maths::sin(PI / n as f64) < b * (1.0 - 1e-12);
    let mut n = ((PI / (b / a).min(1.0).asin()).floor() as usize).max(2);
    while !overlaps(n) {
        n += 1;
    }
    while n > 2 && overlaps(n - 1) {
        n -= 1;
    }
    n
}

/// Place `n_subs` sub-spheres of radius b on `torus`'s centre circle
/// (eq. 4.26–4.29), refusing fewer than [`min_subs`].
pub fn ring(torus: &Torus, n_subs: usize) -> Result<MultiSphere, ShapeError> {
    let n_min = min_subs(torus);
    if n_subs < n_min {
        return Err(ShapeError::TooFewToroidSubs {
            n_subs,
            n_min,
            a_m: torus.a_m,
            b_m: torus.b_m,
        });
    }
    let dphi = TAU / n_subs as f64;
    let subs = (0..n_subs)
        .map(|i| {
            let (s, c) = maths::sin_cos(dphi * i as f64);
            SubSphere::new(DVec3::new(torus.a_m * c, torus.a_m * s, 0.0), torus.b_m)
        })
        .collect();
    Ok(MultiSphere::new(subs))
}

/// Relative errors of the ring's xy cut against the torus' annulus:
/// (area − 4πab)/4πab and (perimeter − 4πa)/4πa (eq. 4.31–4.34, computed
/// exactly for any overlap pattern).
pub fn section_errors(torus: &Torus, body: &MultiSphere) -> (f64, f64) {
    let discs: Vec<Disc> = body
        .subs
        .iter()
        .map(|s| Disc {
            centre_m: DVec2::new(s.centre_m.x, s.centre_m.y),
            radius_m: s.radius_m,
        })
        .collect();
    let u = disc_union(&discs);
    let (a, b) = (torus.a_m, torus.b_m);
    (
        u.moments.area_m2 / (4.0 * PI * a * b) - 1.0,
        u.perimeter_m / (4.0 * PI * a) - 1.0,
    )
}

#[cfg(test)]
mod tests {
    use super::super::fibonacci_directions;
    use super::*;

    fn torus(a_over_b: f64) -> Torus {
        Torus::from_tube_ratio(a_over_b, 3.5e-3).unwrap()
    }

    /// Every sub-sphere lies inside the torus (2000 surface points, implicit
    /// <= 1e-12) and touches the tube along its cross-section circle
    /// (implicit = 0 to 1e-12 on it). Catches centres off the tube's centre
    /// circle or a radius other than b.
    #[test]
    fn sub_spheres_inside_and_tangent() {
        let t = torus(1.5);
        let body = ring(&t, 50).unwrap();
        let dirs = fibonacci_directions(2000);
        for s in &body.subs {
            for d in &dirs {
                assert!(t.implicit(s.centre_m + s.radius_m * *d) <= 1e-12);
            }
            let radial = DVec3::new(s.centre_m.x, s.centre_m.y, 0.0).normalize();
            for k in 0..16 {
                let (sn, cs) = (TAU * k as f64 / 16.0).sin_cos();
                let q = s.centre_m + s.radius_m * (cs * radial + sn * DVec3::Z);
                assert!(t.implicit(q).abs() <= 1e-12);
            }
        }
    }

    /// Exact eq. 4.27: at min_subs neighbours overlap (centre distance < 2b),
    /// one fewer they do not, and fewer are refused with the numbers in the
    /// message. For a/b = 2, asin(1/2) = π/6, so 6 only touches and 7 is the
    /// least. Catches the small-angle form or an off-by-one.
    #[test]
    fn min_subs_is_exact_touching_condition() {
        for ratio in [1.0, 1.1, 1.25, 1.5, 1.75, 2.0, 5.0] {
            let t = torus(ratio);
            let n = min_subs(&t);
            let gap = |n: usize| 2.0 * t.a_m * (PI / n as f64).sin() - 2.0 * t.b_m;
            assert!(gap(n) < -1e-12 * t.b_m, "ratio {ratio}, n {n}");
            assert!(
                n == 2 || gap(n - 1) >= -1e-12 * t.b_m,
                "ratio {ratio}, n {n}"
            );
        }
        assert_eq!(min_subs(&torus(2.0)), 7);
        assert_eq!(min_subs(&torus(1.1)), 3);
        let e = ring(&torus(2.0), 6).unwrap_err().to_string();
        assert!(e.contains("n_subs 6") && e.contains(">= 7"), "{e}");
    }

    /// Fig. 4.11's shape: the xy cut underestimates the annulus' area and
    /// overestimates its perimeter, both errors fall strictly with n (from
    /// the least allowed to 100), and at n = 50 the larger hole ratio errs
    /// more. Catches a ring that does not converge on the torus.
    #[test]
    fn section_errors_fall_with_n_as_fig_4_11() {
        let mut at_50 = Vec::new();
        for ratio in [1.1, 1.5, 2.0] {
            let t = torus(ratio);
            let counts = [min_subs(&t), 10, 20, 50, 100];
            let errs: Vec<(f64, f64)> = counts
                .iter()
                .map(|&n| section_errors(&t, &ring(&t, n).unwrap()))
                .collect();
            for w in errs.windows(2) {
                assert!(
                    w[0].0 < 0.0 && w[1].0 < 0.0 && w[1].0 > w[0].0,
                    "ratio {ratio}: {errs:?}"
                );
                assert!(
                    w[0].1 > 0.0 && w[1].1 > 0.0 && w[1].1 < w[0].1,
                    "ratio {ratio}: {errs:?}"
                );
            }
            at_50.push(section_errors(&t, &ring(&t, 50).unwrap()).0.abs());
        }
        assert!(at_50.windows(2).all(|w| w[1] > w[0]), "{at_50:?}");
    }
}
