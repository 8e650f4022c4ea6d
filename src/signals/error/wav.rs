//! What is wrong with a WAV trace file or its JSON sidecar
//! ([`crate::signals::wav`]).

use std::path::PathBuf;

/// What is wrong with a WAV trace file or its JSON sidecar.
#[derive(Debug, thiserror::Error)]
pub enum WavErrorKind {
    /// hound could not read or write the WAV.
    #[error("WAV: {0}")]
    Hound(#[from] hound::Error),
    /// No sidecar next to the WAV.
    #[error(
        "no sidecar '{}' next to the WAV: channel names, units and full-scale values live \
         there (a WAV stores only normalised samples); supply them with read_wav_with",
        sidecar.display()
    )]
    SidecarMissing {
        /// Where the sidecar was expected.
        sidecar: PathBuf,
    },
    /// The sidecar is of another format or version.
    #[error("sidecar: {problem}")]
    BadSidecar {
        /// What is wrong.
        problem: String,
    },
    /// The sidecar's sample rate is not the WAV header's.
    #[error("sidecar sample rate {sidecar_hz} Hz disagrees with the WAV header's {header_hz} Hz")]
    SampleRateMismatch {
        /// Rate in the sidecar.
        sidecar_hz: f64,
        /// Rate in the WAV header.
        header_hz: u32,
    },
    /// The sidecar names a different number of channels than the WAV holds.
    #[error("the sidecar describes {described} channels but the WAV holds {in_wav}")]
    ChannelCountMismatch {
        /// Channels described.
        described: usize,
        /// Channels in the WAV.
        in_wav: usize,
    },
    /// The sidecar's sample count is not the WAV's.
    #[error("the sidecar says {described} samples per channel but the WAV holds {in_wav}")]
    LengthMismatch {
        /// Samples described.
        described: usize,
        /// Samples in the WAV.
        in_wav: usize,
    },
    /// A full-scale value is unusable.
    #[error("channel '{channel}' full scale {full_scale}: {problem}")]
    BadFullScale {
        /// Channel.
        channel: String,
        /// The value.
        full_scale: f64,
        /// What is wrong.
        problem: String,
    },
    /// Too many channels for a WAV file.
    #[error("{channels} channels: a WAV file holds at most 65535")]
    TooManyChannels {
        /// Channels requested.
        channels: usize,
    },
    /// Sample format not supported.
    #[error("unsupported WAV sample format: {0}")]
    UnsupportedFormat(String),
}
