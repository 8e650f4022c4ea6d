//! A timing hook for `vlab bench`: Yang's power (eq. 7.8-7.12) on a synthetic
//! thesis-sized record (by default 5 s at 40 kHz, two channels). No timed
//! assertions live in tests; this only measures and reports.

use crate::clock::Stopwatch;
use std::f64::consts::PI;

use super::error::{InvalidParameter, Result, SignalsError, positive_finite};
use super::power::{PowerOptions, YangPower, yang_power};

/// Timings of [`bench_yang_power`], in s.
#[derive(Debug, Clone, PartialEq)]
pub struct YangBenchReport {
    /// Samples per channel.
    pub n_samples: usize,
    /// Calls timed per variant.
    pub repeats: usize,
    /// Median time of a fresh [`yang_power`] call (plans its FFT each time).
    pub fresh_median_s: f64,
    /// Fastest fresh call.
    pub fresh_min_s: f64,
    /// Median time of [`YangPower::compute`] with the plan reused.
    pub reused_median_s: f64,
    /// Fastest reused call.
    pub reused_min_s: f64,
    /// The power computed, in W (keeps the work observable).
    pub power_w: f64,
}

/// Times Yang's power on a synthetic record of `duration_s` at
/// `sample_rate_hz` with a `drive_freq_hz` drive, `repeats` times each fresh
/// and with a reused plan.
pub fn bench_yang_power(
    duration_s: f64,
    sample_rate_hz: f64,
    drive_freq_hz: f64,
    repeats: usize,
) -> Result<YangBenchReport> {
    positive_finite("duration_s", duration_s, "s")?;
    positive_finite("sample_rate_hz", sample_rate_hz, "Hz")?;
    positive_finite("drive_freq_hz", drive_freq_hz, "Hz")?;
    if repeats == 0 {
        return Err(SignalsError::from(InvalidParameter::new(
            "repeats",
            0.0,
            "",
            "at least 1",
        )));
    }
    let n = (duration_s * sample_rate_hz).round() as usize;
    let w = 2.0 * PI * drive_freq_hz;
    let (force, accel): (Vec<f64>, Vec<f64>) = (0..n)
        .map(|i| {
            let t = i as f64 / sample_rate_hz;
            // Deterministic broadband "noise" so every bin has content.
            let hash =
                ((i as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 11) as f64 / (1u64 << 53) as f64;
            let a = 196.0 * (w * t).cos() + 20.0 * (3.0 * w * t + 0.4).cos() + (hash - 0.5);
            let f = 0.3 * a + 2.0 * (w * t + 1.2).cos() + 0.1 * (hash - 0.5);
            (f, a)
        })
        .unzip();
    let opts = PowerOptions::default();

    let mut fresh = Vec::with_capacity(repeats);
    let mut power_w = 0.0;
    for _ in 0..repeats {
        let start = Stopwatch::start();
        power_w = yang_power(&force, &accel, sample_rate_hz, drive_freq_hz, &opts)?.power_w;
        fresh.push(start.elapsed().as_secs_f64());
    }
    let mut estimator = YangPower::new();
    estimator.compute(&force, &accel, sample_rate_hz, drive_freq_hz, &opts)?;
    let mut reused = Vec::with_capacity(repeats);
    for _ in 0..repeats {
        let start = Stopwatch::start();
        estimator.compute(&force, &accel, sample_rate_hz, drive_freq_hz, &opts)?;
        reused.push(start.elapsed().as_secs_f64());
    }
    let (fresh_median_s, fresh_min_s) = median_min(&mut fresh);
    let (reused_median_s, reused_min_s) = median_min(&mut reused);
    Ok(YangBenchReport {
        n_samples: n,
        repeats,
        fresh_median_s,
        fresh_min_s,
        reused_median_s,
        reused_min_s,
        power_w,
    })
}

fn median_min(times: &mut [f64]) -> (f64, f64) {
    times.sort_by(f64::total_cmp);
    (times[times.len() / 2], times[0])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bench_runs_and_reports_consistently() {
        // Small size: checks plumbing only, no timing assertions.
        let r = bench_yang_power(0.1, 40_000.0, 40.0, 2).expect("bench");
        assert_eq!((r.n_samples, r.repeats), (4_000, 2));
        assert!(r.fresh_min_s <= r.fresh_median_s && r.reused_min_s <= r.reused_median_s);
        // The 2 cos(wt + 1.2) part of the force is partly in phase with v.
        assert!(r.power_w.is_finite() && r.power_w != 0.0);
        assert!(bench_yang_power(0.1, 40_000.0, 40.0, 0).is_err());
    }
}
