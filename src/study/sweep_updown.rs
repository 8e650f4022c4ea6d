//! A sweep in Γ up and back down with the bed carried from each amplitude
//! to the next, as a lab's controller steps a shaker's level: the map's two
//! branches, and where they part.
//!
//! An ordinary sweep starts every condition from the same settled bed at
//! rest, so a map built from it has one efficiency a condition whatever
//! came before. Near the onset of the bouncing bed (Terzioglu, *Granular
//! dampers*, Chapter 6: the efficiency jumps from about 0.2 to 0.9 between
//! Γ 14 and 17 at 40 Hz) the bed's state can depend on where it came from:
//! a bed already bouncing may keep bouncing below the Γ a bed at rest needs
//! to start, as the impact damper's classical jumps (Masri and Caughey)
//! would have it. Here each chain (a frequency, seed, fill ratio and
//! orientation) settles one bed, drives it at the lowest Γ, hands the bed
//! as the drive left it to the next Γ, up to the highest, and then back
//! down from there. Each branch is an ordinary sweep file (`up/sweep.csv`,
//! `down/sweep.csv`, marked `# carried:`), so a branch can stand as a map
//! (`vlab host predict --map up/sweep.csv --map down/sweep.csv` takes the
//! down branch's conditions in place of the up branch's); `updown.csv` puts
//! the branches side by side.

use std::collections::BTreeMap;
use std::path::Path;

use rayon::prelude::*;

use crate::atomic_write::write_atomic;
use crate::experiment::bed::settle::SettledBed;
use crate::study::sweep::{
    Condition, RowStatus, Shard, SweepError, SweepEvent, SweepFile, SweepPlan, SweepRow,
    fingerprint, phase_name, run_condition_carried,
};

/// How many of their combined errors two branches' efficiencies must be
/// apart to be called apart.
pub const APART_SIGMAS: f64 = 3.0;

/// A carried sweep's two branches.
#[derive(Debug, Clone, PartialEq)]
pub struct UpDownSweep {
    /// Every chain's conditions from the lowest Γ to the highest.
    pub up: SweepFile,
    /// From the highest Γ back to the lowest, the highest shared with the
    /// up branch (the same run).
    pub down: SweepFile,
}

/// One condition on both branches.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BranchPair<'a> {
    pub up: &'a SweepRow,
    pub down: &'a SweepRow,
}

impl BranchPair<'_> {
    /// Down's efficiency less up's.
    pub fn difference(&self) -> f64 {
        self.down.efficiency - self.up.efficiency
    }

    /// The difference over the branches' errors in quadrature (NaN where an
    /// error is not known).
    pub fn z(&self) -> f64 {
        self.difference() / self.up.efficiency_se.hypot(self.down.efficiency_se)
    }

    /// The branches are apart: by more than [`APART_SIGMAS`] of their
    /// errors, both rows run, both errors known.
    pub fn apart(&self) -> bool {
        self.z().abs() > APART_SIGMAS
    }
}

/// A chain's rows: up, then down.
type ChainRows = (Vec<SweepRow>, Vec<SweepRow>);

/// The header of `updown.csv`.
pub const UP_DOWN_CSV_HEADER: &str = "fill_ratio,orientation,freq_hz,gamma,seed,efficiency_up,efficiency_up_se,phase_up,efficiency_down,efficiency_down_se,phase_down,difference,z,apart";

impl UpDownSweep {
    /// The conditions both branches ran, in the up branch's order (the top
    /// of each chain too, where the two are one run).
    pub fn pairs(&self) -> Vec<BranchPair<'_>> {
        let down: BTreeMap<_, &SweepRow> = self
            .down
            .rows
            .iter()
            .map(|r| (key(&r.condition), r))
            .collect();
        self.up
            .rows
            .iter()
            .filter(|r| r.status == RowStatus::Ok)
            .filter_map(|up| {
                let down = down.get(&key(&up.condition))?;
                (down.status == RowStatus::Ok).then_some(BranchPair { up, down })
            })
            .collect()
    }

    /// `updown.csv`: a row a condition both branches ran.
    pub fn csv(&self) -> String {
        let mut out = format!("{UP_DOWN_CSV_HEADER}\n");
        for p in self.pairs() {
            let c = &p.up.condition;
            out += &format!(
                "{},{},{},{},{},{},{},{},{},{},{},{},{},{}\n",
                c.fill_ratio,
                c.orientation.as_str(),
                c.freq_hz,
                c.gamma,
                c.seed,
                p.up.efficiency,
                p.up.efficiency_se,
                phase_name(p.up.phase),
                p.down.efficiency,
                p.down.efficiency_se,
                phase_name(p.down.phase),
                p.difference(),
                p.z(),
                p.apart()
            );
        }
        out
    }

    /// Writes `up/sweep.csv`, `down/sweep.csv` and `updown.csv` into `dir`
    /// (which must exist), each atomically.
    pub fn write(&self, dir: &Path) -> Result<(), SweepError> {
        for (name, file) in [("up", &self.up), ("down", &self.down)] {
            let sub = dir.join(name);
            std::fs::create_dir_all(&sub).map_err(|source| SweepError::Write {
                path: sub.clone(),
                source,
            })?;
            file.write(&sub.join("sweep.csv"))?;
        }
        let path = dir.join("updown.csv");
        let text = self.csv();
        write_atomic(&path, |f| std::io::Write::write_all(f, text.as_bytes()))
            .map_err(|source| SweepError::Write { path, source })
    }
}

/// A condition's identity on either branch.
fn key(c: &Condition) -> (u64, &'static str, u64, u64, u64) {
    (
        c.fill_ratio.to_bits(),
        c.orientation.as_str(),
        c.freq_hz.to_bits(),
        c.seed,
        c.gamma.to_bits(),
    )
}

/// The chains of `plan`: its conditions grouped by everything but Γ, each
/// chain's Γ ascending (repeats dropped).
fn chains(plan: &SweepPlan) -> Vec<Vec<Condition>> {
    let mut by: BTreeMap<(u64, &'static str, u64, u64), Vec<Condition>> = BTreeMap::new();
    for c in plan.conditions() {
        by.entry((
            c.fill_ratio.to_bits(),
            c.orientation.as_str(),
            c.freq_hz.to_bits(),
            c.seed,
        ))
        .or_default()
        .push(c);
    }
    by.into_values()
        .map(|mut chain| {
            chain.sort_by(|a, b| a.gamma.total_cmp(&b.gamma));
            chain.dedup_by(|a, b| a.gamma.to_bits() == b.gamma.to_bits());
            chain
        })
        .collect()
}

/// Checks what a carried sweep needs besides an ordinary sweep's checks:
/// one bed a condition (the state carried is one bed's) and two Γ at least.
pub fn validate(plan: &SweepPlan) -> Result<(), SweepError> {
    plan.validate()?;
    if plan.ensemble_beds != 1 {
        return Err(SweepError::Invalid(
            crate::validation::InvalidParameter::new(
                "beds",
                f64::from(plan.ensemble_beds),
                "beds",
                "1 in a carried sweep (each chain carries one bed's state; give more seeds instead)",
            ),
        ));
    }
    let mut gammas = plan.gammas.clone();
    gammas.sort_by(f64::total_cmp);
    gammas.dedup();
    if gammas.len() < 2 {
        return Err(SweepError::Invalid(
            crate::validation::InvalidParameter::new(
                "gamma",
                gammas.len() as f64,
                "values",
                "at least 2 different Gamma to step between",
            ),
        ));
    }
    Ok(())
}

/// Runs `plan` up and back down in Γ, the chains side by side (each chain
/// in order on one thread: the same numbers whatever the thread count).
pub fn run_up_down(
    plan: &SweepPlan,
    on_event: &(dyn Fn(SweepEvent) + Sync),
) -> Result<UpDownSweep, SweepError> {
    validate(plan)?;
    let chains = chains(plan);
    let total: usize = chains.iter().map(|c| 2 * c.len() - 1).sum();
    on_event(SweepEvent::Started {
        total,
        already_done: 0,
        beds: chains.len(),
    });
    let done = std::sync::atomic::AtomicUsize::new(0);
    let started = crate::clock::Stopwatch::start();
    let finished = |row: &SweepRow| {
        let n = done.fetch_add(1, std::sync::atomic::Ordering::SeqCst) + 1;
        let elapsed = started.elapsed().as_secs_f64();
        on_event(SweepEvent::ConditionDone {
            row,
            done: n,
            total,
            eta_s: elapsed / n as f64 * (total - n) as f64,
        });
    };
    let branches: Vec<Result<ChainRows, SweepError>> = chains
        .par_iter()
        .with_max_len(1)
        .map(|chain| run_chain(plan, chain, on_event, &finished))
        .collect();
    let (mut up, mut down) = (Vec::new(), Vec::new());
    for b in branches {
        let (u, d) = b?;
        up.extend(u);
        down.extend(d);
    }
    let file = |rows: Vec<SweepRow>, branch: &str| {
        let mut header = plan.header(Shard::ALL);
        header.sweep_id = fingerprint(&format!("{}\ncarried {branch}", header.sweep_id));
        header.carried = Some(branch.to_string());
        SweepFile { header, rows }
    };
    Ok(UpDownSweep {
        up: file(up, "up"),
        down: file(down, "down"),
    })
}

/// One chain: its bed settled, driven up through `chain` (Γ ascending) and
/// back down, the bed carried from each condition to the next.
fn run_chain(
    plan: &SweepPlan,
    chain: &[Condition],
    on_event: &(dyn Fn(SweepEvent) + Sync),
    finished: &(dyn Fn(&SweepRow) + Sync),
) -> Result<ChainRows, SweepError> {
    let scene = plan.scene_for(&chain[0])?;
    let settled = plan.beds.settle(&scene, &mut |_| {})?;
    on_event(SweepEvent::BedSettled {
        seed: scene.simulation.seed,
        wall_time_s: settled.wall_time_s,
        from_cache: settled.from_cache,
        warnings: &settled.warnings,
    });
    let mut bed: SettledBed = settled;
    let mut step = |c: &Condition| {
        let (row, next) = run_condition_carried(plan, &bed, c);
        if let Some(next) = next {
            bed = next;
        }
        finished(&row);
        row
    };
    let up: Vec<SweepRow> = chain.iter().map(&mut step).collect();
    let mut down = vec![up[up.len() - 1].clone()];
    down.extend(chain[..chain.len() - 1].iter().rev().map(&mut step));
    Ok((up, down))
}
