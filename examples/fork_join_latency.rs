//! What one join of two threads costs on this machine, with and without a
//! serial stretch between the joins: rayon's `join` against a persistent
//! helper thread that waits for its next piece of work by spinning: the
//! team vlab's step runs its blocks on (`src/dem/step/team.rs`).
//!
//! A step of a mid-size bed (5 000 spheres, 130-250 µs on two threads) has
//! three parallel phases with serial work between them. rayon's idle
//! workers spin for a short while and then sleep; a join that finds its
//! worker asleep pays for waking it. This example times `pairs` rounds of
//! two equal pieces of work (`work` units each, about 9 ns a unit) with a
//! serial stretch of `gap` units after each round, three ways: serially,
//! with `rayon::join` on a pool of two, and with vlab's [`Team`] of two
//! (one persistent helper that spins, then yields, then after 2 ms sleeps;
//! the caller takes a piece too and waits for the other).
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
use std::time::Instant;

use vlab::dem::Team;

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
    let spun = {
        let mut team = Team::new(2);
        per_round_us(rounds, |_| {
            team.for_each([units, units].into_iter(), |u| {
                black_box(work(u));
            });
            black_box(work(gap));
        })
    };
    let ideal = (serial - gap_us) / 2.0 + gap_us;
    println!(
        "work {units} units a piece, gap {gap} units ({gap_us:.1} us): serial {serial:.1} us a round, ideal on 2 threads {ideal:.1} us; rayon::join {joined:.1} us (overhead {:.1} us), vlab's team {spun:.1} us (overhead {:.1} us)",
        joined - ideal,
        spun - ideal
    );
    Ok(())
}
