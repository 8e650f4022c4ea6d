//! `vlab predict`: the bouncing-bed onset amplitude predicted by thesis eq.
//! 6.11–6.13 ([`vlab::study::predict`]), with close- and loose-packing
//! clearances (close packing alone for a fill from loose packing, 0.55, up to
//! close packing, 0.64).

use anyhow::Result;
use clap::Args;

use vlab::study::predict::{CLOSE_PACKING, LOOSE_PACKING, predict_bouncing_bed};

use super::args;

#[derive(Debug, Clone, Args)]
#[command(allow_negative_numbers = true)]
pub struct PredictArgs {
    /// Drive frequencies (Hz), comma-separated.
    #[arg(long = "freq", value_name = "LIST", required = true, value_delimiter = ',', value_parser = args::freq_hz)]
    freqs_hz: Vec<f64>,
    /// Volume fill ratio of the particles (eq. 6.1).
    #[arg(long = "fill-ratio", default_value = "0.466", value_parser = args::gamma)]
    fill_ratio: f64,
    /// Inner length of the enclosure along the drive (m).
    #[arg(long = "length-m", value_name = "M", default_value = "0.04", value_parser = args::metres)]
    length_m: f64,
    /// Gravitational acceleration (m/s^2).
    #[arg(long = "g-mps2", value_name = "M/S2", default_value = "9.81", value_parser = args::acceleration)]
    g_mps2: f64,
    /// Print JSON: close_packing_gamma and loose_packing_gamma in the order of --freq.
    #[arg(long)]
    json: bool,
}

/// Runs the command.
pub fn run(a: PredictArgs) -> Result<()> {
    let flags = args::FlagKeys::new()
        .set(true, "fill_ratio", "--fill-ratio")
        .set(true, "length_m", "--length-m")
        .set(true, "freq_hz", "--freq");
    let p = predict_bouncing_bed(&a.freqs_hz, a.fill_ratio, a.length_m, a.g_mps2)
        .map_err(|e| flags.name_flags(e.into()))?;
    if a.json {
        println!("{}", serde_json::to_string_pretty(&p)?);
        return Ok(());
    }
    println!(
        "bouncing-bed onset (thesis eq. 6.11-6.13): Gamma = w^2 h / (g pi), h = (1 - fill / fill_max) L"
    );
    let lp_clearance = p
        .loose_packing_clearance_m
        .map_or("none".to_string(), |h| format!("{:.2} mm", 1e3 * h));
    println!(
        "  fill {}, L {} m: clearance {:.2} mm with close packing ({CLOSE_PACKING}), {lp_clearance} with loose packing ({LOOSE_PACKING})",
        a.fill_ratio,
        a.length_m,
        1e3 * p.close_packing_clearance_m,
    );
    println!("  freq [Hz]   close packing   loose packing");
    for (k, f) in p.freq_hz.iter().enumerate() {
        let lp = p
            .loose_packing_gamma
            .as_ref()
            .map_or("-".to_string(), |g| format!("{:.1}", g[k]));
        println!(
            "  {:>9}   {:>13.1}   {:>13}",
            f, p.close_packing_gamma[k], lp
        );
    }
    match &p.loose_packing_note {
        Some(note) => println!("  {note}"),
        None => println!(
            "  the loose-packing estimate applies to fills below {LOOSE_PACKING}, the close-packing one up to {CLOSE_PACKING}"
        ),
    }
    println!(
        "  the thesis found the most efficient amplitude at this onset; close packing is the better estimate (Table 6.3)"
    );
    Ok(())
}
