//! The scene format: a damper, its particles, contacts, drive and run length, as
//! a TOML file merged over the built-in thesis preset, validated with units and
//! ranges before anything runs. Everything that runs a scene lives above this
//! module (`experiment`, `study`, `export`); nothing here imports them.

pub mod contact_laws;
pub mod drive_length;
pub mod error;
pub mod figures;
pub mod format;
pub mod packing;
pub mod particle_shape;
pub mod validity;

pub use contact_laws::{ContactLaws, contact_laws};
pub use drive_length::{DriveLength, SteadyCriteria, transient_cycles};
pub use error::{ReplayOption, SceneError};
pub use figures::scene_figures;
pub use format::*;
pub use particle_shape::{ParticleBody, ShapeKind};
