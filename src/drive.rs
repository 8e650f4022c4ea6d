//! The drive of a damper: a sine of frequency `f` and acceleration amplitude
//! `Γ g` along the enclosure's axis (thesis eq. 6.2: `u = Γ g / ω² sin ωt`),
//! with the amplitudes it implies and the largest energy a mass `M` riding it
//! can dissipate per cycle (eq. 6.10: `E_max = 4 (Γ g / ω)² M`).
//!
//! A [`Drive`] is checked once, where it is built ([`Drive::new`]); every
//! layer that moves an enclosure (the rig's shaker, the DEM drive, the scene's
//! time-step rule, the measurement) takes it instead of a loose frequency and
//! Γ, and asks it for ω, the amplitudes and `E_max` instead of recomputing
//! them. What a drive needs from a particular scene (a time step that resolves
//! it) is checked where the scene is known (`experiment::shake::shake_drive`).

use std::f64::consts::PI;

use crate::validation::{InvalidParameter, non_negative, positive};

/// A sinusoidal drive: frequency, acceleration amplitude Γ (peak acceleration
/// / g) and the local gravity Γ is counted in.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Drive {
    freq_hz: f64,
    gamma: f64,
    gravity_mps2: f64,
}

impl Drive {
    /// A drive at `freq_hz` of acceleration amplitude `gamma` × `gravity_mps2`;
    /// refuses a frequency or Γ that is not positive and finite, and a gravity
    /// that is negative or not finite (naming the key, its unit and range).
    pub fn new(freq_hz: f64, gamma: f64, gravity_mps2: f64) -> Result<Drive, InvalidParameter> {
        positive("freq_hz", freq_hz, "Hz")?;
        positive("gamma", gamma, "")?;
        non_negative("gravity_mps2", gravity_mps2, "m/s^2")?;
        Ok(Drive {
            freq_hz,
            gamma,
            gravity_mps2,
        })
    }

    /// The same drive at acceleration amplitude `gamma` (validated as in
    /// [`Drive::new`]).
    pub fn with_gamma(&self, gamma: f64) -> Result<Drive, InvalidParameter> {
        Drive::new(self.freq_hz, gamma, self.gravity_mps2)
    }

    /// The same drive at `freq_hz` (validated as in [`Drive::new`]).
    pub fn with_freq_hz(&self, freq_hz: f64) -> Result<Drive, InvalidParameter> {
        Drive::new(freq_hz, self.gamma, self.gravity_mps2)
    }

    /// Drive frequency (Hz).
    pub fn freq_hz(&self) -> f64 {
        self.freq_hz
    }

    /// Acceleration amplitude Γ: peak acceleration / g (dimensionless).
    pub fn gamma(&self) -> f64 {
        self.gamma
    }

    /// Gravity Γ is counted in (m/s²).
    pub fn gravity_mps2(&self) -> f64 {
        self.gravity_mps2
    }

    /// Angular frequency ω = 2π f (rad/s).
    pub fn omega_rad_s(&self) -> f64 {
        2.0 * PI * self.freq_hz
    }

    /// One cycle, 1 / f (s).
    pub fn period_s(&self) -> f64 {
        1.0 / self.freq_hz
    }

    /// Peak acceleration Γ g (m/s²).
    pub fn acceleration_amplitude_mps2(&self) -> f64 {
        self.gamma * self.gravity_mps2
    }

    /// Peak velocity Γ g / ω (m/s).
    pub fn velocity_amplitude_mps(&self) -> f64 {
        self.acceleration_amplitude_mps2() / self.omega_rad_s()
    }

    /// Displacement amplitude Γ g / ω² (m); the stroke peak to peak is twice it.
    pub fn displacement_amplitude_m(&self) -> f64 {
        let w = self.omega_rad_s();
        self.acceleration_amplitude_mps2() / (w * w)
    }

    /// Largest energy a mass `mass_kg` riding the drive can dissipate per
    /// cycle (J), thesis eq. 6.10: `4 (Γ g / ω)² M`.
    pub fn e_max_j(&self, mass_kg: f64) -> f64 {
        let v = self.velocity_amplitude_mps();
        4.0 * v * v * mass_kg
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const G: f64 = 9.81;

    #[test]
    fn the_amplitudes_follow_from_gamma_and_omega() {
        let d = Drive::new(40.0, 20.0, G).expect("valid");
        let w = 2.0 * PI * 40.0;
        assert_eq!(d.omega_rad_s(), w);
        assert_eq!(d.period_s(), 0.025);
        assert_eq!(d.acceleration_amplitude_mps2(), 20.0 * G);
        assert_eq!(d.velocity_amplitude_mps(), 20.0 * G / w);
        assert_eq!(d.displacement_amplitude_m(), 20.0 * G / (w * w));
        // The thesis bed, 358 spheres of 0.0279 kg at 40 Hz, Gamma 20: E_max
        // 0.0680 J (`vlab shake` prints 6.7970e-2 J for the exact mass).
        let v = 20.0 * G / w;
        assert_eq!(d.e_max_j(0.0279), 4.0 * v * v * 0.0279);
        let e_max = d.e_max_j(0.0279);
        assert!((e_max - 0.0680).abs() < 1e-4, "{e_max}");
    }

    #[test]
    fn a_drive_refuses_what_is_not_a_drive_and_names_it() {
        for (f, gamma, g, key) in [
            (0.0, 20.0, G, "freq_hz"),
            (f64::NAN, 20.0, G, "freq_hz"),
            (40.0, -1.0, G, "gamma"),
            (40.0, f64::INFINITY, G, "gamma"),
            (40.0, 20.0, -9.81, "gravity_mps2"),
        ] {
            let e = Drive::new(f, gamma, g).expect_err("refused");
            assert_eq!(e.key, key, "{e}");
        }
        let e = Drive::new(-40.0, 20.0, G).expect_err("refused");
        assert_eq!(
            e.to_string(),
            "freq_hz = -40 Hz: must be positive and finite"
        );
        let d = Drive::new(40.0, 20.0, G).expect("valid");
        assert_eq!(d.with_gamma(10.0).expect("valid").gamma(), 10.0);
        assert!(d.with_freq_hz(0.0).is_err());
    }
}
