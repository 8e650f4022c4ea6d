//! `vlab calibrate`: the rig's phase error measured on the empty enclosure
//! (thesis Section 7.4.2, Fig. 7.9). No particles, so no DEM is built: only the
//! shaker, the transducers and the digitiser run. The table (frequency → phase
//! error, averaged over the amplitudes) is what `vlab shake --calibration` and
//! `vlab analyze --calibration` subtract.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use clap::Args;

use vlab::experiment::calibration_plan::{CalibrationPlan, CalibrationRow};
use vlab::rig::{RigSpec, ShakerKind};
use vlab::scene::{Scene, SceneError};
use vlab::signals::PhaseCalibration;

use super::args;

#[derive(Debug, Clone, Args)]
#[command(allow_negative_numbers = true)]
pub struct CalibrateArgs {
    /// Drive frequencies (Hz), comma-separated.
    #[arg(long = "freq", value_name = "LIST", required = true, value_delimiter = ',', value_parser = args::freq_hz)]
    freqs_hz: Vec<f64>,
    /// Amplitudes Γ per frequency, comma-separated; averaged, as in Fig. 7.9.
    #[arg(long, value_name = "LIST", default_value = "2,5,10", value_delimiter = ',', value_parser = args::gamma)]
    gammas: Vec<f64>,
    /// The rig: a built-in name or a rig file.
    #[arg(long, value_name = "NAME|FILE", default_value = vlab::rig::DEFAULT_RIG)]
    rig: String,
    /// How the enclosure is moved [default: the rig's own].
    #[arg(long, value_enum)]
    shaker: Option<ShakerKind>,
    /// Drive cycles per run; the last --record-cycles are recorded, as in a
    /// damper run.
    #[arg(long, default_value = "8")]
    cycles: u32,
    /// Cycles recorded at the end of each run.
    #[arg(long, default_value = "5")]
    record_cycles: u32,
    /// Time step (s) of the rig model.
    #[arg(long = "dt-s", value_name = "S", default_value = "1e-6", value_parser = args::seconds)]
    dt_s: f64,
    /// Output file [default: signals/calibration-<rig>.json].
    #[arg(long, value_name = "FILE")]
    out: Option<PathBuf>,
    /// Print the table as JSON.
    #[arg(long)]
    json: bool,
}

pub fn run(a: CalibrateArgs) -> Result<()> {
    let g = Scene::thesis().simulation.gravity_mps2;
    let plan = CalibrationPlan {
        rig: a.rig.clone(),
        shaker: a.shaker,
        freqs_hz: a.freqs_hz.clone(),
        gammas: a.gammas.clone(),
        cycles: a.cycles,
        record_cycles: a.record_cycles,
        dt_s: a.dt_s,
    };
    let rig = plan.check(g).map_err(|e| match &e {
        SceneError::Invalid(p) => anyhow::Error::from(match p.key.as_str() {
            "record_cycles" => p.renamed("--record-cycles"),
            "dt_s" => p.renamed("--dt-s"),
            "freqs_hz" | "freq_hz" => p.renamed("--freq"),
            "gamma" => p.renamed("--gammas"),
            _ => p.clone(),
        }),
        _ => anyhow::Error::from(e).context(format!("--rig {}", a.rig)),
    })?;
    let out = a
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from("signals").join(format!("calibration-{}.json", rig.name)));
    if let Some(parent) = out.parent().filter(|p| !p.as_os_str().is_empty()) {
        std::fs::create_dir_all(parent)
            .with_context(|| format!("cannot create folder {}", parent.display()))?;
    }
    let (table, rows) = plan.run(&rig, g).context("running the empty enclosure")?;
    table.save_json(&out)?;
    if a.json {
        println!("{}", serde_json::to_string_pretty(&rows)?);
    } else {
        print_table(&rig, &a.gammas, &rows, &table, &out);
    }
    Ok(())
}

/// The table as text, with the fitted model and where it was written.
fn print_table(
    rig: &RigSpec,
    gammas: &[f64],
    rows: &[CalibrationRow],
    table: &PhaseCalibration,
    out: &Path,
) {
    println!(
        "rig {} ({} shaker), empty enclosure of {} kg, Gamma {:?}:",
        rig.name, rig.shaker.kind, rig.enclosure.mass_kg, gammas
    );
    println!("   freq [Hz]   phase error [deg]   spread [deg]   rig model [deg]");
    for r in rows {
        println!(
            "  {:9}   {:17.4}   {:12.5}   {:15.4}",
            r.freq_hz,
            r.phase_error_rad.to_degrees(),
            r.spread_rad.to_degrees(),
            r.rig_model_phase_error_rad.to_degrees()
        );
    }
    match &table.model {
        Some(m) => println!(
            "  high-pass + skew fit: net high-pass corner {:.4} Hz, skew {:.3} us (rig model: {:.4} Hz, {:.3} us)",
            m.force_high_pass_hz - m.accel_high_pass_hz,
            1e6 * m.skew_s,
            rig.force.high_pass_hz - rig.accelerometer.high_pass_hz,
            1e6 * (rig.force.sample_skew_s - rig.accelerometer.sample_skew_s)
        ),
        None => println!(
            "  one frequency: harmonics will be corrected as a pure delay; give two or more to fit the high-pass + skew"
        ),
    }
    if table.force_polarity_reversed {
        println!(
            "  force polarity reversed on the empty enclosure (phase near pi): stored without the pi"
        );
    }
    println!("  wrote {}", out.display());
}
