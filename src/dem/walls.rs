//! Rigid walls: the closed cylindrical enclosure, or flat plates.
//!
//! Contact geometry follows thesis Section 3.3 for analytic surfaces: the overlap is
//! the radius minus the distance from the centre to the surface (eq. 3.12) and the
//! normal points from the centre to the closest surface point (eq. 3.14). Walls are
//! flat for the contact law (zero curvature, `R* = R`), as in the thesis; the
//! concave side wall of a 40 mm cylinder is about 8 times the particle radius, so
//! this slightly underestimates its contact stiffness.
//!
//! All walls of a scene move together as one rigid body along `axis` (the shaker
//! axis), with displacement `u(t)`. The enclosure's own axis is the z axis of the
//! simulation frame; gravity sets the orientation (vertical: along -z, horizontal:
//! perpendicular to z). A wall can also move on its own on top of that
//! ([`WallMotion`]: the upper ring and loading table of the shear box of
//! thesis Fig. 8.15), prescribed step by step; its work on the particles is
//! booked as the common motion's is.

use glam::DVec3;

/// One wall surface, in the wall body's rest position.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum WallShape {
    /// A plane through `origin` whose unit `normal` points into the free space.
    Plane { origin: DVec3, normal: DVec3 },
    /// The inside of a cylinder of `radius_m` around the z axis.
    CylinderInside { radius_m: f64 },
    /// The inside of a ring: a cylinder of `radius_m` around the z axis from
    /// `z_min_m` to `z_max_m`, open at both ends. Beyond its ends a particle
    /// meets its rim, a circle, at the point of the rim nearest its centre
    /// (a sphere poking into the gap between two rings); the rim is taken as
    /// flat for the contact law, as every wall is (eq. 3.12, 3.14).
    Ring {
        radius_m: f64,
        z_min_m: f64,
        z_max_m: f64,
    },
}

impl WallShape {
    /// Signed distance (m) from `p` to the surface, positive on the free side, and
    /// the unit normal from `p` towards the surface. `offset` is the displacement of
    /// the wall body.
    #[inline]
    pub fn distance_and_normal(&self, p: DVec3, offset: DVec3) -> (f64, DVec3) {
        (self.distance_m(p, offset), self.normal_from(p, offset))
    }

    /// The signed distance of [`Self::distance_and_normal`] alone: all a step
    /// needs of the many particles far from a wall.
    #[inline]
    pub fn distance_m(&self, p: DVec3, offset: DVec3) -> f64 {
        match *self {
            WallShape::Plane { origin, normal } => (p - origin - offset).dot(normal),
            // On the axis (ρ = 0) this is the radius, as it should be.
            WallShape::CylinderInside { radius_m } => radius_m - rho_m(p - offset),
            WallShape::Ring {
                radius_m,
                z_min_m,
                z_max_m,
            } => {
                let q = p - offset;
                let across = radius_m - rho_m(q);
                let beyond = q.z - q.z.clamp(z_min_m, z_max_m);
                if beyond == 0.0 {
                    across
                } else {
                    (across * across + beyond * beyond).sqrt()
                }
            }
        }
    }

    /// The normal of [`Self::distance_and_normal`] alone: the unit vector from
    /// `p` towards the surface (on the cylinder's axis, any radial direction:
    /// +x).
    #[inline]
    pub fn normal_from(&self, p: DVec3, offset: DVec3) -> DVec3 {
        let radial = |q: DVec3| {
            let rho = rho_m(q);
            if rho > 0.0 {
                DVec3::new(q.x / rho, q.y / rho, 0.0)
            } else {
                DVec3::X
            }
        };
        match *self {
            WallShape::Plane { normal, .. } => -normal,
            WallShape::CylinderInside { .. } => radial(p - offset),
            WallShape::Ring {
                radius_m,
                z_min_m,
                z_max_m,
            } => {
                let q = p - offset;
                let z_rim = q.z.clamp(z_min_m, z_max_m);
                if z_rim == q.z {
                    return radial(q);
                }
                let rim = radial(q) * radius_m + DVec3::Z * z_rim;
                (rim - q).normalize_or(radial(q))
            }
        }
    }
}

/// The distance of `q` from the z axis (m): what the cylinder, the ring and
/// their normals all start from, one expression so that the distance and
/// the normal of a contact read the same bits.
#[inline(always)]
fn rho_m(q: DVec3) -> f64 {
    (q.x * q.x + q.y * q.y).sqrt()
}

/// A wall's own rigid motion on top of the common one, prescribed step by
/// step ([`Walls::prescribe`]): where it is, how fast it moved over the last
/// step, and where it is to be at the end of the next.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct WallMotion {
    /// Its own displacement (m).
    pub offset_m: DVec3,
    /// Its own mean velocity over the last step (m/s).
    pub velocity_mps: DVec3,
    /// Its own displacement over the last step (m).
    pub stroke_m: DVec3,
    /// Where the next step is to leave it (m).
    target_m: DVec3,
}

/// The walls of a scene and their common rigid motion.
#[derive(Debug, Clone, PartialEq)]
pub struct Walls {
    pub shapes: Vec<WallShape>,
    /// Human-readable names, same order as `shapes` ("side", "bottom", ...).
    pub names: Vec<&'static str>,
    /// Unit direction of the rigid motion.
    pub axis: DVec3,
    /// Current displacement along `axis` (m).
    pub displacement_m: f64,
    /// Mean velocity along `axis` over the last step (m/s).
    pub velocity_mps: f64,
    /// Each wall's own motion on top of the common one, in the order of
    /// `shapes`; empty while no wall moves on its own (the damper).
    pub own: Vec<WallMotion>,
}

impl Walls {
    /// No walls at all (free particles).
    pub fn none() -> Self {
        Walls {
            shapes: Vec::new(),
            names: Vec::new(),
            axis: DVec3::Z,
            displacement_m: 0.0,
            velocity_mps: 0.0,
            own: Vec::new(),
        }
    }

    /// A closed cylinder around the z axis: inner radius, floor at z = 0 and lid
    /// at z = `length_m`, moving along z.
    pub fn closed_cylinder(radius_m: f64, length_m: f64) -> Self {
        Walls {
            shapes: vec![
                WallShape::CylinderInside { radius_m },
                WallShape::Plane {
                    origin: DVec3::ZERO,
                    normal: DVec3::Z,
                },
                WallShape::Plane {
                    origin: DVec3::new(0.0, 0.0, length_m),
                    normal: -DVec3::Z,
                },
            ],
            names: vec!["side wall", "bottom cap", "lid"],
            axis: DVec3::Z,
            displacement_m: 0.0,
            velocity_mps: 0.0,
            own: Vec::new(),
        }
    }

    /// Walls of the given shapes and names, at rest, the common motion along z.
    pub fn of(shapes: Vec<WallShape>, names: Vec<&'static str>) -> Self {
        assert_eq!(shapes.len(), names.len(), "one name per wall");
        Walls {
            shapes,
            names,
            ..Walls::none()
        }
    }

    /// One infinite flat plate through the origin with normal +z, moving along z.
    pub fn plate() -> Self {
        Walls {
            shapes: vec![WallShape::Plane {
                origin: DVec3::ZERO,
                normal: DVec3::Z,
            }],
            names: vec!["plate"],
            axis: DVec3::Z,
            displacement_m: 0.0,
            velocity_mps: 0.0,
            own: Vec::new(),
        }
    }

    /// Number of wall surfaces.
    pub fn len(&self) -> usize {
        self.shapes.len()
    }

    /// True when there are no walls.
    pub fn is_empty(&self) -> bool {
        self.shapes.is_empty()
    }

    /// Offset vector of the wall body (m).
    pub fn offset(&self) -> DVec3 {
        self.axis * self.displacement_m
    }

    /// Velocity vector of the wall body (m/s).
    pub fn velocity(&self) -> DVec3 {
        self.axis * self.velocity_mps
    }

    /// Offset of wall `w` (m): the common one and its own.
    #[inline]
    pub fn offset_of(&self, w: usize) -> DVec3 {
        match self.own.get(w) {
            Some(own) => self.offset() + own.offset_m,
            None => self.offset(),
        }
    }

    /// Velocity of wall `w` (m/s): the common one and its own.
    #[inline]
    pub fn velocity_of(&self, w: usize) -> DVec3 {
        match self.own.get(w) {
            Some(own) => self.velocity() + own.velocity_mps,
            None => self.velocity(),
        }
    }

    /// Asks wall `w` to end the next step at its own displacement
    /// `offset_m` (on top of the common one); the step moves it there at
    /// the mean speed that takes it there.
    pub fn prescribe(&mut self, w: usize, offset_m: DVec3) {
        if self.own.len() < self.shapes.len() {
            self.own.resize(self.shapes.len(), WallMotion::default());
        }
        self.own[w].target_m = offset_m;
    }

    /// Moves every wall that moves on its own to where it was prescribed to
    /// be at the end of a step of `dt_s`.
    pub fn move_own(&mut self, dt_s: f64) {
        for own in &mut self.own {
            own.stroke_m = own.target_m - own.offset_m;
            own.offset_m = own.target_m;
            own.velocity_mps = own.stroke_m / dt_s;
        }
    }

    /// Moves the plane `index` (e.g. the lid) so that it passes through `origin`.
    pub fn move_plane(&mut self, index: usize, new_origin: DVec3) {
        if let Some(WallShape::Plane { origin, .. }) = self.shapes.get_mut(index) {
            *origin = new_origin;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cylinder_geometry() {
        let walls = Walls::closed_cylinder(0.02, 0.04);
        let p = DVec3::new(0.018, 0.0, 0.001);
        let (d_side, n_side) = walls.shapes[0].distance_and_normal(p, DVec3::ZERO);
        assert!((d_side - 0.002).abs() < 1e-15);
        assert_eq!(n_side, DVec3::X);
        let (d_floor, n_floor) = walls.shapes[1].distance_and_normal(p, DVec3::ZERO);
        assert!((d_floor - 0.001).abs() < 1e-15);
        assert_eq!(n_floor, -DVec3::Z);
        let (d_lid, n_lid) = walls.shapes[2].distance_and_normal(p, DVec3::ZERO);
        assert!((d_lid - 0.039).abs() < 1e-15);
        assert_eq!(n_lid, DVec3::Z);
        // The whole body moved up by 1 mm: floor distance shrinks.
        let (d_floor, _) = walls.shapes[1].distance_and_normal(p, DVec3::Z * 0.001);
        assert!(d_floor.abs() < 1e-15);
    }

    #[test]
    fn ring_is_a_cylinder_between_its_ends_and_a_circle_beyond() {
        let ring = WallShape::Ring {
            radius_m: 0.02,
            z_min_m: 0.0,
            z_max_m: 0.01,
        };
        // Between its ends: the cylinder's distance and normal.
        let p = DVec3::new(0.015, 0.0, 0.005);
        let (d, n) = ring.distance_and_normal(p, DVec3::ZERO);
        assert!((d - 0.005).abs() < 1e-15);
        assert_eq!(n, DVec3::X);
        // 3 mm below it, 4 mm in from the wall: 5 mm to the rim, towards it.
        let p = DVec3::new(0.0, 0.016, -0.003);
        let (d, n) = ring.distance_and_normal(p, DVec3::ZERO);
        assert!((d - 0.005).abs() < 1e-15, "{d}");
        assert!((n - DVec3::new(0.0, 0.8, 0.6)).length() < 1e-12, "{n}");
        // Moved 1 mm along x, the ring is 1 mm nearer a point on +x.
        let p = DVec3::new(0.015, 0.0, 0.005);
        let d = ring.distance_m(p, DVec3::X * 0.001);
        assert!((d - 0.006).abs() < 1e-15, "{d}");
        let d = ring.distance_m(p, -DVec3::X * 0.001);
        assert!((d - 0.004).abs() < 1e-15, "{d}");
    }

    #[test]
    fn a_wall_moves_on_its_own_on_top_of_the_common_motion() {
        let mut walls = Walls::closed_cylinder(0.02, 0.04);
        walls.displacement_m = 0.001;
        assert_eq!(walls.offset_of(2), DVec3::Z * 0.001);
        walls.prescribe(2, DVec3::new(0.0, 0.0, -0.002));
        walls.move_own(1e-3);
        assert_eq!(walls.offset_of(2), DVec3::new(0.0, 0.0, -0.001));
        assert_eq!(walls.own[2].velocity_mps, DVec3::new(0.0, 0.0, -2.0));
        assert_eq!(walls.offset_of(1), DVec3::Z * 0.001);
        walls.move_own(1e-3);
        assert_eq!(walls.own[2].velocity_mps, DVec3::ZERO);
    }
}
