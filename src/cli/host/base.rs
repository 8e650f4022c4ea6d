//! `vlab host base`: the host on the rig's shaker table, a stepped sine of
//! the table's acceleration in one run, each step's transmissibility and
//! the power the table put in against what was dissipated
//! ([`vlab::experiment::host_test::transmissibility`] does the work).

use std::path::PathBuf;

use anyhow::{Context, Result};
use clap::Args;

use vlab::atomic_write::OutputDir;
use vlab::experiment::host_test::HostTest;
use vlab::experiment::host_test::transmissibility::{TableSine, TableSineResult, run_table_sine};
use vlab::host::Excitation;

use super::{FreqList, HostTestArgs, damper_slug};
use crate::cli::progress::ProgressLine;

#[derive(Debug, Clone, Args)]
#[command(allow_negative_numbers = true)]
pub struct BaseArgs {
    #[command(flatten)]
    common: HostTestArgs,
    /// The frequencies (Hz), FROM:TO:STEP or a comma-separated list.
    #[arg(long = "freq", value_name = "LIST", value_parser = super::parse_freqs)]
    freqs: FreqList,
    /// The table's acceleration amplitude (m/s^2), held at every frequency
    /// as a sine controller holds it.
    #[arg(long = "accel-mps2", value_name = "A", default_value = "10")]
    accel_mps2: f64,
    /// Cycles to settle at each frequency.
    #[arg(long = "settle-cycles", value_name = "N", default_value = "30")]
    settle_cycles: u32,
    /// Cycles measured at each frequency.
    #[arg(long = "record-cycles", value_name = "N", default_value = "20")]
    record_cycles: u32,
    /// Come back down the frequencies after going up, the state carried.
    #[arg(long)]
    down: bool,
    /// Output folder [default: signals/host-base-<host>-<damper>].
    #[arg(long, value_name = "DIR")]
    out: Option<PathBuf>,
}

/// The plan and the test of the flags, checked before any bed is poured;
/// a refusal names the flag.
fn plan_and_test(a: &BaseArgs) -> Result<(vlab::scene::Scene, HostTest, TableSine)> {
    let plan = TableSine {
        freqs_hz: a.freqs.0.clone(),
        table_accel_mps2: a.accel_mps2,
        settle_cycles: a.settle_cycles,
        record_cycles: a.record_cycles,
        down: a.down,
    };
    plan.validate().map_err(|e| {
        let flag = match e.key.as_str() {
            "table_accel_mps2" => "--accel-mps2",
            "settle_cycles" => "--settle-cycles",
            "record_cycles" => "--record-cycles",
            _ => "--freq",
        };
        anyhow::Error::from(e.renamed(flag))
    })?;
    let first = Excitation::Sine {
        freq_hz: plan.freqs_hz[0],
        force_n: plan.table_accel_mps2,
    };
    let (scene, mut test) = a.common.test(first, 1.0)?;
    test.on_base = true;
    test.check()
        .map_err(|e| anyhow::Error::from(e).context(format!("--host {}", a.common.host)))?;
    Ok((scene, test, plan))
}

pub fn run(a: BaseArgs, quiet: bool) -> Result<()> {
    let (scene, test, plan) = plan_and_test(&a)?;
    let out = a.out.clone().unwrap_or_else(|| {
        PathBuf::from("signals").join(format!(
            "host-base-{}-{}",
            test.host.name,
            damper_slug(test.damper)
        ))
    });
    let made = OutputDir::prepare(&out)
        .with_context(|| format!("cannot create output folder {}", out.display()))?;
    let mut progress = ProgressLine::new("host base", quiet);
    let beds = a.common.cache.source(&mut |n| progress.warn(n));
    let scene = crate::cli::args::run_alone(scene);
    let result = made.keep_if_ok(
        run_table_sine(&scene, &beds, &test, &plan, &mut |p| progress.update(p))
            .context("the stepped sine on the table"),
    )?;
    progress.finish();
    report(&result, &test);
    made.keep_if_ok(
        result
            .write(&out, &test)
            .with_context(|| format!("writing into {}", out.display())),
    )?;
    println!("wrote {}", out.display());
    Ok(())
}

fn report(r: &TableSineResult, test: &HostTest) {
    println!(
        "{} on {} on the shaker's table, {} m/s^2 stepped sine in one run: {} steps of {} + {} cycles, {:.1} s wall",
        test.damper.label(),
        test.host.name,
        r.plan.table_accel_mps2,
        r.points.len(),
        r.plan.settle_cycles,
        r.plan.record_cycles,
        r.wall_time_s
    );
    println!("  branch  freq_hz  |T| (A_damper/A_table)   exact  Gamma   power in W  dissipated W");
    for p in &r.points {
        let exact = p
            .exact_re
            .zip(p.exact_im)
            .map_or("      -".to_string(), |(re, im)| {
                format!("{:7.4}", re.hypot(im))
            });
        println!(
            "  {:6}  {:7.2}  {:9.4} +- {:8.4}  {exact}  {:5.2}  {:10.5}  {:10.5}{}",
            p.branch.as_str(),
            p.freq_hz,
            p.magnitude,
            p.magnitude_stderr,
            p.gamma,
            p.power_in_w,
            p.true_dissipated_w,
            if p.steady { "" } else { "  not steady" }
        );
    }
    for w in &r.warnings {
        eprintln!("warning: {}", w.text);
    }
}
