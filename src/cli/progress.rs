//! Progress of long runs on standard error: a line rewritten in place on a
//! terminal, an occasional line otherwise, nothing with `--quiet`; warnings
//! always.

use std::io::{IsTerminal, Write};
use std::time::Instant;

use vlab::experiment::damper::Progress;

/// Throttled progress printer.
pub struct ProgressLine {
    enabled: bool,
    terminal: bool,
    last: Option<Instant>,
    label: String,
}

impl ProgressLine {
    /// A printer labelled `label`; silent when `quiet`.
    pub fn new(label: &str, quiet: bool) -> Self {
        ProgressLine {
            enabled: !quiet,
            terminal: std::io::stderr().is_terminal(),
            last: None,
            label: label.to_string(),
        }
    }

    /// Shows `p` if enough time passed since the last line.
    pub fn update(&mut self, p: Progress) {
        if !self.enabled {
            return;
        }
        let every = if self.terminal { 0.25 } else { 5.0 };
        if self.last.is_some_and(|t| t.elapsed().as_secs_f64() < every) {
            return;
        }
        self.last = Some(Instant::now());
        let rate = if p.wall_time_s > 0.0 {
            p.particle_steps as f64 / p.wall_time_s / 1e6
        } else {
            0.0
        };
        let line = format!(
            "{}: {}  t = {:.4} s simulated  {:.1} M particle-steps/s",
            self.label,
            how_far(&p),
            p.sim_time_s,
            rate
        );
        let mut err = std::io::stderr().lock();
        if self.terminal {
            let _ = write!(err, "\r\x1b[2K{line}");
        } else {
            let _ = writeln!(err, "{line}");
        }
        let _ = err.flush();
    }

    /// Ends the progress display (clears the in-place line).
    pub fn finish(&mut self) {
        if self.enabled && self.terminal && self.last.is_some() {
            let _ = write!(std::io::stderr(), "\r\x1b[2K");
        }
    }

    /// A warning on standard error, quiet or not: `--quiet` silences
    /// progress, never what the user must know about the result.
    pub fn warn(&mut self, text: &str) {
        self.finish();
        eprintln!("{text}");
    }

    /// A note on standard error, unless quiet.
    pub fn note(&mut self, text: &str) {
        if self.enabled {
            self.finish();
            eprintln!("{text}");
        }
    }
}

/// How far a phase is, in words: a drive that runs until steady by its
/// cycles and its error so far (a percentage of the cycle cap would read as
/// a run that stopped at 6 % when it stopped because it was steady); any
/// other phase by its fraction done.
fn how_far(p: &Progress) -> String {
    if p.until_steady && p.fraction < 1.0 {
        let error = p
            .steadiness
            .and_then(|s| s.stderr_rel)
            .map_or(String::new(), |r| {
                format!("; error of the mean so far {:.2} %", 100.0 * r)
            });
        return format!("driving, cycle {} (until steady{error})", p.cycle);
    }
    format!("{} {:5.1} %", p.phase, 100.0 * p.fraction.min(1.0))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_drive_until_steady_tells_its_cycle_not_a_share_of_the_cap() {
        let p = Progress {
            phase: "driving",
            fraction: 23.0 / 400.0,
            cycle: 23,
            until_steady: true,
            ..Progress::default()
        };
        let said = how_far(&p);
        assert!(said.contains("cycle 23") && !said.contains('%'), "{said}");
        let fixed = Progress {
            until_steady: false,
            fraction: 0.5,
            ..p
        };
        assert_eq!(how_far(&fixed), "driving  50.0 %");
    }
}
