//! `vlab.shake`: the shake of `vlab shake` (thesis Section 6.2, measured
//! by Yang's method, eq. 7.8-7.12), its channels as numpy arrays and its
//! summary as `summary.json` holds it.

use std::path::PathBuf;

use numpy::PyArray1;
use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;

use crate::common::{
    Callback, Figure, bed_source, channel_array, thread_pool, value_error, write_into,
};
use crate::scene::scene_of;
use vlab::experiment::damper::Progress;
use vlab::experiment::ensemble::{DEFAULT_BEDS, EnsembleFigure};
use vlab::experiment::ensemble_summary::EnsembleSummary;
use vlab::experiment::measurement::CalibrationSource;
use vlab::experiment::shake_plan::{ShakeOutcome, ShakePlan, ShakeRequest};
use vlab::signals::calibration::PhaseCalibration;

/// A finished shake: the summary, the rig's record and what the DEM knew.
#[pyclass(name = "Shake", module = "vlab._vlab")]
pub(crate) struct Shake {
    outcome: ShakeOutcome,
}

impl Shake {
    /// The ensemble's `figure` when there were several beds, else the one
    /// bed's `own`.
    fn of_beds(&self, own: Figure, figure: fn(&EnsembleSummary) -> &EnsembleFigure) -> Figure {
        self.outcome.summary().ensemble.as_ref().map_or(own, |e| {
            let f = figure(e);
            (f.mean, f.stderr)
        })
    }
}

#[pymethods]
impl Shake {
    /// The summary as JSON, as `summary.json` of `vlab shake` holds it.
    #[getter]
    fn summary_json(&self) -> String {
        self.outcome.summary_json()
    }

    /// The damping efficiency the DEM knows, `(value, one-sigma error)`:
    /// the ensemble's when there were several beds, else the bed's window's.
    #[getter]
    fn efficiency(&self) -> Figure {
        let d = &self.outcome.summary().dem;
        self.of_beds((d.efficiency, d.efficiency_stderr), |e| &e.dem_efficiency)
    }

    /// The damping efficiency the rig measured by Yang's method,
    /// `(value, one-sigma error)`, of the ensemble or of the one bed.
    #[getter]
    fn measured_efficiency(&self) -> Figure {
        let m = &self.outcome.summary().measured;
        self.of_beds((m.efficiency, m.efficiency_stderr), |e| {
            &e.measured_efficiency
        })
    }

    /// The energy the particles dissipated per cycle (J) by the DEM,
    /// `(value, one-sigma error)`.
    #[getter]
    fn energy_per_cycle_j(&self) -> Figure {
        let d = &self.outcome.summary().dem;
        self.of_beds((d.energy_per_cycle_j, d.energy_per_cycle_stderr_j), |e| {
            &e.dem_energy_per_cycle_j
        })
    }

    /// The energy per cycle (J) the rig measured, `(value, one-sigma error)`.
    #[getter]
    fn measured_energy_per_cycle_j(&self) -> Figure {
        let m = &self.outcome.summary().measured;
        self.of_beds((m.energy_per_cycle_j, m.energy_per_cycle_stderr_j), |e| {
            &e.measured_energy_per_cycle_j
        })
    }

    /// One sigma more, relative, for where the same beds driven hundreds
    /// more cycles would read (not in the figures' errors); `None` for one
    /// bed, whose figure claims only its own window.
    #[getter]
    fn longer_drive_rel(&self) -> Option<f64> {
        self.outcome.summary().ensemble.as_ref().map(|e| {
            vlab::experiment::ensemble_summary::longer_drive_rel(e.cycles - e.steady_first_cycle)
        })
    }

    /// What the run warns of, one sentence each.
    #[getter]
    fn warnings(&self) -> Vec<String> {
        self.outcome
            .summary()
            .warnings
            .iter()
            .map(ToString::to_string)
            .collect()
    }

    /// Samples per second of the rig's record (Hz).
    #[getter]
    fn sample_rate_hz(&self) -> f64 {
        self.outcome.run.experiment.trace.sample_rate_hz
    }

    /// The record's channels, `{name: unit}` (the first bed's record).
    #[getter]
    fn channels(&self) -> Vec<(String, String)> {
        self.outcome
            .run
            .experiment
            .trace
            .channels
            .iter()
            .map(|c| (c.name.clone(), c.unit.clone()))
            .collect()
    }

    /// The samples of channel `name` in its unit, as a numpy array.
    fn channel<'py>(&self, py: Python<'py>, name: &str) -> PyResult<Bound<'py, PyArray1<f64>>> {
        channel_array(py, &self.outcome.run.experiment.trace, name)
    }

    /// The time of each sample from the drive's start (s), as a numpy array:
    /// the record's own clock (zero at its start) plus where the record
    /// starts in the drive (`summary["steady_start_s"]`), so that it lines up
    /// with `dissipated_per_cycle_j`'s cycles.
    fn time_s<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        let trace = &self.outcome.run.experiment.trace;
        let from_s = self.outcome.summary().steady_start_s + trace.start_time_s;
        let n = trace.channels.first().map_or(0, |c| c.samples.len());
        let t: Vec<f64> = (0..n)
            .map(|k| from_s + k as f64 / trace.sample_rate_hz)
            .collect();
        PyArray1::from_vec(py, t)
    }

    /// The energy each bed's particles dissipated in each cycle of the
    /// drive (J), the first bed's, from the drive's start.
    fn dissipated_per_cycle_j<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        let snaps = &self.outcome.run.experiment.outcome.cycle_snapshots;
        PyArray1::from_vec(py, vlab::experiment::damper::cycle_energies(snaps, 0))
    }

    /// Writes what `vlab shake` writes into folder `out` (made if missing;
    /// each file written whole under a temporary name, then renamed).
    fn write(&mut self, out: PathBuf) -> PyResult<()> {
        write_into(&out, |dir| self.outcome.write(dir))
    }

    fn __repr__(&self) -> String {
        let s = self.outcome.summary();
        let (e, pm) = self.efficiency();
        format!(
            "<vlab.Shake {} Hz, Gamma {}: efficiency {e:.4}{} over {} bed{}>",
            s.freq_hz,
            s.gamma,
            pm.map_or(" (+- not known)".to_string(), |p| format!(" +- {p:.4}")),
            s.ensemble.as_ref().map_or(1, |e| e.beds),
            if s.ensemble.is_some() { "s" } else { "" }
        )
    }
}

/// Pours and settles the damper's beds, drives them at `freq_hz` and
/// `gamma` (peak acceleration / g) through the rig and measures them, as
/// `vlab shake` does with the flags of the same names; returns a `Shake`.
/// Each bad value is refused with its name, unit and range before any work
/// (`ValueError`).
#[pyfunction]
#[pyo3(signature = (
    freq_hz = 40.0,
    gamma = 20.0,
    *,
    beds = DEFAULT_BEDS,
    seed = None,
    scene = None,
    orientation = None,
    cycles = None,
    steady_cycles = None,
    rig = vlab::rig::DEFAULT_RIG.to_string(),
    noise_seed = None,
    calibration = None,
    threads = None,
    cache = true,
    progress = None,
))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn shake(
    py: Python<'_>,
    freq_hz: f64,
    gamma: f64,
    beds: u32,
    seed: Option<u64>,
    scene: Option<PathBuf>,
    orientation: Option<&str>,
    cycles: Option<u32>,
    steady_cycles: Option<u32>,
    rig: String,
    noise_seed: Option<u64>,
    calibration: Option<PathBuf>,
    threads: Option<usize>,
    cache: bool,
    progress: Option<Py<PyAny>>,
) -> PyResult<Shake> {
    let scene = scene_of(scene, orientation, seed, cycles, steady_cycles)?;
    let calibration = match calibration {
        Some(path) => {
            let table = PhaseCalibration::load_json(&path)
                .map_err(|e| value_error(format!("calibration {}: {e}", path.display())))?;
            CalibrationSource::Given(table, format!("table {}", path.display()))
        }
        None => CalibrationSource::OnTheFly,
    };
    let plan = ShakePlan::new(ShakeRequest {
        rig,
        noise_seed,
        calibration,
        beds,
        ..ShakeRequest::new(scene, freq_hz, gamma)
    })
    .map_err(value_error)?;
    let source = bed_source(py, cache)?;
    let pool = thread_pool(threads)?;
    let callback = Callback::new(progress);
    let outcome = py.detach(|| {
        let mut tell = |p: Progress| callback.call((p.phase, p.fraction, p.cycle));
        pool.install(|| plan.run(&source, rayon::current_num_threads(), &mut [], &mut tell))
    });
    callback.finish()?;
    let outcome = outcome.map_err(|e| PyRuntimeError::new_err(e.to_string()))?;
    Ok(Shake { outcome })
}
