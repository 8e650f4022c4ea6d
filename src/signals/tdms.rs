//! National Instruments TDMS records (LabVIEW, DAQmx loggers, NI's and
//! Python's TDMS writers) read as a [`Trace`], through the `tdms-rs` crate.
//! No thesis equation lives here.
//!
//! # What is read
//!
//! A TDMS file holds groups of channels; each channel a typed array and
//! properties. vlab reads one record per file:
//!
//! - the one group that holds channels; each of its channels becomes a trace
//!   channel, in file order, named as in the file, with the channel's
//!   `unit_string` property as its unit (empty when absent);
//! - samples of type f64 (bit-exact) or f32 (widened exactly to f64);
//! - the sample period from the channel's waveform property `wf_increment`, in
//!   s: the sample rate is `1 / wf_increment`, taken as the nearest whole
//!   number of hertz when that is within 1 ppm (an increment of 2.5e-5 s is
//!   40 kHz exactly); the start time from `wf_start_offset`, in s (0 when
//!   absent). Every channel must carry the same increment and offset;
//! - the file-level string property `vlab_metadata`, when present: a
//!   [`TraceMetadata`] as one JSON object, vlab's own convention for the
//!   drive frequency, amplitude and provenance of a record (a file without it
//!   gets empty metadata, so `vlab analyze` then needs `--freq`).
//!
//! # What is refused, and why
//!
//! - no channel, or channels in several groups (which record is meant?);
//! - a channel that is not f64/f32 (integers are raw ADC codes without their
//!   scaling; strings and timestamps are not samples);
//! - a channel without a positive, finite `wf_increment`, or channels whose
//!   increments, start offsets or lengths differ;
//! - layouts the reader does not decode, found by a scan of the segments' lead-ins
//!   before the file is decoded: big-endian segments, interleaved data and
//!   DAQmx raw data; and a file whose segments hold more (or fewer) raw bytes
//!   than its channels account for, such as one that repeats data chunks
//!   within a segment. These would otherwise be misread silently.
//! - a segment that runs past the end of the file (a truncated recording).

use std::fs::File;
use std::io::{Read, Seek, SeekFrom};
use std::path::Path;

use tdms_rs::{DataType, PropertyValue, TdmsChannel, TdmsFile, TdmsGroup};

use super::error::{Result, SignalsError, TdmsErrorKind};
use super::trace::{Trace, TraceMetadata};

/// The file-level property holding a record's [`TraceMetadata`] as JSON.
pub const VLAB_METADATA_PROPERTY: &str = "vlab_metadata";

/// Bytes in a segment's lead-in: tag, table of contents, version, two offsets.
const LEAD_IN_BYTES: u64 = 28;
/// Table-of-contents flags of a segment lead-in (NI's TDMS file format).
const TOC_RAW_DATA: u32 = 1 << 3;
const TOC_INTERLEAVED: u32 = 1 << 5;
const TOC_BIG_ENDIAN: u32 = 1 << 6;
const TOC_DAQMX_RAW_DATA: u32 = 1 << 7;
/// "Next segment offset" of a segment whose writer did not finish.
const UNFINISHED_SEGMENT: u64 = u64::MAX;

/// Reads a TDMS record as a trace (see the module docs for what is read and
/// what is refused).
pub fn read_tdms(path: &Path) -> Result<Trace> {
    let err = |kind| tdms_error(path, kind);
    let raw_bytes = scan_segments(path)?;
    let file = TdmsFile::open(path).map_err(|e| match e {
        tdms_rs::TdmsError::Io(source) => SignalsError::Io {
            path: path.to_path_buf(),
            source,
        },
        e => err(TdmsErrorKind::Reader(e)),
    })?;
    let group = the_group(&file).map_err(err)?;
    let channels: Vec<_> = group.channels().collect();
    check_channels(&channels, raw_bytes).map_err(err)?;
    let first = &channels[0];
    let (increment_s, start_time_s) = common_time_base(&channels).map_err(err)?;
    let mut trace = Trace::new(rate_from_increment(increment_s), start_time_s).map_err(|e| {
        err(TdmsErrorKind::BadTiming {
            channel: first.name().to_string(),
            problem: e.to_string(),
        })
    })?;
    trace.metadata = metadata(&file).map_err(err)?;
    for c in &channels {
        let samples = read_samples(c).map_err(err)?;
        let unit = match c.property("unit_string") {
            Some(PropertyValue::String(u)) => u.clone(),
            _ => String::new(),
        };
        trace.add_channel(c.name(), unit, samples).map_err(|e| {
            err(TdmsErrorKind::BadChannel {
                problem: e.to_string(),
            })
        })?;
    }
    Ok(trace)
}

/// An error about the TDMS file at `path`.
fn tdms_error(path: &Path, kind: TdmsErrorKind) -> SignalsError {
    SignalsError::Tdms {
        path: path.to_path_buf(),
        kind,
    }
}

/// The one group that holds channels.
fn the_group(file: &TdmsFile) -> Result<TdmsGroup<'_>, TdmsErrorKind> {
    let mut groups: Vec<_> = file.groups().filter(|g| g.channels().count() > 0).collect();
    match groups.len() {
        0 => Err(TdmsErrorKind::NoChannels),
        1 => Ok(groups.remove(0)),
        count => Err(TdmsErrorKind::SeveralGroups {
            count,
            groups: groups
                .iter()
                .map(|g| format!("'{}'", g.name()))
                .collect::<Vec<_>>()
                .join(", "),
        }),
    }
}

/// Refuses channels that are not floating point, and raw data in the
/// segments that the channels do not account for (`raw_bytes` in all).
fn check_channels(channels: &[TdmsChannel], raw_bytes: u64) -> Result<(), TdmsErrorKind> {
    for c in channels {
        if !matches!(c.dtype(), DataType::Double | DataType::Float) {
            return Err(TdmsErrorKind::UnsupportedDataType {
                channel: c.name().to_string(),
                data_type: format!("{:?}", c.dtype()),
            });
        }
    }
    let in_channels: u64 = channels
        .iter()
        .map(|c| (c.len() * c.dtype().itemsize()) as u64)
        .sum();
    if in_channels != raw_bytes {
        return Err(TdmsErrorKind::RawDataUnaccounted {
            in_segments: raw_bytes,
            in_channels,
        });
    }
    Ok(())
}

/// A channel's sample period and start time, s (`wf_increment`,
/// `wf_start_offset`, the latter 0 when absent).
fn timing(c: &TdmsChannel) -> Result<(f64, f64), TdmsErrorKind> {
    let bad = |problem: String| TdmsErrorKind::BadTiming {
        channel: c.name().to_string(),
        problem,
    };
    let increment_s = match number(c.property("wf_increment")) {
        Some(x) if x.is_finite() && x > 0.0 => x,
        Some(x) => {
            return Err(bad(format!(
                "wf_increment = {x} s: the sample period must be positive and finite"
            )));
        }
        None => {
            return Err(bad(
                "no numeric 'wf_increment' property: the sample period (s) is unknown, \
                 so is the sample rate"
                    .into(),
            ));
        }
    };
    let start_s = match number(c.property("wf_start_offset")) {
        Some(x) if x.is_finite() => x,
        Some(x) => return Err(bad(format!("wf_start_offset = {x} s: must be finite"))),
        None => 0.0,
    };
    Ok((increment_s, start_s))
}

/// The sample period and start time every channel shares (the first
/// channel's), checking the others and their lengths against it.
fn common_time_base(channels: &[TdmsChannel]) -> Result<(f64, f64), TdmsErrorKind> {
    let first = &channels[0];
    let (increment_s, start_time_s) = timing(first)?;
    for c in &channels[1..] {
        let (inc, start) = timing(c)?;
        let differs = |what: &str, a: f64, b: f64| TdmsErrorKind::BadTiming {
            channel: c.name().to_string(),
            problem: format!(
                "{what} = {a} s but channel '{}' has {b} s: one record, one time base",
                first.name()
            ),
        };
        if (inc - increment_s).abs() > 1e-12 * increment_s {
            return Err(differs("wf_increment", inc, increment_s));
        }
        if start != start_time_s {
            return Err(differs("wf_start_offset", start, start_time_s));
        }
        if c.len() != first.len() {
            return Err(TdmsErrorKind::UnequalLength {
                first: first.name().to_string(),
                first_len: first.len(),
                channel: c.name().to_string(),
                len: c.len(),
            });
        }
    }
    Ok((increment_s, start_time_s))
}

/// A channel's samples as `f64` (single precision widened exactly).
fn read_samples(c: &TdmsChannel) -> Result<Vec<f64>, TdmsErrorKind> {
    let n = c.len();
    if c.dtype() == DataType::Double {
        let mut x = vec![0.0f64; n];
        c.read(0..n, &mut x).map_err(TdmsErrorKind::Reader)?;
        Ok(x)
    } else {
        let mut x = vec![0.0f32; n];
        c.read(0..n, &mut x).map_err(TdmsErrorKind::Reader)?;
        Ok(x.into_iter().map(f64::from).collect())
    }
}

/// The sample rate for a period of `increment_s`, snapped to whole hertz
/// within 1 ppm.
fn rate_from_increment(increment_s: f64) -> f64 {
    let rate = 1.0 / increment_s;
    let whole = rate.round();
    if whole > 0.0 && (whole - rate).abs() <= 1e-6 * rate {
        whole
    } else {
        rate
    }
}

/// A numeric property as f64.
fn number(p: Option<&PropertyValue>) -> Option<f64> {
    match p? {
        PropertyValue::Double(x) => Some(*x),
        PropertyValue::Float(x) => Some(f64::from(*x)),
        _ => None,
    }
}

/// The record's metadata from the file-level `vlab_metadata` property.
fn metadata(file: &TdmsFile) -> Result<TraceMetadata, TdmsErrorKind> {
    match file.property(VLAB_METADATA_PROPERTY) {
        None => Ok(TraceMetadata::default()),
        Some(PropertyValue::String(json)) => {
            serde_json::from_str(json).map_err(|e| TdmsErrorKind::BadMetadata {
                problem: format!("invalid metadata JSON: {e}"),
            })
        }
        Some(other) => Err(TdmsErrorKind::BadMetadata {
            problem: format!("expected a JSON string, found {other:?}"),
        }),
    }
}

/// Walks the segments' lead-ins: refuses the layouts `tdms-rs` would misread
/// and returns the raw-data bytes the segments hold in all.
fn scan_segments(path: &Path) -> Result<u64> {
    let io = |source| SignalsError::Io {
        path: path.to_path_buf(),
        source,
    };
    let err = |kind| SignalsError::Tdms {
        path: path.to_path_buf(),
        kind,
    };
    let mut f = File::open(path).map_err(io)?;
    let len = f.metadata().map_err(io)?.len();
    let mut offset = 0;
    let mut raw_bytes = 0;
    while offset < len {
        let mut lead_in = [0u8; LEAD_IN_BYTES as usize];
        f.seek(SeekFrom::Start(offset)).map_err(io)?;
        let got = read_up_to(&mut f, &mut lead_in).map_err(io)?;
        if got < lead_in.len() || &lead_in[..4] != b"TDSm" {
            return Err(err(TdmsErrorKind::NotTdms {
                offset,
                found: String::from_utf8_lossy(&lead_in[..got.min(4)]).into_owned(),
            }));
        }
        let u32_at = |i: usize| {
            u32::from_le_bytes([lead_in[i], lead_in[i + 1], lead_in[i + 2], lead_in[i + 3]])
        };
        let u64_at = |i: usize| u64::from(u32_at(i)) | u64::from(u32_at(i + 4)) << 32;
        let toc = u32_at(4);
        let layout = if toc & TOC_BIG_ENDIAN != 0 {
            Some("big-endian data")
        } else if toc & TOC_DAQMX_RAW_DATA != 0 {
            Some("DAQmx raw data (unscaled ADC codes)")
        } else if toc & TOC_INTERLEAVED != 0 && toc & TOC_RAW_DATA != 0 {
            Some("interleaved channel data")
        } else {
            None
        };
        if let Some(layout) = layout {
            return Err(err(TdmsErrorKind::UnsupportedLayout { offset, layout }));
        }
        let (next, raw_offset) = (u64_at(12), u64_at(20));
        let data_start = offset + LEAD_IN_BYTES;
        let end = if next == UNFINISHED_SEGMENT {
            len
        } else {
            data_start.saturating_add(next)
        };
        if end > len || raw_offset > end - data_start {
            return Err(err(TdmsErrorKind::Truncated {
                offset,
                end: end.max(data_start.saturating_add(raw_offset)),
                len,
            }));
        }
        if toc & TOC_RAW_DATA != 0 {
            raw_bytes += end - data_start - raw_offset;
        }
        offset = end;
    }
    Ok(raw_bytes)
}

/// Reads into `buf` until it is full or the file ends; returns the bytes read.
fn read_up_to(f: &mut File, buf: &mut [u8]) -> std::io::Result<usize> {
    let mut got = 0;
    while got < buf.len() {
        match f.read(&mut buf[got..])? {
            0 => break,
            n => got += n,
        }
    }
    Ok(got)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rate_is_whole_hertz_within_one_ppm_of_the_increment() {
        assert_eq!(rate_from_increment(2.5e-5), 40_000.0);
        assert_eq!(rate_from_increment(5e-6), 200_000.0);
        assert_eq!(rate_from_increment(1.0 / 3.0), 3.0);
        // 66 666.67 Hz is 5 ppm from a whole number: kept as it is (tol 1e-9 Hz).
        assert!((rate_from_increment(1.5e-5) - 1.0 / 1.5e-5).abs() < 1e-9);
        // 2 ppm off 40 kHz: kept.
        let off = 1.0 / 40_000.08;
        assert_eq!(rate_from_increment(off), 1.0 / off);
    }
}
