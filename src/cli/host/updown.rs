//! `vlab host frf --up-down`: the stepped sine in one run, up the
//! frequencies and back down, the state carried from step to step
//! ([`vlab::experiment::host_test::carried_sine`] does the work); prints
//! each step and where the branches stand apart.

use std::path::Path;

use anyhow::{Context, Result, bail};

use vlab::experiment::host_test::HostTest;
use vlab::experiment::host_test::carried_sine::{
    BRANCHES_APART_SIGMA, Branch, CarriedSine, CarriedSineResult, run_carried_sine,
};
use vlab::experiment::host_test::frf::SteppedSine;
use vlab::scene::Scene;

use super::FreqList;
use crate::cli::cache_cmd::NoCacheArg;
use crate::cli::progress::ProgressLine;

/// The carried sine of the stepped sine's flags (already checked), one
/// bed: a refusal names the flag.
pub fn plan(freqs: &Option<FreqList>, stepped: &SteppedSine) -> Result<CarriedSine> {
    if stepped.beds != 1 {
        bail!(
            "--beds = {}: --up-down runs one bed (its state is carried from step to step); run it again with --seed for another",
            stepped.beds
        );
    }
    let plan = CarriedSine {
        freqs_hz: freqs.clone().map(|f| f.0).unwrap_or_default(),
        force_n: stepped.force_n,
        settle_cycles: stepped.settle_cycles,
        record_cycles: stepped.record_cycles,
        down: true,
    };
    plan.validate()
        .map_err(|e| anyhow::Error::from(e.renamed("--freq")))?;
    Ok(plan)
}

/// Runs `plan` on `test`'s host and damper, prints it and writes its files
/// into `out`.
pub fn run(
    scene: &Scene,
    test: &HostTest,
    plan: &CarriedSine,
    cache: NoCacheArg,
    out: &Path,
    quiet: bool,
) -> Result<()> {
    let mut progress = ProgressLine::new("host frf --up-down", quiet);
    let beds = cache.source(&mut |n| progress.warn(n));
    let scene = crate::cli::args::run_alone(scene.clone());
    let result = run_carried_sine(&scene, &beds, test, plan, &mut |p| progress.update(p))
        .context("the stepped sine up and down")?;
    progress.finish();
    report(&result, test);
    result
        .write(out, test)
        .with_context(|| format!("writing into {}", out.display()))?;
    println!("wrote {}", out.display());
    Ok(())
}

fn report(r: &CarriedSineResult, test: &HostTest) {
    println!(
        "{} on {}, {} N stepped sine up and down in one run: {} steps of {} + {} cycles, {:.1} s wall",
        test.damper.label(),
        test.host.name,
        r.plan.force_n,
        r.points.len(),
        r.plan.settle_cycles,
        r.plan.record_cycles,
        r.wall_time_s
    );
    println!("  branch  freq_hz  |X|/F mm/N  Gamma   damper W (power input)   truth W");
    for c in &r.points {
        let p = &c.point;
        println!(
            "  {:6}  {:7.2}  {:10.4}  {:5.2}  {:9.5} +- {:8.5}  {:9.5}{}",
            c.branch.as_str(),
            p.freq_hz,
            p.receptance().norm() * 1e3,
            p.gamma,
            p.damper_power_w,
            p.damper_power_stderr_w,
            p.true_damper_w,
            if p.steady { "" } else { "  not steady" }
        );
    }
    let pairs = r.pairs();
    let apart: Vec<String> = pairs
        .iter()
        .filter(|p| p.apart)
        .map(|p| {
            format!(
                "{} Hz ({:+.1} +- {:.1} %, Gamma {:.1} up, {:.1} down)",
                p.freq_hz,
                100.0 * p.down_over_up_minus_1,
                100.0 * p.stderr,
                p.up_gamma,
                p.down_gamma
            )
        })
        .collect();
    let unknown = pairs.iter().filter(|p| p.from_spread).count();
    if apart.is_empty() {
        println!(
            "  the branches do not stand apart: at no frequency are the amplitudes going up and coming down more than {BRANCHES_APART_SIGMA} combined standard errors apart (the records' errors, from their periods)"
        );
    } else {
        println!(
            "  hysteresis: the branches stand more than {BRANCHES_APART_SIGMA} combined standard errors apart at {}",
            apart.join(", ")
        );
    }
    if unknown > 0 {
        println!(
            "  at {unknown} of {} frequencies a record's periods are correlated over about its length (the host beats): its error there is the periods' spread, a cautious one",
            pairs.len()
        );
    }
    let top = r
        .branch(Branch::Up)
        .map(|c| c.point.gamma)
        .fold(0.0, f64::max);
    println!("  highest Gamma going up {top:.1}");
    for w in r.warnings() {
        eprintln!("warning: {w}");
    }
}
