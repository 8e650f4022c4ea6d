//! `vlab scene`: what the built-in scene (or a scene file over it) contains, and
//! the figures that follow from it.

use std::path::PathBuf;

use anyhow::Result;
use clap::Args;

use vlab::dem::restitution::realised_restitution;
use vlab::experiment::damper::first_checkpoint;
use vlab::scene::{
    CyclesSpec, ParticleBody, Scene, ShapeKind, THESIS_DAMPER_TOML, THESIS_SCENE_FILE,
    TimeStepRule, TimeStepSpec,
};
use vlab::scene::{contact_laws, scene_figures};
use vlab::stats::MIN_SERIES_VALUES;

#[derive(Debug, Clone, Args)]
pub struct SceneArgs {
    /// Scene file (TOML) merged over the built-in thesis scene.
    #[arg(long, value_name = "FILE")]
    scene: Option<PathBuf>,
    /// Print the scene as TOML (the annotated preset when no --scene is given).
    #[arg(long)]
    print: bool,
    /// Print the particles' figures as JSON: count, shape, mass, and for a
    /// body that is not a sphere its volume, inertia, sphericity and the
    /// multi-sphere errors.
    #[arg(long, conflicts_with = "print")]
    json: bool,
}

pub fn run(a: SceneArgs) -> Result<()> {
    let scene = match &a.scene {
        Some(path) => Scene::load_over_preset(path)?,
        None => Scene::thesis(),
    };
    if a.print {
        if a.scene.is_none() {
            print!("{THESIS_DAMPER_TOML}");
        } else {
            print!("{}", scene.to_toml());
        }
        return Ok(());
    }
    if a.json {
        println!("{}", serde_json::to_string_pretty(&scene_figures(&scene)?)?);
        return Ok(());
    }
    match &a.scene {
        Some(path) => println!(
            "scene \"{}\" ({} over the built-in {THESIS_SCENE_FILE})",
            scene.name,
            path.display()
        ),
        None => println!(
            "scene \"{}\" (built in: {THESIS_SCENE_FILE}; `vlab scene --print` shows it)",
            scene.name
        ),
    }
    print_bed(&scene)?;
    print_contacts(&scene);
    print_time_step(&scene)?;
    print_run(&scene);
    Ok(())
}

/// The particles and the enclosure.
fn print_bed(scene: &Scene) -> Result<()> {
    let p = &scene.particles;
    let e = &scene.enclosure;
    match scene.particle_body()? {
        None => println!(
            "  particles        {} spheres of {} mm, {:.4} kg in all",
            p.count,
            p.diameter_m * 1e3,
            scene.particle_mass_kg()
        ),
        Some(body) => print_body(scene, &body),
    }
    println!(
        "  enclosure        {} mm x {} mm closed cylinder, {}; fill ratio {:.3} (eq. 6.1; {} would fill it at random close packing; pouring and closing reach about 0.57 in the thesis cylinder)",
        e.inner_diameter_m * 1e3,
        e.inner_length_m * 1e3,
        e.orientation.as_str(),
        scene.fill_ratio(),
        scene.max_particles()
    );
    Ok(())
}

/// What one body of a scene of shapes is: its shape, its union against
/// the exact shape, its mass and moments.
fn print_body(scene: &Scene, body: &ParticleBody) {
    let p = &scene.particles;
    let t = &body.template;
    println!(
        "  particles        {} {}s ({}), volume of a {} mm sphere each, {:.4} kg in all",
        p.count,
        p.shape.as_str(),
        shape_words(scene, body),
        p.diameter_m * 1e3,
        p.count as f64 * t.mass_kg
    );
    let errors = match (body.volume_error(), body.surface_error(), body.sphericity()) {
        (Some(v), Some(s), Some(psi)) => format!(
            "; against the exact shape: volume {:+.2} %, surface {:+.2} %; exact shape's sphericity {psi:.3} (eq. 8.3)",
            100.0 * v,
            100.0 * s
        ),
        _ => format!(
            "; sphericity {:.3} (eq. 8.3 on the union itself: a clump file has no exact shape)",
            body.union_sphericity()
        ),
    };
    println!(
        "  body             union of its sub-spheres {:.2} mm3, {:.3} mm2{errors}",
        body.union_volume_m3 * 1e9,
        body.union_surface_m2 * 1e6
    );
    println!(
        "                   mass {:.4e} kg, principal moments {:.3e} {:.3e} {:.3e} kg m2; sub-spheres {:.3} to {:.3} mm in radius, reach {:.3} mm from the centre of mass",
        t.mass_kg,
        t.inertia_kgm2.x,
        t.inertia_kgm2.y,
        t.inertia_kgm2.z,
        body.min_sub_radius_m * 1e3,
        t.radii_m.iter().copied().fold(0.0, f64::max) * 1e3,
        body.bounding_radius_m * 1e3
    );
}

/// The shape's own numbers, in words.
fn shape_words(scene: &Scene, body: &ParticleBody) -> String {
    let p = &scene.particles;
    let n = body.template.len();
    match p.shape {
        ShapeKind::Prolate | ShapeKind::Oblate => format!(
            "aspect ratio {}, {n} sub-spheres",
            p.aspect_ratio.unwrap_or(1.0)
        ),
        ShapeKind::Toroid => format!(
            "hole ratio {}, {n} sub-spheres",
            p.hole_ratio.unwrap_or(0.0)
        ),
        ShapeKind::Clump => format!(
            "{n} sub-spheres from {}",
            p.clump_file
                .as_ref()
                .map(|f| f.display().to_string())
                .unwrap_or_default()
        ),
        ShapeKind::Sphere => "spheres".into(),
    }
}

/// The two contact laws.
fn print_contacts(scene: &Scene) {
    let laws = contact_laws(scene);
    let (pp, pw) = (laws.particle_particle, laws.particle_wall);
    for (name, law) in [("particle-particle", pp), ("particle-wall", pw)] {
        println!(
            "  {name:18} {}: e = {}, mu = {}, E* = {:.3e} Pa, G* = {:.3e} Pa, damping factor {:.4} ({} mode: realised e = {:.4})",
            law.describe(),
            law.restitution,
            law.friction,
            law.e_star_pa,
            law.g_star_pa,
            law.damping_factor,
            match scene.contact.restitution_mode {
                vlab::dem::RestitutionMode::Exact => "exact",
                vlab::dem::RestitutionMode::Thesis => "thesis",
            },
            realised_restitution(law.damping_factor)
        );
    }
}

/// The time step at the default drive and its rule, and the yield velocities.
fn print_time_step(scene: &Scene) -> Result<()> {
    let thesis_drive = scene.drive(40.0, 20.0)?;
    let dt_rule = match &scene.simulation.dt_s {
        TimeStepSpec::Seconds(_) => "fixed".to_string(),
        TimeStepSpec::Rule(TimeStepRule::Rayleigh) => format!(
            "{} x the Rayleigh step",
            scene.simulation.rayleigh_safety_factor
        ),
        TimeStepSpec::Rule(rule) => {
            let mut said = format!(
                "{} steps per contact at the fastest expected impact ({:.2} m/s at 40 Hz, Gamma 20)",
                scene.simulation.steps_per_contact,
                scene.expected_impact_speed_mps(&thesis_drive)
            );
            let bodies = scene.body_collisions(&thesis_drive);
            match (rule, bodies) {
                (TimeStepRule::Contacts, Some(b)) => {
                    let us = |t: Option<f64>| t.map_or("-".into(), |t| format!("{:.1}", t * 1e6));
                    said.push_str(&format!(
                        "; whole bodies measured: {} us body-body, {} us body-wall",
                        us(b.pair_s),
                        us(b.wall_s)
                    ));
                }
                (TimeStepRule::SubSphereContacts, Some(_)) => {
                    said.push_str("; one sub-sphere pair's contact, not the whole bodies'");
                }
                _ => {}
            }
            said
        }
    };
    println!(
        "  time step        {:.3e} s at 40 Hz, Gamma 20 ({dt_rule}); Rayleigh limit {:.3e} s (eq. 3.31)",
        scene.drive_dt_s(&thesis_drive),
        scene.rayleigh_limit_s()
    );
    if let Some(y) = scene.yield_velocities_mps() {
        println!(
            "  yield velocity   {:.3} m/s particle-particle, {:.3} m/s particle-wall (eq. 5.26)",
            y.particle_particle_mps, y.particle_wall_mps
        );
    }
    Ok(())
}

/// How a run goes: settling, then the drive's length.
fn print_run(scene: &Scene) {
    let d = &scene.drive;
    let drive = match &d.cycles {
        CyclesSpec::Count(n) => format!(
            "{n} cycles with the last {} as steady state",
            d.steady_cycles
        ),
        CyclesSpec::Rule(_) => format!(
            "until steady (work in and dissipation within {} %, energy per cycle to {} % error, no trend, a window of at least {MIN_SERIES_VALUES} cycles), tested from cycle {} to {}",
            100.0 * d.balance_rel,
            100.0 * d.stderr_rel,
            first_checkpoint(d.min_cycles),
            d.max_cycles
        ),
    };
    println!(
        "  run              pour and settle with the settling law (vlab::experiment::bed::settle), then drive {drive}; seed {}",
        scene.simulation.seed
    );
}
