//! `vlab host predict`: the host's steady response to a stepped sine
//! predicted from a sweep's dissipation map (describing function and
//! harmonic balance, [`vlab::host::map_model`]), in milliseconds.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context, Result};
use clap::Args;

use vlab::host::map_model::stepped_sine;
use vlab::host::{DEFAULT_HOST, HostSpec};
use vlab::rig::RigFile;
use vlab::scene::Orientation;
use vlab::study::dissipation_map::{MapSource, dissipation_map};
use vlab::study::sweep::SweepFile;

use super::{FreqList, write_text};

#[derive(Debug, Clone, Args)]
pub struct PredictArgs {
    /// The sweep whose efficiency map models the damper (its sweep.csv).
    #[arg(long, value_name = "FILE")]
    map: PathBuf,
    /// The host: a built-in name (plate-40hz, beam-2mode) or a host file.
    #[arg(long, value_name = "NAME|FILE", default_value = DEFAULT_HOST)]
    host: String,
    /// Frequencies (Hz): FROM:TO:STEP or a comma-separated list.
    #[arg(long = "freq", value_name = "LIST", value_parser = super::parse_freqs)]
    freqs: FreqList,
    /// Force amplitude at the drive point (N).
    #[arg(long = "force-n", value_name = "N", value_parser = super::super::args::newtons)]
    force_n: f64,
    /// The sweep's orientation to use [default: its only one].
    #[arg(long, value_enum)]
    orientation: Option<Orientation>,
    /// Model the damper on Yang's measured efficiency instead of the DEM's.
    #[arg(long)]
    yang: bool,
    /// Write predict.csv and predict.json to this folder.
    #[arg(long, value_name = "DIR")]
    out: Option<PathBuf>,
}

pub fn run(a: PredictArgs) -> Result<()> {
    let file = SweepFile::read(&a.map).with_context(|| format!("--map {}", a.map.display()))?;
    let source = if a.yang {
        MapSource::Yang
    } else {
        MapSource::Dem
    };
    let map = dissipation_map(&file, a.orientation, None, source)
        .with_context(|| format!("--map {}", a.map.display()))?;
    let host =
        HostSpec::from_name_or_path(&a.host).with_context(|| format!("--host {}", a.host))?;
    let started = Instant::now();
    let points = stepped_sine(&map, &host, &a.freqs.0, a.force_n);
    let elapsed_ms = started.elapsed().as_secs_f64() * 1e3;
    println!(
        "{} with the damper of {} ({} kg of particles, {} map points{}), {} N at the drive: {} frequencies in {:.1} ms",
        host.name,
        a.map.display(),
        map.particle_mass_kg,
        map.columns.iter().map(Vec::len).sum::<usize>(),
        if map.has_apparent_mass() {
            ", apparent mass measured"
        } else {
            ", no apparent mass: none assumed above Gamma 1"
        },
        a.force_n,
        a.freqs.0.len(),
        elapsed_ms
    );
    println!(
        "  freq_hz  amplitude_mm  (+- from the map)      Gamma  efficiency  c_eq_n_s_per_m  roots"
    );
    let mut csv = String::from(
        "freq_hz,amplitude_m,amplitude_if_more_damping_m,amplitude_if_less_damping_m,phase_rad,receptance_m_per_n,gamma,efficiency,efficiency_se,damping_n_s_per_m,apparent_mass_kg,damper_energy_per_cycle_j,extrapolated,roots\n",
    );
    for (p, roots) in &points {
        println!(
            "  {:7.2}  {:12.4}  ({:.4} .. {:.4})  {:9.2}  {:10.3}  {:14.3}  {}{}",
            p.freq_hz,
            p.amplitude_m * 1e3,
            p.amplitude_if_more_damping_m * 1e3,
            p.amplitude_if_less_damping_m * 1e3,
            p.damper.gamma,
            p.damper.efficiency,
            p.damper.damping_n_s_per_m,
            roots,
            if p.damper.extrapolated {
                "  (outside the map)"
            } else {
                ""
            }
        );
        csv.push_str(&format!(
            "{},{},{},{},{},{},{},{},{},{},{},{},{},{}\n",
            p.freq_hz,
            p.amplitude_m,
            p.amplitude_if_more_damping_m,
            p.amplitude_if_less_damping_m,
            p.phase_rad,
            p.amplitude_m / a.force_n,
            p.damper.gamma,
            p.damper.efficiency,
            p.damper.efficiency_se,
            p.damper.damping_n_s_per_m,
            p.damper.apparent_mass_kg,
            p.damper_energy_per_cycle_j,
            p.damper.extrapolated,
            roots
        ));
    }
    let warnings: Vec<String> = points
        .iter()
        .filter_map(|(p, _)| map.outside(p.freq_hz, p.damper.gamma))
        .collect();
    for w in &warnings {
        eprintln!("warning: {w} (a prediction outside the map is a guess; extend the sweep)");
    }
    if let Some(dir) = &a.out {
        std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
        write_text(&dir.join("predict.csv"), &csv)?;
        let json = serde_json::json!({
            "host": host,
            "map": a.map.display().to_string(),
            "source": if a.yang { "yang" } else { "dem" },
            "force_n": a.force_n,
            "elapsed_ms": elapsed_ms,
            "warnings": warnings,
            "points": points.iter().map(|(p, r)| serde_json::json!({"response": p, "roots": r})).collect::<Vec<_>>(),
        });
        write_text(
            &dir.join("predict.json"),
            &serde_json::to_string_pretty(&json)?,
        )?;
        println!("wrote {}", dir.display());
    }
    Ok(())
}
