//! Base excitation: the host on a shaker's table, as most dampers are
//! tested on shakers. The table's acceleration `a_b(t)` is prescribed (the
//! sine controller holds it); the host, a mass `m` on a spring `k` and a
//! dashpot `c` to the table, carries the enclosure; what a lab reads is the
//! **transmissibility** `T = A_damper / A_table` (two accelerometers) and,
//! with a force transducer between table and host, the power the table puts
//! in (Yang's method on the table's force and acceleration, thesis eq.
//! 7.9-7.12, as on the thesis rig, whose enclosure sits on its transducer).
//!
//! In the table's frame, with `z` the host's deflection from the table and
//! `M = m + m_a` the host with what the enclosure carries as a rigid mass,
//!
//! `M z'' + (c + c_a) z' + k z = F_d − M a_b`,
//!
//! the damper force `F_d` as for a force drive and `c_a` a dashpot payload
//! between the enclosure and the table: the modal equation of
//! [`super::dynamics`] with the inertial load `−M a_b` as its excitation.
//! The enclosure moves with `y + z` (`y` the table's displacement), and the
//! force the table puts through the transducer is `F_b = M (a_b + z'') − F_d`
//! (Newton on the host as a whole). For a linear payload the steady answer
//! is the classical `T(ω) = (k + i ω c_t) / (k − ω² M + i ω c_t)`,
//! `c_t = c + c_a` ([`transmissibility`]).
//!
//! Only a one-mode host with both shape values 1 (a mass on its spring)
//! can stand on a table: a modal host's participation factors (how much of
//! each mode's mass the table's motion shakes) are not in its file.

use realfft::num_complex::Complex64;

use super::dynamics::Payload;
use super::spec::HostSpec;
use crate::validation::InvalidParameter;

/// Refuses a host that cannot stand on a table: more than one mode, or
/// shape values other than 1.
pub fn check_on_base(spec: &HostSpec) -> Result<(), InvalidParameter> {
    let reason = "a host on a table must be one mode with shape values 1 (a mass on its spring \
                  and dashpot to the table): a modal host's participation factors are not in \
                  its file";
    match spec.modes.as_slice() {
        [m] if m.shape_at_damper == 1.0 && m.shape_at_drive == 1.0 => Ok(()),
        [m] => Err(InvalidParameter::new(
            "host mode shape_at_damper",
            m.shape_at_damper,
            "",
            format!("1 ({reason})"),
        )),
        modes => Err(InvalidParameter::new(
            "host modes",
            modes.len() as f64,
            "modes",
            format!("1 ({reason})"),
        )),
    }
}

/// The mass the table's acceleration shakes, `M = m + m_a`, kg: the
/// inertial load is `−M a_b`.
pub fn base_mass_kg(spec: &HostSpec, payload: Payload) -> f64 {
    spec.modes.iter().map(|m| m.modal_mass_kg).sum::<f64>() + payload.mass_kg
}

/// The steady transmissibility `A_damper / A_table` of a one-mode host
/// carrying a linear `payload` at `omega_rad_s`: `(k + i ω c_t) /
/// (k − ω² M + i ω c_t)`.
pub fn transmissibility(spec: &HostSpec, payload: Payload, omega_rad_s: f64) -> Complex64 {
    let w = omega_rad_s;
    let k: f64 = spec.modes.iter().map(|m| m.stiffness()).sum();
    let c = spec
        .modes
        .iter()
        .map(|m| m.damping_n_s_per_m())
        .sum::<f64>()
        + payload.dashpot_n_s_per_m;
    let m = base_mass_kg(spec, payload);
    Complex64::new(k, w * c) / Complex64::new(k - w * w * m, w * c)
}

/// The table: its acceleration held over each step, its velocity and
/// displacement integrated exactly under it.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Table {
    pub displacement_m: f64,
    pub velocity_mps: f64,
    pub acceleration_mps2: f64,
}

impl Table {
    /// A table about to follow `A sin ω t` from t = 0 with no mean
    /// velocity: its velocity starts at `−A / ω`, so that it swings about
    /// where it started instead of drifting away at `A / ω`.
    pub fn for_sine(accel_mps2: f64, omega_rad_s: f64) -> Table {
        Table {
            velocity_mps: -accel_mps2 / omega_rad_s,
            ..Table::default()
        }
    }

    /// One step of `dt_s` under `accel_mps2` held over it.
    pub fn advance(&mut self, dt_s: f64, accel_mps2: f64) {
        self.displacement_m += dt_s * (self.velocity_mps + 0.5 * dt_s * accel_mps2);
        self.velocity_mps += dt_s * accel_mps2;
        self.acceleration_mps2 = accel_mps2;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::host::ModeSpec;
    use crate::rig::RigFile;
    use std::f64::consts::TAU;

    fn plate() -> HostSpec {
        HostSpec::builtin("plate-40hz").expect("built in")
    }

    /// The classical limits: 1 at low frequency, `√(1 + (2ζ)²) / (2ζ)` at
    /// the natural frequency (exact for ζ the total damping ratio), `√2`
    /// crossing at `ω_n √2` (|T| = 1 there for any damping), and a
    /// payload's mass lowering the resonance.
    #[test]
    fn transmissibility_has_its_classical_values() {
        let spec = plate();
        let mode = spec.modes[0];
        let wn = mode.omega_rad_s();
        let none = Payload::default();
        assert!((transmissibility(&spec, none, 1e-4 * wn).norm() - 1.0).abs() < 1e-6);
        let z = mode.damping_ratio;
        let peak = (1.0 + (2.0 * z).powi(2)).sqrt() / (2.0 * z);
        let at_wn = transmissibility(&spec, none, wn).norm();
        assert!((at_wn / peak - 1.0).abs() < 1e-12, "{at_wn} vs {peak}");
        let cross = transmissibility(&spec, none, wn * 2f64.sqrt()).norm();
        assert!((cross - 1.0).abs() < 1e-12, "{cross}");
        let heavy = Payload {
            mass_kg: mode.modal_mass_kg,
            dashpot_n_s_per_m: 0.0,
        };
        let w_heavy = wn / 2f64.sqrt();
        assert!(
            transmissibility(&spec, heavy, w_heavy).norm() > 0.9 * peak,
            "the doubled mass resonates at w_n / sqrt 2"
        );
    }

    #[test]
    fn only_a_one_mode_host_of_unit_shapes_stands_on_a_table() {
        assert!(check_on_base(&plate()).is_ok());
        let beam = HostSpec::builtin("beam-2mode").expect("built in");
        let e = check_on_base(&beam).expect_err("two modes");
        assert!(e.to_string().contains("participation"), "{e}");
        let mut odd = plate();
        odd.modes[0] = ModeSpec {
            shape_at_damper: 0.5,
            ..ModeSpec::sdof(40.0, 2.0, 0.01)
        };
        assert!(check_on_base(&odd).is_err());
    }

    /// The table under a held sine swings about its start: over whole
    /// periods its mean velocity is zero to the step's second order (the
    /// held mid-step value integrates `A sin` short by `(ω dt)² / 24`, 3e-7
    /// here, which leaves a drift of that fraction of `A / ω`).
    #[test]
    fn a_sine_table_does_not_drift() {
        let (a, f, dt) = (10.0, 40.0, 1e-5);
        let w = TAU * f;
        let mut t = Table::for_sine(a, w);
        let steps = (4.0 / f / dt).round() as usize;
        let mut mean_v = 0.0;
        for k in 1..=steps {
            t.advance(dt, a * (w * (k as f64 - 0.5) * dt).sin());
            mean_v += t.velocity_mps / steps as f64;
        }
        assert!(mean_v.abs() < 1e-5 * a / w, "{mean_v}");
        assert!(
            t.displacement_m.abs() < 1e-4 * a / (w * w),
            "{}",
            t.displacement_m
        );
    }
}
