//! `vlab bench --lammps`: vlab against LAMMPS per core, in one run, on the
//! same settled thesis bed.
//!
//! The LAMMPS side is the deck `vlab export lammps --freq 40 --gamma 20
//! --cycles N --steady-cycles 2` writes ([`vlab::export::lammps_deck`]: the
//! same spheres, packing, contact law, enclosure, prescribed sine drive from
//! t = 0 and time step), run as `lmp -in in.damper` in a temporary folder,
//! one process (no `mpirun`) with `OMP_NUM_THREADS=1`. The vlab side is the
//! same drive (the prescribed sine of eq. 6.2 from the same settled bed, the
//! same cycles at the same time step) on a pool of one thread. The two take
//! turns, `--repeats` times, so that a change of the machine's load falls on
//! both; the ratio is the median of the paired runs' ratios.
//!
//! What each timing holds, said in the report as well:
//! - vlab: the stepping loop of the drive (the walls' force on the particles
//!   every step and the energy ledger every cycle), not the copy of the bed;
//!   no trace is written.
//! - `lmp`, whole process: its start-up, reading the deck and `packing.data`,
//!   the run, its record (`record.txt`, a row every 20 steps) and its
//!   thermo lines.
//! - `lmp`, LAMMPS' "Loop time" (from its log): the run alone, the record
//!   and thermo output included, the start-up and `read_data` not.
//!
//! The deck rounds its run up to whole record rows, so its steps may exceed
//! vlab's by fewer than 20; each side's rate is of its own steps.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::Instant;

use anyhow::{Context, Result, bail};
use serde::Serialize;

use vlab::experiment::bed::settle::SettledBed;
use vlab::export::lammps_deck::{
    DECK_FORM, DeckSummary, INPUT_FILE, LammpsExport, MIN_EXPORT_CYCLES, lammps_deck,
};
use vlab::scene::{Scene, SceneOverrides};

use super::{BenchRow, Run, Speedup, drive_once, proc_stat_cpu_s};
use crate::cli::progress::ProgressLine;

/// What `--lammps` needs, for its refusal.
pub const NEEDS_LMP: &str =
    "--lammps needs LAMMPS' `lmp` on the PATH (Debian package lammps: apt-get install lammps)";

/// The window the deck declares: its fewest (the run's length is what is
/// timed; the window only names the record's last cycles).
const STEADY_CYCLES: u32 = 2;

/// The LAMMPS log file, in the deck's folder.
const LOG_FILE: &str = "log.lammps";

/// Row case names.
pub const VLAB_CASE: &str = "vs LAMMPS: vlab, thesis drive 40 Hz Gamma 20";
pub const LMP_PROCESS_CASE: &str = "vs LAMMPS: lmp in.damper, whole process";
pub const LMP_LOOP_CASE: &str = "vs LAMMPS: lmp in.damper, its Loop time";

/// The comparison's account, in the bench report (`lammps`).
#[derive(Debug, Serialize)]
pub struct LammpsComparison {
    /// LAMMPS' version line from its log, e.g. "LAMMPS (29 Sep 2021 - Update 2)".
    pub lammps_version: String,
    /// The export the deck is: `vlab export lammps` with these arguments.
    pub deck: String,
    /// What that deck holds (its walls, reductions and record).
    pub deck_form: &'static str,
    pub particles: usize,
    pub cycles: u32,
    pub dt_s: f64,
    /// Steps of one run of each (the deck rounds up to whole record rows).
    pub vlab_steps: u64,
    pub lammps_steps: u64,
    pub runs: usize,
    /// What each timing holds.
    pub vlab_timed: &'static str,
    pub lammps_process_timed: &'static str,
    pub lammps_loop_timed: &'static str,
    /// Wall time of each run (s), in the order they ran (vlab first).
    pub vlab_wall_s: Vec<f64>,
    pub lammps_process_wall_s: Vec<f64>,
    pub lammps_loop_s: Vec<f64>,
    /// LAMMPS' own "% CPU use" of each run's loop.
    pub lammps_loop_cpu_use_percent: Vec<f64>,
    /// Particle-steps per wall second, median run.
    pub vlab_particle_steps_per_s: f64,
    pub lammps_process_particle_steps_per_s: f64,
    pub lammps_loop_particle_steps_per_s: f64,
    /// vlab's rate over LAMMPS', median of the paired runs' ratios: against
    /// the whole `lmp` process, and against its Loop time (the run alone,
    /// the lower ratio).
    pub vlab_over_lammps_process: f64,
    pub vlab_over_lammps_loop: f64,
}

/// Fails, naming the package, unless `lmp -h` runs.
pub fn require_lmp() -> Result<()> {
    let runs = Command::new("lmp")
        .arg("-h")
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|s| s.success());
    if !runs {
        bail!("{NEEDS_LMP}");
    }
    Ok(())
}

/// A folder removed when dropped.
struct TempDir(PathBuf);

impl TempDir {
    fn new() -> Result<Self> {
        let nanos = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map_or(0, |d| d.subsec_nanos());
        let path =
            std::env::temp_dir().join(format!("vlab-bench-lammps-{}-{nanos}", std::process::id()));
        std::fs::create_dir_all(&path).with_context(|| format!("creating {}", path.display()))?;
        Ok(TempDir(path))
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}

/// What one `lmp` run's log says: version, Loop time (s), steps, atoms and
/// the loop's CPU use (%).
#[derive(Debug, Clone, PartialEq)]
struct LammpsLog {
    version: String,
    loop_s: f64,
    steps: u64,
    atoms: usize,
    cpu_use_percent: f64,
}

/// Reads the first line ("LAMMPS (...)") and every run's "Loop time of T on
/// 1 procs for S steps with A atoms" and "P% CPU use ..." of a LAMMPS log:
/// the deck runs its first record row's steps apart from the rest, so the
/// loop is the sum of its runs (their CPU use weighted by their time).
fn parse_log(text: &str) -> Option<LammpsLog> {
    let version = text
        .lines()
        .find(|l| l.starts_with("LAMMPS ("))?
        .trim()
        .to_string();
    let mut loops = Vec::new();
    for loop_line in text.lines().filter(|l| l.starts_with("Loop time of ")) {
        let w: Vec<&str> = loop_line.split_whitespace().collect();
        // Loop time of T on P procs for S steps with A atoms
        let loop_s: f64 = w.get(3)?.parse().ok()?;
        let steps: u64 = w.get(8)?.parse().ok()?;
        let atoms: usize = w.get(11)?.parse().ok()?;
        loops.push((loop_s, steps, atoms));
    }
    let &(_, _, atoms) = loops.last()?;
    let cpu_use: Vec<f64> = text
        .lines()
        .filter(|l| l.contains("% CPU use with"))
        .map(|l| {
            l.split('%')
                .next()
                .and_then(|p| p.trim().parse().ok())
                .unwrap_or(f64::NAN)
        })
        .collect();
    let loop_s: f64 = loops.iter().map(|l| l.0).sum();
    let cpu_use_percent = if cpu_use.len() == loops.len() && loop_s > 0.0 {
        loops
            .iter()
            .zip(&cpu_use)
            .map(|(l, c)| l.0 * c)
            .sum::<f64>()
            / loop_s
    } else {
        f64::NAN
    };
    Some(LammpsLog {
        version,
        loop_s,
        steps: loops.iter().map(|l| l.1).sum(),
        atoms,
        cpu_use_percent,
    })
}

/// One `lmp -in in.damper` in `dir`, one process and one thread: its wall
/// time and CPU time (from the process' children's, Linux), and its log.
fn lmp_once(dir: &Path) -> Result<(Run, LammpsLog)> {
    let log = dir.join(LOG_FILE);
    let cpu0 = children_cpu_s();
    let wall = Instant::now();
    let out = Command::new("lmp")
        .args([
            "-in", INPUT_FILE, "-log", LOG_FILE, "-screen", "none", "-nocite",
        ])
        .current_dir(dir)
        .env("OMP_NUM_THREADS", "1")
        .stdin(Stdio::null())
        .output()
        .context(NEEDS_LMP)?;
    let run = Run {
        wall_s: wall.elapsed().as_secs_f64(),
        cpu_s: children_cpu_s() - cpu0,
    };
    let text = std::fs::read_to_string(&log).unwrap_or_default();
    if !out.status.success() || text.contains("ERROR") {
        let last: Vec<&str> = text.lines().rev().take(10).collect();
        bail!(
            "lmp failed ({}) on the exported deck:\n{}\n{}",
            out.status,
            last.into_iter().rev().collect::<Vec<_>>().join("\n"),
            String::from_utf8_lossy(&out.stderr)
        );
    }
    let parsed = parse_log(&text)
        .with_context(|| format!("reading LAMMPS' Loop time from {}", log.display()))?;
    Ok((run, parsed))
}

/// CPU seconds (user + system) of this process' finished children, from
/// /proc on Linux; zero elsewhere.
fn children_cpu_s() -> f64 {
    // cutime and cstime: fields 16 and 17 of the stat line.
    proc_stat_cpu_s(16)
}

/// The comparison on the settled thesis `bed` (of `scene`, the thesis):
/// the deck for `cycles` cycles written into a temporary folder, then vlab's
/// drive and `lmp` in turns, `repeats` times. Pushes three rows (vlab, the
/// whole `lmp` process, LAMMPS' Loop time) and two speed-ups (vlab over
/// each `lmp` timing) and gives the account.
pub fn lammps_rows(
    scene: &Scene,
    bed: &SettledBed,
    cycles: u32,
    repeats: u32,
    progress: &mut ProgressLine,
    rows: &mut Vec<BenchRow>,
    speedups: &mut Vec<Speedup>,
) -> Result<LammpsComparison> {
    let (freq_hz, gamma) = (40.0, 20.0);
    let cycles = cycles.max(MIN_EXPORT_CYCLES);
    let (dir, s) = deck_in_temp(scene, bed, cycles, (freq_hz, gamma))?;
    let s = &s;
    let n = bed.world.particles.len();
    let t = in_turns(scene, bed, (cycles, repeats), (&dir, s), progress)?;
    let vlab_row = BenchRow::new(VLAB_CASE, 1, false, n, t.vlab_steps, &t.vlab_runs);
    let process_row = BenchRow::new(LMP_PROCESS_CASE, 1, false, n, s.steps, &t.lmp_runs);
    let loop_row = BenchRow::new(LMP_LOOP_CASE, 1, false, n, s.steps, &t.loop_runs);
    let over_process = Speedup::between(
        "vlab over LAMMPS per core (1 thread each), against the whole lmp process".into(),
        &process_row,
        &vlab_row,
    );
    let over_loop = Speedup::between(
        "vlab over LAMMPS per core (1 thread each), against LAMMPS' Loop time (its run only)"
            .into(),
        &loop_row,
        &vlab_row,
    );
    let comparison = LammpsComparison {
        lammps_version: t.version,
        deck: format!(
            "vlab export lammps --freq {freq_hz} --gamma {gamma} --cycles {cycles} --steady-cycles {STEADY_CYCLES}"
        ),
        deck_form: DECK_FORM,
        particles: n,
        cycles,
        dt_s: s.dt_s,
        vlab_steps: t.vlab_steps,
        lammps_steps: s.steps,
        runs: t.vlab_runs.len(),
        vlab_timed: "the drive's stepping loop on one thread (wall forces every step, \
                     energy ledger every cycle; no trace written), not the copy of the bed",
        lammps_process_timed: "lmp -in in.damper, 1 process, OMP_NUM_THREADS=1: start-up, \
                               read_data, the run, its record (a row every 20 steps) and thermo",
        lammps_loop_timed: "LAMMPS' Loop time from its log: the run with its record and thermo, \
                            not the start-up or read_data",
        vlab_wall_s: vlab_row.run_wall_s.clone(),
        lammps_process_wall_s: process_row.run_wall_s.clone(),
        lammps_loop_s: loop_row.run_wall_s.clone(),
        lammps_loop_cpu_use_percent: t.cpu_use,
        vlab_particle_steps_per_s: vlab_row.particle_steps_per_s,
        lammps_process_particle_steps_per_s: process_row.particle_steps_per_s,
        lammps_loop_particle_steps_per_s: loop_row.particle_steps_per_s,
        vlab_over_lammps_process: over_process.median_paired,
        vlab_over_lammps_loop: over_loop.median_paired,
    };
    rows.extend([vlab_row, process_row, loop_row]);
    speedups.extend([over_process, over_loop]);
    Ok(comparison)
}

/// The deck of `vlab export lammps --cycles N --steady-cycles 2` for the
/// drive `(freq_hz, gamma)`, written into a temporary folder, checked to
/// step as vlab does.
fn deck_in_temp(
    scene: &Scene,
    bed: &SettledBed,
    cycles: u32,
    (freq_hz, gamma): (f64, f64),
) -> Result<(TempDir, DeckSummary)> {
    // The scene `vlab export lammps --cycles N --steady-cycles 2` resolves.
    let deck_scene = SceneOverrides {
        cycles: Some(cycles),
        steady_cycles: Some(STEADY_CYCLES),
        orientation: None,
        seed: None,
        dt_s: None,
    }
    .apply(scene.clone())
    .context("the LAMMPS deck's scene")?;
    let export = LammpsExport::for_scene(&deck_scene, freq_hz, gamma)?;
    let deck = lammps_deck(&deck_scene, bed, &export).context("writing the LAMMPS deck")?;
    let dir = TempDir::new()?;
    deck.write(&dir.0).context("writing the LAMMPS deck")?;
    let vlab_dt_s = scene.drive_dt_s(&scene.drive(freq_hz, gamma)?);
    let s = deck.summary;
    if (vlab_dt_s / s.dt_s - 1.0).abs() > 1e-12 {
        bail!(
            "the deck's time step {:e} s is not vlab's {vlab_dt_s:e} s",
            s.dt_s
        );
    }
    Ok((dir, s))
}

/// What the runs in turns gave: vlab's and lmp's wall and CPU times, the
/// loop's by LAMMPS' own count, the steps and LAMMPS' version.
#[derive(Default)]
struct Turns {
    vlab_runs: Vec<Run>,
    lmp_runs: Vec<Run>,
    loop_runs: Vec<Run>,
    cpu_use: Vec<f64>,
    vlab_steps: u64,
    version: String,
}

/// vlab's drive of `cycles` and lmp's run of the deck in `dir`, in turns,
/// `repeats` times; lmp must run the deck's steps on the bed's spheres.
fn in_turns(
    scene: &Scene,
    bed: &SettledBed,
    (cycles, repeats): (u32, u32),
    (dir, s): (&TempDir, &DeckSummary),
    progress: &mut ProgressLine,
) -> Result<Turns> {
    let n = bed.world.particles.len();
    let mut t = Turns::default();
    for _ in 0..repeats {
        let (run, steps, _) =
            drive_once(bed, scene, cycles, 1, progress).context("driving the thesis bed")?;
        t.vlab_runs.push(run);
        t.vlab_steps = steps;
        let (run, log) = lmp_once(&dir.0)?;
        if log.steps != s.steps || log.atoms != n {
            bail!(
                "LAMMPS ran {} steps with {} atoms; the deck has {} steps of {n} spheres",
                log.steps,
                log.atoms,
                s.steps
            );
        }
        t.lmp_runs.push(run);
        // The loop's CPU time by LAMMPS' own count of its CPU use.
        t.loop_runs.push(Run {
            wall_s: log.loop_s,
            cpu_s: match log.cpu_use_percent.is_finite() {
                true => log.loop_s * log.cpu_use_percent / 100.0,
                false => 0.0,
            },
        });
        t.cpu_use.push(log.cpu_use_percent);
        t.version = log.version;
    }
    Ok(t)
}

/// The comparison's lines of the text report.
pub fn print_comparison(c: &LammpsComparison) {
    println!(
        "  against {}, per core: the deck of `{}` ({} spheres, dt {:.4e} s; vlab {} steps, lmp {}), vlab and lmp in turns, {} run(s) each",
        c.lammps_version, c.deck, c.particles, c.dt_s, c.vlab_steps, c.lammps_steps, c.runs
    );
    println!("    the deck:   {}", c.deck_form);
    println!("    vlab timed: {}", c.vlab_timed);
    println!("    lmp timed:  {}", c.lammps_process_timed);
    println!("    and:        {}", c.lammps_loop_timed);
    println!(
        "    median: vlab {:.2} M particle-steps/s; lmp {:.2} M (whole process), {:.2} M (Loop time); vlab/lmp x{:.2} against the whole process, x{:.2} against the Loop time (median of paired runs)",
        c.vlab_particle_steps_per_s / 1e6,
        c.lammps_process_particle_steps_per_s / 1e6,
        c.lammps_loop_particle_steps_per_s / 1e6,
        c.vlab_over_lammps_process,
        c.vlab_over_lammps_loop
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The lines of a LAMMPS 2021 log the comparison reads. Catches a field
    /// read from the wrong word (steps for atoms, procs for the time) and a
    /// CPU use read as NaN.
    #[test]
    fn reads_loop_time_steps_atoms_and_cpu_use() {
        let log = "LAMMPS (29 Sep 2021 - Update 2)\nunits si\n\
                   Loop time of 4.46208 on 1 procs for 61480 steps with 358 atoms\n\n\
                   87.7% CPU use with 1 MPI tasks x 1 OpenMP threads\n";
        let got = parse_log(log).expect("parses");
        assert_eq!(
            got,
            LammpsLog {
                version: "LAMMPS (29 Sep 2021 - Update 2)".into(),
                loop_s: 4.46208,
                steps: 61480,
                atoms: 358,
                cpu_use_percent: 87.7,
            }
        );
        // The deck's two runs (the first row's steps, then the rest): summed,
        // the CPU use weighted by each run's time.
        let two = "LAMMPS (29 Sep 2021 - Update 2)\n\
                   Loop time of 0.002 on 1 procs for 20 steps with 358 atoms\n\n\
                   50.0% CPU use with 1 MPI tasks x 1 OpenMP threads\n\
                   Loop time of 4.462 on 1 procs for 61460 steps with 358 atoms\n\n\
                   90.0% CPU use with 1 MPI tasks x 1 OpenMP threads\n";
        let got = parse_log(two).expect("parses");
        assert_eq!(got.steps, 61480);
        assert!((got.loop_s - 4.464).abs() < 1e-12, "{}", got.loop_s);
        assert!((got.cpu_use_percent - (0.1 + 401.58) / 4.464).abs() < 1e-9);
        // No Loop line (LAMMPS stopped before its run): nothing read.
        assert_eq!(parse_log("LAMMPS (29 Sep 2021)\nERROR: x\n"), None);
    }
}
