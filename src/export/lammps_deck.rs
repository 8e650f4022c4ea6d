//! A LAMMPS input deck for a vlab damper (`vlab export lammps`): the same
//! spheres, contact law, enclosure, drive and settled packing, run by LAMMPS
//! (one core, or `mpirun` on a cluster for beds too big for one machine),
//! with the enclosure's motion and the particles' force on it written in the
//! text `vlab replay` reads ([`crate::signals::lammps`]).
//!
//! # What the deck holds
//!
//! - `units si`; spheres (`atom_style sphere`) read from `packing.data`:
//!   vlab's settled packing ([`settle_bed`](crate::experiment::bed::settle::settle_bed)),
//!   positions, velocities, spins, diameters and densities; enclosure axis z,
//!   floor at z = 0, lid at the scene's inner length;
//! - for a scene of bodies (prolates, oblates, toroids, clumps: thesis
//!   Chapter 4 and Section 8.2) the atoms are the bodies' sub-spheres, each
//!   body one molecule, integrated as a rigid body by `fix rigid/small` with
//!   vlab's union mass, centre and inertia (eq. 4.1, 4.2, 4.5) from
//!   `bodies.txt`, gravity on that mass, and no contacts within a body
//!   ([`crate::export::lammps_bodies`]);
//! - `pair_style granular`, `hertz/material` (thesis eq. 5.7 with E* of eq.
//!   5.6), `tangential mindlin` (k_t = 8 G* √(R* δ), eq. 5.24, vector history,
//!   Coulomb cap μ F_n, eq. 5.16) and `damping tsuji` with `limit_damping` (a
//!   dashpot `α √(m* k_n)`, `k_n = 4/3 E* a`, whose force never pulls);
//! - the cylinder as two `fix wall/gran` walls of the same law that move with
//!   the drive by LAMMPS' `wiggle z`: the side (`zcylinder`) and the floor and
//!   lid (one `zplane` pair). Wiggle moves a wall as `u = A (1 - cos ωt)` from
//!   t = 0 at the settled packing, `A = Γ g / ω²` (eq. 6.2): the drive starts
//!   from rest, where a vlab shake starts mid-stroke (`u = A sin ωt`); the two
//!   start-ups differ, the steady drive does not. (Three moving region walls
//!   with a drive variable evaluated every step ran LAMMPS 2.3 times slower.)
//! - gravity along -z (vertical) or -y (horizontal), the time step vlab's
//!   drive would take at this frequency and Γ ([`Scene::drive_dt_s`]: the
//!   scene's `simulation.dt_s` rule) and `cycles` whole drive periods
//!   ([`LammpsExport::for_scene`]: a scene that runs until steady runs
//!   `drive.min_cycles` unless told otherwise, as LAMMPS keeps no ledger of
//!   the dissipation to judge steadiness by);
//! - `record.txt`: time, enclosure displacement, velocity and acceleration
//!   and the particles' axial force on the enclosure (minus the sum of the
//!   two walls' forces on the atoms, from each wall's `contacts` per-atom
//!   array), each the mean over `N` steps (`N` = steps per 40 kHz sample, so
//!   no impact aliases): the force by `fix ave/time 1 N N`, the motion once a
//!   row as the exact window mean of the analytic drive
//!   ([`window_mean_factor`]), with `# key: value` comments giving the drive,
//!   the particle mass, g and the orientation.
//!
//! # Matching vlab's contact law, and what remains
//!
//! - **Restitution.** vlab damps with `c_n = 2 √(5/6) β √(S_n m*)` (eq. 5.32),
//!   `S_n = 2 E* a`, i.e. `√5 β √(k_n m*)`; LAMMPS' `tsuji` damping is
//!   `α √(k_n m*)` with `α(e)` a polynomial fit. The deck sets `α = √5 β`,
//!   with β that of the scene's restitution mode (`exact`: calibrated so that
//!   the clamped contact realises e), by giving LAMMPS the `e_lammps` whose
//!   polynomial value is that α (0.803 for e = 0.86). With `limit_damping`
//!   (LAMMPS' no-pull clamp) the contact is then vlab's own equation and
//!   realises vlab's e: measured head-on, 0.86000 in LAMMPS and 0.86006 in
//!   vlab at 1e-8 s steps, 0.8614 and 0.8611 at the thesis' 1e-6 s. LAMMPS'
//!   own `tsuji` value for e = 0.86 (α = 0.0762) would realise 0.900.
//! - **Tangential damping.** vlab's `c_t = √(k_t / S_n) c_n = √(4 G*/E*) c_n`
//!   (eq. 5.33); LAMMPS scales the normal damping by `x_γ,t`: set to
//!   `√(4 G*/E*)` (0.879 for acrylic).
//! - **Walls.** LAMMPS 2021 computes a wall's E* as `E / (2 (1 - ν))` (not
//!   `1 - ν²`) and its `mindlin NULL` stiffness wrongly; the deck gives the
//!   wall fixes `ν = 0` and `E = 2 E*_pw` (the same E* whichever formula a
//!   LAMMPS version uses) and the Mindlin coefficient `8 G*_pw` explicitly.
//!   LAMMPS treats the inside of a `zcylinder` wall (as of a region
//!   cylinder) as concave with contact radius `-2 R_c` (R* = 2.67 mm for a 2.5 mm sphere in the 40 mm
//!   cylinder) where vlab takes every wall flat (R* = R, thesis); the side
//!   wall's E and k_t coefficient are scaled by `√(1 - R / (2 R_c))` so that
//!   its force against overlap is vlab's. One wall fix has one factor: for
//!   bodies R is the largest sub-sphere's, and a smaller sub-sphere's side
//!   wall contact is softer than vlab's by the ratio of the two factors
//!   (1.5 % for the end spheres of a prolate of 1.5, 7.6 mm, in the thesis
//!   cylinder; none for a toroid, whose sub-spheres are all alike).
//! - **What differs.** The slip rule: when `|F_t| > μ F_n` LAMMPS resets the
//!   spring so that spring plus damping carry `μ F_n`, vlab shortens the
//!   spring to carry `μ F_n` alone; and the order of the history update.
//!   Oblique impacts at 30° differ by 1 % (wall) to 2.5 % (sphere) in the
//!   rebound spin, 0.1° in the rebound angle. Tangential spring histories of
//!   the settled packing are not carried over (they start at zero). LAMMPS
//!   reports no energy ledger: the record's input power is its truth.
//!
//! A scene key with no translation is an error, not a silent omission: the
//! deck's header lists every key of the scene with what the deck did with it.

use std::fmt::Write as _;
use std::path::Path;

use serde::Serialize;

use crate::atomic_write::write_bytes_atomic;
use crate::dem::contact::Tangential;
use crate::dem::material::{effective_shear_pa, effective_youngs_pa};
use crate::dem::{ContactLaw, Particles, RestitutionMode};
use crate::drive::Drive;
use crate::experiment::bed::settle::SettledBed;
use crate::experiment::shake::{TRUTH_SAMPLE_RATE_HZ, shake_drive};
use crate::export::lammps_bodies::RigidBodies;
use crate::maths;
use crate::scene::contact_laws;
use crate::scene::{DriveLength, transient_cycles};
use crate::scene::{Orientation, Scene, SceneError};
use crate::validation::{InvalidParameter, count_in};

/// What the deck is, in a line (for a report that times it).
pub const DECK_FORM: &str = "two fix wall/gran walls moved by wiggle (side zcylinder; floor and lid \
     one zplane pair), one reduction of their forces, the force averaged every step and the motion \
     written once a 40 kHz row";

/// File name of the LAMMPS input.
pub const INPUT_FILE: &str = "in.damper";
/// File name of the packing.
pub const DATA_FILE: &str = "packing.data";
/// File name of the record the deck writes.
pub const RECORD_FILE: &str = "record.txt";
/// File name of vlab's account of the export.
pub const SUMMARY_FILE: &str = "export.json";
/// File name of the rigid bodies' mass, centre, inertia and motion, read by
/// `fix rigid/small ... infile` (bodies only).
pub const BODY_FILE: &str = "bodies.txt";

/// Tsuji et al.'s damping coefficient α(e) as LAMMPS computes it for
/// `damping tsuji` (a polynomial fit; LAMMPS' `pair_style granular` docs).
pub fn tsuji_alpha(e: f64) -> f64 {
    1.2728 - 4.2783 * e + 11.087 * e.powi(2) - 22.348 * e.powi(3) + 27.467 * e.powi(4)
        - 18.022 * e.powi(5)
        + 4.8218 * e.powi(6)
}

/// The `e` to give LAMMPS' `tsuji` damping so that its α is `alpha`: the
/// root of [`tsuji_alpha`] in [0, 1], which falls monotonically from 1.2728 at
/// 0 to 0.0005 at 1; `None` outside that range.
pub fn tsuji_restitution_for(alpha: f64) -> Option<f64> {
    let (mut lo, mut hi) = (0.0_f64, 1.0_f64);
    if !(tsuji_alpha(hi)..=tsuji_alpha(lo)).contains(&alpha) {
        return None;
    }
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if tsuji_alpha(mid) > alpha {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Some(0.5 * (lo + hi))
}

/// What `vlab export lammps` asks for.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LammpsExport {
    pub freq_hz: f64,
    pub gamma: f64,
    /// Drive cycles run.
    pub cycles: u32,
    /// The last this many cycles are the steady window the record declares
    /// (what `vlab replay` measures unless told otherwise).
    pub steady_cycles: u32,
}

/// Fewest cycles a deck runs: a transient cycle and the two whole periods
/// Yang's method needs.
pub const MIN_EXPORT_CYCLES: u32 = 3;

impl LammpsExport {
    /// The run for `scene` at `freq_hz` and `gamma`, as long as the scene's
    /// drive (`vlab export lammps --cycles N --steady-cycles M` set it).
    ///
    /// A scene with a number of cycles (`drive.cycles = N`) runs them, its
    /// last `drive.steady_cycles` the window. A scene that runs until steady
    /// (`drive.cycles = "steady"`, the thesis scene) runs `drive.min_cycles`
    /// (8), its last 5/8 the window as in vlab's drive
    /// ([`transient_cycles`]): a deck cannot stop when steady, as LAMMPS
    /// keeps no ledger of the dissipation to hold the enclosure's work
    /// against. `vlab shake`'s `summary.json` says how many cycles the scene
    /// took in vlab (`cycles`, `steady_cycles`), to give as `--cycles` and
    /// `--steady-cycles`.
    ///
    /// Everything the deck will refuse is refused here, before a bed is
    /// poured (30 s and more for bodies): the cycles, and every scene key
    /// the deck does not translate.
    pub fn for_scene(scene: &Scene, freq_hz: f64, gamma: f64) -> Result<Self, SceneError> {
        let drive = shake_drive(scene, freq_hz, gamma)?;
        // The keys a refusal names: those the scene (or its flags) set.
        let (cycles, steady_cycles, keys) = match scene.drive_length() {
            DriveLength::Fixed {
                cycles,
                steady_cycles,
            } => (
                cycles,
                steady_cycles,
                ["drive.cycles", "drive.steady_cycles"],
            ),
            DriveLength::UntilSteady { min_cycles, .. } => (
                min_cycles,
                min_cycles - transient_cycles(min_cycles),
                ["drive.min_cycles"; 2],
            ),
        };
        let export = LammpsExport {
            freq_hz,
            gamma,
            cycles,
            steady_cycles,
        };
        export.check(keys)?;
        // The step only for the header's words: a key the deck refuses is
        // refused before a body's collisions are measured for it.
        scene_key_uses(scene, &export, &|| scene.drive_dt_s(&drive))?;
        Ok(export)
    }

    /// The run's cycles: at least [`MIN_EXPORT_CYCLES`], a window of 2 to
    /// all of them; a refusal names `keys` (cycles, window).
    fn check(&self, keys: [&str; 2]) -> Result<(), SceneError> {
        count_in(keys[0], self.cycles, "", MIN_EXPORT_CYCLES, None)?;
        count_in(keys[1], self.steady_cycles, "", 2, Some(self.cycles))?;
        Ok(())
    }
}

/// How one of vlab's contact laws is given to LAMMPS.
#[derive(Debug, Clone, Serialize)]
pub struct ContactTranslation {
    /// The scene's restitution e and how vlab derives β from it.
    pub restitution: f64,
    pub restitution_mode: RestitutionMode,
    /// vlab's damping factor β (eq. 5.32).
    pub damping_factor: f64,
    /// LAMMPS' Tsuji α = √5 β.
    pub tsuji_alpha: f64,
    /// The e written in the deck so that LAMMPS' polynomial gives that α
    /// (`None` when e = 1: no damping at all).
    pub lammps_restitution: Option<f64>,
    pub friction: f64,
    /// E* (Pa) and G* (Pa) of the contact, eq. 5.6 and 5.14.
    pub effective_youngs_pa: f64,
    pub effective_shear_pa: f64,
    /// `x_γ,t = √(4 G*/E*)`: tangential over normal damping.
    pub tangential_damping_ratio: f64,
    /// Young's modulus (Pa) and Poisson's ratio written in the deck.
    pub lammps_youngs_pa: f64,
    pub lammps_poisson: f64,
    /// The Mindlin coefficient written in the deck (Pa; `None`: LAMMPS'
    /// NULL, from E and ν).
    pub lammps_tangential_pa: Option<f64>,
}

/// vlab's account of an export (`export.json`).
#[derive(Debug, Clone, Serialize)]
pub struct DeckSummary {
    pub vlab_version: &'static str,
    pub scene: String,
    pub freq_hz: f64,
    pub gamma: f64,
    pub amplitude_m: f64,
    pub cycles: u32,
    /// The last this many cycles: the window the record declares.
    pub steady_cycles: u32,
    /// The time step: vlab's drive step at this frequency and Γ
    /// ([`Scene::drive_dt_s`]).
    pub dt_s: f64,
    pub steps: u64,
    /// Steps averaged per record row (one 40 kHz sample).
    pub record_every_steps: u64,
    /// Atoms in the deck: spheres, or the bodies' sub-spheres.
    pub n_particles: usize,
    /// Rigid bodies (molecules of `fix rigid/small`); 0 for spheres.
    pub n_bodies: usize,
    pub particle_mass_kg: f64,
    pub orientation: &'static str,
    pub gravity_mps2: f64,
    pub particle_particle: ContactTranslation,
    pub particle_wall: ContactTranslation,
    /// Factor on the side wall's E and k_t coefficient for LAMMPS' concave
    /// cylinder contact, `√(1 - R / (2 R_c))`; for bodies R is the largest
    /// sub-sphere's.
    pub side_wall_factor: f64,
    /// Every scene key and what the deck did with it.
    pub scene_keys: Vec<SceneKeyUse>,
    pub files: Vec<String>,
}

/// A scene key, its value and what the deck does with it; written out
/// (`export.json`) as the array `[key, value, use]`.
#[derive(Debug, Clone, PartialEq)]
pub struct SceneKeyUse {
    pub key: String,
    pub value: String,
    pub use_in_deck: String,
}

impl Serialize for SceneKeyUse {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        (&self.key, &self.value, &self.use_in_deck).serialize(s)
    }
}

/// The deck: the LAMMPS input, the packing and vlab's account of it.
#[derive(Debug, Clone)]
pub struct LammpsDeck {
    pub input: String,
    pub data: String,
    /// `bodies.txt` for a scene of bodies, else `None`.
    pub bodies: Option<String>,
    pub summary: DeckSummary,
}

/// How a contact law becomes LAMMPS parameters: the damping and friction
/// words, with `youngs_pa`, `poisson` and the Mindlin coefficient `kt_pa`
/// (`None`: NULL) that the deck writes.
fn translate(
    law: &ContactLaw,
    mode: RestitutionMode,
    youngs_pa: f64,
    poisson: f64,
    kt_pa: Option<f64>,
) -> Result<ContactTranslation, SceneError> {
    let beta = law.damping_factor;
    let alpha = 5f64.sqrt() * beta;
    let lammps_restitution = if beta > 0.0 {
        Some(tsuji_restitution_for(alpha).ok_or_else(|| {
            InvalidParameter::new(
                "contact.restitution",
                law.restitution,
                "",
                format!(
                    "at least the e whose damping LAMMPS' tsuji polynomial can give (alpha = \
                     sqrt(5) beta = {alpha:.4} exceeds its largest value {:.4})",
                    tsuji_alpha(0.0)
                ),
            )
        })?)
    } else {
        None
    };
    let (friction, ratio) = match law.tangential {
        Tangential::MindlinCoulomb {
            damping_ratio,
            friction,
            ..
        } => (friction, damping_ratio),
        Tangential::Frictionless => (0.0, (4.0 * law.g_star_pa / law.e_star_pa).sqrt()),
    };
    Ok(ContactTranslation {
        restitution: law.restitution,
        restitution_mode: mode,
        damping_factor: beta,
        tsuji_alpha: alpha,
        lammps_restitution,
        friction,
        effective_youngs_pa: law.e_star_pa,
        effective_shear_pa: law.g_star_pa,
        tangential_damping_ratio: ratio,
        lammps_youngs_pa: youngs_pa,
        lammps_poisson: poisson,
        lammps_tangential_pa: kt_pa,
    })
}

/// The `hertz/material ... damping ...` words of a pair or wall command.
fn granular_words(t: &ContactTranslation, youngs_pa: f64, poisson: f64, kt: Option<f64>) -> String {
    let kt = kt.map_or_else(|| "NULL".to_string(), |k| format!("{k:.10e}"));
    match t.lammps_restitution {
        Some(e) => format!(
            "hertz/material {youngs_pa:.10e} {e:.12} {poisson} tangential mindlin {kt} {:.12} {} damping tsuji limit_damping",
            t.tangential_damping_ratio, t.friction
        ),
        // e = 1: no damping (velocity damping with a zero coefficient).
        None => format!(
            "hertz/material {youngs_pa:.10e} 0.0 {poisson} tangential mindlin {kt} 0.0 {} damping velocity",
            t.friction
        ),
    }
}

/// What the deck does with each scene key (dotted), for its header, with
/// the time step `dt_s` gives; `Err` names a key the deck does not
/// translate.
fn scene_key_uses(
    scene: &Scene,
    export: &LammpsExport,
    dt_s: &dyn Fn() -> f64,
) -> Result<Vec<SceneKeyUse>, SceneError> {
    let value: toml::Value = toml::Value::try_from(scene).map_err(|e| SceneError::Parse {
        path: scene.name.clone(),
        message: e.to_string(),
    })?;
    let mut leaves = Vec::new();
    flatten("", &value, &mut leaves);
    let shaped = !scene.particles.shape.is_sphere();
    let mut out = Vec::new();
    for (key, value) in leaves {
        let use_ = match key.as_str() {
            "version" => "scene file version: the deck is written from the resolved scene".into(),
            "name" => "named in the deck's header and in record.txt".into(),
            "particles.count" if shaped => format!(
                "{} bodies: molecules of atoms in {DATA_FILE}, each a rigid body of fix rigid/small",
                scene.particles.count
            ),
            "particles.count" => format!("{} atoms in {DATA_FILE}", scene.particles.count),
            "particles.diameter_m" if shaped => format!(
                "the body's equivalent sphere: its sub-spheres' diameters and places in {DATA_FILE}, its mass in {BODY_FILE}"
            ),
            "particles.diameter_m" => format!("atom diameter in {DATA_FILE}"),
            "particles.shape" | "particles.aspect_ratio" | "particles.hole_ratio"
            | "particles.sub_spheres" | "particles.clump_file" => format!(
                "the body's sub-spheres: atoms of one molecule per body in {DATA_FILE}, integrated by fix rigid/small with vlab's union mass, centre and inertia ({BODY_FILE}); contacts within a body excluded (neigh_modify exclude molecule/intra)"
            ),
            k if k.starts_with("particles.material") => {
                "sphere E and nu in pair_coeff (E* of eq. 5.6) and the wall fixes; density in packing.data (and a body's mass in bodies.txt)".into()
            }
            "enclosure.inner_diameter_m" => "radius of the side wall (fix side_wall zcylinder)".into(),
            "enclosure.inner_length_m" => "height of the lid (fix ends_wall zplane hi)".into(),
            "enclosure.orientation" => "direction of fix gravity".into(),
            k if k.starts_with("enclosure.material") => {
                "wall E*_pw and G*_pw in the wall fixes".into()
            }
            "contact.restitution_mode" => {
                "how beta, hence the tsuji e, follows from the restitution".into()
            }
            "contact.multi_point" => {
                // Printed only when not independent: shared.
                return Err(InvalidParameter::new(
                    "contact.multi_point",
                    &value,
                    "",
                    "\"independent\" (the default) for the LAMMPS export: its granular pair style makes every pair of atoms a whole contact and cannot share a body pair's",
                )
                .into());
            }
            k if k.starts_with("contact.particle_particle") => "pair_coeff: tsuji e, friction".into(),
            k if k.starts_with("contact.particle_wall") => "wall fixes: tsuji e, friction".into(),
            "simulation.dt_s" => format!(
                "timestep {:e}: vlab's drive step at this frequency and Gamma", dt_s()
            ),
            "simulation.rayleigh_safety_factor" => format!(
                "caps the time step rule (Rayleigh step x factor); here dt = {:e} s", dt_s()
            ),
            "simulation.steps_per_contact" => format!(
                "steps per shortest expected collision (dt_s = \"contacts\" or \"sub_sphere_contacts\"); here dt = {:e} s", dt_s()
            ),
            "simulation.settle_s" => format!("vlab settled the packing in {DATA_FILE} (the deck does not settle)"),
            "simulation.gravity_mps2" => "fix gravity magnitude".into(),
            "simulation.seed" => format!("seed of vlab's random fill, settled into {DATA_FILE}"),
            "simulation.parallel_min_pairs" => {
                "vlab's threading threshold; LAMMPS parallelises by domains (mpirun -np N)".into()
            }
            "drive.cycles" => format!(
                "run length: {} cycles (a number: itself; \"steady\": drive.min_cycles, as LAMMPS keeps no dissipation ledger to judge steadiness by)",
                export.cycles
            ),
            "drive.steady_cycles" => format!(
                "with a number of cycles, the window; here the last {} cycles, declared as steady_cycles in {RECORD_FILE} for vlab replay",
                export.steady_cycles
            ),
            "drive.min_cycles" => format!(
                "the run length of a scene run until steady ({} cycles here)",
                export.cycles
            ),
            "drive.max_cycles" | "drive.balance_rel" | "drive.stderr_rel" => {
                "vlab's until-steady rule only: not translated (the deck runs a fixed number of cycles; vlab replay reports the record's cycle-to-cycle spread)".into()
            }
            other => {
                return Err(InvalidParameter::new(
                    other,
                    &value,
                    "",
                    "a key the LAMMPS export translates (vlab export lammps does not know this one)",
                )
                .into());
            }
        };
        out.push(SceneKeyUse {
            key,
            value,
            use_in_deck: use_,
        });
    }
    Ok(out)
}

fn flatten(prefix: &str, value: &toml::Value, out: &mut Vec<(String, String)>) {
    match value {
        toml::Value::Table(t) => {
            for (k, v) in t {
                let key = if prefix.is_empty() {
                    k.clone()
                } else {
                    format!("{prefix}.{k}")
                };
                flatten(&key, v, out);
            }
        }
        other => out.push((prefix.to_string(), other.to_string())),
    }
}

/// The deck for `scene`'s settled `bed` (see the module docs).
pub fn lammps_deck(
    scene: &Scene,
    bed: &SettledBed,
    export: &LammpsExport,
) -> Result<LammpsDeck, SceneError> {
    let drive = shake_drive(scene, export.freq_hz, export.gamma)?;
    export.check(["cycles", "steady_cycles"])?;
    let particles = &*bed.world.particles.by_id();
    let plan = DeckPlan::new(scene, bed, export, &drive)?;
    let mut data = packing_data(&plan, particles);
    if let Some(b) = &plan.bodies {
        data.push_str(&b.molecules_section());
    }
    let input = [
        header_lines(&plan),
        contact_comment_lines(&plan),
        setup_lines(&plan),
        pair_lines(&plan),
        drive_lines(&plan),
        enclosure_lines(&plan),
        motion_lines(&plan),
        force_lines(&plan),
        record_and_run_lines(&plan),
    ]
    .concat();
    let bodies = plan
        .bodies
        .as_ref()
        .map(|b| b.infile(&scene.name, plan.version));
    Ok(LammpsDeck {
        input,
        data,
        bodies,
        summary: plan.into_summary(particles.len()),
    })
}

/// The numbers every section of the deck is written from.
struct DeckPlan<'a> {
    scene: &'a Scene,
    export: &'a LammpsExport,
    version: &'static str,
    /// The time step, s: vlab's drive step.
    dt: f64,
    /// Gravity, m/s^2.
    g: f64,
    /// Drive amplitude, m.
    amplitude: f64,
    /// Steps per record row.
    every: u64,
    /// Steps run.
    steps: u64,
    /// Particle radius, m: a sphere's, or a body's largest sub-sphere's.
    radius: f64,
    /// Enclosure radius, m.
    cyl_r: f64,
    /// Enclosure inner length, m.
    length: f64,
    /// Particle Young's modulus (Pa), Poisson's ratio and density (kg/m^3).
    particle_youngs_pa: f64,
    particle_poisson: f64,
    density: f64,
    pp: ContactTranslation,
    pw: ContactTranslation,
    side_factor: f64,
    keys: Vec<SceneKeyUse>,
    /// Particle mass in all, kg.
    mass: f64,
    /// Direction of gravity.
    gravity_dir: (i32, i32, i32),
    /// The rigid bodies of a bed of bodies (`None`: spheres).
    bodies: Option<RigidBodies>,
}

impl<'a> DeckPlan<'a> {
    fn new(
        scene: &'a Scene,
        bed: &SettledBed,
        export: &'a LammpsExport,
        drive: &Drive,
    ) -> Result<DeckPlan<'a>, SceneError> {
        let particles = &*bed.world.particles.by_id();
        let dt = scene.drive_dt_s(drive);
        let g = drive.gravity_mps2();
        let period = drive.period_s();
        let amplitude = drive.displacement_amplitude_m();
        let every = ((1.0 / TRUTH_SAMPLE_RATE_HZ / dt).round() as u64).max(1);
        // Whole record rows, the last ending at or past the last cycle's end: the
        // step need not divide the period (it is vlab's, from the scene's rule),
        // and a record short of the boundary would lose the last period.
        let rows = (f64::from(export.cycles) * period / (every as f64 * dt) - 1e-9).ceil() as u64;
        let bodies = RigidBodies::of(particles);
        let radius = bodies
            .as_ref()
            .map_or_else(|| scene.radius_m(), |b| b.max_sub_radius_m);
        let cyl_r = 0.5 * scene.enclosure.inner_diameter_m;
        let mode = scene.contact.restitution_mode;
        let laws = contact_laws(scene);
        let (pp_law, pw_law) = (laws.particle_particle, laws.particle_wall);
        let pm = scene.particle_material();
        let wm = scene.wall_material();
        // Spheres: their own E and nu (LAMMPS mixes E* of eq. 5.6 correctly).
        // Walls: nu = 0 and E = 2 E*_pw, Mindlin 8 G*_pw (see the module docs).
        let pp = translate(&pp_law, mode, pm.youngs_pa, pm.poisson, None)?;
        let pw = translate(
            &pw_law,
            mode,
            2.0 * pw_law.e_star_pa,
            0.0,
            Some(8.0 * pw_law.g_star_pa),
        )?;
        debug_assert!(
            (pw.effective_youngs_pa - effective_youngs_pa(&pm, &wm)).abs()
                <= 1e-9 * pw.effective_youngs_pa
        );
        debug_assert!(
            (pw.effective_shear_pa - effective_shear_pa(&pm, &wm)).abs()
                <= 1e-9 * pw.effective_shear_pa
        );
        let gravity_dir = match scene.enclosure.orientation {
            Orientation::Vertical => (0, 0, -1),
            Orientation::Horizontal => (0, -1, 0),
        };
        Ok(DeckPlan {
            scene,
            export,
            version: env!("CARGO_PKG_VERSION"),
            dt,
            g,
            amplitude,
            every,
            steps: rows * every,
            radius,
            cyl_r,
            length: scene.enclosure.inner_length_m,
            particle_youngs_pa: pm.youngs_pa,
            particle_poisson: pm.poisson,
            density: pm.density_kgm3,
            pp,
            pw,
            side_factor: (1.0 - radius / (2.0 * cyl_r)).sqrt(),
            keys: scene_key_uses(scene, export, &|| dt)?,
            mass: particles.total_mass_kg(),
            gravity_dir,
            bodies,
        })
    }

    /// vlab's account of the deck of `n_particles` spheres.
    fn into_summary(self, n_particles: usize) -> DeckSummary {
        let (scene, export) = (self.scene, self.export);
        DeckSummary {
            vlab_version: self.version,
            scene: scene.name.clone(),
            freq_hz: export.freq_hz,
            gamma: export.gamma,
            amplitude_m: self.amplitude,
            cycles: export.cycles,
            steady_cycles: export.steady_cycles,
            dt_s: self.dt,
            steps: self.steps,
            record_every_steps: self.every,
            n_particles,
            n_bodies: self.bodies.as_ref().map_or(0, |b| b.rows.len()),
            particle_mass_kg: self.mass,
            orientation: scene.enclosure.orientation.as_str(),
            gravity_mps2: self.g,
            particle_particle: self.pp,
            particle_wall: self.pw,
            side_wall_factor: self.side_factor,
            scene_keys: self.keys,
            files: [INPUT_FILE, DATA_FILE, SUMMARY_FILE]
                .into_iter()
                .chain(self.bodies.is_some().then_some(BODY_FILE))
                .map(String::from)
                .collect(),
        }
    }
}

/// Appends `text` and a newline to `s`.
fn line(s: &mut String, text: &str) {
    s.push_str(text);
    s.push('\n');
}

/// `packing.data`: the box, every sphere's diameter, density and position,
/// and every sphere's velocity and spin.
fn packing_data(plan: &DeckPlan, particles: &Particles) -> String {
    let (scene, version, radius, cyl_r) = (plan.scene, plan.version, plan.radius, plan.cyl_r);
    let (amplitude, length) = (plan.amplitude, plan.length);
    let margin = 2.0 * radius;
    let mut data = String::new();
    let _ = writeln!(
        data,
        "LAMMPS data file: vlab {version} settled packing of the {} damper (seed {}), SI units",
        scene.name, scene.simulation.seed
    );
    let _ = writeln!(data);
    let _ = writeln!(data, "{} atoms", particles.len());
    let _ = writeln!(data, "1 atom types");
    let _ = writeln!(data);
    let _ = writeln!(
        data,
        "{:.9e} {:.9e} xlo xhi",
        -cyl_r - margin,
        cyl_r + margin
    );
    let _ = writeln!(
        data,
        "{:.9e} {:.9e} ylo yhi",
        -cyl_r - margin,
        cyl_r + margin
    );
    let _ = writeln!(
        data,
        "{:.9e} {:.9e} zlo zhi",
        -margin,
        length + 2.0 * amplitude + margin
    );
    let _ = writeln!(data);
    let _ = writeln!(data, "Atoms # sphere");
    let _ = writeln!(data);
    let density = plan.density;
    for i in 0..particles.len() {
        let p = particles.position[i];
        let r = particles.radius[i];
        let _ = writeln!(
            data,
            "{} 1 {:?} {:?} {:?} {:?} {:?}",
            i + 1,
            2.0 * r,
            density,
            p.x,
            p.y,
            p.z
        );
    }
    let _ = writeln!(data);
    let _ = writeln!(data, "Velocities");
    let _ = writeln!(data);
    for i in 0..particles.len() {
        let v = particles.velocity[i];
        let w = particles.angular_velocity[i];
        let _ = writeln!(
            data,
            "{} {:?} {:?} {:?} {:?} {:?} {:?}",
            i + 1,
            v.x,
            v.y,
            v.z,
            w.x,
            w.y,
            w.z
        );
    }
    data
}

/// The input's header: how to run it and every scene key with its use.
fn header_lines(plan: &DeckPlan) -> String {
    let (scene, export, version) = (plan.scene, plan.export, plan.version);
    let mut s = String::new();
    let _ = writeln!(
        s,
        "# LAMMPS input written by vlab {version} (vlab export lammps): the {} damper driven at {} Hz, \
         Gamma {}, {} cycles.",
        scene.name, export.freq_hz, export.gamma, export.cycles
    );
    line(&mut s, "# Run:  lmp -in in.damper          (one core)");
    line(
        &mut s,
        "#       mpirun -np 4 lmp -in in.damper   (a cluster: any number of ranks)",
    );
    line(
        &mut s,
        "# then: vlab replay record.txt --out replay   (the record through vlab's rig)",
    );
    line(
        &mut s,
        "# Needs the GRANULAR package (Debian: apt-get install lammps). SI units throughout.",
    );
    line(&mut s, "#");
    line(
        &mut s,
        "# Every key of the scene and what this deck does with it:",
    );
    for k in &plan.keys {
        let _ = writeln!(s, "#   {} = {}: {}", k.key, k.value, k.use_in_deck);
    }
    line(&mut s, "#");
    s
}

/// The header's account of the contact law's translation (module docs).
fn contact_comment_lines(plan: &DeckPlan) -> String {
    let (pp, pw) = (&plan.pp, &plan.pw);
    let mut s = String::new();
    line(
        &mut s,
        "# Contact law (vlab: Hertz eq. 5.7, Mindlin eq. 5.24 with Coulomb cap eq. 5.16,",
    );
    line(
        &mut s,
        "# restitution damping eq. 5.32/5.33, never pulling):",
    );
    for (what, t) in [("particle-particle", pp), ("particle-wall", pw)] {
        let _ = writeln!(
            s,
            "#   {what}: e = {} ({} mode: beta = {:.6}), tsuji alpha = sqrt(5) beta = {:.6}, given to LAMMPS as e = {}; \
             mu = {}; x_gamma_t = sqrt(4 G*/E*) = {:.6}",
            t.restitution,
            match t.restitution_mode {
                RestitutionMode::Exact => "exact",
                RestitutionMode::Thesis => "thesis",
            },
            t.damping_factor,
            t.tsuji_alpha,
            t.lammps_restitution.map_or_else(
                || "none (e = 1, no damping)".to_string(),
                |e| format!("{e:.6}")
            ),
            t.friction,
            t.tangential_damping_ratio
        );
    }
    line(
        &mut s,
        "#   The e given to LAMMPS is not the e it realises: LAMMPS' tsuji polynomial alpha(e) does",
    );
    line(
        &mut s,
        "#   not realise e for a Hertz contact whose force is clamped at zero (limit_damping); the",
    );
    line(
        &mut s,
        "#   e above makes alpha = sqrt(5) beta, vlab's damping, so LAMMPS realises vlab's e",
    );
    line(
        &mut s,
        "#   (head-on: 0.86000 vs vlab 0.86006 at 1e-8 s steps, 0.8614 vs 0.8611 at 1e-6 s).",
    );
    let _ = writeln!(
        s,
        "#   Walls: nu = 0 and E = 2 E*_pw = {:.6e} Pa (LAMMPS 2021 takes a wall's E* as E/(2(1-nu))),",
        2.0 * pw.effective_youngs_pa
    );
    let _ = writeln!(
        s,
        "#   Mindlin coefficient 8 G*_pw = {:.6e} Pa given explicitly (its NULL is wrong for walls).",
        8.0 * pw.effective_shear_pa
    );
    let side_factor = plan.side_factor;
    let _ = writeln!(
        s,
        "#   Side wall: E and k_t scaled by sqrt(1 - R/(2 R_c)) = {side_factor:.6}: LAMMPS takes the inside of a"
    );
    line(
        &mut s,
        "#   zcylinder wall as concave (contact radius -2 R_c), vlab every wall as flat (R* = R).",
    );
    line(
        &mut s,
        "#   Remaining differences: the slip rule (LAMMPS: spring + damping carry mu F_n; vlab:",
    );
    line(
        &mut s,
        "#   the spring carries mu F_n) and the settled contacts' tangential history (starts at 0).",
    );
    line(&mut s, "");
    s
}

/// Units, atoms and the packing; for bodies each atom's molecule too, and
/// the atom map `fix rigid/small` needs.
fn setup_lines(plan: &DeckPlan) -> String {
    let mut s = String::new();
    line(&mut s, "units           si");
    line(&mut s, "atom_style      sphere");
    if plan.bodies.is_some() {
        line(&mut s, "atom_modify     map array");
    }
    line(&mut s, "dimension       3");
    line(&mut s, "boundary        f f f");
    match &plan.bodies {
        // Ghost atoms out to a whole body, so that a rank sees every atom of
        // the bodies it owns (fix rigid/small under mpirun).
        Some(b) => {
            let _ = writeln!(
                s,
                "comm_modify     vel yes cutoff {:.6e}",
                2.0 * b.reach_m + 0.2 * plan.radius
            );
            line(
                &mut s,
                "fix             mol_ids all property/atom mol ghost yes",
            );
            let _ = writeln!(s, "read_data       {DATA_FILE} fix mol_ids NULL Molecules");
            line(&mut s, "group           bodies molecule > 0");
            line(&mut s, "group           spheres subtract all bodies");
        }
        None => {
            line(&mut s, "comm_modify     vel yes");
            let _ = writeln!(s, "read_data       {DATA_FILE}");
        }
    }
    line(&mut s, "");
    s
}

/// The sphere-sphere contacts, the neighbour list and the time step.
fn pair_lines(plan: &DeckPlan) -> String {
    let mut s = String::new();
    line(&mut s, "# Contacts between spheres.");
    line(&mut s, "pair_style      granular");
    let _ = writeln!(
        s,
        "pair_coeff      * * {}",
        granular_words(
            &plan.pp,
            plan.particle_youngs_pa,
            plan.particle_poisson,
            None
        )
    );
    let _ = writeln!(s, "neighbor        {:.6e} bin", 0.2 * plan.radius);
    if plan.bodies.is_some() {
        line(
            &mut s,
            "# No contacts between sub-spheres of one body (vlab never pairs them).",
        );
        line(
            &mut s,
            "neigh_modify    delay 0 every 1 check yes exclude molecule/intra bodies",
        );
    } else {
        line(&mut s, "neigh_modify    delay 0 every 1 check yes");
    }
    let dt = plan.dt;
    let _ = writeln!(s, "timestep        {dt:e}");
    line(&mut s, "");
    s
}

/// The mean of `sin(ω t_k)` (or `cos`) over `n` instants `dt_s` apart,
/// divided by its value at their centre: `sin(n ω dt / 2) / (n sin(ω dt / 2))`.
/// The record's motion columns are written once a row from it, as the exact
/// window means a per-step average would give. (`libm`'s sine, so that the
/// deck's text is the same on every platform; `ω dt > 0`.)
pub fn window_mean_factor(n: u64, omega_rad_s: f64, dt_s: f64) -> f64 {
    let half = 0.5 * omega_rad_s * dt_s;
    maths::sin(n as f64 * half) / (n as f64 * maths::sin(half))
}

/// The drive (thesis eq. 6.2, from rest) and the record's motion variables.
fn drive_lines(plan: &DeckPlan) -> String {
    let (export, amplitude, every, dt) = (plan.export, plan.amplitude, plan.every, plan.dt);
    let omega = std::f64::consts::TAU * export.freq_hz;
    let factor = window_mean_factor(every, omega, dt);
    let mut s = String::new();
    line(
        &mut s,
        "# The drive (thesis eq. 6.2, amplitude Gamma g / w^2) by the walls' wiggle, from rest at t = 0",
    );
    line(
        &mut s,
        "# at the settled packing: u = A (1 - cos w t). (vlab's shake starts mid-stroke, u = A sin w t;",
    );
    line(
        &mut s,
        "# the start-up differs, the steady drive does not.)",
    );
    let _ = writeln!(s, "variable        drive_freq_hz equal {}", export.freq_hz);
    let _ = writeln!(s, "variable        amplitude_m equal {amplitude:.17e}");
    line(&mut s, "variable        omega equal 2.0*PI*v_drive_freq_hz");
    let _ = writeln!(
        s,
        "# The record's motion, evaluated once a row: the mean over the row's {every} steps, i.e. the value"
    );
    let _ = writeln!(
        s,
        "# at the window's centre (time - {}/2 dt) times sin(n w dt/2) / (n sin(w dt/2)) = {factor:?}.",
        every - 1
    );
    let _ = writeln!(
        s,
        "variable        time equal time-{:?}",
        0.5 * (every - 1) as f64 * dt
    );
    let _ = writeln!(
        s,
        "variable        enclosure_displacement equal v_amplitude_m*(1.0-{factor:?}*cos(v_omega*v_time))"
    );
    let _ = writeln!(
        s,
        "variable        enclosure_velocity equal {factor:?}*v_amplitude_m*v_omega*sin(v_omega*v_time)"
    );
    let _ = writeln!(
        s,
        "variable        enclosure_acceleration equal {factor:?}*v_amplitude_m*v_omega*v_omega*cos(v_omega*v_time)"
    );
    line(&mut s, "");
    s
}

/// The enclosure as two wall fixes moving together along z: the side (a
/// `zcylinder`, with the concave-contact factor) and the floor and lid (one
/// `zplane` pair), each wiggled by the drive.
fn enclosure_lines(plan: &DeckPlan) -> String {
    let (cyl_r, length, amplitude) = (plan.cyl_r, plan.length, plan.amplitude);
    let (pw, side_factor) = (&plan.pw, plan.side_factor);
    let period = 1.0 / plan.export.freq_hz;
    let wiggle = format!("wiggle z {amplitude:?} {period:?}");
    let mut s = String::new();
    line(
        &mut s,
        "# The enclosure: side, floor and lid, moving together along z.",
    );
    let wall_e = 2.0 * pw.effective_youngs_pa;
    let wall_kt = 8.0 * pw.effective_shear_pa;
    let _ = writeln!(
        s,
        "fix             side_wall all wall/gran granular {} zcylinder {cyl_r:?} {wiggle} contacts",
        granular_words(pw, wall_e * side_factor, 0.0, Some(wall_kt * side_factor))
    );
    let _ = writeln!(
        s,
        "fix             ends_wall all wall/gran granular {} zplane 0.0 {length:?} {wiggle} contacts",
        granular_words(pw, wall_e, 0.0, Some(wall_kt))
    );
    line(&mut s, "");
    s
}

/// Time integration and gravity: spheres by `nve/sphere`; bodies by `fix
/// rigid/small` with vlab's mass, centre and inertia (`bodies.txt`) and
/// gravity on that mass at that centre ([`crate::export::lammps_bodies`]).
fn motion_lines(plan: &DeckPlan) -> String {
    let g = plan.g;
    let (gx, gy, gz) = plan.gravity_dir;
    let mut s = String::new();
    let Some(bodies) = &plan.bodies else {
        line(&mut s, "fix             integrate all nve/sphere");
        if g > 0.0 {
            let _ = writeln!(
                s,
                "fix             gravity all gravity {g} vector {gx} {gy} {gz}"
            );
        }
        line(&mut s, "");
        return s;
    };
    line(
        &mut s,
        "# Each body a rigid body: vlab's union mass (eq. 4.1), centre (eq. 4.2) and inertia (eq. 4.5)",
    );
    line(
        &mut s,
        "# from bodies.txt, not LAMMPS' sum over overlapping atoms; gravity on that mass at that centre.",
    );
    if bodies.n_free > 0 {
        line(
            &mut s,
            "fix             integrate_spheres spheres nve/sphere",
        );
    }
    let gravity = if g > 0.0 {
        let _ = writeln!(
            s,
            "fix             gravity spheres gravity {g} vector {gx} {gy} {gz}"
        );
        " gravity gravity"
    } else {
        ""
    };
    let _ = writeln!(
        s,
        "fix             integrate bodies rigid/small molecule infile {BODY_FILE}{gravity}"
    );
    line(&mut s, "");
    s
}

/// The particles' force on the enclosure from the walls' per-atom forces,
/// averaged over each record row's steps.
fn force_lines(plan: &DeckPlan) -> String {
    let every = plan.every;
    let mut s = String::new();
    line(
        &mut s,
        "# The particles' force on the enclosure along z: minus the walls' forces on the atoms,",
    );
    let _ = writeln!(s, "# the mean over each row's {every} steps.");
    line(
        &mut s,
        "compute         wall_fz all reduce sum f_side_wall[4] f_ends_wall[4]",
    );
    line(
        &mut s,
        "variable        wall_force_axial equal -(c_wall_fz[1]+c_wall_fz[2])",
    );
    let _ = writeln!(
        s,
        "fix             force_mean all ave/time 1 {every} {every} v_wall_force_axial"
    );
    line(
        &mut s,
        "variable        particle_force_axial equal f_force_mean",
    );
    line(&mut s, "");
    s
}

/// Thermo output, the first row's steps, the `fix ave/time` that writes
/// `record.txt` (with its `# key: value` header for `vlab replay`), and the
/// rest of the run. No kinetic energy for bodies: LAMMPS' comes from a
/// temperature whose degrees of freedom the rigid bodies take away.
fn record_and_run_lines(plan: &DeckPlan) -> String {
    let (scene, export, version) = (plan.scene, plan.export, plan.version);
    let (every, mass, g, steps) = (plan.every, plan.mass, plan.g, plan.steps);
    let mut s = String::new();
    let ke = if plan.bodies.is_some() { "" } else { " ke" };
    let _ = writeln!(
        s,
        "thermo_style    custom step time atoms{ke} v_enclosure_displacement v_particle_force_axial"
    );
    line(&mut s, "thermo_modify   lost error norm no");
    let _ = writeln!(s, "thermo          {}", (steps / 20 / every).max(1) * every);
    line(
        &mut s,
        "# The first row's steps run before the record exists: a fix ave/time of one sample a row",
    );
    line(&mut s, "# writes a row at the step it starts on.");
    let _ = writeln!(s, "run             {every}");
    line(&mut s, "");
    let _ = writeln!(
        s,
        "# The record vlab replay reads: each row the mean over {every} steps (one 40 kHz sample),"
    );
    line(
        &mut s,
        "# time included (the window's centre), written once a row.",
    );
    let _ = writeln!(
        s,
        "fix             record all ave/time {every} 1 {every} v_time v_enclosure_displacement v_enclosure_velocity v_enclosure_acceleration v_particle_force_axial file {RECORD_FILE} format \" %.17g\" title1 \"\"\"# vlab replay record: {} damper, {} Hz, Gamma {}, from a LAMMPS deck of vlab {version}",
        scene.name, export.freq_hz, export.gamma
    );
    line(&mut s, "# units: si");
    let _ = writeln!(s, "# drive_freq_hz: {}", export.freq_hz);
    let _ = writeln!(s, "# gamma: {}", export.gamma);
    let _ = writeln!(s, "# particle_mass_kg: {mass:?}");
    let _ = writeln!(s, "# gravity_mps2: {g}");
    let _ = writeln!(s, "# orientation: {}", scene.enclosure.orientation.as_str());
    let _ = writeln!(s, "# steady_cycles: {}", export.steady_cycles);
    let _ = writeln!(s, "# record_every_steps: {every}");
    line(
        &mut s,
        "# particle_force_axial: the particles' force on the enclosure along +z (N); each row a window mean\"\"\"",
    );
    line(&mut s, "");
    let _ = writeln!(s, "run             {}", steps - every);
    s
}

impl LammpsDeck {
    /// Writes `in.damper`, `packing.data`, `bodies.txt` (bodies only) and
    /// `export.json` into `dir` (which must exist), each atomically.
    pub fn write(&self, dir: &Path) -> Result<(), SceneError> {
        let summary = serde_json::to_string_pretty(&self.summary)
            .unwrap_or_else(|e| format!("{{\"error\": \"{e}\"}}"))
            + "\n";
        let files = [
            (DATA_FILE, Some(&self.data)),
            (BODY_FILE, self.bodies.as_ref()),
            (INPUT_FILE, Some(&self.input)),
            (SUMMARY_FILE, Some(&summary)),
        ];
        for (name, text) in files.into_iter().filter_map(|(n, t)| Some((n, t?))) {
            let path = dir.join(name);
            write_bytes_atomic(&path, text.as_bytes())
                .map_err(|source| SceneError::Write { path, source })?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dem::restitution::exact_damping_factor;

    #[test]
    fn tsuji_inverse_gives_vlabs_damping() {
        // e = 0.86 in exact mode: beta = 0.04951, alpha = 0.1107, LAMMPS' e 0.8032.
        let alpha = 5f64.sqrt() * exact_damping_factor(0.86);
        let e = tsuji_restitution_for(alpha).expect("in range");
        assert!((e - 0.8032).abs() < 1e-4, "{e}");
        assert!((tsuji_alpha(e) - alpha).abs() < 1e-12);
        assert!((tsuji_alpha(0.86) - 0.0762).abs() < 1e-4);
        assert!(tsuji_restitution_for(2.0).is_none());
        assert!(tsuji_restitution_for(-0.1).is_none());
    }

    #[test]
    fn the_window_factor_turns_a_centre_value_into_the_window_mean() {
        // The record's motion rows: the value at the window's centre times
        // the factor is the mean of the n per-step values, to rounding.
        let (omega, dt) = (std::f64::consts::TAU * 40.0, 1.2201890525467253e-6);
        for (n, t_end_steps) in [(20_u64, 20_u64), (20, 123_460), (7, 301), (1, 5)] {
            let factor = window_mean_factor(n, omega, dt);
            let times = (t_end_steps + 1 - n..=t_end_steps).map(|k| k as f64 * dt);
            let centre = (t_end_steps as f64 - 0.5 * (n - 1) as f64) * dt;
            let (mean_sin, mean_cos) = times.fold((0.0, 0.0), |(s, c), t| {
                (
                    s + (omega * t).sin() / n as f64,
                    c + (omega * t).cos() / n as f64,
                )
            });
            assert!(
                (mean_sin - factor * (omega * centre).sin()).abs() < 1e-14,
                "{n}"
            );
            assert!(
                (mean_cos - factor * (omega * centre).cos()).abs() < 1e-14,
                "{n}"
            );
        }
        // Coarse windows make the factor matter: 10 steps of a tenth of a period.
        let f = window_mean_factor(10, std::f64::consts::TAU, 0.01);
        assert!((f - 0.983_79).abs() < 1e-5, "{f}");
    }
}
