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
//! 20 Hz Γ 7): 80 Hz Γ 9, 80 Hz Γ 10 and 80 Hz Γ 28. Each run's z-score is
//! taken twice, for the DEM's energy per cycle and the measured one (Yang's
//! method): against the mean of all runs, `(x_i − mean) / (+-)_i · √(n / (n
//! − 1))` (the factor undoes the shrinkage of a deviation from a mean that
//! includes the run itself), which asks whether the +- holds how far runs
//! scatter; and against a long-run reference, twelve beds driven 800 cycles
//! and averaged over their last 400, `(x_i − ref) / √((+-)_i² + (+-)_ref²)`,
//! which also asks whether the runs sit where a bed driven on sits (a slow
//! creep common to every bed shows here and not in the first). An honest
//! one-sigma +- gives z-scores spread by about 1 (about the runs' mean; about
//! zero, the rms, against the reference) and about 68 % of them within 1
//! (the bands the test asks are at
//! [`the_printed_error_covers_independent_runs_where_nobody_tuned`]).
//!
//! Long (about two and three quarter hours on 2 cores: at 80 Hz, Γ 9 the
//! runs drive to their cap of 400 cycles, about 4 minutes each, and each
//! reference takes about 15), so ignored by `cargo test`; run it with
//!
//! ```sh
//! cargo test --release --test coverage -- --ignored --nocapture
//! ```
//!
//! The figures it printed are in `docs/accuracy.md` ("Coverage"). On
//! 2026-11-28 the runs' z-scores passed against their mean (sd 1.19 and
//! 1.16) and failed against the 800-cycle references (rms 1.89 and 1.87;
//! 2.60 at Γ 28): the beds change by 1-1.5 % over hundreds of cycles, which
//! the printed +- does not carry yet.

use vlab::experiment::bed_cache::BedSource;
use vlab::experiment::ensemble::{DEFAULT_BEDS, unsteady_reasons};
use vlab::experiment::shake_plan::{ShakePlan, ShakeRequest};
use vlab::scene::{CyclesSpec, Scene};
use vlab::stats::mean_std;

/// Runs per condition, and the first run's seed.
const RUNS: u64 = 12;
const FIRST_SEED: u64 = 601;

/// The long-run reference: beds, seed, cycles driven, cycles averaged.
const REFERENCE_BEDS: u32 = 12;
const REFERENCE_SEED: u64 = 902;
const REFERENCE_CYCLES: u32 = 800;
const REFERENCE_WINDOW: u32 = 400;

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
    ensemble(Scene::thesis(), seed, freq_hz, gamma, DEFAULT_BEDS)
}

/// The long-run reference at a condition: [`REFERENCE_BEDS`] beds (seed
/// [`REFERENCE_SEED`]) driven [`REFERENCE_CYCLES`] cycles each, the figure
/// their last [`REFERENCE_WINDOW`] cycles' (`vlab shake --beds 12 --seed 902
/// --cycles 800 --steady-cycles 400`).
fn reference(freq_hz: f64, gamma: f64) -> Run {
    let mut scene = Scene::thesis();
    scene.drive.cycles = CyclesSpec::Count(REFERENCE_CYCLES);
    scene.drive.steady_cycles = REFERENCE_WINDOW;
    ensemble(scene, REFERENCE_SEED, freq_hz, gamma, REFERENCE_BEDS)
}

fn ensemble(mut scene: Scene, seed: u64, freq_hz: f64, gamma: f64, beds: u32) -> Run {
    scene.simulation.seed = seed;
    // The default command's plan: `vlab shake --freq F --gamma G --seed N`.
    let mut request = ShakeRequest::new(scene, freq_hz, gamma);
    request.beds = beds;
    let e = ShakePlan::new(request)
        .expect("a valid request")
        .run(
            &BedSource::Settle,
            rayon::current_num_threads(),
            &mut [],
            &mut |_| {},
        )
        .expect("the job runs");
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

/// The runs' z-scores against a reference `(value, +-)`, both errors in
/// the denominator: a bias common to the runs shows here, not in
/// [`z_scores`].
fn z_against(values: &[(f64, f64)], reference: (f64, f64)) -> Vec<f64> {
    values
        .iter()
        .map(|(x, pm)| (x - reference.0) / pm.hypot(reference.1))
        .collect()
}

/// The z-scores of one condition's runs, DEM and measured, against the
/// runs' mean and against the long-run reference.
struct ConditionZ {
    dem: Vec<f64>,
    measured: Vec<f64>,
    dem_vs_reference: Vec<f64>,
    measured_vs_reference: Vec<f64>,
}

/// The z-scores of the runs at one condition, printed as they go with the
/// condition's own figures and its long-run reference.
fn condition(freq_hz: f64, gamma: f64) -> ConditionZ {
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
    let reference = reference(freq_hz, gamma);
    println!(
        "{freq_hz} Hz, Gamma {gamma}, reference ({REFERENCE_BEDS} beds, seed {REFERENCE_SEED}, cycles {}-{REFERENCE_CYCLES}): DEM {:.5e} +- {:.2e} J, measured {:.5e} +- {:.2e} J",
        REFERENCE_CYCLES - REFERENCE_WINDOW + 1,
        reference.dem.0,
        reference.dem.1,
        reference.measured.0,
        reference.measured.1,
    );
    let mut out = Vec::new();
    for (what, values, against) in [
        (
            "DEM",
            runs.iter().map(|r| r.dem).collect::<Vec<_>>(),
            reference.dem,
        ),
        (
            "measured",
            runs.iter().map(|r| r.measured).collect(),
            reference.measured,
        ),
    ] {
        let zs = z_scores(&values);
        let means: Vec<f64> = values.iter().map(|v| v.0).collect();
        let m = mean_std(&means);
        let mean_pm = values.iter().map(|v| v.1).sum::<f64>() / values.len() as f64;
        let zr = z_against(&values, against);
        println!(
            "{freq_hz} Hz, Gamma {gamma}, {what}: {RUNS} runs of {DEFAULT_BEDS} beds (seeds {FIRST_SEED}-{}), mean {:.4e} J ({:+.2} % vs the reference), runs spread {:.2} %, mean +- {:.2} %, z sd {:.2}, |z| <= 1 in {} of {RUNS}; against the reference rms z {:.2}, |z| <= 1 in {}",
            FIRST_SEED + RUNS - 1,
            m.mean,
            100.0 * (m.mean / against.0 - 1.0),
            100.0 * m.std / m.mean,
            100.0 * mean_pm / m.mean,
            mean_std(&zs).std,
            zs.iter().filter(|z| z.abs() <= 1.0).count(),
            rms(&zr),
            zr.iter().filter(|z| z.abs() <= 1.0).count(),
        );
        out.push((zs, zr));
    }
    let cycles: Vec<u32> = runs.iter().map(|r| r.cycles).collect();
    let steady = runs.iter().filter(|r| r.steady).count();
    println!("{freq_hz} Hz, Gamma {gamma}: cycles {cycles:?}, {steady} of {RUNS} shown steady");
    let (measured, measured_vs_reference) = out.pop().expect("two series");
    let (dem, dem_vs_reference) = out.pop().expect("two series");
    ConditionZ {
        dem,
        measured,
        dem_vs_reference,
        measured_vs_reference,
    }
}

/// The root mean square: the spread of z-scores about zero, a common
/// bias included.
fn rms(zs: &[f64]) -> f64 {
    (zs.iter().map(|z| z * z).sum::<f64>() / zs.len().max(1) as f64).sqrt()
}

/// Whether z-scores look like those of an honest one-sigma error: their
/// standard deviation within `sd_band` and between `within.0` and
/// `within.1` of them within 1.
/// What z-scores were taken against, and so what their spread is about.
#[derive(Clone, Copy)]
enum Centre {
    /// The runs' own mean: the spread about the z-scores' mean.
    RunsMean,
    /// A long-run reference: the spread about zero (the rms), a bias common
    /// to the runs included.
    Reference,
}

fn judge(
    what: &str,
    centre: Centre,
    zs: &[f64],
    sd_band: std::ops::RangeInclusive<f64>,
    within: (usize, usize),
) -> Option<String> {
    let sd = match centre {
        Centre::RunsMean => mean_std(zs).std,
        Centre::Reference => rms(zs),
    };
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
/// 36 runs' z-scores together (DEM and measured apart, against the runs'
/// mean and against the long-run reference) spread within 0.75-1.35 with 18
/// to 31 within 1 (the binomial's 98 % range about
/// 68.3 %); each condition's 12 within 0.5-2.3, what an honest six-bed
/// error gives 99 % of the time (simulated), so that no condition hides in
/// the pool. An honest error passes the pooled band about 5 times in 6
/// (Student's t on 5 degrees of freedom has long tails; simulated), one
/// 1.5 times too small about 1 in 10.
#[test]
#[ignore = "about two and three quarter hours on 2 cores; run with --ignored"]
fn the_printed_error_covers_independent_runs_where_nobody_tuned() {
    let mut problems = Vec::new();
    let mut pooled: [(&str, Centre, Vec<f64>); 4] = [
        ("DEM", Centre::RunsMean, Vec::new()),
        ("measured", Centre::RunsMean, Vec::new()),
        ("DEM against the reference", Centre::Reference, Vec::new()),
        (
            "measured against the reference",
            Centre::Reference,
            Vec::new(),
        ),
    ];
    for (freq_hz, gamma) in [(80.0, 9.0), (80.0, 10.0), (80.0, 28.0)] {
        let c = condition(freq_hz, gamma);
        let series = [
            c.dem,
            c.measured,
            c.dem_vs_reference,
            c.measured_vs_reference,
        ];
        for ((what, centre, pool), zs) in pooled.iter_mut().zip(series) {
            let label = format!("{freq_hz} Hz, Gamma {gamma}, {what}");
            problems.extend(judge(&label, *centre, &zs, 0.5..=2.3, (0, zs.len())));
            pool.extend(zs);
        }
    }
    for (what, centre, zs) in &pooled {
        problems.extend(judge(
            &format!("all three, {what}"),
            *centre,
            zs,
            0.75..=1.35,
            (18, 31),
        ));
    }
    assert!(problems.is_empty(), "{problems:?}");
}
