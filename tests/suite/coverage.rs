//! Does the +- the default shake prints cover the spread of independent
//! runs, at conditions nobody tuned it to? And does the allowance for a
//! longer drive printed beside it cover where the same beds end up when
//! driven on?
//!
//! **The +-** ([`the_printed_error_covers_independent_runs_where_nobody_tuned`]):
//! the default job (the thesis damper through the thesis rig, an ensemble
//! of `vlab::experiment::ensemble::DEFAULT_BEDS` beds run until the
//! ensemble is steady) is run 12 times with new seeds (601-612, each run's
//! beds derived from its seed) at each of three conditions drawn at random
//! from the thesis grid (20, 40, 80, 160 Hz × Γ 1-40, Γ ≤ 12 at 20 Hz;
//! Python's `random.Random(35)`, leaving out the conditions the rules were
//! designed on, 40 Hz Γ 20, 20 Hz Γ 12, 40 Hz Γ 10, 40 Hz Γ 3, 160 Hz Γ 10,
//! and those of the first draw, `random.Random(34)`, whose runs showed that
//! a drift not told from noise is not a steady bed: 80 Hz Γ 38, 20 Hz Γ 4
//! and 20 Hz Γ 7): 80 Hz Γ 9, 80 Hz Γ 10 and 80 Hz Γ 28. Each run's
//! z-score is taken for the DEM's energy per cycle and the measured one
//! (Yang's method) against the mean of all runs, `(x_i − mean) / (+-)_i ·
//! √(n / (n − 1))` (the factor undoes the shrinkage of a deviation from a
//! mean that includes the run itself), which asks whether the +- holds how
//! far runs scatter. An honest one-sigma +- gives z-scores spread by about
//! 1 and about 68 % of them within 1. It also prints the z-scores against
//! twelve beds driven 800 cycles and averaged over their last 400: they
//! showed that the beds change by 1-1.5 % over hundreds of cycles, which the
//! +- does not carry, and the allowance for a longer drive
//! (`vlab::experiment::ensemble_summary::longer_drive_rel`) was chosen
//! partly from them, so they are printed, not judged.
//!
//! **The allowance** ([`the_longer_drive_allowance_covers_beds_driven_on`]),
//! at four conditions of a new draw (`random.Random(36)`, leaving out all
//! of the above and the two of the draw the allowance was then chosen
//! from): the default job (seed 701) against the same six beds driven 800
//! cycles.
//!
//! Long (the first about two and three quarter hours on 2 cores: at 80 Hz,
//! Γ 9 the runs drive to their cap of 400 cycles, about 4 minutes each, and
//! each reference takes about 15; the second about an hour and a half), so
//! ignored by `cargo test`; run them with
//!
//! ```sh
//! cargo test --release --test suite coverage:: -- --ignored --nocapture
//! ```
//!
//! The figures they printed are in `docs/accuracy.md` ("Coverage" and "A
//! longer drive").

use vlab::experiment::bed::cache::BedSource;
use vlab::experiment::ensemble::{DEFAULT_BEDS, unsteady_reasons};
use vlab::experiment::ensemble_summary::longer_drive_rel;
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
    /// The allowance for a longer drive printed beside the DEM's and the
    /// measured +- (J, one sigma).
    longer_drive: (f64, f64),
    cycles: u32,
    /// Cycles of the window the figures average.
    window_cycles: u32,
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
    driven_on(REFERENCE_SEED, freq_hz, gamma, REFERENCE_BEDS)
}

/// `beds` beds of seed `seed` driven [`REFERENCE_CYCLES`] cycles, the
/// figure their last [`REFERENCE_WINDOW`] cycles'.
fn driven_on(seed: u64, freq_hz: f64, gamma: f64, beds: u32) -> Run {
    let mut scene = Scene::thesis();
    scene.drive.cycles = CyclesSpec::Count(REFERENCE_CYCLES);
    scene.drive.steady_cycles = REFERENCE_WINDOW;
    ensemble(scene, seed, freq_hz, gamma, beds)
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
        longer_drive: (
            s.dem_energy_per_cycle_j.longer_drive,
            s.measured_energy_per_cycle_j.longer_drive,
        ),
        cycles: s.cycles,
        window_cycles: s.cycles - s.steady_first_cycle,
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

/// The runs' z-scores against a reference `(value, +-)` of other beds,
/// both errors and each run's allowance for a longer drive (J) in the
/// denominator: a bias common to the runs shows here, not in
/// [`z_scores`].
fn z_against(values: &[(f64, f64)], reference: (f64, f64), allowances: &[f64]) -> Vec<f64> {
    values
        .iter()
        .zip(allowances)
        .map(|((x, pm), a)| (x - reference.0) / pm.hypot(reference.1).hypot(*a))
        .collect()
}

/// The z-scores of one condition's runs, DEM and measured, against the
/// runs' mean and against the long-run reference.
struct ConditionZ {
    dem: Vec<f64>,
    measured: Vec<f64>,
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
        let zr = z_against(&values, against, &vec![0.0; values.len()]);
        let allowances: Vec<f64> = runs
            .iter()
            .map(|r| match what {
                "DEM" => r.longer_drive.0,
                _ => r.longer_drive.1,
            })
            .collect();
        let zl = z_against(&values, against, &allowances);
        println!(
            "{freq_hz} Hz, Gamma {gamma}, {what}: {RUNS} runs of {DEFAULT_BEDS} beds (seeds {FIRST_SEED}-{}), mean {:.4e} J ({:+.2} % vs the reference), runs spread {:.2} %, mean +- {:.2} %, z sd {:.2}, |z| <= 1 in {} of {RUNS}; against the reference rms z {:.2}, |z| <= 1 in {} (with the allowance for a longer drive, chosen from these runs: {:.2}, {})",
            FIRST_SEED + RUNS - 1,
            m.mean,
            100.0 * (m.mean / against.0 - 1.0),
            100.0 * m.std / m.mean,
            100.0 * mean_pm / m.mean,
            mean_std(&zs).std,
            zs.iter().filter(|z| z.abs() <= 1.0).count(),
            rms(&zr),
            zr.iter().filter(|z| z.abs() <= 1.0).count(),
            rms(&zl),
            zl.iter().filter(|z| z.abs() <= 1.0).count(),
        );
        out.push(zs);
    }
    let cycles: Vec<u32> = runs.iter().map(|r| r.cycles).collect();
    let steady = runs.iter().filter(|r| r.steady).count();
    println!("{freq_hz} Hz, Gamma {gamma}: cycles {cycles:?}, {steady} of {RUNS} shown steady");
    let measured = out.pop().expect("two series");
    let dem = out.pop().expect("two series");
    ConditionZ { dem, measured }
}

/// The root mean square: the spread of z-scores about zero, a common
/// bias included.
fn rms(zs: &[f64]) -> f64 {
    (zs.iter().map(|z| z * z).sum::<f64>() / zs.len().max(1) as f64).sqrt()
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
/// 36 runs' z-scores against the runs' mean together (DEM and measured
/// apart) spread within 0.75-1.35 with 18 to 31 within 1 (the binomial's
/// 98 % range about 68.3 %); each condition's 12 within 0.5-2.3, what an
/// honest six-bed error gives 99 % of the time (simulated), so that no
/// condition hides in the pool. An honest error passes the pooled band
/// about 5 times in 6 (Student's t on 5 degrees of freedom has long tails;
/// simulated), one 1.5 times too small about 1 in 10. Against the long-run
/// references the z-scores are printed, with and without the allowance for
/// a longer drive, not judged: the allowance was chosen from them; it is
/// judged where it was not ([`the_longer_drive_allowance_covers_beds_driven_on`]).
#[test]
#[ignore = "about two and three quarter hours on 2 cores; run with --ignored"]
fn the_printed_error_covers_independent_runs_where_nobody_tuned() {
    let mut problems = Vec::new();
    let mut pooled: [(&str, Vec<f64>); 2] = [("DEM", Vec::new()), ("measured", Vec::new())];
    for (freq_hz, gamma) in [(80.0, 9.0), (80.0, 10.0), (80.0, 28.0)] {
        let c = condition(freq_hz, gamma);
        for ((what, pool), zs) in pooled.iter_mut().zip([c.dem, c.measured]) {
            let label = format!("{freq_hz} Hz, Gamma {gamma}, {what}");
            problems.extend(judge(&label, &zs, 0.5..=2.3, (0, zs.len())));
            pool.extend(zs);
        }
    }
    for (what, zs) in &pooled {
        problems.extend(judge(
            &format!("all three, {what}"),
            zs,
            0.75..=1.35,
            (18, 31),
        ));
    }
    assert!(problems.is_empty(), "{problems:?}");
}

/// The first seed of the allowance's check, and its conditions: a new draw
/// from the thesis grid (`random.Random(36)` in Python, the first six
/// conditions not used before: 80 Hz Γ 4, 20 Hz Γ 5, 20 Hz Γ 1, 40 Hz Γ 16,
/// 80 Hz Γ 36, 80 Hz Γ 35). The first two are not among them: the first
/// form of the allowance, a constant 1.2 %, failed there (20 Hz Γ 5 read
/// 5.0 % above its beds driven on), and they are now among the conditions
/// the allowance was chosen from.
const DRIVEN_ON_SEED: u64 = 701;
const DRIVEN_ON_CONDITIONS: [(f64, f64); 4] =
    [(20.0, 1.0), (40.0, 16.0), (80.0, 36.0), (80.0, 35.0)];

/// The allowance for a longer drive
/// (`vlab::experiment::ensemble_summary::longer_drive_rel`) holds where it
/// was not chosen: at four conditions of a new draw the default job (seed
/// 701) is run and the same six beds are driven 800 cycles; the z-score of
/// the default job's figure `x` against theirs over cycles 401-800, `y`,
/// with what the run printed, `(x − y) / √((+-)_x² + allowance_x²)`, is
/// asked an rms within 1.35 and each within 2.6 (about 99 % of a normal).
/// The beds are the same, so the difference is the drive's length alone
/// (and the two windows' noise). Without the allowance the rms is printed
/// too: what the allowance buys.
#[test]
#[ignore = "about an hour and a half on 2 cores; run with --ignored"]
fn the_longer_drive_allowance_covers_beds_driven_on() {
    let mut with = (Vec::new(), Vec::new());
    let mut without = (Vec::new(), Vec::new());
    for (freq_hz, gamma) in DRIVEN_ON_CONDITIONS {
        let run = run(DRIVEN_ON_SEED, freq_hz, gamma);
        let on = driven_on(DRIVEN_ON_SEED, freq_hz, gamma, DEFAULT_BEDS);
        for (what, x, y, allowance, zs, bare) in [
            (
                "DEM",
                run.dem,
                on.dem,
                run.longer_drive.0,
                &mut with.0,
                &mut without.0,
            ),
            (
                "measured",
                run.measured,
                on.measured,
                run.longer_drive.1,
                &mut with.1,
                &mut without.1,
            ),
        ] {
            // The allowance the run printed: its figure's share for its window.
            let window = run.window_cycles;
            assert!((allowance - longer_drive_rel(window) * x.0).abs() <= 1e-12 * x.0);
            let z = (x.0 - y.0) / x.1.hypot(allowance);
            let z0 = (x.0 - y.0) / x.1;
            println!(
                "{freq_hz} Hz, Gamma {gamma}, {what}: default job {:.5e} +- {:.2e} J (+- {:.2e} longer drive; {} cycles, window {window}), the same beds over cycles {}-{REFERENCE_CYCLES} {:.5e} +- {:.2e} J: {:+.2} %, z {z:+.2} with the allowance, {z0:+.2} without",
                x.0,
                x.1,
                allowance,
                run.cycles,
                REFERENCE_CYCLES - REFERENCE_WINDOW + 1,
                y.0,
                y.1,
                100.0 * (x.0 / y.0 - 1.0),
            );
            zs.push(z);
            bare.push(z0);
        }
    }
    let mut problems = Vec::new();
    for (what, zs, bare) in [
        ("DEM", &with.0, &without.0),
        ("measured", &with.1, &without.1),
    ] {
        println!(
            "{what}: rms z {:.2} with the allowance ({:.2} without), largest |z| {:.2}",
            rms(zs),
            rms(bare),
            zs.iter().fold(0.0_f64, |m, z| m.max(z.abs()))
        );
        if rms(zs) > 1.35 || zs.iter().any(|z| z.abs() > 2.6) {
            problems.push(format!("{what}: {zs:?}"));
        }
    }
    assert!(problems.is_empty(), "{problems:?}");
}
