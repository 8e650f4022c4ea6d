//! `vlab bench`: how fast the lab runs. Reports particle-steps per second
//! (particles × time steps / wall seconds of the stepping loop) on the thesis
//! scene, for pouring/settling (a dense, quasi-static bed) and for the drive at
//! 40 Hz, Γ 20, with one thread and with all threads, and the same drive
//! frictionless (μ = 0: no tangential force, no rotation); steps of lattice
//! beds of many spheres (`--beds`, see `vlab::dem::testbed`) and of poured
//! beds (`--poured`) on one thread and on all; the time to analyse a 5 s, 40 kHz two-channel trace with Yang's
//! method; and the peak memory. With `--lammps`, LAMMPS' `lmp` and vlab
//! drive the same settled thesis bed on one core each, in turns (see
//! [`lammps`]).
//!
//! A virtual machine shares its cores with other work, so one timing is a
//! sample of the load as much as of the code. Every configuration is timed
//! `--repeats` times, the thread counts taking turns, and reported by its
//! median and its fastest run; the speed-ups (all threads over one,
//! frictionless over the thesis contacts) are given as the ratio of the
//! fastest runs (the least disturbed) and as the median of the paired
//! ratios. Each row also gives the rate per CPU second the process used
//! (user + system), which falls much less with the load than the wall rate.
//!
//! What one bed on all cores can reach depends on the host as much as on
//! vlab: a virtual machine's cores may share a physical core, caches and
//! memory bandwidth. With more than one core, each bed is therefore also run
//! as independent 1-thread copies at once, one per core, work that shares
//! nothing: their rate over one copy's is the speed-up the host gives, and
//! the all-threads step is reported against it as well.
//!
//! A lattice bed is ordered in space: neighbours sit next to each other in
//! memory. The beds users drive are poured (`vlab::experiment::bed::settle`): their
//! spheres sit in memory in the order they were inserted, at random in space,
//! so a step reads memory all over the bed, and one core and two threads both
//! fare worse than on a lattice. `--poured` times such beds: `N` spheres of
//! 2 mm poured and settled in the thesis cylinder (40 mm across), made taller
//! than the thesis' 40 mm by `N / 5000` for more than 5 000 spheres (the same
//! fill), or `1mm`, the thesis cylinder filled with 44 740 spheres of 1 mm
//! (the thesis' fill), or `prolate`, the thesis' bed of 90 prolates of
//! aspect ratio 1.5 with 51 sub-spheres (Section 8.2), counted in
//! sub-sphere-steps. A bed comes from the bed cache when it holds it (see
//! `vlab::experiment::bed::cache`; `--no-cache` settles anew), and its settling
//! is reported apart from its steps.

use std::path::PathBuf;
use std::sync::Barrier;
use std::time::Instant;

use anyhow::{Context, Result};
use clap::Args;
use serde::Serialize;

use vlab::atomic_write::write_atomic;
use vlab::dem::testbed::lattice_bed;
use vlab::dem::{TRIAL_STEPS, World};
use vlab::experiment::bed::cache::BedSource;
use vlab::experiment::bed::settle::{SettledBed, prepare_drive, settle_bed};
use vlab::experiment::damper::{DrivePlan, NoObserver, run_drive};
use vlab::rig::SineMotion;
use vlab::scene::DriveLength;
use vlab::scene::Scene;
use vlab::signals::bench_yang_power;

use super::cache_cmd::NoCacheArg;
use super::progress::ProgressLine;

mod lammps;

#[derive(Debug, Clone, Args)]
pub struct BenchArgs {
    /// Drive cycles timed per run of the thesis scene (40 Hz: 20 500 steps each).
    #[arg(long, default_value = "2")]
    cycles: u32,
    /// Times each configuration is run (thread counts taking turns); rows give
    /// the median and the fastest run.
    #[arg(long, default_value = "3", value_parser = clap::value_parser!(u32).range(1..=100))]
    repeats: u32,
    /// Also write the figures to this CSV file.
    #[arg(long, value_name = "FILE")]
    out: Option<PathBuf>,
    /// Print the figures as JSON.
    #[arg(long)]
    json: bool,
    /// Lattice beds to time, by number of spheres, comma-separated ("none": no beds).
    #[arg(long, default_value = "5000,20000", value_parser = parse_beds)]
    beds: BedSizes,
    /// Poured beds to time, comma-separated: a number N of 2 mm spheres poured
    /// in the thesis cylinder (taller by N/5000 above 5 000 spheres), or "1mm"
    /// for its 44 740 spheres of 1 mm, or "prolate" for the thesis' 90
    /// prolates of aspect ratio 1.5 with 51 sub-spheres each (rates count
    /// sub-spheres; timed against a poured bed of as many spheres when that
    /// is asked too, e.g. `--poured 4590,prolate`); "none": no poured beds.
    /// Each is settled once, or read from the bed cache.
    #[arg(long, default_value = "none", value_parser = parse_poured)]
    poured: PouredBeds,
    /// Steps timed per run of a lattice or poured bed.
    #[arg(long, default_value = "300")]
    bed_steps: u32,
    /// Leave out the thesis scene (and Yang's method): time the beds only,
    /// e.g. to read one bed's peak memory (with --no-copies).
    #[arg(long)]
    beds_only: bool,
    /// Leave out the independent 1-thread copies of each bed (the host's
    /// reference), which hold one bed per core in memory at once.
    #[arg(long)]
    no_copies: bool,
    /// Also time LAMMPS against vlab per core on the settled thesis bed: the
    /// deck `vlab export lammps --freq 40 --gamma 20` writes, run by `lmp`
    /// (one process, one thread), and vlab's same drive on one thread, in
    /// turns --repeats times. Needs `lmp` on the PATH (Debian package lammps).
    #[arg(long)]
    lammps: bool,
    /// Drive cycles of each run of the LAMMPS comparison (at 40 Hz, 20 500
    /// steps each; at least 3, the deck's fewest).
    #[arg(long, default_value = "3", value_parser = clap::value_parser!(u32).range(i64::from(vlab::export::lammps_deck::MIN_EXPORT_CYCLES)..=1000))]
    lammps_cycles: u32,
    #[command(flatten)]
    cache: NoCacheArg,
}

/// The lattice beds asked for (sphere counts).
#[derive(Debug, Clone)]
pub struct BedSizes(Vec<usize>);

/// `--beds`: sphere counts separated by commas, each at least 2; "none" or
/// nothing for no beds.
fn parse_beds(s: &str) -> Result<BedSizes, String> {
    let s = s.trim();
    if s.is_empty() || s.eq_ignore_ascii_case("none") {
        return Ok(BedSizes(Vec::new()));
    }
    s.split(',')
        .map(|x| match x.trim().parse::<usize>() {
            Ok(n) if n >= 2 => Ok(n),
            _ => Err(format!(
                "'{x}' is not a bed size: a number of spheres of at least 2 (or \"none\")"
            )),
        })
        .collect::<Result<Vec<_>, _>>()
        .map(BedSizes)
}

/// Spheres of the thesis' 1 mm bed: its fill (0.466) in its cylinder.
const ONE_MM_SPHERES: usize = 44_740;
/// Spheres of 2 mm that fill the thesis cylinder's 40 mm length; a poured
/// bed of more is poured in a cylinder taller in proportion.
const POURED_PER_THESIS_LENGTH: usize = 5000;

/// The poured beds asked for.
#[derive(Debug, Clone)]
pub struct PouredBeds(Vec<PouredBed>);

/// One poured bed: spheres and their diameter, or (`prolate`) the thesis'
/// bed of prolates: 90 of aspect ratio 1.5 and 51 sub-spheres (Section 8.2),
/// `spheres` their sub-spheres.
#[derive(Debug, Clone, Copy, PartialEq)]
struct PouredBed {
    spheres: usize,
    diameter_m: f64,
    prolate: bool,
}

/// The thesis' prolate bed (Section 8.2): bodies, their volume-equivalent
/// diameter, aspect ratio and sub-spheres.
const PROLATE_BED: (usize, f64, f64, usize) = (90, 0.0076, 1.5, 51);

impl PouredBed {
    /// The thesis scene holding this bed, settled for at most 0.1 s once
    /// closed: 2 mm spheres in a cylinder of the thesis' diameter and of its
    /// length or taller, so that up to [`POURED_PER_THESIS_LENGTH`] spheres
    /// fill it to 0.42 and more fill it to the same; the 1 mm bed in the
    /// thesis cylinder itself.
    fn scene(&self) -> Result<Scene> {
        if self.prolate {
            let (count, d, alpha, subs) = PROLATE_BED;
            let text = format!(
                "name = \"prolates\"\n[particles]\ncount = {count}\nshape = \"prolate\"\n\
                 aspect_ratio = {alpha}\nsub_spheres = {subs}\nequivalent_diameter_m = {d}\n\
                 [simulation]\nsettle_s = 0.1\n"
            );
            return Scene::merge_over_preset(&text, "prolate bed")
                .context("building the prolate bed's scene");
        }
        let thesis = Scene::thesis();
        let length_m = match self.diameter_m < 0.002 {
            true => thesis.enclosure.inner_length_m,
            false => {
                thesis.enclosure.inner_length_m
                    * (self.spheres as f64 / POURED_PER_THESIS_LENGTH as f64).max(1.0)
            }
        };
        let text = format!(
            "name = \"poured\"\n[particles]\ncount = {}\ndiameter_m = {}\n\
             [enclosure]\ninner_length_m = {}\n[simulation]\nsettle_s = 0.1\n",
            self.spheres, self.diameter_m, length_m
        );
        Scene::merge_over_preset(&text, "poured bed").context("building the poured bed's scene")
    }
}

/// `--poured`: sphere counts (of 2 mm spheres, each at least 2) or "1mm",
/// separated by commas; "none" or nothing for no poured beds.
fn parse_poured(s: &str) -> Result<PouredBeds, String> {
    let s = s.trim();
    if s.is_empty() || s.eq_ignore_ascii_case("none") {
        return Ok(PouredBeds(Vec::new()));
    }
    s.split(',')
        .map(|x| match x.trim() {
            t if t.eq_ignore_ascii_case("1mm") => Ok(PouredBed {
                spheres: ONE_MM_SPHERES,
                diameter_m: 0.001,
                prolate: false,
            }),
            t if t.eq_ignore_ascii_case("prolate") => Ok(PouredBed {
                spheres: PROLATE_BED.0 * PROLATE_BED.3,
                diameter_m: PROLATE_BED.1,
                prolate: true,
            }),
            t => match t.parse::<usize>() {
                Ok(n) if n >= 2 => Ok(PouredBed {
                    spheres: n,
                    diameter_m: 0.002,
                    prolate: false,
                }),
                _ => Err(format!(
                    "'{x}' is not a poured bed: a number of 2 mm spheres of at least 2, \
                     \"1mm\", \"prolate\" (or \"none\")"
                )),
            },
        })
        .collect::<Result<Vec<_>, _>>()
        .map(PouredBeds)
}

/// One configuration (case, thread count) over its repeated runs.
#[derive(Debug, Serialize)]
struct BenchRow {
    case: String,
    /// How the bed's spheres sit: "lattice" (ordered in space, neighbours
    /// next to each other in memory) or "poured" (in pour order, at random in
    /// memory), as every bed of a scene is.
    bed: &'static str,
    threads: usize,
    /// Whether the step ran on all the threads (a small bed stays on one core
    /// whatever the pool: see `vlab::dem::AUTO_PARALLEL_MIN_PAIRS`).
    split_across_threads: bool,
    /// Independent copies of the work run at once, each on its own thread
    /// (1 but for the host reference; see [`independent_copies`]).
    copies: usize,
    particles: usize,
    /// Steps timed per run.
    steps: u64,
    runs: usize,
    /// Median and fastest wall time of a run (s).
    wall_s: f64,
    fastest_wall_s: f64,
    /// Particle-steps per wall second (of all copies): median run and
    /// fastest run.
    particle_steps_per_s: f64,
    fastest_particle_steps_per_s: f64,
    /// CPU seconds (user + system) of the median run.
    cpu_s: f64,
    /// Particle-steps per CPU second, median over the runs whose CPU time
    /// was measurable (the clock counts in 10 ms ticks); none if no run's was.
    particle_steps_per_cpu_s: Option<f64>,
    /// Wall time of each run (s), in the order they ran.
    run_wall_s: Vec<f64>,
    /// Particle-steps of each run (all copies).
    #[serde(skip)]
    work: f64,
    /// Of a bed's steps: pairs in the neighbour list, and pairs in contact,
    /// per particle, at the end of the last run (what a step's cost grows
    /// with besides the particles).
    listed_pairs_per_particle: Option<f64>,
    touching_pairs_per_particle: Option<f64>,
}

/// One timed run: wall and CPU seconds.
#[derive(Debug, Clone, Copy)]
struct Run {
    wall_s: f64,
    cpu_s: f64,
}

impl BenchRow {
    fn new(
        case: &str,
        threads: usize,
        split: bool,
        particles: usize,
        steps: u64,
        runs: &[Run],
    ) -> Self {
        Self::copies(case, threads, split, 1, particles, steps, runs)
    }

    /// The same row, of a bed that sits as `bed` says, with its pairs
    /// (listed, touching) per particle when known.
    fn of_bed(self, bed: &'static str, pairs: Option<(f64, f64)>) -> Self {
        BenchRow {
            bed,
            listed_pairs_per_particle: pairs.map(|p| p.0),
            touching_pairs_per_particle: pairs.map(|p| p.1),
            ..self
        }
    }

    /// A row of `copies` independent runs of the same work at once.
    fn copies(
        case: &str,
        threads: usize,
        split: bool,
        copies: usize,
        particles: usize,
        steps: u64,
        runs: &[Run],
    ) -> Self {
        let work = (copies as u64 * particles as u64 * steps) as f64;
        let walls: Vec<f64> = runs.iter().map(|r| r.wall_s).collect();
        let cpu_rates: Vec<f64> = runs
            .iter()
            .filter(|r| r.cpu_s > 0.0)
            .map(|r| work / r.cpu_s)
            .collect();
        let wall_s = median(&walls);
        let fastest_wall_s = walls.iter().copied().fold(f64::INFINITY, f64::min);
        let cpus: Vec<f64> = runs.iter().map(|r| r.cpu_s).collect();
        BenchRow {
            case: case.into(),
            bed: POURED,
            threads,
            split_across_threads: split,
            copies,
            particles,
            steps,
            runs: runs.len(),
            wall_s,
            fastest_wall_s,
            particle_steps_per_s: work / wall_s,
            fastest_particle_steps_per_s: work / fastest_wall_s,
            cpu_s: median(&cpus),
            particle_steps_per_cpu_s: (!cpu_rates.is_empty()).then(|| median(&cpu_rates)),
            run_wall_s: walls,
            work,
            listed_pairs_per_particle: None,
            touching_pairs_per_particle: None,
        }
    }

    /// Particle-steps per wall second of each run.
    fn run_rates(&self) -> impl Iterator<Item = f64> + '_ {
        self.run_wall_s.iter().map(|w| self.work / w)
    }
}

/// How much faster one configuration ran than another, in particle-steps
/// per second.
#[derive(Debug, Serialize)]
struct Speedup {
    what: String,
    particles: usize,
    /// Rate of the other's fastest run over the base's fastest.
    fastest: f64,
    /// Median over the repeats of the paired ratios (run k against run k).
    median_paired: f64,
}

impl Speedup {
    fn between(what: String, base: &BenchRow, other: &BenchRow) -> Self {
        let paired: Vec<f64> = base
            .run_rates()
            .zip(other.run_rates())
            .map(|(b, o)| o / b)
            .collect();
        Speedup {
            what,
            particles: base.particles,
            fastest: other.fastest_particle_steps_per_s / base.fastest_particle_steps_per_s,
            median_paired: median(&paired),
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

    fn stop(&self) -> Run {
        Run {
            wall_s: self.wall.elapsed().as_secs_f64(),
            cpu_s: process_cpu_s() - self.cpu_s,
        }
    }
}

/// How a poured bed was made ready: settled here, or read from the cache.
#[derive(Debug, Serialize)]
struct PouredReport {
    particles: usize,
    /// Bodies the particles are sub-spheres of (the prolate bed), or none.
    #[serde(skip_serializing_if = "Option::is_none")]
    bodies: Option<usize>,
    diameter_m: f64,
    /// Inner length of the cylinder it was poured in (m); 40 mm across.
    inner_length_m: f64,
    /// True when the bed was read from the bed cache (settled by an earlier run).
    from_cache: bool,
    /// Steps and simulated time of its settling (of the run that settled it).
    settle_steps: u64,
    settle_time_s: f64,
    /// Wall time to settle it here (s), threads used; none when it was read.
    settle_wall_s: Option<f64>,
    settle_threads: usize,
    /// Particle-steps per wall second of its settling; none when it was read.
    settle_particle_steps_per_s: Option<f64>,
    /// Wall time to read it from the cache (s); none when it was settled.
    read_wall_s: Option<f64>,
    packing_fraction: f64,
}

#[derive(Debug, Serialize)]
struct BenchReport {
    rows: Vec<BenchRow>,
    /// The poured beds timed, and how each was made ready.
    poured_beds: Vec<PouredReport>,
    speedups: Vec<Speedup>,
    /// Yang's method on a 5 s, 40 kHz, two-channel trace, planning the FFT (ms).
    yang_power_5s_40khz_ms: Option<f64>,
    /// The same with the FFT plan reused (ms).
    yang_power_5s_40khz_reused_plan_ms: Option<f64>,
    peak_memory_mib: Option<f64>,
    cores: usize,
    /// Load average over the last minute when the bench ended (Linux).
    load_average_1min: Option<f64>,
    /// Which loops the step ran: "x86-64-v3" or "baseline"
    /// (`vlab::dem::isa`; `VLAB_ISA=baseline` asks for the baseline).
    step_loops: &'static str,
    /// vlab against LAMMPS per core (`--lammps`); none without.
    lammps: Option<lammps::LammpsComparison>,
}

pub fn run(a: BenchArgs, quiet: bool) -> Result<()> {
    let cores = std::thread::available_parallelism()
        .map(|n| n.get())
        .unwrap_or(1);
    if a.lammps {
        // Before anything is timed: a missing lmp fails at once.
        lammps::require_lmp()?;
    }
    let scene = Scene::thesis();
    let mut progress = ProgressLine::new("bench", quiet);
    let mut rows = Vec::new();
    let configs = if cores > 1 { vec![1, cores] } else { vec![1] };
    let thesis_bed = match a.beds_only {
        false => Some(thesis_rows(&scene, &a, &configs, &mut progress, &mut rows)?),
        true => None,
    };
    let mut lammps_speedups = Vec::new();
    let lammps = match a.lammps {
        true => Some(lammps_part(
            &a,
            &scene,
            thesis_bed,
            &mut progress,
            &mut rows,
            &mut lammps_speedups,
        )?),
        false => None,
    };
    for &n in &a.beds.0 {
        bed_rows(&Bed::Lattice(n), &a, &configs, &mut rows)?;
    }
    let poured_beds = poured_rows(&a, &configs, &mut progress, &mut rows)?;
    progress.finish();
    let yang = (!a.beds_only)
        .then(|| bench_yang_power(5.0, 40_000.0, 40.0, 20).context("timing Yang's method"))
        .transpose()?;
    let mut all_speedups = speedups(&rows);
    all_speedups.extend(lammps_speedups);
    let report = BenchReport {
        speedups: all_speedups,
        rows,
        poured_beds,
        yang_power_5s_40khz_ms: yang.as_ref().map(|y| y.fresh_median_s * 1e3),
        yang_power_5s_40khz_reused_plan_ms: yang.as_ref().map(|y| y.reused_median_s * 1e3),
        peak_memory_mib: peak_memory_mib(),
        cores,
        load_average_1min: load_average(),
        step_loops: step_loops(),
        lammps,
    };
    if let Some(path) = &a.out {
        write_csv(path, &report).with_context(|| format!("writing {}", path.display()))?;
    }
    if a.json {
        println!("{}", serde_json::to_string_pretty(&report)?);
    } else {
        print_report(&report, &scene, a.repeats);
    }
    Ok(())
}

/// The LAMMPS rows: the thesis bed (this run's, else from the cache or
/// settled) driven by vlab and by lmp alike.
fn lammps_part(
    a: &BenchArgs,
    scene: &Scene,
    thesis_bed: Option<SettledBed>,
    progress: &mut ProgressLine,
    rows: &mut Vec<BenchRow>,
    speedups: &mut Vec<Speedup>,
) -> Result<lammps::LammpsComparison> {
    let bed = match thesis_bed {
        Some(bed) => bed,
        // Without the thesis rows: the bed from the cache, else settled.
        None => a
            .cache
            .source(&mut |n| progress.warn(n))
            .settle(scene, &mut |p| progress.update(p))
            .context("settling the thesis bed")?,
    };
    lammps::lammps_rows(
        scene,
        &bed,
        a.lammps_cycles,
        a.repeats,
        progress,
        rows,
        speedups,
    )
}

/// The rows of each `--poured` bed (settled or from the cache), and how
/// each was made ready.
fn poured_rows(
    a: &BenchArgs,
    configs: &[usize],
    progress: &mut ProgressLine,
    rows: &mut Vec<BenchRow>,
) -> Result<Vec<PouredReport>> {
    let mut poured_beds = Vec::new();
    if a.poured.0.is_empty() {
        return Ok(poured_beds);
    }
    let source = a.cache.source(&mut |n| progress.warn(n));
    for p in &a.poured.0 {
        let (world, made) = poured_bed(p, &source, configs, progress)?;
        poured_beds.push(made);
        let bed = match p.prolate {
            true => Bed::Prolates(world),
            false => Bed::Poured(world),
        };
        bed_rows(&bed, a, configs, rows)?;
    }
    Ok(poured_beds)
}

fn write_csv(path: &std::path::Path, report: &BenchReport) -> Result<()> {
    write_atomic(path, |w| {
        let mut out = csv::Writer::from_writer(w);
        out.write_record([
            "case []",
            "bed []",
            "threads []",
            "split_across_threads []",
            "copies []",
            "particles []",
            "steps []",
            "runs []",
            "wall [s]",
            "fastest_wall [s]",
            "particle_steps_per_s [1/s]",
            "fastest_particle_steps_per_s [1/s]",
            "cpu [s]",
            "particle_steps_per_cpu_s [1/s]",
            "listed_pairs_per_particle []",
            "touching_pairs_per_particle []",
        ])?;
        for r in &report.rows {
            out.write_record([
                r.case.clone(),
                r.bed.to_string(),
                r.threads.to_string(),
                r.split_across_threads.to_string(),
                r.copies.to_string(),
                r.particles.to_string(),
                r.steps.to_string(),
                r.runs.to_string(),
                r.wall_s.to_string(),
                r.fastest_wall_s.to_string(),
                r.particle_steps_per_s.to_string(),
                r.fastest_particle_steps_per_s.to_string(),
                r.cpu_s.to_string(),
                r.particle_steps_per_cpu_s
                    .map_or(String::new(), |x| x.to_string()),
                r.listed_pairs_per_particle
                    .map_or(String::new(), |x| x.to_string()),
                r.touching_pairs_per_particle
                    .map_or(String::new(), |x| x.to_string()),
            ])?;
        }
        out.flush()?;
        Ok(())
    })?;
    Ok(())
}

fn print_report(report: &BenchReport, scene: &Scene, repeats: u32) {
    println!(
        "thesis scene at dt {:.1e} s, lattice and poured beds; {} cores{}, the step's {} loops; each row: median and fastest of {} runs",
        scene
            .drive(40.0, 20.0)
            .map_or(f64::NAN, |d| scene.drive_dt_s(&d)),
        report.cores,
        report
            .load_average_1min
            .map_or(String::new(), |l| format!(", load average {l:.2}")),
        report.step_loops,
        repeats
    );
    report.poured_beds.iter().for_each(print_poured);
    report.rows.iter().for_each(print_row);
    for s in &report.speedups {
        println!(
            "  speed-up, {} ({} particles): x{:.2} fastest against fastest, x{:.2} median of paired runs",
            s.what, s.particles, s.fastest, s.median_paired
        );
    }
    if let Some(c) = &report.lammps {
        lammps::print_comparison(c);
    }
    if let Some(y) = report.yang_power_5s_40khz_ms {
        println!(
            "  Yang's method on a 5 s, 40 kHz two-channel trace: {:.2} ms ({:.2} ms with the FFT plan reused)",
            y,
            report
                .yang_power_5s_40khz_reused_plan_ms
                .unwrap_or(f64::NAN)
        );
    }
    if let Some(m) = report.peak_memory_mib {
        println!("  peak memory {m:.1} MiB");
    }
}

/// How a poured bed was made: what it holds, its packing, and whether it
/// was settled here or read from the cache.
fn print_poured(p: &PouredReport) {
    let made = match (p.settle_wall_s, p.read_wall_s) {
        (Some(w), _) => format!(
            "settled here in {w:.1} s on {} thread(s), {:.2} M particle-steps/s",
            p.settle_threads,
            p.settle_particle_steps_per_s.unwrap_or(f64::NAN) / 1e6
        ),
        (None, Some(r)) => format!("read from the bed cache in {r:.2} s"),
        (None, None) => String::new(),
    };
    let what = match p.bodies {
        Some(n) => format!(
            "{n} prolates of {} sub-spheres (volume of a {} mm sphere each)",
            p.particles / n.max(1),
            p.diameter_m * 1e3
        ),
        None => format!("{} spheres of {} mm", p.particles, p.diameter_m * 1e3),
    };
    println!(
        "  poured bed: {what} in a cylinder 40 mm across, {} mm long, packing {:.3} ({} settling steps, {:.3} s simulated); {}",
        p.inner_length_m * 1e3,
        p.packing_fraction,
        p.settle_steps,
        p.settle_time_s,
        made
    );
}

/// A row: its rate, fastest rate, CPU rate and pairs a particle.
fn print_row(r: &BenchRow) {
    let how = match (r.threads, r.split_across_threads) {
        _ if r.copies > 1 => format!("{} x 1 thread", r.copies),
        (1, _) => "1 thread ".to_string(),
        (t, true) => format!("{t} threads"),
        (t, false) => format!("{t} threads (step stays on one: few pairs)"),
    };
    let per_cpu = r
        .particle_steps_per_cpu_s
        .map_or("CPU time below the clock's 10 ms".into(), |x| {
            format!("{:6.2} M per CPU s", x / 1e6)
        });
    println!(
        "  {:44} {:7} {:6} particles {:10} {:6.2} M particle-steps/s, fastest {:6.2} M ({}; {} steps, {:.2} s)",
        r.case,
        r.bed,
        r.particles,
        how,
        r.particle_steps_per_s / 1e6,
        r.fastest_particle_steps_per_s / 1e6,
        per_cpu,
        r.steps,
        r.wall_s
    );
    if let (Some(listed), Some(touching)) =
        (r.listed_pairs_per_particle, r.touching_pairs_per_particle)
    {
        println!(
            "  {:44} pairs a particle: {listed:.2} listed, {touching:.2} touching",
            ""
        );
    }
}

/// All threads against one for every case that ran both, and the
/// frictionless thesis drive against the thesis drive on one thread.
fn speedups(rows: &[BenchRow]) -> Vec<Speedup> {
    let mut out = Vec::new();
    for base in rows.iter().filter(|r| r.threads == 1) {
        for other in rows.iter().filter(|r| {
            r.threads > 1
                && r.copies == 1
                && r.case == base.case
                && r.particles == base.particles
                && r.split_across_threads
        }) {
            out.push(Speedup::between(
                format!("{} threads over 1, {}", other.threads, base.case),
                base,
                other,
            ));
        }
        host_speedups(rows, base, &mut out);
    }
    // The prolate bed against spheres of as many (sub-)spheres, 1 thread:
    // what a body costs beyond its spheres.
    let one_bed = |case: &str, n: usize| {
        rows.iter()
            .find(|r| r.threads == 1 && r.copies == 1 && r.case == case && r.particles == n)
    };
    for prolates in rows
        .iter()
        .filter(|r| r.threads == 1 && r.copies == 1 && r.case == Bed::PROLATES.steps)
    {
        if let Some(spheres) = one_bed(Bed::POURED.steps, prolates.particles) {
            out.push(Speedup::between(
                format!(
                    "prolates over a poured bed of as many spheres ({}), 1 thread",
                    prolates.particles
                ),
                spheres,
                prolates,
            ));
        }
    }
    let one = |case: &str| rows.iter().find(|r| r.threads == 1 && r.case == case);
    if let (Some(base), Some(other)) = (one(THESIS_DRIVE), one(FRICTIONLESS_DRIVE)) {
        out.push(Speedup::between(
            "frictionless over the thesis contacts, 1 thread".into(),
            base,
            other,
        ));
    }
    out
}

/// For a bed's 1-thread row `base`: what the host gives copies that share
/// nothing over it, and one bed split across threads against those copies.
fn host_speedups(rows: &[BenchRow], base: &BenchRow, out: &mut Vec<Speedup>) {
    let Some(kind) = [Bed::LATTICE, Bed::POURED, Bed::PROLATES]
        .into_iter()
        .find(|k| k.steps == base.case)
    else {
        return;
    };
    for host in rows
        .iter()
        .filter(|r| r.copies > 1 && r.particles == base.particles && r.case == kind.copies)
    {
        out.push(Speedup::between(
            format!(
                "what the host gives work that shares nothing: {} 1-thread copies at once over 1, {} bed",
                host.copies, base.bed
            ),
            base,
            host,
        ));
        for split in rows.iter().filter(|r| {
            r.case == kind.steps
                && r.particles == base.particles
                && r.threads == host.copies
                && r.split_across_threads
        }) {
            out.push(Speedup::between(
                format!(
                    "{} threads on one bed against {} copies at once (1 = all the host gives), {} bed",
                    split.threads, host.copies, base.bed
                ),
                host,
                split,
            ));
        }
    }
}

/// The case names of a kind of bed's rows.
struct BedCases {
    steps: &'static str,
    copies: &'static str,
}
const THESIS_DRIVE: &str = "thesis: drive 40 Hz Gamma 20";
const FRICTIONLESS_DRIVE: &str = "thesis frictionless: drive 40 Hz Gamma 20";

/// The thesis scene: pour and settle on one thread (once), then the drive at
/// 40 Hz, Γ 20 on each thread count, with the scene's friction and without,
/// `--repeats` times from the same settled bed; the bed.
fn thesis_rows(
    scene: &Scene,
    a: &BenchArgs,
    configs: &[usize],
    progress: &mut ProgressLine,
    rows: &mut Vec<BenchRow>,
) -> Result<SettledBed> {
    let clock = Clock::start();
    let bed = settle_bed(scene, &mut |p| progress.update(p)).context("settling the thesis bed")?;
    let n = bed.world.particles.len();
    rows.push(BenchRow::new(
        "thesis: pour and settle (dense bed)",
        1,
        false,
        n,
        bed.settle_steps,
        &[clock.stop()],
    ));
    let mut frictionless = scene.clone();
    frictionless.contact.particle_particle.friction = 0.0;
    frictionless.contact.particle_wall.friction = 0.0;
    for (case, scene) in [(THESIS_DRIVE, scene), (FRICTIONLESS_DRIVE, &frictionless)] {
        let mut runs = vec![Vec::new(); configs.len()];
        let mut steps = 0;
        let mut split = vec![false; configs.len()];
        for _ in 0..a.repeats {
            for (k, &threads) in configs.iter().enumerate() {
                let (run, s, sp) = drive_once(&bed, scene, a.cycles, threads, progress)
                    .context("driving the thesis bed")?;
                runs[k].push(run);
                steps = s;
                split[k] = sp;
            }
        }
        for (k, &threads) in configs.iter().enumerate() {
            rows.push(BenchRow::new(case, threads, split[k], n, steps, &runs[k]));
        }
    }
    Ok(bed)
}

/// One timed drive of `cycles` at 40 Hz, Γ 20 from the settled bed on
/// `threads` threads: the run, its steps, and whether its steps ran on all
/// threads.
fn drive_once(
    bed: &SettledBed,
    scene: &Scene,
    cycles: u32,
    threads: usize,
    progress: &mut ProgressLine,
) -> Result<(Run, u64, bool)> {
    let drive = scene.drive(40.0, 20.0)?;
    let mut world: World = prepare_drive(bed, scene, scene.drive_dt_s(&drive))?;
    world.set_step_threads(threads);
    let plan = DrivePlan {
        drive,
        length: DriveLength::Fixed {
            cycles: cycles.max(1),
            steady_cycles: 1,
        },
    };
    let mut motion = SineMotion::new(&drive);
    let clock = Clock::start();
    let out = run_drive(&mut world, &plan, &mut motion, &mut NoObserver, &mut |p| {
        progress.update(p)
    })?;
    Ok((clock.stop(), out.steps, world.splits_across_threads()))
}

/// A bed the bench steps: a lattice of `n` spheres, built anew for every
/// run, or a poured bed, settled once and copied for every run.
enum Bed {
    Lattice(usize),
    Poured(Box<World>),
    /// The thesis' prolate bed, poured and settled (its sub-spheres are the
    /// particles the rates count).
    Prolates(Box<World>),
}

impl Bed {
    const LATTICE: BedCases = BedCases {
        steps: "lattice bed, mu 0.52: steps",
        copies: "lattice bed, mu 0.52: copies at once",
    };
    const POURED: BedCases = BedCases {
        steps: "poured bed, thesis contacts: steps",
        copies: "poured bed, thesis contacts: copies at once",
    };
    const PROLATES: BedCases = BedCases {
        steps: "prolate bed (90 x 51 sub-spheres), thesis contacts: steps",
        copies: "prolate bed (90 x 51 sub-spheres), thesis contacts: copies at once",
    };

    fn cases(&self) -> (&'static BedCases, &'static str) {
        match self {
            Bed::Lattice(_) => (&Self::LATTICE, LATTICE),
            Bed::Poured(_) => (&Self::POURED, POURED),
            Bed::Prolates(_) => (&Self::PROLATES, PROLATES),
        }
    }

    fn spheres(&self) -> usize {
        match self {
            Bed::Lattice(n) => *n,
            Bed::Poured(w) | Bed::Prolates(w) => w.particles.len(),
        }
    }

    /// A new copy of the bed after untimed steps that let its lists and
    /// buffers grow (20) and time the serial step against the parallel one
    /// (a whole trial, [`TRIAL_STEPS`]), so that the timed steps run the
    /// way vlab chose, as a long run does; its steps may use `threads`
    /// threads.
    fn warm(&self, threads: usize) -> Result<World> {
        let mut world = match self {
            Bed::Lattice(n) => lattice_bed(*n, 0.52, 1).context("building the lattice bed")?,
            Bed::Poured(w) | Bed::Prolates(w) => (**w).clone(),
        };
        world.set_step_threads(threads);
        world.retime_threads();
        for _ in 0..20 + TRIAL_STEPS {
            world.step(0.0)?;
        }
        Ok(world)
    }
}

/// The row's `bed` of a lattice bed.
const LATTICE: &str = "lattice";
/// The row's `bed` of a poured bed (the thesis scene's included).
const POURED: &str = "poured";
/// The row's `bed` of the prolate bed.
const PROLATES: &str = "prolates";

/// The poured bed `p`, from the cache or settled here on all the threads
/// (the settled bed does not depend on them), ready to step with the
/// thesis contacts at the time step of the drive at 40 Hz, Γ 20; and how it
/// was made ready.
fn poured_bed(
    p: &PouredBed,
    source: &BedSource,
    configs: &[usize],
    progress: &mut ProgressLine,
) -> Result<(Box<World>, PouredReport)> {
    let scene = p.scene()?;
    let threads = configs.last().copied().unwrap_or(1);
    let clock = Clock::start();
    let mut scene = scene;
    scene.simulation.step_threads = threads;
    let bed = source
        .settle(&scene, &mut |x| progress.update(x))
        .with_context(|| format!("settling the poured bed of {} spheres", p.spheres))?;
    let run = clock.stop();
    for w in &bed.warnings {
        progress.warn(&format!("warning: {w}"));
    }
    let drive = scene.drive(40.0, 20.0)?;
    let world = prepare_drive(&bed, &scene, scene.drive_dt_s(&drive))?;
    let work = bed.settle_steps as f64 * bed.world.particles.len() as f64;
    let bodies = bed.world.particles.clumps.len();
    let made = PouredReport {
        particles: bed.world.particles.len(),
        bodies: (bodies > 0).then_some(bodies),
        diameter_m: p.diameter_m,
        inner_length_m: scene.enclosure.inner_length_m,
        from_cache: bed.from_cache,
        settle_steps: bed.settle_steps,
        settle_time_s: bed.settle_time_s,
        settle_wall_s: (!bed.from_cache).then_some(run.wall_s),
        settle_threads: threads,
        settle_particle_steps_per_s: (!bed.from_cache).then(|| work / run.wall_s),
        read_wall_s: bed.from_cache.then_some(run.wall_s),
        packing_fraction: bed.packing_fraction,
    };
    Ok((Box::new(world), made))
}

/// A bed: `--bed-steps` steps on each thread count, `--repeats` times, each
/// run from a new copy after 20 steps that let the lists and buffers grow.
/// With more than one core, each repeat also runs as many independent
/// 1-thread copies at once as there are cores: what the host gives to work
/// that shares nothing, the ceiling of the speed-up of one bed over all
/// cores on a machine that shares its cores.
fn bed_rows(bed: &Bed, a: &BenchArgs, configs: &[usize], rows: &mut Vec<BenchRow>) -> Result<()> {
    let copies = match a.no_copies {
        true => 1,
        false => configs.last().copied().unwrap_or(1),
    };
    let n = bed.spheres();
    let (cases, kind) = bed.cases();
    let mut runs = vec![Vec::new(); configs.len()];
    let mut split = vec![false; configs.len()];
    let mut pairs = vec![None; configs.len()];
    let mut host = Vec::new();
    for _ in 0..a.repeats {
        for (k, &threads) in configs.iter().enumerate() {
            let (run, sp, pp) = bed_run(bed, a.bed_steps, threads)?;
            runs[k].push(run);
            split[k] = sp;
            pairs[k] = Some(pp);
        }
        if copies > 1 {
            host.push(independent_copies(bed, a.bed_steps, copies)?);
        }
    }
    for (k, &threads) in configs.iter().enumerate() {
        rows.push(
            BenchRow::new(
                cases.steps,
                threads,
                split[k],
                n,
                u64::from(a.bed_steps),
                &runs[k],
            )
            .of_bed(kind, pairs[k]),
        );
    }
    if !host.is_empty() {
        rows.push(
            BenchRow::copies(
                cases.copies,
                copies,
                false,
                copies,
                n,
                u64::from(a.bed_steps),
                &host,
            )
            .of_bed(kind, None),
        );
    }
    Ok(())
}

/// One timed run of `steps` steps of a new copy of `bed` on `threads`
/// threads: the run, whether its steps ran on all threads, and its pairs per
/// particle at the end (listed, touching).
fn bed_run(bed: &Bed, steps: u32, threads: usize) -> Result<(Run, bool, (f64, f64))> {
    let mut world = bed.warm(threads)?;
    let clock = Clock::start();
    for _ in 0..steps {
        world.step(0.0)?;
    }
    let run = clock.stop();
    let n = world.particles.len().max(1) as f64;
    let pairs = (
        world.listed_pairs() as f64 / n,
        world.contact_counts().0 as f64 / n,
    );
    Ok((run, world.splits_across_threads(), pairs))
}

/// `copies` copies of `bed` stepped at once, each on one thread: the wall time from the common start to the last one's end, and the
/// process' CPU time over it. The beds are built before any thread starts,
/// so that every thread reaches the start.
fn independent_copies(bed: &Bed, steps: u32, copies: usize) -> Result<Run> {
    let worlds = (0..copies)
        .map(|_| bed.warm(1))
        .collect::<Result<Vec<_>>>()?;
    let start = Barrier::new(copies + 1);
    std::thread::scope(|s| {
        let handles: Vec<_> = worlds
            .into_iter()
            .map(|mut world| {
                let start = &start;
                s.spawn(move || -> Result<()> {
                    start.wait();
                    for _ in 0..steps {
                        world.step(0.0)?;
                    }
                    Ok(())
                })
            })
            .collect();
        start.wait();
        let clock = Clock::start();
        for h in handles {
            h.join()
                .map_err(|_| anyhow::anyhow!("a bench thread panicked"))??;
        }
        Ok(clock.stop())
    })
}

/// CPU seconds (user + system) this process used so far, from /proc on
/// Linux (clock ticks of 10 ms); zero elsewhere.
fn process_cpu_s() -> f64 {
    // utime and stime: fields 14 and 15 of the stat line.
    proc_stat_cpu_s(14)
}

/// CPU seconds in the two clock-tick fields of `/proc/self/stat` from field
/// `first` on (numbered from 1, as `man proc` does; 10 ms ticks): 14 for
/// this process' own user and system time, 16 for its finished
/// children's. Zero where there is no /proc.
pub(crate) fn proc_stat_cpu_s(first: usize) -> f64 {
    let Ok(stat) = std::fs::read_to_string("/proc/self/stat") else {
        return 0.0;
    };
    // Fields after the command name (which may hold spaces) in parentheses:
    // the first of them is field 3.
    let rest = stat.rsplit_once(')').map_or("", |(_, r)| r);
    let f: Vec<&str> = rest.split_whitespace().collect();
    let ticks = |k: usize| {
        f.get(k - 3)
            .and_then(|x| x.parse::<f64>().ok())
            .unwrap_or(0.0)
    };
    (ticks(first) + ticks(first + 1)) / 100.0
}

/// Peak resident memory of this process (MiB), from /proc on Linux.
fn peak_memory_mib() -> Option<f64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kib: f64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib / 1024.0)
}

/// Which loops the step runs on this processor ([`vlab::dem::isa`]).
fn step_loops() -> &'static str {
    if vlab::dem::isa::wide() {
        "x86-64-v3"
    } else {
        "baseline"
    }
}

/// The load average over the last minute, from /proc on Linux.
fn load_average() -> Option<f64> {
    let s = std::fs::read_to_string("/proc/loadavg").ok()?;
    s.split_whitespace().next()?.parse().ok()
}

/// The median of timings (the mean of the middle two for an even count).
fn median(xs: &[f64]) -> f64 {
    let mut v = xs.to_vec();
    v.sort_by(f64::total_cmp);
    let n = v.len();
    match n {
        0 => f64::NAN,
        _ if n % 2 == 1 => v[n / 2],
        _ => 0.5 * (v[n / 2 - 1] + v[n / 2]),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `--poured prolate` is the thesis' prolate bed (90 bodies of 51
    /// sub-spheres, counted as 4 590), whose scene is a valid scene of
    /// prolates of aspect ratio 1.5 in the thesis cylinder; it mixes with
    /// sphere counts, and a word that is neither is refused naming it.
    #[test]
    fn the_prolate_bed_is_parsed_and_is_the_thesis_one() {
        let beds = parse_poured("4590, prolate").expect("parsed").0;
        assert_eq!(beds.len(), 2);
        assert!(!beds[0].prolate && beds[0].spheres == 4590);
        assert!(beds[1].prolate && beds[1].spheres == 90 * 51);
        let scene = beds[1].scene().expect("scene");
        assert_eq!(scene.particles.count, 90);
        assert_eq!(scene.particles.shape, vlab::scene::ShapeKind::Prolate);
        assert_eq!(scene.particles.aspect_ratio, Some(1.5));
        assert_eq!(scene.particles.diameter_m, 0.0076);
        let err = parse_poured("oblate").expect_err("refused");
        assert!(
            err.contains("'oblate'") && err.contains("\"prolate\""),
            "{err}"
        );
    }
}
