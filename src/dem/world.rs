//! The DEM world: particles, walls, contact histories, and the time step.
//!
//! Integration is velocity Verlet (kick–drift–kick), which is symplectic, unlike
//! the explicit Euler of thesis eq. 3.29–3.30 (whose angle update, eq. 3.30, should
//! use ω, not its derivative). Each step:
//! 1. half kick `v += F/m Δt/2`, `ω += τ/I Δt/2`; drift `x += v Δt`;
//! 2. the walls move to the prescribed displacement for the end of the step;
//! 3. the pair list is rebuilt if some particle moved more than half the skin;
//! 4. forces at the new positions (gravity, wall and pair contacts, eq. 3.25–3.28),
//!    with the half-step velocities for damping and tangential displacement;
//! 5. second half kick, and the ledger is updated.
//!
//! Forces are summed in a fixed order (walls in order, then pairs sorted by
//! `(i, j)`), so results are bit-identical whatever the number of threads.
//!
//! **What a step computes is chosen by the scene.** The laws are resolved
//! once per step into an instance of the force loops with or without damping
//! and friction (`D`, `F` below): a law with e = 1 computes no damping, one
//! with μ = 0 no tangential force, no torque and no lever arms, and when no
//! law has friction the rotation is not integrated at all (nothing could
//! change it).
//!
//! **Threads.** Below [`AUTO_PARALLEL_MIN_PAIRS`] listed pairs (the thesis
//! scene lists about 2500) one core runs everything, and each pair contact is
//! added to the forces as soon as it is evaluated. Above it every loop is
//! split into fixed blocks across the threads: the particle loops (kick,
//! drift, gravity and walls: each particle's own), the pair loop (contact
//! states and pair forces, each pair's own), then a gather in which each
//! particle sums its pair forces in pair order, which is exactly the order
//! the serial loop adds them in. Both ways give the same bits; the tests
//! compare them.
//!
//! **The books.** What the contacts dissipate and store is summed per fixed
//! block of contacts (the walls of [`PARTICLE_BLOCK`] particles, or
//! [`PAIR_BLOCK`] pairs), in contact order within a block, and the block sums
//! are added to the ledger in block order, on one core and on many alike:
//! no thread waits for a sum over every contact of the step. The force of
//! the walls on the particles, which drives an electrodynamic shaker, is
//! still summed contact by contact in order.

use glam::DVec3;
use rayon::prelude::*;

use super::contact::{
    ContactGeometry, ContactLaw, ContactState, NormalDamping, Tangential, evaluate_contact_with,
};
use super::error::DemError;
use super::hertz_theory;
use super::ledger::{EnergyState, Ledger, LedgerBalance, LedgerSnapshot};
use super::material::{effective_mass_kg, effective_radius_m};
use super::neighbours::{NeighbourList, StepView as NeighbourStep};
use super::particles::Particles;
use super::walls::{WallShape, Walls};

/// Listed pairs from which a step is split across threads, when there are
/// several: below it waking the other threads costs more than they save (a
/// thesis-scene step, about 2500 pairs, takes some 30 µs on one core).
pub const AUTO_PARALLEL_MIN_PAIRS: usize = 8192;

/// Particles per block of the particle loops. Blocks are fixed, not one per
/// thread, so that partial sums are the same for any number of threads.
const PARTICLE_BLOCK: usize = 1024;
/// Pairs per block of the pair loop.
const PAIR_BLOCK: usize = 4096;

/// The particle state contacts read, borrowed field by field from `$p` so
/// that its forces and torques stay free to write.
macro_rules! bodies {
    ($p:expr) => {
        Bodies {
            position: &$p.position,
            velocity: &$p.velocity,
            angular_velocity: &$p.angular_velocity,
            radius: &$p.radius,
            mass: &$p.mass,
        }
    };
}

/// Tunables of a world that are not physics.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Numerics {
    /// Time step (s).
    pub dt_s: f64,
    /// Verlet-list skin as a fraction of the largest radius.
    pub skin_ratio: f64,
    /// Overlap, as a fraction of the smaller radius, taken as a sign of instability.
    pub max_overlap_ratio: f64,
    /// Deprecated: vlab chooses when to use threads ([`AUTO_PARALLEL_MIN_PAIRS`]).
    /// A value below that makes the step go parallel from this many listed
    /// pairs on (tests use 0 to run the parallel path on a small bed); the
    /// results are the same bits either way.
    pub parallel_min_pairs: usize,
    /// A collision resolved in fewer time steps than this is refused.
    pub min_steps_per_collision: f64,
    /// Steps between checks that the energy books still close.
    pub energy_check_steps: u64,
}

impl Numerics {
    /// Defaults for a given time step: skin 0.5 R, so that the cells of the
    /// neighbour grid are 2.5 R wide as in the thesis (Section 3.4; physics does
    /// not depend on the skin, and 0.1–0.5 R ran equally fast), overlap limit 10 % of R,
    /// threads as vlab chooses, at least 5 steps per collision, energy books
    /// checked every 2000 steps.
    pub fn with_dt(dt_s: f64) -> Self {
        Numerics {
            dt_s,
            skin_ratio: 0.5,
            max_overlap_ratio: 0.10,
            parallel_min_pairs: AUTO_PARALLEL_MIN_PAIRS,
            min_steps_per_collision: 5.0,
            energy_check_steps: 2000,
        }
    }
}

/// What one contact contributed over a step, before it is booked: forces,
/// energies, and what the stability checks read. Pair and wall contacts both
/// produce one, and [`BlockBooks::add`] checks and books both the same way.
#[derive(Debug, Clone, Copy, Default)]
struct ContactResult {
    /// Force on particle `i` (N); particle `j` of a pair gets the opposite.
    force_i: DVec3,
    torque_i: DVec3,
    /// Torque on particle `j` of a pair (N m); unused for a wall.
    torque_j: DVec3,
    dissipated_normal_j: f64,
    dissipated_tangential_j: f64,
    stiffness_work_j: f64,
    integrator_j: f64,
    /// Change of the energy stored in the contact over the step (J).
    stored_change_j: f64,
    /// Overlap as a fraction of the smaller radius.
    overlap_ratio: f64,
    /// Normal approach speed now (m/s).
    approach_mps: f64,
    /// Steps the collision will take, set when the contact opens (else infinite).
    steps_per_collision: f64,
    /// Normal approach speed when the contact opened this step (else zero).
    onset_speed_mps: f64,
}

/// Which contact a [`ContactResult`] belongs to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum ContactAt {
    /// Particles `i < j`.
    Pair(usize, usize),
    /// Particle `i` and wall number `w`.
    Wall(usize, usize),
}

/// A complete DEM system.
#[derive(Debug, Clone)]
pub struct World {
    pub particles: Particles,
    pub walls: Walls,
    /// Particle-particle contact law.
    pub pp_law: ContactLaw,
    /// Particle-wall contact law.
    pub pw_law: ContactLaw,
    /// Gravitational acceleration vector (m/s²).
    pub gravity: DVec3,
    pub numerics: Numerics,
    /// Simulated time (s).
    pub time_s: f64,
    /// Steps taken.
    pub steps: u64,
    /// Cumulative energy flows.
    pub ledger: Ledger,
    neighbours: NeighbourList,
    /// Change of the energy stored in the contacts over the current step (J).
    step_stored_change_j: f64,
    /// Contact state of particle `i` with wall `w` at `i * n_walls + w`; as
    /// for the pairs ([`NeighbourList::gaps`]), its `delta_prev` is current
    /// only while they touch.
    wall_states: Vec<ContactState>,
    /// Overlap of particle `i` with wall `w` at the previous step (m), at
    /// `i * n_walls + w`; negative: the gap. Always current.
    wall_gaps: Vec<f64>,
    /// Scratch of the parallel step, kept from step to step.
    scratch: StepScratch,
    /// Total force of the walls on the particles at the current step (N).
    wall_force: DVec3,
    /// Ledger reading the energy check compares against.
    baseline: LedgerSnapshot,
    /// Largest normal approach speed at contact onset since the last reset (m/s).
    pub impact_speeds: ImpactSpeeds,
    /// Energy each particle's contacts dissipated since tracking began (J),
    /// while tracked ([`World::track_particle_dissipation`]).
    particle_dissipation_j: Option<Vec<f64>>,
    /// Fewest time steps a collision that opened since the last reset is
    /// resolved with (the Hertz duration at its approach speed, eq. 5.10, over
    /// the step); infinite when none opened.
    pub fewest_steps_per_contact: f64,
}

/// Largest normal approach speeds at contact onset (m/s), to hold against the
/// yield velocity of thesis eq. 5.26 (the model's validity, Section 5.5.4).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct ImpactSpeeds {
    pub particle_particle_mps: f64,
    pub particle_wall_mps: f64,
}

impl World {
    /// Builds a world and evaluates the initial forces (no history, no ledger).
    pub fn new(
        particles: Particles,
        walls: Walls,
        pp_law: ContactLaw,
        pw_law: ContactLaw,
        gravity: DVec3,
        numerics: Numerics,
    ) -> Result<Self, DemError> {
        let skin = numerics.skin_ratio * particles.max_radius_m();
        let mut world = World {
            particles,
            walls,
            pp_law,
            pw_law,
            gravity,
            numerics,
            time_s: 0.0,
            steps: 0,
            ledger: Ledger::default(),
            neighbours: NeighbourList::new(skin),
            step_stored_change_j: 0.0,
            wall_states: Vec::new(),
            wall_gaps: Vec::new(),
            scratch: StepScratch::default(),
            wall_force: DVec3::ZERO,
            baseline: LedgerSnapshot::default(),
            impact_speeds: ImpactSpeeds::default(),
            particle_dissipation_j: None,
            fewest_steps_per_contact: f64::INFINITY,
        };
        world.reset_contacts();
        world.compute_forces(0.0)?;
        world.rebaseline();
        Ok(world)
    }

    /// Restarts the energy check from the current state; call after editing the
    /// world by hand (changing gravity, moving a wall, placing particles).
    pub fn rebaseline(&mut self) {
        self.baseline = self.snapshot();
    }

    /// Checks that the energy books still close since the last baseline: energy
    /// the integration made or lost (its own channel plus the residual) above
    /// 2 % of the energy in play (kinetic + elastic + dissipated + |work in|)
    /// means the integration has gone wrong, typically energy growing without
    /// any input because the step is too coarse.
    pub fn check_energy(&self) -> Result<(), DemError> {
        let now = self.snapshot();
        let b = LedgerBalance::between(&self.baseline, &now);
        let in_play = now.stored.kinetic_j()
            + now.stored.elastic_j()
            + self.baseline.stored.kinetic_j()
            + self.baseline.stored.elastic_j()
            + b.dissipated_j.abs()
            + b.work_in_j.abs();
        let unaccounted = b.residual_j.abs() + b.integrator_j.abs();
        if in_play > 0.0 && unaccounted > 0.02 * in_play {
            return Err(DemError::EnergyNotConserved {
                time_s: self.time_s,
                step: self.steps,
                residual_j: b.residual_j - b.integrator_j,
                percent: 100.0 * unaccounted / in_play,
                dt_s: self.numerics.dt_s,
            });
        }
        Ok(())
    }

    /// Forgets every contact history and re-reads the geometry (after the scene was
    /// edited, e.g. particles placed or walls moved by hand).
    pub fn reset_contacts(&mut self) {
        self.neighbours = NeighbourList::new(self.neighbours.skin_m());
        self.neighbours
            .rebuild(&self.particles.position, &self.particles.radius);
        let n_walls = self.walls.len();
        let offset = self.walls.offset();
        self.wall_states.clear();
        self.wall_gaps.clear();
        for i in 0..self.particles.len() {
            for w in 0..n_walls {
                let dist = self.walls.shapes[w].distance_m(self.particles.position[i], offset);
                let overlap = self.particles.radius[i] - dist;
                self.wall_states.push(ContactState::apart(overlap));
                self.wall_gaps.push(overlap);
            }
        }
    }

    /// Replaces the contact laws (the settling law by the scene's, say): every
    /// tangential history is dropped and the forces are evaluated anew with the
    /// new laws; the energy check restarts from here.
    pub fn set_contact_laws(
        &mut self,
        pp_law: ContactLaw,
        pw_law: ContactLaw,
    ) -> Result<(), DemError> {
        self.pp_law = pp_law;
        self.pw_law = pw_law;
        self.reset_contacts();
        self.compute_forces(0.0)?;
        self.rebaseline();
        Ok(())
    }

    /// Changes the time step. The state carries over unchanged: velocity
    /// Verlet's forces depend on positions only.
    pub fn set_dt_s(&mut self, dt_s: f64) {
        self.numerics.dt_s = dt_s;
        self.rebaseline();
    }

    /// Starts the energy ledger and the record of impact speeds from zero:
    /// what follows is the experiment.
    pub fn start_ledger(&mut self) {
        self.ledger = Ledger::default();
        self.impact_speeds = ImpactSpeeds::default();
        self.fewest_steps_per_contact = f64::INFINITY;
        self.rebaseline();
    }

    /// Changes the Verlet skin (a fraction of the largest radius) and rebuilds the
    /// pair list, keeping every contact's history.
    pub fn set_skin_ratio(&mut self, skin_ratio: f64) {
        self.numerics.skin_ratio = skin_ratio;
        self.neighbours
            .set_skin_m(skin_ratio * self.particles.max_radius_m());
        self.neighbours
            .rebuild(&self.particles.position, &self.particles.radius);
    }

    /// Re-reads the gap to every wall a particle does not touch, after walls were
    /// moved by hand (closing the lid); contacts in progress keep their history.
    pub fn refresh_wall_gaps(&mut self) {
        let n_walls = self.walls.len();
        let offset = self.walls.offset();
        for (k, gap) in self.wall_gaps.iter_mut().enumerate() {
            if *gap > 0.0 {
                continue;
            }
            let (i, w) = (k / n_walls, k % n_walls);
            let dist = self.walls.shapes[w].distance_m(self.particles.position[i], offset);
            *gap = self.particles.radius[i] - dist;
        }
    }

    /// Time step (s).
    pub fn dt_s(&self) -> f64 {
        self.numerics.dt_s
    }

    /// Force the walls exert on the particles now (N); the particles push the
    /// enclosure with the opposite force.
    pub fn wall_force(&self) -> DVec3 {
        self.wall_force
    }

    /// Pairs in the neighbour list now (touching or within the skin).
    pub fn listed_pairs(&self) -> usize {
        self.neighbours.pairs.len()
    }

    /// How often the neighbour list was rebuilt.
    pub fn neighbour_rebuilds(&self) -> u64 {
        self.neighbours.rebuilds()
    }

    /// The deepest overlap now, as a fraction of the smaller radius of the pair
    /// (of the particle's radius against a wall).
    pub fn max_overlap_ratio(&self) -> f64 {
        let p = &self.particles;
        let pairs = self
            .neighbours
            .pairs
            .iter()
            .zip(&self.neighbours.gaps)
            .map(|(&(i, j), &d)| d / p.radius[i as usize].min(p.radius[j as usize]));
        let n_walls = self.walls.len().max(1);
        let walls = self
            .wall_gaps
            .iter()
            .enumerate()
            .map(|(k, &d)| d / p.radius[k / n_walls]);
        pairs.chain(walls).fold(0.0, f64::max)
    }

    /// Number of particle-particle and particle-wall contacts now.
    pub fn contact_counts(&self) -> (usize, usize) {
        let pp = self.neighbours.gaps.iter().filter(|&&d| d > 0.0).count();
        let pw = self.wall_gaps.iter().filter(|&&d| d > 0.0).count();
        (pp, pw)
    }

    /// Number of contacts (particle-particle and particle-wall) each particle
    /// is in now, into `counts` (resized to the particle count).
    pub fn contacts_per_particle(&self, counts: &mut Vec<u32>) {
        let n = self.particles.len();
        counts.clear();
        counts.resize(n, 0);
        for (&(i, j), &d) in self.neighbours.pairs.iter().zip(&self.neighbours.gaps) {
            if d > 0.0 {
                counts[i as usize] += 1;
                counts[j as usize] += 1;
            }
        }
        let n_walls = self.walls.len().max(1);
        for (k, &d) in self.wall_gaps.iter().enumerate() {
            if d > 0.0 {
                counts[k / n_walls] += 1;
            }
        }
    }

    /// Starts (from zero) or stops booking dissipated energy per particle: a
    /// pair contact's dissipation is shared half and half, a wall contact's
    /// goes to its particle. Off by default; it costs one branch per contact.
    pub fn track_particle_dissipation(&mut self, on: bool) {
        self.particle_dissipation_j = on.then(|| vec![0.0; self.particles.len()]);
    }

    /// Energy each particle's contacts dissipated since tracking began (J),
    /// when tracked.
    pub fn particle_dissipation_j(&self) -> Option<&[f64]> {
        self.particle_dissipation_j.as_deref()
    }

    /// Mechanical energy stored now.
    pub fn energy_state(&self) -> EnergyState {
        let p = &self.particles;
        let (kt, kr) = p.kinetic_energy_j();
        let mut un = 0.0;
        let mut ut = 0.0;
        for st in self.neighbours.states.iter().chain(&self.wall_states) {
            let (a, b) = st.stored_energy_j();
            un += a;
            ut += b;
        }
        let dt = self.numerics.dt_s;
        let verlet_shadow_j = (0..p.len())
            .map(|i| {
                p.force[i].length_squared() * p.inv_mass[i]
                    + p.torque[i].length_squared() * p.inv_inertia[i]
            })
            .sum::<f64>()
            * (dt * dt / 8.0);
        EnergyState {
            verlet_shadow_j,
            kinetic_translational_j: kt,
            kinetic_rotational_j: kr,
            potential_j: p.potential_energy_j(self.gravity),
            elastic_normal_j: un,
            elastic_tangential_j: ut,
        }
    }

    /// Cumulative flows and stored energy now.
    pub fn snapshot(&self) -> LedgerSnapshot {
        LedgerSnapshot {
            time_s: self.time_s,
            flows: self.ledger,
            stored: self.energy_state(),
        }
    }

    /// Whether a step now runs on all threads of the current pool (several
    /// threads, and enough listed pairs to pay for waking them); the
    /// results are the same bits either way.
    pub fn splits_across_threads(&self) -> bool {
        self.parallel()
    }

    /// Whether this step runs on all threads: several threads, and enough
    /// listed pairs to pay for waking them ([`AUTO_PARALLEL_MIN_PAIRS`]).
    /// Either way the results are the same bits.
    fn parallel(&self) -> bool {
        let from = self
            .numerics
            .parallel_min_pairs
            .min(AUTO_PARALLEL_MIN_PAIRS);
        rayon::current_num_threads() > 1 && self.neighbours.pairs.len() >= from
    }

    /// True when some law has friction: only then can a particle's spin change.
    fn rotates(&self) -> bool {
        self.pp_law.has_friction() || self.pw_law.has_friction()
    }

    /// Advances one step; the wall body ends the step at `wall_displacement_m`.
    pub fn step(&mut self, wall_displacement_m: f64) -> Result<(), DemError> {
        let dt = self.numerics.dt_s;
        let half = 0.5 * dt;
        let parallel = self.parallel();
        // Work the contact forces do on the particles over the step, as velocity
        // Verlet applies them: the trapezoid of the forces (gravity taken out)
        // at both ends on the drift `v_half dt` (rotation: `ω_half dt`).
        let drift = self.half_kick(Pass::KickDrift, 0.0, parallel);
        let kicked_work = drift.work;
        if let Some(i) = drift.nonfinite {
            return Err(DemError::NonFinite {
                time_s: self.time_s + dt,
                step: self.steps + 1,
                particle: i,
                dt_s: dt,
            });
        }

        let du = wall_displacement_m - self.walls.displacement_m;
        self.walls.displacement_m = wall_displacement_m;
        self.walls.velocity_mps = du / dt;
        let axial_before = self.wall_force.dot(self.walls.axis);

        if drift.moved_far || self.neighbours.reference().len() != self.particles.len() {
            self.neighbours
                .rebuild(&self.particles.position, &self.particles.radius);
        }
        let booked_before = self.ledger;
        self.step_stored_change_j = 0.0;
        self.compute_forces(dt)?;

        let mut contact_work_j = self.half_kick(Pass::Kick, kicked_work, parallel).work;
        contact_work_j *= half;
        // Trapezoidal work of the walls on the particles over the step.
        let work_in_j = 0.5 * (axial_before + self.wall_force.dot(self.walls.axis)) * du;
        self.ledger.work_in_j += work_in_j;
        // What the contacts booked (stored, dissipated, left over at opening)
        // against the work their forces really did: the difference is energy
        // the discrete integration made or lost (the contact normal and lever
        // arms turn within a step, which the per-contact books do not see).
        let booked_j = self.step_stored_change_j
            + (self.ledger.dissipated.total() - booked_before.dissipated.total())
            + (self.ledger.integrator_j - booked_before.integrator_j);
        self.ledger.integrator_j += -(contact_work_j - work_in_j + booked_j);
        self.time_s += dt;
        self.steps += 1;
        if self.steps % self.numerics.energy_check_steps == 0 {
            self.check_energy()?;
        }
        Ok(())
    }

    /// One half kick of every particle (and the drift, on the first pass),
    /// in fixed blocks. Returns the sum of the contact power terms
    /// `(F - m g)·v + τ·ω` over the particles, added to `carry` in particle
    /// order (block by block, so the same for any thread count; for one block
    /// the order of a plain loop), the first particle whose position is not
    /// finite, and whether some particle drifted far enough from where the
    /// pair list was built for the list to be rebuilt.
    fn half_kick(&mut self, pass: Pass, carry: f64, parallel: bool) -> KickSums {
        let reference = self.neighbours.reference();
        let kick = Kick {
            pass,
            dt: self.numerics.dt_s,
            gravity: self.gravity,
            rotation: self.rotates(),
            travel_sq_m2: self.neighbours.rebuild_travel_sq_m2(),
        };
        let p = &mut self.particles;
        // A list built for other particles is rebuilt anyway (by the caller).
        let reference = (reference.len() == p.len()).then_some(reference);
        let (force, torque, mass) = (&p.force, &p.torque, &p.mass);
        let (inv_mass, inv_inertia) = (&p.inv_mass, &p.inv_inertia);
        type Block<'b> = (usize, ((&'b mut [DVec3], &'b mut [DVec3]), &'b mut [DVec3]));
        let block = |(c, ((x, v), w)): Block<'_>| {
            let s = c * PARTICLE_BLOCK;
            let e = s + x.len();
            let loads = Loads {
                force: &force[s..e],
                torque: &torque[s..e],
                mass: &mass[s..e],
                inv_mass: &inv_mass[s..e],
                inv_inertia: &inv_inertia[s..e],
            };
            let built_at = reference.map(|r| &r[s..e]);
            let sums = kick.block(&loads, x, v, w, built_at, if c == 0 { carry } else { 0.0 });
            KickSums {
                nonfinite: sums.nonfinite.map(|k| s + k),
                ..sums
            }
        };
        let sums = &mut self.scratch.block_sums;
        if parallel {
            p.position
                .par_chunks_mut(PARTICLE_BLOCK)
                .zip(p.velocity.par_chunks_mut(PARTICLE_BLOCK))
                .zip(p.angular_velocity.par_chunks_mut(PARTICLE_BLOCK))
                .enumerate()
                .map(block)
                .collect_into_vec(sums);
        } else {
            sums.clear();
            sums.extend(
                p.position
                    .chunks_mut(PARTICLE_BLOCK)
                    .zip(p.velocity.chunks_mut(PARTICLE_BLOCK))
                    .zip(p.angular_velocity.chunks_mut(PARTICLE_BLOCK))
                    .enumerate()
                    .map(block),
            );
        }
        let mut total = KickSums {
            work: if sums.is_empty() { carry } else { 0.0 },
            nonfinite: None,
            moved_far: false,
        };
        for b in sums.iter() {
            total.work += b.work;
            total.nonfinite = total.nonfinite.or(b.nonfinite);
            total.moved_far |= b.moved_far;
        }
        total
    }

    /// Human-readable name of a contact, for diagnoses.
    fn contact_name(&self, at: ContactAt) -> String {
        match at {
            ContactAt::Pair(i, j) => format!("particle-particle ({i}, {j})"),
            ContactAt::Wall(i, w) => format!("particle-{} (particle {i})", self.walls.names[w]),
        }
    }

    /// The error that stops the run at contact `at`.
    fn refusal(&self, at: ContactAt, out: &ContactResult, why: Refusal, dt: f64) -> DemError {
        let n = &self.numerics;
        match why {
            Refusal::Unresolved => {
                let duration_s = out.steps_per_collision * dt;
                DemError::UnresolvedCollision {
                    time_s: self.time_s + dt,
                    step: self.steps + 1,
                    contact: self.contact_name(at),
                    speed_mps: out.onset_speed_mps,
                    duration_s,
                    steps: out.steps_per_collision,
                    dt_s: dt,
                    suggested_dt_s: duration_s / 20.0,
                }
            }
            Refusal::Overlap => DemError::ExcessiveOverlap {
                time_s: self.time_s + dt,
                step: self.steps + 1,
                contact: self.contact_name(at),
                overlap_percent: 100.0 * out.overlap_ratio,
                limit_percent: 100.0 * n.max_overlap_ratio,
                speed_mps: out.approach_mps,
                dt_s: n.dt_s,
            },
            Refusal::Escaped => {
                let (i, w) = match at {
                    ContactAt::Wall(i, w) | ContactAt::Pair(i, w) => (i, w),
                };
                DemError::Escaped {
                    time_s: self.time_s + dt,
                    step: self.steps + 1,
                    particle: i,
                    wall: self.walls.names[w].to_string(),
                    dt_s: n.dt_s,
                }
            }
        }
    }

    /// Forces and torques at the current positions. `dt` is the step over which the
    /// tangential springs advance and the ledger accumulates (0 for a pure
    /// evaluation that changes no history).
    ///
    /// On one core: gravity and the walls, then each pair added to both its
    /// particles as it is evaluated. On all threads: the pairs first, each
    /// leaving its force in its own slot, then one pass over the particles
    /// that sets gravity, adds the walls and gathers the pair forces in pair
    /// order (the order of the serial loop, so the same bits), then the
    /// books, walls first as on one core.
    fn compute_forces(&mut self, dt: f64) -> Result<(), DemError> {
        self.wall_force = DVec3::ZERO;
        if !self.parallel() {
            match law_kind(&self.pw_law) {
                (true, true) => self.wall_contacts::<true, true>(dt, None),
                (true, false) => self.wall_contacts::<true, false>(dt, None),
                (false, true) => self.wall_contacts::<false, true>(dt, None),
                (false, false) => self.wall_contacts::<false, false>(dt, None),
            }?;
            return match law_kind(&self.pp_law) {
                (true, true) => self.pair_contacts::<true, true>(dt),
                (true, false) => self.pair_contacts::<true, false>(dt),
                (false, true) => self.pair_contacts::<false, true>(dt),
                (false, false) => self.pair_contacts::<false, false>(dt),
            };
        }
        match law_kind(&self.pp_law) {
            (true, true) => self.pair_blocks::<true, true>(dt),
            (true, false) => self.pair_blocks::<true, false>(dt),
            (false, true) => self.pair_blocks::<false, true>(dt),
            (false, false) => self.pair_blocks::<false, false>(dt),
        }
        let gather = Some(self.pp_law.has_friction());
        match law_kind(&self.pw_law) {
            (true, true) => self.wall_contacts::<true, true>(dt, gather),
            (true, false) => self.wall_contacts::<true, false>(dt, gather),
            (false, true) => self.wall_contacts::<false, true>(dt, gather),
            (false, false) => self.wall_contacts::<false, false>(dt, gather),
        }?;
        self.book_pair_blocks(dt)
    }

    /// Gravity and the wall contacts, particle by particle in fixed blocks;
    /// what the contacts book is then added up on one thread in contact
    /// order. `gather: Some(torques)`: the step runs on all threads, and each
    /// block then also adds its particles' pair forces (and torques, when
    /// `torques`), which [`Self::pair_blocks`] left one per pair.
    fn wall_contacts<const D: bool, const F: bool>(
        &mut self,
        dt: f64,
        gather: Option<bool>,
    ) -> Result<(), DemError> {
        let g = self.gravity;
        let p = &mut self.particles;
        let list = &self.neighbours;
        let slots = &self.scratch.pair_slots;
        let gather_into = |c: usize, f: &mut [DVec3], t: &mut [DVec3]| match gather {
            Some(true) => gather_block::<true>(list, slots, c * PARTICLE_BLOCK, f, t),
            Some(false) => gather_block::<false>(list, slots, c * PARTICLE_BLOCK, f, t),
            None => {}
        };
        if self.walls.is_empty() {
            for (f, (t, m)) in p.force.iter_mut().zip(p.torque.iter_mut().zip(&p.mass)) {
                *f = g * *m;
                *t = DVec3::ZERO;
            }
            if gather.is_some() {
                p.force
                    .par_chunks_mut(PARTICLE_BLOCK)
                    .zip(p.torque.par_chunks_mut(PARTICLE_BLOCK))
                    .enumerate()
                    .for_each(|(c, (f, t))| gather_into(c, f, t));
            }
            return Ok(());
        }
        let law = self.pw_law;
        let walls = WallGeometry {
            shapes: &self.walls.shapes,
            offset: self.walls.offset(),
            v_wall: self.walls.velocity(),
        };
        let bodies = bodies!(p);
        let n_walls = walls.shapes.len();
        let n_blocks = p.force.len().div_ceil(PARTICLE_BLOCK);
        let books = &mut self.scratch.wall_books;
        if books.len() < n_blocks {
            books.resize_with(n_blocks, BlockBooks::default);
        }
        type Block<'b> = (
            usize,
            (
                (
                    ((&'b mut [DVec3], &'b mut [DVec3]), &'b mut [ContactState]),
                    &'b mut [f64],
                ),
                &'b mut BlockBooks,
            ),
        );
        let limits = Limits::of(&self.numerics, self.particle_dissipation_j.is_some());
        let block = |(c, ((((f, t), st), gaps), bk)): Block<'_>| {
            wall_block::<D, F>(
                &law,
                &walls,
                &bodies,
                g,
                c * PARTICLE_BLOCK,
                f,
                t,
                (st, gaps),
                (limits, bk),
                dt,
            );
            gather_into(c, f, t);
        };
        let (states, gaps) = (&mut self.wall_states, &mut self.wall_gaps);
        let chunk = PARTICLE_BLOCK * n_walls;
        if gather.is_some() {
            p.force
                .par_chunks_mut(PARTICLE_BLOCK)
                .zip(p.torque.par_chunks_mut(PARTICLE_BLOCK))
                .zip(states.par_chunks_mut(chunk))
                .zip(gaps.par_chunks_mut(chunk))
                .zip(books[..n_blocks].par_iter_mut())
                .enumerate()
                .for_each(block);
        } else {
            p.force
                .chunks_mut(PARTICLE_BLOCK)
                .zip(p.torque.chunks_mut(PARTICLE_BLOCK))
                .zip(states.chunks_mut(chunk))
                .zip(gaps.chunks_mut(chunk))
                .zip(books[..n_blocks].iter_mut())
                .enumerate()
                .for_each(block);
        }

        let books = std::mem::take(&mut self.scratch.wall_books);
        let booked = self.book(Kind::Wall, &books[..n_blocks], dt);
        self.scratch.wall_books = books;
        booked
    }

    /// The pair contacts on one thread, each added to the forces as soon as
    /// it is evaluated, in pair order; the books block by block.
    fn pair_contacts<const D: bool, const F: bool>(&mut self, dt: f64) -> Result<(), DemError> {
        let law = self.pp_law;
        let limits = Limits::of(&self.numerics, self.particle_dissipation_j.is_some());
        let p = &mut self.particles;
        let bodies = bodies!(p);
        let (force, torque) = (&mut p.force, &mut p.torque);
        let nl = &mut self.neighbours;
        let n_blocks = nl.pairs.len().div_ceil(PAIR_BLOCK);
        let books = &mut self.scratch.pair_books;
        if books.len() < n_blocks {
            books.resize_with(n_blocks, BlockBooks::default);
        }
        let blocks = nl
            .pairs
            .chunks(PAIR_BLOCK)
            .zip(nl.gaps.chunks_mut(PAIR_BLOCK))
            .zip(nl.states.chunks_mut(PAIR_BLOCK))
            .zip(books.iter_mut());
        'blocks: for (((pairs, gaps), states), bk) in blocks {
            bk.clear();
            for (&(i, j), (gap, st)) in pairs.iter().zip(gaps.iter_mut().zip(states.iter_mut())) {
                let (i, j) = (i as usize, j as usize);
                let Some(out) = pair_contact::<D, F>(&law, &bodies, i, j, dt, gap, st) else {
                    continue;
                };
                if !bk.add(&limits, ContactAt::Pair(i, j), &out, dt) {
                    break 'blocks;
                }
                force[i] += out.force_i;
                force[j] -= out.force_i;
                if F {
                    torque[i] += out.torque_i;
                    torque[j] += out.torque_j;
                }
            }
        }
        let books = std::mem::take(&mut self.scratch.pair_books);
        let booked = self.book(Kind::Pair, &books[..n_blocks], dt);
        self.scratch.pair_books = books;
        booked
    }

    /// The pair contacts on all threads, in fixed blocks: each pair advances
    /// its state and leaves its forces in its own slots, and each block sums
    /// its books.
    fn pair_blocks<const D: bool, const F: bool>(&mut self, dt: f64) {
        let law = self.pp_law;
        let limits = Limits::of(&self.numerics, self.particle_dissipation_j.is_some());
        let p = &self.particles;
        let bodies = bodies!(p);
        let nl = &mut self.neighbours;
        let sc = &mut self.scratch;
        let n_pairs = nl.pairs.len();
        sc.pair_slots.resize(n_pairs);
        let n_blocks = n_pairs.div_ceil(PAIR_BLOCK);
        if sc.pair_books.len() < n_blocks {
            sc.pair_books.resize_with(n_blocks, BlockBooks::default);
        }
        sc.pair_blocks = n_blocks;
        let NeighbourStep {
            pairs,
            gaps,
            states,
        } = nl.step_view();
        let PairSlots { acts, force } = &mut sc.pair_slots;
        pairs
            .par_chunks(PAIR_BLOCK)
            .zip(gaps.par_chunks_mut(PAIR_BLOCK))
            .zip(states.par_chunks_mut(PAIR_BLOCK))
            .zip(acts.par_chunks_mut(PAIR_BLOCK))
            .zip(force.par_chunks_mut(PAIR_BLOCK))
            .zip(sc.pair_books[..n_blocks].par_iter_mut())
            .for_each(|(((((pairs, gaps), states), acts), forces), books)| {
                pair_block::<D, F>(
                    &law,
                    &bodies,
                    pairs,
                    (gaps, states),
                    (acts, forces),
                    (&limits, books),
                    dt,
                );
            });
    }

    /// Books the blocks [`Self::pair_blocks`] summed, in block order.
    fn book_pair_blocks(&mut self, dt: f64) -> Result<(), DemError> {
        let books = std::mem::take(&mut self.scratch.pair_books);
        let booked = self.book(Kind::Pair, &books[..self.scratch.pair_blocks], dt);
        self.scratch.pair_books = books;
        booked
    }

    /// Adds the books of the blocks of one kind of contact to the ledger, in
    /// block order, and stops the run at the first contact a block refused.
    fn book(&mut self, kind: Kind, blocks: &[BlockBooks], dt: f64) -> Result<(), DemError> {
        for b in blocks {
            if dt > 0.0 {
                let (normal, tangential) = match kind {
                    Kind::Pair => {
                        let d = &mut self.ledger.dissipated;
                        (&mut d.pp_normal, &mut d.pp_tangential)
                    }
                    Kind::Wall => {
                        let d = &mut self.ledger.dissipated;
                        (&mut d.pw_normal, &mut d.pw_tangential)
                    }
                };
                *normal += b.normal_j;
                *tangential += b.tangential_j;
                self.ledger.stiffness_work_j += b.stiffness_work_j;
                self.ledger.integrator_j += b.integrator_j;
                self.step_stored_change_j += b.stored_change_j;
            }
            let fastest = match kind {
                Kind::Pair => &mut self.impact_speeds.particle_particle_mps,
                Kind::Wall => &mut self.impact_speeds.particle_wall_mps,
            };
            *fastest = fastest.max(b.fastest_onset_mps);
            self.fewest_steps_per_contact = self.fewest_steps_per_contact.min(b.fewest_steps);
            if kind == Kind::Wall {
                for &f in &b.wall_forces {
                    self.wall_force += f;
                }
            }
            if let (Some(per), true) = (self.particle_dissipation_j.as_deref_mut(), dt > 0.0) {
                for &(i, j, e) in &b.dissipation {
                    if kind == Kind::Pair {
                        per[i as usize] += 0.5 * e;
                        per[j as usize] += 0.5 * e;
                    } else {
                        per[i as usize] += e;
                    }
                }
            }
            if let Some((at, out, why)) = b.refused {
                return Err(self.refusal(at, &out, why, dt));
            }
        }
        Ok(())
    }
}

/// The particle state a contact reads, borrowed apart from the forces and
/// torques it writes.
#[derive(Clone, Copy)]
struct Bodies<'a> {
    position: &'a [DVec3],
    velocity: &'a [DVec3],
    angular_velocity: &'a [DVec3],
    radius: &'a [f64],
    mass: &'a [f64],
}

/// Where the walls are this step.
#[derive(Clone, Copy)]
struct WallGeometry<'a> {
    shapes: &'a [WallShape],
    offset: DVec3,
    v_wall: DVec3,
}

/// Why a contact stops the run.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Refusal {
    /// Resolved in fewer steps than `min_steps_per_collision`.
    Unresolved,
    /// Deeper than `max_overlap_ratio`.
    Overlap,
    /// The particle's centre is past the wall.
    Escaped,
}

/// What a pair contributes to the forces, kept for the gather of the
/// parallel step.
#[derive(Debug, Clone, Copy, Default)]
struct PairForce {
    force_i: DVec3,
    torque_i: DVec3,
    torque_j: DVec3,
}

/// Where the pairs of a parallel step leave their forces for the gather,
/// each pair in its own slot (a block writes only its own slots, so no two
/// threads write the same cache line but at a block's ends).
#[derive(Debug, Clone, Default)]
struct PairSlots {
    /// Per pair: whether it acts this step (touches, or stopped touching:
    /// the pairs the serial loop adds).
    acts: Vec<bool>,
    /// Per pair: its forces, written only when it acts.
    force: Vec<PairForce>,
}

impl PairSlots {
    fn resize(&mut self, n_pairs: usize) {
        self.acts.resize(n_pairs, false);
        self.force.resize(n_pairs, PairForce::default());
    }
}

/// Buffers of the step, kept from step to step so that the step allocates
/// nothing once they have grown.
#[derive(Debug, Clone, Default)]
struct StepScratch {
    /// Per particle block: what its half kick found.
    block_sums: Vec<KickSums>,
    /// Per particle block: the books of its wall contacts.
    wall_books: Vec<BlockBooks>,
    /// Where the pairs leave their forces (parallel step).
    pair_slots: PairSlots,
    /// Per pair block: the books of its contacts.
    pair_books: Vec<BlockBooks>,
    /// Pair blocks of the current step (parallel step).
    pair_blocks: usize,
}

/// Which kind of contact a block of books holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Kind {
    Pair,
    Wall,
}

/// What the stability checks refuse, and whether dissipation is booked per
/// particle, for the contacts of a step.
#[derive(Debug, Clone, Copy)]
struct Limits {
    min_steps_per_collision: f64,
    max_overlap_ratio: f64,
    per_particle: bool,
}

impl Limits {
    fn of(n: &Numerics, per_particle: bool) -> Self {
        Limits {
            min_steps_per_collision: n.min_steps_per_collision,
            max_overlap_ratio: n.max_overlap_ratio,
            per_particle,
        }
    }

    /// A collision resolved in too few steps or an excessive overlap stops
    /// the run.
    #[inline(always)]
    fn check(&self, out: &ContactResult) -> Result<(), Refusal> {
        if out.steps_per_collision < self.min_steps_per_collision {
            Err(Refusal::Unresolved)
        } else if out.overlap_ratio > self.max_overlap_ratio {
            Err(Refusal::Overlap)
        } else {
            Ok(())
        }
    }
}

/// What the contacts of one block book over a step, summed in contact order
/// ([`World::book`] adds the blocks to the ledger in block order). Aligned
/// to two cache lines, so that threads adding up neighbouring blocks never
/// write the same line.
#[derive(Debug, Clone)]
#[repr(align(128))]
struct BlockBooks {
    normal_j: f64,
    tangential_j: f64,
    stiffness_work_j: f64,
    integrator_j: f64,
    stored_change_j: f64,
    /// Fastest approach at contact onset (m/s).
    fastest_onset_mps: f64,
    /// Fewest steps an opening collision takes.
    fewest_steps: f64,
    /// Walls: each touching contact's force on its particle, in order (their
    /// sum, the force of the walls, is taken contact by contact).
    wall_forces: Vec<DVec3>,
    /// While dissipation is booked per particle: each contact's particles
    /// (the second unused for a wall) and dissipation (J), in order.
    dissipation: Vec<(u32, u32, f64)>,
    /// The first contact of the block that stops the run.
    refused: Option<(ContactAt, ContactResult, Refusal)>,
}

impl Default for BlockBooks {
    fn default() -> Self {
        BlockBooks {
            normal_j: 0.0,
            tangential_j: 0.0,
            stiffness_work_j: 0.0,
            integrator_j: 0.0,
            stored_change_j: 0.0,
            fastest_onset_mps: 0.0,
            fewest_steps: f64::INFINITY,
            wall_forces: Vec::new(),
            dissipation: Vec::new(),
            refused: None,
        }
    }
}

impl BlockBooks {
    /// Empties the books for a new step, keeping the buffers.
    fn clear(&mut self) {
        let (mut forces, mut dissipation) = (
            std::mem::take(&mut self.wall_forces),
            std::mem::take(&mut self.dissipation),
        );
        forces.clear();
        dissipation.clear();
        *self = BlockBooks {
            wall_forces: forces,
            dissipation,
            ..BlockBooks::default()
        };
    }

    /// Checks contact `at` and books it; false (and the contact kept as the
    /// block's refusal) when it stops the run.
    #[inline(always)]
    fn add(&mut self, limits: &Limits, at: ContactAt, out: &ContactResult, dt: f64) -> bool {
        if let Err(why) = limits.check(out) {
            self.refused = Some((at, *out, why));
            return false;
        }
        self.fastest_onset_mps = self.fastest_onset_mps.max(out.onset_speed_mps);
        self.fewest_steps = self.fewest_steps.min(out.steps_per_collision);
        if dt > 0.0 {
            self.normal_j += out.dissipated_normal_j;
            self.tangential_j += out.dissipated_tangential_j;
            self.stiffness_work_j += out.stiffness_work_j;
            self.integrator_j += out.integrator_j;
            self.stored_change_j += out.stored_change_j;
            if limits.per_particle {
                let e = out.dissipated_normal_j + out.dissipated_tangential_j;
                let (i, j) = match at {
                    ContactAt::Pair(i, j) => (i as u32, j as u32),
                    ContactAt::Wall(i, _) => (i as u32, u32::MAX),
                };
                self.dissipation.push((i, j, e));
            }
        }
        true
    }
}

/// Which instance of the force loops a law needs: (damped, frictional).
fn law_kind(law: &ContactLaw) -> (bool, bool) {
    (
        matches!(law.damping, NormalDamping::Restitution { .. }),
        matches!(law.tangential, Tangential::MindlinCoulomb { .. }),
    )
}

/// Which half of velocity Verlet a particle pass is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Pass {
    /// Half kick, then drift; the power is read after the drift.
    KickDrift,
    /// The power is read, then the second half kick.
    Kick,
}

/// One particle pass of velocity Verlet.
#[derive(Debug, Clone, Copy)]
struct Kick {
    pass: Pass,
    dt: f64,
    gravity: DVec3,
    /// Integrate the spin too (some law has friction).
    rotation: bool,
    /// Squared travel from where the pair list was built beyond which it
    /// must be rebuilt (m²).
    travel_sq_m2: f64,
}

/// What a half kick found, over a block or over all particles.
#[derive(Debug, Clone, Copy, Default)]
struct KickSums {
    /// `carry` plus the contact power `(F - m g)·v + τ·ω`, summed in order.
    work: f64,
    /// The first particle whose position is not finite (drift only).
    nonfinite: Option<usize>,
    /// Some particle travelled more than half the skin since the pair list
    /// was built (drift only).
    moved_far: bool,
}

/// The loads and inertia of a block of particles.
struct Loads<'a> {
    force: &'a [DVec3],
    torque: &'a [DVec3],
    mass: &'a [f64],
    inv_mass: &'a [f64],
    inv_inertia: &'a [f64],
}

impl Kick {
    /// The pass over one block of positions `x`, velocities `v` and spins `w`
    /// (`built_at`: where the pair list was built for them): returns `carry`
    /// plus the contact power `(F - m g)·v + τ·ω` summed over the block in
    /// order, and on the first pass the first particle of the block whose
    /// position is not finite and whether one drifted far enough to need a
    /// new pair list.
    #[inline]
    fn block(
        &self,
        l: &Loads,
        x: &mut [DVec3],
        v: &mut [DVec3],
        w: &mut [DVec3],
        built_at: Option<&[DVec3]>,
        carry: f64,
    ) -> KickSums {
        let half = 0.5 * self.dt;
        let g = self.gravity;
        let mut work = carry;
        for k in 0..x.len() {
            let contact = l.force[k] - g * l.mass[k];
            match self.pass {
                Pass::KickDrift => {
                    v[k] += l.force[k] * (l.inv_mass[k] * half);
                    x[k] += v[k] * self.dt;
                    if self.rotation {
                        w[k] += l.torque[k] * (l.inv_inertia[k] * half);
                        work += contact.dot(v[k]) + l.torque[k].dot(w[k]);
                    } else {
                        work += contact.dot(v[k]);
                    }
                }
                Pass::Kick => {
                    if self.rotation {
                        work += contact.dot(v[k]) + l.torque[k].dot(w[k]);
                        w[k] += l.torque[k] * (l.inv_inertia[k] * half);
                    } else {
                        work += contact.dot(v[k]);
                    }
                    v[k] += l.force[k] * (l.inv_mass[k] * half);
                }
            }
        }
        let (nonfinite, moved_far) = match (self.pass, built_at) {
            (Pass::Kick, _) => (None, false),
            (Pass::KickDrift, built_at) => (
                x.iter().position(|p| !p.is_finite()),
                built_at.is_some_and(|r| {
                    x.iter()
                        .zip(r)
                        .any(|(p, q)| (*p - *q).length_squared() > self.travel_sq_m2)
                }),
            ),
        };
        KickSums {
            work,
            nonfinite,
            moved_far,
        }
    }
}

/// Gravity and the wall contacts of the particles `start..` of one block:
/// their forces and torques are set, the wall states advanced, and the
/// touching contacts booked in `books`, in (particle, wall) order; a
/// contact that stops the run (an escaped particle, say) ends the block.
#[allow(clippy::too_many_arguments)]
#[inline]
fn wall_block<const D: bool, const F: bool>(
    law: &ContactLaw,
    walls: &WallGeometry,
    bodies: &Bodies,
    g: DVec3,
    start: usize,
    force: &mut [DVec3],
    torque: &mut [DVec3],
    (states, gaps): (&mut [ContactState], &mut [f64]),
    (limits, books): (Limits, &mut BlockBooks),
    dt: f64,
) {
    books.clear();
    let n_walls = walls.shapes.len();
    for (m, (f, t)) in force.iter_mut().zip(torque.iter_mut()).enumerate() {
        let i = start + m;
        *f = g * bodies.mass[i];
        *t = DVec3::ZERO;
        let r = bodies.radius[i];
        let x = bodies.position[i];
        for (w, shape) in walls.shapes.iter().enumerate() {
            let gap = &mut gaps[m * n_walls + w];
            let dist = shape.distance_m(x, walls.offset);
            if r - dist <= 0.0 && *gap <= 0.0 {
                *gap = r - dist;
                continue;
            }
            let st = &mut states[m * n_walls + w];
            if *gap <= 0.0 {
                // Opening: the contact's books start from the gap.
                st.delta_prev = *gap;
            }
            let normal = shape.normal_from(x);
            let at = ContactAt::Wall(i, w);
            if dist <= 0.0 {
                books.refused = Some((at, ContactResult::default(), Refusal::Escaped));
                return;
            }
            let out = wall_contact::<D, F>(law, bodies, i, dist, normal, walls.v_wall, dt, st);
            *gap = st.delta_prev;
            if !books.add(&limits, at, &out, dt) {
                return;
            }
            books.wall_forces.push(out.force_i);
            *f += out.force_i;
            if F {
                *t += out.torque_i;
            }
        }
    }
}

/// The pair contacts `start..` of one block: states advanced, whether each
/// pair acts written on both its sides and, when it does, its forces, and
/// its books in `books`; a contact that stops the run ends the block.
#[allow(clippy::too_many_arguments)]
#[inline]
fn pair_block<const D: bool, const F: bool>(
    law: &ContactLaw,
    bodies: &Bodies,
    pairs: &[(u32, u32)],
    (gaps, states): (&mut [f64], &mut [ContactState]),
    (acts, forces): (&mut [bool], &mut [PairForce]),
    (limits, books): (&Limits, &mut BlockBooks),
    dt: f64,
) {
    books.clear();
    let slots = gaps.iter_mut().zip(states);
    let outs = acts.iter_mut().zip(forces);
    for ((&(i, j), (gap, st)), (act, f)) in pairs.iter().zip(slots).zip(outs) {
        let out = pair_contact::<D, F>(law, bodies, i as usize, j as usize, dt, gap, st);
        *act = out.is_some();
        if let Some(out) = out {
            if !books.add(limits, ContactAt::Pair(i as usize, j as usize), &out, dt) {
                return;
            }
            *f = PairForce {
                force_i: out.force_i,
                torque_i: out.torque_i,
                torque_j: out.torque_j,
            };
        }
    }
}

/// Adds to the forces and torques of the particles `start..` of one block
/// the forces of their acting pairs, each particle's in pair order: the
/// pairs, the order, and so the rounding, of the serial loop that adds each
/// acting pair to both its particles.
#[inline]
fn gather_block<const F: bool>(
    list: &NeighbourList,
    slots: &PairSlots,
    start: usize,
    force: &mut [DVec3],
    torque: &mut [DVec3],
) {
    for (m, (f, t)) in force.iter_mut().zip(torque.iter_mut()).enumerate() {
        let p = start + m;
        let (mut fa, mut ta) = (*f, *t);
        // Pairs (i, p), i < p, come first in pair order: the j side.
        for &k in list.j_side_pairs(p) {
            let k = k as usize;
            if !slots.acts[k] {
                continue;
            }
            let c = &slots.force[k];
            fa -= c.force_i;
            if F {
                ta += c.torque_j;
            }
        }
        // Then pairs (p, j): the row.
        for k in list.row(p) {
            if !slots.acts[k] {
                continue;
            }
            let c = &slots.force[k];
            fa += c.force_i;
            if F {
                ta += c.torque_i;
            }
        }
        *f = fa;
        *t = ta;
    }
}

/// Steps an opening collision will take, and its approach speed: the Hertz
/// duration (eq. 5.10) at the normal approach speed, when the contact opens
/// during a step of `dt` (else infinitely many steps and no onset speed).
#[inline]
fn onset(
    law: &ContactLaw,
    geometry: &ContactGeometry,
    dt: f64,
    state: &ContactState,
) -> (f64, f64) {
    if dt > 0.0 && state.delta_prev <= 0.0 {
        let v_n = geometry.v_rel.dot(geometry.normal).max(0.0);
        let t_c = hertz_theory::contact_duration_s(
            geometry.m_star_kg,
            law.e_star_pa,
            geometry.r_star_m,
            v_n,
        );
        (t_c / dt, v_n)
    } else {
        (f64::INFINITY, 0.0)
    }
}

/// Evaluates a touching contact and what the checks need: the contact
/// point's lever `arms` on bodies i and j (zero for a wall; unused without
/// friction), and the smaller radius the overlap is measured against. Always
/// inlined: the result is then written straight into the caller's slot
/// instead of being copied (a 10 % cost per step when it was not).
#[inline(always)]
fn resolve_contact<const D: bool, const F: bool>(
    law: &ContactLaw,
    geometry: &ContactGeometry,
    (arm_i, arm_j): (DVec3, DVec3),
    smaller_radius_m: f64,
    dt: f64,
    st: &mut ContactState,
) -> ContactResult {
    let (steps_per_collision, onset_speed_mps) = onset(law, geometry, dt, st);
    let out = evaluate_contact_with::<D, F>(law, geometry, dt, st);
    let (torque_i, torque_j) = if F {
        (
            arm_i.cross(out.tangential_on_i),
            arm_j.cross(-out.tangential_on_i),
        )
    } else {
        (DVec3::ZERO, DVec3::ZERO)
    };
    ContactResult {
        force_i: out.force_on_i,
        torque_i,
        torque_j,
        dissipated_normal_j: out.dissipated_normal_j,
        dissipated_tangential_j: out.dissipated_tangential_j,
        stiffness_work_j: out.stiffness_work_j,
        integrator_j: out.integrator_j,
        stored_change_j: out.stored_change_j,
        overlap_ratio: geometry.delta_m / smaller_radius_m,
        approach_mps: geometry.v_rel.dot(geometry.normal),
        steps_per_collision,
        onset_speed_mps,
    }
}

/// One particle-wall contact (thesis Section 3.3: overlap eq. 3.12, normal eq.
/// 3.14; a flat wall, R* = R and m* = m). `dist` is the centre's distance to
/// the wall and `normal` points from the centre to the wall. Without
/// friction the spin is left out of the contact velocity: only its normal
/// part acts, and the spin has none.
#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn wall_contact<const D: bool, const F: bool>(
    law: &ContactLaw,
    b: &Bodies,
    i: usize,
    dist: f64,
    normal: DVec3,
    v_wall: DVec3,
    dt: f64,
    st: &mut ContactState,
) -> ContactResult {
    let r = b.radius[i];
    let delta = r - dist;
    let (arm, v_rel) = if F {
        let arm = normal * (r - 0.5 * delta.max(0.0));
        (
            arm,
            b.velocity[i] + b.angular_velocity[i].cross(arm) - v_wall,
        )
    } else {
        (DVec3::ZERO, b.velocity[i] - v_wall)
    };
    let geometry = ContactGeometry {
        r_star_m: r,
        m_star_kg: b.mass[i],
        delta_m: delta,
        normal,
        v_rel,
    };
    resolve_contact::<D, F>(law, &geometry, (arm, DVec3::ZERO), r, dt, st)
}

/// One particle-particle contact (thesis eq. 3.1–3.8, 3.26–3.27); `None`
/// when the particles are apart and were apart. `gap` is the pair's overlap
/// at the previous step (negative: the gap), remembered for the trapezoid
/// at contact onset and updated here; `st` is read only when they touch.
#[inline(always)]
fn pair_contact<const D: bool, const F: bool>(
    law: &ContactLaw,
    b: &Bodies,
    i: usize,
    j: usize,
    dt: f64,
    gap: &mut f64,
    st: &mut ContactState,
) -> Option<ContactResult> {
    let d = b.position[j] - b.position[i];
    let (ri, rj) = (b.radius[i], b.radius[j]);
    let dist_sq = d.length_squared();
    let reach = ri + rj;
    if dist_sq >= reach * reach && *gap <= 0.0 {
        *gap = reach - dist_sq.sqrt();
        return None;
    }
    if *gap <= 0.0 {
        // Opening: the contact's books start from the gap.
        st.delta_prev = *gap;
    }
    let dist = dist_sq.sqrt();
    let n = d / dist;
    let delta = reach - dist;
    let (arms, v_rel) = if F {
        let half_overlap = 0.5 * delta.max(0.0);
        let arm_i = n * (ri - half_overlap);
        let arm_j = -n * (rj - half_overlap);
        let v_rel = b.velocity[i] + b.angular_velocity[i].cross(arm_i)
            - b.velocity[j]
            - b.angular_velocity[j].cross(arm_j);
        ((arm_i, arm_j), v_rel)
    } else {
        ((DVec3::ZERO, DVec3::ZERO), b.velocity[i] - b.velocity[j])
    };
    let geometry = ContactGeometry {
        r_star_m: effective_radius_m(ri, rj),
        m_star_kg: effective_mass_kg(b.mass[i], b.mass[j]),
        delta_m: delta,
        normal: n,
        v_rel,
    };
    let out = resolve_contact::<D, F>(law, &geometry, arms, ri.min(rj), dt, st);
    *gap = st.delta_prev;
    Some(out)
}
