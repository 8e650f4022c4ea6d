//! `vlab.sweep` and `vlab.read_sweep`: a sweep of `vlab sweep` (thesis
//! Section 6.2's map of efficiency over frequency and Γ) run from Python,
//! or one read back from its sweep.csv; its columns as numpy arrays a
//! DataFrame takes as they are, its report as `vlab sweep --json` prints it.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

use numpy::PyArray1;
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use vlab::atomic_write::OutputDir;
use vlab::scene::{Scene, SceneError, SceneOverrides};
use vlab::study::sweep::{Shard, SweepError, SweepEvent, SweepFile, SweepPlan, run_sweep};
use vlab::study::sweep_plot::plot_sweep;
use vlab::study::sweep_updown;

use crate::common::{Callback, bed_source, shaker_of, thread_pool, value_error};
use crate::scene::orientation_of;

/// Columns of whole numbers (int64); the text columns are lists of str,
/// every other column float64.
const INTEGER_COLUMNS: [&str; 5] = ["seed", "beds", "cycles", "steady_cycles", "steps"];
const TEXT_COLUMNS: [&str; 6] = [
    "orientation",
    "status",
    "se_from",
    "steady",
    "phase",
    "note",
];

/// A sweep's rows: run by [`sweep`] or read by [`read_sweep`].
#[pyclass(module = "vlab._vlab", frozen)]
pub(crate) struct Sweep {
    file: SweepFile,
    /// With `up_down`: the down branch and `updown.csv`'s text (the file
    /// is then the up branch).
    branches: Option<(SweepFile, String)>,
}

#[pymethods]
impl Sweep {
    /// What `vlab sweep --json` prints (JSON text): every row, each
    /// condition's figures over its seeds (`by_condition`) and where each
    /// series peaks (`peaks`).
    #[getter]
    fn report_json(&self) -> PyResult<String> {
        self.file
            .report()
            .json()
            .map_err(|e| PyRuntimeError::new_err(e.to_string()))
    }

    /// sweep.csv's columns by name, cell for cell as the file holds them:
    /// float64 arrays (`NaN` where a row has none), int64 for seed, beds,
    /// cycles, steady_cycles and steps, lists of str for the words.
    #[getter]
    fn columns<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        for (name, cells) in self.file.columns() {
            if TEXT_COLUMNS.contains(&name) {
                d.set_item(name, cells)?;
            } else if INTEGER_COLUMNS.contains(&name) {
                let values = parse_cells::<i64>(name, &cells)?;
                d.set_item(name, PyArray1::from_vec(py, values))?;
            } else {
                let values = parse_cells::<f64>(name, &cells)?;
                d.set_item(name, PyArray1::from_vec(py, values))?;
            }
        }
        Ok(d)
    }

    /// The sweep's scene, rig, shaker and drive, as sweep.csv's header
    /// names them.
    #[getter]
    fn header<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let h = &self.file.header;
        let d = PyDict::new(py);
        d.set_item("scene", &h.scene)?;
        d.set_item("rig", &h.rig)?;
        d.set_item("shaker", &h.shaker)?;
        d.set_item("cycles", &h.cycles)?;
        d.set_item("steady_cycles", h.steady_cycles)?;
        d.set_item("sweep_id", &h.sweep_id)?;
        d.set_item("shard", h.shard.to_string())?;
        Ok(d)
    }

    /// Writes sweep.csv and the sweep's plots (efficiency and map, PNG and
    /// SVG, as `vlab sweep` draws them) into folder `out`; returns the
    /// paths written. A failure leaves no folder it made.
    fn write(&self, out: PathBuf) -> PyResult<Vec<PathBuf>> {
        let made = OutputDir::prepare(&out).map_err(|e| {
            PyRuntimeError::new_err(format!("cannot create folder {}: {e}", out.display()))
        })?;
        let written = (|| -> Result<Vec<PathBuf>, String> {
            let csv = out.join("sweep.csv");
            self.file.write(&csv).map_err(|e| e.to_string())?;
            let mut paths = vec![csv];
            paths.extend(plot_sweep(&self.file, &out).map_err(|e| e.to_string())?);
            Ok(paths)
        })();
        made.keep_if_ok(written).map_err(PyRuntimeError::new_err)
    }

    /// The down branch of a sweep run with `up_down` (this one is the up
    /// branch); none for any other sweep.
    #[getter]
    fn down(&self) -> Option<Sweep> {
        self.branches.as_ref().map(|(down, _)| Sweep {
            file: down.clone(),
            branches: None,
        })
    }

    /// `updown.csv` of a sweep run with `up_down`: both branches side by
    /// side, where they part; none for any other sweep.
    #[getter]
    fn up_down_csv(&self) -> Option<String> {
        self.branches.as_ref().map(|(_, csv)| csv.clone())
    }

    fn __len__(&self) -> usize {
        self.file.rows.len()
    }

    fn __repr__(&self) -> String {
        let h = &self.file.header;
        format!(
            "<vlab.Sweep of {} on rig {}: {} rows, {} conditions>",
            h.scene,
            h.rig,
            self.file.rows.len(),
            h.conditions().len()
        )
    }
}

/// The cells of column `name` as numbers (`NaN` reads as NaN).
fn parse_cells<T: std::str::FromStr>(name: &str, cells: &[String]) -> PyResult<Vec<T>> {
    cells
        .iter()
        .map(|c| {
            c.parse::<T>().map_err(|_| {
                PyRuntimeError::new_err(format!("column {name}: {c:?} is not a number"))
            })
        })
        .collect()
}

/// A sweep.csv read back (`path`: the file or its folder), as `vlab plot`
/// and `vlab host predict --map` read it.
#[pyfunction]
pub(crate) fn read_sweep(path: PathBuf) -> PyResult<Sweep> {
    let file_path = if path.is_dir() {
        path.join("sweep.csv")
    } else {
        path
    };
    let file = SweepFile::read(&file_path).map_err(value_error)?;
    Ok(Sweep {
        file,
        branches: None,
    })
}

/// The keyword a library key is given by in Python.
fn keyword(key: &str) -> Option<&'static str> {
    Some(match key {
        "freq_hz" => "freqs_hz",
        "gamma" => "gammas",
        "fill_ratio" => "fill_ratios",
        "seeds" => "seeds",
        "beds" => "beds",
        "drive.cycles" => "cycles",
        "drive.steady_cycles" => "steady_cycles",
        "simulation.dt_s" => "dt_s",
        _ => return None,
    })
}

/// `e` as a `ValueError`, a refused value named by its keyword.
fn refused(e: SweepError) -> PyErr {
    let named = |p: &vlab::validation::InvalidParameter| match keyword(&p.key) {
        Some(k) => value_error(p.renamed(k)),
        None => value_error(p),
    };
    match e {
        SweepError::Invalid(p) | SweepError::Scene(SceneError::Invalid(p)) => named(&p),
        other => value_error(other),
    }
}

/// Runs a sweep as `vlab sweep` does with the flags of the same names:
/// every condition (frequency x Γ x seed x fill ratio x orientation) of
/// the scene driven through the rig, its rows kept in `out`/sweep.csv as
/// they finish (with `resume`, an interrupted sweep there goes on), the
/// plots drawn there at the end. Without `out` the rows are kept in a
/// temporary folder that is removed. Refusals name the keyword before any
/// work (`ValueError`).
#[pyfunction]
#[pyo3(signature = (
    freqs_hz,
    gammas,
    *,
    seeds = vec![1],
    fill_ratios = Vec::new(),
    orientations = Vec::new(),
    scene = None,
    cycles = None,
    steady_cycles = None,
    dt_s = None,
    rig = vlab::rig::DEFAULT_RIG.to_string(),
    shaker = None,
    beds = 1,
    out = None,
    resume = false,
    up_down = false,
    cache = true,
    threads = None,
    progress = None,
))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn sweep(
    py: Python<'_>,
    freqs_hz: Vec<f64>,
    gammas: Vec<f64>,
    seeds: Vec<u64>,
    fill_ratios: Vec<f64>,
    orientations: Vec<String>,
    scene: Option<PathBuf>,
    cycles: Option<u32>,
    steady_cycles: Option<u32>,
    dt_s: Option<f64>,
    rig: String,
    shaker: Option<&str>,
    beds: u32,
    out: Option<PathBuf>,
    resume: bool,
    up_down: bool,
    cache: bool,
    threads: Option<usize>,
    progress: Option<Py<PyAny>>,
) -> PyResult<Sweep> {
    let base = Scene::load_or_thesis(scene.as_deref()).map_err(value_error)?;
    let scene = SceneOverrides {
        cycles,
        steady_cycles,
        orientation: None,
        seed: None,
        dt_s,
    }
    .apply(base)
    .map_err(|e| refused(e.into()))?;
    let plan = SweepPlan {
        scene,
        rig: rig.clone(),
        shaker: shaker_of(shaker)?,
        freqs_hz,
        gammas,
        seeds,
        fill_ratios,
        orientations: orientations
            .iter()
            .map(|o| orientation_of(o))
            .collect::<PyResult<_>>()?,
        beds: bed_source(py, cache)?,
        ensemble_beds: beds,
    };
    let checked = if up_down {
        sweep_updown::validate(&plan)
    } else {
        plan.validate()
    };
    checked.map_err(|e| match e {
        SweepError::Scene(SceneError::Invalid(_)) | SweepError::Invalid(_) => refused(e),
        SweepError::Scene(s) => PyValueError::new_err(format!("rig = {rig:?}: {s}")),
        other => value_error(other),
    })?;
    if up_down && resume {
        return Err(PyValueError::new_err(
            "resume = True: a sweep up and down cannot be resumed (each chain carries its bed from the start)",
        ));
    }
    let pool = thread_pool(threads)?;
    let run = |dir: &Path, resume: bool, progress: Option<Py<PyAny>>| match up_down {
        false => run_into(py, &plan, dir, resume, &pool, progress).map(|file| Sweep {
            file,
            branches: None,
        }),
        true => run_up_down_into(py, &plan, dir, &pool, progress),
    };
    match out {
        Some(dir) => run(&dir, resume, progress),
        None => {
            let dir = scratch_folder();
            let sweep = run(&dir, false, progress);
            let _ = std::fs::remove_dir_all(&dir);
            sweep
        }
    }
}

/// A folder of this process's own under the system's temporary folder.
fn scratch_folder() -> PathBuf {
    static NEXT: AtomicUsize = AtomicUsize::new(0);
    std::env::temp_dir().join(format!(
        "vlab-sweep-{}-{}",
        std::process::id(),
        NEXT.fetch_add(1, Ordering::Relaxed)
    ))
}

/// Runs `plan` keeping its rows in `dir`/sweep.csv, as `vlab sweep --out
/// dir` does (an existing file refused unless `resume`); the plots are
/// drawn there at the end. `progress` is called with ("bed", settled,
/// beds) and ("condition", done, conditions).
fn run_into(
    py: Python<'_>,
    plan: &SweepPlan,
    dir: &Path,
    resume: bool,
    pool: &rayon::ThreadPool,
    progress: Option<Py<PyAny>>,
) -> PyResult<SweepFile> {
    if !resume && dir.join("sweep.csv").exists() {
        return Err(PyValueError::new_err(format!(
            "{} exists: pass resume=True to continue that sweep, or choose another out",
            dir.join("sweep.csv").display()
        )));
    }
    in_folder(py, dir, pool, progress, &|on_event| {
        let file = run_sweep(plan, Shard::ALL, dir, resume, on_event)?;
        plot(&file, dir)?;
        Ok(file)
    })
}

/// Runs `plan` up and back down in Γ as `vlab sweep --up-down --out dir`
/// does: each branch in `dir`/up and `dir`/down (sweep.csv and plots),
/// `updown.csv` beside them, written when every chain has finished.
fn run_up_down_into(
    py: Python<'_>,
    plan: &SweepPlan,
    dir: &Path,
    pool: &rayon::ThreadPool,
    progress: Option<Py<PyAny>>,
) -> PyResult<Sweep> {
    if dir.join("updown.csv").exists() {
        return Err(PyValueError::new_err(format!(
            "{} exists: choose another out",
            dir.join("updown.csv").display()
        )));
    }
    let both = in_folder(py, dir, pool, progress, &|on_event| {
        let both = sweep_updown::run_up_down(plan, on_event)?;
        both.write(dir)?;
        plot(&both.up, &dir.join("up"))?;
        plot(&both.down, &dir.join("down"))?;
        Ok(both)
    })?;
    let csv = both.csv();
    Ok(Sweep {
        file: both.up,
        branches: Some((both.down, csv)),
    })
}

/// A sweep's plots drawn into `dir`, a failure as the sweep's.
fn plot(file: &SweepFile, dir: &Path) -> Result<(), SweepError> {
    plot_sweep(file, dir)
        .map(|_| ())
        .map_err(|e| SweepError::Write {
            path: dir.to_path_buf(),
            source: std::io::Error::other(e.to_string()),
        })
}

/// What [`in_folder`] runs: a sweep given where its events go.
type SweepWork<'a, T> = dyn Fn(&(dyn Fn(SweepEvent) + Sync)) -> Result<T, SweepError> + Sync + 'a;

/// `work` run in `pool` without the GIL, its events given to `progress` as
/// ("bed", settled, beds) and ("condition", done, conditions); the folder
/// `dir` made for it, and removed again if it made it and `work` fails.
fn in_folder<T: Send>(
    py: Python<'_>,
    dir: &Path,
    pool: &rayon::ThreadPool,
    progress: Option<Py<PyAny>>,
    work: &SweepWork<'_, T>,
) -> PyResult<T> {
    let made = OutputDir::prepare(dir).map_err(|e| {
        PyRuntimeError::new_err(format!("cannot create folder {}: {e}", dir.display()))
    })?;
    let callback = Callback::new(progress);
    let beds_total = AtomicUsize::new(0);
    let beds_done = AtomicUsize::new(0);
    let on_event = |e: SweepEvent| match e {
        SweepEvent::Started { beds, .. } => beds_total.store(beds, Ordering::Relaxed),
        SweepEvent::BedSettled { .. } => {
            let done = beds_done.fetch_add(1, Ordering::Relaxed) + 1;
            callback.call(("bed", done, beds_total.load(Ordering::Relaxed)));
        }
        SweepEvent::ConditionDone { done, total, .. } => {
            callback.call(("condition", done, total));
        }
    };
    let result = py.detach(|| pool.install(|| work(&on_event)));
    callback.finish()?;
    made.keep_if_ok(result)
        .map_err(|e| PyRuntimeError::new_err(e.to_string()))
}
