//! The motion of the rigid multi-sphere bodies ([`crate::dem::clumps`]):
//! velocity Verlet for each body as a whole, beside the spheres' pass of
//! [`super::integrate`], which leaves the sub-spheres alone.
//!
//! Each body's resultant force is its weight plus the contact forces on its
//! sub-spheres (Terzioglu's thesis eq. 4.3–4.4), and its resultant moment
//! about the centre of mass is theirs with the lever arms of eq. 4.6–4.7
//! (a sub-sphere's contact torque about its centre plus `(r_i − r_MS) ×
//! F_i`). The first pass kicks the velocity and the angular momentum by half
//! a step, drifts the centre, turns the body freely for the step
//! ([`crate::dem::rigid_rotation`]: Euler's equations with the gyroscopic
//! term, which eq. 3.24 written for spheres has not), and places the
//! sub-spheres; the second, after the forces at the new positions, gathers
//! the resultants and kicks again. A body's sums run over its sub-spheres in
//! id order, wherever the renumbering put them, so the bits do not depend on
//! the order of the particle arrays beyond what the forces themselves do.
//!
//! Both passes also sum the power of the contact forces on the bodies
//! (`(F − m g)·V + M·ω`, at the half-step velocities) for the books, as the
//! spheres' pass does.

use glam::DVec3;

use super::integrate::KickSums;
use crate::dem::particles::Particles;
use crate::dem::rigid_rotation;

/// Sets every body's resultant force (weight included) and moment about its
/// centre of mass from the forces and torques now on its sub-spheres; a
/// sub-sphere's force holds the weight of its body, as the force stage set
/// it (its mass is the body's), which is taken out again.
pub fn gather(p: &mut Particles, gravity: DVec3) {
    let c = &mut p.clumps;
    for b in 0..c.position.len() {
        let x = c.position[b];
        let weight = gravity * c.mass[b];
        let mut f = DVec3::ZERO;
        let mut m = DVec3::ZERO;
        for slot in c.first_slot[b] as usize..c.first_slot[b + 1] as usize {
            let k = c.index[slot] as usize;
            let contact = p.force[k] - weight;
            f += contact;
            m += p.torque[k] + (p.position[k] - x).cross(contact);
        }
        c.force[b] = f + weight;
        c.torque[b] = m;
    }
}

/// The first half of the step for every body: half kick (`V += F/m Δt/2`,
/// `L += M Δt/2`), drift of the centre, a free rotation for the whole step,
/// and the sub-spheres placed. Returns `carry` plus the contact power on the
/// bodies at the half-step velocities, the first sub-sphere whose position
/// is not finite, and whether one travelled farther than the pair list
/// allows from `built_at`, where the list was built.
pub fn kick_drift(
    p: &mut Particles,
    (dt_s, gravity): (f64, DVec3),
    (built_at, travel_sq_m2): (Option<&[DVec3]>, f64),
    carry: f64,
) -> KickSums {
    let half = 0.5 * dt_s;
    let mut sums = KickSums {
        work: carry,
        ..KickSums::default()
    };
    for b in 0..p.clumps.len() {
        let c = &mut p.clumps;
        let contact = c.force[b] - gravity * c.mass[b];
        c.velocity[b] += c.force[b] * (half / c.mass[b]);
        c.angular_momentum[b] += c.torque[b] * half;
        let w = c.angular_velocity(b);
        sums.work += contact.dot(c.velocity[b]) + c.torque[b].dot(w);
        c.position[b] += c.velocity[b] * dt_s;
        c.orientation[b] = rigid_rotation::free_rotation(
            c.orientation[b],
            c.angular_momentum[b],
            c.inertia[b],
            dt_s,
        );
        p.place_clump(b);
        let c = &p.clumps;
        for slot in c.slots(b) {
            let k = c.index[slot] as usize;
            let x = p.position[k];
            if sums.nonfinite.is_none() && !x.is_finite() {
                sums.nonfinite = Some(k);
            }
            if let Some(r) = built_at {
                sums.moved_far |= (x - r[k]).length_squared() > travel_sq_m2;
            }
        }
    }
    sums
}

/// The second half kick of every body, with the resultants of the forces at
/// the new positions ([`gather`] first): returns `carry` plus the contact
/// power on the bodies at the half-step velocities, before the kick; the
/// sub-spheres get the bodies' new velocities and spins.
pub fn kick(p: &mut Particles, (dt_s, gravity): (f64, DVec3), carry: f64) -> f64 {
    gather(p, gravity);
    let half = 0.5 * dt_s;
    let mut work = carry;
    for b in 0..p.clumps.len() {
        let c = &mut p.clumps;
        let contact = c.force[b] - gravity * c.mass[b];
        let w = c.angular_velocity(b);
        work += contact.dot(c.velocity[b]) + c.torque[b].dot(w);
        c.angular_momentum[b] += c.torque[b] * half;
        c.velocity[b] += c.force[b] * (half / c.mass[b]);
        p.set_clump_velocities(b);
    }
    work
}
