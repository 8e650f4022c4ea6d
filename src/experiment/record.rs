//! Sampling the DEM truth at a lab's sample rate.
//!
//! A contact lasts 30–60 µs and a 40 kHz sample 25 µs, so a bare point sample
//! of the impulsive particle force would alias. Each sample `k` at `t_k = k T_s`
//! therefore carries the mean of the force over the DEM steps nearest to `t_k`,
//! a window centred on `t_k` (a boxcar with no phase lag, a first zero at the
//! sample rate), and the enclosure kinematics and the bed's centre of mass at
//! the step nearest to `t_k`.

use crate::dem::World;
use crate::experiment::damper::{Kinematics, StepObserver};

/// Columns of a truth record, one entry per sample.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct TruthSamples {
    pub time_s: Vec<f64>,
    pub displacement_m: Vec<f64>,
    pub velocity_mps: Vec<f64>,
    pub acceleration_mps2: Vec<f64>,
    /// Force of the particles on the enclosure along its axis (N).
    pub force_axial_n: Vec<f64>,
    /// Transverse components (N), x and y of the simulation frame.
    pub force_x_n: Vec<f64>,
    pub force_y_n: Vec<f64>,
    /// The bed's centre of mass along the enclosure's axis, from the
    /// enclosure's floor (m): it rises in flight and turns at an impact.
    pub bed_centre_rel_m: Vec<f64>,
}

impl TruthSamples {
    /// Number of samples.
    pub fn len(&self) -> usize {
        self.time_s.len()
    }

    /// True when nothing was recorded.
    pub fn is_empty(&self) -> bool {
        self.time_s.is_empty()
    }

    /// The bed's apparent mass at `freq_hz` from `from_s` on (kg): the
    /// particles' force on the enclosure in phase with its acceleration,
    /// `−Re(F̂ / Â)` of the two fundamentals over whole periods
    /// ([`crate::signals::structural::sine_component`]). A bed locked to
    /// the floor gives its mass; one in flight less. NaN for a record shorter
    /// than a period.
    pub fn apparent_mass_kg(&self, from_s: f64, freq_hz: f64) -> f64 {
        use crate::signals::structural::sine_component;
        let first = self.time_s.partition_point(|t| *t < from_s - 1e-9);
        if self.time_s.len() < first + 2 {
            return f64::NAN;
        }
        let rate = 1.0 / (self.time_s[first + 1] - self.time_s[first]);
        match (
            sine_component(&self.force_axial_n[first..], rate, freq_hz),
            sine_component(&self.acceleration_mps2[first..], rate, freq_hz),
        ) {
            (Ok(f), Ok(a)) if a.norm() > 0.0 => -(f / a).re,
            _ => f64::NAN,
        }
    }
}

/// Records [`TruthSamples`] at a fixed sample rate from the start of the drive.
#[derive(Debug, Clone)]
pub struct TruthRecorder {
    sample_interval_s: f64,
    start_s: f64,
    current: i64,
    force_sum: [f64; 3],
    count: u32,
    kinematics: Option<Kinematics>,
    /// The bed's centre of mass along the axis at the same step (m).
    bed_centre_m: f64,
    best_offset: f64,
    pub samples: TruthSamples,
}

impl TruthRecorder {
    /// Records at `sample_rate_hz`, keeping only samples at or after `start_s`.
    pub fn new(sample_rate_hz: f64, start_s: f64) -> Self {
        TruthRecorder {
            sample_interval_s: 1.0 / sample_rate_hz,
            start_s,
            current: 0,
            force_sum: [0.0; 3],
            count: 0,
            kinematics: None,
            bed_centre_m: 0.0,
            best_offset: f64::INFINITY,
            samples: TruthSamples::default(),
        }
    }

    fn flush(&mut self) {
        let t = self.current as f64 * self.sample_interval_s;
        if let (Some(kin), true) = (self.kinematics, self.count > 0) {
            if self.current >= 1 && t >= self.start_s - 1e-12 {
                let n = self.count as f64;
                let s = &mut self.samples;
                s.time_s.push(t);
                s.displacement_m.push(kin.displacement_m);
                s.velocity_mps.push(kin.velocity_mps);
                s.acceleration_mps2.push(kin.acceleration_mps2);
                s.force_axial_n.push(self.force_sum[2] / n);
                s.force_x_n.push(self.force_sum[0] / n);
                s.force_y_n.push(self.force_sum[1] / n);
                s.bed_centre_rel_m
                    .push(self.bed_centre_m - kin.displacement_m);
            }
        }
        self.force_sum = [0.0; 3];
        self.count = 0;
        self.kinematics = None;
        self.best_offset = f64::INFINITY;
    }

    /// The samples recorded so far (complete windows only).
    pub fn into_samples(self) -> TruthSamples {
        self.samples
    }
}

impl StepObserver for TruthRecorder {
    fn observe(&mut self, t_s: f64, world: &World, enclosure: &Kinematics) {
        let k = (t_s / self.sample_interval_s).round() as i64;
        if k != self.current {
            self.flush();
            self.current = k;
        }
        // The particles push the enclosure with the opposite of the wall force.
        let f = -world.wall_force();
        self.force_sum[0] += f.x;
        self.force_sum[1] += f.y;
        self.force_sum[2] += f.z;
        self.count += 1;
        let offset = (t_s - k as f64 * self.sample_interval_s).abs();
        if offset < self.best_offset {
            self.best_offset = offset;
            self.kinematics = Some(*enclosure);
            // Only at the step nearest the sample: the one within half a
            // step of it (the sum over the bed costs as much as a step's
            // integration).
            if offset <= 0.5 * world.dt_s() {
                self.bed_centre_m = bed_centre_m(world);
            }
        }
    }
}

/// The bed's centre of mass along the enclosure's axis, z (m): free spheres
/// and bodies, each once.
fn bed_centre_m(world: &World) -> f64 {
    let (m, mz) = world
        .particles
        .movers()
        .fold((0.0, 0.0), |(m, mz), (mass, x, _)| {
            (m + mass, mz + mass * x.z)
        });
    if m > 0.0 { mz / m } else { 0.0 }
}
