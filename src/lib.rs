//! # vlab — a virtual granular-damper laboratory
//!
//! vlab replays the granular-damper test rig of Furkan Terzioglu's PhD thesis,
//! "Vibrational energy dissipation mechanisms in granular dampers" (Department of
//! Mechanical Engineering, The University of Sheffield, 2023; Chapters 3, 5, 6.2
//! and 7), as a signal-level simulator: a discrete-element model of spheres in a
//! vibrated cylinder, inside a model of the shaker rig, emitting the records a lab
//! would; the lab's own post-processing then recovers the physics from them.
//!
//! Units are SI throughout (m, kg, s, N, J, Pa, rad); names carry the unit where it
//! could be ambiguous (`freq_hz`, `dt_s`, `mass_kg`).
//!
//! Module boundaries (imports that must never exist):
//! - `signals` imports neither `rig` nor `dem`: it works on real lab files alone;
//! - `rig` does not import `dem`: it sees the damper only as a force;
//! - `dem` knows nothing of rigs, sensors or files;
//! - `host` (a structure carrying the damper) imports `rig` but not `dem`;
//! - `shape` (multi-sphere grain geometry, thesis Chapter 4 and 8.2) is pure
//!   geometry and imports no other vlab module.

pub mod atomic_write;
pub mod clock;
pub mod dem;
pub mod drive;
pub mod experiment;
pub mod export;
pub mod host;
pub mod maths;
pub mod rig;
pub mod scene;
pub mod shape;
pub mod signals;
pub mod stats;
pub mod study;
pub mod validation;
pub mod warning;
