//! Rigid multi-sphere particles ("clumps"): bodies made of overlapping
//! sub-spheres rigidly joined, the non-spherical particles of Terzioglu's
//! thesis, Chapter 4 (Section 4.2, eq. 4.1–4.7).
//!
//! The sub-spheres are ordinary particles of [`super::Particles`]: the cell lists,
//! the pair list and every contact kernel see spheres, as the multi-sphere
//! method intends ("the kinematics and contact detection ... are also valid
//! for the multi-sphere particles", Section 4.2). Two sub-spheres of one
//! body never form a pair. Each contact between two bodies is a pair of
//! sub-spheres with its own tangential history, so two bodies can touch at
//! several points at once, each with its own history.
//!
//! What is a body's lives here: its centre of mass, velocity, orientation
//! (a unit quaternion, body to space) and angular momentum in the space
//! frame, its mass and principal moments of inertia, and where its
//! sub-spheres sit in the body frame. The resultant force (eq. 4.4) is the
//! body's weight plus every contact force on its sub-spheres; the resultant
//! moment (eq. 4.6) is the moment of those forces about the centre of mass,
//! with lever arms to the contact points (eq. 4.7): a sub-sphere's own
//! contact torque (its arm `(R − δ/2) n`) plus `(r_i − r_MS) × F_i`.
//! Rotation follows Euler's equations with the gyroscopic term
//! ([`super::rigid_rotation`]).
//!
//! **Mass in the contact law.** A sub-sphere's contact reads the mass of its
//! whole body (as LAMMPS does for particles of a rigid body): the
//! restitution damping of a contact between two bodies is then set by the
//! bodies' masses, as it is between two spheres. A sub-sphere's own inverse
//! mass and inertia are zero: the sphere integrator does not move it; the
//! body does (the step's `clump_motion` stage).
//!
//! **Mass and inertia** come with the body ([`ClumpTemplate`]): computed
//! from the union of the sub-spheres (eq. 4.1, 4.5), not by summing
//! overlapping spheres, which counts the overlaps twice (see
//! the `shape` module).

use glam::{DQuat, DVec3};

use super::rigid_rotation;

/// The clump of a particle that belongs to none (a free sphere).
pub const NOT_IN_CLUMP: u32 = u32::MAX;

/// A rigid body as the DEM needs it: its sub-spheres in its principal frame
/// (centred on its centre of mass, axes along its principal axes), its mass
/// and its principal moments of inertia.
#[derive(Debug, Clone, PartialEq)]
pub struct ClumpTemplate {
    /// Sub-sphere centres in the principal frame (m).
    pub offsets_m: Vec<DVec3>,
    /// Sub-sphere radii (m).
    pub radii_m: Vec<f64>,
    /// Mass of the body (kg).
    pub mass_kg: f64,
    /// Principal moments of inertia about the centre of mass (kg m²).
    pub inertia_kgm2: DVec3,
}

impl ClumpTemplate {
    /// A body of one sphere of radius `radius_m` and density
    /// `density_kgm3`: moves as a free sphere does.
    pub fn sphere(radius_m: f64, density_kgm3: f64) -> Self {
        let mass_kg = super::material::sphere_mass_kg(radius_m, density_kgm3);
        ClumpTemplate {
            offsets_m: vec![DVec3::ZERO],
            radii_m: vec![radius_m],
            mass_kg,
            inertia_kgm2: DVec3::splat(0.4 * mass_kg * radius_m * radius_m),
        }
    }

    /// Number of sub-spheres.
    pub fn len(&self) -> usize {
        self.offsets_m.len()
    }

    /// True for a body without sub-spheres.
    pub fn is_empty(&self) -> bool {
        self.offsets_m.is_empty()
    }

    /// Distance from the centre of mass to the farthest sub-sphere surface
    /// (m): the body's bounding radius.
    pub fn bounding_radius_m(&self) -> f64 {
        self.offsets_m
            .iter()
            .zip(&self.radii_m)
            .map(|(o, r)| o.length() + r)
            .fold(0.0, f64::max)
    }
}

/// The bodies of a world, structure-of-arrays, and where their sub-spheres
/// are in the particle arrays.
#[derive(Debug, Clone, Default)]
pub struct Clumps {
    /// Centre of mass (m).
    pub position: Vec<DVec3>,
    /// Velocity of the centre of mass (m/s).
    pub velocity: Vec<DVec3>,
    /// Orientation: body frame to space frame.
    pub orientation: Vec<DQuat>,
    /// Angular momentum about the centre of mass, space frame (kg m²/s).
    pub angular_momentum: Vec<DVec3>,
    /// Mass (kg).
    pub mass: Vec<f64>,
    /// Principal moments of inertia (kg m²).
    pub inertia: Vec<DVec3>,
    /// Resultant force on the body at the last evaluation, weight included
    /// (N; eq. 4.4).
    pub force: Vec<DVec3>,
    /// Resultant moment about the centre of mass at the last evaluation
    /// (N m; eq. 4.6).
    pub torque: Vec<DVec3>,
    /// The sub-spheres of body `b` are the slots
    /// `first_slot[b]..first_slot[b + 1]`.
    pub first_slot: Vec<u32>,
    /// Id of the first sub-sphere of each body; its sub-spheres have
    /// consecutive ids in slot order.
    pub first_id: Vec<u32>,
    /// Per slot: the sub-sphere's centre in the body frame (m).
    pub offsets_m: Vec<DVec3>,
    /// Per slot: where the sub-sphere is in the particle arrays now.
    pub index: Vec<u32>,
}

impl Clumps {
    /// Number of bodies.
    pub fn len(&self) -> usize {
        self.position.len()
    }

    /// True when the world has no bodies (spheres only).
    pub fn is_empty(&self) -> bool {
        self.position.is_empty()
    }

    /// The slots of body `b`'s sub-spheres.
    pub fn slots(&self, b: usize) -> std::ops::Range<usize> {
        self.first_slot[b] as usize..self.first_slot[b + 1] as usize
    }

    /// Adds a body at `position` with `orientation`, `velocity` and angular
    /// velocity `spin` (space frame, rad/s), whose first sub-sphere will
    /// have id and array index `first` (the others follow in order; the
    /// particles are renumbered later, [`Clumps::reindex`]); returns its
    /// number.
    pub fn push(
        &mut self,
        template: &ClumpTemplate,
        (position, orientation): (DVec3, DQuat),
        (velocity, spin): (DVec3, DVec3),
        first: u32,
    ) -> usize {
        if self.first_slot.is_empty() {
            self.first_slot.push(0);
        }
        let l_body = (orientation.inverse() * spin) * template.inertia_kgm2;
        self.position.push(position);
        self.velocity.push(velocity);
        self.orientation.push(orientation.normalize());
        self.angular_momentum.push(orientation * l_body);
        self.mass.push(template.mass_kg);
        self.inertia.push(template.inertia_kgm2);
        self.force.push(DVec3::ZERO);
        self.torque.push(DVec3::ZERO);
        self.first_id.push(first);
        for (k, o) in template.offsets_m.iter().enumerate() {
            self.offsets_m.push(*o);
            self.index.push(first + k as u32);
        }
        self.first_slot.push(self.offsets_m.len() as u32);
        self.len() - 1
    }

    /// Angular velocity of body `b` (space frame, rad/s).
    #[inline]
    pub fn angular_velocity(&self, b: usize) -> DVec3 {
        rigid_rotation::angular_velocity(
            self.orientation[b],
            self.angular_momentum[b],
            self.inertia[b],
        )
    }

    /// Re-reads where each sub-sphere is after the particles were
    /// renumbered: particle `k` is in clump `clump[k]` with id `id[k]`.
    pub fn reindex(&mut self, clump: &[u32], id: &[u32]) {
        for (k, (&b, &i)) in clump.iter().zip(id).enumerate() {
            if b != NOT_IN_CLUMP {
                let b = b as usize;
                let slot = self.first_slot[b] + (i - self.first_id[b]);
                self.index[slot as usize] = k as u32;
            }
        }
    }

    /// Translational and rotational kinetic energy of the bodies (J).
    pub fn kinetic_energy_j(&self) -> (f64, f64) {
        let mut trans = 0.0;
        let mut rot = 0.0;
        for b in 0..self.len() {
            trans += 0.5 * self.mass[b] * self.velocity[b].length_squared();
            rot += rigid_rotation::rotational_energy_j(
                self.orientation[b],
                self.angular_momentum[b],
                self.inertia[b],
            );
        }
        (trans, rot)
    }

    /// Gravitational potential energy of the bodies (J) relative to the
    /// origin.
    pub fn potential_energy_j(&self, gravity: DVec3) -> f64 {
        self.mass
            .iter()
            .zip(&self.position)
            .map(|(m, x)| -m * gravity.dot(*x))
            .sum()
    }

    /// Velocity Verlet's shadow energy of the bodies for a step `dt_s` (J):
    /// `(|F|²/m + Σ M_k²/I_k) Δt²/8` with the resultants of the last
    /// evaluation (the term [`crate::dem::World::energy_state`] adds for
    /// the spheres).
    pub fn verlet_shadow_j(&self, dt_s: f64) -> f64 {
        (0..self.len())
            .map(|b| {
                let m_body = self.orientation[b].inverse() * self.torque[b];
                self.force[b].length_squared() / self.mass[b]
                    + (m_body * m_body / self.inertia[b]).element_sum()
            })
            .sum::<f64>()
            * (dt_s * dt_s / 8.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A one-sphere body has the sphere's mass and 2/5 m R², and its
    /// angular momentum is I ω: a body pushed with a spin gives that spin
    /// back to rounding. A template built with 1/3 or a pushed body that
    /// forgot to rotate ω into the body frame would fail.
    #[test]
    fn a_one_sphere_body_is_a_sphere() {
        let t = ClumpTemplate::sphere(0.002, 7800.0);
        let m = 4.0 / 3.0 * std::f64::consts::PI * 0.002f64.powi(3) * 7800.0;
        assert!((t.mass_kg - m).abs() < 1e-15 * m);
        assert!((t.inertia_kgm2.x - 0.4 * m * 4e-6).abs() < 1e-15 * m * 4e-6);
        assert_eq!(t.bounding_radius_m(), 0.002);
        let mut c = Clumps::default();
        let q = DQuat::from_rotation_y(0.7);
        let spin = DVec3::new(3.0, -1.0, 2.0);
        c.push(&t, (DVec3::ONE, q), (DVec3::ZERO, spin), 0);
        assert!((c.angular_velocity(0) - spin).length() < 1e-12 * spin.length());
        let (kt, kr) = c.kinetic_energy_j();
        assert_eq!(kt, 0.0);
        let expect = 0.5 * t.inertia_kgm2.x * spin.length_squared();
        assert!((kr - expect).abs() < 1e-12 * expect);
    }

    /// After a renumbering each slot finds its sub-sphere again: bodies 0
    /// (ids 0–2) and 1 (ids 3–4) with a free sphere (id 5) between them,
    /// shuffled. A reindex that used the array index for the id would
    /// point slots at the wrong spheres.
    #[test]
    fn reindex_follows_a_renumbering() {
        let mut t = ClumpTemplate::sphere(0.001, 1000.0);
        t.offsets_m = vec![DVec3::ZERO; 3];
        t.radii_m = vec![0.001; 3];
        let mut c = Clumps::default();
        c.push(
            &t,
            (DVec3::ZERO, DQuat::IDENTITY),
            (DVec3::ZERO, DVec3::ZERO),
            0,
        );
        t.offsets_m.pop();
        t.radii_m.pop();
        c.push(
            &t,
            (DVec3::ZERO, DQuat::IDENTITY),
            (DVec3::ZERO, DVec3::ZERO),
            3,
        );
        // Array order after a renumbering: ids 5, 4, 0, 2, 3, 1.
        let id = [5, 4, 0, 2, 3, 1];
        let clump = [NOT_IN_CLUMP, 1, 0, 0, 1, 0];
        c.reindex(&clump, &id);
        assert_eq!(c.index, vec![2, 5, 3, 4, 1]);
    }
}
