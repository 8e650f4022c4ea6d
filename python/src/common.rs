//! What every call shares: a figure with its error, writing into a folder
//! that a failure leaves as it was, errors as Python exceptions, the bed
//! cache, the thread pool and a progress callback.

use std::path::PathBuf;
use std::sync::Mutex;

use numpy::PyArray1;
use pyo3::exceptions::{PyKeyError, PyRuntimeError, PyValueError};
use pyo3::prelude::*;

use vlab::atomic_write::OutputDir;
use vlab::experiment::bed::cache::{BedCache, BedSource};
use vlab::rig::ShakerKind;
use vlab::scene::SceneError;
use vlab::signals::Trace;
use vlab::study::dissipation_map::{map_files_label, read_map_files};
use vlab::study::sweep::SweepFile;

/// A figure and its one-sigma error (`None` where it is not known).
pub(crate) type Figure = (f64, Option<f64>);

/// Makes folder `out` if missing and runs `write` into it; a failed write
/// leaves no folder it made.
pub(crate) fn write_into(
    out: &std::path::Path,
    write: impl FnOnce(&std::path::Path) -> Result<(), SceneError>,
) -> PyResult<()> {
    let made = OutputDir::prepare(out).map_err(|e| {
        PyRuntimeError::new_err(format!("cannot create folder {}: {e}", out.display()))
    })?;
    made.keep_if_ok(write(out))
        .map_err(|e| PyRuntimeError::new_err(e.to_string()))
}

pub(crate) fn value_error(e: impl std::fmt::Display) -> PyErr {
    PyValueError::new_err(e.to_string())
}

/// The `shaker` keyword: "prescribed" or "electrodynamic" (`None`: the
/// rig's own).
pub(crate) fn shaker_of(name: Option<&str>) -> PyResult<Option<ShakerKind>> {
    match name {
        None => Ok(None),
        Some("prescribed") => Ok(Some(ShakerKind::Prescribed)),
        Some("electrodynamic") => Ok(Some(ShakerKind::Electrodynamic)),
        Some(other) => Err(PyValueError::new_err(format!(
            "shaker = {other:?}: must be \"prescribed\" or \"electrodynamic\""
        ))),
    }
}

/// Where settled beds come from: the command line's bed cache (`cache`), or
/// settled anew; a cache that cannot be opened is a warning, as the command
/// line says it, and the beds are settled anew.
pub(crate) fn bed_source(py: Python<'_>, cache: bool) -> PyResult<BedSource> {
    match (cache, BedCache::user()) {
        (false, _) => Ok(BedSource::Settle),
        (true, Ok(c)) => Ok(BedSource::Cache(c)),
        (true, Err(e)) => {
            let said = std::ffi::CString::new(format!("{e}; the beds are settled anew"))
                .unwrap_or_default();
            let category = py.get_type::<pyo3::exceptions::PyUserWarning>();
            PyErr::warn(py, &category, &said, 1)?;
            Ok(BedSource::Settle)
        }
    }
}

/// As `vlab --threads N`: a pool of N workers (default: every core) for
/// everything a run does in parallel (N never changes a number).
pub(crate) fn thread_pool(threads: Option<usize>) -> PyResult<rayon::ThreadPool> {
    let threads = threads.unwrap_or_else(|| {
        std::thread::available_parallelism().map_or(1, std::num::NonZeroUsize::get)
    });
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| PyRuntimeError::new_err(format!("cannot start {threads} threads: {e}")))
}

/// A Python progress callback a run calls from any of its threads while
/// the GIL is released. The first error it raises (a bug in it, or Ctrl-C
/// while it ran) stops the calls and is raised when the run ends
/// ([`Callback::finish`]): the run itself cannot be stopped half-way.
pub(crate) struct Callback {
    function: Option<Py<PyAny>>,
    raised: Mutex<Option<PyErr>>,
}

impl Callback {
    pub(crate) fn new(function: Option<Py<PyAny>>) -> Callback {
        Callback {
            function,
            raised: Mutex::new(None),
        }
    }

    /// Calls the function with `args` (nothing when there is none or it
    /// has raised).
    pub(crate) fn call<A>(&self, args: A)
    where
        A: for<'py> pyo3::call::PyCallArgs<'py>,
    {
        let Some(f) = &self.function else { return };
        let mut raised = self.raised.lock().unwrap_or_else(|e| e.into_inner());
        if raised.is_none() {
            *raised = Python::attach(|py| f.call1(py, args).err());
        }
    }

    /// The error the function raised, if it did.
    pub(crate) fn finish(self) -> PyResult<()> {
        match self.raised.into_inner().unwrap_or_else(|e| e.into_inner()) {
            Some(e) => Err(e),
            None => Ok(()),
        }
    }
}

/// The samples of channel `name` of `trace` as a numpy array; a name it
/// lacks is a `KeyError` that lists the names it has.
pub(crate) fn channel_array<'py>(
    py: Python<'py>,
    trace: &Trace,
    name: &str,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let c = trace.channel(name).map_err(|_| {
        PyKeyError::new_err(format!(
            "no channel {name:?} in the record; it has {}",
            trace.channel_names().join(", ")
        ))
    })?;
    Ok(PyArray1::from_slice(py, &c.samples))
}

/// A `map` keyword: one sweep.csv, or a list of them, the first refined by
/// the later ones as `--map` given again refines it
/// ([`vlab::study::dissipation_map::read_map_files`]).
#[derive(FromPyObject)]
pub(crate) enum MapFiles {
    One(PathBuf),
    Many(Vec<PathBuf>),
}

/// The sweep file(s) of a `map` keyword as one map's rows, and their label
/// (joined by `+`); a refusal names the keyword.
pub(crate) fn read_map(map: MapFiles) -> PyResult<(SweepFile, String)> {
    let paths = match map {
        MapFiles::One(p) => vec![p],
        MapFiles::Many(ps) => ps,
    };
    let label = map_files_label(&paths);
    let file =
        read_map_files(&paths).map_err(|e| PyValueError::new_err(format!("map = {label}: {e}")))?;
    Ok((file, label))
}
