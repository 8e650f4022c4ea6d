//! Traces as 32-bit float WAV files with a JSON sidecar: compact, lossless
//! for ADC-code data, and readable by any audio tool. No thesis equation
//! lives here.
//!
//! # Layout
//!
//! - `run.wav`: one WAV channel per trace channel, in trace order, IEEE
//!   32-bit float, sample rate in whole hertz. Each channel is stored
//!   normalised: WAV sample `s = x / full_scale`, so `|s| <= 1`.
//! - `run.wav.json` (the WAV's file name plus `.json`): the sidecar,
//!   [`WavSidecar`]:
//!   `{"format": "vlab-wav-sidecar", "version": 1, "sample_rate_hz": 40000.0,
//!   "start_time_s": 0.0, "n_samples": 200000, "channels": [{"name": "force",
//!   "unit": "N", "full_scale": 12.5}, ...], "metadata": {...}}`.
//!   `full_scale` is the physical value of WAV sample 1.0, in the channel's
//!   unit. Unknown fields are rejected.
//!
//! By default a channel's full scale is its largest `|x|` (1 for an all-zero
//! channel); [`write_wav_with_full_scale`] takes explicit values, which must
//! be at least the channel's largest `|x|`.
//!
//! # Precision
//!
//! Reading gives `x' = f64(s) * full_scale`. If `x / full_scale` is exactly
//! representable in f32 the round trip is bit-identical: e.g. ADC codes
//! `x = code * lsb` with `|code| < 2^24`, `code * lsb` exact in f64 and
//! `full_scale = 2^k * lsb`. Otherwise the error is f32 rounding, at most
//! 2^-24 (6e-8) of `|x|` for samples above ~1e-37 of full scale.
//!
//! Both files are written atomically, WAV first; the reader cross-checks
//! sample rate, channel count and length, so a WAV paired with a stale sidecar
//! is refused rather than misread.
//!
//! [`read_wav_with`] reads WAVs without a sidecar (any lab recorder's, float
//! or integer PCM; integer codes are normalised by `2^(bits-1)`) when the
//! caller supplies names, units and full scales.

use std::collections::BTreeMap;
use std::io::Cursor;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::error::{Result, SignalsError, WavErrorKind};
use super::trace::{Channel, Trace, TraceMetadata};
use crate::atomic_write::write_bytes_atomic;
use crate::validation::require;

/// The sidecar's `format` value.
pub const WAV_SIDECAR_FORMAT: &str = "vlab-wav-sidecar";
/// The sidecar version written and read.
pub const WAV_SIDECAR_VERSION: u32 = 1;

/// Name, unit and scale of one WAV channel.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WavChannelInfo {
    /// Channel name.
    pub name: String,
    /// Physical unit.
    pub unit: String,
    /// Physical value of WAV sample 1.0, in `unit`; positive and finite.
    pub full_scale: f64,
}

/// The JSON sidecar of a vlab WAV (see the module docs).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WavSidecar {
    /// Always [`WAV_SIDECAR_FORMAT`].
    pub format: String,
    /// [`WAV_SIDECAR_VERSION`].
    pub version: u32,
    /// Sample rate, in Hz; equals the WAV header's.
    pub sample_rate_hz: f64,
    /// Time of sample 0, in s.
    pub start_time_s: f64,
    /// Samples per channel.
    pub n_samples: usize,
    /// One entry per WAV channel, in order.
    pub channels: Vec<WavChannelInfo>,
    /// The trace's metadata.
    pub metadata: TraceMetadata,
}

/// Where the sidecar of `wav` lives: `run.wav` -> `run.wav.json`.
pub fn sidecar_path(wav: &Path) -> PathBuf {
    let mut name = wav
        .file_name()
        .map(|n| n.to_os_string())
        .unwrap_or_default();
    name.push(".json");
    wav.with_file_name(name)
}

/// Writes `trace` as `path` + sidecar, each channel scaled by its largest |x|.
pub fn write_wav(path: &Path, trace: &Trace) -> Result<()> {
    write_wav_with_full_scale(path, trace, &BTreeMap::new())
}

/// Writes `trace` as `path` + sidecar; channels named in `full_scale` use that
/// value (in the channel's unit, at least its largest |x|), the others their
/// largest |x|.
pub fn write_wav_with_full_scale(
    path: &Path,
    trace: &Trace,
    full_scale: &BTreeMap<String, f64>,
) -> Result<()> {
    trace.validate()?;
    let wav_err = |kind| SignalsError::Wav {
        path: path.to_path_buf(),
        kind,
    };
    for name in full_scale.keys() {
        trace.channel(name)?;
    }
    let rate = trace.sample_rate_hz;
    require(
        rate.fract() == 0.0 && (1.0..=f64::from(u32::MAX)).contains(&rate),
        "sample_rate_hz",
        rate,
        "Hz",
        "a whole number of hertz, at most 4294967295: a WAV header holds whole hertz",
    )?;
    let n_channels = u16::try_from(trace.channels.len())
        .ok()
        .filter(|&n| n > 0)
        .ok_or_else(|| {
            wav_err(WavErrorKind::TooManyChannels {
                channels: trace.channels.len(),
            })
        })?;
    let infos = trace
        .channels
        .iter()
        .map(|c| channel_info(c, full_scale.get(&c.name).copied()))
        .collect::<Result<Vec<_>>>()?;
    let bytes =
        wav_bytes(trace, &infos, n_channels).map_err(|e| wav_err(WavErrorKind::Hound(e)))?;
    let sidecar = WavSidecar {
        format: WAV_SIDECAR_FORMAT.into(),
        version: WAV_SIDECAR_VERSION,
        sample_rate_hz: rate,
        start_time_s: trace.start_time_s,
        n_samples: trace.len(),
        channels: infos,
        metadata: trace.metadata.clone(),
    };
    let side_path = sidecar_path(path);
    let mut json = serde_json::to_string_pretty(&sidecar).map_err(|source| SignalsError::Json {
        path: side_path.clone(),
        source,
    })?;
    json.push('\n');
    write_bytes_atomic(path, &bytes).map_err(|source| SignalsError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    write_bytes_atomic(&side_path, json.as_bytes()).map_err(|source| SignalsError::Io {
        path: side_path,
        source,
    })
}

/// A channel's sidecar entry: its full scale is `given` (checked to be
/// positive, finite and at least the largest |x|), else its largest |x|, else
/// 1 for a silent channel.
fn channel_info(c: &Channel, given: Option<f64>) -> Result<WavChannelInfo> {
    let peak = c.samples.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let scale = match given {
        Some(fs) => {
            require(
                fs.is_finite() && fs > 0.0 && fs >= peak,
                &format!("full_scale[{}]", c.name),
                fs,
                &c.unit,
                format!(
                    "positive, finite and at least the channel's largest |x| = {peak} {}",
                    c.unit
                ),
            )?;
            fs
        }
        None if peak > 0.0 => peak,
        None => 1.0,
    };
    Ok(WavChannelInfo {
        name: c.name.clone(),
        unit: c.unit.clone(),
        full_scale: scale,
    })
}

/// The WAV file's bytes: 32-bit float samples, interleaved, each channel over
/// its full scale.
fn wav_bytes(
    trace: &Trace,
    infos: &[WavChannelInfo],
    n_channels: u16,
) -> std::result::Result<Vec<u8>, hound::Error> {
    let spec = hound::WavSpec {
        channels: n_channels,
        sample_rate: trace.sample_rate_hz as u32,
        bits_per_sample: 32,
        sample_format: hound::SampleFormat::Float,
    };
    let mut bytes = Cursor::new(Vec::with_capacity(44 + 4 * trace.len() * infos.len()));
    let mut writer = hound::WavWriter::new(&mut bytes, spec)?;
    for i in 0..trace.len() {
        for (c, info) in trace.channels.iter().zip(infos) {
            writer.write_sample((c.samples[i] / info.full_scale) as f32)?;
        }
    }
    writer.finalize()?;
    Ok(bytes.into_inner())
}

/// Reads a vlab WAV and its sidecar into a trace.
pub fn read_wav(path: &Path) -> Result<Trace> {
    let wav_err = |kind| SignalsError::Wav {
        path: path.to_path_buf(),
        kind,
    };
    let side_path = sidecar_path(path);
    if !side_path.exists() {
        return Err(wav_err(WavErrorKind::SidecarMissing { sidecar: side_path }));
    }
    let text = std::fs::read_to_string(&side_path).map_err(|source| SignalsError::Io {
        path: side_path.clone(),
        source,
    })?;
    let sidecar: WavSidecar = serde_json::from_str(&text).map_err(|source| SignalsError::Json {
        path: side_path.clone(),
        source,
    })?;
    if sidecar.format != WAV_SIDECAR_FORMAT || sidecar.version != WAV_SIDECAR_VERSION {
        return Err(wav_err(WavErrorKind::BadSidecar {
            problem: format!(
                "format '{}' version {}; expected '{WAV_SIDECAR_FORMAT}' version {WAV_SIDECAR_VERSION}",
                sidecar.format, sidecar.version
            ),
        }));
    }
    let (header_rate, columns) = read_normalised(path)?;
    if sidecar.sample_rate_hz != f64::from(header_rate) {
        return Err(wav_err(WavErrorKind::SampleRateMismatch {
            sidecar_hz: sidecar.sample_rate_hz,
            header_hz: header_rate,
        }));
    }
    let in_wav = columns.first().map_or(0, Vec::len);
    if columns.len() == sidecar.channels.len() && in_wav != sidecar.n_samples {
        return Err(wav_err(WavErrorKind::LengthMismatch {
            described: sidecar.n_samples,
            in_wav,
        }));
    }
    let mut trace = scaled_trace(
        path,
        columns,
        &sidecar.channels,
        header_rate,
        sidecar.start_time_s,
    )?;
    trace.metadata = sidecar.metadata;
    Ok(trace)
}

/// Reads a WAV without a sidecar: `channels` gives name, unit and full scale
/// of each WAV channel in order. The rate comes from the header; the start
/// time is 0; metadata is empty (`source` set to the file name).
pub fn read_wav_with(path: &Path, channels: &[WavChannelInfo]) -> Result<Trace> {
    let (rate, columns) = read_normalised(path)?;
    let mut trace = scaled_trace(path, columns, channels, rate, 0.0)?;
    trace.metadata.source = path.display().to_string();
    Ok(trace)
}

/// Header rate and de-interleaved samples normalised to [-1, 1].
fn read_normalised(path: &Path) -> Result<(u32, Vec<Vec<f64>>)> {
    let wav_err = |kind| SignalsError::Wav {
        path: path.to_path_buf(),
        kind,
    };
    let hound_err = |e| wav_err(WavErrorKind::Hound(e));
    let mut reader = hound::WavReader::open(path).map_err(|e| match e {
        hound::Error::IoError(source) => SignalsError::Io {
            path: path.to_path_buf(),
            source,
        },
        other => hound_err(other),
    })?;
    let spec = reader.spec();
    let n_ch = usize::from(spec.channels);
    if n_ch == 0 {
        return Err(wav_err(WavErrorKind::UnsupportedFormat(
            "the header declares 0 channels".into(),
        )));
    }
    let per_channel = reader.duration() as usize;
    let mut columns = vec![Vec::with_capacity(per_channel); n_ch];
    match (spec.sample_format, spec.bits_per_sample) {
        (hound::SampleFormat::Float, 32) => {
            for (i, s) in reader.samples::<f32>().enumerate() {
                columns[i % n_ch].push(f64::from(s.map_err(hound_err)?));
            }
        }
        (hound::SampleFormat::Int, bits @ 1..=32) => {
            let norm = 2f64.powi(i32::from(bits) - 1);
            for (i, s) in reader.samples::<i32>().enumerate() {
                columns[i % n_ch].push(f64::from(s.map_err(hound_err)?) / norm);
            }
        }
        (format, bits) => {
            return Err(wav_err(WavErrorKind::UnsupportedFormat(format!(
                "{format:?} with {bits} bits per sample"
            ))));
        }
    }
    Ok((spec.sample_rate, columns))
}

/// Applies names, units and full scales to normalised columns.
fn scaled_trace(
    path: &Path,
    columns: Vec<Vec<f64>>,
    infos: &[WavChannelInfo],
    rate: u32,
    start_time_s: f64,
) -> Result<Trace> {
    let wav_err = |kind| SignalsError::Wav {
        path: path.to_path_buf(),
        kind,
    };
    if columns.len() != infos.len() {
        return Err(wav_err(WavErrorKind::ChannelCountMismatch {
            described: infos.len(),
            in_wav: columns.len(),
        }));
    }
    let mut trace = Trace::new(f64::from(rate), start_time_s)?;
    for (samples, info) in columns.into_iter().zip(infos) {
        if !(info.full_scale.is_finite() && info.full_scale > 0.0) {
            return Err(wav_err(WavErrorKind::BadFullScale {
                channel: info.name.clone(),
                full_scale: info.full_scale,
                problem: "must be positive and finite".into(),
            }));
        }
        let physical = samples.into_iter().map(|s| s * info.full_scale).collect();
        trace.add_channel(info.name.clone(), info.unit.clone(), physical)?;
    }
    Ok(trace)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scratch(tag: &str) -> PathBuf {
        let dir = std::env::temp_dir().join(format!("vlab-wav-{tag}-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("scratch dir");
        dir
    }

    /// 16-bit ADC codes times an LSB of 20 V / 2^16 times a dyadic sensitivity:
    /// every product is exact in f64.
    fn adc_trace() -> (Trace, f64) {
        let lsb = 20.0 / 65_536.0 * 0.125;
        let mut t = Trace::new(40_000.0, 0.5).expect("trace");
        let codes = |k: i64| -> Vec<f64> {
            (0..2_000i64)
                .map(|i| ((i * k * 7_919) % 65_536 - 32_768) as f64 * lsb)
                .collect()
        };
        t.add_channel("force", "N", codes(3)).expect("force");
        t.add_channel("acceleration", "m/s^2", codes(5))
            .expect("accel");
        t.metadata.rig = "thesis-shaker".into();
        t.metadata.drive_freq_hz = Some(40.0);
        (t, lsb)
    }

    #[test]
    fn exactly_representable_samples_round_trip_bit_identically() {
        let dir = scratch("exact");
        let path = dir.join("adc.wav");
        let (t, lsb) = adc_trace();
        let fs: BTreeMap<String, f64> = [
            ("force".to_string(), 32_768.0 * lsb),
            ("acceleration".to_string(), 32_768.0 * lsb),
        ]
        .into();
        write_wav_with_full_scale(&path, &t, &fs).expect("write");
        let back = read_wav(&path).expect("read");
        assert_eq!(
            back, t,
            "bit-identical samples, names, units, timing, metadata"
        );
        std::fs::remove_dir_all(dir).ok();
    }

    #[test]
    fn other_samples_round_trip_within_f32_precision() {
        // Relative error per sample below 1e-7 (f32 rounding is at most 6e-8).
        let dir = scratch("f32");
        let path = dir.join("smooth.wav");
        let mut t = Trace::new(40_000.0, 0.0).expect("trace");
        let x: Vec<f64> = (1..=4_000)
            .map(|i| (i as f64 * 0.01).sin() * 123.456 + 0.1 / i as f64)
            .collect();
        t.add_channel("force", "N", x.clone()).expect("force");
        write_wav(&path, &t).expect("write");
        let back = read_wav(&path).expect("read");
        let worst = back.channels[0]
            .samples
            .iter()
            .zip(&x)
            .map(|(a, b)| ((a - b) / b).abs())
            .fold(0.0, f64::max);
        assert!(worst < 1e-7, "worst relative error {worst}");
        assert!(
            worst > 0.0,
            "this input is not exactly representable; the test must see rounding"
        );
        std::fs::remove_dir_all(dir).ok();
    }

    fn written(tag: &str) -> (PathBuf, PathBuf, String) {
        let dir = scratch(tag);
        let path = dir.join("t.wav");
        write_wav(&path, &adc_trace().0).expect("write");
        let side = sidecar_path(&path);
        let text = std::fs::read_to_string(&side).expect("sidecar");
        (path, side, text)
    }

    #[test]
    fn sidecar_problems_are_reported() {
        let (path, side, text) = written("side");
        assert!(side.ends_with("t.wav.json"));

        std::fs::write(
            &side,
            text.replace("\"sample_rate_hz\": 40000.0", "\"sample_rate_hz\": 48000.0"),
        )
        .expect("edit");
        let err = read_wav(&path).expect_err("rate");
        assert!(matches!(
            err,
            SignalsError::Wav {
                kind: WavErrorKind::SampleRateMismatch {
                    header_hz: 40_000,
                    ..
                },
                ..
            }
        ));

        let mut sidecar: WavSidecar = serde_json::from_str(&text).expect("parse");
        sidecar.channels.push(WavChannelInfo {
            name: "extra".into(),
            unit: "V".into(),
            full_scale: 1.0,
        });
        std::fs::write(&side, serde_json::to_string(&sidecar).expect("json")).expect("edit");
        let err = read_wav(&path).expect_err("3 names, 2 channels");
        assert!(
            err.to_string()
                .contains("describes 3 channels but the WAV holds 2"),
            "{err}"
        );

        std::fs::write(
            &side,
            text.replace("\"n_samples\": 2000", "\"n_samples\": 2001"),
        )
        .expect("edit");
        assert!(matches!(
            read_wav(&path),
            Err(SignalsError::Wav {
                kind: WavErrorKind::LengthMismatch { .. },
                ..
            })
        ));

        std::fs::write(
            &side,
            text.replace("\"version\": 1", "\"version\": 1, \"colour\": 2"),
        )
        .expect("edit");
        assert!(matches!(read_wav(&path), Err(SignalsError::Json { .. })));

        std::fs::remove_file(&side).expect("remove");
        let err = read_wav(&path).expect_err("no sidecar");
        assert!(err.to_string().contains("read_wav_with"), "{err}");
        std::fs::remove_dir_all(path.parent().expect("dir")).ok();
    }

    #[test]
    fn read_with_explicit_channels_and_integer_pcm() {
        let dir = scratch("pcm");
        let path = dir.join("lab.wav");
        // A 16-bit stereo recording from some other tool.
        let spec = hound::WavSpec {
            channels: 2,
            sample_rate: 200_000,
            bits_per_sample: 16,
            sample_format: hound::SampleFormat::Int,
        };
        let mut w = hound::WavWriter::create(&path, spec).expect("create");
        for i in 0..100i16 {
            w.write_sample(i * 300).expect("l");
            w.write_sample(-i * 300).expect("r");
        }
        w.finalize().expect("finalize");
        assert!(matches!(
            read_wav(&path),
            Err(SignalsError::Wav {
                kind: WavErrorKind::SidecarMissing { .. },
                ..
            })
        ));
        let info = |name: &str, fs: f64| WavChannelInfo {
            name: name.into(),
            unit: "N".into(),
            full_scale: fs,
        };
        let t = read_wav_with(&path, &[info("a", 10.0), info("b", 20.0)]).expect("read");
        assert_eq!(t.sample_rate_hz, 200_000.0);
        // code 99*300 / 32768 * 10 N, exact in f64.
        assert_eq!(t.channels[0].samples[99], 29_700.0 / 32_768.0 * 10.0);
        assert_eq!(t.channels[1].samples[99], -29_700.0 / 32_768.0 * 20.0);
        assert!(matches!(
            read_wav_with(&path, &[info("a", 10.0)]),
            Err(SignalsError::Wav {
                kind: WavErrorKind::ChannelCountMismatch {
                    described: 1,
                    in_wav: 2
                },
                ..
            })
        ));
        assert!(read_wav_with(&path, &[info("a", 0.0), info("b", 1.0)]).is_err());
        std::fs::remove_dir_all(dir).ok();
    }

    #[test]
    fn unwritable_traces_are_refused() {
        let dir = scratch("bad");
        let path = dir.join("x.wav");
        let mut t = Trace::new(40_000.5, 0.0).expect("trace");
        t.add_channel("f", "N", vec![1.0, 2.0]).expect("f");
        assert!(matches!(
            write_wav(&path, &t),
            Err(SignalsError::Invalid(p)) if p.key == "sample_rate_hz"
        ));
        t.sample_rate_hz = 40_000.0;
        let too_small: BTreeMap<String, f64> = [("f".to_string(), 1.5)].into();
        assert!(matches!(
            write_wav_with_full_scale(&path, &t, &too_small),
            Err(SignalsError::Invalid(p)) if p.key == "full_scale[f]"
        ));
        let unknown: BTreeMap<String, f64> = [("g".to_string(), 1.5)].into();
        assert!(write_wav_with_full_scale(&path, &t, &unknown).is_err());
        assert!(!path.exists() && !sidecar_path(&path).exists());
        std::fs::remove_dir_all(dir).ok();
    }
}
