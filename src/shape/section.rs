//! The exact area, perimeter and area moments of a union of discs in a
//! plane: the two-dimensional cross-sections of the thesis' accuracy checks
//! (prolate, eq. 4.16–4.25; toroid, eq. 4.30–4.34) and the slices the
//! three-dimensional union integration of [`super::union`] is built from.
//!
//! Method (exact to rounding, not a sampling): the boundary of a union of
//! discs is made of the arcs of each circle that no other disc covers. For
//! each circle the arcs another disc covers are an angular interval
//! (half-width acos((rᵢ² + d² − rⱼ²)/(2 rᵢ d)) about the direction of the
//! other centre); their complement is the exposed boundary. The perimeter is
//! the sum of the exposed arc lengths, and by Green's theorem every area
//! moment ∬ f dA is the boundary integral ∮ Q dy with ∂Q/∂x = f, taken along
//! the exposed arcs (counter-clockwise on each circle, which orients holes
//! correctly). Along an arc the integrand is a trigonometric polynomial of
//! degree at most 4, integrated by 16-point Gauss–Legendre on pieces of at
//! most π/2: exact to rounding. Unlike the thesis' closed forms (eq. 4.16–
//! 4.23 and 4.31–4.32, which assume only neighbouring spheres overlap), this
//! holds whatever overlaps whatever; for a toroid of 50 sub-spheres with
//! a/b = 2, second neighbours overlap too, and eq. 4.31 would miscount.

use crate::maths;
use glam::DVec2;
use std::f64::consts::{PI, TAU};
use std::sync::OnceLock;

/// A disc in a plane.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Disc {
    /// Centre (m).
    pub centre_m: DVec2,
    /// Radius (m).
    pub radius_m: f64,
}

/// Area moments of a plane region: ∬ 1, x, y, x², y², xy dA.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct AreaMoments {
    /// ∬ dA (m²).
    pub area_m2: f64,
    /// ∬ x dA (m³).
    pub x_m3: f64,
    /// ∬ y dA (m³).
    pub y_m3: f64,
    /// ∬ x² dA (m⁴).
    pub xx_m4: f64,
    /// ∬ y² dA (m⁴).
    pub yy_m4: f64,
    /// ∬ xy dA (m⁴).
    pub xy_m4: f64,
}

/// The union of a set of discs, measured exactly.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct DiscUnion {
    /// Area moments of the union.
    pub moments: AreaMoments,
    /// Length of the union's boundary (m).
    pub perimeter_m: f64,
    /// For each disc, the total angle of its circle on the union's boundary
    /// (rad, 0 to 2π; 0 for a disc covered by the others).
    pub exposed_rad: Vec<f64>,
}

/// Measure the union of `discs`. Discs of zero radius are ignored; of two
/// identical discs the first counts.
pub fn disc_union(discs: &[Disc]) -> DiscUnion {
    let mut out = DiscUnion {
        exposed_rad: vec![0.0; discs.len()],
        ..DiscUnion::default()
    };
    let mut covered: Vec<(f64, f64)> = Vec::new();
    for (i, di) in discs.iter().enumerate() {
        if di.radius_m <= 0.0 {
            continue;
        }
        covered.clear();
        if covered_intervals(discs, i, &mut covered) {
            continue;
        }
        let exposed = complement_in_circle(&mut covered);
        for (t0, t1) in exposed {
            let angle = t1 - t0;
            out.exposed_rad[i] += angle;
            out.perimeter_m += di.radius_m * angle;
            add_arc_moments(di, t0, t1, &mut out.moments);
        }
    }
    out
}

/// Collect into `covered` the angular intervals of disc `i`'s circle that
/// other discs cover; `true` when another disc covers the whole circle.
fn covered_intervals(discs: &[Disc], i: usize, covered: &mut Vec<(f64, f64)>) -> bool {
    let di = discs[i];
    let ri = di.radius_m;
    for (j, dj) in discs.iter().enumerate() {
        let rj = dj.radius_m;
        if j == i || rj <= 0.0 {
            continue;
        }
        let delta = dj.centre_m - di.centre_m;
        let d = delta.length();
        let scale = ri.max(rj);
        let identical = d <= 1e-14 * scale && (ri - rj).abs() <= 1e-14 * scale;
        if identical {
            if j < i {
                return true;
            }
            continue;
        }
        if d + ri <= rj {
            return true; // i inside j
        }
        if d >= ri + rj || d + rj <= ri {
            continue; // apart, or j inside i: no arc of i covered
        }
        let cos_w = ((ri * ri + d * d - rj * rj) / (2.0 * ri * d)).clamp(-1.0, 1.0);
        let w = cos_w.acos();
        let phi = maths::atan2(delta.y, delta.x);
        push_wrapped(covered, phi - w, phi + w);
    }
    false
}

/// Push the interval [t0, t1] (t1 − t0 <= 2π) mapped into [0, 2π), split
/// where it wraps.
fn push_wrapped(out: &mut Vec<(f64, f64)>, t0: f64, t1: f64) {
    let start = t0.rem_euclid(TAU);
    let end = start + (t1 - t0);
    if end <= TAU {
        out.push((start, end));
    } else {
        out.push((start, TAU));
        out.push((0.0, end - TAU));
    }
}

/// The parts of [0, 2π) not in any of `covered` (sorted in place).
fn complement_in_circle(covered: &mut [(f64, f64)]) -> Vec<(f64, f64)> {
    covered.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut exposed = Vec::new();
    let mut reach = 0.0;
    for &(s, e) in covered.iter() {
        if s > reach {
            exposed.push((reach, s));
        }
        reach = f64::max(reach, e);
    }
    if reach < TAU {
        exposed.push((reach, TAU));
    }
    exposed
}

/// 16-point Gauss–Legendre nodes and weights on [−1, 1].
fn gauss_legendre_16() -> &'static [(f64, f64); 16] {
    static RULE: OnceLock<[(f64, f64); 16]> = OnceLock::new();
    RULE.get_or_init(gauss_legendre::<16>)
}

/// N-point Gauss–Legendre rule on [−1, 1] by Newton's method on P_N.
fn gauss_legendre<const N: usize>() -> [(f64, f64); N] {
    let mut rule = [(0.0, 0.0); N];
    let n = N as f64;
    for (k, slot) in rule.iter_mut().enumerate() {
        let mut x = maths::cos(PI * (k as f64 + 0.75) / (n + 0.5));
        let mut dp = 1.0;
        for _ in 0..100 {
            let (p, d) = legendre_and_derivative(N, x);
            dp = d;
            let step = p / d;
            x -= step;
            if step.abs() < 1e-16 {
                break;
            }
        }
        let (_, d) = legendre_and_derivative(N, x);
        dp = if d != 0.0 { d } else { dp };
        *slot = (x, 2.0 / ((1.0 - x * x) * dp * dp));
    }
    rule
}

/// P_n(x) and P_n'(x) by the three-term recursion.
fn legendre_and_derivative(n: usize, x: f64) -> (f64, f64) {
    let (mut p0, mut p1) = (1.0, x);
    for k in 2..=n {
        let kf = k as f64;
        let p2 = ((2.0 * kf - 1.0) * x * p1 - (kf - 1.0) * p0) / kf;
        p0 = p1;
        p1 = p2;
    }
    let nf = n as f64;
    (p1, nf * (x * p1 - p0) / (x * x - 1.0))
}

/// Add ∮ Q dy along the arc of `disc` from angle `t0` to `t1` for each
/// moment (Q = x, x²/2, xy, x³/3, xy², x²y/2), in pieces of at most π/2.
fn add_arc_moments(disc: &Disc, t0: f64, t1: f64, m: &mut AreaMoments) {
    let rule = gauss_legendre_16();
    let pieces = ((t1 - t0) / (0.5 * PI)).ceil().max(1.0) as usize;
    let h = (t1 - t0) / pieces as f64;
    let (c, r) = (disc.centre_m, disc.radius_m);
    for p in 0..pieces {
        let mid = t0 + (p as f64 + 0.5) * h;
        for &(node, weight) in rule.iter() {
            let t = mid + 0.5 * h * node;
            let (s, co) = maths::sin_cos(t);
            let x = c.x + r * co;
            let y = c.y + r * s;
            let w = 0.5 * h * weight * r * co; // dy = r cos t dt
            m.area_m2 += w * x;
            m.x_m3 += w * 0.5 * x * x;
            m.y_m3 += w * x * y;
            m.xx_m4 += w * x * x * x / 3.0;
            m.yy_m4 += w * x * y * y;
            m.xy_m4 += w * 0.5 * x * x * y;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn disc(x: f64, y: f64, r: f64) -> Disc {
        Disc {
            centre_m: DVec2::new(x, y),
            radius_m: r,
        }
    }

    /// One off-centre disc: area πR², perimeter 2πR, the moments of a disc
    /// with the parallel-axis shift, to 1e-13 relative. Catches a wrong Q in
    /// Green's theorem or a too-short quadrature.
    #[test]
    fn single_disc_moments_are_exact() {
        let (cx, cy, r) = (0.3, -0.7, 1.3);
        let u = disc_union(&[disc(cx, cy, r)]);
        let a = PI * r * r;
        let m = u.moments;
        let close = |got: f64, want: f64| (got - want).abs() <= 1e-13 * want.abs().max(1.0);
        assert!(close(m.area_m2, a));
        assert!(close(u.perimeter_m, TAU * r));
        assert!(close(m.x_m3, a * cx) && close(m.y_m3, a * cy));
        assert!(close(m.xx_m4, a * r * r / 4.0 + a * cx * cx));
        assert!(close(m.yy_m4, a * r * r / 4.0 + a * cy * cy));
        assert!(close(m.xy_m4, a * cx * cy));
    }

    /// Two overlapping equal discs: the union area is 2πR² minus the lens
    /// 2R² acos(d/2R) − (d/2)√(4R² − d²), the perimeter the two outer arcs
    /// (1e-13 relative). Catches a covered interval of the wrong width.
    #[test]
    fn two_discs_lens() {
        let (r, d) = (1.0f64, 0.8f64);
        let u = disc_union(&[disc(0.0, 0.0, r), disc(d, 0.0, r)]);
        let lens = 2.0 * r * r * (d / (2.0 * r)).acos() - 0.5 * d * (4.0 * r * r - d * d).sqrt();
        assert!((u.moments.area_m2 - (2.0 * PI * r * r - lens)).abs() < 1e-13);
        let arc = 2.0 * (TAU - 2.0 * (d / (2.0 * r)).acos()) * r;
        assert!((u.perimeter_m - arc).abs() < 1e-13);
        assert!((u.moments.x_m3 / u.moments.area_m2 - d / 2.0).abs() < 1e-13);
    }

    /// A disc inside another, a duplicate and a zero disc add nothing
    /// (1e-13). Catches double counting of contained or identical discs.
    #[test]
    fn contained_and_duplicate_discs_add_nothing() {
        let base = disc_union(&[disc(0.0, 0.0, 2.0)]);
        let u = disc_union(&[
            disc(0.0, 0.0, 2.0),
            disc(0.5, 0.2, 1.0),
            disc(0.0, 0.0, 2.0),
            disc(1.0, 1.0, 0.0),
        ]);
        assert!((u.moments.area_m2 - base.moments.area_m2).abs() < 1e-13);
        assert!((u.perimeter_m - base.perimeter_m).abs() < 1e-13);
        assert_eq!(u.exposed_rad[1], 0.0);
        assert_eq!(u.exposed_rad[2], 0.0);
    }

    /// A ring of discs whose second neighbours do not overlap: the union
    /// area and perimeter equal the thesis' eq. 4.31–4.32 (1e-12 relative),
    /// and the ring's hole is not counted. Catches a hole's boundary taken
    /// with the wrong orientation.
    #[test]
    fn ring_matches_eq_4_31_when_only_neighbours_overlap() {
        let (a, b, n) = (3.0f64, 1.0f64, 12usize);
        let dphi = TAU / n as f64;
        let discs: Vec<Disc> = (0..n)
            .map(|i| {
                let phi = dphi * i as f64;
                disc(a * phi.cos(), a * phi.sin(), b)
            })
            .collect();
        let d = 2.0 * a * (dphi / 2.0).sin(); // eq. 4.30
        assert!(
            2.0 * a * dphi.sin() > 2.0 * b,
            "second neighbours must be apart"
        );
        let nf = n as f64;
        let area = nf
            * (PI * b * b - 2.0 * b * b * (d / (2.0 * b)).acos()
                + d * (b * b - d * d / 4.0).sqrt());
        let perim_431 = 2.0
            * nf
            * b
            * (PI - 2.0 * (2.0 * ((b - d / 2.0) * (b + d / 2.0)).sqrt() / (2.0 * b)).asin());
        let u = disc_union(&discs);
        assert!(
            (u.moments.area_m2 / area - 1.0).abs() < 1e-12,
            "{} vs {area}",
            u.moments.area_m2
        );
        assert!((u.perimeter_m / perim_431 - 1.0).abs() < 1e-12);
        assert!(u.moments.x_m3.abs() < 1e-12 && u.moments.y_m3.abs() < 1e-12);
    }
}
