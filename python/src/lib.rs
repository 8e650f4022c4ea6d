//! The compiled half of the Python package `vlab` (python/vlab/__init__.py
//! is the other): the shake of `vlab shake` (Terzioglu's thesis, Section
//! 6.2, measured by Yang's method, eq. 7.8-7.12) as a function that returns
//! the rig's channels as numpy arrays and the summary `summary.json` holds.
//!
//! It plans and runs exactly what the command line does
//! ([`vlab::experiment::shake_plan`]): the same request, the same checks
//! worded alike, the same numbers for the same scene and seed whatever the
//! thread count. The bed cache is the command line's too: a bed poured by
//! a build of the same optimisation (pip's is a release build, as
//! `cargo build --release` is) is read back by the other.

use std::path::PathBuf;

use numpy::{PyArray1, PyReadonlyArray1};
use pyo3::exceptions::{PyKeyError, PyRuntimeError, PyValueError};
use pyo3::prelude::*;

use vlab::atomic_write::OutputDir;
use vlab::experiment::bed::cache::{BedCache, BedSource};
use vlab::experiment::calibration_plan::{CalibrationPlan, CalibrationRow};
use vlab::experiment::damper::Progress;
use vlab::experiment::drop::DropParticle;
use vlab::experiment::drop::series::{DropRequest, DropSeries, sampling_warning};
use vlab::experiment::ensemble::{DEFAULT_BEDS, EnsembleFigure};
use vlab::experiment::ensemble_summary::EnsembleSummary;
use vlab::experiment::measurement::CalibrationSource;
use vlab::experiment::shake_plan::{ShakeOutcome, ShakePlan, ShakeRequest};
use vlab::host::HostSpec;
use vlab::rig::{ACCEL_CHANNEL, DROP_RIG, DropRigSpec, FORCE_CHANNEL, RigFile, ShakerKind};
use vlab::scene::{Orientation, Scene, SceneError, SceneOverrides, scene_figures};
use vlab::signals::calibration::PhaseCalibration;
use vlab::signals::impacts::default_force_channel;
use vlab::signals::{AnalysisOptions, ImpactParams, Trace, analyse_trace, cor_report, read_trace};
use vlab::study::dissipation_map::{MapSource, dissipation_map};
use vlab::study::host_prediction::{HostPrediction, check_request};
use vlab::study::sweep::SweepFile;
use vlab::validation::{Bound as Limit, in_range, positive};

/// A finished shake: the summary, the rig's record and what the DEM knew.
#[pyclass(name = "Shake", module = "vlab._vlab")]
struct Shake {
    outcome: ShakeOutcome,
}

/// A figure and its one-sigma error (`None` where it is not known).
type Figure = (f64, Option<f64>);

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
        let trace = &self.outcome.run.experiment.trace;
        let c = trace.channel(name).map_err(|_| {
            let names: Vec<&str> = trace.channels.iter().map(|c| c.name.as_str()).collect();
            PyKeyError::new_err(format!(
                "no channel {name:?} in the record; it has {}",
                names.join(", ")
            ))
        })?;
        Ok(PyArray1::from_slice(py, &c.samples))
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

/// The scene of a call: a scene file or the thesis damper, with the
/// keyword arguments over it (as `vlab shake`'s flags go over the file).
fn scene_of(
    scene: Option<PathBuf>,
    orientation: Option<&str>,
    seed: Option<u64>,
    cycles: Option<u32>,
    steady_cycles: Option<u32>,
) -> PyResult<Scene> {
    let orientation = orientation.map(orientation_of).transpose()?;
    let base = Scene::load_or_thesis(scene.as_deref()).map_err(value_error)?;
    SceneOverrides {
        cycles,
        steady_cycles,
        orientation,
        seed,
        dt_s: None,
    }
    .apply(base)
    .map_err(value_error)
}

/// The `orientation` keyword: "vertical" or "horizontal".
fn orientation_of(name: &str) -> PyResult<Orientation> {
    match name {
        "vertical" => Ok(Orientation::Vertical),
        "horizontal" => Ok(Orientation::Horizontal),
        other => Err(PyValueError::new_err(format!(
            "orientation = {other:?}: must be \"vertical\" or \"horizontal\""
        ))),
    }
}

/// Makes folder `out` if missing and runs `write` into it; a failed write
/// leaves no folder it made.
fn write_into(
    out: &std::path::Path,
    write: impl FnOnce(&std::path::Path) -> Result<(), SceneError>,
) -> PyResult<()> {
    let made = OutputDir::prepare(out).map_err(|e| {
        PyRuntimeError::new_err(format!("cannot create folder {}: {e}", out.display()))
    })?;
    made.keep_if_ok(write(out))
        .map_err(|e| PyRuntimeError::new_err(e.to_string()))
}

fn value_error(e: impl std::fmt::Display) -> PyErr {
    PyValueError::new_err(e.to_string())
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
fn shake(
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
    let source = match (cache, BedCache::user()) {
        (false, _) => BedSource::Settle,
        (true, Ok(c)) => BedSource::Cache(c),
        (true, Err(e)) => {
            // As the command line says it: the run goes on, settling anew.
            let said = std::ffi::CString::new(format!("{e}; the beds are settled anew"))
                .unwrap_or_default();
            let category = py.get_type::<pyo3::exceptions::PyUserWarning>();
            PyErr::warn(py, &category, &said, 1)?;
            BedSource::Settle
        }
    };
    // As `vlab --threads N`: a pool of N workers for everything the run
    // does in parallel, the beds among them (N never changes a number).
    let threads = threads.unwrap_or_else(|| {
        std::thread::available_parallelism().map_or(1, std::num::NonZeroUsize::get)
    });
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| PyRuntimeError::new_err(format!("cannot start {threads} threads: {e}")))?;
    // The first error the callback raises (a bug in it, or Ctrl-C while it
    // ran) stops the calls and is raised when the run ends: the run itself
    // cannot be stopped half-way.
    let mut raised: Option<PyErr> = None;
    let outcome = py.detach(|| {
        let mut tell = |p: Progress| {
            if let Some(f) = progress.as_ref().filter(|_| raised.is_none()) {
                raised = Python::attach(|py| f.call1(py, (p.phase, p.fraction, p.cycle)).err());
            }
        };
        pool.install(|| plan.run(&source, rayon::current_num_threads(), &mut [], &mut tell))
    });
    if let Some(e) = raised {
        return Err(e);
    }
    let outcome = outcome.map_err(|e| PyRuntimeError::new_err(e.to_string()))?;
    Ok(Shake { outcome })
}

/// Yang's method on a record, as `vlab analyze --json` does it: a record
/// file (CSV, WAV with its sidecar, TDMS) or the two channels as arrays
/// with their sample rate; returns the analysis as JSON (the wrapper makes
/// it a dict). The keyword arguments are the command's flags.
#[pyfunction]
#[pyo3(signature = (
    record = None,
    *,
    acceleration = None,
    force = None,
    sample_rate_hz = None,
    freq_hz = None,
    gamma = None,
    particle_mass_kg = None,
    calibration = None,
    force_freq = false,
    force_calibration = false,
    as_recorded = false,
    force_channel = FORCE_CHANNEL.to_string(),
    accel_channel = ACCEL_CHANNEL.to_string(),
))]
#[allow(clippy::too_many_arguments)]
fn analyze(
    py: Python<'_>,
    record: Option<PathBuf>,
    acceleration: Option<PyReadonlyArray1<'_, f64>>,
    force: Option<PyReadonlyArray1<'_, f64>>,
    sample_rate_hz: Option<f64>,
    freq_hz: Option<f64>,
    gamma: Option<f64>,
    particle_mass_kg: Option<f64>,
    calibration: Option<PathBuf>,
    force_freq: bool,
    force_calibration: bool,
    as_recorded: bool,
    force_channel: String,
    accel_channel: String,
) -> PyResult<String> {
    let trace = match (record, acceleration, force, sample_rate_hz) {
        (Some(path), None, None, None) => {
            read_trace(&path).map_err(|e| value_error(format!("{}: {e}", path.display())))?
        }
        (None, Some(a), Some(f), Some(rate)) => {
            let samples = |x: &PyReadonlyArray1<'_, f64>| -> PyResult<Vec<f64>> {
                Ok(x.as_slice().map_err(value_error)?.to_vec())
            };
            let mut t = Trace::new(rate, 0.0).map_err(value_error)?;
            t.add_channel(&accel_channel, "m/s^2", samples(&a)?)
                .map_err(value_error)?;
            t.add_channel(&force_channel, "N", samples(&f)?)
                .map_err(value_error)?;
            t
        }
        _ => {
            return Err(PyValueError::new_err(
                "give a record file, or acceleration (m/s^2), force (N) and sample_rate_hz (Hz), not both",
            ));
        }
    };
    let table = match &calibration {
        Some(path) => Some(
            PhaseCalibration::load_json(path)
                .map_err(|e| value_error(format!("calibration {}: {e}", path.display())))?,
        ),
        None => None,
    };
    let options = AnalysisOptions {
        force_channel,
        accel_channel,
        freq_hz,
        force_freq,
        gamma,
        particle_mass_kg,
        calibration: table,
        calibration_name: calibration
            .as_ref()
            .map_or("none".into(), |p| p.display().to_string()),
        force_calibration,
        as_recorded,
    };
    let analysis = py
        .detach(|| analyse_trace(&trace, &options))
        .map_err(value_error)?;
    serde_json::to_string(&analysis).map_err(|e| PyRuntimeError::new_err(e.to_string()))
}

/// The drop-test restitution estimator (thesis eq. 7.3-7.5) on a force
/// record, as `vlab cor --json` does it: a record file, or the force as an
/// array (N) with its sample rate; returns the report as JSON (the wrapper
/// makes it a dict).
#[pyfunction]
#[pyo3(signature = (
    record = None,
    *,
    force = None,
    sample_rate_hz = None,
    channel = None,
    g_mps2 = 9.81,
    threshold_n = None,
    holdoff_s = None,
))]
#[allow(clippy::too_many_arguments)]
fn cor(
    py: Python<'_>,
    record: Option<PathBuf>,
    force: Option<PyReadonlyArray1<'_, f64>>,
    sample_rate_hz: Option<f64>,
    channel: Option<String>,
    g_mps2: f64,
    threshold_n: Option<f64>,
    holdoff_s: Option<f64>,
) -> PyResult<String> {
    let (name, trace) = match (record, force, sample_rate_hz) {
        (Some(path), None, None) => {
            let trace =
                read_trace(&path).map_err(|e| value_error(format!("{}: {e}", path.display())))?;
            (path.display().to_string(), trace)
        }
        (None, Some(f), Some(rate)) => {
            let mut t = Trace::new(rate, 0.0).map_err(value_error)?;
            t.add_channel("force", "N", f.as_slice().map_err(value_error)?.to_vec())
                .map_err(value_error)?;
            ("array".to_string(), t)
        }
        _ => {
            return Err(PyValueError::new_err(
                "give a record file, or force (N) and sample_rate_hz (Hz), not both",
            ));
        }
    };
    let Some(channel) = channel.or_else(|| default_force_channel(&trace)) else {
        return Err(PyValueError::new_err(format!(
            "{name} has channels [{}] and none is called 'force': name it with channel=",
            trace.channel_names().join(", ")
        )));
    };
    let params = ImpactParams {
        threshold_n,
        holdoff_s,
        ..ImpactParams::default()
    };
    let report = py
        .detach(|| cor_report(&name, &trace, &channel, &params, g_mps2))
        .map_err(value_error)?;
    serde_json::to_string(&report).map_err(|e| PyRuntimeError::new_err(e.to_string()))
}

/// A finished drop test: its summary (`drop.json`) and each height's
/// force record.
#[pyclass(name = "Drop", module = "vlab._vlab")]
struct Drop {
    series: DropSeries,
}

#[pymethods]
impl Drop {
    #[getter]
    fn summary_json(&self) -> String {
        self.series.summary_json()
    }

    #[getter]
    fn heights_m(&self) -> Vec<f64> {
        self.series.setups.iter().map(|s| s.height_m).collect()
    }

    #[getter]
    fn sample_rate_hz(&self) -> f64 {
        self.series
            .runs
            .first()
            .map_or(f64::NAN, |(out, _)| out.trace.sample_rate_hz)
    }

    /// The force record of the drop from `height_m` (N).
    fn force<'py>(&self, py: Python<'py>, height_m: f64) -> PyResult<Bound<'py, PyArray1<f64>>> {
        let k = self
            .series
            .setups
            .iter()
            .position(|s| s.height_m == height_m)
            .ok_or_else(|| {
                PyKeyError::new_err(format!(
                    "no drop from {height_m} m; the heights are {:?}",
                    self.heights_m()
                ))
            })?;
        let trace = &self.series.runs[k].0.trace;
        let c = trace
            .channel(vlab::rig::DROP_FORCE_CHANNEL)
            .map_err(|e| PyRuntimeError::new_err(e.to_string()))?;
        Ok(PyArray1::from_slice(py, &c.samples))
    }

    /// Writes what `vlab drop` writes into folder `out`, as `Shake.write`.
    fn write(&self, out: PathBuf) -> PyResult<()> {
        write_into(&out, |dir| self.series.write(dir))
    }

    fn __repr__(&self) -> String {
        let s = &self.series.summary;
        format!(
            "<vlab.Drop {} from {} height{}: COR {:.5} +- {:.5} over {} triples>",
            s.particle,
            s.runs.len(),
            if s.runs.len() == 1 { "" } else { "s" },
            s.cor_mean,
            s.cor_std,
            s.cor_per_triple.len()
        )
    }
}

/// The drop test of `vlab drop` (thesis Section 7.3): a preset sphere
/// dropped on the drop rig's plate from each of `heights_m`, its force
/// recorded and the lab's estimator turning the impacts' gaps into
/// restitution, beside what the DEM contact did. Refusals name the
/// keyword, its unit and its range, before any work.
#[pyfunction]
#[pyo3(signature = (
    heights_m = vec![0.05],
    *,
    particle = "acrylic-smooth".to_string(),
    cor = None,
    diameter_m = vlab::experiment::drop::DEFAULT_DIAMETER_M,
    sample_rate_hz = None,
    rig = None,
    threshold_n = None,
    holdoff_s = None,
    seed = 1,
))]
#[allow(clippy::too_many_arguments)]
fn drop_test(
    py: Python<'_>,
    heights_m: Vec<f64>,
    particle: String,
    cor: Option<f64>,
    diameter_m: f64,
    sample_rate_hz: Option<f64>,
    rig: Option<PathBuf>,
    threshold_n: Option<f64>,
    holdoff_s: Option<f64>,
    seed: u64,
) -> PyResult<Drop> {
    let preset = DropParticle::ALL
        .into_iter()
        .find(|p| p.name() == particle)
        .ok_or_else(|| {
            let names: Vec<&str> = DropParticle::ALL.iter().map(|p| p.name()).collect();
            PyValueError::new_err(format!(
                "particle = {particle:?}: must be one of {}",
                names.join(", ")
            ))
        })?;
    let rig = match &rig {
        Some(path) => DropRigSpec::load(path),
        None => DropRigSpec::builtin(DROP_RIG),
    }
    .map_err(value_error)?;
    let request = DropRequest {
        particle: preset,
        restitution: cor,
        diameter_m,
        heights_m,
        rig,
        sample_rate_hz,
        seed,
    };
    // The setups' keys, as this function's keywords call them.
    let keyword = |e: SceneError| match e {
        SceneError::Invalid(p) => {
            let name = match p.key.as_str() {
                "restitution" => "cor",
                "height_m" => "heights_m",
                "daq.sample_rate_hz" if sample_rate_hz.is_some() => "sample_rate_hz",
                other => other,
            };
            value_error(p.renamed(name))
        }
        other => value_error(other),
    };
    let setups = request.setups().map_err(keyword)?;
    // The estimator's settings, checked as the command's flags are.
    if let Some(t) = threshold_n {
        positive("threshold_n", t, "N").map_err(value_error)?;
    }
    if let Some(h) = holdoff_s {
        in_range("holdoff_s", h, "s", Limit::Closed(0.0), Limit::Unbounded).map_err(value_error)?;
    }
    let rate = if sample_rate_hz.is_some() {
        "sample_rate_hz"
    } else {
        "daq.sample_rate_hz"
    };
    let warnings: Vec<_> = sampling_warning(&setups, rate)
        .map_err(keyword)?
        .into_iter()
        .collect();
    let params = ImpactParams {
        threshold_n,
        holdoff_s,
        ..ImpactParams::default()
    };
    let series = py
        .detach(|| DropSeries::run(setups, &params, preset.material_name(), warnings))
        .map_err(|e| {
            // The causes in one line, each once (an invalid value's own
            // error repeats its text).
            let mut text = e.to_string();
            let mut source = std::error::Error::source(&e);
            while let Some(s) = source {
                let cause = s.to_string();
                if !text.contains(&cause) {
                    text.push_str(&format!(": {cause}"));
                }
                source = s.source();
            }
            PyRuntimeError::new_err(text)
        })?;
    Ok(Drop { series })
}

/// A host's predicted response ([`HostPrediction`]).
#[pyclass(module = "vlab._vlab", frozen)]
struct HostPredict {
    prediction: HostPrediction,
}

#[pymethods]
impl HostPredict {
    /// What predict.json holds, as JSON text.
    #[getter]
    fn summary_json(&self) -> String {
        serde_json::to_string(&self.prediction.summary()).unwrap_or_default()
    }

    /// What predict.csv holds, column by column: numpy arrays of float64,
    /// `extrapolated` of bool and `roots` of int64.
    #[getter]
    fn columns<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, pyo3::types::PyDict>> {
        let p = &self.prediction;
        let col = |f: &dyn Fn(&vlab::host::map_model::SteadyResponse) -> f64| -> Vec<f64> {
            p.points.iter().map(|(r, _)| f(r)).collect()
        };
        let d = pyo3::types::PyDict::new(py);
        let floats: [(&str, Vec<f64>); 12] = [
            ("freq_hz", col(&|r| r.freq_hz)),
            ("amplitude_m", col(&|r| r.amplitude_m)),
            (
                "amplitude_if_more_damping_m",
                col(&|r| r.amplitude_if_more_damping_m),
            ),
            (
                "amplitude_if_less_damping_m",
                col(&|r| r.amplitude_if_less_damping_m),
            ),
            ("phase_rad", col(&|r| r.phase_rad)),
            ("receptance_m_per_n", col(&|r| r.amplitude_m / p.force_n)),
            ("gamma", col(&|r| r.damper.gamma)),
            ("efficiency", col(&|r| r.damper.efficiency)),
            ("efficiency_se", col(&|r| r.damper.efficiency_se)),
            ("damping_n_s_per_m", col(&|r| r.damper.damping_n_s_per_m)),
            ("apparent_mass_kg", col(&|r| r.damper.apparent_mass_kg)),
            (
                "damper_energy_per_cycle_j",
                col(&|r| r.damper_energy_per_cycle_j),
            ),
        ];
        for (name, values) in floats {
            d.set_item(name, PyArray1::from_vec(py, values))?;
        }
        let extrapolated: Vec<bool> = p
            .points
            .iter()
            .map(|(r, _)| r.damper.extrapolated)
            .collect();
        d.set_item("extrapolated", PyArray1::from_vec(py, extrapolated))?;
        let roots: Vec<i64> = p.points.iter().map(|(_, n)| *n as i64).collect();
        d.set_item("roots", PyArray1::from_vec(py, roots))?;
        Ok(d)
    }

    /// The map's words on each response outside it.
    #[getter]
    fn warnings(&self) -> Vec<String> {
        self.prediction.warnings.clone()
    }

    /// Writes predict.csv and predict.json into folder `out`, as `vlab host
    /// predict --out` does.
    fn write(&self, out: PathBuf) -> PyResult<()> {
        write_into(&out, |dir| self.prediction.write(dir))
    }

    fn __repr__(&self) -> String {
        let p = &self.prediction;
        format!(
            "<vlab.HostPrediction {} with the damper of {}: {} frequencies, {} outside the map>",
            p.host.name,
            p.map_label,
            p.points.len(),
            p.warnings.len()
        )
    }
}

/// The host's steady response to a stepped sine of `force_n` at each of
/// `freqs_hz`, predicted from the dissipation map of the sweep `map` (its
/// sweep.csv), as `vlab host predict` does with the flags of the same
/// names. Refusals name the keyword, before any work (`ValueError`).
#[pyfunction]
#[pyo3(signature = (map, freqs_hz, force_n, *, host = vlab::host::DEFAULT_HOST.to_string(), orientation = None, yang = false))]
fn host_predict(
    map: PathBuf,
    freqs_hz: Vec<f64>,
    force_n: f64,
    host: String,
    orientation: Option<&str>,
    yang: bool,
) -> PyResult<HostPredict> {
    check_request(&freqs_hz, force_n).map_err(value_error)?;
    let orientation = orientation.map(orientation_of).transpose()?;
    let in_map =
        |e: &dyn std::fmt::Display| PyValueError::new_err(format!("map = {}: {e}", map.display()));
    let file = SweepFile::read(&map).map_err(|e| in_map(&e))?;
    let source = if yang {
        MapSource::Yang
    } else {
        MapSource::Dem
    };
    let dissipation = dissipation_map(&file, orientation, None, source).map_err(|e| in_map(&e))?;
    let spec = HostSpec::from_name_or_path(&host)
        .map_err(|e| PyValueError::new_err(format!("host = {host:?}: {e}")))?;
    let label = map.display().to_string();
    let prediction = HostPrediction::run(&dissipation, label, source, spec, &freqs_hz, force_n);
    Ok(HostPredict { prediction })
}

/// A scene as `vlab scene` reads it (a file over the built-in thesis
/// damper, or the damper itself): its TOML and its figures (`vlab scene
/// --json`), as a JSON text `{"toml": ..., "figures": ...}`.
#[pyfunction]
#[pyo3(signature = (scene = None))]
fn scene_json(scene: Option<PathBuf>) -> PyResult<String> {
    let resolved = match &scene {
        Some(path) => Scene::load_over_preset(path).map_err(value_error)?,
        None => Scene::thesis(),
    };
    let figures = scene_figures(&resolved).map_err(value_error)?;
    let out = serde_json::json!({ "toml": resolved.to_toml(), "figures": figures });
    Ok(out.to_string())
}

/// A rig's phase-error calibration ([`CalibrationPlan`]).
#[pyclass(module = "vlab._vlab", frozen)]
struct Calibration {
    table: PhaseCalibration,
    rows: Vec<CalibrationRow>,
}

#[pymethods]
impl Calibration {
    /// Each frequency's row, as `vlab calibrate --json` prints them (JSON).
    #[getter]
    fn rows_json(&self) -> String {
        serde_json::to_string(&self.rows).unwrap_or_default()
    }

    /// The table `vlab calibrate --out` writes and `calibration=` reads (JSON).
    #[getter]
    fn table_json(&self) -> String {
        serde_json::to_string(&self.table).unwrap_or_default()
    }

    /// Writes the table to the file `path`, as `vlab calibrate --out` does.
    fn write(&self, path: PathBuf) -> PyResult<()> {
        self.table
            .save_json(&path)
            .map_err(|e| PyRuntimeError::new_err(e.to_string()))
    }
}

/// The rig's phase error measured on the empty enclosure at each of
/// `freqs_hz`, averaged over `gammas`, as `vlab calibrate` does with the
/// flags of the same names; returns a `Calibration`. Refusals name the
/// keyword before any work (`ValueError`); the GIL is released while the
/// shaker runs.
#[pyfunction]
#[pyo3(signature = (
    freqs_hz,
    *,
    gammas = vec![2.0, 5.0, 10.0],
    rig = vlab::rig::DEFAULT_RIG.to_string(),
    shaker = None,
    cycles = 8,
    record_cycles = 5,
    dt_s = 1e-6,
))]
#[allow(clippy::too_many_arguments)]
fn calibrate(
    py: Python<'_>,
    freqs_hz: Vec<f64>,
    gammas: Vec<f64>,
    rig: String,
    shaker: Option<&str>,
    cycles: u32,
    record_cycles: u32,
    dt_s: f64,
) -> PyResult<Calibration> {
    let shaker = match shaker {
        None => None,
        Some("prescribed") => Some(ShakerKind::Prescribed),
        Some("electrodynamic") => Some(ShakerKind::Electrodynamic),
        Some(other) => {
            return Err(PyValueError::new_err(format!(
                "shaker = {other:?}: must be \"prescribed\" or \"electrodynamic\""
            )));
        }
    };
    let plan = CalibrationPlan {
        rig,
        shaker,
        freqs_hz,
        gammas,
        cycles,
        record_cycles,
        dt_s,
    };
    let g = Scene::thesis().simulation.gravity_mps2;
    let spec = plan.check(g).map_err(|e| match &e {
        SceneError::Invalid(_) => value_error(e),
        _ => PyValueError::new_err(format!("rig = {:?}: {e}", plan.rig)),
    })?;
    let (table, rows) = py
        .detach(|| plan.run(&spec, g))
        .map_err(|e| PyRuntimeError::new_err(e.to_string()))?;
    Ok(Calibration { table, rows })
}

#[pymodule]
fn _vlab(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(cor, m)?)?;
    m.add_function(wrap_pyfunction!(shake, m)?)?;
    m.add_function(wrap_pyfunction!(analyze, m)?)?;
    m.add_function(wrap_pyfunction!(drop_test, m)?)?;
    m.add_function(wrap_pyfunction!(host_predict, m)?)?;
    m.add_function(wrap_pyfunction!(scene_json, m)?)?;
    m.add_function(wrap_pyfunction!(calibrate, m)?)?;
    m.add_class::<Calibration>()?;
    m.add_class::<HostPredict>()?;
    m.add_class::<Shake>()?;
    m.add_class::<Drop>()?;
    m.add("DEFAULT_BEDS", DEFAULT_BEDS)?;
    Ok(())
}
