//! `vlab sweep`: damping efficiency against amplitude at one frequency, over
//! several seeds (a granular run is chaotic: the spread matters). Each seed's bed
//! is settled once and driven at every amplitude; independent runs go to
//! separate threads, so the results do not depend on the thread count.

use std::path::PathBuf;
use std::sync::Mutex;

use anyhow::{Context, Result, bail};
use clap::Args;
use rayon::prelude::*;
use serde::Serialize;

use vlab::atomic_write::{OutputDir, write_atomic};
use vlab::rig::SineMotion;
use vlab::scene::damper::{DrivePlan, NoObserver, run_drive};
use vlab::scene::file::Scene;
use vlab::scene::settle::{SettledBed, prepare_drive, settle_bed};
use vlab::scene::shake::check_drive;
use vlab::signals::{Series, SeriesStyle, plot_xy_svg};

use super::args;
use super::progress::ProgressLine;
use super::shake::SceneArgs;

#[derive(Debug, Clone, Args)]
#[command(allow_negative_numbers = true)]
pub struct SweepArgs {
    /// Drive frequency (Hz).
    #[arg(long = "freq", value_name = "HZ", value_parser = args::freq_hz)]
    freq_hz: f64,
    /// Amplitudes Γ, comma-separated (dimensionless).
    #[arg(long, value_name = "LIST", required = true, value_delimiter = ',', value_parser = args::gamma)]
    gammas: Vec<f64>,
    /// Seeds of the random fill, comma-separated.
    #[arg(
        long,
        value_name = "LIST",
        default_value = "1,2,3",
        value_delimiter = ','
    )]
    seeds: Vec<u64>,
    #[command(flatten)]
    scene: SceneArgs,
    /// Output folder [default: signals/sweep-<scene>-<freq>Hz].
    #[arg(long, value_name = "DIR")]
    out: Option<PathBuf>,
    /// Print the results as JSON.
    #[arg(long)]
    json: bool,
}

#[derive(Debug, Clone, Serialize)]
struct SweepRow {
    freq_hz: f64,
    gamma: f64,
    seed: u64,
    efficiency: f64,
    energy_per_cycle_j: f64,
    e_max_j: f64,
    friction_share: f64,
    particle_particle_share: f64,
    ledger_residual_rel: f64,
}

#[derive(Debug, Clone, Serialize)]
struct GammaStats {
    gamma: f64,
    efficiency_mean: f64,
    efficiency_std: f64,
    efficiency_min: f64,
    efficiency_max: f64,
}

pub fn run(a: SweepArgs, quiet: bool) -> Result<()> {
    if a.seeds.is_empty() {
        bail!("--seeds is empty: give at least one seed");
    }
    let gammas = a.gammas.clone();
    let scene = a.scene.resolve()?;
    for &g in &gammas {
        check_drive(&scene, a.freq_hz, g)?;
    }
    let out_dir = a.out.clone().unwrap_or_else(|| {
        PathBuf::from("signals").join(format!("sweep-{}-{}Hz", scene.name, a.freq_hz))
    });
    let made = OutputDir::prepare(&out_dir)?;
    let progress = Mutex::new(ProgressLine::new("sweep", quiet));
    let total = a.seeds.len() * (1 + gammas.len());
    let done = Mutex::new(0usize);
    let tick = |what: String| {
        let mut d = done.lock().unwrap_or_else(|e| e.into_inner());
        *d += 1;
        let mut p = progress.lock().unwrap_or_else(|e| e.into_inner());
        p.note(&format!("sweep: {}/{} {what}", *d, total));
    };
    let result = (|| -> Result<Vec<SweepRow>> {
        let beds: Vec<SettledBed> = a
            .seeds
            .par_iter()
            .map(|&seed| {
                let mut s = scene.clone();
                s.simulation.seed = seed;
                let bed = settle_bed(&s, &mut |_| {})
                    .with_context(|| format!("settling the bed of seed {seed}"));
                tick(format!("bed of seed {seed} settled"));
                bed
            })
            .collect::<Result<_>>()?;
        let jobs: Vec<(usize, f64)> = (0..beds.len())
            .flat_map(|b| gammas.iter().map(move |&g| (b, g)))
            .collect();
        jobs.par_iter()
            .map(|&(b, gamma)| {
                let row = drive_once(&scene, &beds[b], a.seeds[b], a.freq_hz, gamma);
                tick(format!("seed {} Gamma {gamma} driven", a.seeds[b]));
                row
            })
            .collect()
    })();
    let rows = made.keep_if_ok(result)?;
    let stats = statistics(&gammas, &rows);
    write_results(&out_dir, &rows, &stats, a.freq_hz, &scene)?;
    if a.json {
        println!(
            "{}",
            serde_json::to_string_pretty(&serde_json::json!({ "runs": rows, "by_gamma": stats }))?
        );
    } else {
        println!(
            "{} damper, {} Hz, {}: efficiency over seeds {:?}",
            scene.name,
            a.freq_hz,
            scene.enclosure.orientation.as_str(),
            a.seeds
        );
        println!("   Gamma   mean    std     min     max");
        for s in &stats {
            println!(
                "  {:6}  {:.3}  {:.3}  {:.3}  {:.3}",
                s.gamma, s.efficiency_mean, s.efficiency_std, s.efficiency_min, s.efficiency_max
            );
        }
        println!("  wrote {}", out_dir.display());
    }
    Ok(())
}

fn drive_once(
    scene: &Scene,
    bed: &SettledBed,
    seed: u64,
    freq_hz: f64,
    gamma: f64,
) -> Result<SweepRow> {
    let mut world = prepare_drive(bed, scene, scene.drive_dt_s(freq_hz, gamma))?;
    let g = scene.simulation.gravity_mps2;
    let plan = DrivePlan {
        freq_hz,
        gamma,
        gravity_mps2: g,
        length: scene.drive_length(),
    };
    let mut drive = SineMotion::new(freq_hz, gamma, g);
    let out = run_drive(&mut world, &plan, &mut drive, &mut NoObserver, &mut |_| {})
        .with_context(|| format!("driving seed {seed} at Gamma {gamma}"))?;
    let d = out.dissipated_per_cycle;
    let total = d.total();
    Ok(SweepRow {
        freq_hz,
        gamma,
        seed,
        efficiency: out.efficiency,
        energy_per_cycle_j: out.energy_per_cycle_j,
        e_max_j: out.e_max_j,
        friction_share: (d.pp_tangential + d.pw_tangential) / total,
        particle_particle_share: (d.pp_normal + d.pp_tangential) / total,
        ledger_residual_rel: out.whole.residual_relative(),
    })
}

fn statistics(gammas: &[f64], rows: &[SweepRow]) -> Vec<GammaStats> {
    gammas
        .iter()
        .map(|&g| {
            let e: Vec<f64> = rows
                .iter()
                .filter(|r| r.gamma == g)
                .map(|r| r.efficiency)
                .collect();
            let n = e.len() as f64;
            let mean = e.iter().sum::<f64>() / n;
            let var = if e.len() > 1 {
                e.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0)
            } else {
                0.0
            };
            GammaStats {
                gamma: g,
                efficiency_mean: mean,
                efficiency_std: var.sqrt(),
                efficiency_min: e.iter().copied().fold(f64::INFINITY, f64::min),
                efficiency_max: e.iter().copied().fold(f64::NEG_INFINITY, f64::max),
            }
        })
        .collect()
}

fn write_results(
    dir: &std::path::Path,
    rows: &[SweepRow],
    stats: &[GammaStats],
    freq_hz: f64,
    scene: &Scene,
) -> Result<()> {
    let csv = dir.join("sweep.csv");
    write_atomic(&csv, |w| {
        use std::io::Write;
        writeln!(
            w,
            "freq [Hz],gamma [],seed [],efficiency [],energy_per_cycle [J],e_max [J],friction_share [],particle_particle_share [],ledger_residual_rel []"
        )?;
        for r in rows {
            writeln!(
                w,
                "{},{},{},{},{},{},{},{},{}",
                r.freq_hz,
                r.gamma,
                r.seed,
                r.efficiency,
                r.energy_per_cycle_j,
                r.e_max_j,
                r.friction_share,
                r.particle_particle_share,
                r.ledger_residual_rel
            )?;
        }
        Ok(())
    })
    .with_context(|| format!("writing {}", csv.display()))?;
    let series = [
        Series {
            name: "mean over seeds".into(),
            points: stats.iter().map(|s| (s.gamma, s.efficiency_mean)).collect(),
            style: SeriesStyle::Line,
        },
        Series {
            name: "each seed".into(),
            points: rows.iter().map(|r| (r.gamma, r.efficiency)).collect(),
            style: SeriesStyle::Points,
        },
    ];
    let svg = dir.join("efficiency.svg");
    plot_xy_svg(
        &svg,
        &format!(
            "{} damper, {} Hz: damping efficiency (eq. 6.8)",
            scene.name, freq_hz
        ),
        "Gamma (peak acceleration / g)",
        "efficiency",
        &series,
    )?;
    Ok(())
}
