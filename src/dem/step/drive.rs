//! The walls' drive: the enclosure moves along its axis to the displacement
//! prescribed for the end of the step, and the work its walls do on the
//! particles over the step is the trapezoid of their axial force at both
//! ends on the stroke (the input side of the energy balance, eq. 6.4 of
//! Terzioglu's thesis). A wall that moves on its own
//! ([`crate::dem::walls::WallMotion`]) moves too, and its work is the
//! trapezoid of its own force on its own stroke.

use glam::DVec3;

use crate::dem::walls::Walls;

/// One step's stroke of the walls.
#[derive(Debug, Clone, Copy)]
pub struct Stroke {
    /// Displacement over the step (m).
    pub du_m: f64,
    /// Axial force of the walls on the particles before the step (N).
    pub axial_force_before_n: f64,
    /// Work the walls' forces before the step would do on their own strokes
    /// (J): the first half of their trapezoids.
    pub own_work_before_j: f64,
}

impl Stroke {
    /// Work the walls did on the particles over the step (J), given their
    /// force `wall_force` at its end: the trapezoid of the axial force on
    /// the stroke.
    /// `by_wall` is the same force wall by wall, which the walls' own
    /// strokes take.
    pub fn work_in_j(&self, walls: &Walls, wall_force: DVec3, by_wall: &[DVec3]) -> f64 {
        let common = 0.5 * (self.axial_force_before_n + wall_force.dot(walls.axis)) * self.du_m;
        if walls.own.is_empty() {
            return common;
        }
        common + 0.5 * (self.own_work_before_j + own_work_j(walls, by_wall))
    }
}

/// The work the walls' forces `by_wall` do on their own strokes (J).
fn own_work_j(walls: &Walls, by_wall: &[DVec3]) -> f64 {
    walls
        .own
        .iter()
        .zip(by_wall)
        .map(|(own, f)| f.dot(own.stroke_m))
        .sum()
}

/// Moves the walls to `displacement_m` at the end of a step of `dt_s`, at the
/// mean speed that takes them there; `wall_force` is their force on the
/// particles now, before the step, and `by_wall` the same wall by wall.
/// The walls that move on their own go to where they were prescribed to be.
pub fn move_walls(
    walls: &mut Walls,
    displacement_m: f64,
    dt_s: f64,
    wall_force: DVec3,
    by_wall: &[DVec3],
) -> Stroke {
    let du = displacement_m - walls.displacement_m;
    walls.displacement_m = displacement_m;
    walls.velocity_mps = du / dt_s;
    walls.move_own(dt_s);
    Stroke {
        du_m: du,
        axial_force_before_n: wall_force.dot(walls.axis),
        own_work_before_j: own_work_j(walls, by_wall),
    }
}
