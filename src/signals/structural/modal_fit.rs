//! Modal parameters of a measured receptance FRF with several modes: each
//! mode's natural frequency, damping ratio and modal constant, with their
//! one-sigma errors from the fit's residuals. This is the modal extraction a
//! lab runs on a host structure before a damper is fitted to it (the host
//! tests of thesis Section 2.3.1: Terzioglu, *Vibrational energy dissipation
//! mechanisms in granular dampers*, PhD thesis, University of Sheffield,
//! 2023), on any FRF vlab's host commands write.
//!
//! # The model
//!
//! The receptance (displacement per force, m/N) of a viscously damped
//! structure, over a band, as a sum of modes (Ewins, *Modal Testing: Theory,
//! Practice and Application*, 2nd ed., Sections 2.3 and 4.4, the rational
//! fraction form of the FRF in partial fractions):
//!
//! ```text
//! H(ω) = Σ_r A_r / (ω_r² − ω² + 2 i ζ_r ω_r ω)  +  U  +  L / ω²
//! ```
//!
//! `ω_r = 2π f_r` the mode's undamped natural frequency, `ζ_r` its damping
//! ratio, `A_r` its modal constant (complex, 1/kg: `φ_j φ_k / m_r` for a
//! proportionally damped structure, real then; a phase between the channels
//! or non-proportional damping makes it complex). `U` (m/N) and `L` (1/kg)
//! are the residual terms of modes outside the band (Ewins Section 4.4.3):
//! the modes above it act as a flexibility, the ones below as a mass,
//! `L = −1 / M`; both complex, both optional. The loss factor is `η = 2ζ`,
//! as everywhere in [`super`].
//!
//! # The fit
//!
//! 1. **Peaks.** The `modes` most prominent local maxima of `|H|`
//!    (prominence: the peak over the higher of the lowest points either side
//!    before a higher point), so that a small mode beside a large one is
//!    found and the noise's ripples are not.
//! 2. **One mode at a time** (Ewins' inverse, or Dobson's, line fit): near a
//!    peak one mode dominates and `A / H = ω_r² − ω² + i 2ζ_r ω_r ω` is
//!    linear in `ω_r²`, `2ζ_r ω_r` and `A`: a weighted least-squares over
//!    the points around the peak gives the starting `ω_r` and `ζ_r`, however
//!    coarsely the peak is sampled (the half-power points need not lie
//!    between two lines).
//! 3. **The linear part.** With the `ω_r`, `ζ_r` fixed the model is linear
//!    in the `A_r`, `U` and `L`: one least-squares gives their start.
//! 4. **Levenberg–Marquardt** over every parameter at once (Marquardt's
//!    damping `λ diag(JᵀJ)`, the normal equations scaled to unit diagonal),
//!    minimising `Σ_k |H_model(ω_k) − H_k|² / |H_k|²`: the residuals are
//!    relative, so the off-resonance lines and a small mode beside a large
//!    one count, and an FRF whose error is a fraction of its value (H1 from
//!    averaged blocks) has residuals of one size everywhere.
//!
//! The one-sigma errors are the fit's covariance `s² (JᵀJ)⁻¹` at the
//! minimum, `s²` the weighted residuals' variance over `2N − P` (N
//! frequencies, two real residuals each, P parameters): right when the
//! FRF's relative errors are independent from line to line and of one size;
//! a bias (a transient left in the record, leakage) is not in them.

use super::*;

/// The most modes one fit takes.
pub const MAX_MODES: usize = 12;

/// Parameters of one mode in the fit's parameter vector: `ω_r` (rad/s),
/// `ζ_r`, `Re A_r`, `Im A_r` (1/kg).
const PER_MODE: usize = 4;

/// Parameters of the residual terms: `Re U`, `Im U` (m/N), `Re L`, `Im L`
/// (1/kg).
const RESIDUAL_PARAMS: usize = 4;

/// Iterations after which the refinement gives up.
const MAX_ITERATIONS: usize = 500;

/// Marquardt's damping beyond which no step lowers the cost: the minimum
/// to rounding.
const MAX_LAMBDA: f64 = 1e16;

/// A step that moves the model's receptance by less than this fraction of
/// itself (rms over the lines) ends the refinement.
const STEP_TOLERANCE_REL: f64 = 1e-10;

/// What a fit is asked for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ModalFitOptions {
    /// Modes to fit: the most prominent peaks of `|H|`, 1 to [`MAX_MODES`].
    pub modes: usize,
    /// Fit the residual terms `U + L / ω²` of the modes outside the band.
    pub residuals: bool,
}

/// One fitted mode. A `*_stderr` is the parameter's one-sigma error from
/// the fit's residuals; `None` where the fit leaves no degree of freedom for
/// it or its covariance is singular.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct FittedMode {
    /// Undamped natural frequency `ω_r / 2π`, Hz.
    pub freq_hz: f64,
    /// Its one-sigma error, Hz.
    pub freq_hz_stderr: Option<f64>,
    /// Viscous damping ratio `ζ_r`, 1.
    pub damping_ratio: f64,
    /// Its one-sigma error, 1.
    pub damping_ratio_stderr: Option<f64>,
    /// Loss factor `η = 2ζ_r`, 1.
    pub loss_factor: f64,
    /// Its one-sigma error, 1.
    pub loss_factor_stderr: Option<f64>,
    /// Real part of the modal constant `A_r`, 1/kg (m/N times (rad/s)²).
    pub modal_constant_re_per_kg: f64,
    /// Its one-sigma error, 1/kg.
    pub modal_constant_re_stderr_per_kg: Option<f64>,
    /// Imaginary part of the modal constant, 1/kg.
    pub modal_constant_im_per_kg: f64,
    /// Its one-sigma error, 1/kg.
    pub modal_constant_im_stderr_per_kg: Option<f64>,
    /// The line whose peak the mode was started from, Hz.
    pub peak_freq_hz: f64,
}

/// The residual terms `U + L / ω²` of the modes outside the band.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct ResidualTerms {
    /// `Re U`, m/N (the modes above the band, a flexibility).
    pub upper_re_m_per_n: f64,
    /// `Im U`, m/N.
    pub upper_im_m_per_n: f64,
    /// `Re L`, 1/kg (the modes below the band, `−1 / M` of a mass).
    pub lower_re_per_kg: f64,
    /// `Im L`, 1/kg.
    pub lower_im_per_kg: f64,
}

/// The result of [`fit_modes`].
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct ModalFit {
    /// The modes, ascending in frequency.
    pub modes: Vec<FittedMode>,
    /// The residual terms, if fitted.
    pub residuals: Option<ResidualTerms>,
    /// Frequencies fitted.
    pub points: usize,
    /// Real parameters fitted.
    pub parameters: usize,
    /// `s`: the rms of the relative residuals `(H_model − H) / |H|`, per
    /// real and imaginary part, over `2N − P` degrees of freedom.
    pub residual_rms_rel: f64,
    /// Levenberg–Marquardt iterations taken.
    pub iterations: usize,
}

impl ModalFit {
    /// The fitted model's receptance at `freq_hz`, m/N.
    pub fn receptance_m_per_n(&self, freq_hz: f64) -> Complex64 {
        model_value(&self.parameter_vector(), self.layout(), 2.0 * PI * freq_hz)
    }

    fn layout(&self) -> Layout {
        Layout {
            modes: self.modes.len(),
            residuals: self.residuals.is_some(),
        }
    }

    fn parameter_vector(&self) -> Vec<f64> {
        let mut p: Vec<f64> = self
            .modes
            .iter()
            .flat_map(|m| {
                [
                    2.0 * PI * m.freq_hz,
                    m.damping_ratio,
                    m.modal_constant_re_per_kg,
                    m.modal_constant_im_per_kg,
                ]
            })
            .collect();
        if let Some(r) = self.residuals {
            p.extend([
                r.upper_re_m_per_n,
                r.upper_im_m_per_n,
                r.lower_re_per_kg,
                r.lower_im_per_kg,
            ]);
        }
        p
    }
}

/// The receptance `Σ_r A_r / (ω_r² − ω² + 2iζ_r ω_r ω)` of `modes` (each
/// `(freq_hz, damping_ratio, modal_constant_per_kg)`) at `freq_hz`, m/N: the
/// model [`fit_modes`] fits, without residual terms.
pub fn modal_receptance_m_per_n(modes: &[(f64, f64, Complex64)], freq_hz: f64) -> Complex64 {
    let omega = 2.0 * PI * freq_hz;
    modes
        .iter()
        .map(|&(f_hz, zeta, a)| a / denominator(2.0 * PI * f_hz, zeta, omega))
        .sum()
}

/// Fits `options.modes` modes (and, if asked, the residual terms) to the
/// receptance `receptance_m_per_n` (m/N) at `freq_hz` (the module docs).
///
/// `freq_hz` positive and strictly increasing, the receptance finite and
/// nonzero at every line (each line is weighed by `1 / |H|`), at least as
/// many lines as the fit has parameters (4 a mode, 4 more with residuals).
///
/// Errors: lengths differ, a value non-finite, out of range or not
/// increasing, too few lines, fewer peaks than modes asked for, or a fit
/// that cannot be solved (all named in the error).
pub fn fit_modes(
    freq_hz: &[f64],
    receptance_m_per_n: &[Complex64],
    options: &ModalFitOptions,
) -> Result<ModalFit> {
    let layout = check_fit_inputs(freq_hz, receptance_m_per_n, options)?;
    let data = FrfData::new(freq_hz, receptance_m_per_n);
    let magnitude: Vec<f64> = receptance_m_per_n.iter().map(|h| h.norm()).collect();
    let peaks = pick_peaks(&magnitude, options.modes);
    if peaks.len() < options.modes {
        return Err(StructuralError::TooFewResonances {
            asked: options.modes,
            found: peaks.len(),
            min_freq_hz: freq_hz[0],
            max_freq_hz: freq_hz[freq_hz.len() - 1],
        });
    }
    let mut params = vec![0.0; layout.parameters()];
    for (r, &peak) in peaks.iter().enumerate() {
        let (omega_r, zeta) = sdof_start(&data, peak);
        params[PER_MODE * r] = omega_r;
        params[PER_MODE * r + 1] = zeta;
    }
    fit_linear_terms(&data, layout, &mut params)?;
    let refined = levenberg_marquardt(&data, layout, params)?;
    Ok(fit_result(&data, layout, &refined, &peaks, freq_hz))
}

/// Checks the inputs of [`fit_modes`] and returns the parameters' layout.
fn check_fit_inputs(
    freq_hz: &[f64],
    receptance_m_per_n: &[Complex64],
    options: &ModalFitOptions,
) -> Result<Layout> {
    if options.modes == 0 || options.modes > MAX_MODES {
        return Err(invalid(
            "modes",
            options.modes as f64,
            "1",
            format!("must be an integer from 1 to {MAX_MODES}"),
        ));
    }
    if freq_hz.len() != receptance_m_per_n.len() {
        return Err(StructuralError::LengthMismatch {
            first: "freq_hz",
            first_len: freq_hz.len(),
            second: "receptance_m_per_n",
            second_len: receptance_m_per_n.len(),
        });
    }
    let layout = Layout {
        modes: options.modes,
        residuals: options.residuals,
    };
    check_min_len(
        "freq_hz",
        freq_hz,
        layout.parameters().max(3),
        "a modal fit (one line per parameter: 4 a mode, 4 more with residual terms)",
    )?;
    check_finite("freq_hz", freq_hz)?;
    let re: Vec<f64> = receptance_m_per_n.iter().map(|h| h.re).collect();
    let im: Vec<f64> = receptance_m_per_n.iter().map(|h| h.im).collect();
    check_finite("receptance_re_m_per_n", &re)?;
    check_finite("receptance_im_m_per_n", &im)?;
    if let Some(k) =
        (0..freq_hz.len()).find(|&k| freq_hz[k] <= 0.0 || (k > 0 && freq_hz[k] <= freq_hz[k - 1]))
    {
        return Err(invalid(
            "freq_hz",
            freq_hz[k],
            "Hz",
            format!("must be positive and strictly increasing (line {k})"),
        ));
    }
    if let Some(k) = receptance_m_per_n.iter().position(|h| h.norm() == 0.0) {
        return Err(invalid(
            "receptance_m_per_n",
            0.0,
            "m/N",
            format!(
                "must be nonzero at every line: the fit weighs each by 1 / |H| (zero at {} Hz)",
                freq_hz[k]
            ),
        ));
    }
    Ok(layout)
}

// ---------------------------------------------------------------------------
// The model
// ---------------------------------------------------------------------------

/// How the parameter vector is laid out: [`PER_MODE`] a mode, then the
/// residual terms if fitted.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Layout {
    modes: usize,
    residuals: bool,
}

impl Layout {
    fn parameters(self) -> usize {
        PER_MODE * self.modes + if self.residuals { RESIDUAL_PARAMS } else { 0 }
    }
}

/// The FRF to fit, in angular frequency, with each line's weight `1 / |H|`.
struct FrfData<'a> {
    omega_rad_s: Vec<f64>,
    h_m_per_n: &'a [Complex64],
    weight: Vec<f64>,
}

impl<'a> FrfData<'a> {
    fn new(freq_hz: &[f64], h_m_per_n: &'a [Complex64]) -> Self {
        FrfData {
            omega_rad_s: freq_hz.iter().map(|f| 2.0 * PI * f).collect(),
            h_m_per_n,
            weight: h_m_per_n.iter().map(|h| 1.0 / h.norm()).collect(),
        }
    }

    fn len(&self) -> usize {
        self.omega_rad_s.len()
    }
}

/// `ω_r² − ω² + 2iζ ω_r ω`.
fn denominator(omega_r: f64, zeta: f64, omega: f64) -> Complex64 {
    Complex64::new(
        omega_r * omega_r - omega * omega,
        2.0 * zeta * omega_r * omega,
    )
}

/// The model's receptance at `omega` (rad/s).
fn model_value(p: &[f64], layout: Layout, omega: f64) -> Complex64 {
    let mut h: Complex64 = (0..layout.modes)
        .map(|r| {
            let q = &p[PER_MODE * r..PER_MODE * (r + 1)];
            Complex64::new(q[2], q[3]) / denominator(q[0], q[1], omega)
        })
        .sum();
    if layout.residuals {
        let q = &p[PER_MODE * layout.modes..];
        h += Complex64::new(q[0], q[1]) + Complex64::new(q[2], q[3]) / (omega * omega);
    }
    h
}

/// The model's receptance at `omega` and its derivative by each parameter
/// (written into `d`, one per parameter).
fn model_with_derivatives(p: &[f64], layout: Layout, omega: f64, d: &mut [Complex64]) -> Complex64 {
    let i = Complex64::new(0.0, 1.0);
    let mut h = Complex64::new(0.0, 0.0);
    for r in 0..layout.modes {
        let q = &p[PER_MODE * r..PER_MODE * (r + 1)];
        let (omega_r, zeta, a) = (q[0], q[1], Complex64::new(q[2], q[3]));
        let inv = 1.0 / denominator(omega_r, zeta, omega);
        let term = a * inv;
        h += term;
        let dd = &mut d[PER_MODE * r..PER_MODE * (r + 1)];
        dd[0] = -term * inv * Complex64::new(2.0 * omega_r, 2.0 * zeta * omega);
        dd[1] = -term * inv * Complex64::new(0.0, 2.0 * omega_r * omega);
        dd[2] = inv;
        dd[3] = i * inv;
    }
    if layout.residuals {
        let base = PER_MODE * layout.modes;
        let q = &p[base..];
        let inv_w2 = 1.0 / (omega * omega);
        h += Complex64::new(q[0], q[1]) + Complex64::new(q[2], q[3]) * inv_w2;
        d[base] = Complex64::new(1.0, 0.0);
        d[base + 1] = i;
        d[base + 2] = Complex64::new(inv_w2, 0.0);
        d[base + 3] = Complex64::new(0.0, inv_w2);
    }
    h
}

/// Half the sum of the squared weighted residuals.
fn cost(data: &FrfData, layout: Layout, p: &[f64]) -> f64 {
    (0..data.len())
        .map(|k| {
            let e =
                (model_value(p, layout, data.omega_rad_s[k]) - data.h_m_per_n[k]) * data.weight[k];
            0.5 * e.norm_sqr()
        })
        .sum()
}

/// The Gauss–Newton normal equations at `p`: `JᵀJ` (row-major), `Jᵀr` and
/// the cost, `J` the weighted residuals' Jacobian.
struct Normal {
    jtj: Vec<f64>,
    jtr: Vec<f64>,
    cost: f64,
}

fn normal_equations(data: &FrfData, layout: Layout, p: &[f64]) -> Normal {
    let n = layout.parameters();
    let mut normal = Normal {
        jtj: vec![0.0; n * n],
        jtr: vec![0.0; n],
        cost: 0.0,
    };
    let mut d = vec![Complex64::new(0.0, 0.0); n];
    for k in 0..data.len() {
        let w = data.weight[k];
        let e = (model_with_derivatives(p, layout, data.omega_rad_s[k], &mut d)
            - data.h_m_per_n[k])
            * w;
        normal.cost += 0.5 * e.norm_sqr();
        for a in 0..n {
            let ja = d[a] * w;
            normal.jtr[a] += ja.re * e.re + ja.im * e.im;
            for (b, &db) in d.iter().enumerate().skip(a) {
                let jb = db * w;
                normal.jtj[a * n + b] += ja.re * jb.re + ja.im * jb.im;
            }
        }
    }
    for a in 0..n {
        for b in 0..a {
            normal.jtj[a * n + b] = normal.jtj[b * n + a];
        }
    }
    normal
}

// ---------------------------------------------------------------------------
// Starting values
// ---------------------------------------------------------------------------

/// The indices of the `count` most prominent interior local maxima of
/// `magnitude`, ascending; fewer if there are fewer maxima.
fn pick_peaks(magnitude: &[f64], count: usize) -> Vec<usize> {
    let n = magnitude.len();
    let mut peaks: Vec<(usize, f64)> = (1..n.saturating_sub(1))
        .filter(|&i| magnitude[i] > magnitude[i - 1] && magnitude[i] >= magnitude[i + 1])
        .map(|i| (i, prominence(magnitude, i)))
        .collect();
    peaks.sort_by(|a, b| b.1.total_cmp(&a.1).then(a.0.cmp(&b.0)));
    let mut chosen: Vec<usize> = peaks.into_iter().take(count).map(|(i, _)| i).collect();
    chosen.sort_unstable();
    chosen
}

/// How far the peak at `i` stands out: its magnitude over the higher of
/// the lowest magnitudes either side before a higher point (or the end).
fn prominence(magnitude: &[f64], i: usize) -> f64 {
    let peak = magnitude[i];
    let lowest = |range: &mut dyn Iterator<Item = usize>| {
        let mut low = peak;
        for j in range {
            if magnitude[j] > peak {
                break;
            }
            low = low.min(magnitude[j]);
        }
        low
    };
    let left = lowest(&mut (0..i).rev());
    let right = lowest(&mut (i + 1..magnitude.len()));
    peak / left.max(right)
}

/// Starting `(ω_r, ζ_r)` of the mode whose peak is line `peak`: Ewins'
/// inverse line fit of one mode over the lines around it (the module docs),
/// each line's equation weighed by `|H|`; the peak's line and a damping of
/// half the line spacing over its frequency if that fit fails.
fn sdof_start(data: &FrfData, peak: usize) -> (f64, f64) {
    let (lo, hi) = neighbourhood(data, peak);
    let rows = (lo..=hi).flat_map(|k| {
        let w = data.omega_rad_s[k];
        let inv = 1.0 / data.h_m_per_n[k];
        let scale = data.h_m_per_n[k].norm();
        // A / H = ω_r² − ω² + i g ω, unknowns [ω_r², g, Re A, Im A].
        [
            ([scale, 0.0, -inv.re * scale, inv.im * scale], w * w * scale),
            ([0.0, w * scale, -inv.im * scale, -inv.re * scale], 0.0),
        ]
    });
    let omega_peak = data.omega_rad_s[peak];
    let fitted = least_squares::<4>(rows).and_then(|x| {
        let omega_r = x[0].sqrt();
        let zeta = x[1] / (2.0 * omega_r);
        let inside = (data.omega_rad_s[lo]..=data.omega_rad_s[hi]).contains(&omega_r);
        (x[0] > 0.0 && zeta > 0.0 && zeta < 1.0 && inside).then_some((omega_r, zeta))
    });
    fitted.unwrap_or_else(|| {
        let spacing = data.omega_rad_s[hi] - data.omega_rad_s[lo];
        let zeta = (0.5 * spacing / (hi - lo).max(1) as f64 / omega_peak).max(1e-4);
        (omega_peak, zeta)
    })
}

/// The lines around `peak` one mode's line fit takes: out to where `|H|`
/// falls below a quarter of the peak's, at least 2 and at most 8 a side
/// (as the record allows).
fn neighbourhood(data: &FrfData, peak: usize) -> (usize, usize) {
    let magnitude = |k: usize| data.h_m_per_n[k].norm();
    let floor = 0.25 * magnitude(peak);
    let mut lo = peak;
    while lo > 0 && peak - lo < 8 && (peak - lo < 2 || magnitude(lo - 1) >= floor) {
        lo -= 1;
    }
    let mut hi = peak;
    while hi + 1 < data.len() && hi - peak < 8 && (hi - peak < 2 || magnitude(hi + 1) >= floor) {
        hi += 1;
    }
    (lo, hi)
}

/// Sets the parameters the model is linear in (the modal constants and the
/// residual terms) by weighted least squares, the `ω_r`, `ζ_r` held.
fn fit_linear_terms(data: &FrfData, layout: Layout, p: &mut [f64]) -> Result<()> {
    let n = layout.parameters();
    let linear: Vec<usize> = (0..n)
        .filter(|&j| j >= PER_MODE * layout.modes || j % PER_MODE >= 2)
        .collect();
    let m = linear.len();
    let mut a = vec![0.0; m * m];
    let mut b = vec![0.0; m];
    let mut d = vec![Complex64::new(0.0, 0.0); n];
    for k in 0..data.len() {
        let w = data.weight[k];
        model_with_derivatives(p, layout, data.omega_rad_s[k], &mut d);
        let h = data.h_m_per_n[k] * w;
        for (x, &ja) in linear.iter().enumerate() {
            let da = d[ja] * w;
            b[x] += da.re * h.re + da.im * h.im;
            for (y, &jb) in linear.iter().enumerate() {
                let db = d[jb] * w;
                a[x * m + y] += da.re * db.re + da.im * db.im;
            }
        }
    }
    let solution = solve_scaled(&a, &b, m).ok_or_else(|| StructuralError::ModalFitFailed {
        reason: "the modal constants' least squares is singular at the starting frequencies \
                 (two peaks at one frequency?)"
            .into(),
    })?;
    for (&j, v) in linear.iter().zip(solution) {
        p[j] = v;
    }
    Ok(())
}

// ---------------------------------------------------------------------------
// Levenberg–Marquardt
// ---------------------------------------------------------------------------

/// The refined parameters, the normal equations at them and the iterations
/// taken.
struct Refined {
    params: Vec<f64>,
    normal: Normal,
    iterations: usize,
}

/// Minimises [`cost`] from `p` by Levenberg–Marquardt (the module docs).
/// Ends when a step moves the model's receptance by less than
/// [`STEP_TOLERANCE_REL`] of itself, or no step however short lowers the cost (the minimum to
/// rounding).
fn levenberg_marquardt(data: &FrfData, layout: Layout, mut p: Vec<f64>) -> Result<Refined> {
    let mut normal = normal_equations(data, layout, &p);
    let mut lambda = 1e-3;
    for iteration in 1..=MAX_ITERATIONS {
        // A step is taken when it lowers the cost; otherwise (or when the
        // damped system has none) the damping grows, until no step however
        // short helps: the minimum to rounding.
        let mut taken = false;
        if let Some(step) = damped_step(&normal, lambda) {
            let trial: Vec<f64> = p.iter().zip(&step).map(|(a, b)| a + b).collect();
            let trial_cost = if physical(&trial, layout) {
                cost(data, layout, &trial)
            } else {
                f64::INFINITY
            };
            if trial_cost <= normal.cost {
                let small = scaled_step_sq(&normal, &step)
                    <= STEP_TOLERANCE_REL * STEP_TOLERANCE_REL * data.len() as f64;
                p = trial;
                normal = normal_equations(data, layout, &p);
                lambda = (lambda * 0.1).max(1e-12);
                taken = true;
                if small || normal.cost == 0.0 {
                    return Ok(Refined {
                        params: p,
                        normal,
                        iterations: iteration,
                    });
                }
            }
        }
        if !taken {
            lambda *= 10.0;
            if lambda > MAX_LAMBDA {
                return Ok(Refined {
                    params: p,
                    normal,
                    iterations: iteration,
                });
            }
        }
    }
    Err(StructuralError::ModalFitFailed {
        reason: format!(
            "the refinement did not converge in {MAX_ITERATIONS} iterations: fewer --modes, \
             or a band around the modes"
        ),
    })
}

/// `Σ_j δ_j² (JᵀJ)_jj`: about how far the step moves the model's weighted
/// (relative) receptance, summed in squares over the lines.
fn scaled_step_sq(normal: &Normal, step: &[f64]) -> f64 {
    let n = step.len();
    step.iter()
        .enumerate()
        .map(|(j, s)| s * s * normal.jtj[j * n + j])
        .sum()
}

/// Positive natural frequencies and damping ratios, every parameter finite.
fn physical(p: &[f64], layout: Layout) -> bool {
    p.iter().all(|v| v.is_finite())
        && (0..layout.modes).all(|r| p[PER_MODE * r] > 0.0 && p[PER_MODE * r + 1] > 0.0)
}

/// The step `δ` of `(JᵀJ + λ diag JᵀJ) δ = −Jᵀr`.
fn damped_step(normal: &Normal, lambda: f64) -> Option<Vec<f64>> {
    let n = normal.jtr.len();
    let mut a = normal.jtj.clone();
    for j in 0..n {
        a[j * n + j] *= 1.0 + lambda;
    }
    let minus_g: Vec<f64> = normal.jtr.iter().map(|g| -g).collect();
    solve_scaled(&a, &minus_g, n)
}

/// Solves the symmetric `n`×`n` system `a x = b` (row-major) after scaling
/// it to a unit diagonal (`D a D y = D b`, `x = D y`, `D = diag(a)^(−1/2)`),
/// by Gaussian elimination with partial pivoting; `None` if singular.
fn solve_scaled(a: &[f64], b: &[f64], n: usize) -> Option<Vec<f64>> {
    let d: Vec<f64> = (0..n)
        .map(|j| {
            let v = a[j * n + j];
            if v > 0.0 { 1.0 / v.sqrt() } else { 1.0 }
        })
        .collect();
    let mut m: Vec<f64> = (0..n * n).map(|k| a[k] * d[k / n] * d[k % n]).collect();
    let mut r: Vec<f64> = (0..n).map(|j| b[j] * d[j]).collect();
    let y = gauss_solve(&mut m, &mut r, n)?;
    Some(y.iter().zip(&d).map(|(y, d)| y * d).collect())
}

/// Gaussian elimination with partial pivoting of `m y = r` (`m` row-major
/// `n`×`n`, both overwritten); `None` if a pivot is zero or not finite or
/// the solution is not finite.
fn gauss_solve(m: &mut [f64], r: &mut [f64], n: usize) -> Option<Vec<f64>> {
    for col in 0..n {
        let pivot =
            (col..n).max_by(|&i, &j| m[i * n + col].abs().total_cmp(&m[j * n + col].abs()))?;
        let p = m[pivot * n + col];
        if p == 0.0 || !p.is_finite() {
            return None;
        }
        if pivot != col {
            for k in 0..n {
                m.swap(col * n + k, pivot * n + k);
            }
            r.swap(col, pivot);
        }
        for row in col + 1..n {
            let f = m[row * n + col] / p;
            if f == 0.0 {
                continue;
            }
            for k in col..n {
                m[row * n + k] -= f * m[col * n + k];
            }
            r[row] -= f * r[col];
        }
    }
    let mut y = vec![0.0; n];
    for row in (0..n).rev() {
        let known: f64 = (row + 1..n).map(|k| m[row * n + k] * y[k]).sum();
        y[row] = (r[row] - known) / m[row * n + row];
    }
    y.iter().all(|v| v.is_finite()).then_some(y)
}

/// The diagonal of `a⁻¹` (`a` symmetric, row-major `n`×`n`); `None` if
/// singular or a variance comes out negative.
fn inverse_diagonal_dense(a: &[f64], n: usize) -> Option<Vec<f64>> {
    (0..n)
        .map(|j| {
            let mut e = vec![0.0; n];
            e[j] = 1.0;
            let v = solve_scaled(a, &e, n)?[j];
            (v >= 0.0).then_some(v)
        })
        .collect()
}

// ---------------------------------------------------------------------------
// The result
// ---------------------------------------------------------------------------

/// The fit's modes, residual terms and errors from the refined parameters.
fn fit_result(
    data: &FrfData,
    layout: Layout,
    refined: &Refined,
    peaks: &[usize],
    freq_hz: &[f64],
) -> ModalFit {
    let n = layout.parameters();
    let dof = 2 * data.len() - n;
    let s2 = 2.0 * refined.normal.cost / dof as f64;
    let variances = if dof > 0 {
        inverse_diagonal_dense(&refined.normal.jtj, n)
    } else {
        None
    };
    let sigma = |j: usize| variances.as_ref().map(|v| (s2 * v[j]).sqrt());
    let p = &refined.params;
    let mut modes: Vec<FittedMode> = (0..layout.modes)
        .map(|r| {
            let j = PER_MODE * r;
            FittedMode {
                freq_hz: p[j] / (2.0 * PI),
                freq_hz_stderr: sigma(j).map(|s| s / (2.0 * PI)),
                damping_ratio: p[j + 1],
                damping_ratio_stderr: sigma(j + 1),
                loss_factor: 2.0 * p[j + 1],
                loss_factor_stderr: sigma(j + 1).map(|s| 2.0 * s),
                modal_constant_re_per_kg: p[j + 2],
                modal_constant_re_stderr_per_kg: sigma(j + 2),
                modal_constant_im_per_kg: p[j + 3],
                modal_constant_im_stderr_per_kg: sigma(j + 3),
                peak_freq_hz: freq_hz[peaks[r]],
            }
        })
        .collect();
    modes.sort_by(|a, b| a.freq_hz.total_cmp(&b.freq_hz));
    let residuals = layout.residuals.then(|| {
        let q = &p[PER_MODE * layout.modes..];
        ResidualTerms {
            upper_re_m_per_n: q[0],
            upper_im_m_per_n: q[1],
            lower_re_per_kg: q[2],
            lower_im_per_kg: q[3],
        }
    });
    ModalFit {
        modes,
        residuals,
        points: data.len(),
        parameters: n,
        residual_rms_rel: s2.sqrt(),
        iterations: refined.iterations,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::signals::testutil::{gaussian, rng};

    /// Two modes with complex modal constants (1/kg), 40 Hz and 95 Hz.
    fn two_modes() -> [(f64, f64, Complex64); 2] {
        [
            (40.0, 0.01, Complex64::new(0.5, 0.05)),
            (95.0, 0.02, Complex64::new(-1.2, 0.1)),
        ]
    }

    /// Lines from `from_hz` to `to_hz` (both included) `step_hz` apart.
    fn lines(from_hz: f64, to_hz: f64, step_hz: f64) -> Vec<f64> {
        let n = ((to_hz - from_hz) / step_hz + 1e-9).floor() as usize;
        (0..=n).map(|k| from_hz + step_hz * k as f64).collect()
    }

    fn frf(modes: &[(f64, f64, Complex64)], freq_hz: &[f64]) -> Vec<Complex64> {
        freq_hz
            .iter()
            .map(|&f| modal_receptance_m_per_n(modes, f))
            .collect()
    }

    fn options(modes: usize, residuals: bool) -> ModalFitOptions {
        ModalFitOptions { modes, residuals }
    }

    /// The largest relative error of the fitted modes against `exact`.
    fn worst_rel_error(fit: &ModalFit, exact: &[(f64, f64, Complex64)]) -> f64 {
        assert_eq!(fit.modes.len(), exact.len());
        fit.modes
            .iter()
            .zip(exact)
            .flat_map(|(m, &(f, z, a))| {
                let got_a = Complex64::new(m.modal_constant_re_per_kg, m.modal_constant_im_per_kg);
                [
                    (m.freq_hz - f).abs() / f,
                    (m.damping_ratio - z).abs() / z,
                    (m.loss_factor - 2.0 * z).abs() / (2.0 * z),
                    (got_a - a).norm() / a.norm(),
                ]
            })
            .fold(0.0, f64::max)
    }

    #[test]
    fn a_noiseless_two_mode_frf_gives_back_its_modes() {
        let exact = two_modes();
        let f = lines(20.0, 150.0, 0.5);
        for residuals in [false, true] {
            let fit = fit_modes(&f, &frf(&exact, &f), &options(2, residuals)).expect("fit");
            let worst = worst_rel_error(&fit, &exact);
            assert!(worst < 1e-6, "residuals {residuals}: worst {worst:e}");
            assert!(fit.residual_rms_rel < 1e-9, "{}", fit.residual_rms_rel);
            let back = fit.receptance_m_per_n(63.0);
            let want = modal_receptance_m_per_n(&exact, 63.0);
            assert!((back - want).norm() < 1e-8 * want.norm());
        }
    }

    #[test]
    fn a_sharp_mode_between_coarse_lines_and_a_small_one_beside_it_are_found() {
        // beam-2mode's shape: 40 Hz at 0.2 % (half-power band 0.16 Hz, lines
        // 1 Hz apart) and 251 Hz at 0.5 % with a peak 50 times lower; real
        // modal constants of opposite sign.
        let exact = [
            (40.0, 0.002, Complex64::new(0.34, 0.0)),
            (251.0, 0.005, Complex64::new(-0.71, 0.0)),
        ];
        let f = lines(20.3, 300.3, 1.0);
        let fit = fit_modes(&f, &frf(&exact, &f), &options(2, true)).expect("fit");
        let worst = worst_rel_error(&fit, &exact);
        assert!(worst < 1e-6, "worst {worst:e}");
    }

    #[test]
    fn residual_terms_take_up_the_modes_outside_the_band() {
        let exact = two_modes();
        let mut all = exact.to_vec();
        all.push((8.0, 0.02, Complex64::new(0.3, 0.0)));
        all.push((400.0, 0.02, Complex64::new(4.0, 0.0)));
        let f = lines(25.0, 130.0, 0.25);
        let h = frf(&all, &f);
        let without = worst_rel_error(&fit_modes(&f, &h, &options(2, false)).expect("fit"), &exact);
        let with = worst_rel_error(&fit_modes(&f, &h, &options(2, true)).expect("fit"), &exact);
        // Measured: 5.9e-3 with them (the terms are a mode's two-term
        // expansion, not the mode), 0.62 without.
        assert!(with < 1e-2, "with residual terms {with:e}");
        assert!(without > 20.0 * with, "without {without:e}, with {with:e}");
    }

    /// The fit of `exact` over `f` with relative complex noise of `sigma_rel`
    /// per part, seeded.
    fn noisy_fit(
        exact: &[(f64, f64, Complex64)],
        f: &[f64],
        sigma_rel: f64,
        seed: u64,
    ) -> ModalFit {
        let mut g = rng(seed);
        let h: Vec<Complex64> = frf(exact, f)
            .into_iter()
            .map(|h| {
                h * Complex64::new(
                    1.0 + sigma_rel * gaussian(&mut g),
                    sigma_rel * gaussian(&mut g),
                )
            })
            .collect();
        fit_modes(f, &h, &options(exact.len(), true)).expect("fit")
    }

    #[test]
    fn the_errors_of_noisy_fits_match_their_scatter_over_noise_seeds() {
        // Eight FRFs with 1 % relative noise, independent seeds: every
        // fitted parameter against the truth in units of its own printed
        // sigma. The rms of the 64 z-scores is 1 within about 0.1 when the
        // sigmas are right; the bounds are the project's 0.5 to 2.
        let exact = two_modes();
        let f = lines(20.0, 150.0, 0.5);
        let mut z = Vec::new();
        let mut rel_of_sigma = Vec::new();
        for seed in 1..=8 {
            let fit = noisy_fit(&exact, &f, 0.01, seed);
            assert!(
                (fit.residual_rms_rel - 0.01).abs() < 0.001,
                "{}",
                fit.residual_rms_rel
            );
            for (m, &(freq_hz, zeta, a)) in fit.modes.iter().zip(&exact) {
                let pairs = [
                    (m.freq_hz - freq_hz, m.freq_hz_stderr),
                    (m.damping_ratio - zeta, m.damping_ratio_stderr),
                    (
                        m.modal_constant_re_per_kg - a.re,
                        m.modal_constant_re_stderr_per_kg,
                    ),
                    (
                        m.modal_constant_im_per_kg - a.im,
                        m.modal_constant_im_stderr_per_kg,
                    ),
                ];
                for (err, sigma) in pairs {
                    let sigma = sigma.expect("a sigma");
                    z.push(err / sigma);
                }
                rel_of_sigma.push(m.damping_ratio_stderr.expect("sigma") / zeta);
            }
        }
        let rms = (z.iter().map(|z| z * z).sum::<f64>() / z.len() as f64).sqrt();
        assert!((0.5..=2.0).contains(&rms), "z-scores' rms {rms}: {z:?}");
        // The damping is known to a few per cent of itself, not to rounding
        // nor to its whole: the test has teeth.
        assert!(
            rel_of_sigma.iter().all(|r| (1e-3..0.1).contains(r)),
            "{rel_of_sigma:?}"
        );
    }

    #[test]
    fn a_fit_refuses_what_it_cannot_fit() {
        let exact = two_modes();
        let f = lines(20.0, 150.0, 0.5);
        let h = frf(&exact, &f);
        let message = |r: Result<ModalFit>| r.expect_err("refused").to_string();
        assert!(message(fit_modes(&f, &h, &options(0, true))).contains("modes"));
        assert!(message(fit_modes(&f, &h, &options(MAX_MODES + 1, true))).contains("1 to 12"));
        assert!(message(fit_modes(&f[1..], &h, &options(2, true))).contains("equal length"));
        assert!(message(fit_modes(&f[..10], &h[..10], &options(2, true))).contains("at least 12"));
        let mut back = f.clone();
        back.swap(3, 4);
        assert!(message(fit_modes(&back, &h, &options(2, true))).contains("strictly increasing"));
        let mut nan = h.clone();
        nan[5].im = f64::NAN;
        assert!(
            message(fit_modes(&f, &nan, &options(2, true))).contains("receptance_im_m_per_n[5]")
        );
        let mut zero = h.clone();
        zero[7] = Complex64::new(0.0, 0.0);
        assert!(message(fit_modes(&f, &zero, &options(2, true))).contains("nonzero"));
        let e = message(fit_modes(&f, &h, &options(3, true)));
        assert!(
            e.contains("3 mode(s) asked for but |H| has 2 peak(s)"),
            "{e}"
        );
    }
}
