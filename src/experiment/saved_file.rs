//! The error of reading back the files a finished run wrote (its CSV and
//! JSON), to redraw its figures from saved data without running it again
//! (`vlab plot`): the study of accuracy's `accuracy.csv`, a stepped sine's
//! `frf.csv`.

use std::path::PathBuf;

/// Why a run's saved files could not be read back, or its figures redrawn.
#[derive(Debug, thiserror::Error)]
pub enum SavedFileError {
    #[error("cannot read {path}: {source}")]
    Read {
        path: PathBuf,
        source: std::io::Error,
    },
    /// Not the file it should be, or a field that does not parse.
    #[error("{path} is not {expected}: {what}")]
    Invalid {
        path: PathBuf,
        expected: &'static str,
        what: String,
    },
    #[error(transparent)]
    Plot(#[from] crate::scene::SceneError),
}

/// The text of the file `path`.
pub fn read_text(path: &std::path::Path) -> Result<String, SavedFileError> {
    std::fs::read_to_string(path).map_err(|source| SavedFileError::Read {
        path: path.to_path_buf(),
        source,
    })
}
