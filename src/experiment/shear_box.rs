//! The quasi-static compression and shear test of a granular bed (Terzioglu's
//! thesis, Section 8.5.1.2, Fig. 8.15–8.19): why the particle shape moves the
//! bouncing-bed onset.
//!
//! **The box.** Two cylindrical containers of the enclosure's diameter
//! (40 mm) and half its length (20 mm) stand on one axis, the lower one open
//! upwards and fixed, the upper one open downwards, 0.5 mm above it; a
//! loading table inside the upper one presses the bed down. Here the
//! containers are rings ([`WallShape::Ring`]) over a floor, and the table a
//! plane across the upper ring: the thesis' "disc shaped table, whose
//! diameter was 19.9 mm" we read as its radius (0.1 mm clear of the 20 mm
//! ring), since a disc of 19.9 mm across would press a quarter of the bed.
//! The particles are those of the scene, settled into the box as a damper's
//! bed is (poured, closed, at rest under the settling law), then under the
//! scene's contact laws.
//!
//! **The tests.** The table comes down under force control until it holds
//! the pre-load `F_test,0` steadily (10 N for the normal test, 50 N for the
//! shear test); `z_test,0` is how far it moved from first touching the bed.
//! Then, at a constant speed:
//! - **normal**: the table moves down by `z_test`; the force is the
//!   reaction on the fixed container's base, `F_test,z` (the floor's force on
//!   the particles, upward);
//! - **shear**: the upper container (ring and table) moves across by
//!   `x_test` while the table keeps the pre-load (a constant normal load, as
//!   in a direct shear test; the thesis suspends the upper container's
//!   vertical motion and does not say the table moves); the force is the
//!   horizontal reaction on the fixed container (floor and lower ring),
//!   `F_test,x`, in the direction of shearing.
//!
//! Each point of a curve is the force averaged over its stretch of travel,
//! as a load cell's low-pass would give it. The work the moving walls do is
//! booked by the world ([`crate::dem::walls::WallMotion`]), so the energy
//! books close through the test and its energy check guards it.

use crate::clock::Stopwatch;

use glam::DVec3;
use serde::{Deserialize, Serialize};
use thiserror::Error;

use crate::dem::error::DemError;
use crate::dem::walls::{WallShape, Walls};
use crate::dem::world::World;
use crate::experiment::bed::settle::SettledBed;
use crate::experiment::damper::Progress;
use crate::scene::{Orientation, Scene, SceneError, contact_laws};

/// The walls of the box, in the order of [`ShearBox::walls`].
pub const FLOOR: usize = 0;
/// The fixed container's side.
pub const LOWER_RING: usize = 1;
/// The moving container's side.
pub const UPPER_RING: usize = 2;
/// The loading table.
pub const TABLE: usize = 3;

/// The box's geometry.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ShearBox {
    /// Inner radius of both containers (m).
    pub radius_m: f64,
    /// Height of each container (m).
    pub container_height_m: f64,
    /// Gap between the containers (m).
    pub gap_m: f64,
}

impl ShearBox {
    /// The thesis' box (Section 8.5.1.2): 40 mm across, 20 mm high
    /// containers, 0.5 mm apart.
    pub const THESIS: ShearBox = ShearBox {
        radius_m: 0.02,
        container_height_m: 0.02,
        gap_m: 0.0005,
    };

    /// Height of the upper container's open end (m).
    pub fn upper_bottom_m(&self) -> f64 {
        self.container_height_m + self.gap_m
    }

    /// Height of the upper container's closed end (m).
    pub fn top_m(&self) -> f64 {
        self.upper_bottom_m() + self.container_height_m
    }

    /// Floor, lower ring, upper ring and table (at `table_z_m`), at rest.
    pub fn walls(&self, table_z_m: f64) -> Walls {
        Walls::of(
            vec![
                WallShape::Plane {
                    origin: DVec3::ZERO,
                    normal: DVec3::Z,
                },
                WallShape::Ring {
                    radius_m: self.radius_m,
                    z_min_m: 0.0,
                    z_max_m: self.container_height_m,
                },
                WallShape::Ring {
                    radius_m: self.radius_m,
                    z_min_m: self.upper_bottom_m(),
                    z_max_m: self.top_m(),
                },
                WallShape::Plane {
                    origin: DVec3::Z * table_z_m,
                    normal: -DVec3::Z,
                },
            ],
            vec!["floor", "lower ring", "upper ring", "loading table"],
        )
    }

    /// The scene whose settled bed fills the box: `scene`'s particles,
    /// `count` of them, in a vertical enclosure of the box's diameter and
    /// full height.
    pub fn scene(&self, scene: &Scene, count: usize) -> Scene {
        let mut s = scene.clone();
        s.particles.count = count;
        s.enclosure.inner_diameter_m = 2.0 * self.radius_m;
        s.enclosure.inner_length_m = self.top_m();
        s.enclosure.orientation = Orientation::Vertical;
        s
    }
}

/// Which test.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum BoxTest {
    Normal,
    Shear,
}

impl BoxTest {
    /// The thesis' pre-load (N): 10 N for the normal test, 50 N for shear.
    pub fn thesis_preload_n(self) -> f64 {
        match self {
            BoxTest::Normal => 10.0,
            BoxTest::Shear => 50.0,
        }
    }

    /// Its name.
    pub fn as_str(self) -> &'static str {
        match self {
            BoxTest::Normal => "normal",
            BoxTest::Shear => "shear",
        }
    }
}

/// How a test loads the bed.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Loading {
    /// Normal pre-load the table holds (N).
    pub preload_n: f64,
    /// Speed of the loading, and the table's fastest approach (m/s).
    pub speed_mps: f64,
    /// How far the table (normal) or the upper container (shear) moves (m).
    pub travel_m: f64,
    /// Points on the curve.
    pub points: usize,
}

/// One point of a force-displacement curve.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct CurvePoint {
    /// `z_test` or `x_test` at the end of the point's stretch (m).
    pub displacement_m: f64,
    /// `F_test,z` or `F_test,x`, averaged over the stretch (N).
    pub force_n: f64,
    /// The table's force on the bed, averaged over the stretch (N).
    pub table_load_n: f64,
    /// The rings' upward force on the bed (their friction), averaged over
    /// the stretch (N): with the base's, what holds the table's load and
    /// the bed's weight.
    pub rings_up_n: f64,
}

/// What a test measured.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BoxRun {
    pub test: BoxTest,
    pub loading: Loading,
    /// Height of the settled bed's highest particle (m).
    pub bed_top_m: f64,
    /// The bed's weight (N).
    pub weight_n: f64,
    /// `z_test,0`: how far the table moved from first touching the bed to
    /// holding the pre-load steadily (m).
    pub preload_displacement_m: f64,
    /// Simulated time the pre-load took (s).
    pub preload_time_s: f64,
    pub points: Vec<CurvePoint>,
    /// Time step (s).
    pub dt_s: f64,
    /// Steps of the whole test, pre-load included.
    pub steps: u64,
    /// Sphere- (or sub-sphere-) steps per second of wall-clock time.
    pub particle_steps_per_s: f64,
    pub wall_time_s: f64,
    /// Work the walls did on the bed over the test (J), and what it went
    /// to: dissipated in the contacts, and the change of the bed's
    /// mechanical energy (kinetic, potential, elastic).
    pub work_in_j: f64,
    pub dissipated_j: f64,
    pub energy_change_j: f64,
}

/// What can stop a test.
#[derive(Debug, Error)]
pub enum ShearBoxError {
    #[error(transparent)]
    Scene(#[from] SceneError),
    #[error(transparent)]
    Dem(#[from] DemError),
    /// The bed does not reach into the upper container.
    #[error(
        "the settled bed's top stands at {top_m:.4} m, below the upper container's open end at {needed_m:.4} m: {count} particles do not fill the box far enough to be sheared or pressed by the table; use more (particles.count)"
    )]
    TooLow {
        top_m: f64,
        needed_m: f64,
        count: usize,
    },
    /// The table does not fit above the bed.
    #[error(
        "the settled bed's top stands at {top_m:.4} m, too near the box's top at {box_top_m:.4} m for the loading table: use fewer particles (particles.count)"
    )]
    TooHigh { top_m: f64, box_top_m: f64 },
    /// The table did not come to hold the pre-load.
    #[error(
        "the loading table did not hold its pre-load of {preload_n} N within {time_s:.3} s: it held {load_n:.2} N over the last millisecond (steady: within 2 % for {hold_ms} ms)"
    )]
    PreloadNotHeld {
        preload_n: f64,
        time_s: f64,
        load_n: f64,
        hold_ms: f64,
    },
}

/// Clearance between the bed's top and the table where it starts (m).
const START_CLEARANCE_M: f64 = 2.5e-4;
/// The pre-load is held when every millisecond's mean load of this long a
/// stretch is within [`HOLD_TOLERANCE`] of it (s).
const HOLD_S: f64 = 5e-3;
const HOLD_TOLERANCE: f64 = 0.02;
/// The table's force control: its speed per relative shortfall of the load,
/// and its fastest, in loading speeds. With the thesis' 50 N and 5 mm/s the
/// gain is 1e-3 m/s per N: a bed that dilates as fast as it is sheared
/// would hold the load within 10 %, and a contact stiffness of 1e7 N/m
/// moves by 2 % of its force error in a step of 2e-6 s, far from the
/// servo's instability (100 %). At its fastest (50 mm/s) the table follows
/// a bed that slumps in a macro slip as fast as a free fall would for its
/// first 5 ms; at 3 loading speeds, a prolate bed once dropped away from it
/// for a whole point of the curve.
const SERVO_GAIN: f64 = 10.0;
const SERVO_MAX: f64 = 10.0;
/// Window of the load's mean while the pre-load comes on (s).
const WINDOW_S: f64 = 1e-3;

/// Runs one test on `bed`, settled from `scene`, the box's scene
/// ([`ShearBox::scene`]), under its contact laws.
///
/// Over 80 lines: one servo-controlled test, step by step: the pre-load, then
/// the loading and the curve's sampling, all moving the same world, table and
/// servo state; split, every part would take them all.
pub fn run_test(
    bed: &SettledBed,
    scene: &Scene,
    shear_box: &ShearBox,
    test: BoxTest,
    loading: Loading,
    progress: &mut dyn FnMut(Progress),
) -> Result<BoxRun, ShearBoxError> {
    let started = Stopwatch::start();
    let mut world = bed.world.clone();
    let p = &world.particles;
    let bed_top_m = (0..p.len())
        .map(|i| p.position[i].z + p.radius[i])
        .fold(f64::NEG_INFINITY, f64::max);
    if bed_top_m < shear_box.upper_bottom_m() + START_CLEARANCE_M {
        return Err(ShearBoxError::TooLow {
            top_m: bed_top_m,
            needed_m: shear_box.upper_bottom_m(),
            count: scene.particles.count,
        });
    }
    let table_z_m = bed_top_m + START_CLEARANCE_M;
    if table_z_m > shear_box.top_m() - START_CLEARANCE_M {
        return Err(ShearBoxError::TooHigh {
            top_m: bed_top_m,
            box_top_m: shear_box.top_m(),
        });
    }
    let laws = contact_laws(scene);
    world.set_contact_laws(laws.particle_particle, laws.particle_wall)?;
    // The step that resolves a fall across the box: no drive to speak of.
    let drive = scene.drive(1.0, 1e-9).map_err(SceneError::from)?;
    world.set_dt_s(scene.drive_dt_s(&drive));
    world.set_walls(shear_box.walls(table_z_m))?;
    world.start_ledger();
    let before = world.energy_state();
    let dt = world.dt_s();
    let n = world.particles.len() as f64;
    let report = |world: &World, phase: &'static str, fraction: f64| Progress {
        phase,
        fraction,
        sim_time_s: world.time_s,
        particle_steps: world.steps * world.particles.len() as u64,
        wall_time_s: started.elapsed().as_secs_f64(),
        ..Progress::default()
    };

    // 1. The pre-load, under force control: the table approaches at the
    //    loading speed and slows in proportion as the load nears the
    //    pre-load.
    let mut table = Table {
        z_m: 0.0,
        x_m: 0.0,
        preload_n: loading.preload_n,
        speed_mps: loading.speed_mps,
    };
    let approach_s = (START_CLEARANCE_M + 1e-3) / loading.speed_mps;
    let limit_s = approach_s + 1.0;
    let window = (WINDOW_S / dt).ceil() as u64;
    let mut touched_at_m: Option<f64> = None;
    let (mut sum, mut count, mut held_s, mut last_mean) = (0.0, 0u64, 0.0, 0.0);
    let t0 = world.time_s;
    loop {
        table.servo(&mut world, dt);
        world.step(0.0)?;
        let load = table.load_n(&world);
        if touched_at_m.is_none() && load > 0.0 {
            touched_at_m = Some(table.z_m);
        }
        sum += load;
        count += 1;
        if count == window {
            last_mean = sum / count as f64;
            let near = (last_mean - loading.preload_n).abs() <= HOLD_TOLERANCE * loading.preload_n;
            held_s = if near { held_s + WINDOW_S } else { 0.0 };
            (sum, count) = (0.0, 0);
            progress(report(&world, "pre-load", (held_s / HOLD_S).min(1.0)));
            if held_s >= HOLD_S - 0.5 * WINDOW_S {
                break;
            }
        }
        if world.time_s - t0 > limit_s {
            return Err(ShearBoxError::PreloadNotHeld {
                preload_n: loading.preload_n,
                time_s: world.time_s - t0,
                load_n: last_mean,
                hold_ms: HOLD_S * 1e3,
            });
        }
    }
    let preload_time_s = world.time_s - t0;
    let preload_displacement_m = touched_at_m.map_or(0.0, |z| z - table.z_m);

    // 2. The loading at constant speed.
    let phase = match test {
        BoxTest::Normal => "compressing",
        BoxTest::Shear => "shearing",
    };
    let (z0, x0) = (table.z_m, table.x_m);
    let stretch_m = loading.travel_m / loading.points as f64;
    let mut points = Vec::with_capacity(loading.points);
    let (mut force_sum, mut load_sum, mut rings_sum, mut count) = (0.0, 0.0, 0.0, 0u64);
    while points.len() < loading.points {
        match test {
            BoxTest::Normal => table.z_m -= loading.speed_mps * dt,
            BoxTest::Shear => {
                table.x_m += loading.speed_mps * dt;
                table.servo_normal(&world, dt);
            }
        }
        table.place(&mut world);
        world.step(0.0)?;
        let displacement_m = match test {
            BoxTest::Normal => z0 - table.z_m,
            BoxTest::Shear => table.x_m - x0,
        };
        force_sum += match test {
            BoxTest::Normal => world.wall_force_of(FLOOR).z,
            BoxTest::Shear => -(world.wall_force_of(FLOOR) + world.wall_force_of(LOWER_RING)).x,
        };
        load_sum += table.load_n(&world);
        rings_sum += (world.wall_force_of(LOWER_RING) + world.wall_force_of(UPPER_RING)).z;
        count += 1;
        let due = stretch_m * (points.len() + 1) as f64;
        if displacement_m >= due * (1.0 - 1e-9) {
            points.push(CurvePoint {
                displacement_m,
                force_n: force_sum / count as f64,
                table_load_n: load_sum / count as f64,
                rings_up_n: rings_sum / count as f64,
            });
            (force_sum, load_sum, rings_sum, count) = (0.0, 0.0, 0.0, 0);
            let done = points.len() as f64 / loading.points as f64;
            progress(report(&world, phase, done));
        }
    }
    let after = world.energy_state();
    let wall_time_s = started.elapsed().as_secs_f64();
    Ok(BoxRun {
        test,
        loading,
        bed_top_m,
        weight_n: world.particles.movers().map(|(m, _, _)| m).sum::<f64>() * world.gravity.length(),
        preload_displacement_m,
        preload_time_s,
        points,
        dt_s: dt,
        steps: world.steps,
        particle_steps_per_s: world.steps as f64 * n / wall_time_s.max(1e-9),
        wall_time_s,
        work_in_j: world.ledger.work_in_j,
        dissipated_j: world.ledger.dissipated.total(),
        energy_change_j: after.total_j() - before.total_j(),
    })
}

/// The loading table (and, for shear, the upper container it belongs to):
/// its own displacement from where it started.
struct Table {
    z_m: f64,
    x_m: f64,
    preload_n: f64,
    speed_mps: f64,
}

impl Table {
    /// The table's force on the bed now (N), downward positive.
    fn load_n(&self, world: &World) -> f64 {
        -world.wall_force_of(TABLE).z
    }

    /// Moves the table by force control for the next step and places it.
    fn servo(&mut self, world: &mut World, dt: f64) {
        self.servo_normal(world, dt);
        self.place(world);
    }

    /// The next step's height under force control: a speed in proportion
    /// to the load's shortfall, [`SERVO_GAIN`] times the loading speed per
    /// pre-load short, at most [`SERVO_MAX`] times the loading speed either
    /// way (down while the bed does not push back, up while it pushes
    /// harder than the pre-load).
    fn servo_normal(&mut self, world: &World, dt: f64) {
        let shortfall = 1.0 - self.load_n(world) / self.preload_n;
        let speed = self.speed_mps * (SERVO_GAIN * shortfall).clamp(-SERVO_MAX, SERVO_MAX);
        self.z_m -= speed * dt;
    }

    /// Prescribes the table's (and the upper ring's) place at the end of
    /// the next step.
    fn place(&self, world: &mut World) {
        world
            .walls
            .prescribe(TABLE, DVec3::new(self.x_m, 0.0, self.z_m));
        world.walls.prescribe(UPPER_RING, DVec3::X * self.x_m);
    }
}
