//! The damper experiment: fill the enclosure, let the bed settle, drive it.
//!
//! Filling follows the lab: the spheres are poured into a taller column of the
//! enclosure's diameter (random sequential insertion at a fill of 0.30, see
//! `fill`), settle with the axis vertical, the lid is closed at the design length,
//! the damper is turned to its test orientation and the bed settles again (thesis:
//! 0.2 s, ended early once the bed is at rest). Then the enclosure is driven along
//! its axis, by a prescribed sine `u = Γ g / ω² sin ωt` ([`SineMotion`], thesis
//! eq. 6.2) or by any other [`EnclosureMotion`] (the rig's shaker), for whole
//! cycles, and the energy
//! ledger is read at every cycle boundary.
//!
//! Efficiency (thesis eq. 6.8–6.10, erratum for 6.9: the numerator is
//! `E(t_final) - E(t_initial)`): the energy dissipated per cycle, averaged over
//! the steady cycles, divided by `E_max = 4 (Γ g / ω)² M`.

use std::f64::consts::PI;
use std::time::Instant;

use glam::DVec3;

use crate::dem::{
    ContactLaw, Dissipation, ImpactSpeeds, LedgerBalance, LedgerSnapshot, Numerics, Particles,
    Walls, World,
};
pub use crate::rig::{EnclosureMotion, Kinematics, SineMotion};
use crate::scene::file::{Orientation, Scene, SceneError};
use crate::scene::fill::{COLUMN_FILL, SceneRng, insert_in_cylinder};

/// A bed is at rest when no particle is faster than this (m/s).
pub const REST_SPEED_MPS: f64 = 0.005;
/// Longest the poured column may take to come to rest (s).
pub const MAX_POUR_S: f64 = 1.5;

/// Progress of a long run, for display.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Progress {
    pub phase: &'static str,
    /// Fraction of the phase done, 0..1.
    pub fraction: f64,
    pub sim_time_s: f64,
    pub particle_steps: u64,
    pub wall_time_s: f64,
}

/// Something that wants to see every step of the drive (a recorder, a rig).
pub trait StepObserver {
    /// Called after each step, `t_s` from the start of the drive.
    fn observe(&mut self, t_s: f64, world: &World, enclosure: &Kinematics);
}

/// An observer that records nothing.
pub struct NoObserver;

impl StepObserver for NoObserver {
    fn observe(&mut self, _t_s: f64, _world: &World, _enclosure: &Kinematics) {}
}

/// The contact laws of a scene.
pub fn contact_laws(scene: &Scene) -> (ContactLaw, ContactLaw) {
    let pm = scene.particle_material();
    let wm = scene.wall_material();
    let c = &scene.contact;
    let pp = c.particle_particle;
    let pw = c.particle_wall;
    (
        ContactLaw::new(&pm, &pm, pp.restitution, pp.friction, c.restitution_mode),
        ContactLaw::new(&pm, &wm, pw.restitution, pw.friction, c.restitution_mode),
    )
}

/// Gravity vector for an orientation; the enclosure axis is z.
pub fn gravity_vector(orientation: Orientation, g_mps2: f64) -> DVec3 {
    match orientation {
        Orientation::Vertical => DVec3::new(0.0, 0.0, -g_mps2),
        Orientation::Horizontal => DVec3::new(0.0, -g_mps2, 0.0),
    }
}

/// A settled bed in the closed enclosure, ready to drive.
#[derive(Debug, Clone)]
pub struct SettledBed {
    pub world: World,
    /// Simulated time spent pouring and settling (s).
    pub settle_time_s: f64,
    /// Wall-clock time spent (s).
    pub wall_time_s: f64,
}

/// Pours, settles and closes the damper of `scene` with its seed; see the module
/// documentation. `dt_s` overrides the scene's time step.
pub fn settle_bed(
    scene: &Scene,
    dt_s: f64,
    progress: &mut dyn FnMut(Progress),
) -> Result<SettledBed, SceneError> {
    let started = Instant::now();
    let radius = scene.radius_m();
    let cyl_r = 0.5 * scene.enclosure.inner_diameter_m;
    let length = scene.enclosure.inner_length_m;
    let n = scene.particles.count;
    let column =
        (n as f64 * scene.particle_volume_m3() / (COLUMN_FILL * PI * cyl_r * cyl_r)).max(length);
    let mut rng = SceneRng::new(scene.simulation.seed);
    let positions = insert_in_cylinder(n, radius, cyl_r, column, 1e-3 * radius, &mut rng)?;
    let density = scene.particle_material().density_kgm3;
    let mut particles = Particles::default();
    for p in positions {
        particles.push(p, DVec3::ZERO, DVec3::ZERO, radius, density);
    }
    let (pp, pw) = contact_laws(scene);
    let g = scene.simulation.gravity_mps2;
    let mut numerics = Numerics::with_dt(dt_s);
    numerics.parallel_min_pairs = scene.simulation.parallel_min_pairs;
    let mut world = World::new(
        particles,
        Walls::closed_cylinder(cyl_r, column),
        pp,
        pw,
        gravity_vector(Orientation::Vertical, g),
        numerics,
    )?;

    // Pour: axis vertical, until the bed is at rest (at least the fall time).
    let fall_s = if g > 0.0 {
        (2.0 * column / g).sqrt()
    } else {
        0.0
    };
    run_until_rest(&mut world, fall_s, MAX_POUR_S, "pouring", started, progress)?;

    // Close the lid at the design length.
    let top = (0..world.particles.len())
        .map(|i| world.particles.position[i].z + world.particles.radius[i])
        .fold(0.0, f64::max);
    if top > length {
        return Err(SceneError::BedTooTall {
            height_mm: top * 1e3,
            length_m: length,
        });
    }
    world.walls.move_plane(2, DVec3::new(0.0, 0.0, length));
    world.refresh_wall_gaps();

    // Turn to the test orientation and settle again.
    world.gravity = gravity_vector(scene.enclosure.orientation, g);
    world.rebaseline();
    run_until_rest(
        &mut world,
        0.0,
        scene.simulation.settle_s,
        "settling",
        started,
        progress,
    )?;
    Ok(SettledBed {
        settle_time_s: world.time_s,
        world,
        wall_time_s: started.elapsed().as_secs_f64(),
    })
}

/// Steps a still enclosure for at least `min_s` and at most `max_s` of simulated
/// time, stopping once the bed is at rest.
fn run_until_rest(
    world: &mut World,
    min_s: f64,
    max_s: f64,
    phase: &'static str,
    started: Instant,
    progress: &mut dyn FnMut(Progress),
) -> Result<(), SceneError> {
    let dt = world.dt_s();
    let max_steps = (max_s / dt).round() as u64;
    let min_steps = (min_s / dt).round() as u64;
    let check_every = ((1e-3 / dt).round() as u64).max(1);
    let displacement = world.walls.displacement_m;
    let n = world.particles.len() as u64;
    for k in 1..=max_steps {
        world.step(displacement)?;
        if k % check_every == 0 {
            progress(Progress {
                phase,
                fraction: k as f64 / max_steps as f64,
                sim_time_s: world.time_s,
                particle_steps: world.steps * n,
                wall_time_s: started.elapsed().as_secs_f64(),
            });
            if k >= min_steps && world.particles.max_speed_mps() < REST_SPEED_MPS {
                break;
            }
        }
    }
    Ok(())
}

/// How the drive is run.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DrivePlan {
    pub freq_hz: f64,
    pub gamma: f64,
    pub gravity_mps2: f64,
    pub cycles: u32,
    pub steady_cycles: u32,
}

impl DrivePlan {
    /// Maximum energy dissipated per cycle (J), thesis eq. 6.10: 4 (Γ g / ω)² M.
    pub fn e_max_j(&self, particle_mass_kg: f64) -> f64 {
        let v = self.gamma * self.gravity_mps2 / (2.0 * PI * self.freq_hz);
        4.0 * v * v * particle_mass_kg
    }
}

/// DEM truth of a drive.
#[derive(Debug, Clone, PartialEq)]
pub struct DriveOutcome {
    /// Ledger at the drive start and at the end of every cycle.
    pub cycle_snapshots: Vec<LedgerSnapshot>,
    /// Balance of the whole drive (transient and steady cycles).
    pub whole: LedgerBalance,
    /// Balance of the steady cycles.
    pub steady: LedgerBalance,
    /// Dissipated energy per cycle in the steady window (J), thesis eq. 6.9.
    pub energy_per_cycle_j: f64,
    /// Per-cycle dissipation by source in the steady window (J).
    pub dissipated_per_cycle: Dissipation,
    /// Work the walls did per cycle in the steady window (J): what a
    /// measurement of input power sees; it differs from the dissipation by the
    /// change of stored energy over the window.
    pub work_in_per_cycle_j: f64,
    /// Length of the steady window (s).
    pub steady_window_s: f64,
    pub e_max_j: f64,
    pub efficiency: f64,
    pub steps: u64,
    pub wall_time_s: f64,
    /// Start of the steady window, from the drive start (s).
    pub steady_start_s: f64,
    pub largest_speed_mps: f64,
    /// Largest normal approach speeds at contact onset during the drive (m/s).
    pub impact_speeds: ImpactSpeeds,
}

/// Drives a settled world with `motion` for `plan.cycles` cycles.
pub fn run_drive(
    world: &mut World,
    plan: &DrivePlan,
    motion: &mut dyn EnclosureMotion,
    observer: &mut dyn StepObserver,
    progress: &mut dyn FnMut(Progress),
) -> Result<DriveOutcome, SceneError> {
    let started = Instant::now();
    let dt = world.dt_s();
    let period = 1.0 / plan.freq_hz;
    let t0 = world.time_s;
    let n = world.particles.len() as u64;
    let first_step = world.steps;
    world.impact_speeds = ImpactSpeeds::default();
    let mut snapshots = vec![world.snapshot()];
    let mut largest_speed: f64 = 0.0;
    let report_every = ((2e-3 / dt).round() as u64).max(1);
    let total_steps = (plan.cycles as f64 * period / dt).round() as u64;
    let mut next_boundary = 1u32;
    let mut k = 0u64;
    while next_boundary <= plan.cycles {
        k += 1;
        let t = k as f64 * dt;
        let axial = -world.wall_force().dot(world.walls.axis);
        let kin = motion.advance(t, dt, axial);
        world.step(kin.displacement_m)?;
        observer.observe(t, world, &kin);
        // A cycle ends at the step nearest to its boundary time.
        if (t / period - next_boundary as f64) * period > -0.5 * dt {
            snapshots.push(world.snapshot());
            largest_speed = largest_speed.max(world.particles.max_speed_mps());
            next_boundary += 1;
        }
        if k % report_every == 0 {
            progress(Progress {
                phase: "driving",
                fraction: k as f64 / total_steps as f64,
                sim_time_s: world.time_s - t0,
                particle_steps: k * n,
                wall_time_s: started.elapsed().as_secs_f64(),
            });
        }
    }
    let last = snapshots.len() - 1;
    let steady_first = last - plan.steady_cycles as usize;
    let whole = LedgerBalance::between(&snapshots[0], &snapshots[last]);
    let steady = LedgerBalance::between(&snapshots[steady_first], &snapshots[last]);
    let window_s = snapshots[last].time_s - snapshots[steady_first].time_s;
    let per_cycle = period / window_s;
    let energy_per_cycle_j = steady.dissipated_j * per_cycle;
    let e_max_j = plan.e_max_j(world.particles.total_mass_kg());
    Ok(DriveOutcome {
        whole,
        steady,
        energy_per_cycle_j,
        dissipated_per_cycle: steady.dissipated.scaled(per_cycle),
        work_in_per_cycle_j: steady.work_in_j * per_cycle,
        steady_window_s: window_s,
        e_max_j,
        efficiency: energy_per_cycle_j / e_max_j,
        steps: world.steps - first_step,
        wall_time_s: started.elapsed().as_secs_f64(),
        steady_start_s: snapshots[steady_first].time_s - t0,
        cycle_snapshots: snapshots,
        largest_speed_mps: largest_speed,
        impact_speeds: world.impact_speeds,
    })
}
