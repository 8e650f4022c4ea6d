//! Scene files: the damper, its particles, contacts and run length, in TOML.
//!
//! The built-in thesis preset is `scenes/thesis-damper.toml`, embedded in the binary.
//! A user scene file is merged over the preset key by key, so it only needs the
//! keys it changes; unknown keys are errors, and `version` must be 1. Every value
//! is checked with its unit and valid range before anything runs.

use std::collections::HashMap;
use std::f64::consts::PI;
use std::path::Path;
use std::sync::{Mutex, OnceLock};

use serde::{Deserialize, Serialize};

use crate::dem::body_collision::{BodyCollisions, BodyProbe, shortest_body_collisions};
use crate::dem::contact::MultiPoint;
use crate::dem::material::{
    Material, effective_mass_kg, effective_radius_m, effective_youngs_pa, sphere_mass_kg,
};
use crate::dem::timestep::{check_time_step, rayleigh_time_step_s, shortest_contact_with_mass_s};
use crate::dem::{RestitutionMode, hertz_theory};
use crate::drive::Drive;
use crate::scene::drive_length::{DriveLength, SteadyCriteria};
use crate::scene::error::SceneError;
use crate::scene::particle_shape::{ParticleBody, ShapeKeys, ShapeKind, quick_reach_m};
use crate::scene::validity::YieldVelocities;
use crate::validation::{
    self, Bound, InvalidParameter, count_in, in_range, non_negative, positive, require,
};

/// Where the built-in thesis damper lives in the source tree (embedded).
pub const THESIS_SCENE_FILE: &str = "scenes/thesis-damper.toml";

/// The embedded thesis damper preset.
pub const THESIS_DAMPER_TOML: &str = include_str!("../../scenes/thesis-damper.toml");

pub use crate::scene::packing::MAX_FILL;

/// A material given by preset name or inline constants.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(untagged)]
pub enum MaterialSpec {
    Named(String),
    Inline(Material),
}

impl MaterialSpec {
    /// Resolves the spec; `key` names it in messages (`particles.material`).
    pub fn resolve(&self, key: &str) -> Result<Material, InvalidParameter> {
        match self {
            MaterialSpec::Inline(m) => {
                m.validate().map_err(|e| e.within(key))?;
                Ok(*m)
            }
            MaterialSpec::Named(name) => material_preset(name).ok_or_else(|| {
                InvalidParameter::new(
                    key,
                    format!("\"{name}\""),
                    "",
                    "acrylic, steel, aluminium, rigid, or an inline table { youngs_pa, poisson, density_kgm3 }",
                )
            }),
        }
    }
}

/// Material presets by name.
pub fn material_preset(name: &str) -> Option<Material> {
    match name {
        "acrylic" => Some(Material::ACRYLIC),
        "steel" => Some(Material::STEEL),
        "aluminium" | "aluminum" => Some(Material::ALUMINIUM),
        "rigid" => Some(Material::rigid()),
        _ => None,
    }
}

/// Gravity relative to the cylinder (and drive) axis.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
#[serde(rename_all = "lowercase")]
pub enum Orientation {
    /// Axis along gravity.
    Vertical,
    /// Axis perpendicular to gravity.
    Horizontal,
}

impl Orientation {
    /// Lower-case name, as in scene files.
    pub fn as_str(self) -> &'static str {
        match self {
            Orientation::Vertical => "vertical",
            Orientation::Horizontal => "horizontal",
        }
    }
}

/// `simulation.dt_s`: a time step in seconds, or the rule that chooses it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(untagged, try_from = "NumberOrWord<f64>")]
pub enum TimeStepSpec {
    Seconds(f64),
    Rule(TimeStepRule),
}

/// How the time step is chosen when the scene does not give it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum TimeStepRule {
    /// `"contacts"`: the shortest expected contact in `steps_per_contact`
    /// steps ([`Scene::drive_dt_s`]); for bodies, the shortest of one
    /// sub-sphere pair and of the collisions of whole bodies, measured.
    Contacts,
    /// `"sub_sphere_contacts"`: as `"contacts"`, but for bodies only one
    /// sub-sphere pair's contact: the rule before 2026-11-30, under which the
    /// shape study ran (docs/shapes.md).
    SubSphereContacts,
    /// `"rayleigh"`: `rayleigh_safety_factor` times the Rayleigh step.
    Rayleigh,
}

/// A scene value written as a number or a word (`dt_s`, `cycles`), as read.
#[derive(Deserialize)]
#[serde(untagged)]
enum NumberOrWord<T> {
    Number(T),
    Word(String),
}

impl TryFrom<NumberOrWord<f64>> for TimeStepSpec {
    type Error = InvalidParameter;

    fn try_from(v: NumberOrWord<f64>) -> Result<Self, InvalidParameter> {
        match v {
            NumberOrWord::Number(dt) => Ok(TimeStepSpec::Seconds(dt)),
            NumberOrWord::Word(w) => match w.as_str() {
                "contacts" => Ok(TimeStepSpec::Rule(TimeStepRule::Contacts)),
                "rayleigh" => Ok(TimeStepSpec::Rule(TimeStepRule::Rayleigh)),
                "sub_sphere_contacts" => Ok(TimeStepSpec::Rule(TimeStepRule::SubSphereContacts)),
                _ => Err(InvalidParameter::new(
                    "simulation.dt_s",
                    format!("\"{w}\""),
                    "",
                    "a time step in seconds, \"contacts\", \"sub_sphere_contacts\" or \"rayleigh\"",
                )),
            },
        }
    }
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ParticlesSpec {
    pub count: usize,
    /// A sphere's diameter; for another shape, the diameter of the sphere of
    /// the same volume (m).
    #[serde(default = "not_given")]
    pub diameter_m: f64,
    /// Another name for `diameter_m` that says what it is for a shape that
    /// is not a sphere; read into `diameter_m` when the scene is parsed.
    #[serde(default, skip_serializing)]
    pub equivalent_diameter_m: Option<f64>,
    pub material: MaterialSpec,
    /// The particles' shape ([`ShapeKind`]); spheres when absent.
    #[serde(default, skip_serializing_if = "ShapeKind::is_sphere")]
    pub shape: ShapeKind,
    /// a/b of a prolate (> 1) or oblate (< 1) spheroid.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub aspect_ratio: Option<f64>,
    /// (a − b)/(a + b) of a toroid.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub hole_ratio: Option<f64>,
    /// Sub-spheres of a generated body (the thesis' by default).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub sub_spheres: Option<usize>,
    /// A file of sub-spheres (`x_m,y_m,z_m,radius_m` rows) for `shape =
    /// "clump"`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub clump_file: Option<std::path::PathBuf>,
}

/// What sets the time step of a scene's contacts ([`Scene::contact_scale`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactScale {
    /// Radius of the smallest sphere in contact (m).
    pub radius_m: f64,
    /// Mass behind it (kg): the sphere's, or the least a contact on a body
    /// meets.
    pub mass_kg: f64,
    /// How much faster than the particle it can meet another (1 for a
    /// sphere).
    pub speed_factor: f64,
}

/// The Verlet skin of a bed of bodies, as a fraction of its largest
/// sub-sphere's radius. Two prolates side by side have every pair of their
/// central sub-spheres within a skin of half a radius (about 1 600 listed
/// pairs for one contact); a thin skin lists a few dozen, at the cost of
/// more rebuilds. Measured on 90 prolates of aspect ratio 1.5 with 51
/// sub-spheres in the thesis cylinder, 40 Hz, Gamma 20, 3 cycles on one
/// thread (2026-11-26, one run each): 0.5 → 2.3 M sub-sphere-steps/s, 0.2 →
/// 7.3 M, 0.1 → 11.1 M, 0.05 → 13.0 M, 0.03 → 12.0 M, 0.02 → 9.8 M.
pub const BODY_SKIN_RATIO: f64 = 0.05;

/// Steps of the measurement of bodies' collisions
/// ([`Scene::body_collisions`]) in one sub-sphere pair's contact: a
/// collision counted to 1/200 of that.
const BODY_PROBE_STEPS: f64 = 200.0;

/// A size no scene gave: refused by validation with the key's name.
fn not_given() -> f64 {
    f64::NAN
}

impl ParticlesSpec {
    /// The shape keys as given.
    pub fn shape_keys(&self) -> ShapeKeys<'_> {
        ShapeKeys {
            kind: self.shape,
            aspect_ratio: self.aspect_ratio,
            hole_ratio: self.hole_ratio,
            sub_spheres: self.sub_spheres,
            clump_file: self.clump_file.as_ref(),
        }
    }

    /// Reads `equivalent_diameter_m` into `diameter_m`; both given is a
    /// contradiction.
    fn settle_diameter(&mut self) -> Result<(), InvalidParameter> {
        if let Some(d) = self.equivalent_diameter_m.take() {
            // Checked under the name the file gave it, not the one it is
            // read into.
            positive("particles.equivalent_diameter_m", d, "m")?;
            if !self.diameter_m.is_nan() {
                return Err(InvalidParameter::new(
                    "particles.equivalent_diameter_m",
                    d,
                    "m",
                    format!(
                        "given alone: particles.diameter_m = {} m says the same (the diameter of the sphere of equal volume)",
                        self.diameter_m
                    ),
                ));
            }
            self.diameter_m = d;
        }
        Ok(())
    }
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EnclosureSpec {
    pub inner_diameter_m: f64,
    pub inner_length_m: f64,
    pub orientation: Orientation,
    pub material: MaterialSpec,
}

#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PairSpec {
    pub restitution: f64,
    pub friction: f64,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ContactSpec {
    pub restitution_mode: RestitutionMode,
    pub particle_particle: PairSpec,
    pub particle_wall: PairSpec,
    /// How a body's simultaneous sub-sphere contacts combine: each a whole
    /// contact (`"independent"`, the thesis' model) or `"shared"` by the
    /// count touching at once ([`MultiPoint`]). Left out of printed scenes
    /// when independent.
    #[serde(default, skip_serializing_if = "MultiPoint::is_independent")]
    pub multi_point: MultiPoint,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SimulationSpec {
    pub dt_s: TimeStepSpec,
    pub rayleigh_safety_factor: f64,
    /// With `dt_s = "contacts"`: steps the shortest expected contact takes.
    #[serde(default = "default_steps_per_contact")]
    pub steps_per_contact: f64,
    pub settle_s: f64,
    pub gravity_mps2: f64,
    pub seed: u64,
    /// Deprecated, and left out of printed scenes: vlab chooses when to use
    /// threads itself, by timing both ways. Still read, so that older scene
    /// files load; a value below the default makes a bed of several blocks
    /// go parallel from that many listed pairs whatever the timing (the
    /// results are the same bits either way).
    #[serde(
        default = "default_parallel_min_pairs",
        skip_serializing_if = "is_default_parallel_min_pairs"
    )]
    pub parallel_min_pairs: usize,
    /// Threads a bed's step may use, the caller's included: set by whoever
    /// runs the scene (`vlab shake` gives a bed driven alone every thread,
    /// each of beds driven side by side its share), never read from or
    /// written to a scene file. 1 unless set; the same bits whatever it is.
    #[serde(skip, default = "one_thread")]
    pub step_threads: usize,
}

fn one_thread() -> usize {
    1
}

fn default_steps_per_contact() -> f64 {
    25.0
}

fn default_parallel_min_pairs() -> usize {
    crate::dem::AUTO_PARALLEL_MIN_PAIRS
}

fn is_default_parallel_min_pairs(n: &usize) -> bool {
    *n >= crate::dem::AUTO_PARALLEL_MIN_PAIRS
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DriveSpec {
    /// `"steady"` (run until steady) or a number of cycles.
    pub cycles: CyclesSpec,
    /// With a number of cycles: the last this many are the steady window.
    pub steady_cycles: u32,
    /// Run until steady: at least this many cycles.
    #[serde(default = "default_min_cycles")]
    pub min_cycles: u32,
    /// Run until steady: at most this many cycles.
    #[serde(default = "default_max_cycles")]
    pub max_cycles: u32,
    /// Run until steady: |work in − dissipated| / dissipated over the window.
    #[serde(default = "default_tolerance")]
    pub balance_rel: f64,
    /// Run until steady: standard error of the energy per cycle / its mean.
    #[serde(default = "default_tolerance")]
    pub stderr_rel: f64,
}

/// `drive.cycles`: a number, or `"steady"`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(untagged, try_from = "NumberOrWord<u32>")]
pub enum CyclesSpec {
    Count(u32),
    Rule(CyclesRule),
}

/// How many cycles a drive runs when the scene does not fix the count.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum CyclesRule {
    /// `"steady"`: until the bed is steady ([`DriveLength::UntilSteady`]).
    Steady,
}

impl TryFrom<NumberOrWord<u32>> for CyclesSpec {
    type Error = InvalidParameter;

    fn try_from(v: NumberOrWord<u32>) -> Result<Self, InvalidParameter> {
        match v {
            NumberOrWord::Number(n) => Ok(CyclesSpec::Count(n)),
            NumberOrWord::Word(w) if w == "steady" => Ok(CyclesSpec::Rule(CyclesRule::Steady)),
            NumberOrWord::Word(w) => Err(InvalidParameter::new(
                "drive.cycles",
                format!("\"{w}\""),
                "",
                "a number of cycles or \"steady\"",
            )),
        }
    }
}

/// Most cycles a drive may run, fixed or until steady: at 40 Hz about 40
/// minutes of simulated time, far past any steady state vlab has seen.
pub const MAX_DRIVE_CYCLES: u32 = 100_000;

fn default_min_cycles() -> u32 {
    8
}

fn default_max_cycles() -> u32 {
    400
}

fn default_tolerance() -> f64 {
    0.01
}

/// A complete damper scene.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scene {
    pub version: u32,
    pub name: String,
    pub particles: ParticlesSpec,
    pub enclosure: EnclosureSpec,
    pub contact: ContactSpec,
    pub simulation: SimulationSpec,
    pub drive: DriveSpec,
}

impl Scene {
    /// The built-in thesis damper.
    pub fn thesis() -> Scene {
        // The embedded preset is checked by a unit test; parsing it cannot fail.
        Scene::from_toml_str(THESIS_DAMPER_TOML, "built-in thesis scene")
            .unwrap_or_else(|e| panic!("embedded thesis scene is broken: {e}"))
    }

    /// Parses and validates a complete scene from TOML text.
    pub fn from_toml_str(text: &str, origin: &str) -> Result<Scene, SceneError> {
        Scene::parse(text, origin, true)
    }

    /// Parses and validates; `own_text` says whether error positions in `text`
    /// mean anything to the user (not in a scene merged from several sources).
    fn parse(text: &str, origin: &str, own_text: bool) -> Result<Scene, SceneError> {
        let error = |message| SceneError::Parse {
            path: origin.to_string(),
            message,
        };
        let mut scene: Scene = toml::from_str(text).map_err(|e| {
            error(match own_text {
                true => one_line(&e, Some(text)),
                // The merged text's lines are not the user's, but its keys
                // are: name the one at fault.
                false => with_key(&e, text),
            })
        })?;
        scene
            .particles
            .settle_diameter()
            .map_err(|e| SceneError::File {
                path: origin.to_string(),
                source: Box::new(e.into()),
            })?;
        scene.validate().map_err(|e| SceneError::File {
            path: origin.to_string(),
            source: Box::new(e),
        })?;
        Ok(scene)
    }

    /// Reads a scene file and merges it over the thesis preset.
    pub fn load_over_preset(path: &Path) -> Result<Scene, SceneError> {
        let shown = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|source| SceneError::Read {
            path: shown.clone(),
            source,
        })?;
        Scene::merge_over_preset(&text, &shown)
    }

    /// Merges TOML `text` over the thesis preset and validates the result.
    pub fn merge_over_preset(text: &str, origin: &str) -> Result<Scene, SceneError> {
        let parse = |t: &str, o: &str| -> Result<toml::Table, SceneError> {
            toml::from_str::<toml::Table>(t).map_err(|e| SceneError::Parse {
                path: o.to_string(),
                message: one_line(&e, Some(t)),
            })
        };
        let mut base = parse(THESIS_DAMPER_TOML, "built-in thesis scene")?;
        let overlay = parse(text, origin)?;
        // A file that sizes its particles by `equivalent_diameter_m` replaces
        // the preset's `diameter_m` (the same size under another name).
        if let (Some(toml::Value::Table(b)), Some(toml::Value::Table(t))) =
            (base.get_mut("particles"), overlay.get("particles"))
            && t.contains_key("equivalent_diameter_m")
            && !t.contains_key("diameter_m")
        {
            b.remove("diameter_m");
        }
        written_alone(&base, &overlay).map_err(|e| SceneError::File {
            path: origin.to_string(),
            source: Box::new(e.into()),
        })?;
        merge_tables(&mut base, overlay);
        let merged = toml::to_string(&base).map_err(|e| SceneError::Parse {
            path: origin.to_string(),
            message: e.to_string(),
        })?;
        Scene::parse(&merged, origin, false)
    }

    /// The resolved scene as TOML.
    pub fn to_toml(&self) -> String {
        toml::to_string_pretty(self).unwrap_or_else(|e| format!("# cannot print scene: {e}\n"))
    }

    /// Checks every value; a refusal names the key, its unit and valid range.
    /// The checks go table by table, in the file's order, so the first bad
    /// value is the one named.
    pub fn validate(&self) -> Result<(), SceneError> {
        if self.version != 1 {
            return Err(InvalidParameter::new(
                "version",
                self.version,
                "",
                "1 (the scene-file version this vlab reads)",
            )
            .into());
        }
        self.validate_bed()?;
        self.validate_contacts()?;
        self.validate_simulation()?;
        self.validate_drive()
    }

    /// `particles` and `enclosure`: the sizes and materials, and whether the
    /// enclosure can hold the particles.
    fn validate_bed(&self) -> Result<(), SceneError> {
        let p = &self.particles;
        require(
            p.count >= 1,
            "particles.count",
            p.count,
            "",
            "at least 1 (a damper of no particles has nothing to dissipate)",
        )?;
        positive("particles.diameter_m", p.diameter_m, "m")?;
        p.shape_keys().validate()?;
        let particle = p.material.resolve("particles.material")?;
        require(
            particle.youngs_pa.is_finite(),
            "particles.material",
            "\"rigid\"",
            "",
            "an elastic material: particles cannot be rigid",
        )?;
        let e = &self.enclosure;
        positive("enclosure.inner_diameter_m", e.inner_diameter_m, "m")?;
        positive("enclosure.inner_length_m", e.inner_length_m, "m")?;
        e.material.resolve("enclosure.material")?;
        let across_m = match p.shape_keys().sub_spheres_of(self.radius_m())? {
            Some(generated) => 2.0 * quick_reach_m(&generated)?,
            None => p.diameter_m,
        };
        if e.inner_diameter_m <= across_m || e.inner_length_m <= across_m {
            return Err(SceneError::ParticleTooLarge {
                diameter_m: e.inner_diameter_m,
                length_m: e.inner_length_m,
                particle_m: across_m,
            });
        }
        let fill = self.fill_ratio();
        if fill > MAX_FILL {
            return Err(SceneError::Overfull {
                count: p.count,
                what: match p.shape {
                    ShapeKind::Sphere => "spheres".into(),
                    other => format!("{}s with the volume of spheres", other.as_str()),
                },
                diameter_m: p.diameter_m,
                fill,
                max_count: self.max_particles(),
            });
        }
        Ok(())
    }

    /// `contact`: restitution and friction of both pairs.
    fn validate_contacts(&self) -> Result<(), SceneError> {
        let c = &self.contact;
        for (key, pair) in [
            ("contact.particle_particle", c.particle_particle),
            ("contact.particle_wall", c.particle_wall),
        ] {
            validation::restitution(&format!("{key}.restitution"), pair.restitution)?;
            validation::friction(&format!("{key}.friction"), pair.friction)?;
        }
        Ok(())
    }

    /// `simulation`: the time step and its rules, settling time and gravity.
    fn validate_simulation(&self) -> Result<(), SceneError> {
        let s = &self.simulation;
        in_range(
            "simulation.rayleigh_safety_factor",
            s.rayleigh_safety_factor,
            "",
            Bound::Open(0.0),
            Bound::Closed(1.0),
        )?;
        if let TimeStepSpec::Seconds(dt) = s.dt_s {
            check_time_step("simulation.dt_s", dt, self.rayleigh_limit_s())?;
        }
        // More than 1000 steps a contact only makes the run longer (the
        // collision's errors are 1e-5 at 200, docs/accuracy.md) and at
        // 1e12 a run never ended.
        in_range(
            "simulation.steps_per_contact",
            s.steps_per_contact,
            "",
            Bound::Closed(5.0),
            Bound::Closed(1000.0),
        )?;
        non_negative("simulation.settle_s", s.settle_s, "s")?;
        // A bed is poured and comes to rest under gravity, and a drive's
        // Gamma is its acceleration over gravity: neither exists without it.
        positive("simulation.gravity_mps2", s.gravity_mps2, "m/s^2")
            .map_err(|e| e.because("the bed settles under it, and Gamma is measured in it"))?;
        Ok(())
    }

    /// `drive`: the run length, a number of cycles or the until-steady rule.
    fn validate_drive(&self) -> Result<(), SceneError> {
        let d = &self.drive;
        match &d.cycles {
            CyclesSpec::Count(cycles) => {
                count_in("drive.cycles", *cycles, "", 1, Some(MAX_DRIVE_CYCLES))?;
                require(
                    (1..=*cycles).contains(&d.steady_cycles),
                    "drive.steady_cycles",
                    d.steady_cycles,
                    "",
                    format!("in [1, drive.cycles = {cycles}]"),
                )?;
            }
            CyclesSpec::Rule(CyclesRule::Steady) => {
                count_in("drive.min_cycles", d.min_cycles, "", 4, None)?;
                count_in(
                    "drive.max_cycles",
                    d.max_cycles,
                    "",
                    d.min_cycles,
                    Some(MAX_DRIVE_CYCLES),
                )?;
                for (key, x) in [
                    ("drive.balance_rel", d.balance_rel),
                    ("drive.stderr_rel", d.stderr_rel),
                ] {
                    in_range(key, x, "", Bound::Open(0.0), Bound::Open(1.0))?;
                }
            }
        }
        Ok(())
    }

    /// How long the drive runs (validated scenes only).
    pub fn drive_length(&self) -> DriveLength {
        let d = &self.drive;
        match d.cycles {
            CyclesSpec::Count(cycles) => DriveLength::Fixed {
                cycles,
                steady_cycles: d.steady_cycles,
            },
            CyclesSpec::Rule(CyclesRule::Steady) => DriveLength::UntilSteady {
                min_cycles: d.min_cycles,
                max_cycles: d.max_cycles,
                criteria: SteadyCriteria {
                    balance_rel: d.balance_rel,
                    stderr_rel: d.stderr_rel,
                },
            },
        }
    }

    /// Particle material (validated scenes only).
    pub fn particle_material(&self) -> Material {
        self.particles
            .material
            .resolve("particles.material")
            .unwrap_or(Material::ACRYLIC)
    }

    /// Wall material (validated scenes only).
    pub fn wall_material(&self) -> Material {
        self.enclosure
            .material
            .resolve("enclosure.material")
            .unwrap_or(Material::ACRYLIC)
    }

    /// Particle radius (m).
    pub fn radius_m(&self) -> f64 {
        0.5 * self.particles.diameter_m
    }

    /// Enclosure inner volume (m³).
    pub fn enclosure_volume_m3(&self) -> f64 {
        let r = 0.5 * self.enclosure.inner_diameter_m;
        PI * r * r * self.enclosure.inner_length_m
    }

    /// Volume of one particle (m³).
    pub fn particle_volume_m3(&self) -> f64 {
        4.0 / 3.0 * PI * self.radius_m().powi(3)
    }

    /// Volume fill ratio, thesis eq. 6.1.
    pub fn fill_ratio(&self) -> f64 {
        self.particles.count as f64 * self.particle_volume_m3() / self.enclosure_volume_m3()
    }

    /// Most particles the enclosure can hold (random close packing).
    pub fn max_particles(&self) -> usize {
        (MAX_FILL * self.enclosure_volume_m3() / self.particle_volume_m3()).floor() as usize
    }

    /// Total particle mass (kg): of the spheres, or of the bodies, each the
    /// mass of the union of its sub-spheres (eq. 4.1).
    pub fn particle_mass_kg(&self) -> f64 {
        let each_kg = match self.particle_body() {
            Ok(Some(b)) => b.template.mass_kg,
            _ => sphere_mass_kg(self.radius_m(), self.particle_material().density_kgm3),
        };
        self.particles.count as f64 * each_kg
    }

    /// One particle as the DEM takes it when the particles are not spheres
    /// (the union of its sub-spheres measured once per process and shape);
    /// `None` for spheres. Validated scenes only.
    pub fn particle_body(&self) -> Result<Option<ParticleBody>, SceneError> {
        let density = self.particle_material().density_kgm3;
        ParticleBody::of(&self.particles.shape_keys(), self.radius_m(), density)
    }

    /// The smallest sphere that makes contact, the mass behind it, and how
    /// much faster than the particle it can meet a wall: a sphere's own, or
    /// a body's smallest sub-sphere, the least mass a contact on the body
    /// meets ([`ParticleBody::least_effective_mass_kg`]) and
    /// [`ParticleBody::impact_speed_factor`].
    /// Validated scenes only (a body that cannot be built counts as a
    /// sphere).
    pub fn contact_scale(&self) -> ContactScale {
        let density = self.particle_material().density_kgm3;
        match self.particle_body() {
            Ok(Some(b)) => ContactScale {
                radius_m: b.min_sub_radius_m,
                mass_kg: b.least_effective_mass_kg(),
                speed_factor: b.impact_speed_factor(),
            },
            _ => ContactScale {
                radius_m: self.radius_m(),
                mass_kg: sphere_mass_kg(self.radius_m(), density),
                speed_factor: 1.0,
            },
        }
    }

    /// The Verlet skin a bed of bodies needs instead of the spheres'
    /// default ([`crate::dem::Numerics::with_dt`]): [`BODY_SKIN_RATIO`],
    /// as their overlapping sub-spheres put many pairs within a wide skin;
    /// `None` for spheres.
    pub fn body_skin_ratio(&self) -> Option<f64> {
        (!self.particles.shape.is_sphere()).then_some(BODY_SKIN_RATIO)
    }

    /// Rayleigh time step, the stability limit (s), eq. 3.31, of the
    /// smallest sphere in contact (a body's smallest sub-sphere, Section
    /// 4.2).
    pub fn rayleigh_limit_s(&self) -> f64 {
        rayleigh_time_step_s(&self.particle_material(), self.contact_scale().radius_m)
    }

    /// The drive at `freq_hz` and `gamma` under the scene's gravity
    /// (`simulation.gravity_mps2`), checked as [`Drive::new`] checks it.
    pub fn drive(&self, freq_hz: f64, gamma: f64) -> Result<Drive, InvalidParameter> {
        Drive::new(freq_hz, gamma, self.simulation.gravity_mps2)
    }

    /// The time step (s) of `drive`: the scene's own,
    /// `rayleigh_safety_factor` times the Rayleigh step (eq. 3.31), or, for
    /// `"contacts"` (the default), the step that resolves the shortest contact
    /// the drive can bring with `steps_per_contact` steps: the stiffest pair
    /// (particle-particle or particle-wall, eq. 5.6 and 5.10) at the largest
    /// impact speed to expect, the enclosure's velocity amplitude `Γ g / ω`
    /// plus a free fall across the enclosure `√(2 g max(L, D))`; never above
    /// the safety factor times the Rayleigh step, nor 1/200 of a cycle.
    /// For bodies the stiffest pair is a sub-sphere's, or, shorter where
    /// several sub-spheres touch at once, a whole body's against another or
    /// a wall, measured ([`Scene::body_collisions`]); `"sub_sphere_contacts"`
    /// leaves the bodies' collisions out.
    pub fn drive_dt_s(&self, drive: &Drive) -> f64 {
        let sim = &self.simulation;
        let rayleigh = sim.rayleigh_safety_factor * self.rayleigh_limit_s();
        let rule = match sim.dt_s {
            TimeStepSpec::Seconds(dt) => return dt,
            TimeStepSpec::Rule(TimeStepRule::Rayleigh) => return rayleigh,
            TimeStepSpec::Rule(rule) => rule,
        };
        let t_c = self.sub_sphere_contact_s(drive);
        let t_c = match rule {
            TimeStepRule::Contacts => self
                .body_collisions(drive)
                .and_then(|b| b.shortest_s())
                .map_or(t_c, |t_body| t_c.min(t_body)),
            _ => t_c,
        };
        (t_c / sim.steps_per_contact)
            .min(rayleigh)
            .min(1.0 / (200.0 * drive.freq_hz()))
    }

    /// The shortest contact of one pair of spheres, or of sub-spheres of
    /// bodies, `drive` can bring (s): the stiffest pair, particle-particle
    /// or particle-wall (eq. 5.6 and 5.10), at the largest impact speed to
    /// expect ([`Scene::expected_impact_speed_mps`]), faster by a body's
    /// spin ([`ContactScale`]).
    fn sub_sphere_contact_s(&self, drive: &Drive) -> f64 {
        let laws = crate::scene::contact_laws(self);
        let scale = self.contact_scale();
        let speed = self.expected_impact_speed_mps(drive) * scale.speed_factor;
        shortest_contact_with_mass_s(
            &laws.particle_particle,
            &laws.particle_wall,
            scale.radius_m,
            scale.mass_kg,
            speed,
        )
    }

    /// The shortest collisions of whole bodies `drive` can bring
    /// ([`crate::dem::body_collision`]): two bodies, or a body and the
    /// enclosure's floor or side wall, meeting at the largest impact speed
    /// to expect, measured with a step 1/200 of one sub-sphere pair's
    /// contact; `None` for spheres. Measured once per process and scene.
    pub fn body_collisions(&self, drive: &Drive) -> Option<BodyCollisions> {
        static MEASURED: OnceLock<Mutex<HashMap<String, BodyCollisions>>> = OnceLock::new();
        let body = self.particle_body().ok()??;
        let laws = crate::scene::contact_laws(self);
        let speed_mps = self.expected_impact_speed_mps(drive);
        let e = &self.enclosure;
        let cylinder_m = (0.5 * e.inner_diameter_m, e.inner_length_m);
        let dt_s = self.sub_sphere_contact_s(drive) / BODY_PROBE_STEPS;
        let key = format!(
            "{:?} {laws:?} {cylinder_m:?} {speed_mps:e} {dt_s:e}",
            body.template
        );
        let memo = MEASURED.get_or_init(|| Mutex::new(HashMap::new()));
        if let Some(b) = memo.lock().ok().and_then(|m| m.get(&key).copied()) {
            return Some(b);
        }
        let measured = shortest_body_collisions(&BodyProbe {
            template: &body.template,
            pp_law: laws.particle_particle,
            pw_law: laws.particle_wall,
            cylinder_m,
            speed_mps,
            dt_s,
            max_steps: 20 * BODY_PROBE_STEPS as u64,
        });
        if let Ok(mut m) = memo.lock() {
            m.insert(key, measured);
        }
        Some(measured)
    }

    /// The largest impact speed `drive` is expected to bring (m/s): a particle thrown at the enclosure's peak velocity `V`
    /// meeting a wall that moves at `V` towards it (`2 V`), plus a free fall
    /// across the enclosure. (With `V` alone the thesis bed at 40 Hz, Gamma 20
    /// saw collisions of 22.6 steps against the 25 asked for.)
    pub fn expected_impact_speed_mps(&self, drive: &Drive) -> f64 {
        let g = self.simulation.gravity_mps2;
        let e = &self.enclosure;
        2.0 * drive.velocity_amplitude_mps()
            + (2.0 * g * e.inner_length_m.max(e.inner_diameter_m)).sqrt()
    }

    /// Yield velocities (m/s) of particle-particle and particle-wall impacts,
    /// eq. 5.26, when the particle material has a yield strength.
    pub fn yield_velocities_mps(&self) -> Option<YieldVelocities> {
        let pm = self.particle_material();
        let wm = self.wall_material();
        let y = pm.yield_strength_pa?;
        let r = self.radius_m();
        let m = sphere_mass_kg(r, pm.density_kgm3);
        let pp = hertz_theory::yield_velocity_mps(
            effective_mass_kg(m, m),
            effective_youngs_pa(&pm, &pm),
            effective_radius_m(r, r),
            y,
        );
        let pw = hertz_theory::yield_velocity_mps(m, effective_youngs_pa(&pm, &wm), r, y);
        Some(YieldVelocities {
            particle_particle_mps: pp,
            particle_wall_mps: pw,
        })
    }
}

/// A value the file wrote that the preset's other half of a pair refuses:
/// the refusal names the key the file wrote (`drive.cycles = 2`), not the
/// preset's (`drive.steady_cycles = 5`) that the user never saw.
fn written_alone(base: &toml::Table, overlay: &toml::Table) -> Result<(), InvalidParameter> {
    let int = |t: &toml::Table, table: &str, key: &str| -> Option<i64> {
        t.get(table)?.as_table()?.get(key)?.as_integer()
    };
    let wrote = |key: &str| {
        overlay
            .get("drive")
            .and_then(toml::Value::as_table)
            .is_some_and(|t| t.contains_key(key))
    };
    if let (Some(cycles), Some(window), false) = (
        int(overlay, "drive", "cycles"),
        int(base, "drive", "steady_cycles"),
        wrote("steady_cycles"),
    ) {
        window_fits(cycles, window)?;
    }
    if let (Some(min), Some(max), false) = (
        int(overlay, "drive", "min_cycles"),
        int(base, "drive", "max_cycles"),
        wrote("max_cycles"),
    ) && min > max
    {
        return Err(InvalidParameter::new(
            "drive.min_cycles",
            min,
            "",
            format!("at most drive.max_cycles = {max} (the built-in scene's; or set it too)"),
        ));
    }
    Ok(())
}

/// `drive.cycles`, set without a window, must hold the window it keeps
/// (`steady_cycles`, set elsewhere). A count of 0 is left to
/// [`Scene::validate`].
fn window_fits(cycles: i64, steady_cycles: i64) -> Result<(), InvalidParameter> {
    require(
        cycles < 1 || cycles >= steady_cycles,
        "drive.cycles",
        cycles,
        "",
        format!(
            "at least the steady window it keeps, drive.steady_cycles = {steady_cycles} (or set the window too)"
        ),
    )
}

/// Changes to a scene that a caller (the command line, a sweep) makes over a
/// scene file; [`SceneOverrides::apply`] validates the result, and a refusal
/// names the scene key (`drive.cycles`), which the caller may map to its own
/// name for the value.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SceneOverrides {
    /// `drive.cycles`.
    pub cycles: Option<u32>,
    /// `drive.steady_cycles`.
    pub steady_cycles: Option<u32>,
    /// `enclosure.orientation`.
    pub orientation: Option<Orientation>,
    /// `simulation.seed`.
    pub seed: Option<u64>,
    /// `simulation.dt_s`.
    pub dt_s: Option<f64>,
}

impl SceneOverrides {
    /// `scene` with the overrides applied, validated.
    pub fn apply(&self, mut scene: Scene) -> Result<Scene, SceneError> {
        if let Some(c) = self.cycles {
            if self.steady_cycles.is_none() {
                window_fits(c.into(), scene.drive.steady_cycles.into())?;
            }
            scene.drive.cycles = CyclesSpec::Count(c);
        }
        if let Some(s) = self.steady_cycles {
            scene.drive.steady_cycles = s;
            // A steady window asked for without a cycle count: the transient
            // the steady rule would skip, then exactly that window.
            if self.cycles.is_none() && matches!(scene.drive.cycles, CyclesSpec::Rule(_)) {
                let transient = scene.drive_length().min_transient_cycles();
                scene.drive.cycles = CyclesSpec::Count(transient.saturating_add(s));
            }
        }
        if let Some(o) = self.orientation {
            scene.enclosure.orientation = o;
        }
        if let Some(seed) = self.seed {
            scene.simulation.seed = seed;
        }
        if let Some(dt) = self.dt_s {
            scene.simulation.dt_s = TimeStepSpec::Seconds(dt);
        }
        scene.validate()?;
        Ok(scene)
    }
}

impl Scene {
    /// The built-in scene, or the file at `path` merged over it.
    pub fn load_or_thesis(path: Option<&Path>) -> Result<Scene, SceneError> {
        match path {
            Some(p) => Scene::load_over_preset(p),
            None => Ok(Scene::thesis()),
        }
    }

    /// Sets the steady (recorded) part of the drive to `duration_s` at
    /// `freq_hz` (at least 2 whole cycles), keeping the transient cycles.
    /// A record longer than [`MAX_DRIVE_CYCLES`] in all is refused as
    /// `duration_s`.
    pub fn set_record_length(&mut self, duration_s: f64, freq_hz: f64) -> Result<(), SceneError> {
        let transient = self.drive_length().min_transient_cycles();
        let most = MAX_DRIVE_CYCLES.saturating_sub(transient);
        let steady = (duration_s * freq_hz).ceil().max(2.0);
        if steady.is_nan() || steady > f64::from(most) {
            return Err(InvalidParameter::new(
                "duration_s",
                duration_s,
                "s",
                format!(
                    "positive and at most {} s: {most} cycles at {freq_hz} Hz after the {transient} transient ones (drive.cycles at most {MAX_DRIVE_CYCLES})",
                    (f64::from(most) / freq_hz * 1e3).floor() / 1e3
                ),
            )
            .into());
        }
        let steady = steady as u32;
        self.drive.cycles = CyclesSpec::Count(transient + steady);
        self.drive.steady_cycles = steady;
        Ok(())
    }
}

/// A TOML error as one line: its message, and its line and column in `text`
/// when the text is the user's own.
fn one_line(e: &toml::de::Error, text: Option<&str>) -> String {
    let message = e.message().trim().replace('\n', " ");
    match (text, e.span()) {
        (Some(t), Some(span)) => {
            let before = &t[..span.start.min(t.len())];
            let line = before.matches('\n').count() + 1;
            let column = before.len() - before.rfind('\n').map_or(0, |i| i + 1) + 1;
            format!("line {line}, column {column}: {message}")
        }
        _ => message,
    }
}

/// A TOML error of a merged scene as one line, led by the key at fault
/// (`particles.count: invalid value ...`) where the error points at one.
fn with_key(e: &toml::de::Error, text: &str) -> String {
    let message = one_line(e, None);
    let Some(span) = e.span() else {
        return message;
    };
    let before = &text[..span.start.min(text.len())];
    let line_start = before.rfind('\n').map_or(0, |i| i + 1);
    let line = text[line_start..].lines().next().unwrap_or("");
    let Some((key, _)) = line.split_once('=') else {
        return message;
    };
    let table = before[..line_start]
        .lines()
        .rev()
        .find_map(|l| l.trim().strip_prefix('[')?.strip_suffix(']'))
        .map(|t| format!("{}.", t.trim_matches(['[', ']'])));
    format!("{}{}: {message}", table.unwrap_or_default(), key.trim())
}

/// Recursively overlays `top` onto `base`: tables merge, everything else replaces.
fn merge_tables(base: &mut toml::Table, top: toml::Table) {
    for (key, value) in top {
        match (base.get_mut(&key), value) {
            (Some(toml::Value::Table(b)), toml::Value::Table(t)) => merge_tables(b, t),
            (_, v) => {
                base.insert(key, v);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn embedded_preset_is_the_thesis_damper() {
        let s = Scene::thesis();
        assert_eq!(s.particles.count, 358);
        assert!((s.fill_ratio() - 0.466).abs() < 0.001, "{}", s.fill_ratio());
        assert!((s.particle_mass_kg() - 0.0279).abs() < 0.0001);
        // The time step resolves a 40 Hz, Gamma 20 drive's fastest expected
        // contact (acrylic pair at 2 x 0.78 + 0.89 m/s, 29.6 us) in 25 steps:
        // t_c scales as v^(-1/5), 33.3 us at 1.666 m/s.
        let dt = s.drive_dt_s(&s.drive(40.0, 20.0).expect("valid drive"));
        let v = s.expected_impact_speed_mps(&s.drive(40.0, 20.0).expect("valid drive"));
        assert!((v - 2.447).abs() < 0.01, "{v}");
        let expected = 1.33e-6 * (1.666f64 / v).powf(0.2);
        assert!((dt - expected).abs() < 0.02e-6, "{dt} vs {expected}");
        let pp = s
            .yield_velocities_mps()
            .expect("acrylic has a yield strength")
            .particle_particle_mps;
        assert!((pp - 3.5).abs() < 0.1);
    }

    #[test]
    fn every_checked_in_rig_toml_that_is_a_scene_parses() {
        // The scene preset is a file in rig/; it must parse on its own.
        let s = Scene::from_toml_str(THESIS_DAMPER_TOML, "scenes/thesis-damper.toml");
        assert!(s.is_ok(), "{:?}", s.err());
    }

    #[test]
    fn partial_file_overrides_only_its_keys() {
        let s = Scene::merge_over_preset(
            "[particles]\ncount = 200\n[enclosure]\norientation = \"horizontal\"\n",
            "test",
        )
        .expect("valid");
        assert_eq!(s.particles.count, 200);
        assert_eq!(s.enclosure.orientation, Orientation::Horizontal);
        assert_eq!(s.particles.diameter_m, 0.005);
    }

    #[test]
    fn unknown_keys_and_bad_values_are_named() {
        let err = Scene::merge_over_preset("[particles]\ncolour = 3\n", "f.toml").unwrap_err();
        assert!(err.to_string().contains("colour"), "{err}");
        let err = Scene::merge_over_preset("[particles]\ncount = 700\n", "f.toml").unwrap_err();
        assert!(err.to_string().contains("random close packing"), "{err}");
        // A value of the wrong type in a file merged over the preset names
        // its key (it gave serde's words alone).
        let err = Scene::merge_over_preset("[particles]\ncount = -5\n", "f.toml").unwrap_err();
        assert!(err.to_string().contains("particles.count: "), "{err}");
        let err =
            Scene::merge_over_preset("[particles]\nshape = \"cube\"\n", "f.toml").unwrap_err();
        assert!(err.to_string().contains("particles.shape: "), "{err}");
        // A damper of no particles was taken, and driven, before.
        let err = Scene::merge_over_preset("[particles]\ncount = 0\n", "f.toml").unwrap_err();
        assert!(err.to_string().contains("particles.count = 0"), "{err}");
        let err = Scene::merge_over_preset("[simulation]\ndt_s = 1e-4\n", "f.toml").unwrap_err();
        assert!(err.to_string().contains("stability limit"), "{err}");
        let err = Scene::merge_over_preset(
            "[contact]\nparticle_wall = { restitution = 1.5, friction = 0.5 }\n",
            "f.toml",
        )
        .unwrap_err();
        assert!(err.to_string().contains("(0, 1]"), "{err}");
        let err = Scene::merge_over_preset("version = 2\n", "f.toml").unwrap_err();
        assert!(err.to_string().contains("version"), "{err}");
        let err = Scene::merge_over_preset("[particles\n", "f.toml").unwrap_err();
        assert!(err.to_string().contains("f.toml"), "{err}");
    }

    #[test]
    fn rules_keep_their_spelling_and_bad_words_are_named() {
        let s = Scene::thesis();
        assert_eq!(
            s.simulation.dt_s,
            TimeStepSpec::Rule(TimeStepRule::Contacts)
        );
        assert_eq!(s.drive.cycles, CyclesSpec::Rule(CyclesRule::Steady));
        let text = s.to_toml();
        assert!(text.contains("dt_s = \"contacts\""), "{text}");
        assert!(text.contains("cycles = \"steady\""), "{text}");
        assert_eq!(
            Scene::from_toml_str(&text, "printed").expect("reads back"),
            s
        );
        let err = Scene::merge_over_preset("[simulation]\ndt_s = \"fast\"\n", "f.toml")
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("simulation.dt_s = \"fast\": must be a time step in seconds, \"contacts\", \"sub_sphere_contacts\" or \"rayleigh\""),
            "{err}"
        );
        // The shape study's rule reads and prints back under its own word.
        let mut one_pair = Scene::thesis();
        one_pair.simulation.dt_s = TimeStepSpec::Rule(TimeStepRule::SubSphereContacts);
        let text = one_pair.to_toml();
        assert!(text.contains("dt_s = \"sub_sphere_contacts\""), "{text}");
        assert_eq!(
            Scene::from_toml_str(&text, "printed").expect("reads back"),
            one_pair
        );
        let err = Scene::merge_over_preset("[drive]\ncycles = \"forever\"\n", "f.toml")
            .unwrap_err()
            .to_string();
        assert!(err.contains("drive.cycles = \"forever\""), "{err}");
    }

    #[test]
    fn rayleigh_rule_uses_the_safety_factor() {
        let s = Scene::merge_over_preset(
            "[simulation]\ndt_s = \"rayleigh\"\nrayleigh_safety_factor = 0.1\n",
            "t",
        )
        .expect("valid");
        assert!(
            (s.drive_dt_s(&s.drive(40.0, 20.0).expect("valid drive")) - 0.1 * s.rayleigh_limit_s())
                .abs()
                < 1e-18
        );
    }

    /// The contact rule resolves the stiffer pair. In the acrylic thesis
    /// cylinder the particle-particle contact is the shorter one (half the
    /// mass and radius of the wall contact at the same modulus); in a steel
    /// cylinder the acrylic sphere meets a wall of about twice the acrylic
    /// pair's E*, the wall contact is the shortest and the step follows it.
    /// Both steps equal their contact's Hertz duration (eq. 5.10) over 25
    /// steps to 1e-12.
    #[test]
    fn the_time_step_follows_the_stiffer_particle_wall_pair() {
        let acrylic = Scene::thesis();
        let steel_walls = Scene::merge_over_preset("[enclosure]\nmaterial = \"steel\"\n", "t")
            .expect("valid scene");
        let (f, gamma) = (40.0, 20.0);
        let dt_acrylic = acrylic.drive_dt_s(&acrylic.drive(f, gamma).expect("valid drive"));
        let dt_steel = steel_walls.drive_dt_s(&steel_walls.drive(f, gamma).expect("valid drive"));
        assert!(
            dt_steel < 0.95 * dt_acrylic,
            "steel walls {dt_steel:e} s, acrylic walls {dt_acrylic:e} s"
        );

        let pm = acrylic.particle_material();
        let r = acrylic.radius_m();
        let m = sphere_mass_kg(r, pm.density_kgm3);
        let v = acrylic.expected_impact_speed_mps(&acrylic.drive(f, gamma).expect("valid drive"));
        assert_eq!(
            v,
            steel_walls
                .expected_impact_speed_mps(&steel_walls.drive(f, gamma).expect("valid drive"))
        );
        let steps = acrylic.simulation.steps_per_contact;
        let pair_s = hertz_theory::contact_duration_s(
            effective_mass_kg(m, m),
            effective_youngs_pa(&pm, &pm),
            effective_radius_m(r, r),
            v,
        );
        let wall_s = |walls: &Scene| {
            hertz_theory::contact_duration_s(
                m,
                effective_youngs_pa(&pm, &walls.wall_material()),
                r,
                v,
            )
        };
        assert!(pair_s < wall_s(&acrylic), "acrylic: the pair is shorter");
        assert!(wall_s(&steel_walls) < pair_s, "steel: the wall is shorter");
        let rel = |a: f64, b: f64| (a / b - 1.0).abs();
        assert!(rel(dt_acrylic, pair_s / steps) < 1e-12, "{dt_acrylic:e}");
        assert!(
            rel(dt_steel, wall_s(&steel_walls) / steps) < 1e-12,
            "{dt_steel:e}"
        );
    }
}
