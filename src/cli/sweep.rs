//! `vlab sweep`: damping efficiency and motional phase over frequency ×
//! amplitude (× seed, fill ratio, orientation), every condition the shake
//! `vlab shake` runs, in parallel across conditions; `sweep.csv` is kept up to
//! date after every condition, `--resume` finishes an interrupted sweep,
//! `--shard I/N` runs a deterministic slice and `vlab sweep merge` joins the
//! slices. The work is [`vlab::study::sweep`]'s; this is its command line.

use std::path::{Path, PathBuf};
use std::sync::Mutex;

use anyhow::{Context, Result, bail};
use clap::{Args, Subcommand};

use vlab::atomic_write::OutputDir;
use vlab::rig::{RigFile, RigSpec, ShakerKind};
use vlab::scene::{Orientation, Scene, SceneOverrides};
use vlab::study::sweep::{
    ConditionSummary, RowStatus, Shard, SweepEvent, SweepFile, SweepPlan, merge_shards, phase_name,
    run_sweep, summarise,
};
use vlab::study::sweep_peak::{SeriesPeak, series_peaks};
use vlab::study::sweep_plot::plot_sweep;

use super::args;
use super::cache_cmd::NoCacheArg;
use super::progress::ProgressLine;
use super::sweep_lines::{EventLines, plus_minus};

#[derive(Debug, Clone, Args)]
#[command(
    allow_negative_numbers = true,
    args_conflicts_with_subcommands = true,
    subcommand_negates_reqs = true
)]
pub struct SweepArgs {
    #[command(subcommand)]
    action: Option<SweepAction>,
    /// Drive frequencies (Hz), comma-separated.
    #[arg(long = "freq", value_name = "LIST", required = true, value_delimiter = ',', value_parser = args::freq_hz)]
    freqs_hz: Vec<f64>,
    /// Amplitudes Γ (peak acceleration / g), comma-separated.
    #[arg(long = "gamma", alias = "gammas", value_name = "LIST", required = true, value_delimiter = ',', value_parser = args::gamma)]
    gammas: Vec<f64>,
    /// Seeds of the random fill, comma-separated.
    #[arg(long, value_name = "LIST", default_value = "1", value_delimiter = ',')]
    seeds: Vec<u64>,
    /// Volume fill ratios, comma-separated, each reached by the enclosure
    /// length with the scene's particles [default: the scene's].
    #[arg(long = "fill-ratio", value_name = "LIST", value_delimiter = ',', value_parser = args::gamma)]
    fill_ratios: Vec<f64>,
    /// Orientations, comma-separated [default: the scene's].
    #[arg(long, value_name = "LIST", value_delimiter = ',', value_enum)]
    orientation: Vec<Orientation>,
    /// Scene file (TOML) merged over the built-in thesis scene.
    #[arg(long, value_name = "FILE")]
    scene: Option<PathBuf>,
    /// Drive cycles in all, the same for every condition [scene default:
    /// each condition runs until steady: input work and dissipation within
    /// 1 %, error of the energy per cycle below 1 % and no trend over the
    /// window (at least 16 cycles), at most 400 cycles].
    #[arg(long)]
    cycles: Option<u32>,
    /// Last cycles kept as the steady window [scene default: 5 of --cycles].
    #[arg(long)]
    steady_cycles: Option<u32>,
    /// Time step (s) [scene default: per condition, every collision resolved
    /// by 25 steps at the largest expected impact speed].
    #[arg(long = "dt-s", value_name = "S", value_parser = args::seconds)]
    dt_s: Option<f64>,
    /// The rig: a built-in name (thesis-shaker, ideal) or a rig file.
    #[arg(long, value_name = "NAME|FILE", default_value = vlab::rig::DEFAULT_RIG)]
    rig: String,
    /// How the enclosure is moved [default: the rig's own].
    #[arg(long, value_enum)]
    shaker: Option<ShakerKind>,
    /// Output folder [default: signals/sweep-<scene>].
    #[arg(long, value_name = "DIR")]
    out: Option<PathBuf>,
    /// Continue the sweep in --out: run only the conditions its sweep.csv lacks.
    #[arg(long)]
    resume: bool,
    /// Run only slice I of N (1 <= I <= N) of the conditions; join the slices
    /// with `vlab sweep merge`.
    #[arg(long, value_name = "I/N", value_parser = shard)]
    shard: Option<Shard>,
    /// Independent beds each condition drives together, seeds derived from
    /// each of --seeds as `vlab shake --beds` derives them: a row's figures
    /// are then their mean and its +- their spread's; with one bed the +- is
    /// its window's and leaves out how far another packing reads
    /// (sweep.csv's `se_from` says which). Costs N times one bed.
    #[arg(long, value_name = "N", default_value_t = 1)]
    beds: u32,
    /// Carry the bed from each Gamma to the next, up to the highest and back
    /// down, as a lab's controller steps the level (one bed per frequency
    /// and seed): writes each branch as a sweep (up/sweep.csv,
    /// down/sweep.csv) and updown.csv, which says where they part.
    #[arg(long = "up-down", conflicts_with_all = ["resume", "shard"])]
    up_down: bool,
    /// Print the summary as JSON.
    #[arg(long)]
    json: bool,
    #[command(flatten)]
    cache: NoCacheArg,
}

#[derive(Debug, Clone, Subcommand)]
enum SweepAction {
    /// Join the sweep.csv files of all shards of one sweep into one sweep.csv
    /// (as the unsharded sweep writes it) and draw its plots.
    Merge(MergeArgs),
    /// Name every row's motional phase again from its stored indicators with
    /// this vlab's heuristic (after it was tuned), rewrite the file and redraw
    /// its plots.
    Relabel(RelabelArgs),
    /// The optimum Gamma of several sweeps (one point each, with its +- from
    /// seeds) against a number that tells them apart, such as a shape's
    /// aspect ratio: a table, optimum.csv and a plot (thesis Fig. 8.11-8.12).
    Optimum(super::sweep_optimum::OptimumArgs),
}

#[derive(Debug, Clone, Args)]
struct RelabelArgs {
    /// The sweep.csv (or its folder).
    #[arg(value_name = "FILE")]
    file: PathBuf,
}

#[derive(Debug, Clone, Args)]
struct MergeArgs {
    /// Shard files (sweep.csv) or the folders holding them.
    #[arg(required = true, value_name = "SHARD")]
    shards: Vec<PathBuf>,
    /// Output folder for the merged sweep.csv and plots.
    #[arg(long, value_name = "DIR", required = true)]
    out: PathBuf,
}

fn shard(s: &str) -> Result<Shard, vlab::validation::InvalidParameter> {
    Shard::parse(s).map_err(|e| e.renamed("value"))
}

/// Runs the command.
pub fn run(a: SweepArgs, quiet: bool) -> Result<()> {
    match a.action {
        Some(SweepAction::Merge(m)) => return merge(m),
        Some(SweepAction::Relabel(r)) => return relabel(r),
        Some(SweepAction::Optimum(o)) => return super::sweep_optimum::run(o),
        None => {}
    }
    let plan = sweep_plan(&a)?;
    if a.up_down {
        return super::sweep_updown::run(a.out.clone(), &plan, quiet);
    }
    let shard = a.shard.unwrap_or(Shard::ALL);
    let out_dir = a
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from("signals").join(format!("sweep-{}", plan.scene.name)));
    if !a.resume && out_dir.join("sweep.csv").exists() {
        bail!(
            "{} exists: pass --resume to continue that sweep, or choose another --out",
            out_dir.join("sweep.csv").display()
        );
    }
    let made = OutputDir::prepare(&out_dir)
        .with_context(|| format!("cannot create output folder {}", out_dir.display()))?;
    let progress = Mutex::new(ProgressLine::new("sweep", quiet));
    let events = EventLines {
        shard,
        // Name the fill and the orientation in progress lines only when the
        // sweep has several (else four beds' conditions read alike).
        with_fill: plan.fill_ratios.len() > 1,
        with_orientation: plan.orientations.len() > 1,
    };
    let on_event = |e: SweepEvent| {
        let mut p = progress.lock().unwrap_or_else(|e| e.into_inner());
        events.show(e, &mut p);
    };
    let result =
        run_sweep(&plan, shard, &out_dir, a.resume, &on_event).context("running the sweep");
    let file = made.keep_if_ok(result)?;
    let plots = if shard == Shard::ALL {
        plot_sweep(&file, &out_dir).context("drawing the sweep's plots")?
    } else {
        Vec::new()
    };
    report(&file, &out_dir, &plots, a.json)
}

/// The sweep the flags ask for, validated; a refused value is named by its
/// flag.
fn sweep_plan(a: &SweepArgs) -> Result<SweepPlan> {
    let flags = args::FlagKeys::drive(
        a.cycles.is_some(),
        a.steady_cycles.is_some(),
        a.dt_s.is_some(),
    )
    .set(true, "freq_hz", "--freq")
    .set(true, "gamma", "--gamma")
    .set(true, "seeds", "--seeds")
    .set(true, "fill_ratio", "--fill-ratio")
    .set(true, "beds", "--beds");
    // The rig first, so that only its own refusals carry its name.
    RigSpec::from_name_or_path(&a.rig).with_context(|| format!("--rig {}", a.rig))?;
    let scene = Scene::load_or_thesis(a.scene.as_deref())?;
    let scene = SceneOverrides {
        cycles: a.cycles,
        steady_cycles: a.steady_cycles,
        orientation: None,
        seed: None,
        dt_s: a.dt_s,
    }
    .apply(scene)
    .map_err(|e| flags.name_flags(e.into()))?;
    let plan = SweepPlan {
        scene,
        rig: a.rig.clone(),
        shaker: a.shaker,
        freqs_hz: a.freqs_hz.clone(),
        gammas: a.gammas.clone(),
        seeds: a.seeds.clone(),
        fill_ratios: a.fill_ratios.clone(),
        orientations: a.orientation.clone(),
        beds: a.cache.source(&mut |n| eprintln!("{n}")),
        ensemble_beds: a.beds,
    };
    plan.validate().map_err(|e| flags.name_flags(e.into()))?;
    if a.up_down {
        vlab::study::sweep_updown::validate(&plan).map_err(|e| flags.name_flags(e.into()))?;
    }
    Ok(plan)
}

fn report(file: &SweepFile, dir: &Path, plots: &[PathBuf], json: bool) -> Result<()> {
    if json {
        println!("{}", file.report().json()?);
        return Ok(());
    }
    let summary = summarise(file);
    let h = &file.header;
    println!(
        "{} damper, rig {}, {}, seeds {:?}{}:",
        h.scene,
        h.rig,
        if h.cycles.starts_with("steady") {
            format!("each condition driven until {}", h.cycles)
        } else {
            format!("{} cycles (last {} kept)", h.cycles, h.steady_cycles)
        },
        h.grid.seeds,
        if h.shard == Shard::ALL {
            String::new()
        } else {
            format!(", shard {}", h.shard)
        }
    );
    println!(
        "  fill   orientation  freq    Gamma   efficiency (DEM +- se)  +- from    measured  phase"
    );
    summary.iter().for_each(print_condition);
    if summary.iter().any(|s| s.se_from == "window") {
        println!(
            "  (+- from window: one bed's cycles alone, which leaves out how far another packing of the damper reads (at 40 Hz, Gamma 20 the beds spread twice as far as a window claims; docs/accuracy.md); --beds N or several --seeds measure it)"
        );
    }
    print_peaks(&series_peaks(file));
    println!("  wrote {}", dir.join("sweep.csv").display());
    for p in plots {
        println!("  wrote {}", p.display());
    }
    Ok(())
}

/// One condition's row: its efficiency with the +- and where that comes
/// from, the measured one and the phase; or why it has none.
fn print_condition(s: &ConditionSummary) {
    if s.status == RowStatus::Ok {
        println!(
            "  {:.3}  {:<11}  {:>5}  {:>6}   {:.3} +- {:<9}       {:<9}  {:.3}     {}",
            s.fill_ratio,
            s.orientation.as_str(),
            s.freq_hz,
            s.gamma,
            s.efficiency,
            plus_minus(s.efficiency_se),
            s.se_from,
            s.efficiency_measured,
            phase_name(s.phase)
        );
    } else {
        println!(
            "  {:.3}  {:<11}  {:>5}  {:>6}   {}",
            s.fill_ratio,
            s.orientation.as_str(),
            s.freq_hz,
            s.gamma,
            s.status.as_str()
        );
    }
}

/// Where each series' DEM efficiency peaks against Gamma (a parabola in
/// ln Gamma through the largest value and its neighbours), with the spread
/// of the seeds' own peaks.
fn print_peaks(peaks: &[SeriesPeak]) {
    for p in peaks {
        let Some(m) = p.of_mean else { continue };
        let series = format!(
            "  peak at fill {:.3}, {}, {} Hz:",
            p.fill_ratio,
            p.orientation.as_str(),
            p.freq_hz
        );
        if m.at_edge {
            println!(
                "{series} at the grid's end, Gamma {} (efficiency {:.3}): the peak lies beyond the grid",
                m.gamma, m.efficiency
            );
            continue;
        }
        let spread = match (p.gamma_mean, p.gamma_stderr) {
            (Some(mean), Some(se)) => format!(
                "; the seeds' own peaks {mean:.2} +- {se:.2} (from {} seeds)",
                p.per_seed.iter().flatten().filter(|q| !q.at_edge).count()
            ),
            _ => "; +- n/a (fewer than 2 seeds peak inside the grid)".into(),
        };
        println!(
            "{series} Gamma {:.2}, efficiency {:.3} (parabola in ln Gamma through the largest and its neighbours){spread}",
            m.gamma, m.efficiency
        );
    }
}

fn relabel(r: RelabelArgs) -> Result<()> {
    let path = if r.file.is_dir() {
        r.file.join("sweep.csv")
    } else {
        r.file.clone()
    };
    let mut file = SweepFile::read(&path)?;
    let changed = file.relabel(&vlab::study::phases::PhaseThresholds::default());
    file.write(&path)?;
    let dir = path
        .parent()
        .map(Path::to_path_buf)
        .unwrap_or_else(|| PathBuf::from("."));
    let plots = if file.header.shard == Shard::ALL {
        plot_sweep(&file, &dir).context("drawing the sweep's plots")?
    } else {
        Vec::new()
    };
    eprintln!("relabelled {changed} of {} rows", file.rows.len());
    report(&file, &dir, &plots, false)
}

fn merge(m: MergeArgs) -> Result<()> {
    let mut files = Vec::new();
    for p in &m.shards {
        let path = if p.is_dir() {
            p.join("sweep.csv")
        } else {
            p.clone()
        };
        files.push(SweepFile::read(&path)?);
    }
    let merged = merge_shards(&files)?;
    let made = OutputDir::prepare(&m.out)
        .with_context(|| format!("cannot create output folder {}", m.out.display()))?;
    let path = m.out.join("sweep.csv");
    made.keep_if_ok(merged.write(&path))?;
    let plots = plot_sweep(&merged, &m.out).context("drawing the sweep's plots")?;
    report(&merged, &m.out, &plots, false)
}
