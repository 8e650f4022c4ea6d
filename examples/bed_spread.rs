//! How far apart independent beds of one damper are, against how far each
//! run's own +- says it can be: the thesis damper poured with seeds 1..N,
//! each driven for a fixed number of cycles through the thesis rig, and the
//! DEM's energy per cycle averaged over windows of cycles.
//!
//! ```sh
//! cargo run --release --example bed_spread -- 16 40 20 40
//! ```
//! (seeds, frequency in Hz, Gamma, cycles; about 25 s a seed on 2 cores).
//! For each window it prints the mean over the seeds, the spread of the
//! seeds' means (standard deviation, % of the mean) and the mean of the runs'
//! own standard errors (`vlab::stats::mean_stderr`, % of the mean): an honest
//! +- makes the two about equal.

use std::error::Error;

use vlab::drive::Drive;
use vlab::experiment::measurement::{CalibrationSource, ShakeSetup};
use vlab::experiment::shake::{resolve_rig, run_shake};
use vlab::scene::{CyclesSpec, Scene};
use vlab::stats::{mean_std, mean_stderr};

fn arg<T: std::str::FromStr>(args: &[String], i: usize, name: &str) -> Result<T, String> {
    args.get(i)
        .ok_or(format!(
            "usage: bed_spread SEEDS FREQ_HZ GAMMA CYCLES (missing {name})"
        ))?
        .parse()
        .map_err(|_| format!("{name} = {:?} is not a number", args[i]))
}

/// The DEM energy dissipated in each cycle of one seed's drive (J).
fn cycle_energies(seed: u64, drive: &Drive, cycles: u32) -> Result<Vec<f64>, Box<dyn Error>> {
    let mut scene = Scene::thesis();
    scene.simulation.seed = seed;
    scene.drive.cycles = CyclesSpec::Count(cycles);
    scene.drive.steady_cycles = cycles.saturating_sub(3).max(2);
    let rig = resolve_rig("thesis-shaker", None, drive)?;
    let setup = ShakeSetup {
        rig,
        drive: *drive,
        noise_seed: seed,
        calibration: CalibrationSource::OnTheFly,
    };
    let run = run_shake(&scene, &setup, &mut |_| {})?;
    Ok(run
        .experiment
        .outcome
        .cycle_snapshots
        .windows(2)
        .map(|w| w[1].flows.dissipated.total() - w[0].flows.dissipated.total())
        .collect())
}

fn main() -> Result<(), Box<dyn Error>> {
    let args: Vec<String> = std::env::args().collect();
    let seeds: u64 = arg(&args, 1, "SEEDS")?;
    let drive = Drive::new(arg(&args, 2, "FREQ_HZ")?, arg(&args, 3, "GAMMA")?, 9.81)?;
    let cycles: u32 = arg(&args, 4, "CYCLES")?;
    if seeds < 2 || cycles < 10 {
        return Err("need at least 2 seeds and 10 cycles".into());
    }
    let mut series = Vec::new();
    for seed in 1..=seeds {
        let e = cycle_energies(seed, &drive, cycles)?;
        eprintln!("seed {seed}: {} cycles", e.len());
        series.push(e);
    }
    let n = cycles as usize;
    let windows = [(3, 10), (10, n.min(20)), (10, n), (n / 2, n)];
    println!("cycles   mean (J)   spread of the seeds   mean own +-");
    for (a, b) in windows {
        if b <= a + 1 {
            continue;
        }
        let means: Vec<f64> = series.iter().map(|e| mean_std(&e[a..b]).mean).collect();
        let own: Vec<f64> = series
            .iter()
            .map(|e| mean_stderr(&e[a..b]).stderr_or_nan())
            .collect();
        let m = mean_std(&means);
        println!(
            "{:>2}-{:<2}    {:.5}    {:.2} %                {:.2} %",
            a + 1,
            b,
            m.mean,
            100.0 * m.std / m.mean,
            100.0 * mean_std(&own).mean / m.mean
        );
    }
    Ok(())
}
