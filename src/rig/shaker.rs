//! The drive: what moves the enclosure (thesis Sections 6.2, 7.4.2 and 7.6).
//!
//! # Prescribed
//!
//! `u = Gamma g / w^2 sin(w t)` exactly (thesis eq. 6.2 / 7.6), kinematics
//! analytic; the particles cannot disturb it.
//!
//! # Electrodynamic
//!
//! A lumped shaker: armature and enclosure rigidly joined (the force
//! transducer between them is stiff), on a suspension, driven by a voice coil
//! fed by a voltage amplifier:
//!
//! ```text
//! (m_a + m_enc) x'' = Bl i - k x - c x' + F_p
//! L i'            = V_amp - R i - Bl x'
//! V_amp           = gain V_drive sin(w t + phi)
//! ```
//!
//! `F_p` is the axial force the particles exert on the enclosure, passed to
//! [`Shaker::advance`]; their impacts therefore show in the acceleration as
//! spikes of `F_p / (m_a + m_enc)` (thesis Fig. 7.12-7.13). `x` is measured
//! from the static equilibrium of the loaded suspension; gravity on the moving
//! mass only shifts that equilibrium. The mean particle force (their weight,
//! on a vertical axis) shifts it by a further `M_p g / k` (23 um for the thesis
//! damper on thesis-shaker), reached with the suspension's slow time constant.
//!
//! **Drive level.** The open-loop drive comes from the linear model's complex
//! transfer function `X / V_amp = Bl / ((R + jwL)(k - m w^2 + jwc) + jw Bl^2)`
//! with an effective payload `m = m_a + m_enc + f M_p` (`f` =
//! `feedforward_particle_fraction`), phased so that `x = X sin(w t)` with
//! `X = Gamma g / w^2`. With `closed_loop = true` a sine controller then, once
//! per drive cycle, fits the fundamental of the acceleration over the cycle
//! just ended (least squares on `c0 + a sin wt + b cos wt`, so a fractional
//! number of steps per cycle is fine) and multiplies the complex drive by
//! `1 + loop_gain (A_target / A_measured - 1)` (magnitude clamped to
//! [0.5, 2]), correcting amplitude and phase as a vibration controller does.
//! [`Shaker::report`] gives the achieved Gamma of the last whole cycle.
//!
//! **Start.** The state starts at the steady state of the effective-payload
//! model: `u(0) = 0`, `u'(0) = w X`, the steady coil current. An empty
//! enclosure (`F_p = 0`, `M_p = 0`) is thus in steady state from the first
//! step; with particles the remaining transient is the payload mismatch.
//!
//! **Integration.** The state `z = (x, x', i)` is split into the analytic
//! steady-state response to the sine drive and a deviation `e`, which obeys
//! `e' = A e + b F_p` and is advanced by the exact zero-order-hold
//! discretisation `e <- Phi e + gamma F_p` ([`super::discretise`]; `F_p` held
//! over the step). This is exact for the linear model and unconditionally
//! stable: the coil's `L / R` (0.25 ms on thesis-shaker) and the suspension
//! modes are resolved at any step, 1 us or 5 us alike (`Phi`'s spectral radius
//! is `exp(max Re(lambda) dt) < 1`). A change of drive level at a cycle
//! boundary moves the steady state and `e` by the opposite amount, so the
//! state is continuous. Per step: one `sin_cos`, a 3x3 product, ~40 flops.

use glam::{DMat3, DVec3};
use realfft::num_complex::Complex64;

use super::discretise::zero_order_hold;
use super::error::{RigError, non_negative, positive};
use super::motion::{EnclosureMotion, Kinematics, SineMotion};
use super::spec::{ElectrodynamicSpec, RigSpec, ShakerKind};
use crate::drive::Drive;
use crate::maths;

/// How the drive went, for the caller's report.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ShakerReport {
    /// Kind of drive.
    pub kind: ShakerKind,
    /// Gamma asked for.
    pub target_gamma: f64,
    /// Fundamental acceleration amplitude / g over the last whole cycle
    /// (prescribed: the target; `None` before the first whole cycle).
    pub achieved_gamma: Option<f64>,
    /// Phase of that fundamental relative to `-Gamma g sin(w t)`, rad.
    pub fundamental_phase_rad: f64,
    /// Amplitude of the drive signal at the amplifier input, V (electrodynamic).
    pub drive_amplitude_v: Option<f64>,
    /// Whole cycles measured.
    pub cycles_measured: u32,
    /// Drive adjustments made by the controller.
    pub control_updates: u32,
    /// Largest |coil current| seen, A (electrodynamic).
    pub peak_current_a: Option<f64>,
}

/// Checks the rig's stroke and acceleration limits for the sine of `drive`
/// (displacement amplitude `Gamma g / w^2`, peak-to-peak twice that; peak
/// acceleration `Gamma g`).
pub fn check_limits(spec: &RigSpec, drive: &Drive) -> Result<(), RigError> {
    let (freq_hz, gamma) = (drive.freq_hz(), drive.gamma());
    positive("g_mps2", drive.gravity_mps2(), "m/s^2")?;
    let tidy = |x: f64| (x * 1e6).round() / 1e6;
    if let Some(stroke) = spec.shaker.stroke_pp_m {
        let needed = 2.0 * drive.displacement_amplitude_m();
        if needed > stroke * (1.0 + 1e-9) {
            return Err(RigError::StrokeLimit {
                rig: spec.name.clone(),
                gamma,
                freq_hz,
                needed_mm: needed * 1e3,
                allowed_mm: tidy(stroke * 1e3),
            });
        }
    }
    if let Some(max) = spec.shaker.max_accel_mps2 {
        let needed = drive.acceleration_amplitude_mps2();
        if needed > max * (1.0 + 1e-9) {
            return Err(RigError::AccelerationLimit {
                rig: spec.name.clone(),
                gamma,
                freq_hz,
                needed_mps2: needed,
                allowed_mps2: tidy(max),
            });
        }
    }
    Ok(())
}

/// Least-squares fit of `c0 + a sin(wt) + b cos(wt)` over one cycle, from
/// running sums (O(1) per step, no storage).
#[derive(Debug, Clone, Copy, Default)]
struct CycleFit {
    cycle: i64,
    n: f64,
    s: f64,
    c: f64,
    ss: f64,
    cc: f64,
    sc: f64,
    y: f64,
    ys: f64,
    yc: f64,
}

impl CycleFit {
    fn new(cycle: i64) -> Self {
        CycleFit {
            cycle,
            ..Default::default()
        }
    }

    #[inline]
    fn add(&mut self, sn: f64, cs: f64, y: f64) {
        self.n += 1.0;
        self.s += sn;
        self.c += cs;
        self.ss += sn * sn;
        self.cc += cs * cs;
        self.sc += sn * cs;
        self.y += y;
        self.ys += y * sn;
        self.yc += y * cs;
    }

    /// The fundamental as a phasor `a + j b` (signal `Im(P e^{jwt})`): the
    /// normal equations of the fit, solved directly.
    fn phasor(&self) -> Option<Complex64> {
        if self.n < 8.0 {
            return None;
        }
        let m = DMat3::from_cols_array_2d(&[
            [self.n, self.s, self.c],
            [self.s, self.ss, self.sc],
            [self.c, self.sc, self.cc],
        ]);
        let det = m.determinant();
        if det.is_nan() || det.abs() <= 1e-12 * self.n.powi(3) {
            return None;
        }
        let x = m.inverse() * DVec3::new(self.y, self.ys, self.yc);
        Some(Complex64::new(x.y, x.z))
    }
}

/// The lumped electrodynamic shaker's state and constants.
#[derive(Debug, Clone)]
struct Electrodynamic {
    p: ElectrodynamicSpec,
    mass_kg: f64,
    a: DMat3,
    phi: DMat3,
    gamma_f: DVec3,
    dt_s: f64,
    /// Deviation of (x, v, i) from the steady state.
    e: DVec3,
    /// Drive phasor at the amplifier input, V.
    drive: Complex64,
    /// Steady-state phasors of x, v, i for the current drive.
    ss: [Complex64; 3],
    target: Complex64,
    fit: CycleFit,
    last_fit: Option<Complex64>,
    cycles: u32,
    updates: u32,
    peak_current_a: f64,
    current_a: f64,
}

impl Electrodynamic {
    /// `X / V_amp` of the linear model with moving mass `mass_kg`, at `w`.
    fn receptance(p: &ElectrodynamicSpec, mass_kg: f64, w: f64) -> Complex64 {
        let j = Complex64::new(0.0, 1.0);
        let coil = p.coil_resistance_ohm + j * w * p.coil_inductance_h;
        let mech = p.suspension_stiffness_n_per_m - mass_kg * w * w
            + j * w * p.suspension_damping_n_s_per_m;
        let bl = p.force_factor_n_per_a;
        bl / (coil * mech + j * w * bl * bl)
    }

    /// Steady-state phasors (x, v, i) of a model of `mass_kg` under `v_amp`.
    fn steady(p: &ElectrodynamicSpec, mass_kg: f64, w: f64, v_amp: Complex64) -> [Complex64; 3] {
        let j = Complex64::new(0.0, 1.0);
        let x = Self::receptance(p, mass_kg, w) * v_amp;
        let v = j * w * x;
        let i = (v_amp - p.force_factor_n_per_a * v)
            / (p.coil_resistance_ohm + j * w * p.coil_inductance_h);
        [x, v, i]
    }

    fn new(
        p: ElectrodynamicSpec,
        enclosure_mass_kg: f64,
        particle_mass_kg: f64,
        target: &SineMotion,
    ) -> Self {
        let w = target.omega();
        let mass_kg = p.armature_mass_kg + enclosure_mass_kg;
        let m_eff = mass_kg + p.feedforward_particle_fraction * particle_mass_kg;
        let h_eff = Self::receptance(&p, m_eff, w);
        let v_amp = Complex64::new(target.amplitude_m(), 0.0) / h_eff;
        let drive = v_amp / p.amplifier_gain_v_per_v;
        let start = Self::steady(&p, m_eff, w, v_amp);
        let ss = Self::steady(&p, mass_kg, w, v_amp);
        // At t = 0 the state is Im(start); the particular solution is Im(ss).
        let e = DVec3::new(
            start[0].im - ss[0].im,
            start[1].im - ss[1].im,
            start[2].im - ss[2].im,
        );
        let bl = p.force_factor_n_per_a;
        let a = DMat3::from_cols_array_2d(&[
            [0.0, 1.0, 0.0],
            [
                -p.suspension_stiffness_n_per_m / mass_kg,
                -p.suspension_damping_n_s_per_m / mass_kg,
                bl / mass_kg,
            ],
            [
                0.0,
                -bl / p.coil_inductance_h,
                -p.coil_resistance_ohm / p.coil_inductance_h,
            ],
        ])
        .transpose();
        let accel_amp = target.amplitude_m() * w * w;
        Electrodynamic {
            p,
            mass_kg,
            a,
            phi: DMat3::ZERO,
            gamma_f: DVec3::ZERO,
            dt_s: 0.0,
            e,
            drive,
            ss,
            target: Complex64::new(-accel_amp, 0.0),
            fit: CycleFit::new(0),
            last_fit: None,
            cycles: 0,
            updates: 0,
            peak_current_a: start[2].im.abs(),
            current_a: start[2].im,
        }
    }

    /// The force input of the state equation: the particles push the moving mass.
    fn force_input(&self) -> DVec3 {
        DVec3::new(0.0, 1.0 / self.mass_kg, 0.0)
    }

    fn discretise(&mut self, dt_s: f64) {
        let (phi, gamma_f) = zero_order_hold(&self.a, self.force_input(), dt_s);
        self.phi = phi;
        self.gamma_f = gamma_f;
        self.dt_s = dt_s;
    }

    /// State (x, v, i) at phase (sin wt, cos wt).
    #[inline]
    fn state(&self, sn: f64, cs: f64) -> DVec3 {
        DVec3::from_array([0, 1, 2].map(|j| self.ss[j].re * sn + self.ss[j].im * cs)) + self.e
    }

    fn acceleration(&self, z: DVec3, force_n: f64) -> f64 {
        (self.p.force_factor_n_per_a * z.z
            - self.p.suspension_stiffness_n_per_m * z.x
            - self.p.suspension_damping_n_s_per_m * z.y
            + force_n)
            / self.mass_kg
    }

    /// Kinematics at phase (sin wt, cos wt) with the particles' force `force_n`.
    fn kinematics(&self, sn: f64, cs: f64, force_n: f64) -> Kinematics {
        let z = self.state(sn, cs);
        Kinematics {
            displacement_m: z.x,
            velocity_mps: z.y,
            acceleration_mps2: self.acceleration(z, force_n),
        }
    }

    /// One step to `t_s`.
    #[inline]
    fn advance(&mut self, w: f64, freq_hz: f64, t_s: f64, dt_s: f64, force_n: f64) -> Kinematics {
        if (dt_s - self.dt_s).abs() > 1e-12 * dt_s {
            self.discretise(dt_s);
        }
        self.e = self.phi * self.e + self.gamma_f * force_n;
        let (sn, cs) = maths::sin_cos(w * t_s);
        let z = self.state(sn, cs);
        let k = Kinematics {
            displacement_m: z.x,
            velocity_mps: z.y,
            acceleration_mps2: self.acceleration(z, force_n),
        };
        self.current_a = z.z;
        self.peak_current_a = self.peak_current_a.max(self.current_a.abs());
        let cycle = (t_s * freq_hz + 1e-9).floor() as i64;
        if cycle != self.fit.cycle {
            self.end_cycle(w, sn, cs, cycle);
        }
        self.fit.add(sn, cs, k.acceleration_mps2);
        k
    }

    fn end_cycle(&mut self, w: f64, sn: f64, cs: f64, cycle: i64) {
        if let Some(measured) = self.fit.phasor() {
            self.last_fit = Some(measured);
            self.cycles += 1;
            if self.p.closed_loop && measured.norm() > 0.0 && self.target.norm() > 0.0 {
                let ratio = self.target / measured;
                let mut r = 1.0 + self.p.loop_gain * (ratio - 1.0);
                let mag = r.norm();
                if mag.is_finite() && mag > 0.0 {
                    r *= mag.clamp(0.5, 2.0) / mag;
                    self.drive *= r;
                    let old = self.ss;
                    let v_amp = self.drive * self.p.amplifier_gain_v_per_v;
                    self.ss = Self::steady(&self.p, self.mass_kg, w, v_amp);
                    for (k, (old, new)) in old.iter().zip(self.ss).enumerate() {
                        let d = old - new;
                        self.e[k] += d.re * sn + d.im * cs;
                    }
                    self.updates += 1;
                }
            }
        }
        self.fit = CycleFit::new(cycle);
    }
}

/// An electrodynamic shaker following its sine controller.
#[derive(Debug, Clone)]
pub struct ElectrodynamicShaker {
    target: SineMotion,
    model: Electrodynamic,
    g_mps2: f64,
    kin: Kinematics,
}

/// The drive of one test: a prescribed sine, or an electrodynamic shaker whose
/// motion the particles disturb. Either answers [`EnclosureMotion`].
#[derive(Debug, Clone)]
pub enum Shaker {
    /// The enclosure follows the sine exactly.
    Prescribed(SineMotion),
    /// The lumped shaker of the module documentation.
    Electrodynamic(Box<ElectrodynamicShaker>),
}

impl Shaker {
    /// A shaker of `kind` on rig `spec` for the sine of `drive`, moving an
    /// enclosure of `moving_mass_kg` (the mass above the force gauge) that
    /// holds `particle_mass_kg` of particles. Refuses what the rig's limits
    /// forbid ([`check_limits`]).
    pub fn new(
        spec: &RigSpec,
        kind: ShakerKind,
        drive: &Drive,
        moving_mass_kg: f64,
        particle_mass_kg: f64,
    ) -> Result<Shaker, RigError> {
        check_limits(spec, drive)?;
        positive("moving_mass_kg", moving_mass_kg, "kg")?;
        non_negative("particle_mass_kg", particle_mass_kg, "kg")?;
        let g_mps2 = drive.gravity_mps2();
        let target = SineMotion::new(drive);
        Ok(match kind {
            ShakerKind::Prescribed => Shaker::Prescribed(target),
            ShakerKind::Electrodynamic => {
                let p = spec.electrodynamic()?;
                let model = Electrodynamic::new(p, moving_mass_kg, particle_mass_kg, &target);
                let kin = model.kinematics(0.0, 1.0, 0.0);
                Shaker::Electrodynamic(Box::new(ElectrodynamicShaker {
                    target,
                    model,
                    g_mps2,
                    kin,
                }))
            }
        })
    }

    /// The motion the drive aims at: `X sin wt`.
    pub fn target(&self) -> &SineMotion {
        match self {
            Shaker::Prescribed(s) => s,
            Shaker::Electrodynamic(ed) => &ed.target,
        }
    }

    /// Kind of drive.
    pub fn kind(&self) -> ShakerKind {
        match self {
            Shaker::Prescribed(_) => ShakerKind::Prescribed,
            Shaker::Electrodynamic(_) => ShakerKind::Electrodynamic,
        }
    }

    /// Time of the last [`EnclosureMotion::advance`], s.
    pub fn time_s(&self) -> f64 {
        self.target().time_s()
    }

    /// Displacement amplitude of the target motion, `Gamma g / w^2`, m.
    pub fn amplitude_m(&self) -> f64 {
        self.target().amplitude_m()
    }

    /// Coil current at the last time, A (electrodynamic).
    pub fn coil_current_a(&self) -> Option<f64> {
        match self {
            Shaker::Prescribed(_) => None,
            Shaker::Electrodynamic(ed) => Some(ed.model.current_a),
        }
    }

    /// How the drive went so far.
    pub fn report(&self) -> ShakerReport {
        let target = self.target();
        let gamma = target.gamma();
        match self {
            Shaker::Prescribed(s) => ShakerReport {
                kind: ShakerKind::Prescribed,
                target_gamma: gamma,
                achieved_gamma: Some(gamma),
                fundamental_phase_rad: 0.0,
                drive_amplitude_v: None,
                cycles_measured: (s.time_s() * s.freq_hz() + 1e-9).floor() as u32,
                control_updates: 0,
                peak_current_a: None,
            },
            Shaker::Electrodynamic(ed) => {
                let wanted = Complex64::new(-gamma * ed.g_mps2, 0.0);
                let fit = ed.model.last_fit;
                ShakerReport {
                    kind: ShakerKind::Electrodynamic,
                    target_gamma: gamma,
                    achieved_gamma: fit.map(|a| a.norm() / ed.g_mps2),
                    fundamental_phase_rad: match fit {
                        Some(a) if wanted.norm() > 0.0 => (a / wanted).arg(),
                        _ => 0.0,
                    },
                    drive_amplitude_v: Some(ed.model.drive.norm()),
                    cycles_measured: ed.model.cycles,
                    control_updates: ed.model.updates,
                    peak_current_a: Some(ed.model.peak_current_a),
                }
            }
        }
    }

    /// Infinity norm of `Phi^steps`, the step matrix at `dt_s` raised to
    /// `steps`: how much a deviation from the steady state can grow over that
    /// many steps. Tending to 0 means the integration is stable. `None` for the
    /// prescribed drive.
    pub fn step_matrix_norm_after(&self, dt_s: f64, steps: u32) -> Option<f64> {
        let Shaker::Electrodynamic(ed) = self else {
            return None;
        };
        let (phi, _) = zero_order_hold(&ed.model.a, ed.model.force_input(), dt_s);
        let mut m = phi;
        let mut p = DMat3::IDENTITY;
        let mut n = steps;
        while n > 0 {
            if n & 1 == 1 {
                p *= m;
            }
            m *= m;
            n >>= 1;
        }
        Some(
            (0..3)
                .map(|i| p.row(i).abs().element_sum())
                .fold(0.0, f64::max),
        )
    }
}

impl EnclosureMotion for Shaker {
    #[inline]
    fn advance(&mut self, t_s: f64, dt_s: f64, particle_force_n: f64) -> Kinematics {
        match self {
            Shaker::Prescribed(s) => s.advance(t_s, dt_s, particle_force_n),
            Shaker::Electrodynamic(ed) => {
                let (w, f) = (ed.target.omega(), ed.target.freq_hz());
                ed.target.advance(t_s, dt_s, particle_force_n);
                ed.kin = ed.model.advance(w, f, t_s, dt_s, particle_force_n);
                ed.kin
            }
        }
    }

    fn kinematics(&self) -> Kinematics {
        match self {
            Shaker::Prescribed(s) => s.kinematics(),
            Shaker::Electrodynamic(ed) => ed.kin,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rig::RigFile;
    use std::f64::consts::PI;

    const G: f64 = 9.81;

    /// A drive at `freq_hz` and `gamma` under `G`.
    fn drive(freq_hz: f64, gamma: f64) -> Drive {
        Drive::new(freq_hz, gamma, G).expect("valid drive")
    }

    fn thesis() -> RigSpec {
        RigSpec::builtin("thesis-shaker").expect("built in")
    }

    #[test]
    fn thesis_limits_reproduce_the_thesis() {
        let rig = thesis();
        let stroke = check_limits(&rig, &drive(20.0, 13.0))
            .expect_err("stroke")
            .to_string();
        assert!(
            stroke.starts_with("Gamma 13 at 20 Hz needs 16.2 mm peak-to-peak stroke; the thesis-shaker rig allows 15 mm (stroke limit"),
            "{stroke}"
        );
        assert!(
            stroke.ends_with("lower gamma or use the ideal rig"),
            "{stroke}"
        );
        let msg = check_limits(&rig, &drive(20.0, 15.0))
            .expect_err("stroke")
            .to_string();
        assert!(msg.contains("needs 18.6 mm"), "{msg}");
        let accel = check_limits(&rig, &drive(40.0, 41.0))
            .expect_err("accel")
            .to_string();
        assert!(
            accel.starts_with("Gamma 41 at 40 Hz needs 402.2 m/s^2 peak acceleration; the thesis-shaker rig allows 392.4 m/s^2 (acceleration limit"),
            "{accel}"
        );
        assert!(accel.contains("the ideal rig"), "{accel}");
        for (f, gamma) in [(20.0, 12.0), (40.0, 40.0), (160.0, 40.0), (1024.0, 40.0)] {
            check_limits(&rig, &drive(f, gamma))
                .unwrap_or_else(|e| panic!("{f} Hz Gamma {gamma}: {e}"));
        }
        let ideal = RigSpec::builtin("ideal").expect("built in");
        check_limits(&ideal, &drive(20.0, 100.0)).expect("ideal has no limits");
        // Shaker::new refuses the same.
        assert!(matches!(
            Shaker::new(&rig, ShakerKind::Prescribed, &drive(20.0, 13.0), 0.25, 0.0),
            Err(RigError::StrokeLimit { .. })
        ));
        assert!(
            Shaker::new(
                &ideal,
                ShakerKind::Prescribed,
                &drive(20.0, 100.0),
                0.25,
                0.0
            )
            .is_ok()
        );
        let err = Shaker::new(
            &ideal,
            ShakerKind::Electrodynamic,
            &drive(20.0, 10.0),
            0.25,
            0.0,
        )
        .expect_err("no parameters");
        assert!(err.to_string().contains("[shaker.electrodynamic]"), "{err}");
    }

    #[test]
    fn prescribed_kinematics_are_exact() {
        let rig = RigSpec::builtin("ideal").expect("built in");
        let mut s = Shaker::new(&rig, ShakerKind::Prescribed, &drive(40.0, 20.0), 0.25, 0.03)
            .expect("valid");
        let w = 2.0 * PI * 40.0;
        let x = 20.0 * G / (w * w);
        for n in [1u32, 17, 25_000, 123_457] {
            let t = f64::from(n) * 1e-6;
            let k = s.advance(t, 1e-6, 1e3);
            assert_eq!(s.kinematics(), k);
            assert!((k.displacement_m - x * (w * t).sin()).abs() < 1e-12);
            assert!((k.velocity_mps - x * w * (w * t).cos()).abs() < 1e-12);
            assert!((k.acceleration_mps2 + 20.0 * G * (w * t).sin()).abs() < 1e-12);
        }
        assert_eq!(s.report().achieved_gamma, Some(20.0));
    }

    /// Runs `cycles` cycles at `dt_s` with the force `f(t, cycle_phase)`;
    /// returns the shaker and the acceleration of the last cycle.
    fn run(
        rig: &RigSpec,
        freq: f64,
        gamma: f64,
        dt_s: f64,
        cycles: u32,
        particle_mass_kg: f64,
        force: impl Fn(f64) -> f64,
    ) -> (Shaker, Vec<(f64, f64)>) {
        let mut s = Shaker::new(
            rig,
            ShakerKind::Electrodynamic,
            &drive(freq, gamma),
            0.25,
            particle_mass_kg,
        )
        .expect("valid");
        let steps = (f64::from(cycles) / freq / dt_s).round() as u64;
        let last = ((1.0 / freq) / dt_s).round() as u64;
        let mut tail = Vec::with_capacity(last as usize + 1);
        let mut f = 0.0;
        for n in 1..=steps {
            let t = n as f64 * dt_s;
            s.advance(t, dt_s, f);
            f = force(t);
            let a = s.kinematics().acceleration_mps2;
            assert!(a.is_finite(), "diverged at {t} s");
            if n > steps - last {
                tail.push((t, a));
            }
        }
        (s, tail)
    }

    #[test]
    fn empty_electrodynamic_shaker_reaches_gamma() {
        let rig = thesis();
        for freq in [20.0, 40.0, 160.0] {
            let gamma = if freq == 20.0 { 12.0 } else { 20.0 };
            let (s, tail) = run(&rig, freq, gamma, 1e-6, 10, 0.0, |_| 0.0);
            let r = s.report();
            let achieved = r.achieved_gamma.expect("whole cycles");
            assert!((achieved / gamma - 1.0).abs() < 0.01, "{freq} Hz: {r:?}");
            assert!(r.fundamental_phase_rad.abs() < 0.01, "{freq} Hz: {r:?}");
            // Pure sine: no sample departs from -Gamma g sin(wt) by 1 %.
            let w = 2.0 * PI * freq;
            let worst = tail
                .iter()
                .map(|(t, a)| (a + gamma * G * (w * t).sin()).abs())
                .fold(0.0, f64::max);
            assert!(worst < 0.01 * gamma * G, "{freq} Hz: {worst}");
            assert!(r.drive_amplitude_v.expect("ed") < 10.0, "{r:?}");
        }
    }

    /// Two 50 us half-sine impacts of 200 N per cycle, up at phase 0.05 and
    /// down at phase 0.55, as a bouncing bed hits base and lid.
    fn impacts(freq: f64) -> impl Fn(f64) -> f64 {
        move |t: f64| {
            let phase = (t * freq).fract() / freq;
            let pulse = |t0: f64| {
                let s = phase - t0;
                if (0.0..50e-6).contains(&s) {
                    200.0 * (PI * s / 50e-6).sin()
                } else {
                    0.0
                }
            };
            pulse(0.05 / freq) - pulse(0.55 / freq)
        }
    }

    #[test]
    fn impacts_show_in_the_acceleration_and_the_integration_is_stable() {
        let rig = thesis();
        let (freq, gamma) = (40.0, 20.0);
        let w = 2.0 * PI * freq;
        let mut fundamentals = Vec::new();
        for dt in [1e-6, 5e-6] {
            let s0 = Shaker::new(
                &rig,
                ShakerKind::Electrodynamic,
                &drive(freq, gamma),
                0.25,
                0.0,
            )
            .expect("valid");
            // Deviations from the steady state die out: ||Phi^n|| -> 0.
            let n = (0.5 / dt) as u32;
            let norm = s0.step_matrix_norm_after(dt, n).expect("ed");
            assert!(norm < 1e-3, "dt {dt}: ||Phi^n|| = {norm}");
            let (s, tail) = run(&rig, freq, gamma, dt, 30, 0.0, impacts(freq));
            let deviation = |&(t, a): &(f64, f64)| (a + gamma * G * (w * t).sin()).abs();
            let peak_dev = tail.iter().map(deviation).fold(0.0, f64::max);
            assert!(peak_dev > 0.1 * gamma * G, "dt {dt}: spikes {peak_dev}");
            // Spike of 200 N on 0.45 kg, bounded: the integration is stable.
            assert!(peak_dev < 600.0, "dt {dt}: {peak_dev}");
            // Away from the impacts (more than 2 ms after either), the motion is
            // back within 10 % of the sine: the spikes sit at the impact times.
            let near_impact = |t: f64| {
                let phase = (t * freq).fract();
                [0.05, 0.55]
                    .iter()
                    .any(|p0| (0.0..0.08).contains(&(phase - p0)))
            };
            let quiet_dev = tail
                .iter()
                .filter(|(t, _)| !near_impact(*t))
                .map(deviation)
                .fold(0.0, f64::max);
            assert!(
                quiet_dev < 0.1 * gamma * G,
                "dt {dt}: {quiet_dev} between impacts"
            );
            let r = s.report();
            let achieved = r.achieved_gamma.expect("whole cycles");
            assert!((achieved / gamma - 1.0).abs() < 0.01, "dt {dt}: {r:?}");
            assert!(r.control_updates >= 29, "{r:?}");
            fundamentals.push(achieved);
        }
        assert!((fundamentals[0] - fundamentals[1]).abs() < 1e-3 * gamma);
    }

    #[test]
    fn controller_corrects_a_payload_mismatch() {
        // Particles of 0.1 kg resting on the base, modelled as a rigid extra
        // mass (F_p = -m a of the previous step); the feed-forward counts only
        // half of it.
        let mut rig = thesis();
        let extra = 0.1;
        for closed in [false, true] {
            if let Some(ed) = rig.shaker.electrodynamic.as_mut() {
                ed.closed_loop = closed;
            }
            let mut s = Shaker::new(
                &rig,
                ShakerKind::Electrodynamic,
                &drive(40.0, 20.0),
                0.25,
                extra,
            )
            .expect("valid");
            let dt = 1e-6;
            let mut f = 0.0;
            for n in 1..=(20.0 / 40.0 / dt) as u64 {
                s.advance(n as f64 * dt, dt, f);
                f = -extra * s.kinematics().acceleration_mps2;
            }
            let r = s.report();
            let err = (r.achieved_gamma.expect("whole cycles") / 20.0 - 1.0).abs();
            if closed {
                assert!(err < 0.002, "closed loop: {r:?}");
                assert!(r.fundamental_phase_rad.abs() < 0.002, "{r:?}");
            } else {
                assert!(err > 0.01, "the mismatch should show open loop: {r:?}");
            }
        }
    }
}
