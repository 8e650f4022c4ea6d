//! The two contact laws of a scene, particle-particle and particle-wall:
//! Hertz-Mindlin with restitution damping built from the scene's materials,
//! restitution, friction and restitution mode (thesis eq. 5.6-5.10 for the
//! effective moduli; the damping as in Section 5.2), and how a body's
//! simultaneous sub-sphere contacts combine (`contact.multi_point`).

use crate::dem::ContactLaw;
use crate::scene::Scene;

/// A scene's two contact laws.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactLaws {
    pub particle_particle: ContactLaw,
    pub particle_wall: ContactLaw,
}

/// The contact laws of a scene.
pub fn contact_laws(scene: &Scene) -> ContactLaws {
    let pm = scene.particle_material();
    let wm = scene.wall_material();
    let c = &scene.contact;
    let pp = c.particle_particle;
    let pw = c.particle_wall;
    ContactLaws {
        particle_particle: ContactLaw::new(
            &pm,
            &pm,
            pp.restitution,
            pp.friction,
            c.restitution_mode,
        )
        .with_multi_point(c.multi_point),
        particle_wall: ContactLaw::new(&pm, &wm, pw.restitution, pw.friction, c.restitution_mode)
            .with_multi_point(c.multi_point),
    }
}
