//! Commands of the `vlab` binary. Each command validates all its inputs before it
//! writes anything, writes every file atomically, and reports failures as one
//! line with context; the process then exits with status 1 (2 for usage errors,
//! which clap reports itself).

mod accuracy;
mod analyze;
mod args;
mod bench;
mod cache_cmd;
mod calibrate;
mod cor;
mod drop;
mod export;
mod hints;
mod host;
mod impact;
mod plot;
mod predict;
mod press;
mod progress;
mod replay;
mod rig_cmd;
mod scene_cmd;
mod shake;
mod shear_box;
mod sweep;
mod sweep_lines;
mod sweep_optimum;
mod sweep_updown;

use std::process::ExitCode;

use clap::{Parser, Subcommand};

/// vlab — a virtual granular-damper laboratory.
///
/// A DEM model of spheres in a vibrated cylinder, inside a model of the thesis
/// shaker rig, with the lab's own post-processing. SI units throughout.
#[derive(Debug, Parser)]
#[command(name = "vlab", version, about, long_about = None, propagate_version = true)]
struct Cli {
    /// Worker threads (default: all cores). Physics is bit-identical for any count.
    #[arg(long, global = true, value_parser = args::threads)]
    threads: Option<usize>,
    /// No progress on standard error (warnings are still printed).
    #[arg(long, short, global = true)]
    quiet: bool,
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Shake the damper at one frequency and amplitude through the rig; write
    /// the traces, the DEM truth and the measurement.
    Shake(shake::ShakeArgs),
    /// Measure the rig's phase error on the empty enclosure (no particles).
    Calibrate(calibrate::CalibrateArgs),
    /// Dissipated power of a force/acceleration record by Yang's method.
    Analyze(analyze::AnalyzeArgs),
    /// One collision, sphere against a wall or a sphere, against Hertz theory.
    Impact(impact::ImpactArgs),
    /// A scene's particle (a sphere or a multi-sphere body) pressed onto a
    /// plate: normal and tangential force-deformation curves (thesis 5.4).
    Press(press::PressArgs),
    /// The quasi-static compression and shear test of 100 particles between
    /// two containers (thesis Fig. 8.15): normal and shear force-displacement
    /// curves of one scene's particles or several, ordered by stiffness.
    ShearBox(shear_box::ShearBoxArgs),
    /// Show the built-in scene (or a scene file merged over it).
    Scene(scene_cmd::SceneArgs),
    /// List the built-in rigs, or show one (--print: its TOML file).
    Rig(rig_cmd::RigArgs),
    /// Efficiency and motional phase over frequencies x amplitudes (x seeds,
    /// fill ratios, orientations); resumable, shardable (`sweep merge`).
    Sweep(sweep::SweepArgs),
    /// The bouncing-bed onset amplitude predicted by thesis eq. 6.11-6.13.
    Predict(predict::PredictArgs),
    /// Redraw the plots of a sweep.csv, or plot a CSV record.
    Plot(plot::PlotArgs),
    /// Measure speed: particle-steps per second on the thesis scene.
    Bench(bench::BenchArgs),
    /// Error against run time: DEM time step, cycles and seeds; one
    /// collision against Hertz; Yang's method against the DEM truth.
    Accuracy(accuracy::AccuracyArgs),
    /// Drop test: bounce a sphere on the drop rig, record the force, estimate the restitution.
    Drop(drop::DropArgs),
    /// Estimate the restitution from a force record of a drop test (CSV or WAV).
    Cor(cor::CorArgs),
    /// Put another DEM code's record (enclosure motion, particle force) through the
    /// rig and measure it as a shake is measured.
    Replay(replay::ReplayArgs),
    /// Write the damper for another DEM code: `vlab export lammps` writes a LAMMPS
    /// deck and the settled packing.
    Export(export::ExportArgs),
    /// The settled beds kept between runs: list, clear, or show the folder.
    Cache(cache_cmd::CacheArgs),
    /// The damper on a host structure: free decay, FRF, any excitation, and
    /// the map-based model's prediction (thesis 2.3.1, 9.4 i and v).
    Host(host::HostArgs),
}

/// Runs the command line and maps errors to an exit status.
pub fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => return args::parse_error(e),
    };
    match run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(err) => {
            eprintln!("error: {}", hints::with_flag_hint(one_line(&err), &err));
            ExitCode::FAILURE
        }
    }
}

/// The error and its causes on one line, without repeating a cause that an
/// outer message already quotes, nor a file an outer message just named
/// (`--rig rig.toml: rig.toml: force...` reads `--rig rig.toml: force...`).
fn one_line(err: &anyhow::Error) -> String {
    let mut out = String::new();
    for cause in err.chain() {
        let text = cause.to_string();
        if out.contains(&text) {
            continue;
        }
        let last = out.rsplit(' ').next().unwrap_or("");
        let text = match text.strip_prefix(last) {
            Some(rest) if !last.is_empty() && rest.starts_with(": ") => rest[2..].to_string(),
            _ => text,
        };
        if !out.is_empty() {
            out.push_str(": ");
        }
        out.push_str(&text);
    }
    out.replace('\n', " ")
}

fn run(cli: Cli) -> anyhow::Result<()> {
    let threads = cli.threads.unwrap_or_else(|| {
        std::thread::available_parallelism()
            .map(|n| n.get())
            .unwrap_or(1)
    });
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| anyhow::anyhow!("cannot start {threads} worker threads: {e}"))?;
    let quiet = cli.quiet;
    pool.install(|| match cli.command {
        Command::Shake(a) => shake::run(a, quiet),
        Command::Calibrate(a) => calibrate::run(a),
        Command::Analyze(a) => analyze::run(a),
        Command::Impact(a) => impact::run(a),
        Command::Press(a) => press::run(a),
        Command::ShearBox(a) => shear_box::run(a, quiet),
        Command::Scene(a) => scene_cmd::run(a),
        Command::Rig(a) => rig_cmd::run(a),
        Command::Sweep(a) => sweep::run(a, quiet),
        Command::Predict(a) => predict::run(a),
        Command::Cache(a) => cache_cmd::run(a),
        Command::Host(a) => host::run(a, quiet),
        Command::Plot(a) => plot::run(a),
        Command::Bench(a) => bench::run(a, quiet),
        Command::Drop(a) => drop::run(a),
        Command::Accuracy(a) => accuracy::run(a, quiet),
        Command::Cor(a) => cor::run(a),
        Command::Replay(a) => replay::run(a),
        Command::Export(a) => export::run(a, quiet),
    })
}
