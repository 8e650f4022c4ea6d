//! The shortest collision a rigid body makes, measured: what sets the time
//! step of a bed of bodies.
//!
//! The time step of a bed of spheres resolves the Hertz contact of one
//! pair (twice eq. 5.10). A body of sub-spheres (thesis Section 4.2) meets
//! another body, or a wall, at several sub-sphere pairs at once where
//! their surfaces lie alike: two prolates of aspect ratio 1.5 side by side
//! touch at 7 to 211 pairs as they press together. With each pair a whole
//! contact of its own (the thesis' model, `contact.multi_point =
//! "independent"`) these are springs in parallel, and the collision is
//! shorter than any one pair's: 19.5 us side by side at 1 m/s, where one
//! pair of their sub-spheres would take 46 us. Unlike one pair's, the
//! duration of such a collision has no closed form: it depends on how the
//! sub-spheres lie.
//!
//! So it is measured. Two bodies in the same orientation meet along each of
//! their principal axes, and one body meets the floor and the side wall of
//! the enclosure with each of its principal axes along the wall's normal (the
//! six ways a body's axes can lie along the cylinder's); without gravity or
//! friction, the scene's contact laws otherwise. A collision lasts from the
//! first step that changes the body's velocity to the last; the shortest of
//! each kind is returned.

use glam::{DQuat, DVec3};

use super::clumps::ClumpTemplate;
use super::contact::ContactLaw;
use super::particles::Particles;
use super::walls::Walls;
use super::world::{Numerics, World};

/// What a body meets, and how: the body, the two laws, the enclosure and
/// the approach.
#[derive(Debug, Clone, Copy)]
pub struct BodyProbe<'a> {
    pub template: &'a ClumpTemplate,
    /// Body-body law.
    pub pp_law: ContactLaw,
    /// Body-wall law.
    pub pw_law: ContactLaw,
    /// The closed cylinder of the walls: inner radius and length (m).
    pub cylinder_m: (f64, f64),
    /// Relative speed of the meeting (m/s).
    pub speed_mps: f64,
    /// Step of the measurement (s): a small fraction of the collisions.
    pub dt_s: f64,
    /// Steps a collision may last before the measurement gives it up.
    pub max_steps: u64,
}

/// The shortest collisions measured (s); `None` where no meeting of the
/// kind began and ended within the steps allowed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BodyCollisions {
    /// Two bodies in the same orientation, along one of their principal axes.
    pub pair_s: Option<f64>,
    /// A body against the floor or the side wall.
    pub wall_s: Option<f64>,
}

impl BodyCollisions {
    /// The shorter of the two, if either was measured.
    pub fn shortest_s(&self) -> Option<f64> {
        match (self.pair_s, self.wall_s) {
            (Some(a), Some(b)) => Some(a.min(b)),
            (a, b) => a.or(b),
        }
    }
}

/// Gap left between the surfaces at the start, as a fraction of the
/// distance the meeting closes in one step: they touch in the first steps.
const START_GAP_STEPS: f64 = 2.0;

/// Measures the collisions of `probe` (see the module docs).
pub fn shortest_body_collisions(probe: &BodyProbe) -> BodyCollisions {
    let t = probe.template;
    let gap_m = START_GAP_STEPS * probe.speed_mps * probe.dt_s;
    let pair_s = [DVec3::X, DVec3::Y, DVec3::Z]
        .into_iter()
        .filter_map(|axis| {
            let reach_m = t.bounding_radius_m();
            let walls = Walls::closed_cylinder(8.0 * reach_m, 16.0 * reach_m);
            let centre = DVec3::new(0.0, 0.0, 8.0 * reach_m);
            let half_m = 0.5 * (touching_distance_m(t, axis) + gap_m);
            let v = 0.5 * probe.speed_mps;
            let mut p = Particles::default();
            p.push_clump(
                t,
                (centre - axis * half_m, DQuat::IDENTITY),
                (axis * v, DVec3::ZERO),
            );
            p.push_clump(
                t,
                (centre + axis * half_m, DQuat::IDENTITY),
                (-axis * v, DVec3::ZERO),
            );
            collision_s(probe, p, walls)
        })
        .reduce(f64::min);
    let (radius_m, length_m) = probe.cylinder_m;
    let wall_s = axis_permutations()
        .into_iter()
        .flat_map(|q| {
            let subs: Vec<(DVec3, f64)> = t
                .offsets_m
                .iter()
                .zip(&t.radii_m)
                .map(|(o, r)| (q * *o, *r))
                .collect();
            // On the floor, on the axis.
            let lowest = subs
                .iter()
                .map(|(o, r)| o.z - r)
                .fold(f64::INFINITY, f64::min);
            let floor = (DVec3::new(0.0, 0.0, gap_m - lowest), -DVec3::Z);
            // At the side wall, half-way up: as far out along x as every
            // sub-sphere fits inside the radius.
            let out = subs
                .iter()
                .map(|(o, r)| ((radius_m - r).powi(2) - o.y * o.y).max(0.0).sqrt() - o.x)
                .fold(f64::INFINITY, f64::min);
            let side = (DVec3::new(out - gap_m, 0.0, 0.5 * length_m), DVec3::X);
            [floor, side].map(|(x, towards)| {
                let mut p = Particles::default();
                p.push_clump(t, (x, q), (towards * probe.speed_mps, DVec3::ZERO));
                collision_s(probe, p, Walls::closed_cylinder(radius_m, length_m))
            })
        })
        .flatten()
        .reduce(f64::min);
    BodyCollisions { pair_s, wall_s }
}

/// Distance (m) between the centres of two bodies of `t` in the same
/// orientation, along `axis`, at which their surfaces first touch: the
/// largest `D` with `|D axis + o_i - o_j| = r_i + r_j` for some pair of
/// sub-spheres.
pub fn touching_distance_m(t: &ClumpTemplate, axis: DVec3) -> f64 {
    let mut farthest: f64 = 0.0;
    for (oi, ri) in t.offsets_m.iter().zip(&t.radii_m) {
        for (oj, rj) in t.offsets_m.iter().zip(&t.radii_m) {
            let d = *oi - *oj;
            let along = d.dot(axis);
            let across2 = d.length_squared() - along * along;
            let reach2 = (ri + rj) * (ri + rj) - across2;
            if reach2 >= 0.0 {
                farthest = farthest.max(-along + reach2.sqrt());
            }
        }
    }
    farthest
}

/// The six rotations that lay a body's principal axes along the world's
/// axes in each order: the identity, a quarter turn about each axis, and a
/// third of a turn either way about the diagonal.
fn axis_permutations() -> [DQuat; 6] {
    let quarter = std::f64::consts::FRAC_PI_2;
    let third = 2.0 * std::f64::consts::FRAC_PI_3;
    let diagonal = DVec3::ONE.normalize();
    [
        DQuat::IDENTITY,
        DQuat::from_rotation_x(quarter),
        DQuat::from_rotation_y(quarter),
        DQuat::from_rotation_z(quarter),
        DQuat::from_axis_angle(diagonal, third),
        DQuat::from_axis_angle(diagonal, -third),
    ]
}

/// Steps the world of `p` in `walls` until body 0 has met something and
/// left it; the time its velocity changed (s), or `None`.
fn collision_s(probe: &BodyProbe, p: Particles, walls: Walls) -> Option<f64> {
    let numerics = Numerics {
        skin_ratio: 0.05,
        // A measurement of two bodies: no checks of a run, one thread.
        max_overlap_ratio: f64::INFINITY,
        parallel_min_pairs: usize::MAX,
        min_steps_per_collision: 0.0,
        energy_check_steps: u64::MAX,
        ..Numerics::with_dt(probe.dt_s)
    };
    let mut w = World::new(
        p,
        walls,
        probe.pp_law.without_friction(),
        probe.pw_law.without_friction(),
        DVec3::ZERO,
        numerics,
    )
    .ok()?;
    let mut before = w.particles.clumps.velocity[0];
    let mut touched: Option<(u64, u64)> = None;
    for k in 0..probe.max_steps {
        w.step(0.0).ok()?;
        let now = w.particles.clumps.velocity[0];
        if now != before {
            touched = Some(touched.map_or((k, k), |(first, _)| (first, k)));
        } else if let Some((first, last)) = touched {
            return Some((last - first + 1) as f64 * probe.dt_s);
        }
        before = now;
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dem::hertz_theory::contact_duration_s;
    use crate::dem::material::{Material, effective_youngs_pa};
    use crate::dem::restitution::RestitutionMode;

    const R: f64 = 0.0025;

    fn elastic(a: &Material, b: &Material) -> ContactLaw {
        ContactLaw::new(a, b, 1.0, 0.0, RestitutionMode::Exact)
    }

    /// A body of one sphere meets as a sphere does: elastic (e = 1), its
    /// pair collision and its floor collision last the Hertz duration
    /// (twice eq. 5.10) with m* = m/2, R* = R/2 and with m, R, within 1 %
    /// (the step is 1/400 of it; the side wall is curved and holds the
    /// sphere longer, so the floor is the shortest).
    #[test]
    fn a_body_of_one_sphere_meets_as_hertz_says() {
        let acrylic = Material::ACRYLIC;
        let steel = Material::STEEL;
        let body = ClumpTemplate::sphere(R, acrylic.density_kgm3);
        let m = body.mass_kg;
        let v = 1.0;
        let pair = contact_duration_s(0.5 * m, effective_youngs_pa(&acrylic, &acrylic), 0.5 * R, v);
        let wall = contact_duration_s(m, effective_youngs_pa(&acrylic, &steel), R, v);
        let probe = BodyProbe {
            template: &body,
            pp_law: elastic(&acrylic, &acrylic),
            pw_law: elastic(&acrylic, &steel),
            cylinder_m: (0.02, 0.05),
            speed_mps: v,
            dt_s: wall.min(pair) / 400.0,
            max_steps: 10_000,
        };
        let got = shortest_body_collisions(&probe);
        let (p, w) = (got.pair_s.expect("pair"), got.wall_s.expect("wall"));
        assert!((p / pair - 1.0).abs() < 0.01, "pair {p} s, Hertz {pair} s");
        assert!((w / wall - 1.0).abs() < 0.01, "wall {w} s, Hertz {wall} s");
        assert_eq!(got.shortest_s(), Some(p.min(w)));
    }

    /// Two spheres in a body along x touch a copy of it first where their
    /// outer surfaces meet (2 r + 2 x), and beside it (along y) where the
    /// spheres meet side by side (2 r).
    #[test]
    fn bodies_touch_where_their_outer_spheres_meet() {
        let dumbbell = ClumpTemplate {
            offsets_m: vec![DVec3::new(-1e-3, 0.0, 0.0), DVec3::new(1e-3, 0.0, 0.0)],
            radii_m: vec![R, R],
            mass_kg: 1e-4,
            inertia_kgm2: DVec3::ONE * 1e-10,
        };
        let along = touching_distance_m(&dumbbell, DVec3::X);
        let beside = touching_distance_m(&dumbbell, DVec3::Y);
        assert!((along - (2.0 * R + 2e-3)).abs() < 1e-15, "{along}");
        assert!((beside - 2.0 * R).abs() < 1e-15, "{beside}");
    }
}
