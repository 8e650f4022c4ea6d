//! Sphere state: six degrees of freedom per particle, stored as plain arrays.
//!
//! Translational and rotational motion follow the Newton–Euler equations of thesis
//! eq. 3.23–3.24; for a sphere the inertia tensor is isotropic, I = 2/5 m R², so
//! the gyroscopic terms of eq. 3.24 vanish. Spheres need no orientation to compute
//! contact forces, so only the angular velocity is kept.

use glam::DVec3;

use super::material::sphere_mass_kg;

/// All particles of a scene, structure-of-arrays.
#[derive(Debug, Clone, Default)]
pub struct Particles {
    pub position: Vec<DVec3>,
    pub velocity: Vec<DVec3>,
    pub angular_velocity: Vec<DVec3>,
    pub force: Vec<DVec3>,
    pub torque: Vec<DVec3>,
    pub radius: Vec<f64>,
    pub mass: Vec<f64>,
    pub inv_mass: Vec<f64>,
    pub inv_inertia: Vec<f64>,
}

impl Particles {
    /// Number of particles.
    pub fn len(&self) -> usize {
        self.position.len()
    }

    /// True when there are no particles.
    pub fn is_empty(&self) -> bool {
        self.position.is_empty()
    }

    /// Adds a sphere at rest-free state; returns its index.
    pub fn push(
        &mut self,
        position: DVec3,
        velocity: DVec3,
        angular_velocity: DVec3,
        radius_m: f64,
        density_kgm3: f64,
    ) -> usize {
        let mass = sphere_mass_kg(radius_m, density_kgm3);
        let inertia = 0.4 * mass * radius_m * radius_m;
        self.position.push(position);
        self.velocity.push(velocity);
        self.angular_velocity.push(angular_velocity);
        self.force.push(DVec3::ZERO);
        self.torque.push(DVec3::ZERO);
        self.radius.push(radius_m);
        self.mass.push(mass);
        self.inv_mass.push(1.0 / mass);
        self.inv_inertia.push(1.0 / inertia);
        self.len() - 1
    }

    /// Total mass (kg).
    pub fn total_mass_kg(&self) -> f64 {
        self.mass.iter().sum()
    }

    /// Largest radius (m), zero when empty.
    pub fn max_radius_m(&self) -> f64 {
        self.radius.iter().copied().fold(0.0, f64::max)
    }

    /// Smallest radius (m), infinite when empty.
    pub fn min_radius_m(&self) -> f64 {
        self.radius.iter().copied().fold(f64::INFINITY, f64::min)
    }

    /// Translational and rotational kinetic energy (J).
    pub fn kinetic_energy_j(&self) -> (f64, f64) {
        let mut trans = 0.0;
        let mut rot = 0.0;
        for i in 0..self.len() {
            trans += 0.5 * self.mass[i] * self.velocity[i].length_squared();
            rot += 0.5 / self.inv_inertia[i] * self.angular_velocity[i].length_squared();
        }
        (trans, rot)
    }

    /// Gravitational potential energy (J) relative to the origin.
    pub fn potential_energy_j(&self, gravity: DVec3) -> f64 {
        let mut pe = 0.0;
        for i in 0..self.len() {
            pe -= self.mass[i] * gravity.dot(self.position[i]);
        }
        pe
    }

    /// Largest particle speed (m/s).
    pub fn max_speed_mps(&self) -> f64 {
        self.velocity
            .iter()
            .map(|v| v.length_squared())
            .fold(0.0, f64::max)
            .sqrt()
    }
}
