//! The walls' drive: the enclosure moves along its axis to the displacement
//! prescribed for the end of the step, and the work its walls do on the
//! particles over the step is the trapezoid of their axial force at both
//! ends on the stroke (the input side of the energy balance, eq. 6.4 of
//! Terzioglu's thesis).

use glam::DVec3;

use crate::dem::walls::Walls;

/// One step's stroke of the walls.
#[derive(Debug, Clone, Copy)]
pub struct Stroke {
    /// Displacement over the step (m).
    pub du_m: f64,
    /// Axial force of the walls on the particles before the step (N).
    pub axial_force_before_n: f64,
}

impl Stroke {
    /// Work the walls did on the particles over the step (J), given their
    /// force `wall_force` at its end: the trapezoid of the axial force on
    /// the stroke.
    pub fn work_in_j(&self, walls: &Walls, wall_force: DVec3) -> f64 {
        0.5 * (self.axial_force_before_n + wall_force.dot(walls.axis)) * self.du_m
    }
}

/// Moves the walls to `displacement_m` at the end of a step of `dt_s`, at the
/// mean speed that takes them there; `wall_force` is their force on the
/// particles now, before the step.
pub fn move_walls(walls: &mut Walls, displacement_m: f64, dt_s: f64, wall_force: DVec3) -> Stroke {
    let du = displacement_m - walls.displacement_m;
    walls.displacement_m = displacement_m;
    walls.velocity_mps = du / dt_s;
    Stroke {
        du_m: du,
        axial_force_before_n: wall_force.dot(walls.axis),
    }
}
