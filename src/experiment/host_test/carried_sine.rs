//! A stepped sine up and down in one run, as a lab's sine controller steps
//! it: each frequency driven for its settling and recorded cycles, then the
//! next, the host's and the bed's state carried from one step to the next
//! (the force is continuous: every step starts at a zero of its sine). Up
//! the frequencies, then back down them.
//!
//! [`crate::experiment::host_test::frf::run_stepped_sine`] starts every
//! frequency from the same guessed state, which is the steady answer of a
//! linear host but hides what a nonlinear damper does: a granular damper's
//! response depends on its history (its bed bounces or does not, the
//! classical impact-damper branches of Masri and Caughey jump), so its
//! frequency response can differ going up and coming down, and jump. Here
//! each step is measured as a stepped-sine point is
//! ([`crate::experiment::host_test::frf`]: the receptance with the channels'
//! phase error taken out, Γ, its amplitude's error from the periods, the
//! power-input estimate against the DEM's), so that the two branches'
//! difference at a frequency can be told from a record's scatter.

use serde::Serialize;

use crate::experiment::bed::cache::BedSource;
use crate::experiment::damper::Progress;
use crate::experiment::host_test::frf::{FrfPoint, measure_point};
use crate::experiment::host_test::{HostRun, HostTest, run_host_test, write_text};
use crate::host::Excitation;
use crate::host::excitation::check_frequencies;
use crate::scene::{Scene, SceneError};
use crate::validation::{InvalidParameter, count_in};

/// How many combined standard errors apart the branches must be to be
/// called different.
pub const BRANCHES_APART_SIGMA: f64 = 3.0;

/// The plan: ascending frequencies, the force, the cycles of each step.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CarriedSine {
    pub freqs_hz: Vec<f64>,
    pub force_n: f64,
    pub settle_cycles: u32,
    pub record_cycles: u32,
    /// Come back down the frequencies after going up.
    pub down: bool,
}

/// Which way the frequency was moving when a point was taken.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Branch {
    Up,
    Down,
}

impl Branch {
    pub fn as_str(self) -> &'static str {
        match self {
            Branch::Up => "up",
            Branch::Down => "down",
        }
    }
}

/// One step's measurement.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CarriedPoint {
    pub branch: Branch,
    pub point: FrfPoint,
}

/// A frequency both branches measured.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BranchPair {
    pub freq_hz: f64,
    pub up_amplitude_m: f64,
    pub down_amplitude_m: f64,
    pub up_gamma: f64,
    pub down_gamma: f64,
    /// `(down − up) / up`.
    pub down_over_up_minus_1: f64,
    /// Its one-sigma error from the two records' amplitude errors (a
    /// record's periods' spread where its error could not be told).
    pub stderr: f64,
    /// Either record's error is its periods' spread.
    pub from_spread: bool,
    /// The branches stand more than [`BRANCHES_APART_SIGMA`] combined
    /// errors apart: hysteresis the records can tell.
    pub apart: bool,
}

/// Every step in the order driven.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CarriedSineResult {
    pub plan: CarriedSine,
    pub points: Vec<CarriedPoint>,
    pub steps: u64,
    pub wall_time_s: f64,
}

impl CarriedSine {
    /// Checks the plan: frequencies ascending in (0, 5000] Hz, at least two
    /// to go down, the force as the excitation takes it, at least 4 cycles
    /// recorded a step.
    pub fn validate(&self) -> Result<(), InvalidParameter> {
        check_frequencies(&self.freqs_hz)?;
        if self.down && self.freqs_hz.len() < 2 {
            return Err(InvalidParameter::new(
                "freqs_hz",
                self.freqs_hz.len() as f64,
                "frequencies",
                "at least 2 to come back down",
            ));
        }
        count_in(
            "settle_cycles",
            self.settle_cycles,
            "cycles",
            0,
            Some(10_000),
        )?;
        count_in(
            "record_cycles",
            self.record_cycles,
            "cycles",
            4,
            Some(10_000),
        )?;
        self.excitation().validate()
    }

    /// The frequencies in the order driven, each with its branch: up
    /// through all of them, then down from the one below the top.
    pub fn order(&self) -> Vec<(f64, Branch)> {
        let up = self.freqs_hz.iter().map(|f| (*f, Branch::Up));
        let down = self
            .freqs_hz
            .iter()
            .rev()
            .skip(1)
            .filter(|_| self.down)
            .map(|f| (*f, Branch::Down));
        up.chain(down).collect()
    }

    /// The force of the whole run.
    pub fn excitation(&self) -> Excitation {
        Excitation::Stepped {
            freqs_hz: self.order().into_iter().map(|(f, _)| f).collect(),
            cycles: self.settle_cycles + self.record_cycles,
            force_n: self.force_n,
        }
    }
}

/// Runs `plan` on `test`'s host and damper (its excitation replaced, the
/// run started at the first frequency's steady guess), one bed of `scene`,
/// and measures every step's recorded cycles.
pub fn run_carried_sine(
    scene: &Scene,
    beds: &BedSource,
    test: &HostTest,
    plan: &CarriedSine,
    progress: &mut dyn FnMut(Progress),
) -> Result<CarriedSineResult, SceneError> {
    let g = scene.simulation.gravity_mps2;
    let (points, run) = plan.run_steps(scene, beds, test, progress, |window, t, step| {
        let point = measure_point(window, t, step.freq_hz, step.from_s, g)?;
        Ok(CarriedPoint {
            branch: step.branch,
            point,
        })
    })?;
    Ok(CarriedSineResult {
        plan: plan.clone(),
        points,
        steps: run.steps,
        wall_time_s: run.wall_time_s,
    })
}

/// One step of a carried sine as its measurement sees it.
#[derive(Debug, Clone, Copy)]
pub struct Step {
    pub freq_hz: f64,
    pub branch: Branch,
    /// Where its recorded cycles start, s.
    pub from_s: f64,
}

impl CarriedSine {
    /// Runs the plan on `test`'s host and damper (its excitation replaced,
    /// the run started at the first frequency's steady guess; on a table
    /// if `test` is), one bed of `scene`, and gives `measure` each step's
    /// recorded cycles (the run cut to them), in the order driven, with
    /// the whole run.
    pub fn run_steps<P>(
        &self,
        scene: &Scene,
        beds: &BedSource,
        test: &HostTest,
        progress: &mut dyn FnMut(Progress),
        measure: impl Fn(&HostRun, &HostTest, Step) -> Result<P, SceneError>,
    ) -> Result<(Vec<P>, HostRun), SceneError> {
        self.validate()?;
        let excitation = self.excitation();
        let steps = excitation.steps();
        let t = HostTest {
            duration_s: steps.last().map_or(0.0, |s| s.2),
            excitation,
            start_steady: true,
            ..test.clone()
        };
        let run = run_host_test(scene, beds, &t, progress)?;
        let points = steps
            .iter()
            .zip(self.order())
            .map(|(&(freq_hz, start_s, end_s), (_, branch))| {
                let from_s = start_s + f64::from(self.settle_cycles) / freq_hz;
                let step = Step {
                    freq_hz,
                    branch,
                    from_s,
                };
                measure(&run.window(from_s, end_s), &t, step)
            })
            .collect::<Result<Vec<_>, SceneError>>()?;
        Ok((points, run))
    }
}

impl CarriedSineResult {
    /// Every step's warnings, each led by its branch and frequency, a
    /// text repeated from step to step (the bed carried on) once.
    pub fn warnings(&self) -> Vec<String> {
        let mut seen = std::collections::BTreeSet::new();
        let mut out = Vec::new();
        for c in &self.points {
            for w in &c.point.warnings {
                if seen.insert(w.as_str()) {
                    out.push(format!("{} {} Hz: {w}", c.branch.as_str(), c.point.freq_hz));
                }
            }
        }
        out
    }

    /// The points of one branch, in the order driven.
    pub fn branch(&self, branch: Branch) -> impl Iterator<Item = &CarriedPoint> {
        self.points.iter().filter(move |p| p.branch == branch)
    }

    /// Every frequency both branches measured, ascending.
    pub fn pairs(&self) -> Vec<BranchPair> {
        let mut pairs: Vec<BranchPair> = self
            .branch(Branch::Down)
            .filter_map(|down| {
                let up = self
                    .branch(Branch::Up)
                    .find(|u| u.point.freq_hz == down.point.freq_hz)?;
                let (a_up, a_down) = (up.point.amplitude_m, down.point.amplitude_m);
                let rel = a_down / a_up - 1.0;
                let stderr = (a_down / a_up)
                    * ((up.point.amplitude_stderr_m / a_up).powi(2)
                        + (down.point.amplitude_stderr_m / a_down).powi(2))
                    .sqrt();
                Some(BranchPair {
                    freq_hz: up.point.freq_hz,
                    up_amplitude_m: a_up,
                    down_amplitude_m: a_down,
                    up_gamma: up.point.gamma,
                    down_gamma: down.point.gamma,
                    down_over_up_minus_1: rel,
                    stderr,
                    from_spread: up.point.amplitude_error_is_spread
                        || down.point.amplitude_error_is_spread,
                    apart: stderr.is_finite() && rel.abs() > BRANCHES_APART_SIGMA * stderr,
                })
            })
            .collect();
        pairs.sort_by(|a, b| a.freq_hz.total_cmp(&b.freq_hz));
        pairs
    }
}

/// The header of `updown.csv`.
pub const UP_DOWN_CSV_HEADER: &str = "step,branch,freq_hz,receptance_re_m_per_n,receptance_im_m_per_n,amplitude_m,amplitude_stderr_m,amplitude_error_is_spread,gamma,damper_power_w,damper_power_stderr_w,true_damper_w,steady";

impl CarriedSineResult {
    /// `updown.csv`: a row per step, in the order driven.
    pub fn csv(&self) -> String {
        let mut csv = format!("{UP_DOWN_CSV_HEADER}\n");
        for (k, c) in self.points.iter().enumerate() {
            let p = &c.point;
            csv.push_str(&format!(
                "{},{},{},{},{},{},{},{},{},{},{},{},{}\n",
                k + 1,
                c.branch.as_str(),
                p.freq_hz,
                p.receptance_re,
                p.receptance_im,
                p.amplitude_m,
                p.amplitude_stderr_m,
                p.amplitude_error_is_spread,
                p.gamma,
                p.damper_power_w,
                p.damper_power_stderr_w,
                p.true_damper_w,
                p.steady
            ));
        }
        csv
    }

    /// `updown.json`: the plan, every step and the branches compared.
    pub fn summary(&self, test: &HostTest) -> serde_json::Value {
        serde_json::json!({
            "host": test.host,
            "damper": test.damper,
            "plan": self.plan,
            "branches_apart_sigma": BRANCHES_APART_SIGMA,
            "pairs": self.pairs(),
            "points": self.points,
            "steps": self.steps,
            "wall_time_s": self.wall_time_s,
        })
    }

    /// Writes `updown.csv`, `updown.json` and, with plots, `updown.svg`
    /// (the receptance's magnitude on both branches) into `dir`, which must
    /// exist, each atomically.
    pub fn write(&self, dir: &std::path::Path, test: &HostTest) -> Result<(), SceneError> {
        let text = |name: &str, t| write_text(dir, name, t);
        text("updown.csv", Ok(self.csv()))?;
        let json = serde_json::to_string_pretty(&self.summary(test)).map_err(std::io::Error::other);
        text("updown.json", json)?;
        #[cfg(feature = "plot")]
        {
            use crate::signals::{Series, SeriesStyle, plot_xy_svg};
            let branch = |b: Branch, name: &str| Series {
                name: name.into(),
                points: self
                    .branch(b)
                    .map(|c| (c.point.freq_hz, c.point.receptance().norm() * 1e3))
                    .collect(),
                style: SeriesStyle::Line,
            };
            let mut series = vec![branch(Branch::Up, "frequency going up")];
            if self.plan.down {
                series.push(branch(Branch::Down, "coming back down"));
            }
            plot_xy_svg(
                &dir.join("updown.svg"),
                &format!(
                    "{} on {}, {} N stepped sine in one run",
                    test.damper.label(),
                    test.host.name,
                    self.plan.force_n
                ),
                "frequency (Hz)",
                "|X / F| at the damper (mm/N)",
                &series,
            )?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::experiment::host_test::Damper;
    use crate::experiment::host_test::frf::tests::test_of;
    use crate::host::{Payload, Point, receptance};
    use realfft::num_complex::Complex64;
    use std::f64::consts::TAU;

    /// A linear host has one steady answer: up and down, every step of one
    /// run reads the exact receptance of the single mode with its dashpot
    /// (zeta 0.0428: a step's transient falls to e^-5 over 20 settling
    /// cycles) within 1 % and 1 mrad, the branches agree within 0.5 %, and
    /// none is called apart. A window off by a step, or a step that did not
    /// start where the record says, reads another frequency's answer (5-20
    /// % away at 1 Hz steps).
    #[test]
    fn a_linear_host_reads_its_exact_receptance_up_and_down_without_hysteresis() {
        let test = test_of(Damper::Dashpot { n_s_per_m: 10.0 }, "plate-40hz");
        let plan = CarriedSine {
            freqs_hz: vec![38.0, 39.0, 40.0, 41.0, 42.0],
            force_n: 2.0,
            settle_cycles: 20,
            record_cycles: 20,
            down: true,
        };
        let result = run_carried_sine(
            &Scene::thesis(),
            &BedSource::Settle,
            &test,
            &plan,
            &mut |_| {},
        )
        .expect("runs");
        assert_eq!(result.points.len(), 9);
        let payload = Payload {
            mass_kg: 0.0,
            dashpot_n_s_per_m: 10.0,
        };
        for p in &result.points {
            let w = TAU * p.point.freq_hz;
            let s = Complex64::new(-w * w * payload.mass_kg, w * payload.dashpot_n_s_per_m);
            let want = receptance(&test.host, w, s, Point::Drive, Point::Damper);
            let got = p.point.receptance();
            assert!(
                (got.norm() / want.norm() - 1.0).abs() < 0.01,
                "{:?} {} Hz: {got} against {want}",
                p.branch,
                p.point.freq_hz
            );
            assert!((got / want).arg().abs() < 1e-3, "{p:?}");
            assert!(
                (p.point.damper_power_w / p.point.true_damper_w - 1.0).abs() < 0.03,
                "{p:?}"
            );
        }
        let pairs = result.pairs();
        assert_eq!(
            pairs.iter().map(|p| p.freq_hz).collect::<Vec<_>>(),
            vec![38.0, 39.0, 40.0, 41.0]
        );
        for p in &pairs {
            assert!(p.down_over_up_minus_1.abs() < 0.005, "{p:?}");
            assert!(!p.apart && p.stderr.is_finite(), "{p:?}");
        }
    }

    #[test]
    fn the_order_goes_up_then_down_from_below_the_top() {
        let plan = CarriedSine {
            freqs_hz: vec![1.0, 2.0, 3.0],
            force_n: 1.0,
            settle_cycles: 1,
            record_cycles: 4,
            down: true,
        };
        let order: Vec<(f64, &str)> = plan.order().iter().map(|(f, b)| (*f, b.as_str())).collect();
        assert_eq!(
            order,
            vec![
                (1.0, "up"),
                (2.0, "up"),
                (3.0, "up"),
                (2.0, "down"),
                (1.0, "down")
            ]
        );
        let descending = CarriedSine {
            freqs_hz: vec![2.0, 1.0],
            ..plan
        };
        assert!(descending.validate().is_err());
    }
}
