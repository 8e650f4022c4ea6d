//! Records from Python: `vlab.read_record` (a record file's channels as
//! numpy arrays, its metadata as a dict), and the lab's post-processing of
//! a record, `vlab.analyze` and `vlab.cor` (Yang's method, eq. 7.8-7.12;
//! the drop test's estimator, eq. 7.3-7.5) on a file or on arrays, as
//! `vlab analyze --json` and `vlab cor --json`.

use std::path::PathBuf;

use numpy::{PyArray1, PyReadonlyArray1};
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;

use crate::common::{channel_array, value_error};
use vlab::rig::{ACCEL_CHANNEL, FORCE_CHANNEL};
use vlab::signals::calibration::PhaseCalibration;
use vlab::signals::impacts::default_force_channel;
use vlab::signals::{AnalysisOptions, ImpactParams, Trace, analyse_trace, cor_report, read_trace};

/// A record read from its file (CSV, WAV with its sidecar, TDMS).
#[pyclass(module = "vlab._vlab", frozen)]
pub(crate) struct Record {
    trace: Trace,
}

#[pymethods]
impl Record {
    /// Samples per second (Hz).
    #[getter]
    fn sample_rate_hz(&self) -> f64 {
        self.trace.sample_rate_hz
    }

    /// The channels' names and units, in the record's order.
    #[getter]
    fn channels(&self) -> Vec<(String, String)> {
        let t = &self.trace;
        t.channels
            .iter()
            .map(|c| (c.name.clone(), c.unit.clone()))
            .collect()
    }

    /// The samples of channel `name` in its unit, as a numpy array.
    fn channel<'py>(&self, py: Python<'py>, name: &str) -> PyResult<Bound<'py, PyArray1<f64>>> {
        channel_array(py, &self.trace, name)
    }

    /// Each sample's time (s) on the record's clock.
    fn time_s<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        let t: Vec<f64> = (0..self.trace.len())
            .map(|i| self.trace.time_s(i))
            .collect();
        PyArray1::from_vec(py, t)
    }

    /// The record's metadata (source, rig, drive, sensitivities, the
    /// rest), as JSON text.
    #[getter]
    fn metadata_json(&self) -> String {
        serde_json::to_string(&self.trace.metadata).unwrap_or_default()
    }
}

/// Reads the record at `path` as `vlab analyze` reads it.
#[pyfunction]
pub(crate) fn read_record(path: PathBuf) -> PyResult<Record> {
    let trace = read_trace(&path).map_err(|e| value_error(format!("{}: {e}", path.display())))?;
    Ok(Record { trace })
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
pub(crate) fn analyze(
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
pub(crate) fn cor(
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
