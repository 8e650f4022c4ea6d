//! What one join of two threads costs on this machine, with and without a
//! serial stretch between the joins: rayon's `join` against a persistent
//! helper thread that waits for its next piece of work at a spin barrier.
//!
//! A step of a mid-size bed (5 000 spheres, 130-250 µs on two threads) has
//! three parallel phases with serial work between them. rayon's idle
//! workers spin for a short while and then sleep; a join that finds its
//! worker asleep pays for waking it. This example times `pairs` rounds of
//! two equal pieces of work (`work` units each, about 9 ns a unit) with a
//! serial stretch of `gap` units after each round, three ways: serially,
//! with `rayon::join` on a pool of two, and with one persistent helper
//! thread (spin, then yield) that the main thread releases and waits for.
//! The overhead printed is each parallel round's time less the ideal
//! (half the pair of pieces plus the gap).
//!
//! ```sh
//! cargo run --release --example fork_join_latency -- 2000 0
//! cargo run --release --example fork_join_latency -- 2000 2000
//! ```
//!
//! Measured in `docs/performance.md` ("Large beds ordered in space").

use std::hint::black_box;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::time::Instant;

/// A piece of floating-point work of `units` dependent steps.
fn work(units: usize) -> f64 {
    let mut x = 1.0_f64;
    for i in 0..units {
        x = (x * 1.000_001 + i as f64 * 1e-9).sqrt() + 0.5;
    }
    x
}

/// Microseconds per round of `rounds` calls of `round`.
fn per_round_us(rounds: usize, mut round: impl FnMut(usize)) -> f64 {
    let started = Instant::now();
    for k in 0..rounds {
        round(k);
    }
    started.elapsed().as_secs_f64() / rounds as f64 * 1e6
}

/// One helper thread that runs `work(units)` each time the epoch moves and
/// counts what it finished; spins, then yields while it waits.
struct SpinTeam {
    epoch: Arc<AtomicUsize>,
    done: Arc<AtomicUsize>,
    stop: Arc<AtomicBool>,
    helper: Option<std::thread::JoinHandle<()>>,
}

impl SpinTeam {
    fn start(units: usize) -> SpinTeam {
        let epoch = Arc::new(AtomicUsize::new(0));
        let done = Arc::new(AtomicUsize::new(0));
        let stop = Arc::new(AtomicBool::new(false));
        let (e, d, s) = (epoch.clone(), done.clone(), stop.clone());
        let helper = std::thread::spawn(move || {
            let mut seen = 0;
            loop {
                let mut spins = 0_u64;
                while e.load(Ordering::Acquire) == seen {
                    if s.load(Ordering::Relaxed) {
                        return;
                    }
                    std::hint::spin_loop();
                    spins += 1;
                    if spins > 1 << 22 {
                        std::thread::yield_now();
                    }
                }
                seen += 1;
                black_box(work(units));
                d.fetch_add(1, Ordering::Release);
            }
        });
        SpinTeam {
            epoch,
            done,
            stop,
            helper: Some(helper),
        }
    }

    /// Releases the helper for round `k` (from 0), does the main thread's
    /// piece, and waits for the helper's.
    fn round(&self, k: usize, units: usize) {
        self.epoch.fetch_add(1, Ordering::Release);
        black_box(work(units));
        while self.done.load(Ordering::Acquire) < k + 1 {
            std::hint::spin_loop();
        }
    }
}

impl Drop for SpinTeam {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(h) = self.helper.take() {
            let _ = h.join();
        }
    }
}

fn arg(position: usize, name: &str, default: usize) -> Result<usize, String> {
    match std::env::args().nth(position) {
        None => Ok(default),
        Some(a) => a
            .parse()
            .map_err(|_| format!("{name} = {a}: must be a whole number of work units (0 or more)")),
    }
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let units = arg(1, "work", 2000)?;
    let gap = arg(2, "gap", 0)?;
    let rounds = 20_000;
    let serial = per_round_us(rounds, |_| {
        black_box(work(units));
        black_box(work(units));
        black_box(work(gap));
    });
    let gap_us = per_round_us(rounds, |_| {
        black_box(work(gap));
    });
    let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build()?;
    let joined = pool.install(|| {
        per_round_us(rounds, |_| {
            rayon::join(|| black_box(work(units)), || black_box(work(units)));
            black_box(work(gap));
        })
    });
    let team = SpinTeam::start(units);
    let spun = per_round_us(rounds, |k| {
        team.round(k, units);
        black_box(work(gap));
    });
    drop(team);
    let ideal = (serial - gap_us) / 2.0 + gap_us;
    println!(
        "work {units} units a piece, gap {gap} units ({gap_us:.1} us): serial {serial:.1} us a round, ideal on 2 threads {ideal:.1} us; rayon::join {joined:.1} us (overhead {:.1} us), spin team {spun:.1} us (overhead {:.1} us)",
        joined - ideal,
        spun - ideal
    );
    Ok(())
}
