//! The error type of scene files and of the runs built from them, and the
//! replay option an error can ask for. It lives apart from the format so every
//! layer above (experiments, studies, exporters) can name it without importing
//! the scene parser, and the scene format imports nothing above itself.

use thiserror::Error;

use crate::dem::DemError;
use crate::rig::RigError;
use crate::scene::packing::MAX_FILL;
use crate::signals::SignalsError;
use crate::validation::InvalidParameter;

/// Errors of scene files and scene runs. The drop test
/// (`experiment::drop`) has no error type of its own: its refusals and
/// failures (a set-up value out of range, the engine, the rig, the record's
/// analysis) are this type's `Invalid`, `Dem`, `Rig` and `Signals`, so a
/// caller handles the drop and the damper alike.
#[derive(Debug, Error)]
pub enum SceneError {
    /// A bed of an ensemble failed, and the others gave up with it.
    #[error("ensemble of beds given up: {0}")]
    Ensemble(String),
    #[error("cannot read scene file {path}")]
    Read {
        path: String,
        source: std::io::Error,
    },
    /// Not TOML, an unknown key, a missing key or a wrong type.
    #[error("scene file {path} is not valid: {message}")]
    Parse { path: String, message: String },
    /// A value of the file is out of range, or the scene it describes cannot be.
    #[error("scene file {path} is not valid: {source}")]
    File {
        path: String,
        #[source]
        source: Box<SceneError>,
    },
    /// A value out of its range, named by its scene key or parameter name.
    #[error("{0}")]
    Invalid(#[from] InvalidParameter),
    /// More particles than the enclosure can hold.
    #[error(
        "particles.count = {count} {what} of {diameter_m} m fill {fill:.3} of the enclosure, above random close packing ({MAX_FILL}): the enclosure cannot hold them (at most {max_count} fit)"
    )]
    Overfull {
        count: usize,
        /// "spheres", or the shape's plural with "the volume of spheres".
        what: String,
        diameter_m: f64,
        fill: f64,
        max_count: usize,
    },
    /// A particle as large as the enclosure.
    #[error(
        "the enclosure ({diameter_m} m x {length_m} m) must be larger than a particle ({particle_m} m) in both directions"
    )]
    ParticleTooLarge {
        diameter_m: f64,
        length_m: f64,
        particle_m: f64,
    },
    /// Random insertion could not place every sphere in the pouring column.
    #[error(
        "random insertion placed only {placed} of {count} spheres in the pouring column ({column_m:.4} m high)"
    )]
    Insertion {
        placed: usize,
        count: usize,
        column_m: f64,
    },
    /// The bed cannot be closed in its enclosure: the lid, lowered as a piston,
    /// would crush it. `reached` is the packing fraction of the poured bed,
    /// floor to the top of its highest sphere.
    #[error(
        "the particles do not fit: a fill of {fill:.3} needs the bed to pack at {fill:.3} from floor to lid; poured, it packs at {reached:.3} from the floor to its highest sphere, and {cause}; reduce particles.count or lengthen enclosure.inner_length_m"
    )]
    DoesNotFit {
        fill: f64,
        reached: f64,
        cause: String,
    },
    /// The settling bed did not come to rest.
    #[error(
        "the bed did not come to rest while {phase}: after {time_s} s of settling{brake} the particles still move at {rms_speed_mps:.4} m/s RMS (at rest: below {rest_mps:.4} m/s)",
        brake = if *.braked { " (the second half with a brake on rolling and sliding)" } else { "" }
    )]
    NotAtRest {
        phase: &'static str,
        time_s: f64,
        /// Whether the second half of the time braked rolling and sliding
        /// (not without gravity, where nothing rolls on a floor).
        braked: bool,
        rms_speed_mps: f64,
        rest_mps: f64,
    },
    /// An output file could not be written.
    #[error("cannot write {}", path.display())]
    Write {
        path: std::path::PathBuf,
        source: std::io::Error,
    },
    /// A record given to `vlab replay` that cannot be replayed.
    #[error("record {}: {problem}", path.display())]
    Record {
        path: std::path::PathBuf,
        problem: String,
    },
    /// A record that cannot be replayed without an option it does not
    /// declare; `problem` says which.
    #[error("record {}: {problem}", path.display())]
    RecordNeeds {
        path: std::path::PathBuf,
        problem: String,
        option: ReplayOption,
    },
    #[error("particles: {0}")]
    Shape(#[from] crate::shape::ShapeError),
    #[error(transparent)]
    Dem(#[from] DemError),
    #[error(transparent)]
    Rig(#[from] RigError),
    #[error(transparent)]
    Signals(#[from] SignalsError),
}

/// A replay option that an error or a warning asks the caller to give,
/// named as the field of `vlab::experiment::replay::ReplayOptions` that holds it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ReplayOption {
    /// `freq_hz`.
    FreqHz,
    /// `particle_mass_kg`.
    ParticleMassKg,
    /// `columns.force`.
    ForceColumn,
    /// `columns.velocity` (or `displacement`, `acceleration`).
    MotionColumn,
}

impl ReplayOption {
    /// The field's name.
    pub fn key(self) -> &'static str {
        match self {
            ReplayOption::FreqHz => "freq_hz",
            ReplayOption::ParticleMassKg => "particle_mass_kg",
            ReplayOption::ForceColumn => "columns.force",
            ReplayOption::MotionColumn => "columns.velocity",
        }
    }
}

impl std::fmt::Display for ReplayOption {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.key())
    }
}
