//! `vlab.calibrate`: the rig's phase error measured on the empty
//! enclosure (`vlab calibrate`, thesis Section 6.2).

use std::path::PathBuf;

use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;

use crate::common::{shaker_of, value_error};
use vlab::experiment::calibration_plan::{CalibrationPlan, CalibrationRow};
use vlab::scene::{Scene, SceneError};
use vlab::signals::calibration::PhaseCalibration;

/// A rig's phase-error calibration ([`CalibrationPlan`]).
#[pyclass(module = "vlab._vlab", frozen)]
pub(crate) struct Calibration {
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
pub(crate) fn calibrate(
    py: Python<'_>,
    freqs_hz: Vec<f64>,
    gammas: Vec<f64>,
    rig: String,
    shaker: Option<&str>,
    cycles: u32,
    record_cycles: u32,
    dt_s: f64,
) -> PyResult<Calibration> {
    let shaker = shaker_of(shaker)?;
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
