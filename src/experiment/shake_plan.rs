//! One shape for a shake, whoever asks for it: a [`ShakeRequest`] in the
//! terms a user gives (the command line's flags, the browser's form, a
//! notebook's keywords), checked whole into a [`ShakePlan`] before any work
//! is done, run into a [`ShakeOutcome`] that writes its own files and its
//! summary. `vlab shake` and the browser lab both go this way, so what one
//! refuses the other refuses with the same words, and a bed driven by either
//! gives the same numbers.
//!
//! The physics is [`crate::experiment::shake`]'s (the drive of Terzioglu's
//! thesis, Section 6.2, measured by Yang's method, eq. 7.8-7.12) and the
//! ensemble's ([`crate::experiment::ensemble`]); this module only composes
//! and checks.

use std::fmt;
use std::path::Path;

use crate::experiment::damper::{Progress, StepObserver};
use crate::experiment::ensemble::{BedProvider, check_beds, run_ensemble_shake};
use crate::experiment::measurement::{CalibrationSource, ShakeSetup, check_given_calibration};
use crate::experiment::shake::{
    ShakeRun, ShakeSummary, check_record_window, resolve_rig, shake_drive,
};
use crate::rig::ShakerKind;
use crate::scene::{Scene, SceneError};

/// A shake as a user asks for it: plain values, none checked yet.
#[derive(Debug, Clone)]
pub struct ShakeRequest {
    /// The damper, its bed's seed and the drive's cycles.
    pub scene: Scene,
    /// Drive frequency (Hz).
    pub freq_hz: f64,
    /// Peak enclosure acceleration / g.
    pub gamma: f64,
    /// A built-in rig's name or a rig file (TOML).
    pub rig: String,
    /// How the enclosure is moved; `None` for the rig's own.
    pub shaker: Option<ShakerKind>,
    /// Seed of the rig's DAQ noise; `None` for the bed's seed.
    pub noise_seed: Option<u64>,
    /// The phase calibration: a table already read, or one measured now.
    pub calibration: CalibrationSource,
    /// Independent beds driven together (1 to 64).
    pub beds: u32,
}

impl ShakeRequest {
    /// The thesis damper at `freq_hz` and `gamma` through the default rig,
    /// calibrated on the fly, one bed: what a caller changes from.
    pub fn new(scene: Scene, freq_hz: f64, gamma: f64) -> ShakeRequest {
        ShakeRequest {
            scene,
            freq_hz,
            gamma,
            rig: crate::rig::DEFAULT_RIG.to_string(),
            shaker: None,
            noise_seed: None,
            calibration: CalibrationSource::OnTheFly,
            beds: 1,
        }
    }
}

/// Which value of a [`ShakeRequest`] a refusal is about, so that each front
/// end can name its own input (a flag, a form field, a keyword).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RequestField {
    /// `beds`.
    Beds,
    /// `freq_hz` and `gamma`, against the scene's step and record.
    Drive,
    /// `rig` and `shaker`.
    Rig,
    /// The scene's steady cycles against the rig's sampling.
    Record,
    /// `calibration`, against the rig and the drive.
    Calibration,
}

impl fmt::Display for RequestField {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            RequestField::Beds => "beds",
            RequestField::Drive => "drive",
            RequestField::Rig => "rig",
            RequestField::Record => "record",
            RequestField::Calibration => "calibration",
        })
    }
}

/// A request refused before any work: the library's refusal (its key, unit
/// and range) and the request's value it is about.
#[derive(Debug, thiserror::Error)]
#[error("{error}")]
pub struct RequestError {
    pub field: RequestField,
    pub error: SceneError,
}

/// A shake checked whole: the scene, the drive, the rig that can drive it,
/// the record it can sample, the calibration that fits them, the beds.
#[derive(Debug, Clone)]
pub struct ShakePlan {
    pub scene: Scene,
    pub setup: ShakeSetup,
    pub beds: u32,
}

impl ShakePlan {
    /// Checks `req` and plans it; nothing is poured, settled or driven, so a
    /// refusal costs nothing.
    pub fn new(req: ShakeRequest) -> Result<ShakePlan, RequestError> {
        let at = |field| move |error: SceneError| RequestError { field, error };
        check_beds(req.beds).map_err(at(RequestField::Beds))?;
        let drive =
            shake_drive(&req.scene, req.freq_hz, req.gamma).map_err(at(RequestField::Drive))?;
        let rig = resolve_rig(&req.rig, req.shaker, &drive).map_err(at(RequestField::Rig))?;
        check_record_window(&req.scene, drive.freq_hz(), rig.daq.sample_rate_hz)
            .map_err(|e| at(RequestField::Record)(e.into()))?;
        if let CalibrationSource::Given(table, _) = &req.calibration {
            check_given_calibration(table, &rig.name, drive.freq_hz())
                .map_err(at(RequestField::Calibration))?;
        }
        let noise_seed = req.noise_seed.unwrap_or(req.scene.simulation.seed);
        Ok(ShakePlan {
            scene: req.scene,
            setup: ShakeSetup {
                rig,
                drive,
                noise_seed,
                calibration: req.calibration,
            },
            beds: req.beds,
        })
    }

    /// Drives the planned beds (from `source`: settled now or read from the
    /// bed cache), on `threads` threads in all; the first bed on the
    /// calling thread with `observers` and `progress`. The thread count never
    /// changes a number, only how long it takes.
    pub fn run(
        &self,
        source: &dyn BedProvider,
        threads: usize,
        observers: &mut [&mut dyn StepObserver],
        progress: &mut dyn FnMut(Progress),
    ) -> Result<ShakeOutcome, SceneError> {
        let ensemble = run_ensemble_shake(
            &self.scene,
            &self.setup,
            source,
            self.beds,
            threads,
            observers,
            progress,
        )?;
        Ok(ShakeOutcome {
            plan: self.clone(),
            run: ensemble.first,
            others: ensemble.others,
        })
    }
}

/// A finished shake: the first bed's run (its records are the ones a lab
/// keeps; its summary carries the ensemble's figures when there were
/// several beds), every other bed's run, and the plan they came from.
pub struct ShakeOutcome {
    pub plan: ShakePlan,
    pub run: ShakeRun,
    pub others: Vec<ShakeRun>,
}

impl ShakeOutcome {
    /// What the run found, as `summary.json` holds it.
    pub fn summary(&self) -> &ShakeSummary {
        &self.run.summary
    }

    /// Writes the records, the calibration, the plots and `summary.json`
    /// (last) into `dir`, which must exist, each file atomically.
    pub fn write(&mut self, dir: &Path) -> Result<(), SceneError> {
        self.run
            .write(dir, &self.plan.scene, &self.plan.setup, &self.others)
    }

    /// The summary as pretty JSON, as `summary.json` holds it.
    pub fn summary_json(&self) -> String {
        self.run.summary_json()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::experiment::bed::cache::BedSource;
    use crate::scene::CyclesSpec;

    fn short_thesis() -> Scene {
        let mut scene = Scene::thesis();
        scene.drive.cycles = CyclesSpec::Count(8);
        scene.drive.steady_cycles = 4;
        scene
    }

    #[test]
    fn each_refusal_names_the_value_it_is_about_before_any_work() {
        let refused = |change: &dyn Fn(&mut ShakeRequest)| {
            let mut req = ShakeRequest::new(short_thesis(), 40.0, 20.0);
            change(&mut req);
            ShakePlan::new(req).expect_err("refused")
        };
        let e = refused(&|r| r.beds = 0);
        assert_eq!(e.field, RequestField::Beds);
        assert!(e.to_string().contains("1 to 64"), "{e}");
        let e = refused(&|r| r.gamma = -2.0);
        assert_eq!(e.field, RequestField::Drive, "{e}");
        let e = refused(&|r| r.freq_hz = 1e6);
        assert_eq!(e.field, RequestField::Drive, "{e}");
        assert!(e.to_string().contains("Hz"), "{e}");
        let e = refused(&|r| r.rig = "no-such-rig".into());
        assert_eq!(e.field, RequestField::Rig, "{e}");
        let e = refused(&|r| r.scene.drive.steady_cycles = 1);
        assert!(
            matches!(e.field, RequestField::Record | RequestField::Drive),
            "{:?}: {e}",
            e.field
        );
    }

    #[test]
    fn a_plan_keeps_the_request_and_takes_the_beds_seed_for_the_noise() {
        let mut req = ShakeRequest::new(short_thesis(), 40.0, 20.0);
        req.scene.simulation.seed = 17;
        let plan = ShakePlan::new(req.clone()).expect("plans");
        assert_eq!(plan.setup.noise_seed, 17);
        assert_eq!(plan.setup.drive.freq_hz(), 40.0);
        assert_eq!(plan.setup.drive.gamma(), 20.0);
        assert_eq!(plan.setup.rig.name, crate::rig::DEFAULT_RIG);
        req.noise_seed = Some(5);
        assert_eq!(ShakePlan::new(req).expect("plans").setup.noise_seed, 5);
    }

    #[test]
    fn a_planned_shake_is_the_library_shake_bit_for_bit() {
        // The plan composes, it does not change: one bed through the plan
        // gives the dissipation `run_shake` gives for the same scene, rig
        // and noise, to the last bit, whatever the thread count asked.
        let mut req = ShakeRequest::new(short_thesis(), 40.0, 20.0);
        req.rig = "ideal".into();
        let plan = ShakePlan::new(req).expect("plans");
        let planned = plan
            .run(&BedSource::Settle, 2, &mut [], &mut |_| {})
            .expect("runs");
        let direct = crate::experiment::shake::run_shake(&plan.scene, &plan.setup, &mut |_| {})
            .expect("runs");
        assert_eq!(
            planned.summary().dem.energy_per_cycle_j.to_bits(),
            direct.summary.dem.energy_per_cycle_j.to_bits()
        );
        assert_eq!(
            planned.summary().measured.energy_per_cycle_j.to_bits(),
            direct.summary.measured.energy_per_cycle_j.to_bits()
        );
        assert!(planned.others.is_empty() && planned.summary().ensemble.is_none());
    }
}
