//! Experiments: a scene composed into something that runs, one folder or
//! file for each:
//! - `bed/`: a bed filled (`fill`) and settled (`settle`), and kept between
//!   runs (`cache`);
//! - the shake: the damper's drive and its observers (`damper`), the DEM
//!   truth recorder (`record`), the drive through the rig and its
//!   measurement by Yang's method (`shake`, `measurement`), ensembles of
//!   beds driven and judged together (`ensemble`, `ensemble_summary`), and
//!   one shape for a shake whoever asks for it, request, plan and outcome
//!   (`shake_plan`);
//! - `drop/`: the drop test of one sphere, and its series of heights with
//!   the files a lab keeps (`series`);
//! - the rig's phase-error calibration on the empty enclosure
//!   (`calibration_plan`);
//! - the single collision (`impact`);
//! - `press/`: a body pressed onto a plate, and as an experiment with its
//!   files (`outcome`);
//! - the shear box (`shear_box`);
//! - the replay of another code's record (`replay`);
//! - `host_test/`: the damper on a host structure, its free decay (`decay`),
//!   its frequency response (`frf`, written by `frf_outcome`, its figure
//!   drawn again from the files by `frf_figure`) and the bed-to-bed part of
//!   its error (`bed_spread`);
//! - the error of reading a run's saved files back to redraw its figures
//!   (`saved_file`).
//!
//! Each builds only what it needs: a single collision has no enclosure; a
//! drop test has one sphere, a plate and the drop rig.

pub mod bed;
pub mod calibration_plan;
pub mod damper;
pub mod drop;
pub mod ensemble;
pub mod ensemble_summary;
pub mod host_test;
pub mod impact;
pub mod measurement;
pub mod orientation_record;
pub mod press;
pub mod record;
pub mod replay;
pub mod saved_file;
pub mod shake;
pub mod shake_plan;
pub mod shear_box;
