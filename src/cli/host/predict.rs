//! `vlab host predict`: the host's steady response to a stepped sine
//! predicted from a sweep's dissipation map (describing function and
//! harmonic balance, [`vlab::host::map_model`]), in milliseconds.

use std::path::PathBuf;

use anyhow::{Context, Result};
use clap::Args;

use vlab::host::{DEFAULT_HOST, HostSpec};
use vlab::rig::RigFile;
use vlab::scene::Orientation;
use vlab::study::dissipation_map::{MapSource, dissipation_map};
use vlab::study::host_prediction::HostPrediction;

use super::FreqList;

#[derive(Debug, Clone, Args)]
pub struct PredictArgs {
    /// The sweep whose efficiency map models the damper (its sweep.csv).
    /// Given again (`--map COARSE --map FINE`), a later sweep replaces the
    /// conditions it holds: a map refined at the onset by a finer Γ grid
    /// and more seeds there, from a sweep of the same scene and rig.
    #[arg(long, value_name = "FILE", required = true)]
    map: Vec<PathBuf>,
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
    let (file, label) = super::read_maps(&a.map)?;
    let source = if a.yang {
        MapSource::Yang
    } else {
        MapSource::Dem
    };
    let map = dissipation_map(&file, a.orientation, None, source)
        .with_context(|| format!("--map {label}"))?;
    let host =
        HostSpec::from_name_or_path(&a.host).with_context(|| format!("--host {}", a.host))?;
    let p = HostPrediction::run(&map, label, source, host, &a.freqs.0, a.force_n)
        .with_map_branch(&file);
    println!(
        "{} with the damper of {} ({} kg of particles, {} map points{}), {} N at the drive: {} frequencies in {:.1} ms",
        p.host.name,
        p.map_label,
        p.particle_mass_kg,
        p.map_points,
        if p.has_apparent_mass {
            ", apparent mass measured"
        } else {
            ", no apparent mass: none assumed above Gamma 1"
        },
        p.force_n,
        a.freqs.0.len(),
        p.elapsed_ms
    );
    println!(
        "  freq_hz  amplitude_mm  (range claimed)         Gamma  efficiency (its range)  c_eq_n_s_per_m  roots"
    );
    for (r, roots) in &p.points {
        println!(
            "  {:7.2}  {:12.4}  ({:.4} .. {:.4})  {:5.2}  {:5.3} ({:.3} .. {:.3})  {:14.3}  {}{}",
            r.freq_hz,
            r.amplitude_m * 1e3,
            r.amplitude_low_m * 1e3,
            r.amplitude_high_m * 1e3,
            r.damper.gamma,
            r.damper.efficiency,
            r.damper.efficiency_low,
            r.damper.efficiency_high,
            r.damper.damping_n_s_per_m,
            roots,
            if r.damper.extrapolated {
                "  (outside the map)"
            } else {
                ""
            }
        );
    }
    if let Some(w) = &p.branch_warning {
        eprintln!("warning: {w}");
    }
    for w in &p.warnings {
        eprintln!("warning: {w} (a prediction outside the map is a guess; extend the sweep)");
    }
    if let Some(dir) = &a.out {
        p.write(dir)
            .with_context(|| format!("writing into {}", dir.display()))?;
        println!("wrote {}", dir.display());
    }
    Ok(())
}
