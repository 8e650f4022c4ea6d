//! `vlab analyze`: Yang's structure-independent method (thesis eq. 7.8–7.12) on
//! a force/acceleration record, from vlab or from a real lab (CSV of any common
//! dialect, WAV or TDMS): the dissipated power, the energy per cycle, the efficiency
//! (eq. 7.7) when the particle mass and amplitude are known, the phase
//! correction used (at the drive and, through the calibration's high-pass +
//! skew model, at its harmonics) and the force polarity (a record whose force
//! is the gauge reaction is detected, said so and corrected). Also home of [`LabFileArgs`], the options for reading a lab
//! record that `vlab cor` shares.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use clap::Args;
use serde::Serialize;

use vlab::signals::csv::{CsvReadOptions, parse_delimiter};
use vlab::signals::{
    ForcePolarity, HarmonicPower, PhaseCalibration, PhaseCorrection, PolarityVerdict, PowerOptions,
    Trace, TraceFormat, efficiency, read_trace_with, yang_power_of_trace,
};

use super::args;

/// How to read a lab record: the CSV dialect, when detection is not wanted.
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
    /// Phase-error table (from `vlab calibrate` or a shake run's calibration.json).
    #[arg(long, value_name = "FILE")]
    calibration: Option<PathBuf>,
    /// Drive frequency (Hz) [default: from the trace's metadata].
    #[arg(long = "freq", value_name = "HZ", value_parser = args::freq_hz)]
    freq_hz: Option<f64>,
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
}

#[derive(Debug, Serialize)]
pub struct Analysis {
    pub drive_freq_hz: f64,
    pub power_w: f64,
    pub energy_per_cycle_j: f64,
    pub efficiency: Option<f64>,
    pub phase_correction_rad: f64,
    pub calibration: String,
    /// How the phase error is carried to the harmonics.
    pub harmonics_correction: String,
    pub force_polarity: PolarityVerdict,
    pub n_periods: usize,
    pub n_samples: usize,
    pub per_harmonic: Vec<HarmonicPower>,
    pub warnings: Vec<String>,
}

/// Samples sitting at a channel's extreme value: a clipped ADC leaves flat tops.
fn clipping_warning(trace: &Trace, channel: &str) -> Option<String> {
    let x = &trace.channel(channel).ok()?.samples;
    clipping(x).map(|c| {
        format!(
            "channel '{channel}' looks clipped: {} samples sit at its extreme value {} (runs of up to {}), {:.0} times as many as at the level just below: the power is distorted",
            c.at_peak, c.peak, c.longest_run, c.excess
        )
    })
}

/// Flat tops found by [`clipping`].
#[derive(Debug, Clone, Copy, PartialEq)]
struct Clipping {
    peak: f64,
    at_peak: usize,
    longest_run: usize,
    /// Samples at the extreme over samples at the next level in.
    excess: f64,
}

/// Flat tops at a record's extreme values. A smooth wave that the ADC
/// quantised also repeats its top code a few samples running (a 40 Hz sine at
/// 40 kHz and 16 bits stays within one code of its peak for 3-4 samples), but
/// no more often than the codes just below it; a clipped one piles everything
/// beyond full scale onto the extreme code. So: runs of at least 3 at the
/// extreme, and at least 4 times as many samples there as at the next level in.
fn clipping(x: &[f64]) -> Option<Clipping> {
    // An ADC's codes are not symmetric (-2^15 ..= 2^15 - 1): each end separately.
    flat_top(x, 1.0).or_else(|| flat_top(x, -1.0))
}

/// [`clipping`] at the top of `sign * x`.
fn flat_top(x: &[f64], sign: f64) -> Option<Clipping> {
    const CLIP_EXCESS: f64 = 4.0;
    let top = x.iter().fold(f64::NEG_INFINITY, |m, &v| m.max(sign * v));
    if top <= 0.0 || !top.is_finite() {
        return None;
    }
    let next = x
        .iter()
        .map(|&v| sign * v)
        .filter(|&a| a < top)
        .fold(f64::NEG_INFINITY, f64::max);
    let at_next = x.iter().filter(|&&v| sign * v == next).count();
    let (mut longest, mut run, mut at_top) = (0, 0, 0);
    for &v in x {
        if sign * v == top {
            at_top += 1;
            run += 1;
            longest = longest.max(run);
        } else {
            run = 0;
        }
    }
    let excess = at_top as f64 / at_next.max(1) as f64;
    (longest >= 3 && excess >= CLIP_EXCESS).then_some(Clipping {
        peak: sign * top,
        at_peak: at_top,
        longest_run: longest,
        excess,
    })
}

pub fn analyse(a: &AnalyzeArgs) -> Result<Analysis> {
    let trace = a.file.read(&a.trace)?;
    let freq = match a.freq_hz.or(trace.metadata.drive_freq_hz) {
        Some(f) => f,
        None => bail!(
            "unknown drive frequency: {} has no drive_freq_hz in its metadata; give --freq (Hz)",
            a.trace.display()
        ),
    };
    let table = match &a.calibration {
        Some(p) => Some(
            PhaseCalibration::load_json(p)
                .with_context(|| format!("--calibration {}", p.display()))?,
        ),
        None => None,
    };
    let correction = table
        .as_ref()
        .map_or(PhaseCorrection::None, PhaseCorrection::Table);
    let options = PowerOptions {
        phase_correction: correction,
        force_polarity: ForcePolarity::Detect,
        ..PowerOptions::default()
    };
    let r = yang_power_of_trace(&trace, &a.force_channel, &a.accel_channel, freq, &options)
        .with_context(|| format!("analysing {}", a.trace.display()))?;
    let extra_f64 = |key: &str| trace.metadata.extra.get(key).and_then(|v| v.as_f64());
    let gamma = a.gamma.or(trace.metadata.gamma);
    let mass = a.particle_mass_kg.or(extra_f64("particle_mass_kg"));
    let g = extra_f64("gravity_mps2").unwrap_or(vlab::signals::STANDARD_GRAVITY_MPS2);
    let eta = match (gamma, mass) {
        (Some(gamma), Some(m)) => Some(efficiency(r.energy_per_cycle_j, m, gamma, freq, g)?),
        _ => None,
    };
    let mut warnings: Vec<String> = [&a.force_channel, &a.accel_channel]
        .iter()
        .filter_map(|c| clipping_warning(&trace, c))
        .collect();
    if eta.is_none() {
        warnings.push("no efficiency: it needs --gamma and --particle-mass-kg (or both in the trace's metadata)".into());
    }
    if table.is_none() {
        warnings.push("no phase correction: pass --calibration to subtract the rig's phase error (thesis Fig. 7.9)".into());
    }
    if r.force_polarity.reversed {
        warnings.push(polarity_note(&r.force_polarity));
    }
    if table.as_ref().is_some_and(|t| t.model.is_none()) {
        warnings.push("the calibration holds one frequency: its phase error is carried to the harmonics as a pure delay; calibrate at several (vlab calibrate --freq 40,160,640) to fit the rig's high-pass + skew".into());
    }
    Ok(Analysis {
        drive_freq_hz: freq,
        power_w: r.power_w,
        energy_per_cycle_j: r.energy_per_cycle_j,
        efficiency: eta,
        phase_correction_rad: r.phase_correction_rad,
        calibration: a
            .calibration
            .as_ref()
            .map_or("none".into(), |p| p.display().to_string()),
        harmonics_correction: harmonics_correction(table.as_ref()),
        force_polarity: r.force_polarity,
        n_periods: r.n_periods,
        n_samples: r.n_samples,
        per_harmonic: r.per_harmonic,
        warnings,
    })
}

/// What the calibration does at the harmonics, in words.
fn harmonics_correction(table: Option<&PhaseCalibration>) -> String {
    match table {
        None => "none".into(),
        Some(t) => match &t.model {
            Some(m) => format!(
                "high-pass + skew model fitted to {} frequencies: net high-pass corner {:.3} Hz, skew {:.3} us",
                t.points.len(),
                m.force_high_pass_hz - m.accel_high_pass_hz,
                1e6 * m.skew_s
            ),
            None => "pure delay through the one calibrated frequency".into(),
        },
    }
}

/// The sentence that says a record's force was the gauge reaction.
fn polarity_note(v: &PolarityVerdict) -> String {
    format!(
        "force polarity reversed: corrected (the drive bin's complex power lies at {:.1} deg, where the gauge reaction puts it; a force on the enclosure lies near +90 deg)",
        v.drive_power_angle_rad.to_degrees()
    )
}

pub fn run(a: AnalyzeArgs) -> Result<()> {
    let r = analyse(&a)?;
    for w in &r.warnings {
        eprintln!("warning: {w}");
    }
    if a.json {
        println!("{}", serde_json::to_string_pretty(&r)?);
        return Ok(());
    }
    println!(
        "{}: drive {} Hz, {} whole periods ({} samples)",
        a.trace.display(),
        r.drive_freq_hz,
        r.n_periods,
        r.n_samples
    );
    println!("  dissipated power      {:.4e} W", r.power_w);
    println!(
        "  energy per cycle      {:.4e} J  (eq. 7.8)",
        r.energy_per_cycle_j
    );
    match r.efficiency {
        Some(e) => println!("  damping efficiency    {e:.3}  (eq. 7.7)"),
        None => println!("  damping efficiency    unknown (needs --gamma and --particle-mass-kg)"),
    }
    println!(
        "  phase correction      {:.3} mrad at the drive frequency ({})",
        1e3 * r.phase_correction_rad,
        r.calibration
    );
    println!("  at the harmonics      {}", r.harmonics_correction);
    if r.force_polarity.reversed {
        println!("  force polarity reversed: corrected");
    }
    println!("  harmonic   freq [Hz]   force [N]   velocity [m/s]   power [W]");
    for h in r.per_harmonic.iter().take(5) {
        println!(
            "  {:8}   {:9.1}   {:9.4}   {:14.5}   {:10.3e}",
            h.harmonic, h.freq_hz, h.force_amp_n, h.velocity_amp_mps, h.power_w
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A sine of `amplitude` (in full scales) at 40 Hz, 40 kHz, through a
    /// 16-bit ADC that clips at its extreme codes.
    fn adc_sine(amplitude: f64) -> Vec<f64> {
        let lsb = 2.0 / 65536.0;
        (0..40_000)
            .map(|i| {
                let v = amplitude * (2.0 * std::f64::consts::PI * 40.0 * i as f64 / 40_000.0).sin();
                ((v / lsb).round() * lsb).clamp(-1.0, 1.0 - lsb)
            })
            .collect()
    }

    #[test]
    fn a_quantised_sine_is_not_called_clipped_and_a_clipped_one_is() {
        // Within one code of its peak for several samples, yet not clipped.
        for amplitude in [0.05, 0.5, 0.99] {
            assert_eq!(
                clipping(&adc_sine(amplitude)),
                None,
                "amplitude {amplitude}"
            );
        }
        // Unquantised floats: a single sample at the top.
        let smooth: Vec<f64> = (0..4000).map(|i| (i as f64 * 0.0063).sin()).collect();
        assert_eq!(clipping(&smooth), None);
        // 2 % over full scale: about 12 % of each period flat at the limits.
        let c = clipping(&adc_sine(1.02)).expect("clipped");
        assert!(c.longest_run > 50 && c.excess > 10.0, "{c:?}");
    }
}
