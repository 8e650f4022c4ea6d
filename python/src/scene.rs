//! `vlab.scene` and the scene every call builds: a scene file (or the
//! thesis damper) with the keyword arguments over it.

use std::path::PathBuf;

use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

use crate::common::value_error;
use vlab::scene::{Orientation, Scene, SceneOverrides, scene_figures};

/// The scene of a call: a scene file or the thesis damper, with the
/// keyword arguments over it (as `vlab shake`'s flags go over the file).
pub(crate) fn scene_of(
    scene: Option<PathBuf>,
    orientation: Option<&str>,
    seed: Option<u64>,
    cycles: Option<u32>,
    steady_cycles: Option<u32>,
) -> PyResult<Scene> {
    let orientation = orientation.map(orientation_of).transpose()?;
    let base = Scene::load_or_thesis(scene.as_deref()).map_err(value_error)?;
    SceneOverrides {
        cycles,
        steady_cycles,
        orientation,
        seed,
        dt_s: None,
    }
    .apply(base)
    .map_err(value_error)
}

/// The `orientation` keyword: "vertical" or "horizontal".
pub(crate) fn orientation_of(name: &str) -> PyResult<Orientation> {
    match name {
        "vertical" => Ok(Orientation::Vertical),
        "horizontal" => Ok(Orientation::Horizontal),
        other => Err(PyValueError::new_err(format!(
            "orientation = {other:?}: must be \"vertical\" or \"horizontal\""
        ))),
    }
}

/// A scene as `vlab scene` reads it (a file over the built-in thesis
/// damper, or the damper itself): its TOML and its figures (`vlab scene
/// --json`), as a JSON text `{"toml": ..., "figures": ...}`.
#[pyfunction]
#[pyo3(signature = (scene = None))]
pub(crate) fn scene_json(scene: Option<PathBuf>) -> PyResult<String> {
    let resolved = match &scene {
        Some(path) => Scene::load_over_preset(path).map_err(value_error)?,
        None => Scene::thesis(),
    };
    let figures = scene_figures(&resolved).map_err(value_error)?;
    let out = serde_json::json!({ "toml": resolved.to_toml(), "figures": figures });
    Ok(out.to_string())
}
