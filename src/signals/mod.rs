//! The lab's post-processing: traces, their files, and the measurements of
//! thesis Chapter 7 — usable on real lab records alone.
//!
//! - [`trace`]: multichannel uniformly sampled records ([`Trace`]);
//! - [`csv`], [`wav`], [`tdms`](mod@tdms): trace files (CSV with units in the
//!   header, read in the dialects lab software exports; 32-bit float WAV with a
//!   JSON sidecar; National Instruments TDMS, read only);
//! - [`spectrum`]: one-sided amplitude spectra (scaling convention stated there);
//! - [`power`]: Yang's structure-independent dissipated power, eq. 7.8-7.12,
//!   and the damping efficiency, eq. 7.7 / 6.10;
//! - [`calibration`]: the empty-enclosure phase-error table of Fig. 7.9;
//!   [`phase_point`]: one point of it measured on an empty-enclosure record;
//! - [`phase_model`]: the chain's phase error across frequency (high-pass +
//!   skew), fitted to that table or taken from a rig;
//! - [`analysis`]: Yang's method on a whole record as `vlab analyze` runs
//!   it, with the warnings a lab user must see (clipping, missing inputs);
//! - [`impacts`]: drop-test impact detection and restitution, eq. 7.3-7.5;
//! - [`structural`]: the classical methods on a host structure's records
//!   (logarithmic decrement, Hilbert envelope, H1/H2 FRF with coherence,
//!   half-power bandwidth, stepped-sine response, power input);
//! - [`trace_file`]: any of these formats, told apart by the file's extension;
//! - [`table`], [`table_file`], [`lammps`]: records of named columns from
//!   other programs (a DEM code's enclosure motion and force): CSV, or the
//!   text LAMMPS and LIGGGHTS write with `fix ave/time` / `fix print`; time
//!   axis checked for gaps and reversals;
//! - [`plot`]: small SVG and PNG plots (x-y, log x with error bars, heat maps);
//! - [`bench`](mod@bench): a timing hook for `vlab bench`.
//!
//! SI units throughout. This module imports neither `dem` nor `rig`. Every
//! file it writes goes through [`crate::atomic_write`].

pub mod analysis;
#[cfg(feature = "plot")]
pub mod analysis_figures;
pub mod bench;
pub mod calibration;
pub mod column_names;
pub mod csv;
pub mod error;
pub mod hysteresis;
pub mod impacts;
pub mod lammps;
pub mod phase_model;
pub mod phase_point;
#[cfg(feature = "plot")]
pub mod plot;
pub mod power;
pub mod spectrum;
pub mod structural;
pub mod table;
pub mod table_file;
pub mod tdms;
pub mod trace;
pub mod trace_file;
pub mod wav;

#[cfg(test)]
mod testutil;

pub use analysis::{
    Analysis, AnalysisError, AnalysisInput, AnalysisOptions, AnalysisWarning, analyse_trace,
};
pub use bench::{YangBenchReport, bench_yang_power};
pub use calibration::{CalibrationEntry, PhaseCalibration, PhaseErrorPoint, split_polarity};
pub use csv::{CsvReadOptions, read_csv, read_csv_table, read_csv_with, write_csv};
pub use error::{CsvErrorKind, RecordErrorKind, Result, SignalsError, TdmsErrorKind, WavErrorKind};
pub use impacts::{
    CorEstimate, CorInput, CorReport, CorWarning, DropTestResult, Impact, ImpactDetection,
    ImpactParams, ImpactRow, Polarity, cor_report, detect_impacts, estimate_cor,
    restitution_from_impact_times,
};
pub use lammps::read_lammps_text;
pub use phase_model::{PhaseErrorModel, wrap_phase_rad};
pub use phase_point::estimate_phase_error;
#[cfg(feature = "plot")]
pub use plot::{
    CirclePanel, ErrorSeries, HeatCell, HeatMap, HeatOverlay, LineDash, LogXPlot, MarkerLine,
    PanelStrip, RgbColor, Series, SeriesStyle, plot_heat_map, plot_log_x, plot_panel_strip,
    plot_xy_svg, plot_xy_svg_spanning,
};
pub use power::{
    BinSelection, ForcePolarity, HarmonicPower, PhaseCorrection, PolarityVerdict, PowerOptions,
    PowerResult, PowerWindow, WindowPlan, YangPower, efficiency, max_energy_per_cycle_j,
    mean_power_time_domain, period_powers, plan_window, yang_power, yang_power_of_trace,
};
pub use spectrum::{SpectrumPlan, amplitude_spectrum, bin_freq_hz};
pub use table::{Table, TableFormat};
pub use table_file::read_table;
pub use tdms::read_tdms;
pub use trace::{Channel, Sensitivity, Trace, TraceMetadata};
pub use trace_file::{TraceFormat, read_trace, read_trace_with};
pub use wav::{
    WavChannelInfo, WavSidecar, read_wav, read_wav_with, sidecar_path, write_wav,
    write_wav_with_full_scale,
};

/// Standard gravity, 9.806 65 m/s^2 (a convenience; pass your local g where it matters).
pub const STANDARD_GRAVITY_MPS2: f64 = 9.806_65;
