//! `vlab cor TRACE`: the drop-test restitution estimator (thesis eq. 7.3-7.5)
//! on any force record, CSV (time column first; ',', ';' or tab separated), WAV
//! with its JSON sidecar or TDMS, such as a real lab file or one `vlab drop`
//! wrote. The work is [`vlab::signals::impacts`]'s; this is its command
//! line. Reads only; writes nothing.

use std::path::PathBuf;

use anyhow::{Context, Result, bail};
use clap::Args;
use vlab::signals::impacts::default_force_channel;
use vlab::signals::{CorInput, CorReport, ImpactParams, Trace, cor_report};

use super::analyze::LabFileArgs;
use super::args;

#[derive(Debug, Clone, Args)]
#[command(allow_negative_numbers = true)]
pub struct CorArgs {
    /// Force record: .csv (time column first), .wav (with its .wav.json sidecar) or .tdms.
    #[arg(value_name = "TRACE")]
    pub trace: PathBuf,
    /// Channel holding the force [default: 'force', or the record's only channel].
    #[arg(long, value_name = "NAME")]
    pub channel: Option<String>,
    /// Gravity (m/s^2) for v = g T / 2 (eq. 7.3); pass your local value.
    #[arg(long = "g-mps2", value_name = "G", default_value = "9.81", value_parser = args::acceleration)]
    pub g_mps2: f64,
    /// Detection threshold (in the channel's unit, N) [default: 10 % of the largest peak].
    #[arg(long = "threshold-n", value_name = "N", value_parser = args::newtons)]
    pub threshold_n: Option<f64>,
    /// No re-trigger for this long after an impact starts (s), to ignore ringing [default: 0.002].
    #[arg(long = "holdoff-s", value_name = "S", value_parser = args::non_negative_seconds)]
    pub holdoff_s: Option<f64>,
    #[command(flatten)]
    pub file: LabFileArgs,
    /// Print the result as JSON.
    #[arg(long)]
    pub json: bool,
}

fn read_trace(path: &std::path::Path, file: &LabFileArgs) -> Result<Trace> {
    if !path.is_file() {
        bail!(
            "TRACE {}: no such file (a .csv, .wav or .tdms force record)",
            path.display()
        );
    }
    file.read(path)
}

pub fn run(a: CorArgs) -> Result<()> {
    let trace = read_trace(&a.trace, &a.file)?;
    let Some(name) = a.channel.clone().or_else(|| default_force_channel(&trace)) else {
        bail!(
            "{} has channels [{}] and none is called 'force': name the force channel with --channel",
            a.trace.display(),
            trace.channel_names().join(", ")
        );
    };
    trace
        .channel(&name)
        .with_context(|| format!("--channel {name}"))?;
    let params = ImpactParams {
        threshold_n: a.threshold_n,
        holdoff_s: a.holdoff_s,
        ..ImpactParams::default()
    };
    let report = cor_report(
        &a.trace.display().to_string(),
        &trace,
        &name,
        &params,
        a.g_mps2,
    )
    .with_context(|| {
        format!(
            "{}, channel '{name}' ({} samples at {} Hz)",
            a.trace.display(),
            trace.len(),
            trace.sample_rate_hz
        )
    })?;
    for w in &report.warnings {
        match w.advice {
            Some(CorInput::Detection) => eprintln!("warning: {w} (--threshold-n, --holdoff-s)"),
            None => eprintln!("warning: {w}"),
        }
    }
    if a.json {
        println!("{}", serde_json::to_string_pretty(&report)?);
    } else {
        print_report(&report);
    }
    Ok(())
}

fn print_report(r: &CorReport) {
    println!(
        "{}, channel '{}' ({}), {} Hz, {} samples: {} impacts",
        r.file,
        r.channel,
        r.unit,
        r.sample_rate_hz,
        r.samples,
        r.impacts.len()
    );
    println!("  impact  onset [s]    peak [{}]", r.unit);
    for (k, i) in r.impacts.iter().enumerate() {
        println!("  {:6}  {:.6}  {:.4}", k + 1, i.onset_time_s, i.peak_force);
    }
    println!("  triple  gap 1 [s]  gap 2 [s]  speed [m/s]  COR");
    for (k, c) in r.cor_per_triple.iter().enumerate() {
        println!(
            "  {:6}  {:.6}   {:.6}   {:.4}       {:.5}",
            k + 1,
            r.gaps_s[k],
            r.gaps_s[k + 1],
            r.impact_speeds_mps[k],
            c
        );
    }
    println!(
        "  COR mean {:.5}, std {:.5} over {} triples (eq. 7.5); threshold {:.4} {}, hold-off {} s, g {} m/s^2",
        r.cor_mean,
        r.cor_std,
        r.cor_per_triple.len(),
        r.threshold,
        r.unit,
        r.holdoff_s,
        r.g_mps2
    );
}
