//! The host's frequency response from Python, `vlab.host_frf` (`vlab host
//! frf`, thesis Section 2.3.1): a stepped sine (or one carried up and
//! down), a swept sine, or a random force (periodic, true or burst).

use std::path::PathBuf;

use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;

use vlab::experiment::host_test::HostTest;
use vlab::experiment::host_test::carried_sine::{CarriedSine, CarriedSineResult, run_carried_sine};
use vlab::experiment::host_test::frf::{FrfPoint, SteppedSine};
use vlab::experiment::host_test::frf_outcome::{
    FrfMaps, RandomForce, RandomFrfOutcome, SteppedSineOutcome, SweptFrfOutcome,
};
use vlab::host::{Excitation, PeriodicRandom, RandomNoise};
use vlab::study::dissipation_map::{MapSource, dissipation_map};
use vlab::study::host_prediction::check_frequencies;

use crate::common::{
    Callback, MapFiles, bed_source, read_map, thread_pool, value_error, write_into,
};
use crate::host::{PoolRun, host_test_of, run_on_pool};

/// An error of a random or swept test as Python raises it: the library's
/// refusals as `ValueError`, the run's own as it raised them.
struct RunError(PyErr);

impl From<vlab::scene::SceneError> for RunError {
    fn from(e: vlab::scene::SceneError) -> Self {
        RunError(PyRuntimeError::new_err(e.to_string()))
    }
}

impl From<vlab::validation::InvalidParameter> for RunError {
    fn from(e: vlab::validation::InvalidParameter) -> Self {
        RunError(value_error(e))
    }
}

/// A finished frequency response of one kind.
enum FrfKind {
    SteppedSine(Box<SteppedSineOutcome>),
    Random(Box<RandomFrfOutcome>),
    Swept(Box<SweptFrfOutcome>),
    UpDown(Box<(CarriedSineResult, HostTest)>),
}

/// A finished frequency response ([`SteppedSineOutcome`],
/// [`RandomFrfOutcome`], [`SweptFrfOutcome`] or a [`CarriedSineResult`]).
#[pyclass(name = "HostFrf", module = "vlab._vlab", frozen)]
pub(crate) struct HostFrf {
    outcome: FrfKind,
}

#[pymethods]
impl HostFrf {
    /// "stepped sine", "stepped sine up and down", "swept sine", "periodic
    /// random", "true random (Hann, 50 % overlap)" or "burst random".
    #[getter]
    fn kind(&self) -> &'static str {
        match &self.outcome {
            FrfKind::SteppedSine(_) => "stepped sine",
            FrfKind::Random(o) => o.force.kind(),
            FrfKind::Swept(_) => "swept sine",
            FrfKind::UpDown(_) => "stepped sine up and down",
        }
    }

    /// What frf.csv (updown.csv up and down) holds (text).
    #[getter]
    fn csv(&self) -> String {
        match &self.outcome {
            FrfKind::SteppedSine(o) => o.csv(),
            FrfKind::Random(o) => o.csv(),
            FrfKind::Swept(o) => o.csv(),
            FrfKind::UpDown(o) => o.0.csv(),
        }
    }

    /// What frf.json (updown.json) holds (JSON text); `None` for a random
    /// force, which writes none.
    #[getter]
    fn summary_json(&self) -> Option<String> {
        match &self.outcome {
            FrfKind::SteppedSine(o) => serde_json::to_string(&o.summary()).ok(),
            FrfKind::Random(_) => None,
            FrfKind::Swept(o) => serde_json::to_string(&o.summary()).ok(),
            FrfKind::UpDown(o) => serde_json::to_string(&o.0.summary(&o.1)).ok(),
        }
    }

    /// What the test warns of, as `vlab host frf` prints it on standard
    /// error: a channel clipped or too faint, a map outside its range, a
    /// random test's lines too coarse for its resonance, a swept or burst
    /// response that had not died out (texts; empty when nothing).
    #[getter]
    fn warnings(&self) -> Vec<String> {
        match &self.outcome {
            FrfKind::SteppedSine(o) => o.warnings(),
            FrfKind::Random(o) => o.run.warnings.iter().map(|w| w.text.clone()).collect(),
            FrfKind::Swept(o) => o.run.warnings.iter().map(|w| w.text.clone()).collect(),
            FrfKind::UpDown(o) => o.0.warnings(),
        }
    }

    /// Writes what `vlab host frf --out` writes into folder `out`.
    fn write(&self, out: PathBuf) -> PyResult<()> {
        write_into(&out, |dir| match &self.outcome {
            FrfKind::SteppedSine(o) => o.write(dir),
            FrfKind::Random(o) => o.write(dir),
            FrfKind::Swept(o) => o.write(dir),
            FrfKind::UpDown(o) => o.0.write(dir, &o.1),
        })
    }
}

/// The one kind of test the keywords ask for, refused by name when they ask
/// for none or several.
fn one_kind(asked: &[(&str, bool)]) -> PyResult<()> {
    let given: Vec<&str> = asked.iter().filter(|a| a.1).map(|a| a.0).collect();
    match given.len() {
        1 => Ok(()),
        0 => Err(PyValueError::new_err(
            "give freqs_hz (a stepped sine), swept, random, noise or burst",
        )),
        _ => Err(PyValueError::new_err(format!(
            "{} ask for different tests: give one",
            given.join(" and ")
        ))),
    }
}

/// The random force of `random`, `noise` (with `block_s`) or `burst`,
/// refused by keyword.
fn random_force(
    random: Option<String>,
    noise: Option<String>,
    block_s: f64,
    burst: Option<String>,
) -> PyResult<Option<RandomForce>> {
    let named = |kw: &str, e: vlab::validation::InvalidParameter| match e.key.as_str() {
        "excitation" => value_error(e.renamed(kw)),
        field => value_error(e.renamed(&format!("{kw} {field}"))),
    };
    if let Some(key) = random {
        let force = PeriodicRandom::parse(&key).map_err(|e| named("random", e))?;
        return Ok(Some(force.into()));
    }
    let key_of = |kind: &str, key: Option<String>| key.map(|k| (kind.to_string(), k));
    if let Some((kind, key)) = key_of("noise", noise).or(key_of("burst", burst)) {
        let noise = RandomNoise::parse(&format!("{kind}:{key}")).map_err(|e| named(&kind, e))?;
        let force = RandomForce::noise(noise, block_s).map_err(value_error)?;
        return Ok(Some(force));
    }
    Ok(None)
}

/// The host's frequency response with the damper, as `vlab host frf` does
/// with the flags of the same names: a stepped sine at `freqs_hz` (Hz) of
/// `force_n` (the receptance, the host without particles and with their
/// mass as a solid, the damper's power; `map`, a sweep.csv, adds the
/// map-based prediction), or with `up_down` the same in one run up and
/// back down, the state carried; a swept sine (`swept`,
/// "START_HZ:END_HZ:SWEEP_S", then silence until `duration_s`); or a random
/// force over `duration_s`: `random` (periodic,
/// "LOW_HZ:HIGH_HZ:RMS_N:PERIOD_S:SEED"), `noise` (true random,
/// "LOW_HZ:HIGH_HZ:RMS_N:SEED", Hann blocks of `block_s`) or `burst`
/// ("LOW_HZ:HIGH_HZ:RMS_N:PERIOD_S:ON_FRACTION:SEED"). Refusals name the
/// keyword before any work (`ValueError`).
#[pyfunction]
#[pyo3(signature = (
    freqs_hz = None,
    *,
    force_n = 5.0,
    settle_cycles = 30,
    record_cycles = 20,
    beds = 1,
    up_down = false,
    swept = None,
    random = None,
    noise = None,
    block_s = 2.0,
    burst = None,
    duration_s = 8.0,
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
pub(crate) fn host_frf(
    py: Python<'_>,
    freqs_hz: Option<Vec<f64>>,
    force_n: f64,
    settle_cycles: u32,
    record_cycles: u32,
    beds: u32,
    up_down: bool,
    swept: Option<String>,
    random: Option<String>,
    noise: Option<String>,
    block_s: f64,
    burst: Option<String>,
    duration_s: f64,
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
) -> PyResult<HostFrf> {
    one_kind(&[
        ("freqs_hz", freqs_hz.is_some()),
        ("swept", swept.is_some()),
        ("random", random.is_some()),
        ("noise", noise.is_some()),
        ("burst", burst.is_some()),
    ])?;
    let release = Excitation::Release { x0_m: 1e-3 };
    let (scene, test) = host_test_of(
        release,
        duration_s,
        &host,
        &damper,
        scene,
        seed,
        orientation,
        &rig,
        noise_seed,
    )?;
    if let Some(force) = random_force(random, noise, block_s, burst)? {
        RandomFrfOutcome::check_duration(duration_s, force).map_err(value_error)?;
        let run = |t: &HostTest| run_on_pool(py, &scene, t, cache, threads, progress);
        let outcome =
            RandomFrfOutcome::run(test, force, |t| run(t).map_err(RunError)).map_err(|e| e.0)?;
        return Ok(HostFrf {
            outcome: FrfKind::Random(Box::new(outcome)),
        });
    }
    if let Some(key) = swept {
        let sweep = Excitation::parse(&format!("sweep:{key}:{force_n}"))
            .map_err(|e| value_error(e.renamed("swept")))?;
        let run = |t: &HostTest| run_on_pool(py, &scene, t, cache, threads, progress);
        let outcome =
            SweptFrfOutcome::run(test, sweep, |t| run(t).map_err(RunError)).map_err(|e| e.0)?;
        return Ok(HostFrf {
            outcome: FrfKind::Swept(Box::new(outcome)),
        });
    }
    let freqs_hz = freqs_hz.unwrap_or_default();
    check_frequencies(&freqs_hz).map_err(|e| value_error(e.renamed("freqs_hz")))?;
    let plan = SteppedSine {
        freqs_hz,
        force_n,
        settle_cycles,
        record_cycles,
        beds,
    };
    plan.validate().map_err(value_error)?;
    if up_down {
        return up_and_down(py, &scene, test, &plan, cache, threads, progress);
    }
    let maps = match map {
        Some(files) => {
            let (file, label) = read_map(files)?;
            let in_map =
                |e: &dyn std::fmt::Display| PyValueError::new_err(format!("map = {label}: {e}"));
            let o = Some(scene.enclosure.orientation);
            let of = |source| dissipation_map(&file, o, None, source).map_err(|e| in_map(&e));
            Some((of(MapSource::Dem)?, of(MapSource::Yang)?))
        }
        None => None,
    };
    let source = bed_source(py, cache)?;
    let pool = thread_pool(threads)?;
    let callback = Callback::new(progress);
    let total = plan.freqs_hz.len();
    let done_count = std::sync::atomic::AtomicUsize::new(0);
    let done = |_: &FrfPoint| {
        let n = done_count.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
        callback.call(("frequency", n, total));
    };
    let outcome = py.detach(|| {
        let maps = maps.as_ref().map(|(dem, yang)| FrfMaps { dem, yang });
        pool.install(|| SteppedSineOutcome::run(&scene, &source, &test, &plan, maps, &done))
    });
    callback.finish()?;
    let outcome = outcome.map_err(|e| PyRuntimeError::new_err(format!("the stepped sine: {e}")))?;
    Ok(HostFrf {
        outcome: FrfKind::SteppedSine(Box::new(outcome)),
    })
}

/// `plan` in one run, up and back down, one bed (`beds` must be 1).
fn up_and_down(
    py: Python<'_>,
    scene: &vlab::scene::Scene,
    test: HostTest,
    plan: &SteppedSine,
    cache: bool,
    threads: Option<usize>,
    progress: Option<Py<PyAny>>,
) -> PyResult<HostFrf> {
    if plan.beds != 1 {
        return Err(PyValueError::new_err(format!(
            "beds = {}: up_down runs one bed (its state is carried from step to step)",
            plan.beds
        )));
    }
    let carried = CarriedSine {
        freqs_hz: plan.freqs_hz.clone(),
        force_n: plan.force_n,
        settle_cycles: plan.settle_cycles,
        record_cycles: plan.record_cycles,
        down: true,
    };
    carried
        .validate()
        .map_err(|e| value_error(e.renamed("freqs_hz")))?;
    let pool = PoolRun {
        cache,
        threads,
        progress,
    };
    let result = pool.run(
        py,
        scene,
        "the stepped sine up and down",
        |scene, source, tell| run_carried_sine(scene, source, &test, &carried, tell),
    )?;
    Ok(HostFrf {
        outcome: FrfKind::UpDown(Box::new((result, test))),
    })
}
