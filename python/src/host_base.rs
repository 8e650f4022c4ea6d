//! The host on the shaker's table from Python, `vlab.host_base` (`vlab host
//! base`): a stepped sine of the table's acceleration in one run, each
//! step's transmissibility and the power the table put in.

use std::path::PathBuf;

use pyo3::prelude::*;

use vlab::experiment::host_test::HostTest;
use vlab::experiment::host_test::transmissibility::{TableSine, TableSineResult, run_table_sine};
use vlab::host::Excitation;

use crate::common::{value_error, write_into};
use crate::host::{PoolRun, host_test_of};

/// A finished table test ([`TableSineResult`]).
#[pyclass(name = "HostBase", module = "vlab._vlab", frozen)]
pub(crate) struct HostBase {
    result: TableSineResult,
    test: HostTest,
}

#[pymethods]
impl HostBase {
    /// What transmissibility.csv holds (text).
    #[getter]
    fn csv(&self) -> String {
        self.result.csv()
    }

    /// Writes what `vlab host base --out` writes into folder `out`.
    fn write(&self, out: PathBuf) -> PyResult<()> {
        write_into(&out, |dir| self.result.write(dir, &self.test))
    }
}

/// The host on the rig's shaker table, as `vlab host base` does with the
/// flags of the same names: a stepped sine of the table's acceleration
/// `accel_mps2` (m/s²) at `freqs_hz` (Hz, ascending), `settle_cycles` and
/// `record_cycles` at each, in one run (`down` comes back down). Refusals
/// name the keyword before any work (`ValueError`); the host must have one
/// mode.
#[pyfunction]
#[pyo3(signature = (
    freqs_hz,
    *,
    accel_mps2 = 10.0,
    settle_cycles = 30,
    record_cycles = 20,
    down = false,
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
pub(crate) fn host_base(
    py: Python<'_>,
    freqs_hz: Vec<f64>,
    accel_mps2: f64,
    settle_cycles: u32,
    record_cycles: u32,
    down: bool,
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
) -> PyResult<HostBase> {
    let plan = TableSine {
        freqs_hz,
        table_accel_mps2: accel_mps2,
        settle_cycles,
        record_cycles,
        down,
    };
    plan.validate().map_err(|e| {
        let keyword = match e.key.as_str() {
            "table_accel_mps2" => "accel_mps2",
            "settle_cycles" | "record_cycles" => e.key.as_str(),
            _ => "freqs_hz",
        };
        value_error(e.renamed(keyword))
    })?;
    let first = Excitation::Sine {
        freq_hz: plan.freqs_hz[0],
        force_n: accel_mps2,
    };
    let (scene, mut test) = host_test_of(
        first,
        1.0,
        &host,
        &damper,
        scene,
        seed,
        orientation,
        &rig,
        noise_seed,
    )?;
    test.on_base = true;
    test.check()
        .map_err(|e| value_error(e.renamed(&format!("host {host:?}: {}", e.key))))?;
    let pool = PoolRun {
        cache,
        threads,
        progress,
    };
    let result = pool.run(
        py,
        &scene,
        "the stepped sine on the table",
        |scene, source, tell| run_table_sine(scene, source, &test, &plan, tell),
    )?;
    Ok(HostBase { result, test })
}
