//! The DEM world: particles, walls, contact histories, and the time step.
//!
//! [`World`] holds the state in plain structs and advances it with
//! [`World::step`], a short pipeline of the named stages of
//! [`super::step`], each in its own file:
//! 1. half kick and drift of velocity Verlet ([`integrate`]; symplectic,
//!    unlike the explicit Euler of Terzioglu's thesis eq. 3.29–3.30), of the
//!    free spheres and then of the rigid bodies ([`clump_motion`], Section
//!    4.2), which places their sub-spheres;
//! 2. the walls move to the prescribed displacement for the end of the step
//!    ([`drive`]);
//! 3. the pair list is rebuilt if some particle moved more than half the
//!    skin ([`neighbour_update`], Section 3.4), a bed of several blocks
//!    renumbered in space with it ([`crate::dem::ordering`]);
//! 4. forces at the new positions (gravity, wall and pair contacts, eq.
//!    3.25–3.28), with the half-step velocities for damping and tangential
//!    displacement ([`forces`], block by block), each contact checked and
//!    booked ([`checks`], [`books`]);
//! 5. the second half kick ([`integrate`]), each block first adding the
//!    forces of the pairs that reach it from earlier blocks, then the
//!    bodies' from their sub-spheres' forces ([`clump_motion`]);
//! 6. the step's books are closed ([`books::close_step`], eq. 6.4);
//! 7. every few thousand steps, the energy books are checked
//!    ([`checks::energy_closes`]).
//!
//! Every loop runs over the fixed blocks of particles of [`block_size`], and
//! each particle's forces are summed in a fixed order (gravity, its walls in
//! order, its pairs within its block in pair order, then those from earlier
//! blocks in pair order), so results are bit-identical whatever the number
//! of threads. When no law has friction the rotation is not integrated at
//! all (nothing could change it).
//!
//! **Threads.** A bed of one block (the thesis bed) is one serial loop.
//! A larger bed's blocks can run side by side on the threads the world is
//! given ([`World::set_step_threads`]; none but the caller's unless it is),
//! each writing only its own particles, pairs and books; whether they do is
//! decided by timing both ways as the world steps ([`thread_choice`]). Both
//! ways give the same bits; the tests compare them. The step's buffers,
//! threads and timing are its [`StepWorkspace`], not the world's state.
//!
//! [`block_size`]: super::step::block_size
//! [`thread_choice`]: super::step::thread_choice
//! [`integrate`]: super::step::integrate
//! [`drive`]: super::step::drive
//! [`clump_motion`]: super::step::clump_motion
//! [`neighbour_update`]: super::step::neighbour_update
//! [`forces`]: super::step::forces
//! [`checks`]: super::step::checks
//! [`books`]: super::step::books
//! [`books::close_step`]: super::step::books::close_step
//! [`checks::energy_closes`]: super::step::checks::energy_closes

use crate::clock::Stopwatch;

use glam::DVec3;

use super::contact::{ContactLaw, ContactState};
use super::error::DemError;
use super::ledger::{EnergyState, Ledger, LedgerSnapshot};
use super::neighbours::NeighbourList;
use super::particles::Particles;
use super::step::block_size::spans_blocks;
use super::step::books::{self, Books};
use super::step::checks::{self, Diagnosis, Limits};
use super::step::forces::ForceStage;
use super::step::integrate::{KickSums, VelocityVerlet};
use super::step::neighbour_update::PerParticle;
use super::step::thread_choice::ThreadChoice;
use super::step::workspace::StepWorkspace;
use super::step::{clump_motion, drive, neighbour_update};
use super::walls::Walls;

pub use super::step::books::CollisionSteps;
pub use super::step::checks::ImpactSpeeds;

/// The default of [`Numerics::parallel_min_pairs`]: vlab decides when to
/// split a step across threads by timing both ways
/// ([`super::step::thread_choice`]); a smaller value forces the split.
pub const AUTO_PARALLEL_MIN_PAIRS: usize = 8192;

/// Tunables of a world that are not physics.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Numerics {
    /// Time step (s).
    pub dt_s: f64,
    /// Verlet-list skin as a fraction of the largest radius.
    pub skin_ratio: f64,
    /// Overlap, as a fraction of the smaller radius, taken as a sign of instability.
    pub max_overlap_ratio: f64,
    /// Deprecated: vlab chooses when to use threads by timing both ways
    /// ([`AUTO_PARALLEL_MIN_PAIRS`], the default). A value below that makes
    /// the step go parallel from this many listed pairs on, whenever the bed
    /// has several blocks (tests use 0 to run the parallel path on a small
    /// bed); the results are the same bits either way.
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
    /// What the step works with: buffers, threads, the serial/parallel
    /// choice. Not state: a clone gets a new one of the same thread count.
    workspace: StepWorkspace,
    /// Total force of the walls on the particles at the current step (N).
    wall_force: DVec3,
    /// The same, wall by wall.
    wall_force_by_wall: Vec<DVec3>,
    /// Ledger reading the energy check compares against.
    baseline: LedgerSnapshot,
    /// Largest normal approach speed at contact onset since the last reset (m/s).
    pub impact_speeds: ImpactSpeeds,
    /// Energy each particle's contacts dissipated since tracking began (J),
    /// while tracked ([`World::track_particle_dissipation`]).
    particle_dissipation_j: Option<Vec<f64>>,
    /// Fewest time steps a collision that began since the counting started
    /// ([`World::start_collision_records`]) was planned to take: the Hertz
    /// duration at its approach speed (eq. 5.10) over the step, what the
    /// time-step rule plans with; infinite when none began.
    pub planned_steps_per_contact: f64,
    /// Fewest time steps a collision took, counted from the first to the
    /// last step of overlap, over the collisions that both began and ended
    /// since the counting started (one open then, or still open, is not
    /// counted); `None` while none did.
    pub fewest_counted_steps_per_contact: Option<u32>,
    /// Of the collisions counted, the one the Hertz duration planned the
    /// fewest steps for (the fastest impact): planned and counted; `None`
    /// while none was counted.
    pub fastest_collision: Option<CollisionSteps>,
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
            workspace: StepWorkspace::default(),
            wall_force: DVec3::ZERO,
            wall_force_by_wall: Vec::new(),
            baseline: LedgerSnapshot::default(),
            impact_speeds: ImpactSpeeds::default(),
            particle_dissipation_j: None,
            planned_steps_per_contact: f64::INFINITY,
            fewest_counted_steps_per_contact: None,
            fastest_collision: None,
        };
        world.reset_contacts();
        world.compute_forces(0.0, false, false)?;
        world.rebaseline();
        Ok(world)
    }

    /// Restarts the energy check from the current state; call after editing the
    /// world by hand (changing gravity, moving a wall, placing particles).
    pub fn rebaseline(&mut self) {
        self.baseline = self.snapshot();
    }

    /// Checks that the energy books still close since the last baseline: energy
    /// Checks that the energy books still close since the last baseline: energy
    /// the integration made or lost (its own channel plus the residual) above
    /// 2 % of the energy in play (kinetic + elastic + dissipated + |work in|)
    /// means the integration has gone wrong, typically energy growing without
    /// any input because the step is too coarse ([`checks::energy_closes`]).
    pub fn check_energy(&self) -> Result<(), DemError> {
        let now = self.snapshot();
        let at = (self.time_s, self.steps, self.numerics.dt_s);
        checks::energy_closes(&self.baseline, &now, at)
    }

    /// Forgets every contact history and re-reads the geometry (after the scene was
    /// edited, e.g. particles placed or walls moved by hand). A bed of
    /// several blocks is renumbered in space here, as at every rebuild of
    /// its pair list.
    pub fn reset_contacts(&mut self) {
        self.neighbours = NeighbourList::new(self.neighbours.skin_m());
        self.update_neighbours(true);
        let n_walls = self.walls.len();
        self.wall_states.clear();
        self.wall_gaps.clear();
        for i in 0..self.particles.len() {
            for w in 0..n_walls {
                let offset = self.walls.offset_of(w);
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
        self.compute_forces(0.0, false, false)?;
        self.rebaseline();
        Ok(())
    }

    /// Replaces the walls (the closed enclosure a bed settled in by a shear
    /// box, say): every contact history is dropped and the forces are
    /// evaluated anew; the energy check restarts from here.
    pub fn set_walls(&mut self, walls: Walls) -> Result<(), DemError> {
        self.walls = walls;
        self.reset_contacts();
        self.compute_forces(0.0, false, false)?;
        self.rebaseline();
        Ok(())
    }

    /// Changes the time step. The state carries over unchanged: velocity
    /// Verlet's forces depend on positions only.
    pub fn set_dt_s(&mut self, dt_s: f64) {
        self.numerics.dt_s = dt_s;
        self.rebaseline();
    }

    /// Starts the energy ledger and the records of the collisions from zero:
    /// what follows is the experiment.
    pub fn start_ledger(&mut self) {
        self.ledger = Ledger::default();
        self.start_collision_records();
        self.rebaseline();
    }

    /// Starts the records of the collisions from zero: the fastest impacts,
    /// the fewest steps planned and the fewest counted. The contacts open now
    /// are left out of the count (their beginning is not in it); only the
    /// collisions that begin from here on are counted.
    pub fn start_collision_records(&mut self) {
        self.impact_speeds = ImpactSpeeds::default();
        self.planned_steps_per_contact = f64::INFINITY;
        self.fewest_counted_steps_per_contact = None;
        self.fastest_collision = None;
        for st in self
            .neighbours
            .states
            .iter_mut()
            .chain(&mut self.wall_states)
        {
            st.steps_touching = 0;
        }
    }

    /// Changes the Verlet skin (a fraction of the largest radius) and rebuilds the
    /// pair list, keeping every contact's history.
    pub fn set_skin_ratio(&mut self, skin_ratio: f64) {
        self.numerics.skin_ratio = skin_ratio;
        self.neighbours
            .set_skin_m(skin_ratio * self.particles.max_radius_m());
        self.update_neighbours(true);
    }

    /// The neighbour update ([`neighbour_update::update`]): the pair list
    /// rebuilt when `rebuild` or when it may miss a contact, a bed of
    /// several blocks renumbered in space with it.
    fn update_neighbours(&mut self, rebuild: bool) {
        let per_particle = PerParticle {
            wall_states: &mut self.wall_states,
            wall_gaps: &mut self.wall_gaps,
            n_walls: self.walls.len(),
            dissipation_j: self.particle_dissipation_j.as_mut(),
        };
        neighbour_update::update(
            &mut self.neighbours,
            &mut self.particles,
            per_particle,
            &mut self.workspace.order,
            rebuild,
        );
    }

    /// Re-reads the gap to every wall a particle does not touch, after walls were
    /// moved by hand (closing the lid); contacts in progress keep their history.
    pub fn refresh_wall_gaps(&mut self) {
        let n_walls = self.walls.len();
        for (k, gap) in self.wall_gaps.iter_mut().enumerate() {
            if *gap > 0.0 {
                continue;
            }
            let (i, w) = (k / n_walls, k % n_walls);
            let dist = self.walls.shapes[w]
                .distance_m(self.particles.position[i], self.walls.offset_of(w));
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

    /// Force wall `w` exerts on the particles now (N).
    pub fn wall_force_of(&self, w: usize) -> DVec3 {
        self.wall_force_by_wall
            .get(w)
            .copied()
            .unwrap_or(DVec3::ZERO)
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
    /// is in now, into `counts` (resized to the particle count), in id order
    /// (the order of [`Particles::by_id`]).
    pub fn contacts_per_particle(&self, counts: &mut Vec<u32>) {
        let n = self.particles.len();
        counts.clear();
        counts.resize(n, 0);
        let id = |k: usize| self.particles.id[k] as usize;
        for (&(i, j), &d) in self.neighbours.pairs.iter().zip(&self.neighbours.gaps) {
            if d > 0.0 {
                counts[id(i as usize)] += 1;
                counts[id(j as usize)] += 1;
            }
        }
        let n_walls = self.walls.len().max(1);
        for (k, &d) in self.wall_gaps.iter().enumerate() {
            if d > 0.0 {
                counts[id(k / n_walls)] += 1;
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
    /// when tracked, in id order (the order of [`Particles::by_id`]).
    pub fn particle_dissipation_j(&self) -> Option<Vec<f64>> {
        let d = self.particle_dissipation_j.as_ref()?;
        let mut by_id = vec![0.0; d.len()];
        for (&id, &e) in self.particles.id.iter().zip(d) {
            by_id[id as usize] = e;
        }
        Some(by_id)
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
            * (dt * dt / 8.0)
            + p.clumps.verlet_shadow_j(dt);
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

    /// Whether steps now run on all threads of the current pool: several
    /// threads, several blocks, and the parallel step timed faster (or
    /// forced). The results are the same bits either way.
    pub fn splits_across_threads(&self) -> bool {
        self.can_split() && (self.forced_split() || self.workspace.choice.parallel())
    }

    /// Times the serial and the parallel step anew from the next step on
    /// (a trial of [`TRIAL_STEPS`] steps), as if the world were new: a bench
    /// calls it before it warms a bed up, so that no trial falls in its
    /// timed steps.
    ///
    /// [`TRIAL_STEPS`]: super::TRIAL_STEPS
    pub fn retime_threads(&mut self) {
        self.workspace.choice = ThreadChoice::default();
    }

    /// Lets a step use `threads` threads, the caller's included (a new
    /// world's steps run on the caller alone). Whoever runs worlds side by
    /// side gives each its share of the cores, so that N beds on P cores
    /// keep P threads busy, not N × P. The same bits whatever the count.
    pub fn set_step_threads(&mut self, threads: usize) {
        if self.workspace.threads() != threads.max(1) {
            self.workspace = StepWorkspace::new(threads);
        }
    }

    /// Threads a step may use, the caller's included.
    pub fn step_threads(&self) -> usize {
        self.workspace.threads()
    }

    /// Helper threads the step's team has started (none until a step of
    /// several blocks first splits).
    pub fn step_helpers_started(&self) -> usize {
        self.workspace.team.helpers_started()
    }

    /// Whether a step can split across threads: several threads given and
    /// several blocks of particles.
    fn can_split(&self) -> bool {
        self.workspace.threads() > 1 && spans_blocks(self.particles.len())
    }

    /// Whether the split is forced ([`Numerics::parallel_min_pairs`] below
    /// its default, and that many pairs listed).
    fn forced_split(&self) -> bool {
        let from = self.numerics.parallel_min_pairs;
        from < AUTO_PARALLEL_MIN_PAIRS && self.neighbours.pairs.len() >= from
    }

    /// True when some law has friction: only then can a particle's spin change.
    fn rotates(&self) -> bool {
        self.pp_law.has_friction() || self.pw_law.has_friction()
    }

    /// Advances one step; the wall body ends the step at `wall_displacement_m`.
    pub fn step(&mut self, wall_displacement_m: f64) -> Result<(), DemError> {
        let dt = self.numerics.dt_s;
        let started = Stopwatch::start();
        let parallel = self
            .workspace
            .choice
            .pick(self.can_split(), self.forced_split());
        let verlet = self.integrator();
        // 1. Integration: half kick and drift; a position that is not finite stops.
        let (sums, team) = (&mut self.workspace.kick_sums, &mut self.workspace.team);
        let team = parallel.then_some(team);
        let mut drift = verlet.kick_drift(&mut self.particles, &self.neighbours, sums, team);
        if !self.particles.clumps.is_empty() {
            let built = self.neighbours.reference();
            let built = (built.len() == self.particles.len()).then_some(built);
            let bodies = clump_motion::kick_drift(
                &mut self.particles,
                (dt, self.gravity),
                (built, self.neighbours.rebuild_travel_sq_m2()),
                drift.work,
            );
            drift = KickSums {
                work: bodies.work,
                nonfinite: drift.nonfinite.or(bodies.nonfinite),
                moved_far: drift.moved_far || bodies.moved_far,
            };
        }
        if let Some(i) = drift.nonfinite {
            return Err(self.diagnosis().nonfinite(i, dt));
        }
        // 2. The walls' stroke.
        let stroke = drive::move_walls(
            &mut self.walls,
            wall_displacement_m,
            dt,
            self.wall_force,
            &self.wall_force_by_wall,
        );
        // 3. Neighbour update.
        self.update_neighbours(drift.moved_far);
        // 4. Contact forces, each contact checked and booked.
        let booked_before = self.ledger;
        self.step_stored_change_j = 0.0;
        self.compute_forces(dt, true, parallel)?;
        // 5. Integration: second half kick, each block first adding the
        //    forces its pairs from earlier blocks left.
        let shares = self.workspace.forces.cross_shares(
            &self.neighbours,
            self.particles.len(),
            self.pp_law.has_friction(),
        );
        let (sums, team) = (&mut self.workspace.kick_sums, &mut self.workspace.team);
        let team = parallel.then_some(team);
        let mut kick = verlet.kick(&mut self.particles, shares, sums, drift.work, team);
        if !self.particles.clumps.is_empty() {
            kick.work = clump_motion::kick(&mut self.particles, (dt, self.gravity), kick.work);
        }
        // 6. The step's books close.
        books::close_step(
            &mut self.ledger,
            &booked_before,
            self.step_stored_change_j,
            kick.work * (0.5 * dt),
            stroke.work_in_j(&self.walls, self.wall_force, &self.wall_force_by_wall),
        );
        self.time_s += dt;
        self.steps += 1;
        self.workspace.choice.record(started.elapsed());
        // 7. Every few thousand steps, the energy books must still close.
        if self.steps % self.numerics.energy_check_steps == 0 {
            self.check_energy()?;
        }
        Ok(())
    }

    /// The integrator of this step: velocity Verlet, with the spin only when
    /// some law has friction.
    fn integrator(&self) -> VelocityVerlet {
        VelocityVerlet {
            dt_s: self.numerics.dt_s,
            gravity: self.gravity,
            rotation: self.rotates(),
        }
    }

    /// Where the run stands, for the diagnosis of a failed check.
    fn diagnosis(&self) -> Diagnosis<'_> {
        Diagnosis {
            time_s: self.time_s,
            steps: self.steps,
            dt_s: self.numerics.dt_s,
            max_overlap_ratio: self.numerics.max_overlap_ratio,
            wall_names: &self.walls.names,
            ids: &self.particles.id,
        }
    }

    /// Forces and torques at the current positions ([`ForceStage::run`]).
    /// `dt` is the step over which the tangential springs advance and the
    /// ledger accumulates (0 for a pure evaluation that changes no history).
    /// `defer_cross`: the shares of pairs into later blocks are left for the
    /// half kick that follows to add (a step); else added here. `parallel`:
    /// the blocks run on all threads of the step's team (the same bits
    /// either way).
    fn compute_forces(
        &mut self,
        dt: f64,
        defer_cross: bool,
        parallel: bool,
    ) -> Result<(), DemError> {
        self.wall_force_by_wall.clear();
        self.wall_force_by_wall
            .resize(self.walls.len(), DVec3::ZERO);
        let stage = ForceStage {
            team: parallel.then_some(&mut self.workspace.team),
            defer_cross,
            limits: Limits {
                min_steps_per_collision: self.numerics.min_steps_per_collision,
                max_overlap_ratio: self.numerics.max_overlap_ratio,
                per_particle: self.particle_dissipation_j.is_some(),
            },
            particles: &mut self.particles,
            walls: &self.walls,
            pp_law: self.pp_law,
            pw_law: self.pw_law,
            gravity: self.gravity,
            neighbours: &mut self.neighbours,
            wall_states: &mut self.wall_states,
            wall_gaps: &mut self.wall_gaps,
            scratch: &mut self.workspace.forces,
            books: Books {
                ledger: &mut self.ledger,
                stored_change_j: &mut self.step_stored_change_j,
                impact_speeds: &mut self.impact_speeds,
                planned_steps_per_contact: &mut self.planned_steps_per_contact,
                fewest_counted_steps_per_contact: &mut self.fewest_counted_steps_per_contact,
                fastest_collision: &mut self.fastest_collision,
                wall_force: &mut self.wall_force,
                wall_force_by_wall: &mut self.wall_force_by_wall,
                per_particle_j: self.particle_dissipation_j.as_deref_mut(),
            },
        };
        stage
            .run(dt)
            .map_err(|refused| self.diagnosis().refusal(&refused, dt))?;
        // A pure evaluation leaves the bodies their resultants now; a step's
        // second half kick gathers them itself, once the crossing shares
        // are in.
        if !defer_cross && !self.particles.clumps.is_empty() {
            clump_motion::gather(&mut self.particles, self.gravity);
        }
        Ok(())
    }
}
