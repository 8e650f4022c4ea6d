//! Errors of the DEM engine: invalid set-ups and runs that went unstable.

use thiserror::Error;

/// What can go wrong inside the engine. Instabilities stop the run with a
/// diagnosis instead of letting NaNs reach an output file.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum DemError {
    #[error(
        "numerical instability at t = {time_s:.6} s (step {step}): particle {particle} has a non-finite position; reduce the time step (now {dt_s:.3e} s)"
    )]
    NonFinite {
        time_s: f64,
        step: u64,
        particle: usize,
        dt_s: f64,
    },
    #[error(
        "numerical instability at t = {time_s:.6} s (step {step}): particle {particle} passed through the {wall}; the time step {dt_s:.3e} s is too large for these impact speeds"
    )]
    Escaped {
        time_s: f64,
        step: u64,
        particle: usize,
        wall: String,
        dt_s: f64,
    },
    #[error(
        "numerical instability at t = {time_s:.6} s (step {step}): a {contact} collision at {speed_mps:.2} m/s lasts {duration_s:.2e} s (Hertz, thesis eq. 5.10), only {steps:.2} time steps of {dt_s:.3e} s; use a time step of at most {suggested_dt_s:.2e} s"
    )]
    UnresolvedCollision {
        time_s: f64,
        step: u64,
        contact: String,
        speed_mps: f64,
        duration_s: f64,
        steps: f64,
        dt_s: f64,
        suggested_dt_s: f64,
    },
    #[error(
        "numerical instability at t = {time_s:.6} s (step {step}): the energy books are off by {residual_j:.3e} J, {percent:.1} % of the energy in play; the time step {dt_s:.3e} s is too large"
    )]
    EnergyNotConserved {
        time_s: f64,
        step: u64,
        residual_j: f64,
        percent: f64,
        dt_s: f64,
    },
    #[error(
        "numerical instability at t = {time_s:.6} s (step {step}): overlap of {overlap_percent:.1} % of the radius in a {contact} contact (limit {limit_percent:.0} %), approach speed {speed_mps:.2} m/s; the collision is too fast for the time step {dt_s:.3e} s or for the small-strain Hertz model"
    )]
    ExcessiveOverlap {
        time_s: f64,
        step: u64,
        contact: String,
        overlap_percent: f64,
        limit_percent: f64,
        speed_mps: f64,
        dt_s: f64,
    },
}
