//! Scenes: descriptions that compose the engine into an experiment, building only
//! what the experiment needs (a single collision has no enclosure; a damper run
//! has particles, a cylinder and a drive; a drop test has one sphere, a plate and
//! the drop rig; a replay has a record from another DEM code and the rig).

pub mod accuracy;
pub mod bed_cache;
pub mod damper;
pub mod drop;
pub mod dump;
pub mod file;
pub mod fill;
pub mod impact;
pub mod lammps;
pub mod measurement;
pub mod phases;
pub mod predict;
pub mod record;
pub mod replay;
pub mod settle;
pub mod shake;
pub mod snapshots;
pub mod sweep;
#[cfg(feature = "plot")]
pub mod sweep_plot;
pub mod validity;
