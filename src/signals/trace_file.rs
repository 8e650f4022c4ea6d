//! Reading a trace file of either format, told apart by its extension: `.csv`
//! ([`super::csv`]) or `.wav` with its JSON sidecar ([`super::wav`]).

use std::path::Path;

use super::error::{Result, SignalsError};
use super::trace::Trace;
use super::{read_csv, read_wav};

/// Reads `path` as a CSV or a WAV trace, by its extension (case-insensitive).
pub fn read_trace(path: &Path) -> Result<Trace> {
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    match ext.as_deref() {
        Some("csv") => read_csv(path),
        Some("wav") => read_wav(path),
        _ => Err(SignalsError::UnknownTraceFormat {
            path: path.to_path_buf(),
        }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unknown_extension_is_named() {
        let err = read_trace(Path::new("record.txt")).unwrap_err();
        assert!(err.to_string().contains(".csv") && err.to_string().contains("record.txt"));
    }
}
