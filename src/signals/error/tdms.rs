//! What is wrong with a TDMS trace file ([`crate::signals::tdms`]).

/// What is wrong with a TDMS trace file.
#[derive(Debug, thiserror::Error)]
pub enum TdmsErrorKind {
    /// The TDMS reader (crate `tdms-rs`) could not read the file.
    #[error("TDMS: {0}")]
    Reader(#[source] tdms_rs::TdmsError),
    /// A segment does not start with the TDMS tag.
    #[error(
        "byte {offset}: expected a TDMS segment (tag 'TDSm'), found {found:?}: not a TDMS file, or a damaged one"
    )]
    NotTdms {
        /// Byte offset of the segment.
        offset: u64,
        /// What was there, as text.
        found: String,
    },
    /// A segment uses a layout the reader does not support.
    #[error(
        "segment at byte {offset} holds {layout}, which vlab does not read: export the channels as plain little-endian f64/f32 waveforms"
    )]
    UnsupportedLayout {
        /// Byte offset of the segment.
        offset: u64,
        /// The layout, in words.
        layout: &'static str,
    },
    /// The raw data in the file do not add up to the channels found.
    #[error(
        "the segments hold {in_segments} bytes of raw data but the channels account for {in_channels}: \
         a layout vlab does not read (several data chunks per segment?)"
    )]
    RawDataUnaccounted {
        /// Raw bytes in the segments.
        in_segments: u64,
        /// Raw bytes the channels' indices describe.
        in_channels: u64,
    },
    /// No channel holds data.
    #[error("no channels: the file holds no waveform to read")]
    NoChannels,
    /// Channels in more than one group.
    #[error("channels in {count} groups [{groups}]: vlab reads one group (one record) per file")]
    SeveralGroups {
        /// Number of groups with channels.
        count: usize,
        /// Their names.
        groups: String,
    },
    /// A channel is not of a floating-point type.
    #[error(
        "channel '{channel}' holds {data_type} values: vlab reads f64 and f32 channels in physical units"
    )]
    UnsupportedDataType {
        /// Channel name.
        channel: String,
        /// Its TDMS data type.
        data_type: String,
    },
    /// A channel's waveform timing is missing or unusable.
    #[error("channel '{channel}': {problem}")]
    BadTiming {
        /// Channel name.
        channel: String,
        /// What is wrong.
        problem: String,
    },
    /// Channels of different lengths.
    #[error(
        "channel '{channel}' has {len} samples but '{first}' has {first_len}: \
         the channels of a record must have equal length"
    )]
    UnequalLength {
        /// First channel.
        first: String,
        /// Its length.
        first_len: usize,
        /// The channel that differs.
        channel: String,
        /// Its length.
        len: usize,
    },
    /// A segment runs past the end of the file.
    #[error(
        "segment at byte {offset} runs to byte {end} but the file ends at byte {len}: a truncated file"
    )]
    Truncated {
        /// Byte offset of the segment.
        offset: u64,
        /// Where the segment says it ends.
        end: u64,
        /// File length in bytes.
        len: u64,
    },
    /// A channel's samples cannot make a trace channel (empty name, NaN, ...).
    #[error("{problem}")]
    BadChannel {
        /// What is wrong, naming the channel.
        problem: String,
    },
    /// The file-level `vlab_metadata` property is unusable.
    #[error("property 'vlab_metadata': {problem}")]
    BadMetadata {
        /// What is wrong.
        problem: String,
    },
}
