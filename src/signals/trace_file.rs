//! Reading a trace file of any format vlab knows, told apart by its extension:
//! `.csv` ([`super::csv`]), `.wav` with its JSON sidecar ([`super::wav`]) or
//! `.tdms` ([`super::tdms`]).

use std::path::Path;

use super::csv::{CsvReadOptions, read_csv_with};
use super::error::{Result, SignalsError};
use super::read_wav;
use super::tdms::read_tdms;
use super::trace::Trace;

/// The kinds of trace file, by extension.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TraceFormat {
    /// `.csv`: text, time column first.
    Csv,
    /// `.wav` with its `.wav.json` sidecar.
    Wav,
    /// `.tdms`: National Instruments TDMS.
    Tdms,
}

impl TraceFormat {
    /// The format of `path` by its extension (case-insensitive), if vlab reads it.
    pub fn of(path: &Path) -> Option<Self> {
        let ext = path.extension()?.to_str()?.to_ascii_lowercase();
        match ext.as_str() {
            "csv" => Some(Self::Csv),
            "wav" => Some(Self::Wav),
            "tdms" => Some(Self::Tdms),
            _ => None,
        }
    }
}

/// Reads `path` as a CSV, WAV or TDMS trace, by its extension
/// (case-insensitive); a CSV's separator and decimal mark are detected.
pub fn read_trace(path: &Path) -> Result<Trace> {
    read_trace_with(path, &CsvReadOptions::default())
}

/// Reads `path` like [`read_trace`]; a CSV is read with `csv` options (other
/// formats ignore them).
pub fn read_trace_with(path: &Path, csv: &CsvReadOptions) -> Result<Trace> {
    match TraceFormat::of(path) {
        Some(TraceFormat::Csv) => read_csv_with(path, csv),
        Some(TraceFormat::Wav) => read_wav(path),
        Some(TraceFormat::Tdms) => read_tdms(path),
        None => Err(SignalsError::UnknownTraceFormat {
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

    #[test]
    fn formats_by_extension_in_any_case() {
        assert_eq!(
            TraceFormat::of(Path::new("a/b.CSV")),
            Some(TraceFormat::Csv)
        );
        assert_eq!(TraceFormat::of(Path::new("b.wav")), Some(TraceFormat::Wav));
        assert_eq!(
            TraceFormat::of(Path::new("c.Tdms")),
            Some(TraceFormat::Tdms)
        );
        assert_eq!(TraceFormat::of(Path::new("c.tdms_index")), None);
        assert_eq!(TraceFormat::of(Path::new("b.wav.json")), None);
        assert_eq!(TraceFormat::of(Path::new("noext")), None);
    }
}
