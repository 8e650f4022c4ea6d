//! `vlab analyze`: Yang's structure-independent method (thesis eq. 7.8–7.12) on
//! a force/acceleration record, from vlab or from a real lab (CSV of any common
//! dialect, WAV or TDMS): the dissipated power, the energy per cycle, the efficiency
//! (eq. 7.7) when the particle mass and amplitude are known, the phase
//! correction used (at the drive and, through the calibration's high-pass +
//! skew model, at its harmonics) and the force polarity (a record whose force
//! is the gauge reaction is detected, said so and corrected). A drive
//! frequency the record contradicts (`--freq` against its metadata or
//! spectrum) and a calibration of another rig are refused, naming the flag
//! that overrides (`--force-freq`, `--force-calibration`). The work is
//! [`vlab::signals::analysis`]'s; this is its command line, and the home of
//! [`LabFileArgs`], the options for reading a lab record that `vlab cor`
//! shares.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, anyhow, bail};
use clap::Args;
use vlab::signals::csv::{CsvReadOptions, parse_delimiter};

use vlab::atomic_write::OutputDir;
use vlab::signals::analysis_figures::draw_analysis_figures;
use vlab::signals::hysteresis::ForceLoop;
use vlab::signals::{
    Analysis, AnalysisError, AnalysisInput, AnalysisOptions, PhaseCalibration, Trace, TraceFormat,
    analyse_trace, read_trace_with,
};

use super::args;

/// How to read a lab record: the CSV dialect, when detection is not wanted.
/// Said under the per-harmonic table when a harmonic's power is negative.
const NEGATIVE_HARMONIC_POWER: &str =
    "  phase: the force's against the velocity's at that harmonic, after the phase correction;
  power = 1/2 |F| |V| cos(phase) (eq. 7.12). A negative power (|phase| > 90 deg): at that
  frequency the damper gave energy back to the shaker over the record; only the sum over
  all the harmonics is the dissipation. Where a harmonic's velocity is tiny (a prescribed
  sine), its phase and its sign are noise.";

#[derive(Debug, Clone, Default, Args)]
pub struct LabFileArgs {
    /// Field separator of a CSV record: ',', ';' or tab [default: detected from the header line].
    #[arg(long, value_name = "SEP", value_parser = parse_delimiter)]
    pub delimiter: Option<u8>,
    /// The CSV record's numbers use ',' as the decimal mark (0,25) [default: detected].
    #[arg(long)]
    pub decimal_comma: bool,
}

impl LabFileArgs {
    /// The CSV options these arguments ask for (`None`: detect).
    pub fn csv_options(&self) -> CsvReadOptions {
        CsvReadOptions {
            delimiter: self.delimiter,
            decimal_comma: self.decimal_comma.then_some(true),
        }
    }

    /// Reads `path` (any format vlab reads); refuses the CSV options for a
    /// file that is not a CSV rather than ignore them.
    pub fn read(&self, path: &Path) -> Result<Trace> {
        let csv_options = self.csv_options();
        if csv_options != CsvReadOptions::default()
            && TraceFormat::of(path) != Some(TraceFormat::Csv)
        {
            bail!(
                "--delimiter and --decimal-comma describe a CSV record; {} is not a .csv",
                path.display()
            );
        }
        Ok(read_trace_with(path, &csv_options)?)
    }
}

#[derive(Debug, Clone, Args)]
#[command(allow_negative_numbers = true)]
pub struct AnalyzeArgs {
    /// The record: a CSV (',', ';' or tab separated), a WAV file (with its .json sidecar) or a TDMS file.
    #[arg(value_name = "TRACE")]
    trace: PathBuf,
    /// Phase-error table (from `vlab calibrate` or a shake run's calibration.json);
    /// refused when it names another rig than the record.
    #[arg(long, value_name = "FILE")]
    calibration: Option<PathBuf>,
    /// Apply --calibration even when it names another rig than the record.
    #[arg(long, requires = "calibration")]
    force_calibration: bool,
    /// Drive frequency (Hz) [default: from the trace's metadata]; refused
    /// when the metadata or the acceleration's spectrum says another.
    #[arg(long = "freq", value_name = "HZ", value_parser = args::freq_hz)]
    freq_hz: Option<f64>,
    /// Use --freq even where the record's metadata or spectrum says another
    /// frequency.
    #[arg(long, requires = "freq_hz")]
    force_freq: bool,
    /// Amplitude Γ, for the efficiency [default: from the metadata].
    #[arg(long, value_parser = args::gamma)]
    gamma: Option<f64>,
    /// Particle mass (kg), for the efficiency [default: from the metadata].
    #[arg(long = "particle-mass-kg", value_name = "KG", value_parser = args::positive_kg)]
    particle_mass_kg: Option<f64>,
    /// Name of the force channel (N).
    #[arg(long, default_value = "force")]
    force_channel: String,
    /// Name of the acceleration channel (m/s^2).
    #[arg(long, default_value = "acceleration")]
    accel_channel: String,
    #[command(flatten)]
    file: LabFileArgs,
    /// Print the result as JSON.
    #[arg(long)]
    json: bool,
    /// Use the force as recorded: do not detect and correct a reversed force
    /// sign (to see what a flipped transducer does to the result).
    #[arg(long)]
    as_recorded: bool,
    /// Draw the record's force-displacement loop (its area is the energy
    /// per cycle) and the drive frequency's force and velocity phasors into
    /// this folder (loop.svg/png, phasor.svg/png).
    #[arg(long, value_name = "DIR")]
    plots: Option<PathBuf>,
}

/// Reads the record and runs Yang's method on it ([`analyse_trace`]).
pub fn analyse(a: &AnalyzeArgs) -> Result<(Trace, Analysis)> {
    let trace = a.file.read(&a.trace)?;
    let calibration = match &a.calibration {
        Some(p) => Some(
            PhaseCalibration::load_json(p)
                .with_context(|| format!("--calibration {}", p.display()))?,
        ),
        None => None,
    };
    let options = AnalysisOptions {
        force_channel: a.force_channel.clone(),
        accel_channel: a.accel_channel.clone(),
        freq_hz: a.freq_hz,
        force_freq: a.force_freq,
        gamma: a.gamma,
        particle_mass_kg: a.particle_mass_kg,
        calibration,
        calibration_name: a
            .calibration
            .as_ref()
            .map_or("none".into(), |p| p.display().to_string()),
        force_calibration: a.force_calibration,
        as_recorded: a.as_recorded,
    };
    let analysis = analyse_trace(&trace, &options)
        .map_err(refusal)
        .with_context(|| format!("analysing {}", a.trace.display()))?;
    Ok((trace, analysis))
}

/// An analysis error for the command line: a refusal names the flag that
/// overrides it; the record's own error is unwrapped so its flag hint is found.
fn refusal(e: AnalysisError) -> anyhow::Error {
    let overridden_by = e.overridden_by();
    match (e, overridden_by) {
        (AnalysisError::Signals(e), _) => anyhow::Error::new(e),
        (e, Some(input)) => anyhow!(
            "{}; {} uses it anyway",
            flag_words(&e.figures()),
            input_flags(input)
        ),
        (e, None) => anyhow::Error::new(e),
    }
}

/// The library's parameter names in a refusal or warning, as this command's flags.
fn flag_words(text: &str) -> String {
    text.replace("freq_hz = ", "--freq ")
        .replace("force_freq", "--force-freq")
        .replace("force_calibration", "--force-calibration")
}

/// The flags that give what an analysis warning lacks.
fn input_flags(input: AnalysisInput) -> &'static str {
    match input {
        AnalysisInput::GammaAndMass => "--gamma, --particle-mass-kg",
        AnalysisInput::Calibration => "--calibration FILE",
        AnalysisInput::CalibrationFrequencies => "vlab calibrate --freq 40,160,640",
        AnalysisInput::CalibrationAtDrive => {
            "vlab calibrate --freq HZ,... with the drive frequency among them"
        }
        AnalysisInput::Freq => "--freq HZ --force-freq",
        AnalysisInput::ForceFreq => "--force-freq",
        AnalysisInput::ForceCalibration => "--force-calibration",
    }
}

/// Where the drive frequency came from and what the record says, in words.
fn freq_provenance(r: &Analysis) -> String {
    let mut parts = vec![match r.drive_freq_source {
        "given" => "from --freq".to_string(),
        other => format!("from the {other}"),
    }];
    if let (Some(m), "given") = (r.metadata_freq_hz, r.drive_freq_source) {
        parts.push(format!("metadata {m} Hz"));
    }
    if let Some(s) = r.spectrum_freq_hz {
        parts.push(format!("spectrum {s:.2} Hz"));
    }
    parts.join("; ")
}

pub fn run(a: AnalyzeArgs) -> Result<()> {
    let (trace, r) = analyse(&a)?;
    for w in &r.warnings {
        match w.advice {
            Some(input) => eprintln!("warning: {} ({})", flag_words(&w.text), input_flags(input)),
            None => eprintln!("warning: {}", flag_words(&w.text)),
        }
    }
    let drawn = match &a.plots {
        Some(dir) => Some(draw_plots(&trace, &r, &a, dir)?),
        None => None,
    };
    if a.json {
        println!("{}", serde_json::to_string_pretty(&r)?);
        return Ok(());
    }
    println!(
        "{}: drive {} Hz ({}), {} whole periods ({} samples) of the record's {:.2}{}",
        a.trace.display(),
        r.drive_freq_hz,
        freq_provenance(&r),
        r.n_periods,
        r.n_samples,
        r.record_periods,
        match r.dropped_samples {
            0 => String::new(),
            d => format!(", the last {d} samples left out"),
        }
    );
    print_figures(&r);
    print_harmonics(&r);
    if let (Some(l), Some(dir)) = (drawn, &a.plots) {
        println!(
            "  force-displacement loop: {:.4e} J enclosed per cycle (the record as it is, before the phase correction); loop.svg/png and phasor.svg/png in {}",
            l.energy_per_cycle_j,
            dir.display()
        );
    }
    Ok(())
}

/// The figures of Yang's method with their +-, and the phase correction.
fn print_figures(r: &Analysis) {
    let pm = |e: Option<f64>, digits: usize| {
        e.map_or(
            format!(
                " +- not known (fewer than {} whole periods)",
                vlab::stats::MIN_SERIES_VALUES
            ),
            |e| format!(" +- {e:.digits$e}"),
        )
    };
    println!(
        "  dissipated power      {:.4e} W{}",
        r.power_w,
        pm(r.power_stderr_w, 1)
    );
    println!(
        "  energy per cycle      {:.4e} J{}  (eq. 7.8)",
        r.energy_per_cycle_j,
        pm(r.energy_per_cycle_stderr_j, 1)
    );
    match r.efficiency {
        Some(e) => println!(
            "  damping efficiency    {e:.3}{}  (eq. 7.7)",
            r.efficiency_stderr
                .map_or(String::new(), |err| format!(" +- {err:.3}"))
        ),
        None => println!("  damping efficiency    unknown (needs --gamma and --particle-mass-kg)"),
    }
    println!(
        "  (+- : one sigma, from the spread of Yang's power period by period over this record{}: this record's bed and window alone, not another packing of the damper)",
        if r.periods_alternate {
            ", in pairs of periods (they alternate)"
        } else {
            ""
        }
    );
    println!(
        "  phase correction      {:.3} mrad at the drive frequency ({})",
        1e3 * r.phase_correction_rad,
        r.calibration
    );
    println!("  at the harmonics      {}", r.harmonics_correction);
    if r.force_polarity.reversed {
        println!("  force polarity reversed: corrected");
    }
}

/// The first five harmonics' force, velocity, phase and power.
fn print_harmonics(r: &Analysis) {
    println!("  harmonic   freq [Hz]   force [N]   velocity [m/s]   phase [deg]   power [W]");
    for h in r.per_harmonic.iter().take(5) {
        println!(
            "  {:8}   {:9.1}   {:9.4}   {:14.5}   {:11.2}   {:10.3e}",
            h.harmonic,
            h.freq_hz,
            h.force_amp_n,
            h.velocity_amp_mps,
            h.phase_rad.to_degrees(),
            h.power_w
        );
    }
    if r.per_harmonic.iter().take(5).any(|h| h.power_w < 0.0) {
        println!("{NEGATIVE_HARMONIC_POWER}");
    }
}

/// The loop and the phasors in `dir`, made for them and removed again if
/// they cannot be drawn.
fn draw_plots(trace: &Trace, r: &Analysis, a: &AnalyzeArgs, dir: &Path) -> Result<ForceLoop> {
    let made = OutputDir::prepare(dir)
        .with_context(|| format!("cannot create output folder {}", dir.display()))?;
    let channels = (a.force_channel.as_str(), a.accel_channel.as_str());
    let drawn = draw_analysis_figures(trace, r, channels, dir).map_err(anyhow::Error::from);
    made.keep_if_ok(drawn)
}
