//! Drop-test restitution (thesis Section 7.3, eq. 7.3-7.5): find the impacts
//! of a bouncing particle in the plate's force record, then turn the time gaps
//! between them into coefficients of restitution.
//!
//! # Impact detection ([`detect_impacts`])
//!
//! The record `y = s x` is taken with the sign `s` that makes the largest
//! peak positive ([`Polarity::Auto`]), or as told. An impact starts when
//! `y` rises through `threshold_n` while the detector is armed; it ends when
//! `y` falls below `release_n` (hysteresis). After an impact start, nothing
//! re-triggers for `holdoff_s` (the plate rings after each impact), and the
//! detector re-arms only once `y` is below `release_n` again after that.
//!
//! - **Onset time**: the threshold crossing, refined by linear interpolation
//!   between the two samples around it. It lies a little after the true
//!   contact start (by the pulse's rise time to the threshold: about
//!   `w asin(threshold/peak) / pi` for a half-sine of width `w`); the bias is
//!   nearly the same for every impact and cancels in the gaps.
//! - **Peak time**: the largest sample of the impact, refined by a parabola
//!   through it and its neighbours.
//!
//! Defaults when a parameter is not given: `threshold_n` = 10 % of the
//! largest peak, `release_n` = half the threshold, `holdoff_s` = 2 ms (well
//! below the gap of any bounce worth measuring: a 1 cm bounce lasts 90 ms,
//! and long enough for plate ringing to decay). With the default threshold
//! the record must hold something that stands out from the noise: the
//! threshold must be at least [`MIN_THRESHOLD_TO_NOISE`] noise standard
//! deviations (estimated robustly as 1.4826 x the median absolute deviation),
//! otherwise the result is [`SignalsError::NoImpacts`]. The estimate is never
//! below the quantisation noise `q / sqrt(12)` of the record's own step `q`
//! (the smallest gap between two distinct sample values): a digitised quiet
//! record whose noise is below one ADC step has most samples on one code and
//! a median absolute deviation of zero, and without that floor its 1-LSB
//! flickers would pass for impacts.
//!
//! # Restitution ([`restitution_from_impact_times`])
//!
//! With gaps `T_k = t_{k+1} - t_k` between successive impacts, a particle
//! that loses energy only in contacts hits impact `k+1` at `v = g T_k / 2`
//! (eq. 7.3-7.4), so each triple of impacts gives `e = T_{k+1} / T_k`
//! (eq. 7.5). `cor_per_triple[k]` pairs with `impact_speeds_mps[k]`, the
//! speed at the middle impact of the triple, for "COR vs impact velocity".
//!
//! A bouncing particle's gaps only shrink, so a triple with `e > 1`
//! ([`CorEstimate::growing_gaps`]) means the detector missed an impact (its
//! two gaps were counted as one) or took ringing or noise for one; such an
//! estimate should not be trusted. Missed impacts happen when the record
//! samples an impact's short pulse too coarsely for it to cross the threshold.
//!
//! [`cor_report`] runs the estimator on one channel of a record as `vlab cor`
//! reports it ([`CorReport`]), with those warnings.

use super::error::{InvalidParameter, Result, SignalsError, all_finite, positive_finite};
use super::trace::Trace;
use crate::stats::{MeanStd, mean_std};
use crate::warning::Warning;

/// Default threshold as a fraction of the largest peak.
pub const DEFAULT_THRESHOLD_FRACTION: f64 = 0.10;
/// Default release level as a fraction of the threshold.
pub const DEFAULT_RELEASE_FRACTION_OF_THRESHOLD: f64 = 0.5;
/// Default hold-off after an impact start, in s.
pub const DEFAULT_HOLDOFF_S: f64 = 2e-3;
/// Smallest default threshold, in noise standard deviations, that counts as
/// "something stands out from the noise".
pub const MIN_THRESHOLD_TO_NOISE: f64 = 6.0;

/// Which way impacts point in the force record.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum Polarity {
    /// The sign of the sample with the largest magnitude.
    #[default]
    Auto,
    /// Impacts are positive forces.
    Positive,
    /// Impacts are negative forces.
    Negative,
}

/// Detector settings; `None` means "derive from the record" (module docs).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct ImpactParams {
    /// Arming level, in N (positive, in the impact's direction).
    pub threshold_n: Option<f64>,
    /// Disarming level, in N (below `threshold_n`).
    pub release_n: Option<f64>,
    /// No re-trigger for this long after an impact start, in s.
    pub holdoff_s: Option<f64>,
    /// Direction of impacts.
    pub polarity: Polarity,
}

/// One detected impact.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Impact {
    /// Threshold-crossing time, linearly interpolated, in s.
    pub onset_time_s: f64,
    /// Time of the force peak, parabola-refined, in s.
    pub peak_time_s: f64,
    /// The peak force as recorded (with its sign), in N.
    pub peak_force_n: f64,
    /// Index of the first sample at or above the threshold.
    pub onset_index: usize,
}

/// What [`detect_impacts`] found and the settings it used.
#[derive(Debug, Clone, PartialEq)]
pub struct ImpactDetection {
    /// Impacts in time order.
    pub impacts: Vec<Impact>,
    /// Threshold used, in N (in the impact direction).
    pub threshold_n: f64,
    /// Release level used, in N.
    pub release_n: f64,
    /// Hold-off used, in s.
    pub holdoff_s: f64,
    /// +1 if impacts are positive forces, -1 if negative.
    pub polarity_sign: f64,
    /// Robust noise standard deviation of the record, in N.
    pub noise_std_n: f64,
}

impl ImpactDetection {
    /// Onset times, in s.
    pub fn onset_times_s(&self) -> Vec<f64> {
        self.impacts.iter().map(|i| i.onset_time_s).collect()
    }
}

/// Restitution from impact times (eq. 7.3-7.5).
#[derive(Debug, Clone, PartialEq)]
pub struct CorEstimate {
    /// Gaps between successive impacts, in s.
    pub gaps_s: Vec<f64>,
    /// `gaps[k+1] / gaps[k]` for each triple of successive impacts.
    pub cor_per_triple: Vec<f64>,
    /// `g gaps[k] / 2`: speed at impact k+1, in m/s (eq. 7.3).
    pub impact_speeds_mps: Vec<f64>,
    /// Mean of `cor_per_triple`.
    pub cor_mean: f64,
    /// Sample standard deviation (n - 1) of `cor_per_triple`; 0 for one triple.
    pub cor_std: f64,
}

impl CorEstimate {
    /// Indices of the triples whose second gap is longer than the first
    /// (`e > 1`): a sign of a missed or a false impact (module docs).
    pub fn growing_gaps(&self) -> Vec<usize> {
        self.cor_per_triple
            .iter()
            .enumerate()
            .filter(|(_, e)| **e > 1.0)
            .map(|(k, _)| k)
            .collect()
    }
}

/// Impacts and restitution of one drop-test record.
#[derive(Debug, Clone, PartialEq)]
pub struct DropTestResult {
    /// The impacts found.
    pub detection: ImpactDetection,
    /// Restitution from their onset times.
    pub cor: CorEstimate,
}

/// Finds impacts in `force` (N) sampled at `sample_rate_hz`, sample 0 at
/// `start_time_s`. See the module docs for the rules.
pub fn detect_impacts(
    force: &[f64],
    sample_rate_hz: f64,
    start_time_s: f64,
    params: &ImpactParams,
) -> Result<ImpactDetection> {
    positive_finite("sample_rate_hz", sample_rate_hz, "Hz")?;
    if force.len() < 2 {
        return Err(SignalsError::TooFewSamples {
            what: "impact detection".into(),
            need: 2,
            got: force.len(),
        });
    }
    all_finite("force", force)?;
    let polarity_sign = polarity_sign(force, params.polarity);
    let y: Vec<f64> = force.iter().map(|x| polarity_sign * x).collect();
    let peak = y.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let noise_std_n = robust_std(force);
    let threshold_n = threshold_n(params.threshold_n, peak, noise_std_n)?;
    let (release_n, holdoff_s) = release_and_holdoff(params, threshold_n)?;
    let crossings = Crossings {
        y: &y,
        force,
        start_time_s,
        dt_s: 1.0 / sample_rate_hz,
        threshold_n,
        release_n,
        holdoff_samples: (holdoff_s * sample_rate_hz).ceil() as usize,
    };
    let impacts = crossings.impacts();
    if impacts.is_empty() {
        return Err(SignalsError::NoImpacts {
            reason: format!(
                "no rising crossing of threshold_n = {threshold_n} N (largest peak {peak} N)"
            ),
        });
    }
    Ok(ImpactDetection {
        impacts,
        threshold_n,
        release_n,
        holdoff_s,
        polarity_sign,
        noise_std_n,
    })
}

/// +1 or -1: the sign that makes impacts positive (for `Auto`, the sign of
/// the sample of largest magnitude).
fn polarity_sign(force: &[f64], polarity: Polarity) -> f64 {
    match polarity {
        Polarity::Positive => 1.0,
        Polarity::Negative => -1.0,
        Polarity::Auto => {
            let extreme = force
                .iter()
                .fold(0.0f64, |m, &x| if x.abs() > m.abs() { x } else { m });
            if extreme < 0.0 { -1.0 } else { 1.0 }
        }
    }
}

/// The threshold, N: `given`, else a fraction of the `peak` that must stand
/// clear of the noise.
fn threshold_n(given: Option<f64>, peak: f64, noise_std_n: f64) -> Result<f64> {
    if let Some(t) = given {
        return positive_finite("threshold_n", t, "N");
    }
    let t = DEFAULT_THRESHOLD_FRACTION * peak;
    if !(peak > 0.0 && t >= MIN_THRESHOLD_TO_NOISE * noise_std_n) {
        return Err(SignalsError::NoImpacts {
            reason: format!(
                "the largest force peak, {peak} N, is {:.1} noise standard deviations \
                 ({noise_std_n:.3e} N); the default threshold ({}% of it) must be at least \
                 {MIN_THRESHOLD_TO_NOISE} of them. Give threshold_n if the record holds impacts.",
                peak / noise_std_n,
                DEFAULT_THRESHOLD_FRACTION * 100.0
            ),
        });
    }
    Ok(t)
}

/// The release level (N, below `threshold_n`) and the hold-off (s), given or
/// defaults.
fn release_and_holdoff(params: &ImpactParams, threshold_n: f64) -> Result<(f64, f64)> {
    let release_n = match params.release_n {
        Some(r) if r.is_finite() && r < threshold_n => r,
        Some(r) => {
            return Err(SignalsError::from(InvalidParameter::new(
                "release_n",
                r,
                "N",
                format!("finite and below threshold_n = {threshold_n} N"),
            )));
        }
        None => DEFAULT_RELEASE_FRACTION_OF_THRESHOLD * threshold_n,
    };
    let holdoff_s = match params.holdoff_s {
        Some(h) if h.is_finite() && h >= 0.0 => h,
        Some(h) => {
            return Err(SignalsError::from(InvalidParameter::new(
                "holdoff_s",
                h,
                "s",
                "finite and >= 0",
            )));
        }
        None => DEFAULT_HOLDOFF_S,
    };
    Ok((release_n, holdoff_s))
}

/// The crossing detector over a record made positive (`y`).
struct Crossings<'a> {
    y: &'a [f64],
    /// The record as given, for the peak force.
    force: &'a [f64],
    start_time_s: f64,
    dt_s: f64,
    threshold_n: f64,
    release_n: f64,
    holdoff_samples: usize,
}

impl Crossings<'_> {
    /// Time of the (fractional) sample index `i`, s.
    fn time(&self, i: f64) -> f64 {
        self.start_time_s + i * self.dt_s
    }

    /// An impact from its onset and the index of its largest sample.
    fn finish(&self, onset_index: usize, onset_time_s: f64, p: usize) -> Impact {
        Impact {
            onset_time_s,
            peak_time_s: self.time(p as f64 + parabolic_offset(self.y, p)),
            peak_force_n: self.force[p],
            onset_index,
        }
    }

    /// Every impact: armed once below the release level and past the
    /// hold-off, an impact starts at a rising crossing of the threshold
    /// (interpolated between samples) and ends below the release level.
    fn impacts(&self) -> Vec<Impact> {
        let y = self.y;
        let mut impacts = Vec::new();
        let mut current: Option<(usize, f64, usize)> = None; // onset index, onset time, peak index
        let mut ready = false;
        let mut holdoff_until = 0usize;
        for (i, &yi) in y.iter().enumerate() {
            if let Some((onset_i, onset_t, ref mut p)) = current {
                if yi > y[*p] {
                    *p = i;
                }
                if yi < self.release_n {
                    impacts.push(self.finish(onset_i, onset_t, *p));
                    current = None;
                }
                continue;
            }
            if !ready {
                ready = yi < self.release_n && i >= holdoff_until;
                continue;
            }
            if yi >= self.threshold_n {
                // Armed implies y[i-1] < threshold <= y[i], and i >= 1.
                let prev = y[i - 1];
                let frac = (self.threshold_n - prev) / (yi - prev);
                current = Some((i, self.time(i as f64 - 1.0 + frac), i));
                holdoff_until = i + self.holdoff_samples;
                ready = false;
            }
        }
        if let Some((onset_i, onset_t, p)) = current {
            impacts.push(self.finish(onset_i, onset_t, p));
        }
        impacts
    }
}

/// Sub-sample offset of the vertex of the parabola through y[p-1], y[p],
/// y[p+1], within [-0.5, 0.5]; 0 at the ends or when not a maximum.
fn parabolic_offset(y: &[f64], p: usize) -> f64 {
    if p == 0 || p + 1 >= y.len() {
        return 0.0;
    }
    let (a, b, c) = (y[p - 1], y[p], y[p + 1]);
    let curvature = a - 2.0 * b + c;
    if curvature >= 0.0 {
        return 0.0;
    }
    (0.5 * (a - c) / curvature).clamp(-0.5, 0.5)
}

/// 1.4826 x the median absolute deviation, the standard deviation of the
/// Gaussian part of a record that is mostly quiet; at least `q / sqrt(12)`
/// for the record's quantisation step `q` (module docs).
fn robust_std(x: &[f64]) -> f64 {
    let mut v = x.to_vec();
    v.sort_unstable_by(f64::total_cmp);
    let step = v
        .windows(2)
        .map(|w| w[1] - w[0])
        .filter(|d| *d > 0.0)
        .fold(f64::INFINITY, f64::min);
    let quantisation = if step.is_finite() {
        step / 12f64.sqrt()
    } else {
        0.0
    };
    let med = v[v.len() / 2];
    for e in v.iter_mut() {
        *e = (*e - med).abs();
    }
    (1.4826 * median_in_place(&mut v)).max(quantisation)
}

fn median_in_place(v: &mut [f64]) -> f64 {
    let mid = v.len() / 2;
    let (_, m, _) = v.select_nth_unstable_by(mid, f64::total_cmp);
    *m
}

/// Restitution from impact times in s (strictly increasing, at least 3),
/// with gravity `g_mps2` (eq. 7.3-7.5).
pub fn restitution_from_impact_times(times_s: &[f64], g_mps2: f64) -> Result<CorEstimate> {
    positive_finite("g_mps2", g_mps2, "m/s^2")?;
    all_finite("impact times", times_s)?;
    for (i, w) in times_s.windows(2).enumerate() {
        if w[1] <= w[0] {
            return Err(SignalsError::ImpactTimesNotIncreasing {
                index: i + 1,
                time_s: w[1],
                prev_index: i,
                prev_time_s: w[0],
            });
        }
    }
    if times_s.len() < 3 {
        return Err(SignalsError::NotEnoughImpacts {
            found: times_s.len(),
        });
    }
    let gaps_s: Vec<f64> = times_s.windows(2).map(|w| w[1] - w[0]).collect();
    let cor_per_triple: Vec<f64> = gaps_s.windows(2).map(|w| w[1] / w[0]).collect();
    let impact_speeds_mps = gaps_s.iter().map(|t| g_mps2 * t / 2.0).collect();
    let MeanStd {
        mean: cor_mean,
        std: cor_std,
    } = mean_std(&cor_per_triple);
    Ok(CorEstimate {
        gaps_s,
        cor_per_triple,
        impact_speeds_mps,
        cor_mean,
        cor_std,
    })
}

/// Detects impacts in channel `channel` of `trace` and estimates restitution
/// from their onset times.
pub fn estimate_cor(
    trace: &Trace,
    channel: &str,
    params: &ImpactParams,
    g_mps2: f64,
) -> Result<DropTestResult> {
    let c = trace.channel(channel)?;
    let detection = detect_impacts(&c.samples, trace.sample_rate_hz, trace.start_time_s, params)?;
    let cor = restitution_from_impact_times(&detection.onset_times_s(), g_mps2)?;
    Ok(DropTestResult { detection, cor })
}

/// One impact as a [`CorReport`] lists it.
#[derive(Debug, Clone, serde::Serialize)]
pub struct ImpactRow {
    pub onset_time_s: f64,
    pub peak_time_s: f64,
    pub peak_force: f64,
}

/// An input whose change a drop-test estimate's warning advises.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CorInput {
    /// `threshold_n` or `holdoff_s` of [`ImpactParams`]: the detection.
    Detection,
}

/// A warning of a restitution estimate, and the input that would lift it.
pub type CorWarning = Warning<CorInput>;

/// The restitution estimator's result on one force channel of a record, as
/// `vlab cor` reports it.
#[derive(Debug, Clone, serde::Serialize)]
pub struct CorReport {
    pub file: String,
    pub channel: String,
    pub unit: String,
    pub sample_rate_hz: f64,
    pub samples: usize,
    pub g_mps2: f64,
    pub threshold: f64,
    pub release: f64,
    pub holdoff_s: f64,
    pub noise_std: f64,
    pub impacts: Vec<ImpactRow>,
    pub gaps_s: Vec<f64>,
    /// COR of each triple (eq. 7.5).
    pub cor_per_triple: Vec<f64>,
    /// Speed at each triple's middle impact, g T / 2 of the gap before it (eq. 7.3), m/s.
    pub impact_speeds_mps: Vec<f64>,
    pub cor_mean: f64,
    pub cor_std: f64,
    /// Triples (from 1) whose second gap is longer than the first.
    pub growing_gap_triples: Vec<usize>,
    pub warnings: Vec<CorWarning>,
}

/// The channel of `trace` a drop-test estimate reads when none is named:
/// `force`, or the record's only channel; `None` when neither is there.
pub fn default_force_channel(trace: &Trace) -> Option<String> {
    if trace.channel("force").is_ok() {
        Some("force".to_string())
    } else if let [only] = trace.channels.as_slice() {
        Some(only.name.clone())
    } else {
        None
    }
}

/// Detects the impacts in channel `channel` of `trace` (the record `file`)
/// and estimates the restitution ([`estimate_cor`]), with the warnings a lab
/// user must see: triples whose gaps grew, a channel not in N.
pub fn cor_report(
    file: &str,
    trace: &Trace,
    channel: &str,
    params: &ImpactParams,
    g_mps2: f64,
) -> Result<CorReport> {
    let unit = trace.channel(channel)?.unit.clone();
    let r = estimate_cor(trace, channel, params, g_mps2)?;
    let d = &r.detection;
    let n = r.cor.cor_per_triple.len();
    let grown: Vec<usize> = r.cor.growing_gaps().iter().map(|k| k + 1).collect();
    let mut warnings = Vec::new();
    if !grown.is_empty() {
        warnings.push(CorWarning::advising(
            format!(
                "triple(s) {} have a second gap longer than the first (COR > 1): an impact was \
                 missed or ringing taken for one; try another threshold_n or holdoff_s",
                grown
                    .iter()
                    .map(|k| k.to_string())
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
            CorInput::Detection,
        ));
    }
    if unit != "N" {
        warnings.push(CorWarning::from(format!(
            "channel '{channel}' is in '{unit}', not N: the threshold is in that unit"
        )));
    }
    Ok(CorReport {
        file: file.to_string(),
        channel: channel.to_string(),
        unit,
        sample_rate_hz: trace.sample_rate_hz,
        samples: trace.len(),
        g_mps2,
        threshold: d.threshold_n,
        release: d.release_n,
        holdoff_s: d.holdoff_s,
        noise_std: d.noise_std_n,
        impacts: d
            .impacts
            .iter()
            .map(|i| ImpactRow {
                onset_time_s: i.onset_time_s,
                peak_time_s: i.peak_time_s,
                peak_force: i.peak_force_n,
            })
            .collect(),
        gaps_s: r.cor.gaps_s.clone(),
        cor_per_triple: r.cor.cor_per_triple.clone(),
        impact_speeds_mps: r.cor.impact_speeds_mps[..n].to_vec(),
        cor_mean: r.cor.cor_mean,
        cor_std: r.cor.cor_std,
        growing_gap_triples: grown,
        warnings,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::signals::testutil::{gaussian, rng};
    use std::f64::consts::PI;

    const FS: f64 = 200_000.0;
    const G: f64 = 9.81;
    const WIDTH_S: f64 = 50e-6;

    /// Half-sine pulses at `onsets` with peaks `peaks`, each followed by a 3 kHz
    /// plate ring of 20 % of its peak decaying with a 0.25 ms time constant (gone
    /// within ~1 ms), plus white noise of `noise` N RMS.
    fn drop_record(onsets: &[f64], peaks: &[f64], duration_s: f64, noise: f64) -> Vec<f64> {
        let mut r = rng(7);
        (0..(duration_s * FS) as usize)
            .map(|i| {
                let t = i as f64 / FS;
                let mut x = noise * gaussian(&mut r);
                for (&t0, &p) in onsets.iter().zip(peaks) {
                    let s = t - t0;
                    if (0.0..WIDTH_S).contains(&s) {
                        x += p * (PI * s / WIDTH_S).sin();
                    } else if s >= WIDTH_S {
                        let r = s - WIDTH_S;
                        x += 0.2 * p * (2.0 * PI * 3000.0 * r).sin() * (-r / 0.25e-3).exp();
                    }
                }
                x
            })
            .collect()
    }

    /// Bouncing-ball schedule: first impact at t0, gaps 2 v e^k / g.
    fn schedule(n: usize, e: f64, v: f64) -> (Vec<f64>, Vec<f64>) {
        let mut onsets = vec![0.01];
        for k in 0..n - 1 {
            let last = onsets[k];
            onsets.push(last + 2.0 * v * e.powi(k as i32) / G);
        }
        let peaks = (0..n).map(|k| 100.0 * e.powi(k as i32)).collect();
        (onsets, peaks)
    }

    #[test]
    fn finds_bounces_within_a_sample_and_the_cor_within_0_1_percent() {
        let (onsets, peaks) = schedule(6, 0.9, 1.0);
        let duration = onsets[5] + 0.02;
        let x = drop_record(&onsets, &peaks, duration, 1.0); // noise 1 % of the largest peak
        let mut trace = Trace::new(FS, 0.0).expect("trace");
        trace.add_channel("force", "N", x).expect("force");
        let r = estimate_cor(&trace, "force", &ImpactParams::default(), G).expect("cor");
        let found = r.detection.onset_times_s();
        assert_eq!(found.len(), 6, "{found:?}");
        for (got, want) in found.iter().zip(&onsets) {
            // Tolerance: one sample period (5 us).
            assert!((got - want).abs() < 1.0 / FS, "onset {got} vs {want}");
            assert!(
                got >= want,
                "a threshold crossing cannot precede the contact"
            );
        }
        for (imp, (&t0, &p)) in r.detection.impacts.iter().zip(onsets.iter().zip(&peaks)) {
            // Peak at the half-sine's middle within a sample, height within 3 % (noise).
            assert!((imp.peak_time_s - (t0 + WIDTH_S / 2.0)).abs() < 1.0 / FS);
            assert!((imp.peak_force_n - p).abs() < 0.03 * p);
        }
        assert_eq!(r.cor.cor_per_triple.len(), 4);
        assert!((r.cor.cor_mean - 0.9).abs() < 0.9e-3, "{}", r.cor.cor_mean);
        // Speed at the second impact is the initial 1 m/s (rel. tol 1e-4).
        assert!((r.cor.impact_speeds_mps[0] - 1.0).abs() < 1e-4);
        assert!((r.detection.noise_std_n - 1.0).abs() < 0.05);
    }

    #[test]
    fn negative_impacts_are_found_too() {
        let (onsets, peaks) = schedule(4, 0.8, 0.5);
        let x: Vec<f64> = drop_record(&onsets, &peaks, onsets[3] + 0.01, 0.5)
            .into_iter()
            .map(|v| -v)
            .collect();
        let d = detect_impacts(&x, FS, 0.0, &ImpactParams::default()).expect("detect");
        assert_eq!(d.polarity_sign, -1.0);
        assert_eq!(d.impacts.len(), 4);
        assert!(d.impacts[0].peak_force_n < -90.0);
    }

    #[test]
    fn without_hold_off_the_ringing_re_triggers() {
        // The test that the hold-off matters: with none, a 20 % ring crosses a
        // 10 % threshold again.
        let (onsets, peaks) = schedule(3, 0.9, 1.0);
        let x = drop_record(&onsets, &peaks, onsets[2] + 0.01, 0.0);
        let params = ImpactParams {
            threshold_n: Some(10.0),
            holdoff_s: Some(0.0),
            ..ImpactParams::default()
        };
        let d = detect_impacts(&x, FS, 0.0, &params).expect("detect");
        assert!(d.impacts.len() > 3, "{}", d.impacts.len());
        let d = detect_impacts(&x, FS, 0.0, &ImpactParams::default()).expect("detect");
        assert_eq!(d.impacts.len(), 3);
    }

    #[test]
    fn a_missed_impact_shows_as_a_growing_gap() {
        // The fourth impact is too weak for a 10 N threshold: gaps 3 and 4
        // merge, triple 2 reads e + e^2 = 1.71 and is flagged.
        let (onsets, mut peaks) = schedule(6, 0.9, 1.0);
        peaks[3] = 5.0;
        let x = drop_record(&onsets, &peaks, onsets[5] + 0.01, 0.2);
        let mut trace = Trace::new(FS, 0.0).expect("trace");
        trace.add_channel("force", "N", x).expect("force");
        let params = ImpactParams {
            threshold_n: Some(10.0),
            ..ImpactParams::default()
        };
        let r = estimate_cor(&trace, "force", &params, G).expect("cor");
        assert_eq!(r.detection.impacts.len(), 5);
        assert!((r.cor.cor_per_triple[1] - 1.71).abs() < 0.01);
        assert_eq!(r.cor.growing_gaps(), vec![1]);
        // Found, it is an ordinary bounce.
        let params = ImpactParams {
            threshold_n: Some(2.0),
            ..params
        };
        let r = estimate_cor(&trace, "force", &params, G).expect("cor");
        assert_eq!(r.detection.impacts.len(), 6);
        assert!(r.cor.growing_gaps().is_empty());
    }

    #[test]
    fn two_impacts_are_not_enough() {
        let (onsets, peaks) = schedule(2, 0.9, 1.0);
        let mut trace = Trace::new(FS, 0.0).expect("trace");
        trace
            .add_channel(
                "force",
                "N",
                drop_record(&onsets, &peaks, onsets[1] + 0.01, 1.0),
            )
            .expect("force");
        let err = estimate_cor(&trace, "force", &ImpactParams::default(), G).expect_err("two");
        assert_eq!(
            err.to_string(),
            "found 2 impacts; the estimator needs at least 3 (two gaps)"
        );
    }

    #[test]
    fn noise_alone_is_no_impacts() {
        let mut r = rng(11);
        let x: Vec<f64> = (0..200_000).map(|_| gaussian(&mut r)).collect();
        let err = detect_impacts(&x, FS, 0.0, &ImpactParams::default()).expect_err("noise");
        assert!(matches!(err, SignalsError::NoImpacts { .. }));
        assert!(err.to_string().starts_with("no impacts"), "{err}");
        let quiet = vec![0.0; 1000];
        assert!(matches!(
            detect_impacts(&quiet, FS, 0.0, &ImpactParams::default()),
            Err(SignalsError::NoImpacts { .. })
        ));
        let params = ImpactParams {
            threshold_n: Some(50.0),
            ..ImpactParams::default()
        };
        assert!(matches!(
            detect_impacts(&x, FS, 0.0, &params),
            Err(SignalsError::NoImpacts { .. })
        ));
    }

    #[test]
    fn a_quantised_quiet_record_is_no_impacts() {
        // Noise of 0.37 LSB rms on a 16-bit-like grid: most samples on code 0,
        // MAD 0, the largest flicker 2-3 steps. Found before the quantisation
        // floor: hundreds of "impacts".
        let q = 0.0136;
        let mut r = rng(5);
        let quiet: Vec<f64> = (0..100_000)
            .map(|_| (0.005 * gaussian(&mut r) / q).round() * q)
            .collect();
        let err = detect_impacts(&quiet, FS, 0.0, &ImpactParams::default()).expect_err("quiet");
        assert!(matches!(err, SignalsError::NoImpacts { .. }), "{err}");
        // The same grid with bounces on it: found, noise at the floor q / sqrt(12).
        let (onsets, peaks) = schedule(4, 0.9, 1.0);
        let mut r = rng(6);
        let x: Vec<f64> = drop_record(&onsets, &peaks, onsets[3] + 0.01, 0.0)
            .into_iter()
            .map(|v| ((v + 0.005 * gaussian(&mut r)) / q).round() * q)
            .collect();
        let d = detect_impacts(&x, FS, 0.0, &ImpactParams::default()).expect("bounces");
        assert_eq!(d.impacts.len(), 4);
        assert!(
            (d.noise_std_n - q / 12f64.sqrt()).abs() < 1e-12,
            "{}",
            d.noise_std_n
        );
    }

    #[test]
    fn restitution_arithmetic() {
        // Gaps 0.2, 0.18, 0.171: e = 0.9, 0.95; mean 0.925, std 0.0353553 (tol 1e-12).
        let c = restitution_from_impact_times(&[1.0, 1.2, 1.38, 1.551], 10.0).expect("cor");
        assert!((c.cor_per_triple[0] - 0.9).abs() < 1e-12);
        assert!((c.cor_per_triple[1] - 0.95).abs() < 1e-12);
        assert!((c.cor_mean - 0.925).abs() < 1e-12);
        assert!((c.cor_std - 0.05 / 2f64.sqrt()).abs() < 1e-12);
        assert!((c.impact_speeds_mps[0] - 1.0).abs() < 1e-12);
        let one = restitution_from_impact_times(&[0.0, 0.2, 0.38], 10.0).expect("one triple");
        assert_eq!(one.cor_std, 0.0);
        assert!(matches!(
            restitution_from_impact_times(&[0.0, 0.2, 0.2], 10.0),
            Err(SignalsError::ImpactTimesNotIncreasing { index: 2, .. })
        ));
        assert!(restitution_from_impact_times(&[0.0, 0.2, 0.3], 0.0).is_err());
    }
}
