//! Studies: many experiments and what they say together. Sweeps of frequency,
//! Gamma, fill and orientation with their maps (`sweep`, `sweep_plot`) and
//! where each series peaks (`sweep_peak`), a sweep's report and columns
//! (`sweep_report`), a sweep up and back down in Γ with the bed carried
//! (`sweep_updown`), the optimum Γ of several sweeps
//! against what tells them apart (`sweep_optimum`), the
//! motional phases read from DEM truth (`phases`), accuracy against run time
//! (`accuracy`) and the bouncing-bed onset predicted from the scene alone
//! (`predict`, thesis eq. 6.11-6.13); a sweep as the dissipation map a host
//! model closes on (`dissipation_map`), and the host's response predicted
//! from it (`host_prediction`); the shear box over scenes and seeds
//! (`shear_box_series`).

pub mod accuracy;
pub mod dissipation_map;
pub mod host_prediction;
pub mod phases;
pub mod predict;
pub mod shear_box_series;
pub mod sweep;
pub mod sweep_optimum;
pub mod sweep_peak;
#[cfg(feature = "plot")]
pub mod sweep_plot;
pub mod sweep_report;
pub mod sweep_updown;
