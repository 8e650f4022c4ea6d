//! The damper on a structure (thesis Section 2.3.1, and future work 9.4 i
//! and v): a host of a few modes carrying the enclosure, two-way coupled to
//! the DEM as the rig's electrodynamic shaker is, the forces that drive it,
//! and a model that predicts its response from a sweep's dissipation map.
//!
//! - [`spec`]: host files (`kind = "host"`, `host/*.toml` built in):
//!   modes with frequency, modal mass, damping ratio, shape values;
//! - [`dynamics`]: the modal equations stepped exactly with the forces held
//!   over a step, energies booked apart, and the receptance;
//! - [`excitation`]: sine, swept sine, multi-sine, periodic random, hammer,
//!   release, each a documented key;
//! - [`motion`]: the host as an [`crate::rig::EnclosureMotion`], driven by
//!   a force at its drive point or standing on a shaker's table ([`base`]:
//!   base excitation and the transmissibility);
//! - [`map_model`]: the damper as an amplitude- and frequency-dependent
//!   equivalent dashpot from a sweep (describing function), closed on the
//!   host by harmonic balance.
//!
//! The host sees the damper only as a force on the enclosure: this module
//! imports `rig` (the drive abstraction, the file loader) but not `dem`.
//! SI units throughout.

pub mod base;
pub mod dynamics;
pub mod excitation;
pub mod map_model;
pub mod motion;
pub mod spec;

pub use dynamics::{HostDynamics, HostEnergy, Payload, Point, receptance};
pub use excitation::{Excitation, PeriodicRandom, RandomNoise};
pub use map_model::{DissipationMap, MapPoint};
pub use motion::HostMotion;
pub use spec::{DEFAULT_HOST, HostSpec, ModeSpec};
