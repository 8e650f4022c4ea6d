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
//! `(i, j)`), and pair contributions are computed into a buffer before they are
//! added, so results are bit-identical whatever the number of threads.

use glam::DVec3;
use rayon::prelude::*;

use super::contact::{ContactGeometry, ContactLaw, ContactState, evaluate_contact};
use super::error::DemError;
use super::hertz_theory;
use super::ledger::{EnergyState, Ledger, LedgerBalance, LedgerSnapshot};
use super::material::{effective_mass_kg, effective_radius_m};
use super::neighbours::NeighbourList;
use super::particles::Particles;
use super::walls::Walls;

/// Tunables of a world that are not physics.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Numerics {
    /// Time step (s).
    pub dt_s: f64,
    /// Verlet-list skin as a fraction of the largest radius.
    pub skin_ratio: f64,
    /// Overlap, as a fraction of the smaller radius, taken as a sign of instability.
    pub max_overlap_ratio: f64,
    /// The pair loop is split across threads only from this many listed pairs on:
    /// below it, waking a second thread costs more than the loop (a thesis-scene
    /// step, ~2500 pairs, takes about 25 µs on one core).
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
    /// parallel pair loop from 16384 pairs, at least 5 steps per collision, energy
    /// books checked every 2000 steps.
    pub fn with_dt(dt_s: f64) -> Self {
        Numerics {
            dt_s,
            skin_ratio: 0.5,
            max_overlap_ratio: 0.10,
            parallel_min_pairs: 16384,
            min_steps_per_collision: 5.0,
            energy_check_steps: 2000,
        }
    }
}

/// What one contact contributed over a step, before it is booked: forces,
/// energies, and what the stability checks read. Pair and wall contacts both
/// produce one, and [`World::book`] checks and accumulates both the same way.
#[derive(Debug, Clone, Copy, Default)]
struct ContactResult {
    touching: bool,
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
    /// Contact state of particle `i` with wall `w` at `i * n_walls + w`.
    wall_states: Vec<ContactState>,
    pair_out: Vec<ContactResult>,
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
            pair_out: Vec::new(),
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
        for i in 0..self.particles.len() {
            for w in 0..n_walls {
                let (dist, _) =
                    self.walls.shapes[w].distance_and_normal(self.particles.position[i], offset);
                self.wall_states
                    .push(ContactState::apart(self.particles.radius[i] - dist));
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
        for (k, st) in self.wall_states.iter_mut().enumerate() {
            if st.delta_prev > 0.0 {
                continue;
            }
            let (i, w) = (k / n_walls, k % n_walls);
            let (dist, _) =
                self.walls.shapes[w].distance_and_normal(self.particles.position[i], offset);
            st.delta_prev = self.particles.radius[i] - dist;
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
            .zip(&self.neighbours.states)
            .map(|(&(i, j), st)| st.delta_prev / p.radius[i as usize].min(p.radius[j as usize]));
        let n_walls = self.walls.len().max(1);
        let walls = self
            .wall_states
            .iter()
            .enumerate()
            .map(|(k, st)| st.delta_prev / p.radius[k / n_walls]);
        pairs.chain(walls).fold(0.0, f64::max)
    }

    /// Number of particle-particle and particle-wall contacts now.
    pub fn contact_counts(&self) -> (usize, usize) {
        let pp = self
            .neighbours
            .states
            .iter()
            .filter(|s| s.delta_prev > 0.0)
            .count();
        let pw = self
            .wall_states
            .iter()
            .filter(|s| s.delta_prev > 0.0)
            .count();
        (pp, pw)
    }

    /// Number of contacts (particle-particle and particle-wall) each particle
    /// is in now, into `counts` (resized to the particle count).
    pub fn contacts_per_particle(&self, counts: &mut Vec<u32>) {
        let n = self.particles.len();
        counts.clear();
        counts.resize(n, 0);
        for (&(i, j), st) in self.neighbours.pairs.iter().zip(&self.neighbours.states) {
            if st.delta_prev > 0.0 {
                counts[i as usize] += 1;
                counts[j as usize] += 1;
            }
        }
        let n_walls = self.walls.len().max(1);
        for (k, st) in self.wall_states.iter().enumerate() {
            if st.delta_prev > 0.0 {
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

    /// Advances one step; the wall body ends the step at `wall_displacement_m`.
    pub fn step(&mut self, wall_displacement_m: f64) -> Result<(), DemError> {
        let dt = self.numerics.dt_s;
        let half = 0.5 * dt;
        let g = self.gravity;
        let p = &mut self.particles;
        // Work the contact forces do on the particles over the step, as velocity
        // Verlet applies them: the trapezoid of the forces (gravity taken out)
        // at both ends on the drift `v_half dt` (rotation: `ω_half dt`).
        let mut contact_work_j = 0.0;
        for i in 0..p.position.len() {
            p.velocity[i] += p.force[i] * (p.inv_mass[i] * half);
            p.angular_velocity[i] += p.torque[i] * (p.inv_inertia[i] * half);
            p.position[i] += p.velocity[i] * dt;
            contact_work_j += (p.force[i] - g * p.mass[i]).dot(p.velocity[i])
                + p.torque[i].dot(p.angular_velocity[i]);
        }
        if let Some(i) = p.position.iter().position(|x| !x.is_finite()) {
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

        if self.neighbours.needs_rebuild(&self.particles.position) {
            self.neighbours
                .rebuild(&self.particles.position, &self.particles.radius);
        }
        let booked_before = self.ledger;
        self.step_stored_change_j = 0.0;
        self.compute_forces(dt)?;

        let p = &mut self.particles;
        for i in 0..p.position.len() {
            contact_work_j += (p.force[i] - g * p.mass[i]).dot(p.velocity[i])
                + p.torque[i].dot(p.angular_velocity[i]);
            p.velocity[i] += p.force[i] * (p.inv_mass[i] * half);
            p.angular_velocity[i] += p.torque[i] * (p.inv_inertia[i] * half);
        }
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

    /// Human-readable name of a contact, for diagnoses.
    fn contact_name(&self, at: ContactAt) -> String {
        match at {
            ContactAt::Pair(i, j) => format!("particle-particle ({i}, {j})"),
            ContactAt::Wall(i, w) => format!("particle-{} (particle {i})", self.walls.names[w]),
        }
    }

    /// Checks one contact's result and adds it to the forces, the ledger and
    /// the impact speeds: the one path for pair and wall contacts. A collision
    /// resolved in too few steps or an excessive overlap stops the run.
    #[inline]
    fn book(&mut self, at: ContactAt, out: &ContactResult, dt: f64) -> Result<(), DemError> {
        let n = &self.numerics;
        if out.steps_per_collision < n.min_steps_per_collision {
            let duration_s = out.steps_per_collision * dt;
            return Err(DemError::UnresolvedCollision {
                time_s: self.time_s + dt,
                step: self.steps + 1,
                contact: self.contact_name(at),
                speed_mps: out.onset_speed_mps,
                duration_s,
                steps: out.steps_per_collision,
                dt_s: dt,
                suggested_dt_s: duration_s / 20.0,
            });
        }
        if out.overlap_ratio > n.max_overlap_ratio {
            return Err(DemError::ExcessiveOverlap {
                time_s: self.time_s + dt,
                step: self.steps + 1,
                contact: self.contact_name(at),
                overlap_percent: 100.0 * out.overlap_ratio,
                limit_percent: 100.0 * n.max_overlap_ratio,
                speed_mps: out.approach_mps,
                dt_s: self.numerics.dt_s,
            });
        }
        let p = &mut self.particles;
        let (fastest, ledger_normal, ledger_tangential) = match at {
            ContactAt::Pair(i, j) => {
                p.force[i] += out.force_i;
                p.force[j] -= out.force_i;
                p.torque[i] += out.torque_i;
                p.torque[j] += out.torque_j;
                let d = &mut self.ledger.dissipated;
                (
                    &mut self.impact_speeds.particle_particle_mps,
                    &mut d.pp_normal,
                    &mut d.pp_tangential,
                )
            }
            ContactAt::Wall(i, _) => {
                p.force[i] += out.force_i;
                p.torque[i] += out.torque_i;
                self.wall_force += out.force_i;
                let d = &mut self.ledger.dissipated;
                (
                    &mut self.impact_speeds.particle_wall_mps,
                    &mut d.pw_normal,
                    &mut d.pw_tangential,
                )
            }
        };
        *fastest = fastest.max(out.onset_speed_mps);
        self.fewest_steps_per_contact = self.fewest_steps_per_contact.min(out.steps_per_collision);
        if dt > 0.0 {
            *ledger_normal += out.dissipated_normal_j;
            *ledger_tangential += out.dissipated_tangential_j;
            self.ledger.stiffness_work_j += out.stiffness_work_j;
            self.ledger.integrator_j += out.integrator_j;
            self.step_stored_change_j += out.stored_change_j;
            if let Some(per) = &mut self.particle_dissipation_j {
                let e = out.dissipated_normal_j + out.dissipated_tangential_j;
                match at {
                    ContactAt::Pair(i, j) => {
                        per[i] += 0.5 * e;
                        per[j] += 0.5 * e;
                    }
                    ContactAt::Wall(i, _) => per[i] += e,
                }
            }
        }
        Ok(())
    }

    /// Forces and torques at the current positions. `dt` is the step over which the
    /// tangential springs advance and the ledger accumulates (0 for a pure
    /// evaluation that changes no history).
    fn compute_forces(&mut self, dt: f64) -> Result<(), DemError> {
        let p = &mut self.particles;
        for i in 0..p.len() {
            p.force[i] = self.gravity * p.mass[i];
            p.torque[i] = DVec3::ZERO;
        }
        self.wall_force = DVec3::ZERO;
        self.wall_contacts(dt)?;
        self.pair_contacts(dt)
    }

    fn wall_contacts(&mut self, dt: f64) -> Result<(), DemError> {
        let n_walls = self.walls.len();
        let offset = self.walls.offset();
        let v_wall = self.walls.velocity();
        for i in 0..self.particles.len() {
            for w in 0..n_walls {
                let p = &self.particles;
                let st = &mut self.wall_states[i * n_walls + w];
                let (dist, normal) =
                    self.walls.shapes[w].distance_and_normal(p.position[i], offset);
                let r = p.radius[i];
                if r - dist <= 0.0 && st.delta_prev <= 0.0 {
                    st.delta_prev = r - dist;
                    continue;
                }
                if dist <= 0.0 {
                    return Err(DemError::Escaped {
                        time_s: self.time_s + dt,
                        step: self.steps + 1,
                        particle: i,
                        wall: self.walls.names[w].to_string(),
                        dt_s: self.numerics.dt_s,
                    });
                }
                let out = wall_contact(&self.pw_law, p, i, dist, normal, v_wall, dt, st);
                self.book(ContactAt::Wall(i, w), &out, dt)?;
            }
        }
        Ok(())
    }

    fn pair_contacts(&mut self, dt: f64) -> Result<(), DemError> {
        let n_pairs = self.neighbours.pairs.len();
        self.pair_out.resize(n_pairs, ContactResult::default());
        let law = self.pp_law;
        let p = &self.particles;
        let work =
            |(&(i, j), (st, out)): (&(u32, u32), (&mut ContactState, &mut ContactResult))| {
                *out = pair_contact(&law, p, i as usize, j as usize, dt, st);
            };
        let pairs = &self.neighbours.pairs;
        let states = &mut self.neighbours.states;
        if rayon::current_num_threads() > 1 && n_pairs >= self.numerics.parallel_min_pairs {
            pairs
                .par_iter()
                .zip(states.par_iter_mut().zip(self.pair_out.par_iter_mut()))
                .with_min_len(256)
                .for_each(work);
        } else {
            pairs
                .iter()
                .zip(states.iter_mut().zip(self.pair_out.iter_mut()))
                .for_each(work);
        }

        // Fixed-order accumulation: identical sums for any thread count.
        let results = std::mem::take(&mut self.pair_out);
        let booked = results.iter().enumerate().try_for_each(|(k, out)| {
            if !out.touching {
                return Ok(());
            }
            let (i, j) = self.neighbours.pairs[k];
            self.book(ContactAt::Pair(i as usize, j as usize), out, dt)
        });
        self.pair_out = results;
        booked
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
/// point's lever `arms` on bodies i and j (zero for a wall), and the smaller
/// radius the overlap is measured against. Always inlined: the result is
/// then written straight into the caller's slot instead of being copied (a
/// 10 % cost per step when it was not).
#[inline(always)]
fn resolve_contact(
    law: &ContactLaw,
    geometry: &ContactGeometry,
    (arm_i, arm_j): (DVec3, DVec3),
    smaller_radius_m: f64,
    dt: f64,
    st: &mut ContactState,
) -> ContactResult {
    let (steps_per_collision, onset_speed_mps) = onset(law, geometry, dt, st);
    let out = evaluate_contact(law, geometry, dt, st);
    ContactResult {
        touching: true,
        force_i: out.force_on_i,
        torque_i: arm_i.cross(out.tangential_on_i),
        torque_j: arm_j.cross(-out.tangential_on_i),
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
/// the wall and `normal` points from the centre to the wall.
#[allow(clippy::too_many_arguments)]
#[inline]
fn wall_contact(
    law: &ContactLaw,
    p: &Particles,
    i: usize,
    dist: f64,
    normal: DVec3,
    v_wall: DVec3,
    dt: f64,
    st: &mut ContactState,
) -> ContactResult {
    let r = p.radius[i];
    let delta = r - dist;
    let arm = normal * (r - 0.5 * delta.max(0.0));
    let v_rel = p.velocity[i] + p.angular_velocity[i].cross(arm) - v_wall;
    let geometry = ContactGeometry {
        r_star_m: r,
        m_star_kg: p.mass[i],
        delta_m: delta,
        normal,
        v_rel,
    };
    resolve_contact(law, &geometry, (arm, DVec3::ZERO), r, dt, st)
}

/// One particle-particle contact (thesis eq. 3.1–3.8, 3.26–3.27).
#[inline]
fn pair_contact(
    law: &ContactLaw,
    p: &Particles,
    i: usize,
    j: usize,
    dt: f64,
    st: &mut ContactState,
) -> ContactResult {
    let d = p.position[j] - p.position[i];
    let (ri, rj) = (p.radius[i], p.radius[j]);
    let dist_sq = d.length_squared();
    let reach = ri + rj;
    if dist_sq >= reach * reach && st.delta_prev <= 0.0 {
        // Apart now and before: remember the gap for the trapezoid at contact onset.
        st.delta_prev = reach - dist_sq.sqrt();
        return ContactResult::default();
    }
    let dist = dist_sq.sqrt();
    let n = d / dist;
    let delta = reach - dist;
    let half_overlap = 0.5 * delta.max(0.0);
    let arm_i = n * (ri - half_overlap);
    let arm_j = -n * (rj - half_overlap);
    let v_rel = p.velocity[i] + p.angular_velocity[i].cross(arm_i)
        - p.velocity[j]
        - p.angular_velocity[j].cross(arm_j);
    let geometry = ContactGeometry {
        r_star_m: effective_radius_m(ri, rj),
        m_star_kg: effective_mass_kg(p.mass[i], p.mass[j]),
        delta_m: delta,
        normal: n,
        v_rel,
    };
    resolve_contact(law, &geometry, (arm_i, arm_j), ri.min(rj), dt, st)
}
