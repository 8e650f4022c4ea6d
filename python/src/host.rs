//! The host structure from Python: `vlab.host_predict` (the map model of
//! `vlab host predict`).

use std::path::PathBuf;

use numpy::PyArray1;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

use crate::common::{value_error, write_into};
use crate::scene::orientation_of;
use vlab::host::HostSpec;
use vlab::rig::RigFile;
use vlab::study::dissipation_map::{MapSource, dissipation_map};
use vlab::study::host_prediction::{HostPrediction, check_request};
use vlab::study::sweep::SweepFile;

/// A host's predicted response ([`HostPrediction`]).
#[pyclass(module = "vlab._vlab", frozen)]
pub(crate) struct HostPredict {
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
pub(crate) fn host_predict(
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
