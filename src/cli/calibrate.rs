//! `vlab calibrate`: the rig's phase error measured on the empty enclosure
//! (thesis Section 7.4.2, Fig. 7.9). No particles, so no DEM is built: only the
//! shaker, the transducers and the digitiser run. The table (frequency → phase
//! error, averaged over the amplitudes) is what `vlab shake --calibration` and
//! `vlab analyze --calibration` subtract.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use clap::Args;
use serde::Serialize;

use vlab::drive::Drive;
use vlab::experiment::measurement::calibrate_rig;
use vlab::experiment::shake::resolve_rig;
use vlab::rig::{RigSpec, ShakerKind};
use vlab::scene::Scene;
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

#[derive(Debug, Serialize)]
struct Row {
    freq_hz: f64,
    phase_error_rad: f64,
    spread_rad: f64,
    amplitudes: usize,
    rig_model_phase_error_rad: f64,
}

pub fn run(a: CalibrateArgs) -> Result<()> {
    if a.record_cycles < 2 || a.record_cycles > a.cycles {
        bail!(
            "--record-cycles {} is invalid: must lie in [2, --cycles = {}]",
            a.record_cycles,
            a.cycles
        );
    }
    let g = Scene::thesis().simulation.gravity_mps2;
    let rig = resolve_for_all(&a, g)?;
    if a.dt_s > 1.0 / rig.daq.sample_rate_hz {
        bail!(
            "--dt-s {} is invalid: must be at most one sample period, {} s at {} Hz",
            a.dt_s,
            1.0 / rig.daq.sample_rate_hz,
            rig.daq.sample_rate_hz
        );
    }
    let out = a
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from("signals").join(format!("calibration-{}.json", rig.name)));
    if let Some(parent) = out.parent().filter(|p| !p.as_os_str().is_empty()) {
        std::fs::create_dir_all(parent)
            .with_context(|| format!("cannot create folder {}", parent.display()))?;
    }
    let table = calibrate_rig(
        &rig,
        rig.shaker.kind,
        &a.freqs_hz,
        &a.gammas,
        g,
        a.dt_s,
        a.cycles,
        a.record_cycles,
        1,
    )
    .context("running the empty enclosure")?
    .table;
    table.save_json(&out)?;
    let rows: Vec<Row> = table
        .points
        .iter()
        .map(|e| Row {
            freq_hz: e.freq_hz,
            phase_error_rad: e.phase_error_rad,
            spread_rad: e.spread_rad,
            amplitudes: e.n_amplitudes,
            rig_model_phase_error_rad: rig.expected_phase_error_rad(e.freq_hz),
        })
        .collect();
    if a.json {
        println!("{}", serde_json::to_string_pretty(&rows)?);
    } else {
        print_table(&rig, &a.gammas, &rows, &table, &out);
    }
    Ok(())
}

/// The rig of `--rig` and `--shaker`, refusing any (frequency, amplitude)
/// it cannot do before running anything.
fn resolve_for_all(a: &CalibrateArgs, g: f64) -> Result<RigSpec> {
    let mut resolved = None;
    for &f in &a.freqs_hz {
        for &gamma in &a.gammas {
            let drive = Drive::new(f, gamma, g)?;
            resolved = Some(
                resolve_rig(&a.rig, a.shaker, &drive)
                    .with_context(|| format!("--rig {}", a.rig))?,
            );
        }
    }
    let Some(rig) = resolved else {
        bail!("--freq and --gammas must name at least one value each");
    };
    Ok(rig)
}

/// The table as text, with the fitted model and where it was written.
fn print_table(rig: &RigSpec, gammas: &[f64], rows: &[Row], table: &PhaseCalibration, out: &Path) {
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
