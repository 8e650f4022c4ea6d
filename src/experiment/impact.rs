//! A single collision as a verification and teaching instrument (thesis Fig.
//! 5.17–5.21): one sphere against a flat wall, or two identical spheres, run
//! through the same engine as the damper, with the Hertz closed forms alongside.
//!
//! Frame: the contact normal is the z axis. Against a wall, the plate lies at
//! z = 0 and the sphere comes down at `angle_deg` from the normal, moving in the
//! x-z plane. Against a sphere, the two spheres approach each other along z in
//! their centre-of-mass frame. The spin is about the y axis of sphere A, positive
//! in the rolling sense for motion along +x (it reduces the slip of the contact
//! point). Gravity is off: only the contact acts.

use glam::DVec3;
use serde::Serialize;

use crate::dem::hertz_theory;
use crate::dem::material::{
    Material, effective_mass_kg, effective_radius_m, effective_youngs_pa, sphere_mass_kg,
};
use crate::dem::{ContactLaw, LedgerBalance, Numerics, Particles, RestitutionMode, Walls, World};
use crate::scene::SceneError;
use crate::validation::{self, Bound, InvalidParameter, finite, in_range, positive};

/// What the sphere hits.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Target {
    /// A flat wall of the given material (`Material::rigid()` for a rigid one).
    Wall(Material),
    /// An identical sphere.
    Sphere,
}

/// Set-up of one collision.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImpactSetup {
    pub material: Material,
    pub radius_m: f64,
    pub target: Target,
    /// Relative approach speed (m/s).
    pub speed_mps: f64,
    /// Incidence angle from the normal (degrees), in [0, 90).
    pub angle_deg: f64,
    /// Spin of sphere A about y (rad/s).
    pub spin_rad_s: f64,
    pub restitution: f64,
    pub friction: f64,
    pub mode: RestitutionMode,
    /// Time step (s); `None` picks one fine enough for 1 % accuracy.
    pub dt_s: Option<f64>,
}

/// One sample of the contact history.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ImpactSample {
    pub time_s: f64,
    pub overlap_m: f64,
    pub normal_force_n: f64,
    pub tangential_force_n: f64,
}

/// Measured outcome of the collision, with the Hertz references.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ImpactOutcome {
    pub contact_duration_s: f64,
    pub max_overlap_m: f64,
    pub max_normal_force_n: f64,
    pub normal_restitution: f64,
    pub rebound_speed_mps: f64,
    pub rebound_angle_deg: f64,
    pub rebound_spin_rad_s: f64,
    pub dissipated_j: f64,
    /// Kinetic energy lost, before minus after (J); equals `dissipated_j` up to the
    /// integration error.
    pub kinetic_energy_lost_j: f64,
    /// Energy the time integration lost over the collision (J), the ledger's
    /// `integrator` channel: O(Δt²).
    pub integrator_j: f64,
    /// What the energy books leave unexplained (J): rounding.
    pub ledger_residual_j: f64,
    pub hertz_duration_s: f64,
    pub hertz_max_overlap_m: f64,
    pub hertz_max_force_n: f64,
    pub damping_factor: f64,
    pub dt_s: f64,
    pub steps: u64,
    #[serde(skip)]
    pub trace: Vec<ImpactSample>,
}

impl ImpactSetup {
    /// Checks every parameter; a refusal names it (as the field of this
    /// struct), its unit and valid range.
    pub fn validate(&self) -> Result<(), InvalidParameter> {
        self.material.validate().map_err(|e| e.within("material"))?;
        if let Target::Wall(w) = &self.target {
            if w.youngs_pa.is_finite() {
                w.validate().map_err(|e| e.within("target"))?;
            }
        }
        positive("radius_m", self.radius_m, "m")?;
        positive("speed_mps", self.speed_mps, "m/s")?;
        in_range(
            "angle_deg",
            self.angle_deg,
            "degrees",
            Bound::Closed(0.0),
            Bound::Open(90.0),
        )?;
        finite("spin_rad_s", self.spin_rad_s, "rad/s")?;
        validation::restitution("restitution", self.restitution)?;
        validation::friction("friction", self.friction)?;
        if let Some(dt) = self.dt_s {
            positive("dt_s", dt, "s")?;
        }
        Ok(())
    }

    fn pair_constants(&self) -> (f64, f64, f64) {
        let m = sphere_mass_kg(self.radius_m, self.material.density_kgm3);
        match self.target {
            Target::Wall(w) => (m, effective_youngs_pa(&self.material, &w), self.radius_m),
            Target::Sphere => (
                effective_mass_kg(m, m),
                effective_youngs_pa(&self.material, &self.material),
                effective_radius_m(self.radius_m, self.radius_m),
            ),
        }
    }

    /// Hertz contact duration at the normal approach speed (s).
    pub fn hertz_duration_s(&self) -> f64 {
        let (m, e, r) = self.pair_constants();
        hertz_theory::contact_duration_s(m, e, r, self.normal_speed_mps())
    }

    fn normal_speed_mps(&self) -> f64 {
        self.speed_mps * self.angle_deg.to_radians().cos()
    }
}

/// Steps per Hertz contact duration when no time step is given: the sampled peak
/// and the interpolated start and end times are then well inside 1 %.
pub const STEPS_PER_CONTACT: f64 = 400.0;

/// Runs the collision to separation.
pub fn run_impact(setup: &ImpactSetup) -> Result<ImpactOutcome, SceneError> {
    setup.validate()?;
    let (m_star, e_star, r_star) = setup.pair_constants();
    let v_n = setup.normal_speed_mps();
    let hertz_duration_s = hertz_theory::contact_duration_s(m_star, e_star, r_star, v_n);
    let dt = setup.dt_s.unwrap_or(hertz_duration_s / STEPS_PER_CONTACT);
    // Start a few steps before the touch, so the contact opens mid-run.
    let gap = 5.0 * v_n * dt;
    let mut world = impact_world(setup, dt, gap)?;
    let damping_factor = world.pp_law.damping_factor;
    let start = world.snapshot();
    let v_before = relative_velocity(setup, &world);
    let max_steps = 10 * (gap / (v_n * dt)) as u64 + 20 * STEPS_PER_CONTACT as u64 + 100_000;
    let Some(contact) = run_contact(setup, &mut world, max_steps)? else {
        return Err(SceneError::Invalid(InvalidParameter::new(
            "restitution",
            setup.restitution,
            "",
            "large enough for the bodies to separate: this contact is overdamped and never lets go",
        )));
    };
    let end = world.snapshot();
    let balance = LedgerBalance::between(&start, &end);
    let v_after = relative_velocity(setup, &world);
    let rebound_normal = -(v_after.z * v_before.z.signum());
    let rebound_tangential = v_after.truncate().length();
    let trace = contact.trace;
    let in_contact: Vec<&ImpactSample> = trace.iter().filter(|s| s.overlap_m > 0.0).collect();
    Ok(ImpactOutcome {
        contact_duration_s: contact.end_s - contact.onset_s,
        max_overlap_m: in_contact.iter().map(|s| s.overlap_m).fold(0.0, f64::max),
        max_normal_force_n: in_contact
            .iter()
            .map(|s| s.normal_force_n)
            .fold(0.0, f64::max),
        normal_restitution: rebound_normal / v_before.z.abs(),
        rebound_speed_mps: v_after.length(),
        rebound_angle_deg: rebound_tangential.atan2(rebound_normal).to_degrees(),
        rebound_spin_rad_s: world.particles.angular_velocity[0].y,
        dissipated_j: end.flows.dissipated.total() - start.flows.dissipated.total(),
        kinetic_energy_lost_j: start.stored.kinetic_j() - end.stored.kinetic_j(),
        integrator_j: balance.integrator_j,
        ledger_residual_j: balance.residual_j,
        hertz_duration_s,
        hertz_max_overlap_m: hertz_theory::max_overlap_m(m_star, e_star, r_star, v_n),
        hertz_max_force_n: hertz_theory::max_force_n(m_star, e_star, r_star, v_n),
        damping_factor,
        dt_s: dt,
        steps: world.steps,
        trace,
    })
}

/// The world of the collision at time step `dt_s` (module docs' frame),
/// `gap_m` before the touch.
fn impact_world(setup: &ImpactSetup, dt_s: f64, gap_m: f64) -> Result<World, SceneError> {
    let r = setup.radius_m;
    let gap = gap_m;
    let (sin, cos) = setup.angle_deg.to_radians().sin_cos();
    let direction = DVec3::new(sin, 0.0, -cos);
    let spin = DVec3::new(0.0, setup.spin_rad_s, 0.0);
    let mut particles = Particles::default();
    let (walls, wall_material) = match setup.target {
        Target::Wall(w) => {
            particles.push(
                DVec3::new(0.0, 0.0, r + gap),
                direction * setup.speed_mps,
                spin,
                r,
                setup.material.density_kgm3,
            );
            (Walls::plate(), w)
        }
        Target::Sphere => {
            let half = 0.5 * (2.0 * r + gap);
            let v = direction * (0.5 * setup.speed_mps);
            particles.push(DVec3::Z * half, v, spin, r, setup.material.density_kgm3);
            particles.push(
                -DVec3::Z * half,
                -v,
                DVec3::ZERO,
                r,
                setup.material.density_kgm3,
            );
            (Walls::none(), setup.material)
        }
    };
    let law = |other: &Material| {
        ContactLaw::new(
            &setup.material,
            other,
            setup.restitution,
            setup.friction,
            setup.mode,
        )
    };
    let (pp_law, pw_law) = (law(&setup.material), law(&wall_material));
    Ok(World::new(
        particles,
        walls,
        pp_law,
        pw_law,
        DVec3::ZERO,
        Numerics::with_dt(dt_s),
    )?)
}

/// Velocity of sphere A relative to what it hits.
fn relative_velocity(setup: &ImpactSetup, w: &World) -> DVec3 {
    match setup.target {
        Target::Wall(_) => w.particles.velocity[0],
        Target::Sphere => w.particles.velocity[0] - w.particles.velocity[1],
    }
}

/// Overlap of the contact, m (negative: a gap).
fn overlap(setup: &ImpactSetup, w: &World) -> f64 {
    let r = setup.radius_m;
    match setup.target {
        Target::Wall(_) => r - w.particles.position[0].z,
        Target::Sphere => 2.0 * r - (w.particles.position[0] - w.particles.position[1]).length(),
    }
}

/// A contact followed from its onset to its end.
struct Contact {
    /// Every step's sample, from the first.
    trace: Vec<ImpactSample>,
    onset_s: f64,
    end_s: f64,
}

/// Steps `world` until the contact has opened and closed again (onset and
/// end by linear interpolation of the overlap's zero crossing), at most
/// `max_steps` in all; `None` when it never closed.
fn run_contact(
    setup: &ImpactSetup,
    world: &mut World,
    max_steps: u64,
) -> Result<Option<Contact>, SceneError> {
    let mut trace = Vec::new();
    let mut prev = (world.time_s, overlap(setup, world));
    let mut started_at = None;
    while world.steps < max_steps {
        world.step(0.0)?;
        let d = overlap(setup, world);
        let f = world.particles.force[0];
        trace.push(ImpactSample {
            time_s: world.time_s,
            overlap_m: d,
            normal_force_n: f.z.abs(),
            tangential_force_n: f.truncate().length(),
        });
        match started_at {
            None if d > 0.0 => started_at = Some(crossing(prev, (world.time_s, d))),
            Some(onset_s) if d <= 0.0 => {
                return Ok(Some(Contact {
                    trace,
                    onset_s,
                    end_s: crossing(prev, (world.time_s, d)),
                }));
            }
            _ => {}
        }
        prev = (world.time_s, d);
    }
    Ok(None)
}

/// Time at which the linear interpolation between two samples crosses zero.
fn crossing((t0, d0): (f64, f64), (t1, d1): (f64, f64)) -> f64 {
    if d1 == d0 {
        return t1;
    }
    t0 + (t1 - t0) * d0 / (d0 - d1)
}
