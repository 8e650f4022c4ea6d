//! What a scene's particles are, in figures: their count, shape and mass,
//! and for a body that is not a sphere its sub-spheres, volume, inertia,
//! sphericity and the multi-sphere model's errors against the exact shape
//! (Terzioglu's thesis, Chapter 4); the fill ratio and the time steps. What
//! `vlab scene --json` prints and `vlab.scene()` returns.

use super::{Scene, SceneError};

/// The scene's figures as JSON.
pub fn scene_figures(scene: &Scene) -> Result<serde_json::Value, SceneError> {
    let p = &scene.particles;
    let body = scene.particle_body()?.map(|b| {
        let t = &b.template;
        serde_json::json!({
            "sub_spheres": t.len(),
            "mass_kg": t.mass_kg,
            "principal_moments_kgm2": t.inertia_kgm2.to_array(),
            "union_volume_m3": b.union_volume_m3,
            "union_surface_m2": b.union_surface_m2,
            "exact_volume_m3": b.exact.map(|e| e.0),
            "exact_surface_m2": b.exact.map(|e| e.1),
            "volume_error": b.volume_error(),
            "surface_error": b.surface_error(),
            "sphericity": b.sphericity(),
            "union_sphericity": b.union_sphericity(),
            "min_sub_radius_m": b.min_sub_radius_m,
            "bounding_radius_m": b.bounding_radius_m,
            "sub_sphere_centres_m": t.offsets_m.iter().map(|o| o.to_array()).collect::<Vec<_>>(),
            "sub_sphere_radii_m": t.radii_m,
        })
    });
    let drive = scene.drive(40.0, 20.0)?;
    Ok(serde_json::json!({
        "scene": scene.name,
        "particles": {
            "count": p.count,
            "shape": p.shape.as_str(),
            "aspect_ratio": p.aspect_ratio,
            "hole_ratio": p.hole_ratio,
            "equivalent_diameter_m": p.diameter_m,
            "total_mass_kg": scene.particle_mass_kg(),
            "body": body,
        },
        "fill_ratio": scene.fill_ratio(),
        "dt_s_at_40hz_gamma20": scene.drive_dt_s(&drive),
        // Whole bodies' shortest collisions at 40 Hz, Gamma 20, measured
        // (what the "contacts" rule also counts); null for spheres.
        "body_collisions_s_at_40hz_gamma20": scene.body_collisions(&drive).map(|b| serde_json::json!({
            "body_body": b.pair_s,
            "body_wall": b.wall_s,
        })),
        "rayleigh_limit_s": scene.rayleigh_limit_s(),
    }))
}
