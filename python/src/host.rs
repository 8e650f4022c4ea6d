//! The host structure from Python (thesis Section 2.3.1, 9.4): a test of
//! the damper on a host, `vlab.host_run` (`vlab host run`), its free decay
//! measured, `vlab.host_decay` (`vlab host decay`), its frequency response,
//! `vlab.host_frf` (`vlab host frf`, in `host_frf.rs`), and the response
//! predicted from a
//! sweep's map, `vlab.host_predict` (`vlab host predict`).

use std::path::PathBuf;

use numpy::PyArray1;
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;

use pyo3::types::PyDict;
use vlab::experiment::damper::Progress;
use vlab::experiment::ensemble::check_beds;
use vlab::experiment::host_test::decay::{DecayError, DecayEstimate, DecayOutcome};
use vlab::experiment::host_test::{Damper, HostRun, HostTest, run_host_test};
use vlab::host::{DissipationMap, Excitation};
use vlab::rig::RigSpec;
use vlab::scene::Scene;

use crate::common::{
    Callback, MapFiles, bed_source, channel_array, read_map, thread_pool, value_error, write_into,
};
use crate::scene::{orientation_of, scene_of};
use vlab::host::HostSpec;
use vlab::rig::RigFile;
use vlab::study::dissipation_map::{MapSource, dissipation_map};
use vlab::study::host_prediction::{HostPrediction, check_request};

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
        let floats: [(&str, Vec<f64>); 16] = [
            ("freq_hz", col(&|r| r.freq_hz)),
            ("amplitude_m", col(&|r| r.amplitude_m)),
            ("amplitude_low_m", col(&|r| r.amplitude_low_m)),
            ("amplitude_high_m", col(&|r| r.amplitude_high_m)),
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
            ("efficiency_low", col(&|r| r.damper.efficiency_low)),
            ("efficiency_high", col(&|r| r.damper.efficiency_high)),
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
        self.prediction.all_warnings()
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
    map: MapFiles,
    freqs_hz: Vec<f64>,
    force_n: f64,
    host: String,
    orientation: Option<&str>,
    yang: bool,
) -> PyResult<HostPredict> {
    check_request(&freqs_hz, force_n).map_err(value_error)?;
    let orientation = orientation.map(orientation_of).transpose()?;
    let (file, label) = read_map(map)?;
    let in_map = |e: &dyn std::fmt::Display| PyValueError::new_err(format!("map = {label}: {e}"));
    let source = if yang {
        MapSource::Yang
    } else {
        MapSource::Dem
    };
    let dissipation = dissipation_map(&file, orientation, None, source).map_err(|e| in_map(&e))?;
    let spec = HostSpec::from_name_or_path(&host)
        .map_err(|e| PyValueError::new_err(format!("host = {host:?}: {e}")))?;
    let prediction = HostPrediction::run(&dissipation, label, source, spec, &freqs_hz, force_n)
        .with_map_branch(&file);
    Ok(HostPredict { prediction })
}

/// The scene and the test of the keywords every host test shares, as
/// `vlab host`'s flags of the same names give them; a refusal names the
/// keyword.
#[allow(clippy::too_many_arguments)]
pub(crate) fn host_test_of(
    excitation: Excitation,
    duration_s: f64,
    host: &str,
    damper: &str,
    scene: Option<PathBuf>,
    seed: Option<u64>,
    orientation: Option<&str>,
    rig: &str,
    noise_seed: Option<u64>,
) -> PyResult<(Scene, HostTest)> {
    let scene = scene_of(scene, orientation, seed, None, None)?;
    let host_spec = HostSpec::from_name_or_path(host)
        .map_err(|e| PyValueError::new_err(format!("host = {host:?}: {e}")))?;
    let damper = Damper::parse(damper).map_err(|e| value_error(e.renamed("damper")))?;
    let rig_spec = RigSpec::from_name_or_path(rig)
        .map_err(|e| PyValueError::new_err(format!("rig = {rig:?}: {e}")))?;
    let test = HostTest::new(
        &scene, host_spec, damper, excitation, duration_s, rig_spec, noise_seed,
    );
    test.check().map_err(value_error)?;
    Ok((scene, test))
}

/// Runs `test` on a pool of `threads` with the GIL released, `progress`
/// called as `shake`'s is; the bed run alone takes every thread.
pub(crate) fn run_on_pool(
    py: Python<'_>,
    scene: &Scene,
    test: &HostTest,
    cache: bool,
    threads: Option<usize>,
    progress: Option<Py<PyAny>>,
) -> PyResult<HostRun> {
    let pool = PoolRun {
        cache,
        threads,
        progress,
    };
    pool.run(
        py,
        scene,
        "running the damper on its host",
        |scene, source, tell| run_host_test(scene, source, test, tell),
    )
}

/// How a run of one bed takes the pool: the bed cache or not, the threads,
/// and the progress callback.
pub(crate) struct PoolRun {
    pub cache: bool,
    pub threads: Option<usize>,
    pub progress: Option<Py<PyAny>>,
}

impl PoolRun {
    /// Runs `work` on a pool of the threads with the GIL released, the bed
    /// run alone taking every thread, `progress` called with (phase,
    /// fraction, cycle); a failure raised as `RuntimeError` after `what`.
    pub(crate) fn run<T: Send>(
        self,
        py: Python<'_>,
        scene: &Scene,
        what: &str,
        work: impl FnOnce(
            &Scene,
            &vlab::experiment::bed::cache::BedSource,
            &mut dyn FnMut(Progress),
        ) -> Result<T, vlab::scene::SceneError>
        + Send,
    ) -> PyResult<T> {
        let source = bed_source(py, self.cache)?;
        let pool = thread_pool(self.threads)?;
        let mut scene = scene.clone();
        scene.simulation.step_threads = pool.current_num_threads();
        let callback = Callback::new(self.progress);
        let run = py.detach(|| {
            let mut tell = |p: Progress| callback.call((p.phase, p.fraction, p.cycle));
            pool.install(|| work(&scene, &source, &mut tell))
        });
        callback.finish()?;
        run.map_err(|e| PyRuntimeError::new_err(format!("{what}: {e}")))
    }
}

/// A finished host test: the lab's record, the truth and the energy books.
#[pyclass(name = "HostRun", module = "vlab._vlab", frozen)]
pub(crate) struct HostRunResult {
    run: HostRun,
}

#[pymethods]
impl HostRunResult {
    /// The rig's samples per second (Hz).
    #[getter]
    fn sample_rate_hz(&self) -> f64 {
        self.run.trace.sample_rate_hz
    }

    /// The lab's channels, names and units: the acceleration at the damper
    /// and the force at the drive point.
    #[getter]
    fn channels(&self) -> Vec<(String, String)> {
        let t = &self.run.trace;
        t.channels
            .iter()
            .map(|c| (c.name.clone(), c.unit.clone()))
            .collect()
    }

    /// The samples of the lab's channel `name`, as a numpy array.
    fn channel<'py>(&self, py: Python<'py>, name: &str) -> PyResult<Bound<'py, PyArray1<f64>>> {
        channel_array(py, &self.run.trace, name)
    }

    /// What the simulator knows at each sample (record.csv), by name with
    /// its unit: time_s, damper_displacement_m, damper_velocity_mps,
    /// damper_acceleration_mps2, drive_force_n, drive_velocity_mps,
    /// damper_force_n, host_energy_j and the running energies
    /// damper_dissipated_j, damper_work_in_j, host_dissipated_j,
    /// dashpot_dissipated_j, excitation_work_j.
    #[getter]
    fn truth<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let r = &self.run.record;
        let d = PyDict::new(py);
        let columns: [(&str, &Vec<f64>); 13] = [
            ("time_s", &r.time_s),
            ("damper_displacement_m", &r.displacement_m),
            ("damper_velocity_mps", &r.velocity_mps),
            ("damper_acceleration_mps2", &r.acceleration_mps2),
            ("drive_force_n", &r.drive_force_n),
            ("drive_velocity_mps", &r.drive_velocity_mps),
            ("damper_force_n", &r.damper_force_n),
            ("host_energy_j", &r.host_energy_j),
            ("damper_dissipated_j", &r.damper_dissipated_j),
            ("damper_work_in_j", &r.damper_work_in_j),
            ("host_dissipated_j", &r.host_dissipated_j),
            ("dashpot_dissipated_j", &r.dashpot_dissipated_j),
            ("excitation_work_j", &r.excitation_work_j),
        ];
        for (name, values) in columns {
            d.set_item(name, PyArray1::from_slice(py, values))?;
        }
        Ok(d)
    }

    /// Where the host's energy went over the test (J), each term integrated
    /// on its own, and what the bed dissipated by its ledger: JSON text.
    #[getter]
    fn energy_json(&self) -> String {
        let run = &self.run;
        serde_json::json!({
            "host": run.energy,
            "damper_dissipated_j": run.damper_dissipated_j,
            "bed": run.bed,
        })
        .to_string()
    }

    /// The steps, their length (s) and the wall time (s) of the run.
    #[getter]
    fn steps(&self) -> (u64, f64, f64) {
        (self.run.steps, self.run.dt_s, self.run.wall_time_s)
    }

    /// What the lab's record cannot be trusted for, one sentence each.
    #[getter]
    fn warnings(&self) -> Vec<String> {
        self.run.warnings.iter().map(|w| w.text.clone()).collect()
    }

    /// Writes trace.csv, trace.wav, record.csv and record.svg into folder
    /// `out`, as `vlab host run --out` does.
    fn write(&self, out: PathBuf) -> PyResult<()> {
        write_into(&out, |dir| self.run.write_records(dir))
    }
}

/// Drives the host with `excitation` (a key of `vlab host run
/// --excitation`: sine:F_HZ:FORCE_N, sweep:..., multisine:..., random:...,
/// hammer:IMPULSE_N_S, release:X0_M) for `duration_s` and records it, as
/// `vlab host run` does with the flags of the same names; returns a
/// HostRun. Refusals name the keyword before any work (`ValueError`).
#[pyfunction]
#[pyo3(signature = (
    excitation,
    *,
    duration_s = 1.0,
    host = vlab::host::DEFAULT_HOST.to_string(),
    damper = "particles".to_string(),
    scene = None,
    seed = None,
    orientation = None,
    rig = vlab::rig::DEFAULT_RIG.to_string(),
    noise_seed = None,
    cache = true,
    threads = None,
    progress = None,
))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn host_run(
    py: Python<'_>,
    excitation: &str,
    duration_s: f64,
    host: String,
    damper: String,
    scene: Option<PathBuf>,
    seed: Option<u64>,
    orientation: Option<&str>,
    rig: String,
    noise_seed: Option<u64>,
    cache: bool,
    threads: Option<usize>,
    progress: Option<Py<PyAny>>,
) -> PyResult<HostRunResult> {
    let excitation =
        Excitation::parse(excitation).map_err(|e| value_error(e.renamed("excitation")))?;
    let (scene, test) = host_test_of(
        excitation,
        duration_s,
        &host,
        &damper,
        scene,
        seed,
        orientation,
        &rig,
        noise_seed,
    )?;
    let run = run_on_pool(py, &scene, &test, cache, threads, progress)?;
    Ok(HostRunResult { run })
}

/// A finished free decay ([`DecayOutcome`]), with the map it is held
/// against when one was given.
#[pyclass(name = "HostDecay", module = "vlab._vlab", frozen)]
pub(crate) struct HostDecay {
    outcome: DecayOutcome,
    map: Option<DissipationMap>,
    g_mps2: f64,
}

impl HostDecay {
    /// Yang's energy per cycle from the map at an estimate, if a map was given.
    fn map_energy(&self, e: &DecayEstimate) -> Option<f64> {
        self.map
            .as_ref()
            .map(|m| m.energy_per_cycle_j(e.freq_hz, e.amplitude_m, self.g_mps2))
    }
}

#[pymethods]
impl HostDecay {
    /// What decay.json holds (JSON text).
    #[getter]
    fn summary_json(&self) -> String {
        serde_json::to_string(&self.outcome.summary()).unwrap_or_default()
    }

    /// What decay.csv holds (text): one row per estimate of each method.
    #[getter]
    fn csv(&self) -> String {
        self.outcome.csv(&|e| self.map_energy(e))
    }

    /// What decay-beds.csv holds (text) with several beds, else `None`.
    #[getter]
    fn beds_csv(&self) -> Option<String> {
        self.outcome.ensemble.as_ref().map(|e| e.csv())
    }

    /// The first bed's run.
    #[getter]
    fn run(&self) -> HostRunResult {
        HostRunResult {
            run: self.outcome.run.clone(),
        }
    }

    /// Writes what `vlab host decay --out` writes into folder `out`.
    fn write(&self, out: PathBuf) -> PyResult<()> {
        write_into(&out, |dir| self.outcome.write(dir, &|e| self.map_energy(e)))
    }
}

/// The host released from `x0_m` at the damper (or struck by a hammer of
/// `hammer_n_s`) and left to ring down for `duration_s`: the loss factor
/// against amplitude by the logarithmic decrement and by the Hilbert
/// envelope, each against the DEM's energies, as `vlab host decay` does
/// with the flags of the same names; `map` (a sweep.csv) adds Yang's
/// structure-independent energy at each point, `beds` > 1 the beds'
/// ensemble. Refusals name the keyword before any work (`ValueError`).
#[pyfunction]
#[pyo3(signature = (
    *,
    x0_m = 0.003,
    hammer_n_s = None,
    duration_s = 1.0,
    beds = 1,
    map = None,
    host = vlab::host::DEFAULT_HOST.to_string(),
    damper = "particles".to_string(),
    scene = None,
    seed = None,
    orientation = None,
    rig = vlab::rig::DEFAULT_RIG.to_string(),
    noise_seed = None,
    cache = true,
    threads = None,
    progress = None,
))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn host_decay(
    py: Python<'_>,
    x0_m: f64,
    hammer_n_s: Option<f64>,
    duration_s: f64,
    beds: u32,
    map: Option<MapFiles>,
    host: String,
    damper: String,
    scene: Option<PathBuf>,
    seed: Option<u64>,
    orientation: Option<&str>,
    rig: String,
    noise_seed: Option<u64>,
    cache: bool,
    threads: Option<usize>,
    progress: Option<Py<PyAny>>,
) -> PyResult<HostDecay> {
    let (excitation, keyword) = match hammer_n_s {
        Some(j) => (Excitation::Hammer { impulse_n_s: j }, "hammer_n_s"),
        None => (Excitation::Release { x0_m }, "x0_m"),
    };
    excitation
        .validate()
        .map_err(|e| value_error(e.renamed(keyword)))?;
    check_beds(beds).map_err(|e| match e {
        vlab::scene::SceneError::Invalid(p) => value_error(p.renamed("beds")),
        e => value_error(e),
    })?;
    let (scene, test) = host_test_of(
        excitation,
        duration_s,
        &host,
        &damper,
        scene,
        seed,
        orientation,
        &rig,
        noise_seed,
    )?;
    let beds = if test.damper == Damper::Particles {
        beds
    } else {
        1
    };
    let map = match map {
        Some(files) => {
            let (file, label) = read_map(files)?;
            let in_map =
                |e: &dyn std::fmt::Display| PyValueError::new_err(format!("map = {label}: {e}"));
            let o = Some(scene.enclosure.orientation);
            Some(dissipation_map(&file, o, None, MapSource::Yang).map_err(|e| in_map(&e))?)
        }
        None => None,
    };
    // A hammer's blow is over in 0.5 ms; the record starts after it.
    let skip_s = if hammer_n_s.is_some() { 2e-3 } else { 0.0 };
    let first = run_on_pool(py, &scene, &test, cache, threads, progress)?;
    let source = bed_source(py, cache)?;
    let pool = thread_pool(threads)?;
    let outcome = py
        .detach(|| {
            pool.install(|| {
                DecayOutcome::measure(&scene, test.clone(), first, &source, beds, skip_s)
            })
        })
        .map_err(|e| match e {
            DecayError::NoPeaks => PyValueError::new_err(
                "the decay has no two successive peaks to compare: lengthen duration_s",
            ),
            e => PyRuntimeError::new_err(e.to_string()),
        })?;
    Ok(HostDecay {
        outcome,
        map,
        g_mps2: scene.simulation.gravity_mps2,
    })
}
