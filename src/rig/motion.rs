//! Where the enclosure is and how it moves: the one abstraction every drive
//! answers, whether it is a prescribed sine or a shaker the particles disturb.
//!
//! A drive is stepped with the DEM: [`EnclosureMotion::advance`] moves it to
//! the end of a step, given the axial force the particles exerted on the
//! enclosure during the step, and returns the enclosure's [`Kinematics`] there.
//! [`SineMotion`] is the prescribed motion of thesis eq. 6.2 / 7.6,
//! `u = Γ g / ω² sin ωt`; [`super::Shaker`] is the rig's drive (prescribed, or
//! the electrodynamic shaker of Section 7.6).

use std::f64::consts::PI;

use serde::Serialize;

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
}
