//! The settling protocol (issue 9, item 1): a bed is poured with one fixed
//! settling law, so that its packing does not depend on the contacts under
//! test, and the test contacts then hold it.

use vlab::experiment::settle::{packing, prepare_drive, settle_bed};
use vlab::scene::Scene;

fn scene_with_contacts(restitution: f64, friction: f64) -> Scene {
    let text = format!(
        "[contact]\n\
         particle_particle = {{ restitution = {restitution}, friction = {friction} }}\n\
         particle_wall = {{ restitution = {restitution}, friction = {friction} }}\n"
    );
    Scene::merge_over_preset(&text, "test scene").expect("valid scene")
}

/// A frictionless elastic bed (e = 1, mu = 0: it never comes to rest under its
/// own contacts), a dead rough one (e = 0.05, mu = 1: it stays loose) and the
/// thesis bed settle to the same packing fraction, and each keeps it within
/// 0.02 when left 20 ms under its own contacts at the drive's time step.
#[test]
fn three_contact_laws_settle_to_one_packing() {
    let laws = [(1.0, 0.0), (0.05, 1.0), (0.86, 0.52)];
    let mut fractions = Vec::new();
    for (e, mu) in laws {
        let scene = scene_with_contacts(e, mu);
        let bed = settle_bed(&scene, &mut |_| {}).expect("the bed settles");
        // A random poured packing in a cylinder of 8 diameters: between the
        // random loose (0.55) and random close (0.64) packings, thinned by the
        // wall; measured 0.590.
        assert!(
            (0.55..0.64).contains(&bed.packing_fraction),
            "e {e}, mu {mu}: packing {:.3}",
            bed.packing_fraction
        );
        let dt = scene.drive_dt_s(&scene.drive(40.0, 20.0).expect("valid drive"));
        let mut world = prepare_drive(&bed, &scene, dt).expect("drive ready");
        let steps = (0.02 / dt).round() as u64;
        for _ in 0..steps {
            world.step(0.0).expect("the bed holds still");
        }
        let held = packing(&world, &scene).fraction;
        assert!(
            (held - bed.packing_fraction).abs() < 0.02,
            "e {e}, mu {mu}: packing {:.3} settled, {held:.3} after 20 ms under the test contacts",
            bed.packing_fraction
        );
        fractions.push(held);
    }
    let spread = fractions.iter().cloned().fold(f64::MIN, f64::max)
        - fractions.iter().cloned().fold(f64::MAX, f64::min);
    assert!(spread < 0.02, "packing fractions {fractions:?}");
}
