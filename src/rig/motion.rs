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

use serde::Serialize;

use super::error::{InvalidParameter, RigError, positive};
use crate::drive::Drive;
use crate::maths;

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
    drive: Drive,
    omega: f64,
    amplitude_m: f64,
    t_s: f64,
}

impl SineMotion {
    /// The sine of `drive`.
    pub fn new(drive: &Drive) -> Self {
        SineMotion {
            drive: *drive,
            omega: drive.omega_rad_s(),
            amplitude_m: drive.displacement_amplitude_m(),
            t_s: 0.0,
        }
    }

    /// The drive this sine follows.
    pub fn drive(&self) -> &Drive {
        &self.drive
    }

    /// Drive frequency, Hz.
    pub fn freq_hz(&self) -> f64 {
        self.drive.freq_hz()
    }

    /// Acceleration amplitude Γ (peak acceleration / g).
    pub fn gamma(&self) -> f64 {
        self.drive.gamma()
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
        let (s, c) = maths::sin_cos(self.omega * t_s);
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

/// A recorded motion, replayed: uniformly sampled enclosure velocity, each
/// sample `v_i` standing for its interval `[t_i - h/2, t_i + h/2]`,
/// `t_i = t_0 + i h` (the record's own time axis), whatever the particles do.
///
/// The motion is the smooth curve whose mean over every interval is its
/// sample: the displacement is the natural cubic spline through the running
/// integral of the samples at the interval edges,
/// `x(t_0 - h/2 + j h) = x_0 + h Σ_{i<j} v_i`, so the velocity is a C¹
/// quadratic spline with
/// `(1/h) ∫ v dt = v_i` over interval `i` and the acceleration is continuous
/// and linear within each interval. Hence a force held over an interval
/// does work `F_i v_i h` on it, exactly the record's own `Σ F v h`, and the
/// acceleration's integral over an interval is the velocity change across
/// it: an impact between two samples keeps its impulse instead of being
/// point-sampled, which would alias it. Outside the record the enclosure
/// moves on at its end velocity.
#[derive(Debug, Clone, PartialEq)]
pub struct RecordedMotion {
    t0_s: f64,
    step_s: f64,
    velocity_mps: Vec<f64>,
    /// Displacement at the interval edges `t_0 - h/2 + j h`, `j = 0..=n`.
    edge_displacement_m: Vec<f64>,
    /// Acceleration (the spline's second derivative) at the edges.
    edge_acceleration_mps2: Vec<f64>,
    t_s: f64,
}

impl RecordedMotion {
    /// A motion from velocity samples (m/s) at `t0_s + i step_s`, with
    /// displacement `displacement0_m` (m) at the first sample's interval
    /// start. At least two samples, all finite.
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
        let h = step_s;
        let n = velocity_mps.len();
        let mut edge_displacement_m = Vec::with_capacity(n + 1);
        let mut x = displacement0_m;
        edge_displacement_m.push(x);
        for v in &velocity_mps {
            x += v * h;
            edge_displacement_m.push(x);
        }
        // Natural cubic spline through the edges: M[0] = M[n] = 0 and
        // M[j-1] + 4 M[j] + M[j+1] = 6 (v[j] - v[j-1]) / h, by Thomas' method.
        let mut m = vec![0.0; n + 1];
        if n >= 2 {
            let rhs: Vec<f64> = (1..n)
                .map(|j| 6.0 * (velocity_mps[j] - velocity_mps[j - 1]) / h)
                .collect();
            let k = rhs.len();
            let mut c = vec![0.0; k];
            let mut d = vec![0.0; k];
            for i in 0..k {
                let denom = 4.0 - if i > 0 { c[i - 1] } else { 0.0 };
                c[i] = 1.0 / denom;
                d[i] = (rhs[i] - if i > 0 { d[i - 1] } else { 0.0 }) / denom;
            }
            for i in (0..k).rev() {
                let next = if i + 1 < k { m[i + 2] } else { 0.0 };
                m[i + 1] = d[i] - c[i] * next;
            }
        }
        Ok(RecordedMotion {
            t0_s,
            step_s,
            velocity_mps,
            edge_displacement_m,
            edge_acceleration_mps2: m,
            t_s: t0_s,
        })
    }

    /// A motion from displacement samples (m): the velocity of each interval
    /// is the central difference `(x_{i+1} - x_{i-1}) / 2h` (one-sided at the
    /// ends), the displacement at the first interval's start `x_0 - v_0 h/2`.
    /// At least three samples.
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
        let x0 = x[0] - 0.5 * v[0] * step_s;
        Self::from_velocity(t0_s, step_s, v, x0)
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
        let h = self.step_s;
        let n = self.velocity_mps.len();
        let first_edge = self.t0_s - 0.5 * h;
        let u = (t_s - first_edge) / h;
        let x = &self.edge_displacement_m;
        let m = &self.edge_acceleration_mps2;
        if u < 0.0 {
            // Before the record: on at the start velocity.
            let v = self.at(first_edge).velocity_mps;
            return Kinematics {
                displacement_m: x[0] + v * (t_s - first_edge),
                velocity_mps: v,
                acceleration_mps2: 0.0,
            };
        }
        let j = u.floor() as usize;
        if j >= n {
            let end = first_edge + n as f64 * h;
            let v = self.velocity_mps[n - 1] + (m[n] - m[n - 1]) * h / 6.0 + m[n] * h / 2.0;
            return Kinematics {
                displacement_m: x[n] + v * (t_s - end),
                velocity_mps: v,
                acceleration_mps2: 0.0,
            };
        }
        let tau = t_s - (first_edge + j as f64 * h);
        let r = h - tau;
        let (m0, m1) = (m[j], m[j + 1]);
        let a = (m0 * r + m1 * tau) / h;
        let v = self.velocity_mps[j] - (m1 - m0) * h / 6.0 - m0 * r * r / (2.0 * h)
            + m1 * tau * tau / (2.0 * h);
        let disp = m0 * r * r * r / (6.0 * h)
            + m1 * tau * tau * tau / (6.0 * h)
            + (x[j] / h - m0 * h / 6.0) * r
            + (x[j + 1] / h - m1 * h / 6.0) * tau;
        Kinematics {
            displacement_m: disp,
            velocity_mps: v,
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
    use std::f64::consts::PI;

    #[test]
    fn sine_is_exact_and_ignores_the_particles() {
        let g = 9.81;
        let mut s = SineMotion::new(&Drive::new(40.0, 20.0, g).expect("valid"));
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
    fn recorded_motion_keeps_interval_means_and_impulse_and_follows_a_sine() {
        // A sine sampled at 40 kHz: velocity, displacement and acceleration
        // agree with the analytic motion.
        let (g, h) = (9.81, 25e-6);
        let sine = SineMotion::new(&Drive::new(40.0, 20.0, g).expect("valid"));
        let v: Vec<f64> = (0..4000)
            .map(|i| sine.at(i as f64 * h).velocity_mps)
            .collect();
        let x0 = sine.at(-0.5 * h).displacement_m;
        let rec = RecordedMotion::from_velocity(0.0, h, v.clone(), x0).expect("valid");
        for t in [0.001_013, 0.05, 0.0724] {
            let (k, s) = (rec.at(t), sine.at(t));
            assert!((k.velocity_mps - s.velocity_mps).abs() < 1e-4 * 0.78, "{t}");
            assert!(
                (k.displacement_m - s.displacement_m).abs() < 1e-5 * 3.1e-3,
                "{t}"
            );
            assert!(
                (k.acceleration_mps2 - s.acceleration_mps2).abs() < 1e-3 * 196.2,
                "{t}"
            );
        }
        // The mean over each interval is the sample (midpoint rule at 1 us
        // on a quadratic: exact to its curvature).
        for i in [1usize, 17, 2000, 3998] {
            let ti = i as f64 * h;
            let mean: f64 = (0..25)
                .map(|k| rec.at(ti - 0.5 * h + (k as f64 + 0.5) * 1e-6).velocity_mps)
                .sum::<f64>()
                / 25.0;
            assert!((mean - v[i]).abs() < 1e-8, "{i}: {mean} vs {}", v[i]);
        }
        // An impact inside one interval: the velocity jumps by 0.1 m/s
        // between two samples; the replay carries all of it as acceleration.
        let mut v = vec![0.0; 40];
        for x in &mut v[20..] {
            *x = 0.1;
        }
        let mut rec = RecordedMotion::from_velocity(1.0, 1e-3, v, 0.0).expect("valid");
        let dt = 1e-5;
        let impulse: f64 = (0..4000)
            .map(|k| {
                rec.advance(0.9995 + (k as f64 + 0.5) * dt, dt, 0.0)
                    .acceleration_mps2
                    * dt
            })
            .sum();
        assert!((impulse - 0.1).abs() < 1e-9, "{impulse}");
        assert_eq!(rec.at(0.5).acceleration_mps2, 0.0);
        assert!((rec.at(2.0).velocity_mps - 0.1).abs() < 1e-12);
        assert!((rec.end_s() - 1.039).abs() < 1e-12);
    }

    #[test]
    fn recorded_motion_from_displacement_or_acceleration() {
        let (g, h) = (9.81, 1e-5);
        let sine = SineMotion::new(&Drive::new(40.0, 20.0, g).expect("valid"));
        let n = 10_000; // 4 periods
        let x: Vec<f64> = (0..n)
            .map(|i| sine.at(i as f64 * h).displacement_m)
            .collect();
        let a: Vec<f64> = (0..n)
            .map(|i| sine.at(i as f64 * h).acceleration_mps2)
            .collect();
        let from_x = RecordedMotion::from_displacement(0.0, h, &x).expect("valid");
        let from_a = RecordedMotion::from_acceleration(0.0, h, &a).expect("valid");
        for t in [0.013, 0.05] {
            let s = sine.at(t);
            assert!(
                (from_x.at(t).velocity_mps - s.velocity_mps).abs() < 1e-4,
                "{t}"
            );
            assert!(
                (from_x.at(t).displacement_m - s.displacement_m).abs() < 1e-8,
                "{t}"
            );
            assert!(
                (from_a.at(t).velocity_mps - s.velocity_mps).abs() < 1e-3,
                "{t}"
            );
        }
        let err = RecordedMotion::from_velocity(0.0, 1e-3, vec![1.0, f64::NAN], 0.0)
            .expect_err("NaN")
            .to_string();
        assert!(err.starts_with("velocity_mps[1] = NaN m/s"), "{err}");
        assert!(RecordedMotion::from_velocity(0.0, 0.0, vec![1.0, 2.0], 0.0).is_err());
        assert!(RecordedMotion::from_displacement(0.0, 1e-3, &[1.0, 2.0]).is_err());
    }
}
