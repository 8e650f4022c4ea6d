//! `vlab cor TRACE`: the drop-test restitution estimator (thesis eq. 7.3-7.5)
//! on any force record, CSV (time column first; ',', ';' or tab separated), WAV
//! with its JSON sidecar or TDMS, such as a real lab file or one `vlab drop`
//! wrote.
//! Reads only; writes nothing.

use std::path::PathBuf;

use anyhow::{Context, Result, bail};
use clap::Args;
use serde::Serialize;

use vlab::signals::{ImpactParams, Trace, estimate_cor};

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

#[derive(Debug, Serialize)]
struct ImpactRow {
    onset_time_s: f64,
    peak_time_s: f64,
    peak_force: f64,
}

#[derive(Debug, Serialize)]
struct CorReport {
    file: String,
    channel: String,
    unit: String,
    sample_rate_hz: f64,
    samples: usize,
    g_mps2: f64,
    threshold: f64,
    release: f64,
    holdoff_s: f64,
    noise_std: f64,
    impacts: Vec<ImpactRow>,
    gaps_s: Vec<f64>,
    /// COR of each triple (eq. 7.5).
    cor_per_triple: Vec<f64>,
    /// Speed at each triple's middle impact, g T / 2 of the gap before it (eq. 7.3), m/s.
    impact_speeds_mps: Vec<f64>,
    cor_mean: f64,
    cor_std: f64,
    /// Triples (from 1) whose second gap is longer than the first.
    growing_gap_triples: Vec<usize>,
    warnings: Vec<String>,
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
    let name = match &a.channel {
        Some(n) => n.clone(),
        None if trace.channel("force").is_ok() => "force".to_string(),
        None if trace.channels.len() == 1 => trace.channels[0].name.clone(),
        None => bail!(
            "{} has channels [{}] and none is called 'force': name the force channel with --channel",
            a.trace.display(),
            trace.channel_names().join(", ")
        ),
    };
    let channel = trace
        .channel(&name)
        .with_context(|| format!("--channel {name}"))?;
    let params = ImpactParams {
        threshold_n: a.threshold_n,
        holdoff_s: a.holdoff_s,
        ..ImpactParams::default()
    };
    let r = estimate_cor(&trace, &name, &params, a.g_mps2).with_context(|| {
        format!(
            "{}, channel '{name}' ({} samples at {} Hz)",
            a.trace.display(),
            trace.len(),
            trace.sample_rate_hz
        )
    })?;
    let d = &r.detection;
    let n = r.cor.cor_per_triple.len();
    let grown: Vec<usize> = r.cor.growing_gaps().iter().map(|k| k + 1).collect();
    let mut warnings = Vec::new();
    if !grown.is_empty() {
        warnings.push(format!(
            "triple(s) {} have a second gap longer than the first (COR > 1): an impact was \
             missed or ringing taken for one; try --threshold-n or --holdoff-s",
            grown
                .iter()
                .map(|k| k.to_string())
                .collect::<Vec<_>>()
                .join(", ")
        ));
    }
    if channel.unit != "N" {
        warnings.push(format!(
            "channel '{name}' is in '{}', not N: the threshold is in that unit",
            channel.unit
        ));
    }
    let report = CorReport {
        file: a.trace.display().to_string(),
        channel: name.clone(),
        unit: channel.unit.clone(),
        sample_rate_hz: trace.sample_rate_hz,
        samples: trace.len(),
        g_mps2: a.g_mps2,
        threshold: d.threshold_n,
        release: d.release_n,
        holdoff_s: d.holdoff_s,
        noise_std: d.noise_std_n,
        impacts: d
            .impacts
            .iter()
            .map(|i| ImpactRow {
                onset_time_s: i.onset_time_s,
                peak_time_s: i.peak_time_s,
                peak_force: i.peak_force_n,
            })
            .collect(),
        gaps_s: r.cor.gaps_s.clone(),
        cor_per_triple: r.cor.cor_per_triple.clone(),
        impact_speeds_mps: r.cor.impact_speeds_mps[..n].to_vec(),
        cor_mean: r.cor.cor_mean,
        cor_std: r.cor.cor_std,
        growing_gap_triples: grown,
        warnings,
    };
    for w in &report.warnings {
        eprintln!("warning: {w}");
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
