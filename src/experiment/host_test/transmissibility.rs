//! Base excitation measured as a lab measures it: the host on the rig's
//! shaker table ([`crate::host::base`]), a stepped sine of the table's
//! acceleration in one run (the host's and the bed's state carried from step
//! to step, up and optionally back down, as
//! [`super::carried_sine`] steps a force), and at every step
//! - the **transmissibility** `T = A_damper / A_table`, the ratio of the two
//!   accelerometers' lines at the drive frequency (the same chain on both,
//!   so the chain's response cancels), its error from the record's periods;
//! - the **power the table puts in**, Yang's method (thesis eq. 7.9-7.12) on
//!   the table's transducer force and acceleration with the rig's phase
//!   error taken out (eq. 7.13), against what the host's damping, a dashpot
//!   payload and the DEM's bed dissipated over the same periods;
//! - for a linear payload, the exact `T(ω)` beside it.

use std::f64::consts::TAU;

use realfft::num_complex::Complex64;
use serde::Serialize;

use crate::experiment::bed::cache::BedSource;
use crate::experiment::damper::Progress;
use crate::experiment::host_test::carried_sine::{Branch, CarriedSine};
use crate::experiment::host_test::frf::receptance_error_rel;
use crate::experiment::host_test::{DAMPER_ACCEL_CHANNEL, Damper, HostRun, HostTest, write_text};
use crate::host::base::transmissibility;
use crate::rig::{ACCEL_CHANNEL, FORCE_CHANNEL};
use crate::scene::{Scene, SceneError};
use crate::signals::SignalsError;
use crate::signals::structural::{power_input_corrected_w, sine_component};
use crate::validation::{Bound, InvalidParameter, in_range};

/// Harmonics of the drive frequency Yang's sum takes (the table's
/// acceleration is a sine: the higher ones carry only noise).
const HARMONICS: usize = 10;

/// Largest table acceleration, m/s² (Γ 50 at the table).
pub const MAX_TABLE_ACCEL_MPS2: f64 = 490.0;

/// The plan: ascending frequencies, the table's acceleration amplitude
/// (m/s²), the cycles of each step, and whether to come back down.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TableSine {
    pub freqs_hz: Vec<f64>,
    pub table_accel_mps2: f64,
    pub settle_cycles: u32,
    pub record_cycles: u32,
    pub down: bool,
}

impl TableSine {
    /// The same steps as a carried force sine of amplitude
    /// `table_accel_mps2` (its order and its stepped excitation).
    fn steps(&self) -> CarriedSine {
        CarriedSine {
            freqs_hz: self.freqs_hz.clone(),
            force_n: self.table_accel_mps2,
            settle_cycles: self.settle_cycles,
            record_cycles: self.record_cycles,
            down: self.down,
        }
    }

    /// Checks the plan: [`CarriedSine::validate`]'s rules and the table's
    /// acceleration in (0, [`MAX_TABLE_ACCEL_MPS2`]] m/s².
    pub fn validate(&self) -> Result<(), InvalidParameter> {
        in_range(
            "table_accel_mps2",
            self.table_accel_mps2,
            "m/s^2",
            Bound::Open(0.0),
            Bound::Closed(MAX_TABLE_ACCEL_MPS2),
        )?;
        self.steps().validate()
    }
}

/// One step's measurement.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TablePoint {
    pub branch: Branch,
    pub freq_hz: f64,
    /// `A_damper / A_table` from the two accelerometers.
    pub transmissibility_re: f64,
    pub transmissibility_im: f64,
    /// `|T|` and its one-sigma error from the record's periods (their
    /// spread where the periods are correlated over the record).
    pub magnitude: f64,
    pub magnitude_stderr: f64,
    pub magnitude_error_is_spread: bool,
    /// The exact linear `T` for a linear payload (`None` with particles).
    pub exact_re: Option<f64>,
    pub exact_im: Option<f64>,
    /// Peak acceleration at the damper / g (its line).
    pub gamma: f64,
    /// The table's acceleration as recorded (its line), m/s².
    pub table_accel_mps2: f64,
    /// Yang's power through the table's transducer, W.
    pub power_in_w: f64,
    /// What the host's damping, a dashpot and the bed dissipated over the
    /// same samples, W: the truth the power in must read in steady state.
    pub true_dissipated_w: f64,
    /// Of it, the bed's (its ledger), W.
    pub true_damper_w: f64,
    /// The rate the host's stored energy (in the table's frame) changed
    /// over the step, W.
    pub host_storage_w: f64,
    /// The host's stored energy (in the table's frame) changed over the
    /// step by less than 5 % of the power in: steady, so the power in is
    /// the dissipation. Where it is not, the power in also fills or drains
    /// the host (and the bed), and the two differ by that.
    pub steady: bool,
}

impl TablePoint {
    pub fn transmissibility(&self) -> Complex64 {
        Complex64::new(self.transmissibility_re, self.transmissibility_im)
    }
}

/// Every step in the order driven.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TableSineResult {
    pub plan: TableSine,
    pub points: Vec<TablePoint>,
    pub steps: u64,
    pub wall_time_s: f64,
    #[serde(skip)]
    pub warnings: Vec<crate::warning::RunWarning>,
}

/// Runs `plan` with `test`'s host (on the table) and damper, one bed of
/// `scene`, the run started at the first frequency's steady guess, and
/// measures every step's recorded cycles.
pub fn run_table_sine(
    scene: &Scene,
    beds: &BedSource,
    test: &HostTest,
    plan: &TableSine,
    progress: &mut dyn FnMut(Progress),
) -> Result<TableSineResult, SceneError> {
    plan.validate()?;
    let g = scene.simulation.gravity_mps2;
    let on_table = HostTest {
        on_base: true,
        ..test.clone()
    };
    let (points, run) =
        plan.steps()
            .run_steps(scene, beds, &on_table, progress, |window, t, step| {
                measure(window, t, step.freq_hz, step.branch, g)
            })?;
    Ok(TableSineResult {
        plan: plan.clone(),
        points,
        steps: run.steps,
        wall_time_s: run.wall_time_s,
        warnings: run.warnings,
    })
}

/// One step of a table test: `run` cut to the step's recorded cycles.
fn measure(
    run: &HostRun,
    test: &HostTest,
    freq_hz: f64,
    branch: Branch,
    g_mps2: f64,
) -> Result<TablePoint, SceneError> {
    let trace = &run.trace;
    let rate_hz = trace.sample_rate_hz;
    let table = &trace.channel(ACCEL_CHANNEL)?.samples;
    let force = &trace.channel(FORCE_CHANNEL)?.samples;
    let damper = &trace.channel(DAMPER_ACCEL_CHANNEL)?.samples;
    let line = |x: &[f64]| sine_component(x, rate_hz, freq_hz).map_err(SignalsError::from);
    let (a_table, a_damper) = (line(table)?, line(damper)?);
    let t = a_damper / a_table;
    let (rel, is_spread) = receptance_error_rel(damper, table, rate_hz, freq_hz)?;
    let exact = match test.damper {
        Damper::Particles => None,
        d => Some(transmissibility(
            &test.host,
            d.payload(run.particle_mass_kg),
            TAU * freq_hz,
        )),
    };
    let power_in_w = power_input_corrected_w(force, table, rate_hz, freq_hz, HARMONICS, |f| {
        test.rig.expected_phase_error_rad(f)
    })
    .map_err(SignalsError::from)?;
    let r = &run.record;
    let span_s = r.time_s.last().copied().unwrap_or(0.0) - r.time_s.first().copied().unwrap_or(0.0);
    let rate = |v: &[f64]| match (v.first(), v.last(), span_s > 0.0) {
        (Some(a), Some(b), true) => (b - a) / span_s,
        _ => f64::NAN,
    };
    let true_damper_w = rate(&r.damper_dissipated_j);
    let storage_w = rate(&r.host_energy_j);
    Ok(TablePoint {
        branch,
        freq_hz,
        transmissibility_re: t.re,
        transmissibility_im: t.im,
        magnitude: t.norm(),
        magnitude_stderr: rel * t.norm(),
        magnitude_error_is_spread: is_spread,
        exact_re: exact.map(|e| e.re),
        exact_im: exact.map(|e| e.im),
        gamma: a_damper.norm() / g_mps2,
        table_accel_mps2: a_table.norm(),
        power_in_w,
        true_dissipated_w: rate(&r.host_dissipated_j)
            + rate(&r.dashpot_dissipated_j)
            + true_damper_w,
        true_damper_w,
        host_storage_w: storage_w,
        steady: storage_w.abs() <= STEADY_STORAGE_FRACTION * power_in_w.abs(),
    })
}

/// Largest change of the host's stored energy over a step, as a fraction of
/// the power in, for the step to count as steady.
const STEADY_STORAGE_FRACTION: f64 = 0.05;

/// The header of `transmissibility.csv`.
pub const TRANSMISSIBILITY_CSV_HEADER: &str = "step,branch,freq_hz,transmissibility_re,transmissibility_im,magnitude,magnitude_stderr,magnitude_error_is_spread,exact_magnitude,gamma,table_accel_mps2,power_in_w,true_dissipated_w,true_damper_w,host_storage_w,steady";

impl TableSineResult {
    /// `transmissibility.csv`: a row per step, in the order driven (the
    /// exact magnitude empty with particles).
    pub fn csv(&self) -> String {
        let mut csv = format!("{TRANSMISSIBILITY_CSV_HEADER}\n");
        for (k, p) in self.points.iter().enumerate() {
            let exact = p
                .exact_re
                .zip(p.exact_im)
                .map_or(String::new(), |(re, im)| {
                    Complex64::new(re, im).norm().to_string()
                });
            csv.push_str(&format!(
                "{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}\n",
                k + 1,
                p.branch.as_str(),
                p.freq_hz,
                p.transmissibility_re,
                p.transmissibility_im,
                p.magnitude,
                p.magnitude_stderr,
                p.magnitude_error_is_spread,
                exact,
                p.gamma,
                p.table_accel_mps2,
                p.power_in_w,
                p.true_dissipated_w,
                p.true_damper_w,
                p.host_storage_w,
                p.steady
            ));
        }
        csv
    }

    /// Writes `transmissibility.csv`, `transmissibility.json` (the plan,
    /// the host and damper, every step) and, with plots,
    /// `transmissibility.svg` (|T| against frequency, each branch, the
    /// exact line for a linear payload) into `dir`, each atomically.
    pub fn write(&self, dir: &std::path::Path, test: &HostTest) -> Result<(), SceneError> {
        let text = |name: &str, t| write_text(dir, name, t);
        text("transmissibility.csv", Ok(self.csv()))?;
        let summary = serde_json::json!({
            "host": test.host,
            "damper": test.damper,
            "plan": self.plan,
            "points": self.points,
            "steps": self.steps,
            "wall_time_s": self.wall_time_s,
            "warnings": self.warnings,
        });
        let json = serde_json::to_string_pretty(&summary).map_err(std::io::Error::other);
        text("transmissibility.json", json)?;
        #[cfg(feature = "plot")]
        self.plot(&dir.join("transmissibility.svg"))?;
        Ok(())
    }

    #[cfg(feature = "plot")]
    fn plot(&self, path: &std::path::Path) -> Result<(), SceneError> {
        use crate::signals::{Series, SeriesStyle, plot_xy_svg};
        let of = |b: Branch| self.points.iter().filter(move |p| p.branch == b);
        let mut series = vec![Series {
            name: "frequency going up".into(),
            points: of(Branch::Up).map(|p| (p.freq_hz, p.magnitude)).collect(),
            style: SeriesStyle::Line,
        }];
        if self.plan.down {
            series.push(Series {
                name: "coming back down".into(),
                points: of(Branch::Down).map(|p| (p.freq_hz, p.magnitude)).collect(),
                style: SeriesStyle::Line,
            });
        }
        let exact: Vec<(f64, f64)> = of(Branch::Up)
            .filter_map(|p| Some((p.freq_hz, Complex64::new(p.exact_re?, p.exact_im?).norm())))
            .collect();
        if !exact.is_empty() {
            series.push(Series {
                name: "exact (linear)".into(),
                points: exact,
                style: SeriesStyle::Points,
            });
        }
        plot_xy_svg(
            path,
            "Transmissibility: damper over table acceleration",
            "frequency (Hz)",
            "|A_damper / A_table|",
            &series,
        )?;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::experiment::host_test::frf::tests::test_of;

    /// On plate-40hz with a dashpot between the enclosure and the table
    /// (the exact linear answer known), a stepped sine of the table at
    /// 10 m/s² through the rig's chains reads `T` within 0.3 % in magnitude
    /// and 3 mrad in phase at every step (the chains' noise and ADC; the
    /// same chain on both accelerometers, so no calibration), and the power
    /// through the table's transducer reads what the host's damping and
    /// the dashpot dissipated within 1 %, its phase error taken out.
    #[test]
    fn a_linear_host_on_the_table_reads_its_exact_transmissibility() {
        let test = test_of(Damper::Dashpot { n_s_per_m: 20.0 }, "plate-40hz");
        let plan = TableSine {
            freqs_hz: vec![30.0, 36.0, 39.0, 40.0, 41.0, 44.0, 52.0],
            table_accel_mps2: 10.0,
            settle_cycles: 30,
            record_cycles: 20,
            down: false,
        };
        let result = run_table_sine(
            &Scene::thesis(),
            &BedSource::Settle,
            &test,
            &plan,
            &mut |_| {},
        )
        .expect("runs");
        assert_eq!(result.points.len(), 7);
        for p in &result.points {
            let exact = Complex64::new(p.exact_re.expect("linear"), p.exact_im.expect("linear"));
            let t = p.transmissibility();
            let mag = t.norm() / exact.norm() - 1.0;
            let phase = (t / exact).arg();
            assert!(mag.abs() < 3e-3, "{} Hz: |T| off by {mag}", p.freq_hz);
            assert!(
                phase.abs() < 3e-3,
                "{} Hz: phase off by {phase} rad",
                p.freq_hz
            );
            let power = p.power_in_w / p.true_dissipated_w - 1.0;
            assert!(
                power.abs() < 0.01,
                "{} Hz: power in off by {power}",
                p.freq_hz
            );
            assert!((p.table_accel_mps2 / 10.0 - 1.0).abs() < 0.01);
            assert!(p.steady, "{} Hz: storage {} W", p.freq_hz, p.host_storage_w);
        }
    }

    #[test]
    fn a_table_plan_is_checked() {
        let plan = TableSine {
            freqs_hz: vec![40.0],
            table_accel_mps2: 0.0,
            settle_cycles: 10,
            record_cycles: 10,
            down: false,
        };
        let e = plan.validate().expect_err("no acceleration");
        assert!(e.to_string().contains("table_accel_mps2"), "{e}");
    }
}
