//! `vlab sweep --up-down`: the sweep in Γ up and back down with the bed
//! carried from each condition to the next; the work is
//! [`vlab::study::sweep_updown`]'s, this prints and files it.

use std::path::PathBuf;
use std::sync::Mutex;

use anyhow::{Context, Result, bail};

use vlab::atomic_write::OutputDir;
use vlab::study::sweep::{Shard, SweepEvent, SweepPlan, phase_name};
use vlab::study::sweep_plot::plot_sweep;
use vlab::study::sweep_updown::{APART_SIGMAS, UpDownSweep, run_up_down};

use super::progress::ProgressLine;
use super::sweep_lines::{EventLines, plus_minus};

/// Runs `plan` up and down, writes both branches and their comparison into
/// `out` (refused if it holds a carried sweep already) and prints where
/// the branches part.
pub fn run(out: Option<PathBuf>, plan: &SweepPlan, quiet: bool) -> Result<()> {
    let out_dir =
        out.unwrap_or_else(|| PathBuf::from("signals").join(format!("updown-{}", plan.scene.name)));
    if out_dir.join("updown.csv").exists() {
        bail!(
            "{} exists: choose another --out",
            out_dir.join("updown.csv").display()
        );
    }
    let made = OutputDir::prepare(&out_dir)
        .with_context(|| format!("cannot create output folder {}", out_dir.display()))?;
    let progress = Mutex::new(ProgressLine::new("sweep", quiet));
    let events = EventLines {
        shard: Shard::ALL,
        with_fill: plan.fill_ratios.len() > 1,
        with_orientation: plan.orientations.len() > 1,
    };
    let on_event = |e: SweepEvent| {
        let mut p = progress.lock().unwrap_or_else(|e| e.into_inner());
        match e {
            SweepEvent::Started { total, beds, .. } => p.note(&format!(
                "sweep up and down: {total} runs in {beds} chain{} of one bed each, the bed carried from run to run",
                if beds == 1 { "" } else { "s" }
            )),
            e => events.show(e, &mut p),
        }
    };
    let result = run_up_down(plan, &on_event)
        .and_then(|s| s.write(&out_dir).map(|()| s))
        .context("running the sweep up and down");
    let sweep = made.keep_if_ok(result)?;
    for branch in ["up", "down"] {
        let file = if branch == "up" {
            &sweep.up
        } else {
            &sweep.down
        };
        plot_sweep(file, &out_dir.join(branch))
            .with_context(|| format!("drawing the {branch} branch's plots"))?;
    }
    report(&sweep);
    println!(
        "wrote {}: up/sweep.csv, down/sweep.csv (each a sweep file, usable as a --map), updown.csv",
        out_dir.display()
    );
    Ok(())
}

/// Each condition both branches ran: the two efficiencies and whether they
/// are apart.
fn report(sweep: &UpDownSweep) {
    println!(
        "up and down in Gamma, the bed carried ({} conditions on both branches):",
        sweep.pairs().len()
    );
    println!(
        "  freq_hz  seed  Gamma   up efficiency (phase)          down efficiency (phase)        down - up"
    );
    let mut apart = 0;
    for p in sweep.pairs() {
        let c = &p.up.condition;
        let z = p.z();
        if p.apart() {
            apart += 1;
        }
        println!(
            "  {:7} {:5} {:6}   {:.3} +- {:<14}    {:<24}  {:.3} +- {:<14}    {:<24}  {:+.3}{}",
            c.freq_hz,
            c.seed,
            c.gamma,
            p.up.efficiency,
            plus_minus(p.up.efficiency_se),
            phase_name(p.up.phase),
            p.down.efficiency,
            plus_minus(p.down.efficiency_se),
            phase_name(p.down.phase),
            p.difference(),
            if p.apart() {
                format!("  APART ({z:+.1} sigma)")
            } else if z.is_finite() {
                format!("  ({z:+.1} sigma)")
            } else {
                "  (+- not known)".into()
            }
        );
    }
    println!(
        "  {apart} condition{} apart by more than {APART_SIGMAS} sigma (the top of each chain is one run, on both branches)",
        if apart == 1 { "" } else { "s" }
    );
}
