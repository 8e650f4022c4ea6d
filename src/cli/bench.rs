//! `vlab bench`: how fast the lab runs. Reports particle-steps per second
//! (particles × time steps / wall seconds of the stepping loop) on the thesis
//! scene, for pouring/settling (a dense, quasi-static bed) and for the drive at
//! 40 Hz, Γ 20, with one thread and with all threads; the time to analyse a 5 s,
//! 40 kHz two-channel trace with Yang's method; and the peak memory.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context, Result};
use clap::Args;
use serde::Serialize;

use vlab::atomic_write::write_atomic;
use vlab::dem::World;
use vlab::rig::SineMotion;
use vlab::scene::damper::{DriveLength, DrivePlan, NoObserver, run_drive};
use vlab::scene::file::Scene;
use vlab::scene::settle::{prepare_drive, settle_bed};
use vlab::signals::bench_yang_power;

use super::progress::ProgressLine;

#[derive(Debug, Clone, Args)]
pub struct BenchArgs {
    /// Drive cycles timed per configuration (40 Hz: 25 000 steps each).
    #[arg(long, default_value = "2")]
    cycles: u32,
    /// Also write the figures to this CSV file.
    #[arg(long, value_name = "FILE")]
    out: Option<PathBuf>,
    /// Print the figures as JSON.
    #[arg(long)]
    json: bool,
}

#[derive(Debug, Serialize)]
struct BenchRow {
    case: String,
    threads: usize,
    particles: usize,
    steps: u64,
    wall_s: f64,
    particle_steps_per_s: f64,
}

#[derive(Debug, Serialize)]
struct BenchReport {
    rows: Vec<BenchRow>,
    /// Yang's method on a 5 s, 40 kHz, two-channel trace, planning the FFT (ms).
    yang_power_5s_40khz_ms: f64,
    /// The same with the FFT plan reused (ms).
    yang_power_5s_40khz_reused_plan_ms: f64,
    peak_memory_mib: Option<f64>,
    cores: usize,
}

pub fn run(a: BenchArgs, quiet: bool) -> Result<()> {
    let cores = std::thread::available_parallelism()
        .map(|n| n.get())
        .unwrap_or(1);
    let scene = Scene::thesis();
    let mut progress = ProgressLine::new("bench", quiet);
    let mut rows = Vec::new();

    let one = single_pool(1)?;
    let started = Instant::now();
    let bed = one
        .install(|| settle_bed(&scene, &mut |p| progress.update(p)))
        .context("settling the thesis bed")?;
    let settle_wall = started.elapsed().as_secs_f64();
    let n = bed.world.particles.len();
    let settle_steps = bed.settle_steps;
    rows.push(BenchRow {
        case: "pour and settle (dense bed)".into(),
        threads: 1,
        particles: n,
        steps: settle_steps,
        wall_s: settle_wall,
        particle_steps_per_s: (n as u64 * settle_steps) as f64 / settle_wall,
    });

    let mut configs = vec![(1usize, false)];
    if cores > 1 {
        configs.push((cores, false));
        configs.push((cores, true));
    }
    for (threads, force_parallel) in configs {
        let pool = single_pool(threads)?;
        let mut world: World = prepare_drive(&bed, &scene, scene.drive_dt_s(40.0, 20.0))?;
        if force_parallel {
            world.numerics.parallel_min_pairs = 0;
        }
        let plan = DrivePlan {
            freq_hz: 40.0,
            gamma: 20.0,
            gravity_mps2: scene.simulation.gravity_mps2,
            length: DriveLength::Fixed {
                cycles: a.cycles.max(1),
                steady_cycles: 1,
            },
        };
        let mut drive = SineMotion::new(plan.freq_hz, plan.gamma, plan.gravity_mps2);
        let out = pool
            .install(|| {
                run_drive(&mut world, &plan, &mut drive, &mut NoObserver, &mut |p| {
                    progress.update(p)
                })
            })
            .context("driving the thesis bed")?;
        rows.push(BenchRow {
            case: if force_parallel {
                "drive 40 Hz Gamma 20, pair loop split across threads".into()
            } else {
                "drive 40 Hz Gamma 20".into()
            },
            threads,
            particles: n,
            steps: out.steps,
            wall_s: out.wall_time_s,
            particle_steps_per_s: (n as u64 * out.steps) as f64 / out.wall_time_s,
        });
    }
    progress.finish();
    let yang = bench_yang_power(5.0, 40_000.0, 40.0, 20).context("timing Yang's method")?;
    let report = BenchReport {
        rows,
        yang_power_5s_40khz_ms: yang.fresh_median_s * 1e3,
        yang_power_5s_40khz_reused_plan_ms: yang.reused_median_s * 1e3,
        peak_memory_mib: peak_memory_mib(),
        cores,
    };
    if let Some(path) = &a.out {
        write_atomic(path, |w| {
            use std::io::Write;
            writeln!(
                w,
                "case [],threads [],particles [],steps [],wall [s],particle_steps_per_s [1/s]"
            )?;
            for r in &report.rows {
                writeln!(
                    w,
                    "{},{},{},{},{},{}",
                    r.case, r.threads, r.particles, r.steps, r.wall_s, r.particle_steps_per_s
                )?;
            }
            Ok(())
        })
        .with_context(|| format!("writing {}", path.display()))?;
    }
    if a.json {
        println!("{}", serde_json::to_string_pretty(&report)?);
    } else {
        println!(
            "thesis scene, {} particles, dt {:.1e} s, {} cores",
            n,
            scene.drive_dt_s(40.0, 20.0),
            cores
        );
        for r in &report.rows {
            println!(
                "  {:55} {} thread{:1}  {:6.2} M particle-steps/s  ({} steps, {:.2} s)",
                r.case,
                r.threads,
                if r.threads == 1 { "" } else { "s" },
                r.particle_steps_per_s / 1e6,
                r.steps,
                r.wall_s
            );
        }
        println!(
            "  Yang's method on a 5 s, 40 kHz two-channel trace: {:.2} ms ({:.2} ms with the FFT plan reused)",
            report.yang_power_5s_40khz_ms, report.yang_power_5s_40khz_reused_plan_ms
        );
        if let Some(m) = report.peak_memory_mib {
            println!("  peak memory {m:.1} MiB");
        }
    }
    Ok(())
}

fn single_pool(threads: usize) -> Result<rayon::ThreadPool> {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| anyhow::anyhow!("cannot start {threads} threads: {e}"))
}

/// Peak resident memory of this process (MiB), from /proc on Linux.
fn peak_memory_mib() -> Option<f64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kib: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib / 1024.0)
}
