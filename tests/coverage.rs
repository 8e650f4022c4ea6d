//! Does the +- the default shake prints cover the spread of independent
//! runs, at conditions nobody tuned it to? The default job (the thesis
//! damper through the thesis rig, an ensemble of
//! `vlab::experiment::ensemble::DEFAULT_BEDS` beds run until the ensemble is
//! steady) is run 12 times with new seeds (601-612, each run's beds derived
//! from its seed) at each of three conditions drawn at random from the
//! thesis grid (20, 40, 80, 160 Hz × Γ 1-40, Γ ≤ 12 at 20 Hz; Python's
//! `random.Random(35)`, leaving out the conditions the rules were designed
//! on, 40 Hz Γ 20, 20 Hz Γ 12, 40 Hz Γ 10, 40 Hz Γ 3, 160 Hz Γ 10, and those
//! of the first draw, `random.Random(34)`, whose runs showed that a drift
//! not told from noise is not a steady bed: 80 Hz Γ 38, 20 Hz Γ 4 and
//! 20 Hz Γ 7): 80 Hz Γ 9, 80 Hz Γ 10 and 80 Hz Γ 28. None has a long-run
//! reference, so each run's z-score is taken against the mean of all runs,
//! `(x_i − mean) / (+-)_i · √(n / (n − 1))` (the factor undoes the shrinkage
//! of a deviation from a mean that includes the run itself), for the DEM's
//! energy per cycle and the measured one (Yang's method). An honest
//! one-sigma +- gives z-scores with a standard deviation of about 1 and
//! about 68 % of them within 1 (the bands the test asks are at
//! [`the_printed_error_covers_independent_runs_where_nobody_tuned`]).
//!
//! Long (about two hours on 2 cores: at 80 Hz, Γ 9 the runs drive to
//! their cap of 400 cycles, about 4 minutes each), so ignored by `cargo
//! test`; run it with
//!
//! ```sh
//! cargo test --release --test coverage -- --ignored --nocapture
//! ```
//!
//! The figures it printed are in `docs/accuracy.md` ("Coverage").

use vlab::experiment::bed_cache::BedSource;
use vlab::experiment::ensemble::{DEFAULT_BEDS, unsteady_reasons};
use vlab::experiment::shake_plan::{ShakePlan, ShakeRequest};
use vlab::scene::Scene;
use vlab::stats::mean_std;

/// Runs per condition, and the first run's seed.
const RUNS: u64 = 12;
const FIRST_SEED: u64 = 601;

/// One run's ensemble figures: DEM and measured energy per cycle with
/// their +-, the cycles it drove and whether it was shown steady.
struct Run {
    dem: (f64, f64),
    measured: (f64, f64),
    cycles: u32,
    steady: bool,
    /// Why a run was not shown steady (empty if it was).
    why: String,
}

fn run(seed: u64, freq_hz: f64, gamma: f64) -> Run {
    let mut scene = Scene::thesis();
    scene.simulation.seed = seed;
    // The default command's plan: `vlab shake --freq F --gamma G --seed N`.
    let mut request = ShakeRequest::new(scene, freq_hz, gamma);
    request.beds = DEFAULT_BEDS;
    let e = ShakePlan::new(request)
        .expect("a valid request")
        .run(
            &BedSource::Settle,
            rayon::current_num_threads(),
            &mut [],
            &mut |_| {},
        )
        .expect("the default job runs");
    let s = e.run.summary.ensemble.expect("an ensemble");
    let figure = |f: vlab::experiment::ensemble::EnsembleFigure| {
        (f.mean, f.stderr.expect("an ensemble has an error"))
    };
    Run {
        dem: figure(s.dem_energy_per_cycle_j),
        measured: figure(s.measured_energy_per_cycle_j),
        cycles: s.cycles,
        steady: s.steadiness.reached,
        why: if s.steadiness.reached {
            String::new()
        } else {
            unsteady_reasons(&s.steadiness, s.steady_first_cycle)
        },
    }
}

/// The runs' z-scores against their common mean.
fn z_scores(values: &[(f64, f64)]) -> Vec<f64> {
    let n = values.len() as f64;
    let mean = values.iter().map(|v| v.0).sum::<f64>() / n;
    values
        .iter()
        .map(|(x, pm)| (x - mean) / pm * (n / (n - 1.0)).sqrt())
        .collect()
}

/// The z-scores of the runs at one condition, DEM and measured, printed
/// as they go with the condition's own figures.
fn condition(freq_hz: f64, gamma: f64) -> (Vec<f64>, Vec<f64>) {
    let runs: Vec<Run> = (FIRST_SEED..FIRST_SEED + RUNS)
        .map(|seed| {
            let r = run(seed, freq_hz, gamma);
            println!(
                "{freq_hz} Hz, Gamma {gamma}, seed {seed}: DEM {:.5e} +- {:.2e} J, measured {:.5e} +- {:.2e} J, {} cycles, {}",
                r.dem.0,
                r.dem.1,
                r.measured.0,
                r.measured.1,
                r.cycles,
                if r.steady {
                    "steady".to_string()
                } else {
                    format!("NOT shown steady: {}", r.why)
                }
            );
            r
        })
        .collect();
    let mut out = Vec::new();
    for (what, values) in [
        ("DEM", runs.iter().map(|r| r.dem).collect::<Vec<_>>()),
        ("measured", runs.iter().map(|r| r.measured).collect()),
    ] {
        let zs = z_scores(&values);
        let means: Vec<f64> = values.iter().map(|v| v.0).collect();
        let m = mean_std(&means);
        let mean_pm = values.iter().map(|v| v.1).sum::<f64>() / values.len() as f64;
        println!(
            "{freq_hz} Hz, Gamma {gamma}, {what}: {RUNS} runs of {DEFAULT_BEDS} beds (seeds {FIRST_SEED}-{}), mean {:.4e} J, runs spread {:.2} %, mean +- {:.2} %, z sd {:.2}, |z| <= 1 in {} of {RUNS}",
            FIRST_SEED + RUNS - 1,
            m.mean,
            100.0 * m.std / m.mean,
            100.0 * mean_pm / m.mean,
            mean_std(&zs).std,
            zs.iter().filter(|z| z.abs() <= 1.0).count()
        );
        out.push(zs);
    }
    let cycles: Vec<u32> = runs.iter().map(|r| r.cycles).collect();
    let steady = runs.iter().filter(|r| r.steady).count();
    println!("{freq_hz} Hz, Gamma {gamma}: cycles {cycles:?}, {steady} of {RUNS} shown steady");
    let measured = out.pop().expect("two series");
    (out.pop().expect("two series"), measured)
}

/// Whether z-scores look like those of an honest one-sigma error: their
/// standard deviation within `sd_band` and between `within.0` and
/// `within.1` of them within 1.
fn judge(
    what: &str,
    zs: &[f64],
    sd_band: std::ops::RangeInclusive<f64>,
    within: (usize, usize),
) -> Option<String> {
    let sd = mean_std(zs).std;
    let inside = zs.iter().filter(|z| z.abs() <= 1.0).count();
    println!(
        "{what}: {} z-scores, sd {sd:.2}, |z| <= 1 in {inside}",
        zs.len()
    );
    (!sd_band.contains(&sd) || inside < within.0 || inside > within.1).then(|| {
        format!(
            "{what}: sd of z {sd:.2}, |z| <= 1 in {inside} of {}",
            zs.len()
        )
    })
}

/// The default shake's +- covers at three conditions drawn at random: the
/// 36 runs' z-scores together (DEM and measured apart) spread within
/// 0.75-1.35 with 18 to 31 within 1 (the binomial's 98 % range about
/// 68.3 %); each condition's 12 within 0.5-2.3, what an honest six-bed
/// error gives 99 % of the time (simulated), so that no condition hides in
/// the pool. An honest error passes the pooled band about 5 times in 6
/// (Student's t on 5 degrees of freedom has long tails; simulated), one
/// 1.5 times too small about 1 in 10.
#[test]
#[ignore = "about two hours on 2 cores; run with --ignored"]
fn the_printed_error_covers_independent_runs_where_nobody_tuned() {
    let mut problems = Vec::new();
    let (mut dem, mut measured) = (Vec::new(), Vec::new());
    for (freq_hz, gamma) in [(80.0, 9.0), (80.0, 10.0), (80.0, 28.0)] {
        let (d, m) = condition(freq_hz, gamma);
        for (what, zs) in [("DEM", &d), ("measured", &m)] {
            let label = format!("{freq_hz} Hz, Gamma {gamma}, {what}");
            problems.extend(judge(&label, zs, 0.5..=2.3, (0, zs.len())));
        }
        dem.extend(d);
        measured.extend(m);
    }
    problems.extend(judge("all three, DEM", &dem, 0.75..=1.35, (18, 31)));
    problems.extend(judge(
        "all three, measured",
        &measured,
        0.75..=1.35,
        (18, 31),
    ));
    assert!(problems.is_empty(), "{problems:?}");
}
