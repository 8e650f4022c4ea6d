//! The host's equations of motion: stepped exactly under forces held over a
//! step, and its receptance for the frequency-domain model.
//!
//! In modal coordinates `q` (one per `[[mode]]` of [`HostSpec`]),
//!
//! `M q'' + C q' + K q = φ_d F_d + φ_e F_e`,
//!
//! `M = diag(m_r) + m_a φ_d φ_dᵀ`, `C = diag(2 ζ_r ω_r m_r) + c_a φ_d φ_dᵀ`,
//! `K = diag(m_r ω_r²)`, where `m_a` and `c_a` are what the enclosure
//! carries as a rigid mass or a linear dashpot to ground-fixed velocity
//! ([`Payload`]), `F_d` the force on the host at the damper (the DEM's
//! particles push the enclosure) and `F_e` the excitation at the drive point.
//! With both held over a step (the DEM's explicit coupling, as the
//! electrodynamic shaker), the state advances exactly by one matrix
//! exponential ([`crate::rig::discretise::zero_order_hold_dense`]).
//!
//! The receptance from `b` to `a` with an impedance `s(ω)` at the damper
//! (`F_d = −s x_d`, `s = −ω² m + i ω c`) is `φ_aᵀ Z⁻¹ φ_b`,
//! `Z = diag(k_r − ω² m_r + i ω c_r) + s φ_d φ_dᵀ`, inverted by the
//! Sherman–Morrison formula: the model the map-based damper
//! ([`super::map_model`]) closes with its amplitude-dependent `s`.

use std::f64::consts::TAU;

use realfft::num_complex::Complex64;
use serde::Serialize;

use super::spec::HostSpec;
use crate::rig::discretise::{DenseMatrix, zero_order_hold_dense};

/// What the enclosure carries besides the DEM's particles: a rigid mass or a
/// linear dashpot at the damper (the comparisons a lab makes: the empty
/// enclosure, an equivalent solid mass, a known viscous damper).
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize)]
pub struct Payload {
    /// Rigid mass moving with the enclosure, kg.
    pub mass_kg: f64,
    /// Linear dashpot between the enclosure and ground, N s/m.
    pub dashpot_n_s_per_m: f64,
}

/// Where a host's energy went over a run (J), each term integrated on its
/// own (not a remainder): the check is that they close.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize)]
pub struct HostEnergy {
    /// Work of the excitation at the drive point, `Σ F_e Δx_e` (exact for a
    /// force held over the step).
    pub excitation_work_j: f64,
    /// Work of the damper's force on the host, `Σ F_d Δx_d`: minus what the
    /// host gave the particles.
    pub damper_work_j: f64,
    /// Dissipated by the host's own modal damping, `∫ q'ᵀ C_host q' dt`
    /// (trapezoidal rule).
    pub host_dissipated_j: f64,
    /// Dissipated by the payload's dashpot, `∫ c_a x_d'² dt`.
    pub dashpot_dissipated_j: f64,
}

/// A host stepped in time: its matrices, its exact step and its state.
#[derive(Debug, Clone)]
pub struct HostDynamics {
    n: usize,
    phi_d: Vec<f64>,
    phi_e: Vec<f64>,
    mass: DenseMatrix,
    stiffness: Vec<f64>,
    host_damping: Vec<f64>,
    payload: Payload,
    /// `z' = A z + B [F_d, F_e]`.
    a: DenseMatrix,
    b: Vec<f64>,
    step: Option<(f64, DenseMatrix, Vec<f64>)>,
    /// `[q; q']`.
    z: Vec<f64>,
    energy: HostEnergy,
}

impl HostDynamics {
    /// The host `spec` carrying `payload`, at rest.
    pub fn new(spec: &HostSpec, payload: Payload) -> Self {
        let phi_e: Vec<f64> = spec.modes.iter().map(|m| m.shape_at_drive).collect();
        Self::with_drive(spec, payload, phi_e)
    }

    /// The host `spec` carrying `payload` with the drive vector `phi_e`
    /// (one value a mode) in place of the shape values at the drive: on a
    /// shaker's table ([`super::base`]) the table's mass `M` for the
    /// inertial load `−M a_b`.
    pub fn with_drive(spec: &HostSpec, payload: Payload, phi_e: Vec<f64>) -> Self {
        let n = spec.modes.len();
        let phi_d: Vec<f64> = spec.modes.iter().map(|m| m.shape_at_damper).collect();
        let stiffness: Vec<f64> = spec.modes.iter().map(|m| m.stiffness()).collect();
        let host_damping: Vec<f64> = spec.modes.iter().map(|m| m.damping_n_s_per_m()).collect();
        let mut mass = DenseMatrix::zeros(n);
        let mut damping = DenseMatrix::zeros(n);
        for i in 0..n {
            for j in 0..n {
                let rank_one = phi_d[i] * phi_d[j];
                let diagonal = |v: f64| if i == j { v } else { 0.0 };
                mass.set(
                    i,
                    j,
                    diagonal(spec.modes[i].modal_mass_kg) + payload.mass_kg * rank_one,
                );
                damping.set(
                    i,
                    j,
                    diagonal(host_damping[i]) + payload.dashpot_n_s_per_m * rank_one,
                );
            }
        }
        let inverse = inverse_mass(spec, &phi_d, payload.mass_kg);
        // A = [[0, I], [-M^-1 K, -M^-1 C]], B = [[0, 0], [M^-1 phi_d, M^-1 phi_e]].
        let mut a = DenseMatrix::zeros(2 * n);
        let mut b = vec![0.0; 4 * n];
        for i in 0..n {
            a.set(i, n + i, 1.0);
            for (j, k_j) in stiffness.iter().enumerate() {
                a.set(n + i, j, -inverse.get(i, j) * k_j);
                let mc: f64 = (0..n).map(|k| inverse.get(i, k) * damping.get(k, j)).sum();
                a.set(n + i, n + j, -mc);
            }
            b[(n + i) * 2] = (0..n).map(|k| inverse.get(i, k) * phi_d[k]).sum();
            b[(n + i) * 2 + 1] = (0..n).map(|k| inverse.get(i, k) * phi_e[k]).sum();
        }
        HostDynamics {
            n,
            phi_d,
            phi_e,
            mass,
            stiffness,
            host_damping,
            payload,
            a,
            b,
            step: None,
            z: vec![0.0; 2 * n],
            energy: HostEnergy::default(),
        }
    }

    /// Releases the host from rest under a constant force at the damper
    /// that holds it at `x0_m`: each mode at its static deflection
    /// `q_r = φ_r(d) F / k_r`, `F = x0 / Σ φ_r(d)² / k_r` (a free decay as a
    /// lab starts one: pull the damper, hold, let go).
    pub fn release_from(&mut self, spec: &HostSpec, x0_m: f64) {
        let flexibility: f64 = spec
            .modes
            .iter()
            .map(|m| m.shape_at_damper.powi(2) / m.stiffness())
            .sum();
        let force = x0_m / flexibility;
        for r in 0..self.n {
            self.z[r] = self.phi_d[r] * force / self.stiffness[r];
            self.z[self.n + r] = 0.0;
        }
    }

    /// Sets the state `[q; q']` (2 values a mode).
    pub fn set_state(&mut self, modal_state: &[f64]) {
        if modal_state.len() == self.z.len() {
            self.z.copy_from_slice(modal_state);
        }
    }

    /// Advances one step of `dt_s` with the damper force `damper_force_n`
    /// (on the host, along the axis) and the excitation `excitation_n` held
    /// over it, booking the energies.
    pub fn advance(&mut self, dt_s: f64, damper_force_n: f64, excitation_n: f64) {
        if self.step.as_ref().is_none_or(|(dt, _, _)| *dt != dt_s) {
            let (phi, gamma) = zero_order_hold_dense(&self.a, &self.b, 2, dt_s);
            self.step = Some((dt_s, phi, gamma));
        }
        let Some((_, phi, gamma)) = &self.step else {
            return;
        };
        let (xd0, xe0) = (self.damper_displacement_m(), self.drive_displacement_m());
        let (p_host0, p_dash0) = self.damping_powers_w();
        let mut z = phi.apply(&self.z);
        for (i, zi) in z.iter_mut().enumerate() {
            *zi += gamma[2 * i] * damper_force_n + gamma[2 * i + 1] * excitation_n;
        }
        self.z = z;
        let (p_host1, p_dash1) = self.damping_powers_w();
        let (xd1, xe1) = (self.damper_displacement_m(), self.drive_displacement_m());
        let e = &mut self.energy;
        e.excitation_work_j += excitation_n * (xe1 - xe0);
        e.damper_work_j += damper_force_n * (xd1 - xd0);
        e.host_dissipated_j += 0.5 * dt_s * (p_host0 + p_host1);
        e.dashpot_dissipated_j += 0.5 * dt_s * (p_dash0 + p_dash1);
    }

    /// Power the host's own damping and the payload's dashpot dissipate now, W.
    fn damping_powers_w(&self) -> (f64, f64) {
        let v = &self.z[self.n..];
        let host = (0..self.n)
            .map(|r| self.host_damping[r] * v[r] * v[r])
            .sum();
        let vd = self.damper_velocity_mps();
        (host, self.payload.dashpot_n_s_per_m * vd * vd)
    }

    fn dot(phi: &[f64], x: &[f64]) -> f64 {
        phi.iter().zip(x).map(|(p, x)| p * x).sum()
    }

    /// Modal accelerations `q''` of the present state under the forces
    /// `[damper, excitation]` (N).
    fn modal_acceleration(&self, forces_n: [f64; 2]) -> Vec<f64> {
        let zdot = self.a.apply(&self.z);
        (0..self.n)
            .map(|i| {
                zdot[self.n + i]
                    + self.b[(self.n + i) * 2] * forces_n[0]
                    + self.b[(self.n + i) * 2 + 1] * forces_n[1]
            })
            .collect()
    }

    /// Displacement at the damper, m.
    pub fn damper_displacement_m(&self) -> f64 {
        Self::dot(&self.phi_d, &self.z[..self.n])
    }

    /// Velocity at the damper, m/s.
    pub fn damper_velocity_mps(&self) -> f64 {
        Self::dot(&self.phi_d, &self.z[self.n..])
    }

    /// Acceleration at the damper now, under the damper force
    /// `damper_force_n` and the excitation `excitation_n` acting at this
    /// instant, m/s²: what an accelerometer reads at the end of a step. (The
    /// force held over the step is the excitation's at mid-step, half a
    /// step old at its end: read with it, a sine's acceleration lagged the
    /// state's velocity by `ω_n² dt / 2ω` off resonance, 0.6 mrad at 20 Hz
    /// on plate-40hz, and the power input read 1.4 % low there, 7 % at
    /// 10 Hz, where the input is a small part of the power that flows.)
    pub fn damper_acceleration_now_mps2(&self, damper_force_n: f64, excitation_n: f64) -> f64 {
        Self::dot(
            &self.phi_d,
            &self.modal_acceleration([damper_force_n, excitation_n]),
        )
    }

    /// Displacement at the drive point, m.
    pub fn drive_displacement_m(&self) -> f64 {
        Self::dot(&self.phi_e, &self.z[..self.n])
    }

    /// Velocity at the drive point, m/s.
    pub fn drive_velocity_mps(&self) -> f64 {
        Self::dot(&self.phi_e, &self.z[self.n..])
    }

    /// Kinetic and strain energy of the host and its payload, J.
    pub fn mechanical_energy_j(&self) -> f64 {
        let (q, v) = self.z.split_at(self.n);
        let kinetic: f64 = self.mass.apply(v).iter().zip(v).map(|(mv, v)| mv * v).sum();
        let strain: f64 = (0..self.n).map(|r| self.stiffness[r] * q[r] * q[r]).sum();
        0.5 * (kinetic + strain)
    }

    /// The energies booked since the start.
    pub fn energy(&self) -> HostEnergy {
        self.energy
    }
}

/// `M⁻¹` for `M = diag(m) + m_a φ φᵀ` (Sherman–Morrison).
fn inverse_mass(spec: &HostSpec, phi: &[f64], added_kg: f64) -> DenseMatrix {
    let n = phi.len();
    let d: Vec<f64> = spec.modes.iter().map(|m| 1.0 / m.modal_mass_kg).collect();
    let u: Vec<f64> = (0..n).map(|i| d[i] * phi[i]).collect();
    let denom = 1.0 + added_kg * (0..n).map(|i| phi[i] * u[i]).sum::<f64>();
    let mut inv = DenseMatrix::zeros(n);
    for i in 0..n {
        for j in 0..n {
            let diagonal = if i == j { d[i] } else { 0.0 };
            inv.set(i, j, diagonal - added_kg * u[i] * u[j] / denom);
        }
    }
    inv
}

/// Each mode's dynamic compliance `1 / (k_r − ω² m_r + i ω c_r)` at
/// `omega_rad_s` (m/N per unit of modal force): the diagonal `D⁻¹` both
/// [`receptance`] and [`sine_steady_state`] correct for the damper.
fn modal_compliances(spec: &HostSpec, omega_rad_s: f64) -> Vec<Complex64> {
    let w = omega_rad_s;
    spec.modes
        .iter()
        .map(|m| {
            Complex64::new(
                m.stiffness() - w * w * m.modal_mass_kg,
                w * m.damping_n_s_per_m(),
            )
            .inv()
        })
        .collect()
}

/// The state `[q; q']` at t = 0 of `spec` with `payload` in the steady
/// response to `F sin ω t` at the drive point: `q(t) = Im(Q e^{iωt})`,
/// `Q = Z⁻¹ φ_e F` (Sherman–Morrison as [`receptance`]).
pub fn sine_steady_state(
    spec: &HostSpec,
    payload: Payload,
    omega_rad_s: f64,
    force_n: f64,
) -> Vec<f64> {
    let w = omega_rad_s;
    let s = Complex64::new(-w * w * payload.mass_kg, w * payload.dashpot_n_s_per_m);
    let inv_d = modal_compliances(spec, w);
    let dd: Complex64 = spec
        .modes
        .iter()
        .zip(&inv_d)
        .map(|(m, d)| d * m.shape_at_damper.powi(2))
        .sum();
    let de: Complex64 = spec
        .modes
        .iter()
        .zip(&inv_d)
        .map(|(m, d)| d * (m.shape_at_damper * m.shape_at_drive))
        .sum();
    let scale = s * de / (1.0 + s * dd);
    let q: Vec<Complex64> = spec
        .modes
        .iter()
        .zip(&inv_d)
        .map(|(m, d)| (d * m.shape_at_drive - d * m.shape_at_damper * scale) * force_n)
        .collect();
    q.iter()
        .map(|q| q.im)
        .chain(q.iter().map(|q| w * q.re))
        .collect()
}

/// The state `[q; q']` at t = 0 of `spec` with `payload` in the steady
/// response to a sum of lines `F_k sin(ω_k t + φ_k)` at the drive point
/// (a multi-sine, a periodic random force): by superposition, each line's
/// `q(t) = Im(Q_k e^{i(ω_k t + φ_k)})` ([`sine_steady_state`]'s `Q`) summed
/// at t = 0, `payload_at(ω)` the payload each line sees.
pub fn lines_steady_state(
    spec: &HostSpec,
    payload_at: &dyn Fn(f64) -> Payload,
    lines: &[super::excitation::Line],
) -> Vec<f64> {
    let n = spec.modes.len();
    let mut state = vec![0.0; 2 * n];
    for l in lines {
        let w = TAU * l.freq_hz;
        // The line's state at phase 0 is [Im Q; w Re Q]: turn Q by phi.
        let at_zero = sine_steady_state(spec, payload_at(w), w, l.force_n);
        let turn = Complex64::from_polar(1.0, l.phase_rad);
        for r in 0..n {
            let q = Complex64::new(at_zero[n + r] / w, at_zero[r]) * turn;
            state[r] += q.im;
            state[n + r] += w * q.re;
        }
    }
    state
}

/// Which point of the host.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Point {
    /// Where the damper (the enclosure) sits.
    Damper,
    /// Where the excitation acts.
    Drive,
}

/// Receptance (displacement per force, m/N) of `spec` from a force at `from`
/// to the displacement at `to`, at `omega_rad_s`, with the impedance
/// `damper_impedance` (N/m, complex: `−ω² m + i ω c` for a mass and a
/// dashpot) acting at the damper.
pub fn receptance(
    spec: &HostSpec,
    omega_rad_s: f64,
    damper_impedance: Complex64,
    from: Point,
    to: Point,
) -> Complex64 {
    let w = omega_rad_s;
    let shape = |m: &super::spec::ModeSpec, p: Point| match p {
        Point::Damper => m.shape_at_damper,
        Point::Drive => m.shape_at_drive,
    };
    let inv_d = modal_compliances(spec, w);
    let sum = |a: Point, b: Point| -> Complex64 {
        spec.modes
            .iter()
            .zip(&inv_d)
            .map(|(m, d)| d * (shape(m, a) * shape(m, b)))
            .sum()
    };
    let h_ab = sum(to, from);
    let h_ad = sum(to, Point::Damper);
    let h_db = sum(Point::Damper, from);
    let h_dd = sum(Point::Damper, Point::Damper);
    h_ab - damper_impedance * h_ad * h_db / (1.0 + damper_impedance * h_dd)
}

#[cfg(test)]
mod tests {
    use std::f64::consts::TAU;

    use super::*;
    use crate::rig::RigFile;

    fn plate() -> HostSpec {
        HostSpec::sdof("test", 40.0, 0.5, 0.003).expect("valid")
    }

    /// Runs `host` under a sine of `force_n` at `freq_hz` for `cycles`, then
    /// one more cycle, and returns the damper's peak displacement in it.
    fn steady_amplitude(host: &mut HostDynamics, freq_hz: f64, force_n: f64, cycles: u32) -> f64 {
        let dt = 1.0 / (freq_hz * 2000.0);
        let steps = 2000 * (cycles + 1);
        let mut peak: f64 = 0.0;
        for k in 0..steps {
            let t_mid = (f64::from(k) + 0.5) * dt;
            host.advance(dt, 0.0, force_n * (TAU * freq_hz * t_mid).sin());
            if k >= 2000 * cycles {
                peak = peak.max(host.damper_displacement_m().abs());
            }
        }
        peak
    }

    #[test]
    fn a_forced_sdof_host_reaches_the_analytical_steady_amplitude() {
        // |X| = F / sqrt((k - m w^2)^2 + (c w)^2) off resonance and at it,
        // with the dashpot payload adding c_a to c. Tolerance 2e-4: the
        // transient has decayed to e^(-zeta w t) < 1e-4 and the held force
        // is a midpoint sample (error (w dt)^2 / 24 ~ 4e-7).
        let spec = plate();
        for (payload, freq_hz, cycles) in [
            (Payload::default(), 30.0, 600),
            (
                Payload {
                    mass_kg: 0.0,
                    dashpot_n_s_per_m: 15.0,
                },
                40.0,
                40,
            ),
            (
                Payload {
                    mass_kg: 0.1,
                    dashpot_n_s_per_m: 15.0,
                },
                36.0,
                40,
            ),
        ] {
            let mut host = HostDynamics::new(&spec, payload);
            let got = steady_amplitude(&mut host, freq_hz, 5.0, cycles);
            let z = Complex64::new(-payload.mass_kg, 0.0) * (TAU * freq_hz).powi(2)
                + Complex64::new(0.0, TAU * freq_hz * payload.dashpot_n_s_per_m);
            let want =
                5.0 * receptance(&spec, TAU * freq_hz, z, Point::Drive, Point::Damper).norm();
            assert!(
                (got / want - 1.0).abs() < 2e-4,
                "{payload:?} at {freq_hz} Hz: {got} m against {want} m"
            );
        }
    }

    #[test]
    fn a_released_host_decays_at_its_damping_ratio_and_its_energy_closes() {
        // Free decay x0 e^(-zeta w t) (cos wd t + zeta w / wd sin wd t):
        // after whole damped periods the amplitude is x0 e^(-zeta w n Td),
        // within 1e-6 relative; the energy booked apart closes to 1e-6 of
        // what was dissipated (trapezoidal damping power, error ~ (w dt)^2).
        let spec = plate();
        let payload = Payload {
            mass_kg: 0.0,
            dashpot_n_s_per_m: 20.0,
        };
        let mut host = HostDynamics::new(&spec, payload);
        host.release_from(&spec, 3e-3);
        assert!((host.damper_displacement_m() - 3e-3).abs() < 1e-15);
        let e0 = host.mechanical_energy_j();
        let m = spec.modes[0];
        let w = m.omega_rad_s();
        let c = m.damping_n_s_per_m() + 20.0;
        let zeta = c / (2.0 * m.modal_mass_kg * w);
        let wd = w * (1.0 - zeta * zeta).sqrt();
        let td = TAU / wd;
        let steps_per_period = 4000;
        let dt = td / f64::from(steps_per_period);
        let periods = 10;
        for _ in 0..periods * steps_per_period {
            host.advance(dt, 0.0, 0.0);
        }
        let want = 3e-3 * (-zeta * w * f64::from(periods) * td).exp();
        let got = host.damper_displacement_m();
        assert!((got / want - 1.0).abs() < 1e-6, "{got} against {want}");
        let e = host.energy();
        let lost = e.host_dissipated_j + e.dashpot_dissipated_j;
        let closes = e0 - host.mechanical_energy_j() - lost;
        assert!(closes.abs() < 1e-6 * lost, "{closes} J of {lost} J");
        // Each part as its damping's share: c_host / c of what was lost.
        let share = e.dashpot_dissipated_j / lost;
        assert!((share - 20.0 / c).abs() < 1e-9, "{share}");
    }

    #[test]
    fn the_excitation_and_damper_work_close_the_energy_of_a_two_mode_host() {
        // A two-mode host under a drive force and an unrelated damper force:
        // the work of both, less both dissipations, is the energy stored,
        // to 1e-6 of the work (the sign of any term wrong fails it by far).
        let spec = HostSpec::builtin("beam-2mode").expect("built in");
        let payload = Payload {
            mass_kg: 0.03,
            dashpot_n_s_per_m: 4.0,
        };
        let mut host = HostDynamics::new(&spec, payload);
        let dt = 2e-6;
        for k in 0..200_000 {
            let t = (f64::from(k) + 0.5) * dt;
            let f_e = 3.0 * (TAU * 41.0 * t).sin() + 1.0 * (TAU * 250.0 * t).cos();
            let f_d = -8.0 * host.damper_velocity_mps() + 0.5 * (TAU * 7.0 * t).sin();
            host.advance(dt, f_d, f_e);
        }
        let e = host.energy();
        let stored = host.mechanical_energy_j();
        let closes = e.excitation_work_j + e.damper_work_j
            - e.host_dissipated_j
            - e.dashpot_dissipated_j
            - stored;
        assert!(e.excitation_work_j > 0.0 && e.damper_work_j < 0.0, "{e:?}");
        assert!(
            closes.abs() < 1e-6 * e.excitation_work_j,
            "{closes} J of {} J",
            e.excitation_work_j
        );
    }

    #[test]
    fn the_two_mode_receptance_is_the_sum_of_its_modes_and_reciprocal() {
        let spec = HostSpec::builtin("beam-2mode").expect("built in");
        let w = TAU * 100.0;
        let zero = Complex64::new(0.0, 0.0);
        let h = receptance(&spec, w, zero, Point::Drive, Point::Damper);
        let by_hand: Complex64 = spec
            .modes
            .iter()
            .map(|m| {
                m.shape_at_damper * m.shape_at_drive
                    / Complex64::new(
                        m.stiffness() - w * w * m.modal_mass_kg,
                        w * m.damping_n_s_per_m(),
                    )
            })
            .sum();
        assert!((h - by_hand).norm() < 1e-15 * by_hand.norm());
        // Reciprocity with a damper impedance too (Maxwell-Betti).
        let s = Complex64::new(-w * w * 0.03, w * 5.0);
        let ab = receptance(&spec, w, s, Point::Drive, Point::Damper);
        let ba = receptance(&spec, w, s, Point::Damper, Point::Drive);
        assert!((ab - ba).norm() < 1e-15 * ab.norm());
        // A mass at the damper of the SDOF plate moves its resonance to
        // sqrt(k / (m + m_a)).
        let plate = plate();
        let k = plate.modes[0].stiffness();
        let wn = (k / 0.6).sqrt();
        let at = |w: f64| {
            receptance(
                &plate,
                w,
                Complex64::new(-w * w * 0.1, 0.0),
                Point::Drive,
                Point::Damper,
            )
            .norm()
        };
        assert!(at(wn) > at(wn * 1.01) && at(wn) > at(wn * 0.99));
    }
}
