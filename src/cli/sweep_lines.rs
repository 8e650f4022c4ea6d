//! How a running sweep reads on the console: its events on the progress
//! line ([`EventLines`]), a finished condition's result, an error that is
//! not known, the time left. Shared by `vlab sweep` and `vlab sweep
//! --up-down`.

use vlab::study::sweep::{RowStatus, Shard, Steady, SweepEvent, SweepRow, phase_name};

use super::progress::ProgressLine;

/// How the sweep's events read on the progress line.
pub struct EventLines {
    pub shard: Shard,
    pub with_fill: bool,
    pub with_orientation: bool,
}

impl EventLines {
    /// Shows `e` on `progress`.
    pub fn show(&self, e: SweepEvent, progress: &mut ProgressLine) {
        match e {
            SweepEvent::Started {
                total,
                already_done,
                beds,
            } => progress.note(&format!(
                "sweep{}: {total} conditions, {already_done} already in sweep.csv, {beds} bed{} to settle",
                if self.shard == Shard::ALL {
                    String::new()
                } else {
                    format!(" shard {}", self.shard)
                },
                if beds == 1 { "" } else { "s" }
            )),
            SweepEvent::BedSettled {
                seed,
                wall_time_s,
                from_cache,
                warnings,
            } => {
                for w in warnings {
                    progress.warn(&format!("sweep: warning: {w}"));
                }
                progress.note(&if from_cache {
                    format!("sweep: bed of seed {seed} read from the cache ({wall_time_s:.1} s)")
                } else {
                    format!("sweep: bed of seed {seed} settled ({wall_time_s:.0} s)")
                })
            }
            SweepEvent::ConditionDone {
                row,
                done,
                total,
                eta_s,
            } => progress.note(&format!(
                "sweep: {done}/{total}  {}: {}; ETA {}",
                row.condition
                    .describe(self.with_fill, self.with_orientation),
                outcome(row),
                eta(eta_s)
            )),
        }
    }
}

/// A finished condition's result, for its progress line.
fn outcome(row: &SweepRow) -> String {
    match row.status {
        RowStatus::Ok => format!(
            "efficiency {:.3} +- {}, measured {:.3}, {} ({} cycles{}, {:.0} s)",
            row.efficiency,
            plus_minus(row.efficiency_se),
            row.efficiency_measured,
            phase_name(row.phase),
            row.cycles,
            if row.steady == Some(Steady::Capped) {
                ", NOT steady at the cap"
            } else {
                ""
            },
            row.wall_time_s
        ),
        RowStatus::Unreachable => "beyond the rig".into(),
        RowStatus::Failed => format!("FAILED: {}", row.note),
    }
}

/// A one-sigma error as printed: "n/a" when there is none (a window of
/// fewer than 16 cycles has no error estimate; JSON and CSV keep it empty).
pub fn plus_minus(se: f64) -> String {
    if se.is_finite() {
        format!("{se:.3}")
    } else {
        "not known".into()
    }
}

fn eta(s: f64) -> String {
    if !s.is_finite() {
        "?".into()
    } else if s < 90.0 {
        format!("{s:.0} s")
    } else if s < 5400.0 {
        format!("{:.0} min", s / 60.0)
    } else {
        format!("{:.1} h", s / 3600.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// An efficiency without an error estimate (one seed, a window under 16
    /// cycles) prints "not known", never "NaN"; one with an estimate prints
    /// it.
    #[test]
    fn an_error_that_is_not_known_prints_as_not_known() {
        assert_eq!(plus_minus(f64::NAN).trim(), "not known");
        assert_eq!(plus_minus(0.0123), "0.012");
    }
}
