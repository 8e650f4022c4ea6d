//! `vlab host decay`: the host released from a displacement (or struck by a
//! hammer) and left to ring down; the loss factor against amplitude by the
//! logarithmic decrement and the Hilbert envelope
//! ([`vlab::experiment::host_test::decay`]), each held against the DEM's energies,
//! and, with `--map`, against Yang's structure-independent figure at the same
//! frequency and Γ.

use std::path::PathBuf;

use anyhow::{Context, Result};
use clap::Args;

use vlab::atomic_write::OutputDir;
use vlab::experiment::ensemble::check_beds;
use vlab::experiment::host_test::Damper;
use vlab::experiment::host_test::decay::{
    DecayEnsemble, DecayError, DecayEstimate, DecayOutcome, MapEnergy,
};
use vlab::host::Excitation;
use vlab::study::dissipation_map::{MapSource, dissipation_map};

use super::{HostTestArgs, damper_slug, run_test};
use crate::cli::args;

#[derive(Debug, Clone, Args)]
#[command(allow_negative_numbers = true)]
pub struct DecayArgs {
    #[command(flatten)]
    common: HostTestArgs,
    /// Release the host from this displacement at the damper (m).
    #[arg(long = "x0-m", value_name = "M", default_value = "0.003", conflicts_with = "hammer_n_s", value_parser = args::finite)]
    x0_m: f64,
    /// Strike the drive point with a hammer of this impulse (N s) instead.
    #[arg(long = "hammer-n-s", value_name = "N_S", value_parser = args::newton_seconds)]
    hammer_n_s: Option<f64>,
    /// Length of the record (s).
    #[arg(long = "duration-s", value_name = "S", default_value = "1", value_parser = args::seconds)]
    duration_s: f64,
    /// A sweep (its sweep.csv) whose Yang-measured efficiency gives the
    /// structure-independent energy per cycle at each point's frequency and Γ.
    /// Given again (`--map COARSE --map FINE`), a later sweep replaces the
    /// conditions it holds: a map refined at the onset by a finer Γ grid
    /// and more seeds there, from a sweep of the same scene and rig.
    #[arg(long, value_name = "FILE")]
    map: Vec<PathBuf>,
    /// Independent beds, one decay each (seeds derived from --seed as
    /// `vlab shake --beds` derives them; the particle damper only): each
    /// cycle's loss factor is then also given as their mean with the error
    /// of their spread (decay-beds.csv). Costs N times one bed, side by side
    /// on the cores.
    #[arg(long, value_name = "N", default_value_t = 1)]
    beds: u32,
    /// Output folder [default: signals/host-decay-<host>-<damper>].
    #[arg(long, value_name = "DIR")]
    out: Option<PathBuf>,
}

pub fn run(a: DecayArgs, quiet: bool) -> Result<()> {
    let excitation = excitation(&a)?;
    check_beds(a.beds).map_err(|e| {
        args::FlagKeys::new()
            .set(true, "beds", "--beds")
            .name_flags(e.into())
    })?;
    let (scene, test) = a.common.test(excitation, a.duration_s)?;
    let beds = match test.damper {
        Damper::Particles => a.beds,
        _ => 1,
    };
    let map = match a.map.is_empty() {
        false => {
            let (file, label) = super::read_maps(&a.map)?;
            let o = Some(scene.enclosure.orientation);
            let map = dissipation_map(&file, o, None, MapSource::Yang);
            Some(map.with_context(|| format!("--map {label}"))?)
        }
        true => None,
    };
    let out = a.out.clone().unwrap_or_else(|| {
        let name = format!("host-decay-{}-{}", test.host.name, damper_slug(test.damper));
        PathBuf::from("signals").join(name)
    });
    let made = OutputDir::prepare(&out)
        .with_context(|| format!("cannot create output folder {}", out.display()))?;
    // A hammer's blow is over in 0.5 ms; the record starts after it.
    let skip_s = if a.hammer_n_s.is_some() { 2e-3 } else { 0.0 };
    let outcome = made.keep_if_ok((|| {
        let first = run_test(&scene, &test, a.common.cache, quiet)?;
        let source = a.common.cache.source(&mut |n| eprintln!("{n}"));
        DecayOutcome::measure(&scene, test.clone(), first, &source, beds, skip_s).map_err(|e| {
            match e {
                DecayError::NoPeaks => anyhow::anyhow!(
                    "the decay has no two successive peaks to compare: lengthen --duration-s"
                ),
                e => e.into(),
            }
        })
    })())?;
    let g = scene.simulation.gravity_mps2;
    // Yang's structure-independent energy per cycle at a point's f and Γ.
    let yang_energy = |e: &DecayEstimate| {
        map.as_ref()
            .map(|m| m.energy_per_cycle_j(e.freq_hz, e.amplitude_m, g))
    };
    print_decay(&outcome, &yang_energy, map.is_some());
    if let Some(e) = &outcome.ensemble {
        print_ensemble(e);
    }
    outcome
        .write(&out, &yang_energy)
        .with_context(|| format!("writing into {}", out.display()))?;
    println!("wrote {}", out.display());
    Ok(())
}

/// The release or the hammer blow of the flags, checked.
fn excitation(a: &DecayArgs) -> Result<Excitation> {
    let (excitation, flag) = match a.hammer_n_s {
        Some(j) => (Excitation::Hammer { impulse_n_s: j }, "--hammer-n-s"),
        None => (Excitation::Release { x0_m: a.x0_m }, "--x0-m"),
    };
    excitation
        .validate()
        .map_err(|e| anyhow::Error::from(e.renamed(flag)))?;
    Ok(excitation)
}

/// The first bed's decay: each method's estimates against the truth, and
/// what the damper took over the decay.
fn print_decay(outcome: &DecayOutcome, yang_energy: MapEnergy<'_>, with_map: bool) {
    let (test, run, analysis) = (&outcome.test, &outcome.run, &outcome.analysis);
    println!(
        "{} on {}, {}: {} steps of {:.3e} s, {:.1} s wall; the bare host's loss factor {:.4}",
        test.damper.label(),
        test.host.name,
        super::excitation_text(&test.excitation),
        run.steps,
        run.dt_s,
        run.wall_time_s,
        analysis.host_loss_factor
    );
    println!(
        "  method          t_s     Gamma   eta (+- reading)     eta_true  damper J/cycle: method  host's work  dissipated{}",
        if with_map { "  Yang's map" } else { "" }
    );
    for (name, points) in outcome.methods() {
        for e in points {
            println!(
                "  {:14} {:6.3}  {:6.2}  {:.4} +- {:.4}   {:.4}    {:12.5}  {:11.5}  {:10.5}{}",
                name,
                e.time_s,
                e.gamma,
                e.loss_factor,
                e.loss_factor_stderr,
                e.true_loss_factor,
                e.damper_energy_j,
                e.true_damper_energy_j,
                e.true_damper_dissipated_j,
                yang_energy(e).map_or(String::new(), |y| format!("  {y:10.5}"))
            );
        }
    }
    println!(
        "  over the decay the damper took {:.5} J (+- at most {:.5} J) by the log decrement; the host did {:.5} J of work on it and it dissipated {:.5} J",
        analysis.damper_energy_sum_j,
        analysis.damper_energy_sum_stderr_j,
        analysis.true_damper_energy_sum_j,
        analysis.true_damper_dissipated_sum_j
    );
}

/// The beds' decays cycle by cycle: the mean loss factor with the error of
/// the beds' spread.
fn print_ensemble(e: &DecayEnsemble) {
    println!(
        "  {} beds (seeds {}), cycle by cycle: the mean over the beds, +- one sigma of it from their spread (Student's t on {}, never less than their readings' errors make it)",
        e.beds,
        e.seeds
            .iter()
            .map(u64::to_string)
            .collect::<Vec<_>>()
            .join(", "),
        crate::cli::shake::degrees_of_freedom(e.beds.saturating_sub(1))
    );
    println!("  method          cycle  t_s     Gamma   eta (+- beds)        spread   eta_true");
    let opt = |v: Option<f64>| v.map_or("not known".to_string(), |x| format!("{x:.4}"));
    for (name, points) in e.methods() {
        for p in points {
            println!(
                "  {:14} {:5}  {:6.3}  {:6.2}  {:.4} +- {:9}  {:.4}   {:.4}",
                name,
                p.cycle,
                p.time_s,
                p.gamma,
                p.loss_factor,
                opt(p.loss_factor_stderr),
                p.loss_factor_spread,
                p.true_loss_factor
            );
        }
    }
}
