//! Experiments: a scene composed into something that runs. The damper drive and
//! its observers (`damper`), filling and settling a bed (`fill`, `settle`,
//! `bed_cache`), ensembles of beds driven and judged together (`ensemble`),
//! the bed-to-bed part of a host test's error (`bed_spread`), the DEM
//! truth recorder (`record`), the shake through the rig and
//! its measurement by Yang's method (`shake`, `measurement`), one shape
//! for a shake whoever asks for it, request, plan and outcome (`shake_plan`), the drop test
//! (`drop`), the single collision (`impact`), a body pressed onto a plate
//! (`press`, as an experiment with its files `press_outcome`), the replay of another code's
//! record (`replay`) and the damper on a host structure (`host_test`), its free decay
//! (`host_decay`) and its frequency response (`host_frf`). Each builds only what it needs: a single collision has no
//! enclosure; a drop test has one sphere, a plate and the drop rig.

pub mod bed_cache;
pub mod bed_spread;
pub mod damper;
pub mod drop;
pub mod drop_series;
pub mod ensemble;
pub mod ensemble_summary;
pub mod fill;
pub mod host_decay;
pub mod host_frf;
pub mod host_frf_outcome;
pub mod host_test;
pub mod impact;
pub mod measurement;
pub mod press;
pub mod press_outcome;
pub mod record;
pub mod replay;
pub mod settle;
pub mod shake;
pub mod shake_plan;
pub mod shear_box;
