//! Sphere state: six degrees of freedom per particle, stored as plain arrays.
//!
//! Translational and rotational motion follow the Newton–Euler equations of thesis
//! eq. 3.23–3.24; for a sphere the inertia tensor is isotropic, I = 2/5 m R², so
//! the gyroscopic terms of eq. 3.24 vanish. Spheres need no orientation to compute
//! contact forces, so only the angular velocity is kept.
//!
//! **Order.** A particle keeps its `id` (the order it was added in) while the
//! world may hold it anywhere in the arrays: a large bed is renumbered in
//! space as it moves ([`crate::dem::ordering`]), so that particles that touch
//! sit close in memory. Whatever reads particles by number from outside the
//! engine (files, dumps, caches) takes them in id order ([`Particles::by_id`]).
//!
//! **Bodies.** A particle may be a sub-sphere of a rigid multi-sphere body
//! ([`super::clumps`]): then `clump` names its body, its inverse mass and
//! inertia are zero (the body moves it, not the sphere integrator) and its
//! mass is the body's (what its contacts read). Energies and masses count
//! each body once.

use std::borrow::Cow;

use glam::{DQuat, DVec3};

use super::clumps::{ClumpTemplate, Clumps, NOT_IN_CLUMP};
use super::material::sphere_mass_kg;
use super::ordering::Renumbering;

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
    /// Each particle's id: the order it was added in, kept when the arrays
    /// are renumbered.
    pub id: Vec<u32>,
    /// Each particle's body ([`NOT_IN_CLUMP`] for a free sphere).
    pub clump: Vec<u32>,
    /// The rigid bodies the sub-spheres belong to (empty: spheres only).
    pub clumps: Clumps,
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
        self.id.push(self.id.len() as u32);
        self.clump.push(NOT_IN_CLUMP);
        self.len() - 1
    }

    /// Adds a rigid body of `template`'s sub-spheres with its centre of mass
    /// at `position`, turned by `orientation` (body to space), moving at
    /// `velocity` and spinning at `spin` (space frame, rad/s); returns the
    /// body's number. Its sub-spheres are placed and given their velocities.
    pub fn push_clump(
        &mut self,
        template: &ClumpTemplate,
        (position, orientation): (DVec3, DQuat),
        (velocity, spin): (DVec3, DVec3),
    ) -> usize {
        let first = self.len() as u32;
        let b = self
            .clumps
            .push(template, (position, orientation), (velocity, spin), first);
        for &r in &template.radii_m {
            self.position.push(position);
            self.velocity.push(velocity);
            self.angular_velocity.push(spin);
            self.force.push(DVec3::ZERO);
            self.torque.push(DVec3::ZERO);
            self.radius.push(r);
            self.mass.push(template.mass_kg);
            self.inv_mass.push(0.0);
            self.inv_inertia.push(0.0);
            self.id.push(self.id.len() as u32);
            self.clump.push(b as u32);
        }
        self.place_clump(b);
        b
    }

    /// Puts body `b`'s sub-spheres where the body is: position, velocity and
    /// spin of each from the body's.
    #[inline]
    pub fn place_clump(&mut self, b: usize) {
        let c = &self.clumps;
        let (x, v, q) = (c.position[b], c.velocity[b], c.orientation[b]);
        let w = c.angular_velocity(b);
        for slot in c.slots(b) {
            let k = c.index[slot] as usize;
            let arm = q * c.offsets_m[slot];
            self.position[k] = x + arm;
            self.velocity[k] = v + w.cross(arm);
            self.angular_velocity[k] = w;
        }
    }

    /// Sets the spins and sub-sphere velocities of body `b` from its
    /// velocity and angular momentum, leaving positions.
    #[inline]
    pub fn set_clump_velocities(&mut self, b: usize) {
        let c = &self.clumps;
        let (x, v) = (c.position[b], c.velocity[b]);
        let w = c.angular_velocity(b);
        for slot in c.slots(b) {
            let k = c.index[slot] as usize;
            self.velocity[k] = v + w.cross(self.position[k] - x);
            self.angular_velocity[k] = w;
        }
    }

    /// True when particle `k` of the arrays is the `k`-th added, for every
    /// `k`.
    pub fn in_id_order(&self) -> bool {
        self.id.iter().enumerate().all(|(k, &id)| id as usize == k)
    }

    /// The particles in id order (the order they were added in): these
    /// arrays when they are in it, else a renumbered copy.
    pub fn by_id(&self) -> Cow<'_, Particles> {
        if self.in_id_order() {
            return Cow::Borrowed(self);
        }
        let mut order = vec![0u32; self.len()];
        for (k, &id) in self.id.iter().enumerate() {
            order[id as usize] = k as u32;
        }
        let mut copy = self.clone();
        copy.renumber(&order);
        Cow::Owned(copy)
    }

    /// Renumbers the particles: the `k`-th of the new arrays is the
    /// `order[k]`-th of the old. `order` must be a permutation of
    /// `0..len`.
    pub fn renumber(&mut self, order: &[u32]) {
        let mut cycles = Renumbering::default();
        cycles.find(order);
        self.renumber_by(&cycles, order);
    }

    /// [`Self::renumber`] by the cycles already found for `order`, in place.
    pub fn renumber_by(&mut self, cycles: &Renumbering, order: &[u32]) {
        debug_assert_eq!(order.len(), self.len());
        cycles.apply(&mut self.position, order);
        cycles.apply(&mut self.velocity, order);
        cycles.apply(&mut self.angular_velocity, order);
        cycles.apply(&mut self.force, order);
        cycles.apply(&mut self.torque, order);
        cycles.apply(&mut self.radius, order);
        cycles.apply(&mut self.mass, order);
        cycles.apply(&mut self.inv_mass, order);
        cycles.apply(&mut self.inv_inertia, order);
        cycles.apply(&mut self.id, order);
        cycles.apply(&mut self.clump, order);
        if !self.clumps.is_empty() {
            self.clumps.reindex(&self.clump, &self.id);
        }
    }

    /// True when particle `k` is a sub-sphere of a body.
    #[inline]
    pub fn in_clump(&self, k: usize) -> bool {
        self.clump[k] != NOT_IN_CLUMP
    }

    /// Scales every free sphere's and body's velocity across `down` (a unit
    /// vector: what is left is along it) and its spin by `factor`: a brake
    /// on rolling and sliding that leaves falling and bouncing alone.
    pub fn brake_across(&mut self, down: DVec3, factor: f64) {
        let across = |v: DVec3| {
            let along = down * v.dot(down);
            along + (v - along) * factor
        };
        for k in 0..self.len() {
            if !self.in_clump(k) {
                self.velocity[k] = across(self.velocity[k]);
                self.angular_velocity[k] *= factor;
            }
        }
        let c = &mut self.clumps;
        for b in 0..c.len() {
            c.velocity[b] = across(c.velocity[b]);
            c.angular_momentum[b] *= factor;
        }
    }

    /// Every free sphere and every body once, as `(mass, centre, velocity)`:
    /// what a sum over the bed's masses (its centre of mass, momentum,
    /// granular temperature) runs over.
    pub fn movers(&self) -> impl Iterator<Item = (f64, DVec3, DVec3)> + '_ {
        let free = (0..self.len())
            .filter(|&k| !self.in_clump(k))
            .map(|k| (self.mass[k], self.position[k], self.velocity[k]));
        let c = &self.clumps;
        let bodies = (0..c.len()).map(|b| (c.mass[b], c.position[b], c.velocity[b]));
        free.chain(bodies)
    }

    /// Total mass (kg): free spheres and bodies, each once.
    pub fn total_mass_kg(&self) -> f64 {
        let free: f64 = (0..self.len())
            .filter(|&k| !self.in_clump(k))
            .map(|k| self.mass[k])
            .sum();
        free + self.clumps.mass.iter().sum::<f64>()
    }

    /// Largest radius (m), zero when empty.
    pub fn max_radius_m(&self) -> f64 {
        self.radius.iter().copied().fold(0.0, f64::max)
    }

    /// Smallest radius (m), infinite when empty.
    pub fn min_radius_m(&self) -> f64 {
        self.radius.iter().copied().fold(f64::INFINITY, f64::min)
    }

    /// Translational and rotational kinetic energy (J), of the free spheres
    /// and the bodies.
    pub fn kinetic_energy_j(&self) -> (f64, f64) {
        let mut trans = 0.0;
        let mut rot = 0.0;
        for i in 0..self.len() {
            if self.in_clump(i) {
                continue;
            }
            trans += 0.5 * self.mass[i] * self.velocity[i].length_squared();
            rot += 0.5 / self.inv_inertia[i] * self.angular_velocity[i].length_squared();
        }
        let (bt, br) = self.clumps.kinetic_energy_j();
        (trans + bt, rot + br)
    }

    /// Gravitational potential energy (J) relative to the origin, of the
    /// free spheres and the bodies.
    pub fn potential_energy_j(&self, gravity: DVec3) -> f64 {
        let mut pe = 0.0;
        for i in 0..self.len() {
            if !self.in_clump(i) {
                pe -= self.mass[i] * gravity.dot(self.position[i]);
            }
        }
        pe + self.clumps.potential_energy_j(gravity)
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

#[cfg(test)]
mod tests {
    use super::*;

    fn three() -> Particles {
        let mut p = Particles::default();
        for k in 0..3 {
            let x = DVec3::splat(k as f64);
            p.push(x, x, x, 0.001 * (k + 1) as f64, 1000.0);
        }
        p
    }

    /// A renumbering moves every array alike, and `by_id` undoes it: an
    /// array left out of `renumber` (a mass that stays behind its sphere)
    /// fails here.
    #[test]
    fn renumbered_particles_read_back_in_id_order() {
        let p = three();
        let mut q = p.clone();
        q.renumber(&[2, 0, 1]);
        assert_eq!(q.id, vec![2, 0, 1]);
        assert!(!q.in_id_order());
        assert_eq!(q.radius, vec![p.radius[2], p.radius[0], p.radius[1]]);
        assert_eq!(q.inv_mass[0], p.inv_mass[2]);
        assert_eq!(q.position[1], p.position[0]);
        let back = q.by_id();
        assert!(matches!(back, Cow::Owned(_)));
        for k in 0..3 {
            assert_eq!(back.position[k], p.position[k]);
            assert_eq!(back.mass[k], p.mass[k]);
            assert_eq!(back.inv_inertia[k], p.inv_inertia[k]);
        }
        assert!(matches!(p.by_id(), Cow::Borrowed(_)));
    }
}
