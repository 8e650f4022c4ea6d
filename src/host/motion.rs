//! The host as the enclosure's drive: [`HostMotion`] is an
//! [`EnclosureMotion`], so the DEM steps a damper on a host exactly as it
//! steps one on the rig's electrodynamic shaker (two-way, explicit: the
//! particles' force over a step moves the host over the next).
//!
//! The DEM's enclosure position is the damper's displacement from where the
//! bed settled (the host's release position for a free decay), and the
//! particles' force on the host is their force on the enclosure less the one
//! of the bed at rest (its weight, which the host carried before the test:
//! displacements are from the loaded rest position).

use super::dynamics::{HostDynamics, HostEnergy, Payload};
use super::excitation::Excitation;
use super::spec::HostSpec;
use crate::rig::{EnclosureMotion, Kinematics};

/// A host carrying the enclosure, driven by an excitation.
#[derive(Debug, Clone)]
pub struct HostMotion {
    dynamics: HostDynamics,
    excitation: Excitation,
    start_m: f64,
    resting_force_n: f64,
    last_excitation_n: f64,
    last_damper_force_n: f64,
    kinematics: Kinematics,
}

impl HostMotion {
    /// `spec` carrying `payload`, driven by `excitation`, the particles'
    /// force on the enclosure at rest being `resting_force_n` (N, along the
    /// axis; 0 without particles). A release starts deflected, the rest at
    /// rest.
    pub fn new(
        spec: &HostSpec,
        payload: Payload,
        excitation: Excitation,
        resting_force_n: f64,
    ) -> Self {
        let mut dynamics = HostDynamics::new(spec, payload);
        let x0 = excitation.initial_displacement_m();
        if x0 != 0.0 {
            dynamics.release_from(spec, x0);
        }
        HostMotion {
            start_m: dynamics.damper_displacement_m(),
            dynamics,
            excitation,
            resting_force_n,
            last_excitation_n: 0.0,
            last_damper_force_n: 0.0,
            kinematics: Kinematics::default(),
        }
    }

    /// Starts a sine at its steady state from `modal_state` (`[q; q']`, e.g.
    /// [`super::dynamics::sine_steady_state`]).
    pub fn start_at(&mut self, modal_state: &[f64]) {
        self.dynamics.set_state(modal_state);
        self.start_m = self.dynamics.damper_displacement_m();
    }

    /// The host's own state and energies.
    pub fn dynamics(&self) -> &HostDynamics {
        &self.dynamics
    }

    /// The excitation force held over the last step, N.
    pub fn excitation_n(&self) -> f64 {
        self.last_excitation_n
    }

    /// The damper's force on the host held over the last step, N.
    pub fn damper_force_n(&self) -> f64 {
        self.last_damper_force_n
    }

    /// The energies booked so far.
    pub fn energy(&self) -> HostEnergy {
        self.dynamics.energy()
    }

    /// Where the damper started, m (the DEM's enclosure position 0).
    pub fn start_m(&self) -> f64 {
        self.start_m
    }
}

impl EnclosureMotion for HostMotion {
    fn advance(&mut self, t_s: f64, dt_s: f64, particle_force_n: f64) -> Kinematics {
        // The force held over the step is the excitation's at mid-step.
        let f_e = self.excitation.force_n(t_s - 0.5 * dt_s);
        let f_d = particle_force_n - self.resting_force_n;
        self.dynamics.advance(dt_s, f_d, f_e);
        self.last_excitation_n = f_e;
        self.last_damper_force_n = f_d;
        self.kinematics = Kinematics {
            displacement_m: self.dynamics.damper_displacement_m() - self.start_m,
            velocity_mps: self.dynamics.damper_velocity_mps(),
            acceleration_mps2: self.dynamics.damper_acceleration_mps2(),
        };
        self.kinematics
    }

    fn kinematics(&self) -> Kinematics {
        self.kinematics
    }
}
