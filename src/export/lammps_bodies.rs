//! The rigid bodies of a LAMMPS deck (`vlab export lammps` of a scene of
//! prolates, oblates, toroids or clumps): each multi-sphere body (thesis
//! Chapter 4, Section 4.2) becomes one molecule of atoms, its sub-spheres,
//! integrated as one rigid body by LAMMPS' `fix rigid/small`.
//!
//! LAMMPS, left to itself, would sum its atoms' masses and inertias, which
//! counts the overlaps of the sub-spheres twice (a prolate of 1.5 of 51
//! sub-spheres would weigh several times its union). The deck gives each
//! body vlab's own instead (`fix rigid/small ... infile bodies.txt`): the
//! mass of the union of its sub-spheres (eq. 4.1), its centre of mass
//! (eq. 4.2) and its inertia tensor about it (eq. 4.5), in the space frame
//! at the body's settled orientation (`R diag(I₁, I₂, I₃) Rᵀ`, which LAMMPS
//! diagonalises again), with the body's velocity and angular momentum.
//! Gravity acts on that mass at that centre (`fix rigid/small ... gravity`,
//! with `fix gravity` on the free spheres only), not on the atoms' summed
//! masses. Contacts between sub-spheres of one body are excluded from the
//! neighbour list (`neigh_modify exclude molecule/intra`), as vlab never
//! pairs them; LAMMPS' granular pair and wall styles read the body's mass
//! for a sub-sphere's contact damping (eq. 5.32's m*), as vlab does.
//!
//! SI units throughout: kg, m, kg m², m/s, kg m²/s.

use std::fmt::Write as _;

use glam::{DMat3, DVec3};

use crate::dem::Particles;
use crate::dem::clumps::NOT_IN_CLUMP;

/// One rigid body as `bodies.txt` gives it to LAMMPS.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BodyRow {
    /// LAMMPS molecule ID: vlab's body number + 1.
    pub molecule: u32,
    /// Mass of the union of the sub-spheres (kg, eq. 4.1).
    pub mass_kg: f64,
    /// Centre of mass (m).
    pub centre_m: DVec3,
    /// Inertia tensor about the centre of mass, space frame (kg m²):
    /// xx, yy, zz, xy, xz, yz.
    pub inertia_kgm2: [f64; 6],
    /// Velocity of the centre of mass (m/s).
    pub velocity_mps: DVec3,
    /// Angular momentum about the centre of mass, space frame (kg m²/s).
    pub angular_momentum_kgm2ps: DVec3,
}

/// The bodies of a settled bed, in the order of their molecule IDs, and
/// each atom's molecule.
#[derive(Debug, Clone, PartialEq)]
pub struct RigidBodies {
    pub rows: Vec<BodyRow>,
    /// Per atom (id order): its molecule, 0 for a free sphere.
    pub molecule: Vec<u32>,
    /// Free spheres (molecule 0).
    pub n_free: usize,
    /// The largest sub-sphere radius (m).
    pub max_sub_radius_m: f64,
    /// The largest distance from a body's centre of mass to one of its
    /// sub-spheres' surfaces (m).
    pub reach_m: f64,
}

/// The space-frame inertia tensor `R diag(principal) Rᵀ` of a body whose
/// orientation (body to space) is `rotation`: xx, yy, zz, xy, xz, yz.
pub fn space_inertia_kgm2(rotation: glam::DQuat, principal_kgm2: DVec3) -> [f64; 6] {
    let r = DMat3::from_quat(rotation);
    let t = r * DMat3::from_diagonal(principal_kgm2) * r.transpose();
    [
        t.x_axis.x, t.y_axis.y, t.z_axis.z, t.y_axis.x, t.z_axis.x, t.z_axis.y,
    ]
}

impl RigidBodies {
    /// The bodies of `particles` (in id order, [`Particles::by_id`]); `None`
    /// when there are none (a bed of spheres).
    pub fn of(particles: &Particles) -> Option<Self> {
        let clumps = &particles.clumps;
        if clumps.is_empty() {
            return None;
        }
        let rows = (0..clumps.len())
            .map(|b| BodyRow {
                molecule: b as u32 + 1,
                mass_kg: clumps.mass[b],
                centre_m: clumps.position[b],
                inertia_kgm2: space_inertia_kgm2(clumps.orientation[b], clumps.inertia[b]),
                velocity_mps: clumps.velocity[b],
                angular_momentum_kgm2ps: clumps.angular_momentum[b],
            })
            .collect();
        let molecule: Vec<u32> = particles
            .clump
            .iter()
            .map(|&b| if b == NOT_IN_CLUMP { 0 } else { b + 1 })
            .collect();
        let in_body = |k: &usize| particles.in_clump(*k);
        let max_sub_radius_m = (0..particles.len())
            .filter(in_body)
            .map(|k| particles.radius[k])
            .fold(0.0, f64::max);
        let reach_m = (0..particles.len())
            .filter(in_body)
            .map(|k| {
                let b = particles.clump[k] as usize;
                (particles.position[k] - clumps.position[b]).length() + particles.radius[k]
            })
            .fold(0.0, f64::max);
        Some(RigidBodies {
            n_free: molecule.iter().filter(|&&m| m == 0).count(),
            rows,
            molecule,
            max_sub_radius_m,
            reach_m,
        })
    }

    /// The `Molecules` section of `packing.data` (read by `read_data ... fix
    /// mol_ids NULL Molecules`): each atom's molecule.
    pub fn molecules_section(&self) -> String {
        let mut s = String::from("\nMolecules\n\n");
        for (k, m) in self.molecule.iter().enumerate() {
            let _ = writeln!(s, "{} {m}", k + 1);
        }
        s
    }

    /// `bodies.txt`, the `infile` of `fix rigid/small`: per body its
    /// molecule, mass, centre, space-frame inertia, velocity, angular
    /// momentum and image flags (0: the box is not periodic), each number as
    /// Rust prints an f64 exactly (shortest round trip).
    pub fn infile(&self, scene_name: &str, version: &str) -> String {
        let mut s = String::new();
        let _ = writeln!(
            s,
            "# Rigid bodies of the {scene_name} damper for fix rigid/small (vlab {version}): vlab's union mass \
             (thesis eq. 4.1), centre of mass (eq. 4.2) and inertia (eq. 4.5), SI units."
        );
        line(
            &mut s,
            "# molecule mass_kg xcm ycm zcm ixx iyy izz ixy ixz iyz vxcm vycm vzcm lx ly lz ixcm iycm izcm",
        );
        let _ = writeln!(s, "{}", self.rows.len());
        for r in &self.rows {
            let [xx, yy, zz, xy, xz, yz] = r.inertia_kgm2;
            let (c, v, l) = (r.centre_m, r.velocity_mps, r.angular_momentum_kgm2ps);
            let _ = writeln!(
                s,
                "{} {:?} {:?} {:?} {:?} {xx:?} {yy:?} {zz:?} {xy:?} {xz:?} {yz:?} {:?} {:?} {:?} {:?} {:?} {:?} 0 0 0",
                r.molecule, r.mass_kg, c.x, c.y, c.z, v.x, v.y, v.z, l.x, l.y, l.z
            );
        }
        s
    }
}

fn line(s: &mut String, text: &str) {
    s.push_str(text);
    s.push('\n');
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DQuat;

    #[test]
    fn space_inertia_is_the_principal_moments_turned() {
        // A quarter turn about z swaps the x and y moments.
        let q = DQuat::from_rotation_z(std::f64::consts::FRAC_PI_2);
        let t = space_inertia_kgm2(q, DVec3::new(1.0, 2.0, 3.0));
        for (got, want) in t.iter().zip([2.0, 1.0, 3.0, 0.0, 0.0, 0.0]) {
            assert!((got - want).abs() < 1e-12, "{t:?}");
        }
        // Any turn keeps the trace and gives a symmetric tensor whose
        // quadratic form along a body axis is that axis' moment.
        let q = DQuat::from_euler(glam::EulerRot::ZYX, 0.3, -1.1, 2.0);
        let t = space_inertia_kgm2(q, DVec3::new(1.0, 2.0, 3.0));
        assert!((t[0] + t[1] + t[2] - 6.0).abs() < 1e-12);
        let m = DMat3::from_cols(
            DVec3::new(t[0], t[3], t[4]),
            DVec3::new(t[3], t[1], t[5]),
            DVec3::new(t[4], t[5], t[2]),
        );
        let axis = q * DVec3::Y;
        assert!((axis.dot(m * axis) - 2.0).abs() < 1e-12);
    }
}
