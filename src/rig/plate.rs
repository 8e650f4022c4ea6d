//! The drop rig's base plate on its force transducer: a mass on a spring and a
//! damper to ground, driven by the sphere's contact force (thesis Section 7.3:
//! "the base plate vibration after the separation with the particle" is one of
//! the two things that limit the method's accuracy).
//!
//! ```text
//! m x'' = -k x - c x' + F,     c = 2 zeta sqrt(k m)
//! F_transducer = -(k x + c x')   (compression positive)
//! ```
//!
//! `x` is the plate's displacement along +z (up) from its static equilibrium
//! under its own weight, `F` the force the sphere exerts on the plate along +z
//! (negative while it pushes the plate down). The transducer carries the spring
//! and damper force; its reading is the force the plate puts on it, positive in
//! compression, so impacts read positive. Because the plate's period (99 us on
//! the built-in rig) is longer than a contact (30-65 us), the transducer mostly
//! records the plate's ring, not the contact force itself.
//!
//! **Integration.** Exact zero-order-hold discretisation, as the electrodynamic
//! shaker ([`super::discretise`]): `z <- Phi z + gamma F` with `F` held over the
//! step. Exact for the linear model at any step and unconditionally stable, so
//! the plate rings correctly whether the scene steps it at 0.3 us during a
//! contact or at 1 ms in free flight (with `F = 0`).

use std::f64::consts::PI;

use glam::{DMat3, DVec3};

use super::discretise::zero_order_hold;
use super::drop_spec::DropRigSpec;
use super::error::{RigError, positive};
use crate::validation::{Bound, in_range};

/// The plate on its mount.
#[derive(Debug, Clone)]
pub struct Plate {
    mass_kg: f64,
    stiffness_n_per_m: f64,
    damping_n_s_per_m: f64,
    a: DMat3,
    /// Displacement along +z, m, and velocity, m/s (third state unused).
    z: DVec3,
    dt_s: f64,
    phi: DMat3,
    gamma: DVec3,
}

impl Plate {
    /// A plate of `mass_kg` on a mount of `stiffness_n_per_m` with damping
    /// ratio `damping_ratio` in [0, 1), at rest.
    pub fn new(mass_kg: f64, stiffness_n_per_m: f64, damping_ratio: f64) -> Result<Self, RigError> {
        positive("plate.mass_kg", mass_kg, "kg")?;
        positive("mount.stiffness_n_per_m", stiffness_n_per_m, "N/m")?;
        in_range(
            "mount.damping_ratio",
            damping_ratio,
            "",
            Bound::Closed(0.0),
            Bound::Open(1.0),
        )?;
        let c = 2.0 * damping_ratio * (stiffness_n_per_m * mass_kg).sqrt();
        let a = DMat3::from_cols_array_2d(&[
            [0.0, 1.0, 0.0],
            [-stiffness_n_per_m / mass_kg, -c / mass_kg, 0.0],
            [0.0, 0.0, 0.0],
        ])
        .transpose();
        Ok(Plate {
            mass_kg,
            stiffness_n_per_m,
            damping_n_s_per_m: c,
            a,
            z: DVec3::ZERO,
            dt_s: 0.0,
            phi: DMat3::ZERO,
            gamma: DVec3::ZERO,
        })
    }

    /// The plate of a drop rig.
    pub fn from_spec(spec: &DropRigSpec) -> Result<Self, RigError> {
        Self::new(
            spec.plate.mass_kg,
            spec.mount.stiffness_n_per_m,
            spec.mount.damping_ratio,
        )
    }

    /// Advances by `dt_s` with the sphere's force `force_n` (along +z) held over
    /// the step; returns the displacement at the end, m.
    #[inline]
    pub fn advance(&mut self, dt_s: f64, force_n: f64) -> f64 {
        if dt_s != self.dt_s {
            let b = DVec3::new(0.0, 1.0 / self.mass_kg, 0.0);
            let (phi, gamma) = zero_order_hold(&self.a, b, dt_s);
            self.phi = phi;
            self.gamma = gamma;
            self.dt_s = dt_s;
        }
        self.z = self.phi * self.z + self.gamma * force_n;
        self.z.x
    }

    /// Displacement along +z from equilibrium, m.
    pub fn displacement_m(&self) -> f64 {
        self.z.x
    }

    /// Velocity along +z, m/s.
    pub fn velocity_mps(&self) -> f64 {
        self.z.y
    }

    /// What the transducer carries: the spring and damper force, positive in
    /// compression, N.
    #[inline]
    pub fn transducer_force_n(&self) -> f64 {
        -(self.stiffness_n_per_m * self.z.x + self.damping_n_s_per_m * self.z.y)
    }

    /// Mass, kg.
    pub fn mass_kg(&self) -> f64 {
        self.mass_kg
    }

    /// Damping coefficient `c = 2 zeta sqrt(k m)`, N s/m.
    pub fn damping_n_s_per_m(&self) -> f64 {
        self.damping_n_s_per_m
    }

    /// Damping ratio, 1.
    pub fn damping_ratio(&self) -> f64 {
        self.damping_n_s_per_m / (2.0 * (self.stiffness_n_per_m * self.mass_kg).sqrt())
    }

    /// Undamped natural frequency `sqrt(k / m) / 2 pi`, Hz.
    pub fn natural_freq_hz(&self) -> f64 {
        (self.stiffness_n_per_m / self.mass_kg).sqrt() / (2.0 * PI)
    }

    /// Damped ring frequency `f_n sqrt(1 - zeta^2)`, Hz.
    pub fn ring_freq_hz(&self) -> f64 {
        let z = self.damping_ratio();
        self.natural_freq_hz() * (1.0 - z * z).sqrt()
    }

    /// Decay time constant of the ring's envelope, `1 / (zeta w_n)`, s
    /// (infinite when undamped).
    pub fn ring_time_constant_s(&self) -> f64 {
        1.0 / (self.damping_ratio() * 2.0 * PI * self.natural_freq_hz())
    }

    /// How long the transducer's first compression pulse lasts when a plate at
    /// rest is hit by a half-sine force of `contact_duration_s` (the shape of a
    /// Hertz contact): from the contact's start to the transducer force's first
    /// return to zero, s. About `t_c / 2 + (pi - phi) / w_d` for a contact much
    /// shorter than the ring period (half a ring period, less the damper's
    /// phase lead `phi ~ 2 zeta`); computed here on the model itself.
    pub fn first_pulse_duration_s(&self, contact_duration_s: f64) -> f64 {
        let mut p = Plate {
            z: DVec3::ZERO,
            dt_s: 0.0,
            ..self.clone()
        };
        let period = 1.0 / self.natural_freq_hz();
        let dt = contact_duration_s.min(period) / 200.0;
        let limit = contact_duration_s + 10.0 * period;
        let mut t = 0.0;
        let mut started = false;
        while t < limit {
            let mid = t + 0.5 * dt;
            let f = if mid < contact_duration_s {
                -(PI * mid / contact_duration_s).sin()
            } else {
                0.0
            };
            p.advance(dt, f);
            t += dt;
            let ft = p.transducer_force_n();
            if ft > 0.0 {
                started = true;
            } else if started && t > 0.5 * contact_duration_s {
                return t;
            }
        }
        limit
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rig::{DROP_RIG, RigFile};

    fn rig_plate() -> Plate {
        Plate::from_spec(&DropRigSpec::builtin(DROP_RIG).expect("built in")).expect("valid")
    }

    #[test]
    fn free_ring_matches_the_closed_form_at_any_step() {
        // Released from x0 = 1 um at rest: x = x0 e^{-zeta w t} (cos wd t + zeta w / wd sin wd t).
        let p0 = rig_plate();
        let (wn, z) = (2.0 * PI * p0.natural_freq_hz(), p0.damping_ratio());
        let wd = wn * (1.0 - z * z).sqrt();
        let x0 = 1e-6;
        for (dt, steps) in [(0.3e-6, 1000u32), (1e-3 / 3.0, 1)] {
            let mut p = p0.clone();
            p.z = DVec3::new(x0, 0.0, 0.0);
            for _ in 0..steps {
                p.advance(dt, 0.0);
            }
            let t = dt * f64::from(steps);
            let want = x0 * (-z * wn * t).exp() * ((wd * t).cos() + z * wn / wd * (wd * t).sin());
            // Exact discretisation: rounding only, ~4e-14 of x0 per step.
            assert!(
                (p.displacement_m() - want).abs() < 1e-9 * x0,
                "dt {dt}: {} vs {want}",
                p.displacement_m()
            );
        }
        assert!((p0.ring_time_constant_s() - 0.395e-3).abs() < 0.001e-3);
    }

    #[test]
    fn impulse_rings_at_j_w_and_static_load_reads_its_weight() {
        // Undamped: a short impulse J rings the transducer with amplitude
        // J w_n, less cos(w_n w / 2) - 1 = 5e-4 for a 1 us pulse at 10 kHz.
        let rig = DropRigSpec::builtin(DROP_RIG).expect("built in");
        let mut p = Plate::new(rig.plate.mass_kg, rig.mount.stiffness_n_per_m, 0.0).expect("valid");
        let (j, width) = (1e-4, 1e-6);
        let steps = 10;
        for _ in 0..steps {
            p.advance(width / steps as f64, -j / width);
        }
        let mut peak = 0.0f64;
        for _ in 0..4000 {
            p.advance(0.05e-6, 0.0);
            peak = peak.max(p.transducer_force_n());
        }
        let wn = 2.0 * PI * p.natural_freq_hz();
        assert!((peak / (j * wn) - 1.0).abs() < 1e-3, "{peak} vs {}", j * wn);
        // A constant 1 N downward settles to a reading of +1 N (compression).
        let mut p = rig_plate();
        for _ in 0..200 {
            p.advance(1e-4, -1.0);
        }
        assert!((p.transducer_force_n() - 1.0).abs() < 1e-9);
    }

    #[test]
    fn first_pulse_of_a_short_contact_is_half_a_ring_period_longer() {
        let p = rig_plate();
        let z = p.damping_ratio();
        let wd = 2.0 * PI * p.ring_freq_hz();
        // After a short blow the reading is e^{-zeta w t} (k sin wd t + c d/dt sin wd t)
        // up to a factor: zero at (pi - phi) / wd, the damper leading by phi.
        let phi = (2.0 * z * (1.0 - z * z).sqrt() / (1.0 - 2.0 * z * z)).atan();
        let tc = 2e-6;
        let want = 0.5 * tc + (PI - phi) / wd;
        let d = p.first_pulse_duration_s(tc);
        assert!(((d - want) / want).abs() < 0.01, "{d} vs {want}");
        // A 35 us contact: longer still, and shorter than contact + half period.
        let d35 = p.first_pulse_duration_s(35e-6);
        assert!(d35 > d && d35 < 35e-6 + PI / wd, "{d35}");
    }
}
