//! `vlab bench`: how fast the lab runs. Reports particle-steps per second
//! (particles × time steps / wall seconds of the stepping loop) on the thesis
//! scene, for pouring/settling (a dense, quasi-static bed) and for the drive at
//! 40 Hz, Γ 20, with one thread and with all threads, and the same drive
//! frictionless (μ = 0: no tangential force, no rotation); one step of lattice
//! beds of many spheres (`--beds`, see `vlab::dem::testbed`) on one thread and
//! on all; the time to analyse a 5 s, 40 kHz two-channel trace with Yang's
//! method; and the peak memory.
//!
//! Each row also gives the rate per CPU second the process used (user +
//! system): on a machine shared with other work the wall-clock rate falls
//! with the load, the CPU rate much less.

use std::path::PathBuf;
use std::time::Instant;

use anyhow::{Context, Result};
use clap::Args;
use serde::Serialize;

use vlab::atomic_write::write_atomic;
use vlab::dem::World;
use vlab::dem::testbed::lattice_bed;
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
    /// Lattice beds to time, by number of spheres (comma-separated; none: "").
    #[arg(long, value_delimiter = ',', default_value = "5000,20000")]
    beds: Vec<usize>,
    /// Steps timed per lattice bed and thread count.
    #[arg(long, default_value = "300")]
    bed_steps: u32,
    /// Leave out the thesis scene (and Yang's method): time the beds only,
    /// e.g. to read one bed's peak memory.
    #[arg(long)]
    beds_only: bool,
}

#[derive(Debug, Serialize)]
struct BenchRow {
    case: String,
    threads: usize,
    particles: usize,
    steps: u64,
    wall_s: f64,
    particle_steps_per_s: f64,
    /// CPU seconds (user + system) the process used over the row.
    cpu_s: f64,
    /// Particle-steps per CPU second.
    particle_steps_per_cpu_s: f64,
}

impl BenchRow {
    fn new(case: String, threads: usize, particles: usize, steps: u64, clock: Clock) -> Self {
        let (wall_s, cpu_s) = clock.elapsed();
        let work = (particles as u64 * steps) as f64;
        BenchRow {
            case,
            threads,
            particles,
            steps,
            wall_s,
            particle_steps_per_s: work / wall_s,
            cpu_s,
            particle_steps_per_cpu_s: work / cpu_s,
        }
    }
}

/// Wall and CPU time since it was started.
#[derive(Debug, Clone, Copy)]
struct Clock {
    wall: Instant,
    cpu_s: f64,
}

impl Clock {
    fn start() -> Self {
        Clock {
            wall: Instant::now(),
            cpu_s: process_cpu_s(),
        }
    }

    /// (wall, CPU) seconds since the start.
    fn elapsed(&self) -> (f64, f64) {
        (
            self.wall.elapsed().as_secs_f64(),
            process_cpu_s() - self.cpu_s,
        )
    }
}

#[derive(Debug, Serialize)]
struct BenchReport {
    rows: Vec<BenchRow>,
    /// Yang's method on a 5 s, 40 kHz, two-channel trace, planning the FFT (ms).
    yang_power_5s_40khz_ms: Option<f64>,
    /// The same with the FFT plan reused (ms).
    yang_power_5s_40khz_reused_plan_ms: Option<f64>,
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
    let mut configs = vec![1usize];
    if cores > 1 {
        configs.push(cores);
    }
    if !a.beds_only {
        thesis_rows(&scene, &a, &configs, &mut progress, &mut rows)?;
    }
    for &n in &a.beds {
        bed_rows(n, a.bed_steps, &configs, &mut rows)?;
    }
    progress.finish();
    let yang = if a.beds_only {
        None
    } else {
        Some(bench_yang_power(5.0, 40_000.0, 40.0, 20).context("timing Yang's method")?)
    };
    let report = BenchReport {
        rows,
        yang_power_5s_40khz_ms: yang.as_ref().map(|y| y.fresh_median_s * 1e3),
        yang_power_5s_40khz_reused_plan_ms: yang.as_ref().map(|y| y.reused_median_s * 1e3),
        peak_memory_mib: peak_memory_mib(),
        cores,
    };
    if let Some(path) = &a.out {
        write_atomic(path, |w| {
            use std::io::Write;
            writeln!(
                w,
                "case [],threads [],particles [],steps [],wall [s],particle_steps_per_s [1/s],cpu [s],particle_steps_per_cpu_s [1/s]"
            )?;
            for r in &report.rows {
                writeln!(
                    w,
                    "{},{},{},{},{},{},{},{}",
                    r.case,
                    r.threads,
                    r.particles,
                    r.steps,
                    r.wall_s,
                    r.particle_steps_per_s,
                    r.cpu_s,
                    r.particle_steps_per_cpu_s
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
            "thesis scene at dt {:.1e} s and lattice beds of 2 mm spheres; {} cores",
            scene.drive_dt_s(40.0, 20.0),
            cores
        );
        for r in &report.rows {
            println!(
                "  {:48} {:6} particles {} thread{:1} {:6.2} M particle-steps/s ({:6.2} M per CPU s; {} steps, {:.2} s)",
                r.case,
                r.particles,
                r.threads,
                if r.threads == 1 { " " } else { "s" },
                r.particle_steps_per_s / 1e6,
                r.particle_steps_per_cpu_s / 1e6,
                r.steps,
                r.wall_s
            );
        }
        if let Some(y) = &yang {
            println!(
                "  Yang's method on a 5 s, 40 kHz two-channel trace: {:.2} ms ({:.2} ms with the FFT plan reused)",
                y.fresh_median_s * 1e3,
                y.reused_median_s * 1e3
            );
        }
        if let Some(m) = report.peak_memory_mib {
            println!("  peak memory {m:.1} MiB");
        }
    }
    Ok(())
}

/// The thesis scene: pour and settle on one thread, then the drive at
/// 40 Hz, Γ 20 on each thread count, with the scene's friction and without.
fn thesis_rows(
    scene: &Scene,
    a: &BenchArgs,
    configs: &[usize],
    progress: &mut ProgressLine,
    rows: &mut Vec<BenchRow>,
) -> Result<()> {
    let one = single_pool(1)?;
    let clock = Clock::start();
    let bed = one
        .install(|| settle_bed(scene, &mut |p| progress.update(p)))
        .context("settling the thesis bed")?;
    let n = bed.world.particles.len();
    rows.push(BenchRow::new(
        "thesis: pour and settle (dense bed)".into(),
        1,
        n,
        bed.settle_steps,
        clock,
    ));
    let mut frictionless = scene.clone();
    frictionless.contact.particle_particle.friction = 0.0;
    frictionless.contact.particle_wall.friction = 0.0;
    for (case, scene) in [
        ("thesis: drive 40 Hz Gamma 20", scene),
        ("thesis frictionless: drive 40 Hz Gamma 20", &frictionless),
    ] {
        for &threads in configs {
            let pool = single_pool(threads)?;
            let mut world: World = prepare_drive(&bed, scene, scene.drive_dt_s(40.0, 20.0))?;
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
            let clock = Clock::start();
            let out = pool
                .install(|| {
                    run_drive(&mut world, &plan, &mut drive, &mut NoObserver, &mut |p| {
                        progress.update(p)
                    })
                })
                .context("driving the thesis bed")?;
            rows.push(BenchRow::new(case.into(), threads, n, out.steps, clock));
        }
    }
    Ok(())
}

/// A lattice bed of `n` spheres: `steps` steps on each thread count, after
/// 20 steps that let the lists and buffers grow.
fn bed_rows(n: usize, steps: u32, configs: &[usize], rows: &mut Vec<BenchRow>) -> Result<()> {
    for &threads in configs {
        let pool = single_pool(threads)?;
        let row = pool.install(|| -> Result<BenchRow> {
            let mut world = lattice_bed(n, 0.52, 1).context("building the lattice bed")?;
            for _ in 0..20 {
                world.step(0.0)?;
            }
            let clock = Clock::start();
            for _ in 0..steps {
                world.step(0.0)?;
            }
            Ok(BenchRow::new(
                "lattice bed, mu 0.52: one step".into(),
                threads,
                n,
                u64::from(steps),
                clock,
            ))
        })?;
        rows.push(row);
    }
    Ok(())
}

fn single_pool(threads: usize) -> Result<rayon::ThreadPool> {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| anyhow::anyhow!("cannot start {threads} threads: {e}"))
}

/// CPU seconds (user + system) this process used so far, from /proc on
/// Linux (clock ticks of 10 ms); zero elsewhere.
fn process_cpu_s() -> f64 {
    let Ok(stat) = std::fs::read_to_string("/proc/self/stat") else {
        return 0.0;
    };
    // Fields after the command name (which may hold spaces) in parentheses.
    let rest = stat.rsplit_once(')').map_or("", |(_, r)| r);
    let f: Vec<&str> = rest.split_whitespace().collect();
    let ticks = |k: usize| f.get(k).and_then(|x| x.parse::<f64>().ok()).unwrap_or(0.0);
    // utime and stime: fields 14 and 15 of the stat line, 11 and 12 after the name.
    (ticks(11) + ticks(12)) / 100.0
}

/// Peak resident memory of this process (MiB), from /proc on Linux.
fn peak_memory_mib() -> Option<f64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kib: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib / 1024.0)
}
