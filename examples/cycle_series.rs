//! The per-cycle series behind every +- vlab prints, for independent beds:
//! the thesis damper poured with seeds FIRST..=LAST, driven for CYCLES cycles
//! through the thesis rig, and for each cycle the DEM's dissipated energy and
//! the enclosure's work (J), and from cycle 3 on the energy Yang's method
//! measures on that period of the record (J).
//!
//! ```sh
//! cargo run --release --example cycle_series -- 1 16 40 20 100 series.csv
//! ```
//! (first and last seed, frequency in Hz, Gamma, cycles, output CSV). The
//! rows are what `docs/accuracy.md` studies the estimators and the steady
//! rule on.

use std::error::Error;
use std::io::Write;

use vlab::drive::Drive;
use vlab::experiment::measurement::{CalibrationSource, ShakeSetup, period_powers};
use vlab::experiment::shake::{resolve_rig, run_shake};
use vlab::scene::{CyclesSpec, Scene};
use vlab::signals::ForcePolarity;

fn arg<T: std::str::FromStr>(args: &[String], i: usize, name: &str) -> Result<T, String> {
    args.get(i)
        .ok_or(format!(
            "usage: cycle_series FIRST LAST FREQ_HZ GAMMA CYCLES OUT.csv (missing {name})"
        ))?
        .parse()
        .map_err(|_| format!("{name} = {:?} is not valid", args[i]))
}

fn main() -> Result<(), Box<dyn Error>> {
    let args: Vec<String> = std::env::args().collect();
    let first: u64 = arg(&args, 1, "FIRST")?;
    let last: u64 = arg(&args, 2, "LAST")?;
    let drive = Drive::new(arg(&args, 3, "FREQ_HZ")?, arg(&args, 4, "GAMMA")?, 9.81)?;
    let cycles: u32 = arg(&args, 5, "CYCLES")?;
    let out: String = arg(&args, 6, "OUT")?;
    if cycles < 4 {
        return Err("need at least 4 cycles".into());
    }
    let unrecorded = 2;
    let mut rows = String::from("seed,cycle,dem_j,work_in_j,measured_j\n");
    for seed in first..=last {
        let mut scene = Scene::thesis();
        scene.simulation.seed = seed;
        scene.drive.cycles = CyclesSpec::Count(cycles);
        scene.drive.steady_cycles = cycles - unrecorded;
        let rig = resolve_rig("thesis-shaker", None, &drive)?;
        let setup = ShakeSetup {
            rig,
            drive,
            noise_seed: seed,
            calibration: CalibrationSource::OnTheFly,
        };
        let run = run_shake(&scene, &setup, &mut |_| {})?;
        let exp = &run.experiment;
        let polarity = if exp.measured.force_polarity_reversed {
            ForcePolarity::Reversed
        } else {
            ForcePolarity::AsRecorded
        };
        let measured = period_powers(&exp.trace, drive.freq_hz(), &exp.calibration, polarity)?;
        for (c, w) in exp.outcome.cycle_snapshots.windows(2).enumerate() {
            let dem = w[1].flows.dissipated.total() - w[0].flows.dissipated.total();
            let work = w[1].flows.work_in_j - w[0].flows.work_in_j;
            let m = c
                .checked_sub(unrecorded as usize)
                .and_then(|k| measured.get(k))
                .map_or(String::new(), |p| format!("{:e}", p / drive.freq_hz()));
            rows.push_str(&format!("{seed},{},{dem:e},{work:e},{m}\n", c + 1));
        }
        eprintln!(
            "seed {seed}: {} cycles, {} periods measured",
            exp.outcome.cycles,
            measured.len()
        );
        std::fs::File::create(&out)?.write_all(rows.as_bytes())?;
    }
    Ok(())
}
