//! Where the enclosure is and how it moves: the one abstraction every drive
//! answers, whether it is a prescribed sine or a shaker the particles disturb.
//!
//! A drive is stepped with the DEM: [`EnclosureMotion::advance`] moves it to
//! the end of a step, given the axial force the particles exerted on the
//! enclosure during the step, and returns the enclosure's [`Kinematics`] there.
//! [`SineMotion`] is the prescribed motion of thesis eq. 6.2 / 7.6,
//! `u = Γ g / ω² sin ωt`; [`RecordedMotion`] is a motion someone else
//! recorded (another DEM code's enclosure), replayed; [`super::Shaker`] is the
//! rig's drive (prescribed, or the electrodynamic shaker of Section 7.6).

use std::f64::consts::PI;

use serde::Serialize;

use super::error::{InvalidParameter, RigError, positive};

/// Enclosure kinematics along the drive axis.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize)]
pub struct Kinematics {
    /// Displacement from the rest position, m.
    pub displacement_m: f64,
    /// Velocity, m/s.
    pub velocity_mps: f64,
    /// Acceleration, m/s^2.
    pub acceleration_mps2: f64,
}

/// Motion of the enclosure along its axis.
pub trait EnclosureMotion {
    /// Advances the enclosure to time `t_s` (the end of a step of `dt_s`, time
    /// from the drive start), given the axial force the particles exerted on
    /// it during the step (N, positive along the axis), and returns its
    /// kinematics at `t_s`.
    fn advance(&mut self, t_s: f64, dt_s: f64, particle_force_n: f64) -> Kinematics;
    /// Kinematics at the last time passed to `advance` (at t = 0 before).
    fn kinematics(&self) -> Kinematics;
}

/// The prescribed sine of thesis eq. 6.2 / 7.6: `u = Γ g / ω² sin ωt`,
/// `u' = Γ g / ω cos ωt`, `u'' = -Γ g sin ωt`, whatever the particles do.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SineMotion {
    freq_hz: f64,
    gamma: f64,
    omega: f64,
    amplitude_m: f64,
    t_s: f64,
}

impl SineMotion {
    /// A sine of acceleration amplitude `gamma` g (`g_mps2`) at `freq_hz`.
    pub fn new(freq_hz: f64, gamma: f64, g_mps2: f64) -> Self {
        let omega = 2.0 * PI * freq_hz;
        SineMotion {
            freq_hz,
            gamma,
            omega,
            amplitude_m: gamma * g_mps2 / (omega * omega),
            t_s: 0.0,
        }
    }

    /// Drive frequency, Hz.
    pub fn freq_hz(&self) -> f64 {
        self.freq_hz
    }

    /// Acceleration amplitude Γ (peak acceleration / g).
    pub fn gamma(&self) -> f64 {
        self.gamma
    }

    /// Angular frequency ω, rad/s.
    pub fn omega(&self) -> f64 {
        self.omega
    }

    /// Displacement amplitude `Γ g / ω²`, m.
    pub fn amplitude_m(&self) -> f64 {
        self.amplitude_m
    }

    /// Velocity amplitude `Γ g / ω`, m/s.
    pub fn velocity_amplitude_mps(&self) -> f64 {
        self.amplitude_m * self.omega
    }

    /// Kinematics at `t_s`.
    pub fn at(&self, t_s: f64) -> Kinematics {
        let (s, c) = (self.omega * t_s).sin_cos();
        let x = self.amplitude_m;
        Kinematics {
            displacement_m: x * s,
            velocity_mps: x * self.omega * c,
            acceleration_mps2: -x * self.omega * self.omega * s,
        }
    }

    /// Time of the last [`EnclosureMotion::advance`], s.
    pub fn time_s(&self) -> f64 {
        self.t_s
    }
}

impl EnclosureMotion for SineMotion {
    fn advance(&mut self, t_s: f64, _dt_s: f64, _particle_force_n: f64) -> Kinematics {
        self.t_s = t_s;
        self.at(t_s)
    }

    fn kinematics(&self) -> Kinematics {
        self.at(self.t_s)
    }
}

/// A recorded motion, replayed: uniformly sampled enclosure velocity
/// `v_i` at `t_i = t_0 + i h` (the record's own time axis), whatever the
/// particles do.
///
/// Between samples the velocity is linear, so the acceleration is constant
/// over each sample interval, `(v_{i+1} - v_i) / h`: the mean of the true
/// acceleration over the interval, whatever happened inside it. A sharp
/// impact in the motion therefore keeps its impulse (`∫ a dt = Δv` exactly)
/// instead of being point-sampled, which would alias it. The displacement is
/// the integral of that velocity from the first sample's displacement. Before
/// the first sample and after the last the enclosure moves on at the end
/// velocity with no acceleration (a caller replays within the record).
#[derive(Debug, Clone, PartialEq)]
pub struct RecordedMotion {
    t0_s: f64,
    step_s: f64,
    velocity_mps: Vec<f64>,
    /// Displacement at each sample: the start value plus the integral of the
    /// piecewise-linear velocity.
    displacement_m: Vec<f64>,
    t_s: f64,
}

impl RecordedMotion {
    /// A motion from velocity samples (m/s) at `t0_s + i step_s`, starting
    /// from `displacement0_m` (m). At least two samples, all finite.
    pub fn from_velocity(
        t0_s: f64,
        step_s: f64,
        velocity_mps: Vec<f64>,
        displacement0_m: f64,
    ) -> Result<Self, RigError> {
        super::error::finite("t0_s", t0_s, "s")?;
        positive("step_s", step_s, "s")?;
        super::error::finite("displacement0_m", displacement0_m, "m")?;
        if velocity_mps.len() < 2 {
            return Err(InvalidParameter::new(
                "velocity_mps",
                format!("{} samples", velocity_mps.len()),
                "",
                "at least 2 samples",
            )
            .into());
        }
        if let Some(i) = velocity_mps.iter().position(|v| !v.is_finite()) {
            return Err(InvalidParameter::new(
                format!("velocity_mps[{i}]"),
                velocity_mps[i],
                "m/s",
                "finite",
            )
            .into());
        }
        let mut displacement_m = Vec::with_capacity(velocity_mps.len());
        let mut x = displacement0_m;
        displacement_m.push(x);
        for w in velocity_mps.windows(2) {
            x += 0.5 * (w[0] + w[1]) * step_s;
            displacement_m.push(x);
        }
        Ok(RecordedMotion {
            t0_s,
            step_s,
            velocity_mps,
            displacement_m,
            t_s: t0_s,
        })
    }

    /// A motion from displacement samples (m): the velocity at each sample is
    /// the central difference `(x_{i+1} - x_{i-1}) / 2h` (one-sided at the
    /// ends). At least three samples.
    pub fn from_displacement(
        t0_s: f64,
        step_s: f64,
        displacement_m: &[f64],
    ) -> Result<Self, RigError> {
        positive("step_s", step_s, "s")?;
        let n = displacement_m.len();
        if n < 3 {
            return Err(InvalidParameter::new(
                "displacement_m",
                format!("{n} samples"),
                "",
                "at least 3 samples",
            )
            .into());
        }
        let x = displacement_m;
        let v: Vec<f64> = (0..n)
            .map(|i| match i {
                0 => (x[1] - x[0]) / step_s,
                i if i == n - 1 => (x[n - 1] - x[n - 2]) / step_s,
                i => (x[i + 1] - x[i - 1]) / (2.0 * step_s),
            })
            .collect();
        Self::from_velocity(t0_s, step_s, v, x[0])
    }

    /// A motion from acceleration samples (m/s^2): the velocity is their
    /// trapezoidal integral less its mean over the record (an oscillating
    /// enclosure does not drift), the displacement starts at zero.
    pub fn from_acceleration(
        t0_s: f64,
        step_s: f64,
        acceleration_mps2: &[f64],
    ) -> Result<Self, RigError> {
        positive("step_s", step_s, "s")?;
        let mut v = Vec::with_capacity(acceleration_mps2.len());
        let mut u = 0.0;
        for (i, a) in acceleration_mps2.iter().enumerate() {
            if i > 0 {
                u += 0.5 * (acceleration_mps2[i - 1] + a) * step_s;
            }
            v.push(u);
        }
        let mean = v.iter().sum::<f64>() / v.len().max(1) as f64;
        v.iter_mut().for_each(|x| *x -= mean);
        Self::from_velocity(t0_s, step_s, v, 0.0)
    }

    /// Time of the first sample, s.
    pub fn start_s(&self) -> f64 {
        self.t0_s
    }

    /// Time of the last sample, s.
    pub fn end_s(&self) -> f64 {
        self.t0_s + (self.velocity_mps.len() - 1) as f64 * self.step_s
    }

    /// The record's sample interval, s.
    pub fn step_s(&self) -> f64 {
        self.step_s
    }

    /// The velocity samples, m/s.
    pub fn velocity_samples_mps(&self) -> &[f64] {
        &self.velocity_mps
    }

    /// Kinematics at `t_s` (see the type's docs).
    pub fn at(&self, t_s: f64) -> Kinematics {
        let n = self.velocity_mps.len();
        let u = (t_s - self.t0_s) / self.step_s;
        if u < 0.0 {
            let v = self.velocity_mps[0];
            return Kinematics {
                displacement_m: self.displacement_m[0] + v * (t_s - self.t0_s),
                velocity_mps: v,
                acceleration_mps2: 0.0,
            };
        }
        let i = u.floor() as usize;
        if i >= n - 1 {
            let v = self.velocity_mps[n - 1];
            return Kinematics {
                displacement_m: self.displacement_m[n - 1] + v * (t_s - self.end_s()),
                velocity_mps: v,
                acceleration_mps2: 0.0,
            };
        }
        let tau = t_s - (self.t0_s + i as f64 * self.step_s);
        let v0 = self.velocity_mps[i];
        let a = (self.velocity_mps[i + 1] - v0) / self.step_s;
        Kinematics {
            displacement_m: self.displacement_m[i] + v0 * tau + 0.5 * a * tau * tau,
            velocity_mps: v0 + a * tau,
            acceleration_mps2: a,
        }
    }
}

impl EnclosureMotion for RecordedMotion {
    fn advance(&mut self, t_s: f64, _dt_s: f64, _particle_force_n: f64) -> Kinematics {
        self.t_s = t_s;
        self.at(t_s)
    }

    fn kinematics(&self) -> Kinematics {
        self.at(self.t_s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sine_is_exact_and_ignores_the_particles() {
        let g = 9.81;
        let mut s = SineMotion::new(40.0, 20.0, g);
        let w = 2.0 * PI * 40.0;
        let x = 20.0 * g / (w * w);
        assert_eq!(s.kinematics().velocity_mps, x * w);
        for n in [1u32, 17, 25_000, 123_457] {
            let t = f64::from(n) * 1e-6;
            let k = s.advance(t, 1e-6, 1e3);
            assert!((k.displacement_m - x * (w * t).sin()).abs() < 1e-12);
            assert!((k.velocity_mps - x * w * (w * t).cos()).abs() < 1e-12);
            assert!((k.acceleration_mps2 + 20.0 * g * (w * t).sin()).abs() < 1e-12);
            assert_eq!(s.kinematics(), k);
        }
        assert!((s.velocity_amplitude_mps() - 20.0 * g / w).abs() < 1e-15);
    }

    #[test]
    fn recorded_motion_keeps_impulse_and_follows_a_sine() {
        // A sine sampled at 40 kHz: velocity, displacement and the mean
        // acceleration over each interval agree with the analytic motion.
        let (g, h) = (9.81, 25e-6);
        let sine = SineMotion::new(40.0, 20.0, g);
        let v: Vec<f64> = (0..4000)
            .map(|i| sine.at(i as f64 * h).velocity_mps)
            .collect();
        let rec = RecordedMotion::from_velocity(0.0, h, v, 0.0).expect("valid");
        let w = sine.omega();
        for t in [0.001_013, 0.05, 0.0724] {
            let (k, s) = (rec.at(t), sine.at(t));
            assert!((k.velocity_mps - s.velocity_mps).abs() < 1e-4 * 0.78, "{t}");
            assert!((k.displacement_m - s.displacement_m).abs() < 1e-5 * 3.1e-3, "{t}");
            let i = (t / h).floor();
            let mean_a = (sine.at((i + 1.0) * h).velocity_mps - sine.at(i * h).velocity_mps) / h;
            assert!((k.acceleration_mps2 - mean_a).abs() < 1e-9 * 196.2, "{t}");
            assert!((k.acceleration_mps2 - s.acceleration_mps2).abs() < 0.02 * w * 0.78);
        }
        // An impact inside one interval: the velocity jumps by 0.1 m/s
        // between two samples; the replay carries all of it in that interval.
        let mut v = vec![0.0; 10];
        for x in &mut v[5..] {
            *x = 0.1;
        }
        let mut rec = RecordedMotion::from_velocity(1.0, 1e-3, v, 0.0).expect("valid");
        let dt = 1e-5;
        let impulse: f64 = (0..1000)
            .map(|k| rec.advance(1.0 + (k as f64 + 0.5) * dt, dt, 0.0).acceleration_mps2 * dt)
            .sum();
        assert!((impulse - 0.1).abs() < 1e-12, "{impulse}");
        assert_eq!(rec.at(0.5).acceleration_mps2, 0.0);
        assert_eq!(rec.at(2.0).velocity_mps, 0.1);
        assert!((rec.end_s() - 1.009).abs() < 1e-12);
    }

    #[test]
    fn recorded_motion_from_displacement_or_acceleration() {
        let (g, h) = (9.81, 1e-5);
        let sine = SineMotion::new(40.0, 20.0, g);
        let n = 10_000; // 4 periods
        let x: Vec<f64> = (0..n).map(|i| sine.at(i as f64 * h).displacement_m).collect();
        let a: Vec<f64> = (0..n)
            .map(|i| sine.at(i as f64 * h).acceleration_mps2)
            .collect();
        let from_x = RecordedMotion::from_displacement(0.0, h, &x).expect("valid");
        let from_a = RecordedMotion::from_acceleration(0.0, h, &a).expect("valid");
        for t in [0.013, 0.05] {
            let s = sine.at(t).velocity_mps;
            assert!((from_x.at(t).velocity_mps - s).abs() < 1e-4, "{t}");
            assert!((from_a.at(t).velocity_mps - s).abs() < 1e-3, "{t}");
        }
        let err = RecordedMotion::from_velocity(0.0, 1e-3, vec![1.0, f64::NAN], 0.0)
            .expect_err("NaN")
            .to_string();
        assert!(err.starts_with("velocity_mps[1] = NaN m/s"), "{err}");
        assert!(RecordedMotion::from_velocity(0.0, 0.0, vec![1.0, 2.0], 0.0).is_err());
        assert!(RecordedMotion::from_displacement(0.0, 1e-3, &[1.0, 2.0]).is_err());
    }
}
