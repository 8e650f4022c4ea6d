//! `vlab.drop`: the drop test of `vlab drop` (thesis Section 7.3).

use std::path::PathBuf;

use numpy::PyArray1;
use pyo3::exceptions::{PyKeyError, PyRuntimeError, PyValueError};
use pyo3::prelude::*;

use crate::common::{value_error, write_into};
use vlab::experiment::drop::DropParticle;
use vlab::experiment::drop::series::{DropRequest, DropSeries, sampling_warning};
use vlab::rig::{DROP_RIG, DropRigSpec, RigFile};
use vlab::scene::SceneError;
use vlab::signals::ImpactParams;
use vlab::validation::{Bound as Limit, in_range, positive};

/// A finished drop test: its summary (`drop.json`) and each height's
/// force record.
#[pyclass(name = "Drop", module = "vlab._vlab")]
pub(crate) struct Drop {
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
pub(crate) fn drop_test(
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
