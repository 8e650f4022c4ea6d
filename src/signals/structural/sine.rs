//! A stepped sine's component at its frequency and the power a force puts
//! into a structure, with a channel's phase error taken out (the module
//! docs of [`super`]).

use super::*;

/// Complex amplitude of the component at `freq_hz` (**stepped-sine
/// response**).
///
/// Least-squares fit of `a cos(ωt) + b sin(ωt) + c` (`ω = 2π freq_hz`,
/// `t = n / sample_rate_hz`, `t = 0` at the first sample) over the longest
/// whole number of periods from the start of the record; returns
/// `a − i b = A e^(iφ)` for `A cos(ωt + φ)`. The offset `c` is fitted and
/// discarded. Exact (to rounding) for a sinusoid plus offset whatever the
/// window; harmonics of `freq_hz` are orthogonal to the fit, and so
/// rejected exactly, when the window is a whole number of samples per
/// period × periods (e.g. integer samples per period), otherwise they leak
/// in by about (their amplitude) / (samples in the window). One stepped-sine
/// FRF point is `H(f) = Y / X` of the response and force amplitudes.
///
/// Errors: `sample_rate_hz` not positive, `freq_hz` not in
/// `(0, sample_rate_hz / 2)`, a non-finite sample, or a record shorter than
/// one period.
pub fn sine_component(x: &[f64], sample_rate_hz: f64, freq_hz: f64) -> Result<Complex64> {
    check_sample_rate(sample_rate_hz)?;
    check_analysis_freq(freq_hz, sample_rate_hz)?;
    check_finite("x", x)?;
    let m = whole_period_len("x", x.len(), sample_rate_hz, freq_hz, "sine_component")?;
    let cycles_per_sample = freq_hz / sample_rate_hz;
    let fit = least_squares(x[..m].iter().enumerate().map(|(n, &v)| {
        let (s, c) = phase_rad(n as f64 * cycles_per_sample).sin_cos();
        ([c, s, 1.0], v)
    }));
    // Over at least one period of more than 2 samples the three basis
    // functions are linearly independent, so the system is regular; a
    // failure would be a numerical breakdown, reported as a parameter error.
    let [ca, cb, _] = fit.ok_or(invalid(
        "freq_hz",
        freq_hz,
        "Hz",
        "gives a singular least-squares fit on this record",
    ))?;
    Ok(Complex64::new(ca, -cb))
}

/// Complex amplitude `(2 / M) Σ_n x_n e^(−i 2π c n)` of `x` (`M` samples) at
/// `c` cycles per sample: the exact DFT sum at that frequency.
pub(super) fn dft_amplitude(x: &[f64], cycles_per_sample: f64) -> Complex64 {
    let mut sum = Complex64::new(0.0, 0.0);
    for (n, &v) in x.iter().enumerate() {
        let (s, c) = phase_rad(n as f64 * cycles_per_sample).sin_cos();
        sum += Complex64::new(v * c, -v * s);
    }
    sum * (2.0 / x.len() as f64)
}

/// Mean power input of a periodic force, W (**power-input method**).
///
/// Over the longest whole number of periods of `freq_hz` from the start of
/// the records (`M` samples), the harmonic amplitudes of force and
/// acceleration are the exact DFT sums at `k freq_hz`,
/// `F_k = (2 / M) Σ_n F_n e^(−i ω_k t_n)` (likewise `A_k`),
/// `k = 1 ..= harmonics`; the velocity harmonics are `V_k = A_k / (i ω_k)`
/// and `P = Σ_k ½ Re(F_k conj(V_k))`. The DC term carries no power (a
/// steady force does no work on a structure that does not drift) and is
/// not used; a DC offset of either channel therefore does not matter when
/// the window holds whole samples per period. Cost `O(M × harmonics)` sine
/// and cosine evaluations (≈ 2·10⁷ for 10⁶ samples and 20 harmonics, a
/// fraction of a second).
///
/// Exact (to rounding) when `k freq_hz M / sample_rate_hz` is an integer
/// for every `k` (e.g. integer samples per period); otherwise each
/// amplitude carries a leakage error of about 1 / M of the record's
/// components.
///
/// Errors: lengths differ, `sample_rate_hz` not positive, `freq_hz` not in
/// `(0, sample_rate_hz / 2)`, `harmonics` zero or with
/// `harmonics × freq_hz ≥ sample_rate_hz / 2`, non-finite samples, or a
/// record shorter than one period.
pub fn power_input_w(
    force_n: &[f64],
    accel_mps2: &[f64],
    sample_rate_hz: f64,
    freq_hz: f64,
    harmonics: usize,
) -> Result<f64> {
    power_input_corrected_w(
        force_n,
        accel_mps2,
        sample_rate_hz,
        freq_hz,
        harmonics,
        |_| 0.0,
    )
}

/// [`power_input_w`] with the channels' phase error taken out: the force
/// record leads the acceleration record by `phase_error_rad(f)` at `f` (Hz;
/// a rig's calibration, e.g. `RigSpec::expected_phase_error_rad`), so each
/// harmonic's product is `½ Re(F_k conj(V_k) e^(−i φ_k))`. Off resonance the
/// power is a small part of `½ |F| |V|`, and a phase error of a few
/// milliradians moves it by per cents.
pub fn power_input_corrected_w(
    force_n: &[f64],
    accel_mps2: &[f64],
    sample_rate_hz: f64,
    freq_hz: f64,
    harmonics: usize,
    phase_error_rad: impl Fn(f64) -> f64,
) -> Result<f64> {
    check_same_len("force_n", force_n, "accel_mps2", accel_mps2)?;
    check_sample_rate(sample_rate_hz)?;
    check_analysis_freq(freq_hz, sample_rate_hz)?;
    let nyquist_hz = 0.5 * sample_rate_hz;
    if harmonics == 0 || harmonics as f64 * freq_hz >= nyquist_hz {
        return Err(invalid(
            "harmonics",
            harmonics as f64,
            "(count)",
            format!(
                "must be at least 1 and keep harmonics × freq_hz below the Nyquist frequency \
                 {nyquist_hz} Hz (at most {} for freq_hz = {freq_hz} Hz)",
                ((nyquist_hz / freq_hz).ceil() as usize).saturating_sub(1)
            ),
        ));
    }
    check_finite("force_n", force_n)?;
    check_finite("accel_mps2", accel_mps2)?;
    let m = whole_period_len(
        "force_n",
        force_n.len(),
        sample_rate_hz,
        freq_hz,
        "power_input_w",
    )?;
    let power_w = (1..=harmonics)
        .map(|k| {
            let cycles_per_sample = k as f64 * freq_hz / sample_rate_hz;
            let f_k = dft_amplitude(&force_n[..m], cycles_per_sample);
            let a_k = dft_amplitude(&accel_mps2[..m], cycles_per_sample);
            let v_k = a_k / Complex64::new(0.0, 2.0 * PI * k as f64 * freq_hz);
            let undo = Complex64::from_polar(1.0, -phase_error_rad(k as f64 * freq_hz));
            0.5 * (f_k * v_k.conj() * undo).re
        })
        .sum();
    Ok(power_w)
}
