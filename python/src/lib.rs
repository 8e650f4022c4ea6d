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

use pyo3::prelude::*;

mod calibrate;
mod common;
mod drop;
mod host;
mod host_base;
mod host_frf;
mod records;
mod scene;
mod shake;
mod sweep;

use vlab::experiment::ensemble::DEFAULT_BEDS;

#[pymodule]
fn _vlab(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(records::cor, m)?)?;
    m.add_function(wrap_pyfunction!(shake::shake, m)?)?;
    m.add_function(wrap_pyfunction!(records::analyze, m)?)?;
    m.add_function(wrap_pyfunction!(drop::drop_test, m)?)?;
    m.add_function(wrap_pyfunction!(host::host_predict, m)?)?;
    m.add_function(wrap_pyfunction!(host::host_run, m)?)?;
    m.add_function(wrap_pyfunction!(host::host_decay, m)?)?;
    m.add_function(wrap_pyfunction!(host_frf::host_frf, m)?)?;
    m.add_class::<host_frf::HostFrf>()?;
    m.add_function(wrap_pyfunction!(host_base::host_base, m)?)?;
    m.add_class::<host_base::HostBase>()?;
    m.add_class::<host::HostRunResult>()?;
    m.add_class::<host::HostDecay>()?;
    m.add_function(wrap_pyfunction!(scene::scene_json, m)?)?;
    m.add_function(wrap_pyfunction!(calibrate::calibrate, m)?)?;
    m.add_function(wrap_pyfunction!(sweep::sweep, m)?)?;
    m.add_function(wrap_pyfunction!(sweep::read_sweep, m)?)?;
    m.add_class::<sweep::Sweep>()?;
    m.add_function(wrap_pyfunction!(records::read_record, m)?)?;
    m.add_class::<records::Record>()?;
    m.add_class::<calibrate::Calibration>()?;
    m.add_class::<host::HostPredict>()?;
    m.add_class::<shake::Shake>()?;
    m.add_class::<drop::Drop>()?;
    m.add("DEFAULT_BEDS", DEFAULT_BEDS)?;
    Ok(())
}
