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
//! perpendicular to z).

use glam::DVec3;

/// One wall surface, in the wall body's rest position.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum WallShape {
    /// A plane through `origin` whose unit `normal` points into the free space.
    Plane { origin: DVec3, normal: DVec3 },
    /// The inside of a cylinder of `radius_m` around the z axis.
    CylinderInside { radius_m: f64 },
}

impl WallShape {
    /// Signed distance (m) from `p` to the surface, positive on the free side, and
    /// the unit normal from `p` towards the surface. `offset` is the displacement of
    /// the wall body.
    #[inline]
    pub fn distance_and_normal(&self, p: DVec3, offset: DVec3) -> (f64, DVec3) {
        (self.distance_m(p, offset), self.normal_from(p))
    }

    /// The signed distance of [`Self::distance_and_normal`] alone: all a step
    /// needs of the many particles far from a wall.
    #[inline]
    pub fn distance_m(&self, p: DVec3, offset: DVec3) -> f64 {
        match *self {
            WallShape::Plane { origin, normal } => (p - origin - offset).dot(normal),
            // On the axis (ρ = 0) this is the radius, as it should be.
            WallShape::CylinderInside { radius_m } => radius_m - (p.x * p.x + p.y * p.y).sqrt(),
        }
    }

    /// The normal of [`Self::distance_and_normal`] alone: the unit vector from
    /// `p` towards the surface (on the cylinder's axis, any radial direction:
    /// +x).
    #[inline]
    pub fn normal_from(&self, p: DVec3) -> DVec3 {
        match *self {
            WallShape::Plane { normal, .. } => -normal,
            WallShape::CylinderInside { .. } => {
                let rho = (p.x * p.x + p.y * p.y).sqrt();
                if rho > 0.0 {
                    DVec3::new(p.x / rho, p.y / rho, 0.0)
                } else {
                    DVec3::X
                }
            }
        }
    }
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
}
