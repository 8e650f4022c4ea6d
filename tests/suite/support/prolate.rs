//! The shape study's prolate of aspect ratio 1.5 (the built-in scene's
//! 5 mm equivalent sphere, 51 sub-spheres), for tests that build bodies by
//! hand.

use vlab::dem::clumps::ClumpTemplate;
use vlab::scene::Scene;

/// The prolate of 1.5.
pub struct Prolate {
    /// Its sub-spheres, mass and moments, laid along x (the principal axis
    /// of the least moment).
    pub template: ClumpTemplate,
    /// Semi-major axis a (m).
    pub a_m: f64,
    /// Semi-minor axis b (m).
    pub b_m: f64,
}

/// The prolate of 1.5 of the built-in scene.
pub fn prolate15() -> Prolate {
    let scene = Scene::merge_over_preset(
        "[particles]\nshape = \"prolate\"\naspect_ratio = 1.5\n",
        "test",
    )
    .expect("a prolate scene");
    let body = scene
        .particle_body()
        .expect("a body")
        .expect("not a sphere");
    // Equal volume: a b^2 = r^3 with a = 1.5 b.
    let b_m = scene.radius_m() / 1.5_f64.cbrt();
    Prolate {
        template: body.template,
        a_m: 1.5 * b_m,
        b_m,
    }
}
