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
//!
//! On a shaker's table ([`HostMotion::on_base`], [`super::base`]) the
//! excitation is the table's acceleration (m/s²), the host's modal state is
//! its deflection from the table, and the enclosure moves with the table
//! plus that deflection.

use super::base::{Table, base_mass_kg};
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
    /// The excitation at the last step's end (what a transducer reads then).
    end_excitation_n: f64,
    last_damper_force_n: f64,
    kinematics: Kinematics,
    /// On a table: the table, the mass it shakes (kg) and the damper
    /// force's work on the table's motion, `Σ F_d Δy` (J).
    base: Option<OnBase>,
}

#[derive(Debug, Clone, Copy)]
struct OnBase {
    table: Table,
    mass_kg: f64,
    damper_work_on_table_j: f64,
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
            end_excitation_n: 0.0,
            last_damper_force_n: 0.0,
            kinematics: Kinematics::default(),
            base: None,
        }
    }

    /// `spec` carrying `payload` on a shaker's table whose acceleration
    /// (m/s²) `excitation` gives, from rest in the table's frame; a sine's
    /// (a stepped sine's first) table starts at the velocity that makes it
    /// swing about its start ([`Table::for_sine`]). `spec` must pass
    /// [`super::base::check_on_base`].
    pub fn on_base(
        spec: &HostSpec,
        payload: Payload,
        excitation: Excitation,
        resting_force_n: f64,
    ) -> Self {
        let table = match excitation.first_sine() {
            Some((freq_hz, accel_mps2)) => {
                Table::for_sine(accel_mps2, std::f64::consts::TAU * freq_hz)
            }
            None => Table::default(),
        };
        let mut motion = HostMotion::new(spec, payload, excitation, resting_force_n);
        let mass_kg = base_mass_kg(spec, payload);
        motion.dynamics = HostDynamics::with_drive(spec, payload, vec![mass_kg; spec.modes.len()]);
        motion.start_m = motion.dynamics.damper_displacement_m();
        motion.base = Some(OnBase {
            table,
            mass_kg: base_mass_kg(spec, payload),
            damper_work_on_table_j: 0.0,
        });
        motion
    }

    /// The damper force's work on the table's motion so far, `Σ F_d Δy`
    /// (J, 0 for a force drive): what the bed's walls' work differs by
    /// from the host's books, which are in the table's frame.
    pub fn damper_work_on_table_j(&self) -> f64 {
        self.base.map_or(0.0, |b| b.damper_work_on_table_j)
    }

    /// The damper's displacement from its start, m: on a table the
    /// table's displacement plus the host's deflection.
    pub fn damper_displacement_m(&self) -> f64 {
        self.kinematics.displacement_m + self.start_m
    }

    /// The force at the drive point (N): the excitation's at the step's end
    /// for a force drive (read with the acceleration, at one instant; the
    /// mid-step force held over the step put the force half a step late
    /// against it, and the power input 0.3 % low at 20 Hz); on a table, the
    /// force the table puts through its transducer, `M (a_b + z'') − F_d`
    /// (Newton on the host as a whole).
    pub fn drive_force_n(&self) -> f64 {
        match self.base {
            None => self.end_excitation_n,
            Some(b) => b.mass_kg * self.kinematics.acceleration_mps2 - self.last_damper_force_n,
        }
    }

    /// The drive point's velocity (m/s): the table's on a table.
    pub fn drive_velocity_mps(&self) -> f64 {
        match self.base {
            None => self.dynamics.drive_velocity_mps(),
            Some(b) => b.table.velocity_mps,
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

    /// The excitation at the last step's end, what the lab's channel reads
    /// with the acceleration at that instant: a force (N), or on a table the
    /// table's acceleration (m/s²). (The step holds it at its middle.)
    pub fn excitation_n(&self) -> f64 {
        self.end_excitation_n
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
        self.last_damper_force_n = f_d;
        // The accelerometer reads the step's end, under the excitation
        // there (`HostDynamics::damper_acceleration_now_mps2`).
        let f_e_end = self.excitation.force_n(t_s);
        self.end_excitation_n = f_e_end;
        let Some(base) = self.base.as_mut() else {
            self.dynamics.advance(dt_s, f_d, f_e);
            self.kinematics = Kinematics {
                displacement_m: self.dynamics.damper_displacement_m() - self.start_m,
                velocity_mps: self.dynamics.damper_velocity_mps(),
                acceleration_mps2: self.dynamics.damper_acceleration_now_mps2(f_d, f_e_end),
            };
            return self.kinematics;
        };
        // On a table: f_e is the table's acceleration, the load −M a_b.
        self.dynamics.advance(dt_s, f_d, -f_e);
        let y0 = base.table.displacement_m;
        base.table.advance(dt_s, f_e);
        base.damper_work_on_table_j += f_d * (base.table.displacement_m - y0);
        self.kinematics = Kinematics {
            displacement_m: base.table.displacement_m + self.dynamics.damper_displacement_m()
                - self.start_m,
            velocity_mps: base.table.velocity_mps + self.dynamics.damper_velocity_mps(),
            acceleration_mps2: f_e_end + self.dynamics.damper_acceleration_now_mps2(f_d, -f_e_end),
        };
        self.kinematics
    }

    fn kinematics(&self) -> Kinematics {
        self.kinematics
    }
}
