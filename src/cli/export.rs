//! `vlab export lammps`: the damper as a LAMMPS input deck, for beds too big
//! for one machine or to check vlab against another DEM code. The work is
//! [`vlab::export::lammps_deck`]'s; this is its command line.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use clap::{Args, Subcommand};

use vlab::atomic_write::OutputDir;
use vlab::export::lammps_deck::{
    ContactTranslation, DeckSummary, INPUT_FILE, LammpsExport, RECORD_FILE, lammps_deck,
};

use super::args;
use super::cache_cmd::NoCacheArg;
use super::progress::ProgressLine;

#[derive(Debug, Clone, Args)]
pub struct ExportArgs {
    #[command(subcommand)]
    target: ExportTarget,
}

#[derive(Debug, Clone, Subcommand)]
enum ExportTarget {
    /// A LAMMPS input deck (pair_style granular, two wiggling wall fixes; bodies
    /// as fix rigid/small molecules with vlab's mass and inertia) and vlab's
    /// settled packing; the deck writes record.txt for `vlab replay`. It runs
    /// --cycles (the last --steady-cycles the window) at vlab's time step for
    /// this drive; a scene run until steady runs drive.min_cycles, its last
    /// 5/8 the window (LAMMPS keeps no dissipation ledger to judge
    /// steadiness): give the cycles `vlab shake` took (its summary.json).
    Lammps(LammpsArgs),
}

#[derive(Debug, Clone, Args)]
#[command(allow_negative_numbers = true)]
struct LammpsArgs {
    /// Drive frequency (Hz).
    #[arg(long = "freq", value_name = "HZ", value_parser = args::freq_hz)]
    freq_hz: f64,
    /// Acceleration amplitude Γ: peak enclosure acceleration / g.
    #[arg(long, value_parser = args::gamma)]
    gamma: f64,
    #[command(flatten)]
    scene: args::SceneArgs,
    /// Output folder for in.damper, packing.data and export.json.
    #[arg(long, value_name = "DIR")]
    out: PathBuf,
    #[command(flatten)]
    cache: NoCacheArg,
}

/// Runs the command.
pub fn run(a: ExportArgs, quiet: bool) -> Result<()> {
    match a.target {
        ExportTarget::Lammps(a) => run_lammps(a, quiet),
    }
}

fn run_lammps(a: LammpsArgs, quiet: bool) -> Result<()> {
    let flags = a
        .scene
        .flags()
        .set(true, "freq_hz", "--freq")
        .set(true, "gamma", "--gamma");
    let scene = super::args::run_alone(a.scene.resolve()?);
    let export = LammpsExport::for_scene(&scene, a.freq_hz, a.gamma)
        .map_err(|e| flags.name_flags(e.into()))?;
    let made = OutputDir::prepare(&a.out)
        .with_context(|| format!("cannot create output folder {}", a.out.display()))?;
    let mut progress = ProgressLine::new("export", quiet);
    let beds = a.cache.source(&mut |n| progress.warn(n));
    let result = beds
        .settle(&scene, &mut |p| progress.update(p))
        .context("settling the packing")
        .and_then(|bed| {
            lammps_deck(&scene, &bed, &export)
                .map_err(|e| flags.name_flags(e.into()))
                .context("writing the LAMMPS deck")
        });
    progress.finish();
    let deck = made.keep_if_ok(result)?;
    let written = deck.write(&a.out);
    made.keep_if_ok(written)?;
    print_deck(&deck.summary, &a.out);
    Ok(())
}

/// What the deck holds, how vlab's contacts were translated, and how to
/// run it.
fn print_deck(s: &DeckSummary, out: &Path) {
    println!(
        "LAMMPS deck for the {} damper at {} Hz, Gamma {}: {} ({:.4} kg), {} cycles (the last {} the window) = {} steps of {:e} s",
        s.scene,
        s.freq_hz,
        s.gamma,
        if s.n_bodies > 0 {
            format!(
                "{} rigid bodies of {} sub-spheres (fix rigid/small, vlab's mass and inertia)",
                s.n_bodies, s.n_particles
            )
        } else {
            format!("{} spheres", s.n_particles)
        },
        s.particle_mass_kg,
        s.cycles,
        s.steady_cycles,
        s.steps,
        s.dt_s
    );
    let show = |what: &str, t: &ContactTranslation| {
        println!(
            "  {what}: e = {} -> LAMMPS tsuji e = {} (alpha = sqrt(5) beta = {:.5}), mu = {}, x_gamma_t = {:.4}",
            t.restitution,
            t.lammps_restitution
                .map_or_else(|| "none (no damping)".into(), |e| format!("{e:.5}")),
            t.tsuji_alpha,
            t.friction,
            t.tangential_damping_ratio
        );
    };
    show("particle-particle", &s.particle_particle);
    show("particle-wall", &s.particle_wall);
    println!(
        "  side wall stiffness x {:.5} (LAMMPS' concave cylinder contact, vlab's flat wall)",
        s.side_wall_factor
    );
    println!(
        "  wrote {}/{{{}}}; run: cd {} && lmp -in {INPUT_FILE} (or mpirun -np N lmp -in {INPUT_FILE}); then vlab replay {}/{RECORD_FILE}",
        out.display(),
        s.files.join(", "),
        out.display(),
        out.display()
    );
}
