//! Settled beds kept between runs, so that settling is paid once.
//!
//! Settling is three quarters of a default shake's wall time, and its result
//! depends only on what shapes the bed: the particles, the enclosure, the
//! settling law, gravity, the orientation and the seed — not on the contacts
//! under test or the drive (the settling law is fixed, see
//! [`crate::experiment::bed::settle`]) — and on the code that settles it. A bed is
//! stored under a key made of exactly those, plus the bed-file format and
//! vlab's version.
//!
//! # Why a bed cannot go stale
//!
//! The code's part of the key is [`PHYSICS_FINGERPRINT`], computed by the
//! package's `build.rs` when vlab is compiled: an FNV-1a 64 hash of
//!
//! - the bytes and paths of every file below `src/dem/`, `src/scene/` and
//!   `src/experiment/bed/`, and of `src/experiment/damper.rs` (the contact laws,
//!   integrator, neighbour search, walls, the scene's figures, the filling and
//!   the settling schedule, and this file's own encoding);
//! - the `Cargo.lock` versions of `glam`, `rand_core` and `rand_xoshiro`,
//!   whose arithmetic and random numbers reach the bed;
//! - the rustc version, target triple, target features and optimisation
//!   level (`powi` and `powf` need not round alike across them).
//!
//! A change there that moves a single trajectory therefore misses every cached
//! bed: nothing has to remember to bump a number, and CI, whose tests isolate
//! the cache, is not needed to notice. The price: any edit of a hashed file,
//! a comment-only one included, and a debug build after a release build,
//! settle their beds anew once. [`SETTLING_VERSION`] stays in the key as the
//! settling law's own name. The transcendental functions are `libm`'s
//! ([`crate::maths`]), whose version is in the key, not the platform's.
//!
//! Beds of another fingerprint are never read; `vlab cache list` marks them
//! stale and `vlab cache clear` removes them.
//!
//! # The bed file
//!
//! `bed-<hash>.vbed` in the cache folder, where `<hash>` is the FNV-1a 64-bit
//! hash of the key text:
//!
//! | bytes | what |
//! |---|---|
//! | 8 | magic `VLABBED\0` |
//! | 4 | format version [`BED_FORMAT_VERSION`], little-endian u32 |
//! | 4 | length `h` of the header, little-endian u32 |
//! | h | header, JSON ([`BedHeader`]): the full key text and the bed's figures |
//! | 80 n | per particle: position, velocity, angular velocity (3 f64 each), radius (f64), little-endian |
//! | 8 | FNV-1a 64 of everything before, little-endian |
//!
//! Floats are stored as their bits, so a bed read back drives to the same
//! numbers as the bed that was settled (tested). A file that is truncated,
//! fails its checksum, has another format version or holds another key (a
//! hash collision, a file copied in by hand) is ignored with a warning and
//! the bed is settled anew and stored over it. Writes go to a temporary file
//! that is renamed into place, so two runs settling the same bed at once both
//! leave a whole file.

use crate::clock::Stopwatch;
use crate::dem::state_hash::fnv1a64;
use std::fs;
use std::io;
use std::path::{Path, PathBuf};

use glam::DVec3;
use serde::{Deserialize, Serialize};

use crate::atomic_write::write_bytes_atomic;
use crate::dem::Particles;
use crate::experiment::bed::settle::{
    SETTLING_VERSION, SettledBed, rebuild_settled_world, settle_bed,
};
use crate::experiment::damper::Progress;
use crate::scene::{Scene, SceneError};
use crate::warning::RunWarning;

/// Hash of the code and compiler that settle a bed (see the module docs):
/// part of every bed's key.
pub const PHYSICS_FINGERPRINT: &str = env!("VLAB_PHYSICS_FINGERPRINT");
/// Version of the bed-file layout.
pub const BED_FORMAT_VERSION: u32 = 1;
/// Environment variable that moves the cache folder (tests, shared clusters).
pub const CACHE_DIR_ENV: &str = "VLAB_CACHE_DIR";

const MAGIC: &[u8; 8] = b"VLABBED\0";
const EXTENSION: &str = "vbed";
const F64_PER_PARTICLE: usize = 10;

/// Errors of the cache folder itself (not of one entry: those are warnings).
#[derive(Debug, thiserror::Error)]
pub enum BedCacheError {
    #[error("no cache folder: the platform names none and {CACHE_DIR_ENV} is not set")]
    NoFolder,
    #[error("cannot read the bed cache folder {path}")]
    Read {
        path: PathBuf,
        #[source]
        source: io::Error,
    },
    #[error("cannot remove {path}")]
    Remove {
        path: PathBuf,
        #[source]
        source: io::Error,
    },
}

/// What makes one bed differ from another; its JSON text is the cache key.
#[derive(Debug, Clone, PartialEq, Serialize)]
struct BedKey<'a> {
    bed_format: u32,
    settling_version: u32,
    physics_fingerprint: &'a str,
    vlab_version: &'static str,
    particles: &'a crate::scene::ParticlesSpec,
    particle_material: crate::dem::material::Material,
    inner_diameter_m: f64,
    inner_length_m: f64,
    orientation: &'static str,
    wall_material: crate::dem::material::Material,
    gravity_mps2: f64,
    seed: u64,
    /// Longest a settling stage may run (s): a bed that needs it is shaped by it.
    settle_s: f64,
    /// The body each particle is, when not a sphere: its sub-spheres
    /// (principal frame, `[x, y, z, r]`), mass and moments, so that a
    /// changed generator or clump file makes another bed.
    #[serde(skip_serializing_if = "Option::is_none")]
    body: Option<BodyKey>,
}

/// The body of a bed of bodies, in its key.
#[derive(Debug, Clone, PartialEq, Serialize)]
struct BodyKey {
    sub_spheres: Vec<[f64; 4]>,
    mass_kg: f64,
    inertia_kgm2: [f64; 3],
}

impl BodyKey {
    fn of(scene: &Scene) -> Option<BodyKey> {
        let body = scene.particle_body().ok().flatten()?;
        let t = &body.template;
        Some(BodyKey {
            sub_spheres: t
                .offsets_m
                .iter()
                .zip(&t.radii_m)
                .map(|(o, r)| [o.x, o.y, o.z, *r])
                .collect(),
            mass_kg: t.mass_kg,
            inertia_kgm2: t.inertia_kgm2.to_array(),
        })
    }
}

/// The cache key of the bed `scene` settles to (JSON text), with this
/// build's [`PHYSICS_FINGERPRINT`].
pub fn bed_key(scene: &Scene) -> String {
    bed_key_with(scene, PHYSICS_FINGERPRINT)
}

/// [`bed_key`] as code of fingerprint `fingerprint` would make it.
fn bed_key_with(scene: &Scene, fingerprint: &str) -> String {
    let key = BedKey {
        bed_format: BED_FORMAT_VERSION,
        settling_version: SETTLING_VERSION,
        physics_fingerprint: fingerprint,
        vlab_version: env!("CARGO_PKG_VERSION"),
        particles: &scene.particles,
        particle_material: scene.particle_material(),
        inner_diameter_m: scene.enclosure.inner_diameter_m,
        inner_length_m: scene.enclosure.inner_length_m,
        orientation: scene.enclosure.orientation.as_str(),
        wall_material: scene.wall_material(),
        gravity_mps2: scene.simulation.gravity_mps2,
        seed: scene.simulation.seed,
        settle_s: scene.simulation.settle_s,
        body: BodyKey::of(scene),
    };
    // Plain data with string keys: serialising cannot fail.
    serde_json::to_string(&key).unwrap_or_else(|e| panic!("bed key: {e}"))
}

/// The header of a bed file: the key and the figures of the bed.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BedHeader {
    /// The full key text ([`bed_key`]).
    pub key: String,
    /// The [`PHYSICS_FINGERPRINT`] of the vlab that settled it (empty in beds
    /// made before fingerprints).
    #[serde(default)]
    pub fingerprint: String,
    /// Name of the scene that first settled it (for `vlab cache list`).
    pub scene: String,
    pub n_particles: usize,
    pub settle_time_s: f64,
    pub settle_steps: u64,
    /// Wall time the settling took when it was done (s).
    pub settle_wall_time_s: f64,
    pub packing_fraction: f64,
    pub bed_height_m: f64,
    /// Time step the bed settled at last (s).
    pub dt_s: f64,
    /// Rigid bodies the particles are sub-spheres of (none for spheres);
    /// their states follow the particles' ([`BodyState`]).
    #[serde(default, skip_serializing_if = "is_zero")]
    pub n_bodies: usize,
}

fn is_zero(n: &usize) -> bool {
    *n == 0
}

/// Numbers per body of a bed file: centre, velocity, orientation
/// (x, y, z, w) and angular momentum.
const F64_PER_BODY: usize = 13;

/// One rigid body of a bed file: what its sub-spheres' states follow from.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BodyState {
    pub position_m: DVec3,
    pub velocity_mps: DVec3,
    pub orientation: glam::DQuat,
    pub angular_momentum_kgm2ps: DVec3,
}

/// Encodes `bed` of `scene` as a bed file.
pub fn encode_bed(scene: &Scene, bed: &SettledBed) -> Vec<u8> {
    encode_bed_with(scene, bed, PHYSICS_FINGERPRINT)
}

/// [`encode_bed`] as code of fingerprint `fingerprint` would write it.
fn encode_bed_with(scene: &Scene, bed: &SettledBed, fingerprint: &str) -> Vec<u8> {
    let p = &*bed.world.particles.by_id();
    let header = BedHeader {
        key: bed_key_with(scene, fingerprint),
        fingerprint: fingerprint.to_string(),
        scene: scene.name.clone(),
        n_particles: p.len(),
        settle_time_s: bed.settle_time_s,
        settle_steps: bed.settle_steps,
        settle_wall_time_s: bed.wall_time_s,
        packing_fraction: bed.packing_fraction,
        bed_height_m: bed.bed_height_m,
        dt_s: bed.world.dt_s(),
        n_bodies: p.clumps.len(),
    };
    let header = serde_json::to_vec(&header).unwrap_or_else(|e| panic!("bed header: {e}"));
    let mut out = Vec::with_capacity(24 + header.len() + 8 * F64_PER_PARTICLE * p.len());
    out.extend_from_slice(MAGIC);
    out.extend_from_slice(&BED_FORMAT_VERSION.to_le_bytes());
    out.extend_from_slice(&(header.len() as u32).to_le_bytes());
    out.extend_from_slice(&header);
    for i in 0..p.len() {
        for v in [p.position[i], p.velocity[i], p.angular_velocity[i]] {
            for x in v.to_array() {
                out.extend_from_slice(&x.to_le_bytes());
            }
        }
        out.extend_from_slice(&p.radius[i].to_le_bytes());
    }
    let c = &p.clumps;
    for b in 0..c.len() {
        let numbers = [
            c.position[b].to_array().as_slice(),
            c.velocity[b].to_array().as_slice(),
            c.orientation[b].to_array().as_slice(),
            c.angular_momentum[b].to_array().as_slice(),
        ]
        .concat();
        for x in numbers {
            out.extend_from_slice(&x.to_le_bytes());
        }
    }
    let sum = fnv1a64(&out);
    out.extend_from_slice(&sum.to_le_bytes());
    out
}

/// Why a bed file was not used.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum BadBed {
    #[error("it is not a vlab bed file")]
    NotABed,
    #[error("it is cut short or its checksum does not match (a corrupt file)")]
    Corrupt,
    #[error("it has bed format {0}, this vlab reads {BED_FORMAT_VERSION}")]
    OtherFormat(u32),
    #[error("its header cannot be read: {0}")]
    Header(String),
    #[error("it holds another bed (scene {0:?})")]
    OtherKey(String),
}

/// A decoded bed file: its header and particles' state.
#[derive(Debug, Clone)]
pub struct DecodedBed {
    pub header: BedHeader,
    /// Each particle's state.
    pub state: Vec<ParticleState>,
    /// Each rigid body's state (none for spheres).
    pub bodies: Vec<BodyState>,
}

/// One particle of a bed file.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ParticleState {
    pub position_m: DVec3,
    pub velocity_mps: DVec3,
    pub angular_velocity_radps: DVec3,
    pub radius_m: f64,
}

/// Reads a bed file's bytes; `expect_key` (when given) must be its key.
pub fn decode_bed(bytes: &[u8], expect_key: Option<&str>) -> Result<DecodedBed, BadBed> {
    if bytes.len() < 16 || &bytes[..8] != MAGIC {
        return Err(BadBed::NotABed);
    }
    let u32_at =
        |k: usize| u32::from_le_bytes([bytes[k], bytes[k + 1], bytes[k + 2], bytes[k + 3]]);
    let version = u32_at(8);
    if version != BED_FORMAT_VERSION {
        return Err(BadBed::OtherFormat(version));
    }
    if bytes.len() < 24 {
        return Err(BadBed::Corrupt);
    }
    let (body, sum) = bytes.split_at(bytes.len() - 8);
    let mut sum_bytes = [0u8; 8];
    sum_bytes.copy_from_slice(sum);
    if fnv1a64(body) != u64::from_le_bytes(sum_bytes) {
        return Err(BadBed::Corrupt);
    }
    let h = u32_at(12) as usize;
    let Some(header_bytes) = body.get(16..16 + h) else {
        return Err(BadBed::Corrupt);
    };
    let header: BedHeader =
        serde_json::from_slice(header_bytes).map_err(|e| BadBed::Header(e.to_string()))?;
    if let Some(key) = expect_key
        && header.key != key
    {
        return Err(BadBed::OtherKey(header.scene));
    }
    let data = &body[16 + h..];
    let particle_bytes = 8 * F64_PER_PARTICLE * header.n_particles;
    if data.len() != particle_bytes + 8 * F64_PER_BODY * header.n_bodies {
        return Err(BadBed::Corrupt);
    }
    let f = |k: usize| {
        let mut b = [0u8; 8];
        b.copy_from_slice(&data[8 * k..8 * k + 8]);
        f64::from_le_bytes(b)
    };
    let state = (0..header.n_particles)
        .map(|i| {
            let o = F64_PER_PARTICLE * i;
            let v = |k: usize| DVec3::new(f(o + k), f(o + k + 1), f(o + k + 2));
            ParticleState {
                position_m: v(0),
                velocity_mps: v(3),
                angular_velocity_radps: v(6),
                radius_m: f(o + 9),
            }
        })
        .collect();
    let bodies = (0..header.n_bodies)
        .map(|b| {
            let o = F64_PER_PARTICLE * header.n_particles + F64_PER_BODY * b;
            let v = |k: usize| DVec3::new(f(o + k), f(o + k + 1), f(o + k + 2));
            BodyState {
                position_m: v(0),
                velocity_mps: v(3),
                orientation: glam::DQuat::from_xyzw(f(o + 6), f(o + 7), f(o + 8), f(o + 9)),
                angular_momentum_kgm2ps: v(10),
            }
        })
        .collect();
    Ok(DecodedBed {
        header,
        state,
        bodies,
    })
}

/// One entry of the cache, for `vlab cache list`.
#[derive(Debug, Clone)]
pub struct CachedBedInfo {
    pub path: PathBuf,
    pub bytes: u64,
    /// The header, or why the file cannot be read.
    pub header: Result<BedHeader, BadBed>,
    /// Settled by other code than this vlab's (another
    /// [`PHYSICS_FINGERPRINT`]): never read, only listed and cleared.
    pub stale: bool,
}

/// A folder of settled beds.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct BedCache {
    dir: PathBuf,
    /// The fingerprint beds are stored and looked up under: this build's
    /// [`PHYSICS_FINGERPRINT`], another one only in tests.
    fingerprint: String,
}

impl BedCache {
    /// A cache in `dir` (made when the first bed is stored).
    pub fn new(dir: impl Into<PathBuf>) -> Self {
        BedCache {
            dir: dir.into(),
            fingerprint: PHYSICS_FINGERPRINT.to_string(),
        }
    }

    /// A cache in `dir` as code of fingerprint `fingerprint` would see it.
    #[cfg(test)]
    fn with_fingerprint(dir: impl Into<PathBuf>, fingerprint: &str) -> Self {
        BedCache {
            dir: dir.into(),
            fingerprint: fingerprint.to_string(),
        }
    }

    /// The user's cache: `$VLAB_CACHE_DIR`, else the platform's cache folder
    /// (`~/.cache/vlab/beds` on Linux, `~/Library/Caches/vlab/beds` on macOS,
    /// `%LOCALAPPDATA%\vlab\beds` on Windows).
    pub fn user() -> Result<Self, BedCacheError> {
        if let Some(dir) = std::env::var_os(CACHE_DIR_ENV).filter(|d| !d.is_empty()) {
            return Ok(BedCache::new(dir));
        }
        dirs::cache_dir()
            .map(|d| BedCache::new(d.join("vlab").join("beds")))
            .ok_or(BedCacheError::NoFolder)
    }

    /// The cache folder.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// Where the bed of `scene` is kept.
    pub fn path_for(&self, scene: &Scene) -> PathBuf {
        let hash = fnv1a64(bed_key_with(scene, &self.fingerprint).as_bytes());
        self.dir.join(format!("bed-{hash:016x}.{EXTENSION}"))
    }

    /// The bed of `scene` from the cache: `Ok(None)` when there is none,
    /// `Err` (a warning's text) when there is one that cannot be used.
    ///
    /// Over 80 lines: a cached bed read and checked in order (header, physics,
    /// scene, particles), each refusal with its own words.
    pub fn load(&self, scene: &Scene) -> Result<Option<SettledBed>, String> {
        let path = self.path_for(scene);
        let started = Stopwatch::start();
        let bytes = match fs::read(&path) {
            Ok(b) => b,
            Err(e) if e.kind() == io::ErrorKind::NotFound => return Ok(None),
            Err(e) => return Err(format!("cannot read cached bed {}: {e}", path.display())),
        };
        let key = bed_key_with(scene, &self.fingerprint);
        let decoded = decode_bed(&bytes, Some(&key)).map_err(|why| {
            format!(
                "cached bed {} was not used: {why}; settled anew",
                path.display()
            )
        })?;
        let density = scene.particle_material().density_kgm3;
        let unusable = |why: String| {
            format!(
                "cached bed {} was not used: {why}; settled anew",
                path.display()
            )
        };
        let mut particles = Particles::default();
        if decoded.bodies.is_empty() {
            for s in decoded.state {
                particles.push(
                    s.position_m,
                    s.velocity_mps,
                    s.angular_velocity_radps,
                    s.radius_m,
                    density,
                );
            }
        } else {
            let body = scene
                .particle_body()
                .map_err(|e| unusable(e.to_string()))?
                .ok_or_else(|| unusable("it holds bodies, the scene spheres".into()))?;
            for s in &decoded.bodies {
                let b = particles.push_clump(
                    &body.template,
                    (s.position_m, s.orientation),
                    (s.velocity_mps, DVec3::ZERO),
                );
                // The momentum as it was, not through the spin: the same bits.
                particles.clumps.angular_momentum[b] = s.angular_momentum_kgm2ps;
                particles.clumps.orientation[b] = s.orientation;
                particles.place_clump(b);
                // The sub-spheres' velocities as the step's half kick left
                // them (the spin crossed with each one's offset from the
                // centre), to the last bit: the first damping force reads
                // them.
                particles.set_clump_velocities(b);
            }
            if particles.len() != decoded.state.len() {
                return Err(unusable(format!(
                    "its {} sub-spheres are not the scene's {}",
                    decoded.state.len(),
                    particles.len()
                )));
            }
        }
        let h = decoded.header;
        let mut world = rebuild_settled_world(scene, particles, h.dt_s).map_err(|e| {
            format!(
                "cached bed {} was not used: {e}; settled anew",
                path.display()
            )
        })?;
        world.time_s = h.settle_time_s;
        world.steps = h.settle_steps;
        Ok(Some(SettledBed {
            world,
            settle_time_s: h.settle_time_s,
            settle_steps: h.settle_steps,
            wall_time_s: started.elapsed().as_secs_f64(),
            packing_fraction: h.packing_fraction,
            bed_height_m: h.bed_height_m,
            from_cache: true,
            warnings: Vec::new(),
        }))
    }

    /// Stores `bed` of `scene`, atomically.
    pub fn store(&self, scene: &Scene, bed: &SettledBed) -> io::Result<PathBuf> {
        fs::create_dir_all(&self.dir)?;
        let path = self.path_for(scene);
        write_bytes_atomic(&path, &encode_bed_with(scene, bed, &self.fingerprint))?;
        Ok(path)
    }

    /// Every bed file in the cache, by name.
    pub fn list(&self) -> Result<Vec<CachedBedInfo>, BedCacheError> {
        let mut out = Vec::new();
        for path in self.bed_files()? {
            let bytes = fs::read(&path).map_err(|source| BedCacheError::Read {
                path: path.clone(),
                source,
            })?;
            let header = decode_bed(&bytes, None).map(|d| d.header);
            out.push(CachedBedInfo {
                bytes: bytes.len() as u64,
                stale: header
                    .as_ref()
                    .is_ok_and(|h| h.fingerprint != self.fingerprint),
                header,
                path,
            });
        }
        Ok(out)
    }

    /// Removes every bed file (and nothing else); returns how many.
    pub fn clear(&self) -> Result<usize, BedCacheError> {
        let files = self.bed_files()?;
        for path in &files {
            fs::remove_file(path).map_err(|source| BedCacheError::Remove {
                path: path.clone(),
                source,
            })?;
        }
        Ok(files.len())
    }

    fn bed_files(&self) -> Result<Vec<PathBuf>, BedCacheError> {
        let entries = match fs::read_dir(&self.dir) {
            Ok(e) => e,
            Err(e) if e.kind() == io::ErrorKind::NotFound => return Ok(Vec::new()),
            Err(source) => {
                return Err(BedCacheError::Read {
                    path: self.dir.clone(),
                    source,
                });
            }
        };
        let mut files: Vec<PathBuf> = entries
            .filter_map(Result::ok)
            .map(|e| e.path())
            .filter(|p| {
                p.extension().is_some_and(|x| x == EXTENSION)
                    && p.file_name()
                        .is_some_and(|n| n.to_string_lossy().starts_with("bed-"))
            })
            .collect();
        files.sort();
        Ok(files)
    }
}

/// Where the settled beds of a run come from.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub enum BedSource {
    /// Settle every bed (a library's default: nothing is read or written
    /// outside the run).
    #[default]
    Settle,
    /// Read beds from this cache, settling and storing those it lacks.
    Cache(BedCache),
}

impl BedSource {
    /// The bed of `scene`: from the cache when it holds it, else settled (and
    /// stored when there is a cache). A cache entry that cannot be read, or a
    /// bed that cannot be stored, is a warning on the bed, never an error.
    pub fn settle(
        &self,
        scene: &Scene,
        progress: &mut dyn FnMut(Progress),
    ) -> Result<SettledBed, SceneError> {
        let BedSource::Cache(cache) = self else {
            return settle_bed(scene, progress);
        };
        let mut warnings: Vec<RunWarning> = Vec::new();
        match cache.load(scene) {
            Ok(Some(bed)) => return Ok(bed),
            Ok(None) => {}
            Err(w) => warnings.push(w.into()),
        }
        let mut bed = settle_bed(scene, progress)?;
        if let Err(e) = cache.store(scene, &bed) {
            warnings.push(
                format!(
                    "the settled bed could not be kept in the cache {}: {e}",
                    cache.dir().display()
                )
                .into(),
            );
        }
        warnings.append(&mut bed.warnings);
        bed.warnings = warnings;
        Ok(bed)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn small_scene() -> Scene {
        let mut s = Scene::thesis();
        s.particles.count = 40;
        s
    }

    #[test]
    fn the_key_holds_what_shapes_the_bed_and_not_what_does_not() {
        let base = small_scene();
        let k = bed_key(&base);
        let mut contacts = base.clone();
        contacts.contact.particle_particle.restitution = 0.3;
        contacts.contact.particle_wall.friction = 0.9;
        contacts.name = "renamed".into();
        assert_eq!(
            bed_key(&contacts),
            k,
            "contacts and name do not shape the bed"
        );
        let mut seed = base.clone();
        seed.simulation.seed += 1;
        let mut count = base.clone();
        count.particles.count += 1;
        let mut length = base.clone();
        length.enclosure.inner_length_m *= 1.01;
        let mut turned = base.clone();
        turned.enclosure.orientation = crate::scene::Orientation::Horizontal;
        let mut g = base.clone();
        g.simulation.gravity_mps2 = 1.62;
        for other in [seed, count, length, turned, g] {
            assert_ne!(bed_key(&other), k);
        }
    }

    #[test]
    fn a_bed_of_other_physics_is_a_miss_and_listed_stale() {
        let scene = small_scene();
        assert_eq!(PHYSICS_FINGERPRINT.len(), 16, "{PHYSICS_FINGERPRINT}");
        assert_ne!(
            bed_key_with(&scene, "0000000000000000"),
            bed_key(&scene),
            "the fingerprint is part of the key"
        );
        let dir = std::env::temp_dir().join(format!("vlab-bed-stale-test-{}", std::process::id()));
        let _ = fs::remove_dir_all(&dir);
        let old = BedCache::with_fingerprint(&dir, "0123456789abcdef");
        let bed = settle_bed(&scene, &mut |_| {}).expect("settles");
        old.store(&scene, &bed).expect("stores");
        assert!(
            old.load(&scene).expect("reads").is_some(),
            "a hit for its own code"
        );
        let now = BedCache::new(&dir);
        assert!(
            now.load(&scene).expect("no error").is_none(),
            "a bed of another fingerprint is a miss"
        );
        // Even copied to the name this build looks up, it is refused.
        fs::copy(old.path_for(&scene), now.path_for(&scene)).expect("copy");
        let refused = now.load(&scene).expect_err("another key");
        assert!(refused.contains("not used"), "{refused}");
        fs::remove_file(now.path_for(&scene)).expect("remove");
        let listed = now.list().expect("lists");
        assert_eq!(listed.len(), 1);
        assert!(listed[0].stale, "listed as stale");
        assert!(
            !old.list().expect("lists")[0].stale,
            "not stale to its own code"
        );
        let _ = fs::remove_dir_all(&dir);
    }

    #[test]
    fn a_bed_file_reads_back_to_the_same_bits_and_refuses_damage() {
        let scene = small_scene();
        let bed = settle_bed(&scene, &mut |_| {}).expect("settles");
        let bytes = encode_bed(&scene, &bed);
        let key = bed_key(&scene);
        let back = decode_bed(&bytes, Some(&key)).expect("reads back");
        assert_eq!(back.state.len(), 40);
        let p = &bed.world.particles;
        for (i, s) in back.state.iter().enumerate() {
            let (x, v, w, r) = (
                s.position_m,
                s.velocity_mps,
                s.angular_velocity_radps,
                s.radius_m,
            );
            assert_eq!(
                x.to_array().map(f64::to_bits),
                p.position[i].to_array().map(f64::to_bits)
            );
            assert_eq!(
                v.to_array().map(f64::to_bits),
                p.velocity[i].to_array().map(f64::to_bits)
            );
            assert_eq!(
                w.to_array().map(f64::to_bits),
                p.angular_velocity[i].to_array().map(f64::to_bits)
            );
            assert_eq!(r.to_bits(), p.radius[i].to_bits());
        }
        // A flipped byte, a cut file, another key, another format, not a bed.
        let mut flipped = bytes.clone();
        let mid = bytes.len() / 2;
        flipped[mid] ^= 0x10;
        assert_eq!(
            decode_bed(&flipped, Some(&key)).unwrap_err(),
            BadBed::Corrupt
        );
        assert_eq!(
            decode_bed(&bytes[..bytes.len() - 100], Some(&key)).unwrap_err(),
            BadBed::Corrupt
        );
        assert!(matches!(
            decode_bed(&bytes, Some("another key")).unwrap_err(),
            BadBed::OtherKey(_)
        ));
        let mut newer = bytes.clone();
        newer[8..12].copy_from_slice(&(BED_FORMAT_VERSION + 1).to_le_bytes());
        assert_eq!(
            decode_bed(&newer, Some(&key)).unwrap_err(),
            BadBed::OtherFormat(BED_FORMAT_VERSION + 1)
        );
        assert_eq!(
            decode_bed(b"id,t\n1,2\n", None).unwrap_err(),
            BadBed::NotABed
        );
    }

    #[test]
    fn a_cached_bed_drives_to_the_same_bits_as_a_fresh_one() {
        use crate::experiment::bed::settle::prepare_drive;
        let scene = small_scene();
        let dir = std::env::temp_dir().join(format!("vlab-bed-cache-test-{}", std::process::id()));
        let _ = fs::remove_dir_all(&dir);
        let source = BedSource::Cache(BedCache::new(&dir));
        let fresh = source.settle(&scene, &mut |_| {}).expect("settles");
        assert!(
            !fresh.from_cache && fresh.warnings.is_empty(),
            "{:?}",
            fresh.warnings
        );
        let cached = source.settle(&scene, &mut |_| {}).expect("reads");
        assert!(cached.from_cache);
        assert_eq!(cached.settle_steps, fresh.settle_steps);
        let dt = scene.drive_dt_s(&scene.drive(40.0, 20.0).expect("valid drive"));
        let mut a = prepare_drive(&fresh, &scene, dt).expect("drive");
        let mut b = prepare_drive(&cached, &scene, dt).expect("drive");
        let (amp, w) = (
            20.0 * 9.81 / (2.0 * std::f64::consts::PI * 40.0).powi(2),
            2.0 * std::f64::consts::PI * 40.0,
        );
        for k in 1..=3000u32 {
            let t = f64::from(k) * dt;
            let d = amp * (w * t).sin();
            a.step(d).expect("steps");
            b.step(d).expect("steps");
        }
        for i in 0..a.particles.len() {
            assert_eq!(
                a.particles.position[i].to_array().map(f64::to_bits),
                b.particles.position[i].to_array().map(f64::to_bits),
                "particle {i}"
            );
        }
        assert_eq!(
            a.ledger.dissipated.total().to_bits(),
            b.ledger.dissipated.total().to_bits()
        );

        // A damaged entry is a warning, and is settled anew and replaced.
        let path = BedCache::new(&dir).path_for(&scene);
        fs::write(&path, b"VLABBED\0garbage").expect("write");
        let again = source.settle(&scene, &mut |_| {}).expect("settles");
        assert!(!again.from_cache);
        assert!(
            again.warnings[0].text.contains("not used"),
            "{:?}",
            again.warnings
        );
        assert!(
            source
                .settle(&scene, &mut |_| {})
                .expect("reads")
                .from_cache
        );
        let cache = BedCache::new(&dir);
        assert_eq!(cache.list().expect("lists").len(), 1);
        assert_eq!(cache.clear().expect("clears"), 1);
        assert!(cache.list().expect("lists").is_empty());
        let _ = fs::remove_dir_all(&dir);
    }

    /// A bed of bodies read back from the cache is the bed that settled, bit
    /// for bit: the sub-spheres' positions, velocities and spins as well as
    /// the bodies' state. A sub-sphere velocity rebuilt by another formula
    /// than the step's (the spin crossed with the body-frame arm instead of
    /// with the sub-sphere's offset from the centre) differs in the last
    /// bit, enters the first damping force, and a long run from the cached
    /// bed then ends elsewhere than one from the fresh bed (a shear test's
    /// mean force 31.7 N against 31.6 N).
    #[test]
    fn a_cached_bed_of_bodies_is_the_settled_bed_bit_for_bit() {
        let text = "name = \"prolates\"\n[particles]\ncount = 24\nshape = \"prolate\"\naspect_ratio = 2.0\nsub_spheres = 11\nequivalent_diameter_m = 0.004\n[enclosure]\ninner_diameter_m = 0.02\ninner_length_m = 0.03\n[simulation]\nsettle_s = 0.05\n";
        let scene = Scene::merge_over_preset(text, "test").expect("scene");
        let dir = std::env::temp_dir().join(format!("vlab-bed-bodies-test-{}", std::process::id()));
        let _ = fs::remove_dir_all(&dir);
        let cache = BedCache::new(&dir);
        let fresh = settle_bed(&scene, &mut |_| {}).expect("settles");
        cache.store(&scene, &fresh).expect("stores");
        let read = cache.load(&scene).expect("reads").expect("a hit");
        let (a, b) = (fresh.world.particles.by_id(), read.world.particles.by_id());
        assert_eq!(a.len(), b.len());
        for k in 0..a.len() {
            assert_eq!(a.position[k], b.position[k], "position of {k}");
            assert_eq!(a.velocity[k], b.velocity[k], "velocity of {k}");
            assert_eq!(a.angular_velocity[k], b.angular_velocity[k], "spin of {k}");
        }
        assert_eq!(a.clumps.velocity, b.clumps.velocity);
        assert_eq!(a.clumps.angular_momentum, b.clumps.angular_momentum);
        let _ = fs::remove_dir_all(&dir);
    }
}
