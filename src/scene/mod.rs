//! Scenes: descriptions that compose the engine into an experiment, building only
//! what the experiment needs (a single collision has no enclosure; a damper run
//! has particles, a cylinder and a drive; a drop test has one sphere, a plate and
//! the drop rig).

pub mod accuracy;
pub mod damper;
pub mod drop;
pub mod file;
pub mod fill;
pub mod impact;
pub mod measurement;
pub mod record;
pub mod settle;
pub mod shake;
pub mod validity;
