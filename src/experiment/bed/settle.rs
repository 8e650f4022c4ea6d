//! Filling the damper: pour, settle, close the lid, turn to the test
//! orientation, with one fixed settling law, so that the bed a test starts
//! from does not depend on the contacts under test.
//!
//! The thesis settled its beds under gravity with the test contacts for
//! 0.2 s (Section 6.2.2). That couples the packing to e and μ: an elastic,
//! frictionless bed never comes to rest, a rough dead one stays loose and too
//! tall for its lid. vlab instead fills every damper the same way:
//!
//! 1. **Pour.** Random sequential insertion into a taller column of the
//!    enclosure's diameter (see [`crate::experiment::bed::fill`]; the column is made
//!    taller until every sphere fits), then the spheres fall under the *soft*
//!    settling law, frictionless for two fall times of the column so that they
//!    slide into a dense bed, then with the settling friction until at rest.
//! 2. **Close.** The lid comes down to the design length. Spheres that stand
//!    above it are pushed down by the lid moving as a piston, slowly, with the
//!    friction off so the bed can rearrange. If the lid then squeezes the bed
//!    harder than the bed's own weight did ([`CLOSED_SQUEEZE_FACTOR`]), the
//!    particles do not fit, and the refusal gives the packing they would need
//!    and the one the bed reached.
//! 3. **Turn** gravity to the test orientation and settle again.
//! 4. **Stiffen** in [`RELAX_STAGES`] geometric stages to the particles' own
//!    stiffness, settling to rest at each, so that the overlaps shrink to those
//!    the test contacts hold the bed with without springing the bed apart.
//!
//! Then [`prepare_drive`] switches to the scene's contact laws (same Hertz
//! stiffness: no force jump), drops every tangential history, sets the test
//! time step and starts the energy ledger.
//!
//! # The settling law
//!
//! Hertz contacts of the particles' own materials, with Young's moduli scaled
//! by [`SETTLE_STIFFNESS_FACTOR`] while pouring (a contact lasts
//! `0.01^{-2/5}` = 6.3 times longer, so the step can be 6.3 times longer),
//! restitution [`SETTLE_RESTITUTION`] in `exact` mode and friction
//! [`SETTLE_FRICTION`], for particle-particle and particle-wall contacts
//! alike; each step resolves the fastest fall the pour column allows with
//! [`SETTLE_STEPS_PER_CONTACT`] steps. In the thesis cylinder (D/d = 8) this
//! pours to a packing fraction of 0.59 in the bulk, whatever the test
//! contacts, and fills up to 0.57 close under the lid; 0.58 (446 spheres of
//! 5 mm), 0.59 and 0.6 are refused: the layers at the floor and lid pack
//! looser than the bulk, and the lid would have to squeeze the bed to close.
//! (A lab taps or vibrates such a fill denser; vlab does not yet.) A bed is at rest
//! when its kinetic energy is below [`REST_KINETIC_FRACTION`] of `M g d`
//! ([`at_rest`]). One still moving after [`MAX_POUR_S`] of simulated time
//! (a few spheres rolling on a floor they do not cover: the contact law has
//! no rolling resistance) goes on as long again with a brake on rolling and
//! sliding ([`ROLLING_BRAKE_S`]); one that is still not at rest is an error
//! of its own.
//!
//! # Packing and bed height
//!
//! The packing fraction is measured in the bulk of the poured bed: the share
//! of a slab of the enclosure, from one diameter above the floor to one
//! diameter below the bed's surface, that the spheres fill (sphere caps cut
//! exactly). The bed height is the height that the particles' volume fills at
//! that packing, `h = V_p / (φ A)`, not the top of the highest sphere.

use crate::clock::Stopwatch;
use std::f64::consts::PI;

use glam::DVec3;

use crate::dem::material::Material;
use crate::dem::timestep::{rayleigh_time_step_s, shortest_contact_with_mass_s};
use crate::dem::{
    ContactLaw, ContactParams, DemError, Numerics, Particles, RestitutionMode, Walls, World,
};
use crate::experiment::bed::fill::{COLUMN_FILL, SceneRng, insert_in_cylinder, random_orientation};
use crate::experiment::damper::{Progress, gravity_vector};
use crate::maths;
use crate::scene::contact_laws;
use crate::scene::{Orientation, Scene, SceneError};
use crate::warning::RunWarning;

/// Young's moduli of the settling law while pouring, as a fraction of the
/// materials' own.
pub const SETTLE_STIFFNESS_FACTOR: f64 = 0.01;
/// Normal restitution of the settling law (exact mode).
pub const SETTLE_RESTITUTION: f64 = 0.1;
/// The pour is frictionless for this many fall times of the column, so that
/// the landing spheres slide into a dense bed; the settling friction then
/// brings it to rest.
pub const POUR_SLIDING_FALLS: f64 = 2.0;
/// Friction of the settling law.
pub const SETTLE_FRICTION: f64 = 0.1;
/// A bed is at rest when its kinetic energy is below this fraction of `M g d`
/// ([`at_rest`]).
pub const REST_KINETIC_FRACTION: f64 = 1e-4;
/// Longest the poured column may take to come to rest (s).
pub const MAX_POUR_S: f64 = 2.0;

/// Time constant (s) of the brake on rolling a bed still moving after its
/// phase's time meets ([`run_until_rest`]): its rolling and sliding decay as
/// `exp(-t / 0.05 s)`, a tenth of the time a bed of the thesis damper takes
/// to settle, so a bed of a few spheres comes to rest within the stage.
pub const ROLLING_BRAKE_S: f64 = 0.05;
/// Stages of the stiffening from the pouring law to the particles' own
/// stiffness, each a factor `0.01^{-1/RELAX_STAGES}` stiffer.
pub const RELAX_STAGES: u32 = 4;
/// Longest one stage of the stiffening may take (s).
pub const MAX_RELAX_S: f64 = 0.2;
/// Steps a contact of the settling law is resolved with, at the fastest
/// impact the pour can bring.
pub const SETTLE_STEPS_PER_CONTACT: f64 = 25.0;
/// Speed at which the lid comes down on a bed that stands above it (m/s).
pub const PISTON_SPEED_MPS: f64 = 0.05;
/// A closed bed may hold its deepest overlap at most this many times deeper
/// than the poured bed held it under its own weight.
pub const CLOSED_SQUEEZE_FACTOR: f64 = 3.0;
/// Version of the settling procedure and law: part of the key of cached beds.
pub const SETTLING_VERSION: u32 = 1;

/// A settled bed in the closed enclosure, turned to the test orientation, still
/// under the (stiff) settling law; [`prepare_drive`] makes it ready to drive.
#[derive(Debug, Clone)]
pub struct SettledBed {
    pub world: World,
    /// Simulated time spent pouring, closing and settling (s).
    pub settle_time_s: f64,
    /// Steps spent on it.
    pub settle_steps: u64,
    /// Wall-clock time spent (s); zero for a bed read from the cache.
    pub wall_time_s: f64,
    /// Packing fraction in the bulk of the poured bed (-).
    pub packing_fraction: f64,
    /// Height the bed fills at that packing, `V_p / (φ A)` (m), poured along the
    /// axis.
    pub bed_height_m: f64,
    /// True when the bed came from the cache.
    pub from_cache: bool,
    /// What went wrong on the way that the run should report (a cache entry
    /// that could not be read and was rebuilt, say).
    pub warnings: Vec<RunWarning>,
}

/// The settling law between two materials, at `stiffness_factor` of their
/// Young's moduli.
pub fn settling_law(a: &Material, b: &Material, stiffness_factor: f64) -> ContactLaw {
    let soften = |m: &Material| Material {
        youngs_pa: m.youngs_pa * stiffness_factor,
        ..*m
    };
    ContactLaw::from_spec(
        &soften(a),
        &soften(b),
        &ContactParams {
            restitution: SETTLE_RESTITUTION,
            friction: SETTLE_FRICTION,
            mode: RestitutionMode::Exact,
        },
    )
}

/// The settling laws of `scene` (particle-particle, particle-wall).
fn settling_laws(scene: &Scene, stiffness_factor: f64) -> (ContactLaw, ContactLaw) {
    let pm = scene.particle_material();
    let wm = scene.wall_material();
    (
        settling_law(&pm, &pm, stiffness_factor),
        settling_law(&pm, &wm, stiffness_factor),
    )
}

/// Time step (s) that resolves every contact of the laws at `speed_mps` with
/// `steps` steps, and stays below a quarter of the Rayleigh step of the
/// particles' material at the laws' stiffness (thesis eq. 3.31).
fn resolving_step_s(
    pp: &ContactLaw,
    pw: &ContactLaw,
    scene: &Scene,
    stiffness_factor: f64,
    speed_mps: f64,
    steps: f64,
) -> f64 {
    let pm = scene.particle_material();
    let soft = Material {
        youngs_pa: pm.youngs_pa * stiffness_factor,
        ..pm
    };
    let scale = scene.contact_scale();
    let rayleigh = rayleigh_time_step_s(&soft, scale.radius_m);
    let contact = shortest_contact_with_mass_s(
        pp,
        pw,
        scale.radius_m,
        scale.mass_kg,
        speed_mps * scale.speed_factor,
    );
    (contact / steps).min(0.25 * rayleigh)
}

/// Pours, closes, turns and settles the damper of `scene` with its seed and
/// the settling law (see the module documentation).
pub fn settle_bed(
    scene: &Scene,
    progress: &mut dyn FnMut(Progress),
) -> Result<SettledBed, SceneError> {
    let started = Stopwatch::start();
    // 1. Pour under the soft law, resolving the fastest fall the column allows.
    let mut world = pour(scene, started, progress)?;
    let Packing {
        fraction: packing_fraction,
        bed_height_m,
    } = packing(&world, scene);

    // 2. Close the lid, as a piston where spheres stand above it.
    close_lid(&mut world, scene, started, progress)?;

    // 3. Turn to the test orientation and settle again.
    turn(&mut world, scene, started, progress)?;

    // 4. Stiffen to the particles' own stiffness in geometric stages, so that
    //    the overlaps shrink a little at a time instead of springing apart.
    stiffen(&mut world, scene, started, progress)?;
    Ok(SettledBed {
        settle_time_s: world.time_s,
        settle_steps: world.steps,
        world,
        wall_time_s: started.elapsed().as_secs_f64(),
        packing_fraction,
        bed_height_m,
        from_cache: false,
        warnings: Vec::new(),
    })
}

/// Step 1 of [`settle_bed`]: the spheres inserted in the pour column and
/// poured under the soft settling law, frictionless for
/// [`POUR_SLIDING_FALLS`] fall times and then with the settling friction
/// until at rest.
fn pour(
    scene: &Scene,
    started: Stopwatch,
    progress: &mut dyn FnMut(Progress),
) -> Result<World, SceneError> {
    let radius = scene.radius_m();
    let cyl_r = 0.5 * scene.enclosure.inner_diameter_m;
    let g = scene.simulation.gravity_mps2;
    let mut rng = SceneRng::new(scene.simulation.seed);
    let body = scene.particle_body()?;
    let reach_m = body.as_ref().map_or(radius, |b| b.bounding_radius_m);
    let (positions, column) = pour_column(scene, reach_m, &mut rng)?;
    let density = scene.particle_material().density_kgm3;
    let mut particles = Particles::default();
    for p in positions {
        match &body {
            // A body falls from a random orientation.
            Some(b) => {
                let q = random_orientation(&mut rng);
                particles.push_clump(&b.template, (p, q), (DVec3::ZERO, DVec3::ZERO));
            }
            None => {
                particles.push(p, DVec3::ZERO, DVec3::ZERO, radius, density);
            }
        }
    }
    let (pp, pw) = settling_laws(scene, SETTLE_STIFFNESS_FACTOR);
    let fall_mps = (2.0 * g * column).sqrt().max(0.1);
    let dt_soft = resolving_step_s(
        &pp,
        &pw,
        scene,
        SETTLE_STIFFNESS_FACTOR,
        fall_mps,
        SETTLE_STEPS_PER_CONTACT,
    );
    let mut numerics = Numerics::with_dt(dt_soft);
    numerics.parallel_min_pairs = scene.simulation.parallel_min_pairs;
    if let Some(skin) = scene.body_skin_ratio() {
        numerics.skin_ratio = skin;
    }
    let mut world = World::new(
        particles,
        Walls::closed_cylinder(cyl_r, column),
        pp,
        pw,
        gravity_vector(Orientation::Vertical, g),
        numerics,
    )?;
    world.set_step_threads(scene.simulation.step_threads);
    let fall_s = if g > 0.0 {
        (2.0 * column / g).sqrt()
    } else {
        0.0
    };
    // Frictionless while the spheres land and slide into place (a dense bed),
    // then with the settling friction, which stops the sliding.
    let (pp_rough, pw_rough) = (world.pp_law, world.pw_law);
    world.set_contact_laws(pp_rough.without_friction(), pw_rough.without_friction())?;
    run_steps(
        &mut world,
        POUR_SLIDING_FALLS * fall_s,
        "pouring",
        started,
        progress,
    )?;
    world.set_contact_laws(pp_rough, pw_rough)?;
    run_until_rest(&mut world, 0.0, MAX_POUR_S, "pouring", started, progress)?;
    Ok(world)
}

/// Step 3 of [`settle_bed`]: gravity turned to the test orientation, and the
/// bed settled again if that turned it.
fn turn(
    world: &mut World,
    scene: &Scene,
    started: Stopwatch,
    progress: &mut dyn FnMut(Progress),
) -> Result<(), SceneError> {
    let g = scene.simulation.gravity_mps2;
    world.gravity = gravity_vector(scene.enclosure.orientation, g);
    world.rebaseline();
    if scene.enclosure.orientation != Orientation::Vertical {
        run_until_rest(
            world,
            0.0,
            scene.simulation.settle_s.max(MAX_POUR_S),
            "turning",
            started,
            progress,
        )?;
    }
    Ok(())
}

/// Step 4 of [`settle_bed`]: the settling law stiffened to the particles'
/// own stiffness in [`RELAX_STAGES`] geometric stages, the bed at rest after
/// each.
fn stiffen(
    world: &mut World,
    scene: &Scene,
    started: Stopwatch,
    progress: &mut dyn FnMut(Progress),
) -> Result<(), SceneError> {
    let (pp_full, pw_full) = settling_laws(scene, 1.0);
    let stages = RELAX_STAGES;
    for k in 1..=stages {
        let factor = maths::powf(SETTLE_STIFFNESS_FACTOR, 1.0 - k as f64 / stages as f64);
        let (pp, pw) = (
            pp_full.with_stiffness_scaled(factor),
            pw_full.with_stiffness_scaled(factor),
        );
        let dt = resolving_step_s(&pp, &pw, scene, factor, 0.1, SETTLE_STEPS_PER_CONTACT);
        world.set_contact_laws(pp, pw)?;
        world.set_dt_s(dt);
        run_until_rest(
            world,
            0.0,
            scene.simulation.settle_s.max(MAX_RELAX_S),
            "settling",
            started,
            progress,
        )?;
    }
    Ok(())
}

/// The world of a settled bed rebuilt from its particles' state (a bed read
/// back from the cache): the closed enclosure, the stiff settling law, the
/// test orientation's gravity and time step `dt_s`. Every contact is
/// re-detected, as [`prepare_drive`] does anyway, so a drive from this world
/// is the same, bit for bit, as one from the world the bed settled in.
pub fn rebuild_settled_world(
    scene: &Scene,
    particles: Particles,
    dt_s: f64,
) -> Result<World, SceneError> {
    let (pp, pw) = settling_laws(scene, 1.0);
    let mut numerics = Numerics::with_dt(dt_s);
    numerics.parallel_min_pairs = scene.simulation.parallel_min_pairs;
    if let Some(skin) = scene.body_skin_ratio() {
        numerics.skin_ratio = skin;
    }
    let mut world = World::new(
        particles,
        Walls::closed_cylinder(
            0.5 * scene.enclosure.inner_diameter_m,
            scene.enclosure.inner_length_m,
        ),
        pp,
        pw,
        gravity_vector(scene.enclosure.orientation, scene.simulation.gravity_mps2),
        numerics,
    )?;
    world.set_step_threads(scene.simulation.step_threads);
    Ok(world)
}

/// Random positions in a pouring column of the enclosure's diameter, and the
/// column's height (m): at [`COLUMN_FILL`], or taller until every sphere fits
/// (narrow cylinders jam sooner).
fn pour_column(
    scene: &Scene,
    radius: f64,
    rng: &mut SceneRng,
) -> Result<(Vec<DVec3>, f64), SceneError> {
    let cyl_r = 0.5 * scene.enclosure.inner_diameter_m;
    let length = scene.enclosure.inner_length_m;
    let n = scene.particles.count;
    let mut fill = COLUMN_FILL;
    loop {
        let column = (n as f64 * scene.particle_volume_m3() / (fill * PI * cyl_r * cyl_r))
            .max(length)
            .max(4.0 * radius);
        match insert_in_cylinder(n, radius, cyl_r, column, 1e-3 * radius, rng) {
            Ok(p) => return Ok((p, column)),
            Err(SceneError::Insertion { .. }) if fill > 0.02 => fill *= 0.7,
            Err(e) => return Err(e),
        }
    }
}

/// Lowers the lid of the pouring column to the enclosure's length: at once when
/// no sphere reaches above it, else as a piston at [`PISTON_SPEED_MPS`] while
/// the bed rearranges under the settling law.
fn close_lid(
    world: &mut World,
    scene: &Scene,
    started: Stopwatch,
    progress: &mut dyn FnMut(Progress),
) -> Result<(), SceneError> {
    const LID: usize = 2;
    let length = scene.enclosure.inner_length_m;
    let top = top_of_bed(world);
    if top <= length {
        world.walls.move_plane(LID, DVec3::new(0.0, 0.0, length));
        world.refresh_wall_gaps();
        world.rebaseline();
        return Ok(());
    }
    // Frictionless while the lid pushes: spheres slide into the gaps below
    // them, as a tapped or vibrated fill does.
    let rest_overlap = world.max_overlap_ratio();
    // Packing of the whole poured bed, floor to the top of its highest sphere.
    let area = PI * (0.5 * scene.enclosure.inner_diameter_m).powi(2);
    let poured = scene.particles.count as f64 * scene.particle_volume_m3() / (area * top);
    let (pp, pw) = (world.pp_law, world.pw_law);
    world.set_contact_laws(pp.without_friction(), pw.without_friction())?;
    let dt = world.dt_s();
    let mut z = top + 1e-3 * scene.radius_m();
    let drop = PISTON_SPEED_MPS * dt;
    let n = world.particles.len() as u64;
    let steps = ((z - length) / drop).ceil() as u64;
    // The lid is moved by hand, not as the enclosure's displacement, so its
    // work is in no ledger: the energy check waits until it has stopped.
    let check = world.numerics.energy_check_steps;
    world.numerics.energy_check_steps = u64::MAX;
    for k in 1..=steps {
        z = (z - drop).max(length);
        world.walls.move_plane(LID, DVec3::new(0.0, 0.0, z));
        world.refresh_wall_gaps();
        world.step(0.0).map_err(|e| crushed(e, poured, scene))?;
        if k % 1000 == 0 {
            progress(Progress {
                phase: "closing",
                fraction: k as f64 / steps as f64,
                sim_time_s: world.time_s,
                particle_steps: world.steps * n,
                wall_time_s: started.elapsed().as_secs_f64(),
                ..Progress::default()
            });
        }
    }
    world.numerics.energy_check_steps = check;
    world.set_contact_laws(pp, pw)?;
    run_until_rest(world, 0.0, MAX_POUR_S, "closing", started, progress).map_err(|e| match e {
        SceneError::Dem(d) => crushed(d, poured, scene),
        other => other,
    })?;
    // A bed the lid holds down harder than its own weight did is crushed, not
    // closed: its overlaps would become forces a hundred times larger at the
    // particles' own stiffness.
    let squeeze = world.max_overlap_ratio();
    let limit = CLOSED_SQUEEZE_FACTOR * rest_overlap;
    if squeeze > limit {
        return Err(crushed(
            DemError::ExcessiveOverlap {
                time_s: world.time_s,
                step: world.steps,
                contact: "closed bed".into(),
                overlap_percent: 100.0 * squeeze,
                limit_percent: 100.0 * limit,
                speed_mps: 0.0,
                dt_s: world.dt_s(),
            },
            poured,
            scene,
        ));
    }
    Ok(())
}

/// The refusal of a bed the lid cannot close on; `poured` is the packing
/// fraction of the whole poured bed before the lid pushed it.
fn crushed(e: DemError, poured: f64, scene: &Scene) -> SceneError {
    match e {
        DemError::ExcessiveOverlap { .. } | DemError::Escaped { .. } => {
            let cause = match &e {
                DemError::ExcessiveOverlap {
                    overlap_percent,
                    limit_percent,
                    ..
                } => format!(
                    "pushed down to it, the bed is squeezed: a contact overlaps by {overlap_percent:.2} % of a radius, more than {limit_percent:.2} %"
                ),
                other => other.to_string(),
            };
            SceneError::DoesNotFit {
                fill: scene.fill_ratio(),
                reached: poured,
                cause,
            }
        }
        other => SceneError::Dem(other),
    }
}

/// Height of the top of the highest sphere above the floor (m), along the axis.
fn top_of_bed(world: &World) -> f64 {
    let p = &world.particles;
    (0..p.len())
        .map(|i| p.position[i].z + p.radius[i])
        .fold(0.0, f64::max)
}

/// How a poured bed packs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Packing {
    /// Packing fraction of the bulk of the bed.
    pub fraction: f64,
    /// Height the particles' volume fills at that packing (m).
    pub bed_height_m: f64,
}

/// Packing fraction of the bulk of a bed poured along the axis (z), and the
/// height its particles' volume fills at that packing.
///
/// A body's volume is its union's (its mass over the density), shared
/// between heights as its sub-spheres' volumes are: their sum counts the
/// overlaps several times over.
pub fn packing(world: &World, scene: &Scene) -> Packing {
    let p = &world.particles;
    let area = PI * (0.5 * scene.enclosure.inner_diameter_m).powi(2);
    let density = scene.particle_material().density_kgm3;
    let c = &p.clumps;
    // Each sphere's share of its particle's volume: 1 for a free sphere,
    // the body's union over its sub-spheres' sum for a sub-sphere.
    let mut share = vec![1.0; p.len()];
    for b in 0..c.len() {
        let slots = c.slots(b);
        let summed: f64 = slots
            .clone()
            .map(|s| 4.0 / 3.0 * PI * p.radius[c.index[s] as usize].powi(3))
            .sum();
        for s in slots {
            share[c.index[s] as usize] = c.mass[b] / density / summed;
        }
    }
    let v_p: f64 = (0..p.len())
        .map(|i| share[i] * 4.0 / 3.0 * PI * p.radius[i].powi(3))
        .sum();
    let d = 2.0 * scene.radius_m();
    let top = top_of_bed(world);
    let (lo, hi) = (d, top - d);
    if hi - lo < d {
        // Too shallow for a bulk: the whole bed up to its top.
        let phi = v_p / (area * top.max(f64::MIN_POSITIVE));
        return Packing {
            fraction: phi,
            bed_height_m: top,
        };
    }
    let inside: f64 = (0..p.len())
        .map(|i| share[i] * sphere_volume_between(p.position[i].z, p.radius[i], lo, hi))
        .sum();
    let phi = inside / (area * (hi - lo));
    Packing {
        fraction: phi,
        bed_height_m: v_p / (area * phi),
    }
}

/// Volume of a sphere of radius `r` centred at height `z` between the planes
/// `lo` and `hi` (m³): the difference of two caps.
fn sphere_volume_between(z: f64, r: f64, lo: f64, hi: f64) -> f64 {
    // Volume of the sphere below height `h`.
    let below = |h: f64| {
        let x = (h - (z - r)).clamp(0.0, 2.0 * r);
        PI * x * x * (3.0 * r - x) / 3.0
    };
    below(hi) - below(lo)
}

/// Steps a still enclosure for at least `min_s` and at most `max_s` of
/// simulated time, stopping once the bed is at rest; not coming to rest is an
/// error.
fn run_until_rest(
    world: &mut World,
    min_s: f64,
    max_s: f64,
    phase: &'static str,
    started: Stopwatch,
    progress: &mut dyn FnMut(Progress),
) -> Result<(), SceneError> {
    let dt = world.dt_s();
    let max_steps = (max_s / dt).round() as u64;
    let min_steps = (min_s / dt).round() as u64;
    let check_every = ((1e-3 / dt).round() as u64).max(1);
    let displacement = world.walls.displacement_m;
    if world.particles.is_empty() {
        return Ok(());
    }
    for k in 1..=max_steps {
        world.step(displacement)?;
        if k % check_every == 0 {
            progress(settling_progress(world, phase, k, max_steps, started));
            if k >= min_steps && at_rest(world) {
                return Ok(());
            }
        }
    }
    // Still moving: the contact law has no rolling resistance, so a sphere
    // rolling on a floor it does not cover (a bed of a few particles) rolls
    // on. As long again with a brake on the motion across gravity and on
    // the spin, which a bed that came to rest above never meets (its bits
    // are unchanged) and which leaves falling and bouncing alone.
    let down = world.gravity.normalize_or_zero();
    let braked = down != DVec3::ZERO;
    if braked {
        let factor = 1.0 - dt / ROLLING_BRAKE_S;
        for k in 1..=max_steps {
            world.step(displacement)?;
            world.particles.brake_across(down, factor);
            if k % check_every == 0 {
                progress(settling_progress(world, phase, k, max_steps, started));
                if at_rest(world) {
                    return Ok(());
                }
            }
        }
    }
    let p = &world.particles;
    let (kt, kr) = p.kinetic_energy_j();
    Err(SceneError::NotAtRest {
        phase,
        time_s: if braked { 2.0 * max_s } else { max_s },
        braked,
        rms_speed_mps: (2.0 * (kt + kr) / p.total_mass_kg()).sqrt(),
        rest_mps: (REST_KINETIC_FRACTION
            * 2.0
            * world.gravity.length().max(1.0)
            * 2.0
            * p.max_radius_m())
        .sqrt(),
    })
}

/// True when the bed's kinetic energy (translational and rotational) is below
/// [`REST_KINETIC_FRACTION`] of what lifting it by one diameter would take,
/// `M g d`: an RMS speed of about 3 mm/s for any size of sphere in earth's
/// gravity. A few spheres still finding their place do not hold up the run.
pub fn at_rest(world: &World) -> bool {
    let p = &world.particles;
    let (kt, kr) = p.kinetic_energy_j();
    let g = world.gravity.length().max(1.0);
    let scale = p.total_mass_kg() * g * 2.0 * p.max_radius_m();
    kt + kr < REST_KINETIC_FRACTION * scale
}

/// Steps a still enclosure for `duration_s`.
fn run_steps(
    world: &mut World,
    duration_s: f64,
    phase: &'static str,
    started: Stopwatch,
    progress: &mut dyn FnMut(Progress),
) -> Result<(), SceneError> {
    let dt = world.dt_s();
    let steps = (duration_s / dt).round() as u64;
    let displacement = world.walls.displacement_m;
    let report_every = ((1e-3 / dt).round() as u64).max(1);
    for k in 1..=steps {
        world.step(displacement)?;
        if k % report_every == 0 {
            progress(settling_progress(world, phase, k, steps, started));
        }
    }
    Ok(())
}

/// Where a settling `phase` stands after step `k` of `steps`.
fn settling_progress(
    world: &World,
    phase: &'static str,
    k: u64,
    steps: u64,
    started: Stopwatch,
) -> Progress {
    Progress {
        phase,
        fraction: k as f64 / steps as f64,
        sim_time_s: world.time_s,
        particle_steps: world.steps * world.particles.len() as u64,
        wall_time_s: started.elapsed().as_secs_f64(),
        ..Progress::default()
    }
}

/// Makes a settled bed ready to drive: the scene's contact laws (every
/// tangential history dropped; a bed under them already keeps its
/// histories), the test time step `dt_s`, the energy ledger started.
pub fn prepare_drive(bed: &SettledBed, scene: &Scene, dt_s: f64) -> Result<World, SceneError> {
    let mut world = bed.world.clone();
    let laws = contact_laws(scene);
    // A bed a drive left (a carried sweep's) is under the drive's laws
    // already: its contacts' histories are part of its state and stay.
    if world.pp_law != laws.particle_particle || world.pw_law != laws.particle_wall {
        world.set_contact_laws(laws.particle_particle, laws.particle_wall)?;
    }
    world.set_dt_s(dt_s);
    world.numerics.parallel_min_pairs = scene.simulation.parallel_min_pairs;
    world.set_step_threads(scene.simulation.step_threads);
    world.start_ledger();
    Ok(world)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dem::timestep::shortest_contact_s;

    #[test]
    fn cap_volumes_add_up() {
        let r: f64 = 0.002;
        let whole = 4.0 / 3.0 * PI * r.powi(3);
        assert!((sphere_volume_between(0.0, r, -1.0, 1.0) - whole).abs() < 1e-18);
        assert!((sphere_volume_between(0.0, r, 0.0, 1.0) - 0.5 * whole).abs() < 1e-18);
        assert_eq!(sphere_volume_between(0.0, r, 0.01, 0.02), 0.0);
        let a = sphere_volume_between(0.0, r, -1.0, 0.0007);
        let b = sphere_volume_between(0.0, r, 0.0007, 1.0);
        assert!((a + b - whole).abs() < 1e-18);
    }

    #[test]
    fn the_settling_law_is_soft_dissipative_and_slightly_rough() {
        let m = Material::ACRYLIC;
        let soft = settling_law(&m, &m, SETTLE_STIFFNESS_FACTOR);
        let stiff = settling_law(&m, &m, 1.0);
        assert!((soft.e_star_pa / stiff.e_star_pa - 0.01).abs() < 1e-12);
        assert!(soft.has_friction());
        assert!(!soft.without_friction().has_friction());
        assert_eq!(soft.restitution, SETTLE_RESTITUTION);
        // A soft contact lasts 0.01^(-2/5) = 6.3 times longer.
        let (r, rho) = (0.0025, m.density_kgm3);
        let ratio = shortest_contact_s(&soft, &soft, r, rho, 1.0)
            / shortest_contact_s(&stiff, &stiff, r, rho, 1.0);
        assert!((ratio - 0.01f64.powf(-0.4)).abs() < 1e-9, "{ratio}");
    }

    /// Two elastic, frictionless spheres bouncing in a weightless cylinder
    /// never come to rest: after the allowed time the run stops with
    /// `NotAtRest`, naming the phase, the time, the bed's RMS speed (that of
    /// the world it left, to 1e-12) and the rest threshold (sqrt(1e-4 x 2 x
    /// 1 m/s^2 x 5 mm) = 1 mm/s; gravity below 1 m/s^2 counts as 1).
    #[test]
    fn a_bed_that_keeps_moving_is_not_at_rest() {
        let m = Material::ACRYLIC;
        let r = 0.0025;
        let mut p = Particles::default();
        for (x, v) in [(-0.004, 0.5), (0.004, -0.5)] {
            p.push(
                DVec3::new(x, 0.0, 0.01),
                DVec3::new(v, 0.0, 0.0),
                DVec3::ZERO,
                r,
                m.density_kgm3,
            );
        }
        let law = ContactLaw::new(&m, &m, 1.0, 0.0, RestitutionMode::Exact);
        let mut world = World::new(
            p,
            Walls::closed_cylinder(0.01, 0.02),
            law,
            law,
            DVec3::ZERO,
            Numerics::with_dt(1e-6),
        )
        .expect("a valid world");
        let err = run_until_rest(
            &mut world,
            0.0,
            0.01,
            "pouring",
            Stopwatch::start(),
            &mut |_| {},
        )
        .expect_err("elastic spheres never rest");
        let msg = err.to_string();
        let SceneError::NotAtRest {
            phase,
            time_s,
            rms_speed_mps,
            rest_mps,
            ..
        } = &err
        else {
            panic!("another error: {msg}");
        };
        assert_eq!(*phase, "pouring");
        // Without gravity nothing rolls on a floor: no brake.
        assert_eq!(*time_s, 0.01);
        let (kt, kr) = world.particles.kinetic_energy_j();
        let rms = (2.0 * (kt + kr) / world.particles.total_mass_kg()).sqrt();
        assert!((rms_speed_mps / rms - 1.0).abs() < 1e-12, "{rms_speed_mps}");
        assert!(*rms_speed_mps > 0.4, "the spheres keep their speed");
        assert!((rest_mps - 1e-3).abs() < 1e-12, "{rest_mps}");
        for part in [
            "did not come to rest while pouring",
            "after 0.01 s of settling the particles",
            "m/s RMS",
            "below 0.0010 m/s",
        ] {
            assert!(msg.contains(part), "'{msg}' lacks '{part}'");
        }
    }
}
