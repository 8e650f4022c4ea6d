//! The orientation order of a bed of bodies over a shake: the order
//! parameter `S` of [`crate::dem::orientation_order`] against the
//! cylinder's axis (the drive's axis), as the bed was settled and at the
//! end of every cycle of the drive, for `summary.json` and the console.

use serde::Serialize;

use super::damper::StepObserver;
use crate::dem::World;
use crate::dem::orientation_order::{CYLINDER_AXIS, order_parameter};
use crate::rig::motion::Kinematics;

/// What a shake of bodies says about how they lie.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct OrientationOrder {
    /// `S` of the settled bed, before the drive.
    pub settled: f64,
    /// `S` at the end of each cycle of the drive.
    pub per_cycle: Vec<f64>,
    /// Mean of `per_cycle` over the cycles from `steady_first_cycle` (the
    /// drive's steady window; all cycles when it has none).
    pub steady_mean: f64,
    /// Standard deviation of those cycles' values (zero for one).
    pub steady_sd: f64,
}

impl OrientationOrder {
    /// The order of a bed that was `settled` and then passed through the
    /// values `per_cycle`, its steady window starting at cycle
    /// `steady_first_cycle` (0-based); `None` without a value.
    pub fn new(settled: Option<f64>, per_cycle: Vec<f64>, steady_first_cycle: u32) -> Option<Self> {
        let settled = settled?;
        let window = match per_cycle.get(steady_first_cycle as usize..) {
            Some(w) if !w.is_empty() => w,
            _ => &per_cycle[..],
        };
        let (steady_mean, steady_sd) = if window.is_empty() {
            (settled, 0.0)
        } else {
            let m = crate::stats::mean_std(window);
            (m.mean, m.std)
        };
        Some(OrientationOrder {
            settled,
            per_cycle,
            steady_mean,
            steady_sd,
        })
    }
}

/// Samples `S` at the end of each cycle of a drive at `freq_hz`.
#[derive(Debug, Clone)]
pub struct OrientationTrack {
    period_s: f64,
    /// `S` at the end of each cycle so far.
    pub per_cycle: Vec<f64>,
}

impl OrientationTrack {
    /// A track of a drive at `freq_hz`.
    pub fn new(freq_hz: f64) -> Self {
        OrientationTrack {
            period_s: 1.0 / freq_hz,
            per_cycle: Vec::new(),
        }
    }
}

impl StepObserver for OrientationTrack {
    fn observe(&mut self, t_s: f64, world: &World, _enclosure: &Kinematics) {
        // A cycle ends at the step nearest to its boundary time, as the
        // drive's ledger takes it.
        let next_end = (self.per_cycle.len() + 1) as f64;
        if (t_s / self.period_s - next_end) * self.period_s > -0.5 * world.dt_s()
            && let Some(s) = order_parameter(&world.particles.clumps, CYLINDER_AXIS)
        {
            self.per_cycle.push(s);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The steady figures come from the window's cycles, or from every
    /// cycle when the window starts past them; a window taken from the
    /// start, or from the last cycle alone, fails it.
    #[test]
    fn the_steady_figures_are_the_windows_or_all_cycles() {
        let o = OrientationOrder::new(Some(-0.2), vec![0.1, 0.2, 0.3, 0.5], 2).expect("a value");
        assert!((o.steady_mean - 0.4).abs() < 1e-15, "{o:?}");
        assert!((o.steady_sd - 0.02f64.sqrt()).abs() < 1e-15, "{o:?}");
        let all = OrientationOrder::new(Some(-0.2), vec![0.1, 0.3], 5).expect("a value");
        assert!((all.steady_mean - 0.2).abs() < 1e-15, "{all:?}");
        let none = OrientationOrder::new(Some(-0.2), Vec::new(), 0).expect("a value");
        assert_eq!((none.steady_mean, none.steady_sd), (-0.2, 0.0));
        assert_eq!(OrientationOrder::new(None, vec![0.1], 0), None);
    }
}
