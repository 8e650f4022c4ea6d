//! `vlab shear-box`: the quasi-static compression and shear test of the
//! thesis' Fig. 8.15 on one scene's particles or several (Section 8.5.1.2):
//! normal and shear force-displacement curves, each scene's in its own
//! folder, all of them in one plot per test, and the scenes ordered by
//! their shear stiffness.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use clap::{Args, ValueEnum};
use vlab::atomic_write::OutputDir;
use vlab::experiment::shear_box::{BoxRun, BoxTest, Loading, ShearBox};
use vlab::scene::Scene;
use vlab::study::shear_box_series::{ShearBoxEvent, ShearBoxOutcome, ShearBoxPlan};

use super::args;
use super::cache_cmd::NoCacheArg;
use super::progress::ProgressLine;

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Tests {
    Normal,
    Shear,
    Both,
}

#[derive(Debug, Clone, Args)]
pub struct ShearBoxArgs {
    /// Scene file whose particles fill the box (merged over the built-in
    /// thesis scene); give it once per shape to compare them [default: the
    /// thesis' Chapter 8 spheres, 7.6 mm across, of the built-in scene's
    /// material].
    #[arg(long, value_name = "FILE")]
    scene: Vec<PathBuf>,
    /// Which test.
    #[arg(long, value_enum, default_value = "both")]
    test: Tests,
    /// Particles in the box (the thesis: 100).
    #[arg(long, default_value = "100")]
    count: usize,
    /// Seeds of the random fill, comma-separated: each scene's bed settled
    /// once per seed, and the table's mean force given with its standard
    /// error over them (a bed of 100 particles differs from the next by as
    /// much as the shapes do) [default: the scene's seed].
    #[arg(long, value_delimiter = ',')]
    seeds: Vec<u64>,
    /// Loading speed of the table (normal) and the upper container (shear)
    /// (m/s); the table's force control moves it at up to 10 times this. At
    /// 0.01 m/s the thesis bed sheared under 50 N has an inertial number
    /// of about 9e-4: quasi-static (below 1e-3).
    #[arg(long = "speed-mps", value_name = "M/S", default_value = "0.01", value_parser = args::speed_mps)]
    speed_mps: f64,
    /// Normal pre-load of the normal test (N; the thesis: 10).
    #[arg(long = "normal-preload-n", value_name = "N", default_value = "10")]
    normal_preload_n: f64,
    /// Normal pre-load held through the shear test (N; the thesis: 50).
    #[arg(long = "shear-preload-n", value_name = "N", default_value = "50")]
    shear_preload_n: f64,
    /// How far the table presses the bed after the pre-load (m).
    #[arg(long = "normal-travel-m", value_name = "M", default_value = "0.0003", value_parser = args::metres)]
    normal_travel_m: f64,
    /// How far the upper container moves across (m): by 1.5 mm the bed has
    /// slipped; further on, particles jam between the offset rims of a box
    /// only five particles across.
    #[arg(long = "shear-travel-m", value_name = "M", default_value = "0.0015", value_parser = args::metres)]
    shear_travel_m: f64,
    /// Points on each curve (10 to 10000).
    #[arg(long, default_value = "150")]
    points: usize,
    /// Output folder [default: signals/shear-box].
    #[arg(long, value_name = "DIR")]
    out: Option<PathBuf>,
    #[command(flatten)]
    cache: NoCacheArg,
}

pub fn run(a: ShearBoxArgs, quiet: bool) -> Result<()> {
    check(&a)?;
    let scenes = load_scenes(&a)?;
    let tests: &[BoxTest] = match a.test {
        Tests::Normal => &[BoxTest::Normal],
        Tests::Shear => &[BoxTest::Shear],
        Tests::Both => &[BoxTest::Normal, BoxTest::Shear],
    };
    let out_dir = a
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from("signals/shear-box"));
    let made = OutputDir::prepare(&out_dir)
        .with_context(|| format!("cannot create output folder {}", out_dir.display()))?;
    let plan = ShearBoxPlan {
        scenes,
        seeds: a.seeds.clone(),
        tests: tests.iter().map(|&t| (t, loading(&a, t))).collect(),
    };
    let outcome = made.keep_if_ok(run_all(&plan, a.cache, quiet))?;
    made.keep_if_ok(outcome.write(&out_dir).map_err(anyhow::Error::from))?;
    print_table(&outcome, tests, &out_dir);
    Ok(())
}

fn check(a: &ShearBoxArgs) -> Result<()> {
    if !(2..=100_000).contains(&a.count) {
        bail!("--count = {}: must be in [2, 100000] particles", a.count);
    }
    for (flag, f) in [
        ("--normal-preload-n", a.normal_preload_n),
        ("--shear-preload-n", a.shear_preload_n),
    ] {
        if !(f.is_finite() && f > 0.0 && f <= 1e5) {
            bail!("{flag} = {f}: must be in (0, 100000] N");
        }
    }
    if a.normal_travel_m > 0.005 {
        bail!(
            "--normal-travel-m = {}: must be in (0, 0.005] m (a granular bed pressed further by a rigid table crushes its particles)",
            a.normal_travel_m
        );
    }
    if a.shear_travel_m > 0.02 {
        bail!(
            "--shear-travel-m = {}: must be in (0, 0.02] m (half the box's diameter)",
            a.shear_travel_m
        );
    }
    if a.speed_mps > 0.1 {
        bail!(
            "--speed-mps = {}: must be in (0, 0.1] m/s (quasi-static loading)",
            a.speed_mps
        );
    }
    if !(10..=10_000).contains(&a.points) {
        bail!("--points = {}: must be in [10, 10000]", a.points);
    }
    Ok(())
}

/// The scenes, each turned into the box's scene, with unique names.
fn load_scenes(a: &ShearBoxArgs) -> Result<Vec<Scene>> {
    let files: Vec<Option<&Path>> = if a.scene.is_empty() {
        vec![None]
    } else {
        a.scene.iter().map(|p| Some(p.as_path())).collect()
    };
    let mut scenes: Vec<Scene> = Vec::new();
    for file in files {
        let scene = match file {
            Some(_) => Scene::load_or_thesis(file)?,
            None => chapter_8_spheres(),
        };
        let scene = ShearBox::THESIS.scene(&scene, a.count);
        scene
            .validate()
            .with_context(|| format!("the box filled with {}", scene.name))?;
        if scenes.iter().any(|s| s.name == scene.name) {
            bail!(
                "two scenes are named '{}': give each scene file its own name (the top-level key name), which names its folder",
                scene.name
            );
        }
        // The beds are settled and tested one at a time, each on every
        // thread.
        scenes.push(super::args::run_alone(scene));
    }
    Ok(scenes)
}

/// The spheres of the thesis' shape study (Chapter 8): the volume of its
/// spheroids, a radius of 3.8 mm, in the built-in scene's material.
fn chapter_8_spheres() -> Scene {
    let mut scene = Scene::thesis();
    scene.name = "spheres-7.6mm".into();
    scene.particles.diameter_m = 0.0076;
    scene
}

/// The loading of `test` from the flags.
fn loading(a: &ShearBoxArgs, test: BoxTest) -> Loading {
    let (preload_n, travel_m) = match test {
        BoxTest::Normal => (a.normal_preload_n, a.normal_travel_m),
        BoxTest::Shear => (a.shear_preload_n, a.shear_travel_m),
    };
    Loading {
        preload_n,
        speed_mps: a.speed_mps,
        travel_m,
        points: a.points,
    }
}

/// The plan run with a progress line per bed.
fn run_all(plan: &ShearBoxPlan, cache: NoCacheArg, quiet: bool) -> Result<ShearBoxOutcome> {
    let mut line: Option<ProgressLine> = None;
    let beds = cache.source(&mut |n| eprintln!("{n}"));
    let outcome = plan.run(&beds, &mut |event| match event {
        ShearBoxEvent::Bed { scene, seed } => {
            let label = format!("shear-box {} seed {seed}", scene.name);
            line = Some(ProgressLine::new(&label, quiet));
        }
        ShearBoxEvent::Progress(p) => {
            if let Some(l) = &mut line {
                l.update(p);
            }
        }
        ShearBoxEvent::BedDone => {
            if let Some(mut l) = line.take() {
                l.finish();
            }
        }
    });
    Ok(outcome?)
}

/// The mean force over a curve (N): the area under it over its travel,
/// one number per test that is less noisy than any one point.
pub fn mean_force_n(run: &BoxRun) -> f64 {
    run.points.iter().map(|p| p.force_n).sum::<f64>() / run.points.len().max(1) as f64
}

/// The force at the point nearest `displacement_m` (N).
fn force_at_n(run: &BoxRun, displacement_m: f64) -> f64 {
    run.points
        .iter()
        .min_by(|a, b| {
            (a.displacement_m - displacement_m)
                .abs()
                .total_cmp(&(b.displacement_m - displacement_m).abs())
        })
        .map_or(f64::NAN, |p| p.force_n)
}

/// The mean and, over two or more beds, the standard error of a figure.
fn mean_se(values: &[f64]) -> (f64, f64) {
    let n = values.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    if values.len() < 2 {
        return (mean, f64::NAN);
    }
    let var = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0);
    (mean, (var / n).sqrt())
}

fn with_se(mean: f64, se: f64) -> String {
    if se.is_finite() {
        format!("{mean:.1} +- {se:.1}")
    } else {
        format!("{mean:.1}")
    }
}

fn print_table(outcome: &ShearBoxOutcome, tests: &[BoxTest], out_dir: &Path) {
    for &test in tests {
        println!(
            "{} test ({}):",
            test.as_str(),
            match test {
                BoxTest::Normal => "force on the base as the table presses down",
                BoxTest::Shear => "force on the fixed container as the upper one moves across",
            }
        );
        println!(
            "  {:<16} {:>5} {:>13} {:>16} {:>16}  per bed",
            "scene", "beds", "z_test,0 (mm)", "F at 1/2 (N)", "mean F (N)"
        );
        let mut order: Vec<(f64, f64, &str)> = Vec::new();
        for name in outcome.scene_names() {
            let runs = outcome.runs_of(name, test);
            if runs.is_empty() {
                continue;
            }
            let pick =
                |f: &dyn Fn(&BoxRun) -> f64| -> Vec<f64> { runs.iter().map(|r| f(r)).collect() };
            let z0 = mean_se(&pick(&|r| r.preload_displacement_m * 1e3));
            let half = mean_se(&pick(&|r| force_at_n(r, 0.5 * r.loading.travel_m)));
            let means = pick(&|r| mean_force_n(r));
            let mean = mean_se(&means);
            order.push((mean.0, mean.1, name));
            let per_bed: Vec<String> = means.iter().map(|m| format!("{m:.1}")).collect();
            println!(
                "  {:<16} {:>5} {:>13} {:>16} {:>16}  {}",
                name,
                runs.len(),
                format!("{:.3}", z0.0),
                with_se(half.0, half.1),
                with_se(mean.0, mean.1),
                per_bed.join(", ")
            );
        }
        if order.len() > 1 {
            order.sort_by(|a, b| a.0.total_cmp(&b.0));
            let mut line = order[0].2.to_string();
            for w in order.windows(2) {
                let apart = (w[1].0 - w[0].0) > 2.0 * w[0].1.hypot(w[1].1);
                line.push_str(if apart { " < " } else { " ~ " });
                line.push_str(w[1].2);
            }
            println!(
                "  order by the mean force: {line}  ('<': apart by more than twice their combined standard error; '~': not, or one bed each)"
            );
        }
    }
    println!(
        "wrote {} (a folder per scene with its curves, shear_box.json, plots)",
        out_dir.display()
    );
}
