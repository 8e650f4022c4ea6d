//! Central slices of the bed at eight phases of one steady cycle, coloured
//! by each particle's speed relative to the enclosure, the way the thesis
//! shows its motional phases (Fig. 6.6, 6.14, 6.19–6.21). Relative to the
//! enclosure, a bed riding on its floor is dark and a bed in flight or
//! being struck lights up; in the lab frame the whole bed would share the
//! enclosure's colour. The slice holds the particles the plane through the
//! enclosure's axis cuts, so that the bed's inside shows, not its outer
//! layer. A rigid body of sub-spheres is drawn as its sub-spheres, all in
//! its centre's colour.
//!
//! [`PhaseSnapshots`] is a [`StepObserver`] that keeps the particles at the
//! steps nearest to `(n + k / 8) T`, k = 0..7, of the last whole drive cycle n
//! (phase 0: the enclosure at mid-stroke moving in +z, at its peak speed). It
//! captures every cycle and keeps the last whole one, so it works for a drive
//! whose length is known only at its end (run until steady). The view is
//! the x–z plane (enclosure axis up) for a vertical damper and the z–y plane
//! (axis across, gravity down) for a horizontal one; nearer particles are
//! drawn over farther ones.

#[cfg(feature = "plot")]
use std::path::Path;

use glam::DVec3;

use crate::dem::World;
use crate::dem::clumps::NOT_IN_CLUMP;
use crate::experiment::damper::{Kinematics, StepObserver};
use crate::scene::Orientation;
#[cfg(feature = "plot")]
use crate::signals::{CirclePanel, PanelStrip, SignalsError, plot_panel_strip};

/// Phases per cycle.
pub const PHASES: usize = 8;

/// One captured phase.
#[derive(Debug, Clone, PartialEq)]
pub struct Snapshot {
    /// Degrees of the drive cycle.
    pub phase_deg: f64,
    pub time_s: f64,
    pub enclosure_displacement_m: f64,
    pub enclosure_velocity_mps: f64,
    pub position: Vec<DVec3>,
    pub speed_mps: Vec<f64>,
    pub radius_m: Vec<f64>,
}

/// Captures [`PHASES`] snapshots of the last whole cycle of a drive.
#[derive(Debug, Clone)]
pub struct PhaseSnapshots {
    period_s: f64,
    /// Index of the next phase to capture, counted from the drive start
    /// (cycle `next / PHASES`, phase `next % PHASES`).
    next: u64,
    current: Vec<Snapshot>,
    /// The last whole cycle captured (empty until one is).
    pub snapshots: Vec<Snapshot>,
}

impl PhaseSnapshots {
    /// Snapshots of the last whole cycle of `freq_hz` that starts at or after
    /// `from_s` (from the drive start; earlier cycles are not captured).
    pub fn new(freq_hz: f64, from_s: f64) -> Self {
        let period = 1.0 / freq_hz;
        let first_cycle = (from_s / period - 1e-9).ceil().max(0.0) as u64;
        PhaseSnapshots {
            period_s: period,
            next: first_cycle * PHASES as u64,
            current: Vec::with_capacity(PHASES),
            snapshots: Vec::new(),
        }
    }

    /// Draws the strip into `path` (SVG or PNG by the extension): `title`
    /// above, the enclosure of `radius_m` × `length_m` in each panel, speeds
    /// coloured from 0 to twice `peak_speed_mps` (the enclosure's).
    #[cfg(feature = "plot")]
    #[allow(clippy::too_many_arguments)]
    pub fn plot(
        &self,
        path: &Path,
        title: &str,
        orientation: Orientation,
        radius_m: f64,
        length_m: f64,
        peak_speed_mps: f64,
    ) -> Result<(), SignalsError> {
        let amp = self
            .snapshots
            .iter()
            .map(|s| s.enclosure_displacement_m.abs())
            .fold(0.0, f64::max);
        let (x_range, y_range) = view_ranges(orientation, radius_m, length_m, amp);
        let panels = self
            .snapshots
            .iter()
            .map(|s| phase_panel(s, orientation, radius_m, length_m))
            .collect();
        plot_panel_strip(
            path,
            &PanelStrip {
                title: title.to_string(),
                panels,
                x_range,
                y_range,
                value_label: "rel. speed (m/s)".into(),
                value_range: (0.0, 2.0 * peak_speed_mps),
                footnote: format!(
                    "central slices (mm; the particles the plane through the axis cuts) at 8 phases of the last drive cycle, coloured by speed relative to the enclosure;\nphase 0: enclosure at mid-stroke moving {} at its peak speed {peak_speed_mps:.2} m/s",
                    match orientation {
                        Orientation::Vertical => "up",
                        Orientation::Horizontal => "right",
                    }
                ),
            },
        )
    }
}

/// Millimetres per metre: the plots' unit.
#[cfg(feature = "plot")]
const MM: f64 = 1e3;

/// (across, along-the-view-up, depth) of a point in the side view of a
/// damper of `orientation`: the axis is z; a vertical damper's up is z, a
/// horizontal one's y (gravity −y). The browser lab draws the same view.
pub fn side_view(orientation: Orientation, p: DVec3) -> (f64, f64, f64) {
    match orientation {
        Orientation::Vertical => (p.x, p.z, p.y),
        Orientation::Horizontal => (p.z, p.y, p.x),
    }
}

/// The (x, y) ranges of every panel, mm: the enclosure of `radius_m` ×
/// `length_m` at both ends of its stroke `amp_m`, with a margin.
#[cfg(feature = "plot")]
fn view_ranges(
    orientation: Orientation,
    radius_m: f64,
    length_m: f64,
    amp_m: f64,
) -> ((f64, f64), (f64, f64)) {
    let (mm, amp) = (MM, amp_m);
    let across = (-radius_m * mm * 1.05, radius_m * mm * 1.05);
    let along = (
        (-amp - 0.05 * length_m) * mm,
        (length_m + amp + 0.05 * length_m) * mm,
    );
    match orientation {
        Orientation::Vertical => (across, along),
        Orientation::Horizontal => (along, across),
    }
}

/// One phase's panel: its enclosure outline and its particles, nearer ones
/// drawn over farther ones, coloured by speed.
#[cfg(feature = "plot")]
fn phase_panel(
    s: &Snapshot,
    orientation: Orientation,
    radius_m: f64,
    length_m: f64,
) -> CirclePanel {
    let mm = MM;
    let u = s.enclosure_displacement_m;
    let outline = match orientation {
        Orientation::Vertical => [
            (-radius_m * mm, u * mm),
            (radius_m * mm, (u + length_m) * mm),
        ],
        Orientation::Horizontal => [
            (u * mm, -radius_m * mm),
            ((u + length_m) * mm, radius_m * mm),
        ],
    };
    let depth = |i: usize| side_view(orientation, s.position[i]).2;
    let mut order: Vec<usize> = (0..s.position.len())
        .filter(|&i| in_slice(depth(i), s.radius_m[i]))
        .collect();
    order.sort_by(|&a, &b| depth(b).total_cmp(&depth(a)));
    CirclePanel {
        title: format!(
            "{:.0} deg, v_enc {:+.2} m/s",
            s.phase_deg, s.enclosure_velocity_mps
        ),
        outline,
        circles: order
            .into_iter()
            .map(|i| {
                let (x, y, _) = side_view(orientation, s.position[i]);
                (x * mm, y * mm, s.radius_m[i] * mm, s.speed_mps[i])
            })
            .collect(),
    }
}

/// Whether a sphere of `radius_m` whose centre lies `depth_m` from the
/// plane through the enclosure's axis is cut by it.
pub fn in_slice(depth_m: f64, radius_m: f64) -> bool {
    depth_m.abs() < radius_m
}

impl StepObserver for PhaseSnapshots {
    fn observe(&mut self, t_s: f64, world: &World, enclosure: &Kinematics) {
        let target = self.next as f64 * self.period_s / PHASES as f64;
        let dt = world.dt_s();
        if t_s + 0.5 * dt < target {
            return;
        }
        let k = (self.next % PHASES as u64) as usize;
        self.next += 1;
        if k == 0 {
            self.current.clear();
        }
        let p = world.particles.by_id();
        self.current.push(Snapshot {
            phase_deg: 360.0 * k as f64 / PHASES as f64,
            time_s: t_s,
            enclosure_displacement_m: enclosure.displacement_m,
            enclosure_velocity_mps: enclosure.velocity_mps,
            position: p.position.clone(),
            // Relative to the enclosure, which moves along z. A body's
            // sub-spheres take its centre's speed: one colour a body, so
            // that the strip shows bodies, not their spheres.
            speed_mps: (0..p.len())
                .map(|k| {
                    let v = match p.clump[k] {
                        NOT_IN_CLUMP => p.velocity[k],
                        b => p.clumps.velocity[b as usize],
                    };
                    (v - DVec3::Z * enclosure.velocity_mps).length()
                })
                .collect(),
            radius_m: p.radius.clone(),
        });
        if k == PHASES - 1 && self.current.len() == PHASES {
            std::mem::swap(&mut self.snapshots, &mut self.current);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dem::clumps::ClumpTemplate;
    use crate::dem::{ContactLaw, Material, Numerics, Particles, RestitutionMode, Walls};
    use glam::DQuat;

    /// A world of `p`, free of walls and gravity, and its snapshot at
    /// phase 0 with the enclosure moving at `enclosure_mps`.
    fn captured(p: Particles, enclosure_mps: f64) -> (World, Snapshot) {
        let m = Material::ACRYLIC;
        let law = ContactLaw::new(&m, &m, 0.8, 0.3, RestitutionMode::Exact);
        let world = World::new(
            p,
            Walls::none(),
            law,
            law,
            DVec3::ZERO,
            Numerics::with_dt(1e-6),
        )
        .expect("world");
        let mut snaps = PhaseSnapshots::new(40.0, 0.0);
        let enclosure = Kinematics {
            displacement_m: 0.0,
            velocity_mps: enclosure_mps,
            acceleration_mps2: 0.0,
        };
        snaps.observe(0.0, &world, &enclosure);
        let s = snaps.current.remove(0);
        (world, s)
    }

    /// A spinning body of two spheres and a free sphere, captured at phase
    /// 0: the body's sub-spheres (whose own speeds differ, one on each side
    /// of the spin) are drawn in the speed of its centre, the free sphere in
    /// its own. A capture that kept the sub-spheres' speeds would colour the
    /// body in two colours.
    #[test]
    fn a_body_is_drawn_in_its_centre_speed() {
        let mut p = Particles::default();
        let t = ClumpTemplate {
            offsets_m: vec![DVec3::new(-0.002, 0.0, 0.0), DVec3::new(0.002, 0.0, 0.0)],
            radii_m: vec![0.0015; 2],
            mass_kg: 1e-4,
            inertia_kgm2: DVec3::new(1.0, 3.0, 3.0) * 1e-10,
        };
        let v = DVec3::new(0.0, 0.3, 0.0);
        p.push_clump(
            &t,
            (DVec3::new(0.0, 0.0, 0.01), DQuat::IDENTITY),
            (v, DVec3::Z * 50.0),
        );
        p.push(
            DVec3::new(0.0, 0.0, 0.03),
            DVec3::Y * 0.7,
            DVec3::ZERO,
            0.002,
            1000.0,
        );
        let (world, s) = captured(p, 0.0);
        let sub = |k: usize| world.particles.velocity[k].length();
        assert!((sub(0) - sub(1)).abs() > 0.1, "the sub-spheres move alike");
        assert!(
            (s.speed_mps[0] - v.length()).abs() < 1e-12,
            "{:?}",
            s.speed_mps
        );
        assert!(
            (s.speed_mps[1] - v.length()).abs() < 1e-12,
            "{:?}",
            s.speed_mps
        );
        assert!((s.speed_mps[2] - 0.7).abs() < 1e-12, "{:?}", s.speed_mps);
    }

    /// A sphere moving with the enclosure is still in its frame; one
    /// off the plane through the axis by more than its radius is not in
    /// the slice.
    #[test]
    fn speeds_are_relative_to_the_enclosure_and_the_slice_is_central() {
        let mut p = Particles::default();
        p.push(
            DVec3::new(0.0, 0.0, 0.01),
            DVec3::Z * 0.5,
            DVec3::ZERO,
            0.002,
            1000.0,
        );
        p.push(
            DVec3::new(0.0, 0.0, 0.02),
            DVec3::ZERO,
            DVec3::ZERO,
            0.002,
            1000.0,
        );
        let (_, s) = captured(p, 0.5);
        assert!(s.speed_mps[0].abs() < 1e-12, "{:?}", s.speed_mps);
        assert!((s.speed_mps[1] - 0.5).abs() < 1e-12, "{:?}", s.speed_mps);
        #[cfg(feature = "plot")]
        {
            assert!(in_slice(0.0019, 0.002) && in_slice(-0.0019, 0.002));
            assert!(!in_slice(0.0021, 0.002));
        }
    }
}
