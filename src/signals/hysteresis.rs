//! The force-displacement loop of a damper record, the picture of what
//! Yang's method computes (Terzioglu's thesis, Section 7.4.2, eq. 7.8–7.12).
//!
//! The enclosure's displacement comes from its acceleration over whole drive
//! periods: each bin of the window's spectrum divided by `-ω_k²` (the mean,
//! which integration cannot know, set to zero), so the displacement has no
//! drift. Drawn against the force, one loop per cycle; its area is the
//! energy the damper took per cycle, `∮ F dx = ∫ F v dt`, the time-domain
//! twin of the frequency-domain sum of eq. 7.9. It is the record's own loop,
//! before any correction of the rig's phase error.

use std::f64::consts::PI;

use realfft::RealFftPlanner;
use realfft::num_complex::Complex64;

use super::error::{Result, SignalsError};

/// A loop of force against displacement over whole periods.
#[derive(Debug, Clone, PartialEq)]
pub struct ForceLoop {
    /// The enclosure's displacement (m), one value per sample.
    pub displacement_m: Vec<f64>,
    /// The force (N), one value per sample.
    pub force_n: Vec<f64>,
    /// `∮ F dx` per cycle (J): the trapezoid of the force over each
    /// sample's step in displacement, around the closed window, over the
    /// periods.
    pub energy_per_cycle_j: f64,
}

/// The loop of `force` against the displacement of `accel`, both over a
/// window of `n_periods` whole drive periods sampled at `sample_rate_hz`.
pub fn force_loop(
    force: &[f64],
    accel: &[f64],
    sample_rate_hz: f64,
    n_periods: usize,
) -> Result<ForceLoop> {
    let n = accel.len();
    if n < 4 || force.len() != n || n_periods == 0 {
        return Err(SignalsError::Plot {
            path: "force loop".into(),
            message: format!(
                "needs equally long force and acceleration of at least 4 samples over whole periods (got {} and {n} samples, {n_periods} periods)",
                force.len()
            ),
        });
    }
    let mut planner = RealFftPlanner::<f64>::new();
    let forward = planner.plan_fft_forward(n);
    let inverse = planner.plan_fft_inverse(n);
    let mut input = accel.to_vec();
    let mut spectrum = forward.make_output_vec();
    forward
        .process(&mut input, &mut spectrum)
        .map_err(|e| fft_error(e.to_string()))?;
    for (k, bin) in spectrum.iter_mut().enumerate() {
        let omega = 2.0 * PI * k as f64 * sample_rate_hz / n as f64;
        *bin = if k == 0 {
            Complex64::new(0.0, 0.0)
        } else {
            -*bin / (omega * omega * n as f64)
        };
    }
    // The inverse of an even length needs a real Nyquist bin.
    if n % 2 == 0
        && let Some(last) = spectrum.last_mut()
    {
        last.im = 0.0;
    }
    let mut displacement_m = inverse.make_output_vec();
    inverse
        .process(&mut spectrum, &mut displacement_m)
        .map_err(|e| fft_error(e.to_string()))?;
    let work: f64 = (0..n)
        .map(|i| {
            let j = (i + 1) % n;
            0.5 * (force[i] + force[j]) * (displacement_m[j] - displacement_m[i])
        })
        .sum();
    Ok(ForceLoop {
        displacement_m,
        force_n: force.to_vec(),
        energy_per_cycle_j: work / n_periods as f64,
    })
}

fn fft_error(message: String) -> SignalsError {
    SignalsError::Plot {
        path: "force loop".into(),
        message,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A force that leads the motion by 90° minus a loss angle: the loop is
    /// the ellipse whose area is `π F X sin(loss)`, and the displacement is
    /// the acceleration's `-a/ω²`, to 1e-9.
    #[test]
    fn an_ellipse_encloses_pi_f_x_sin_of_its_loss_angle() {
        let (fs, f, periods) = (40_000.0, 40.0, 5);
        let n = (fs / f) as usize * periods;
        let w = 2.0 * PI * f;
        let (x0, f0, loss) = (1e-3, 50.0, 0.3f64);
        let t = |i: usize| i as f64 / fs;
        let accel: Vec<f64> = (0..n).map(|i| -w * w * x0 * (w * t(i)).sin()).collect();
        // Ahead of the displacement by the loss angle: its part in phase
        // with the velocity is f0 sin(loss).
        let force: Vec<f64> = (0..n).map(|i| f0 * (w * t(i) + loss).sin()).collect();
        let l = force_loop(&force, &accel, fs, periods).expect("loop");
        for i in (0..n).step_by(97) {
            assert!((l.displacement_m[i] - x0 * (w * t(i)).sin()).abs() < 1e-9);
        }
        let area = PI * f0 * x0 * loss.sin();
        assert!(
            (l.energy_per_cycle_j / area - 1.0).abs() < 1e-4,
            "{} against {area}",
            l.energy_per_cycle_j
        );
    }
}
