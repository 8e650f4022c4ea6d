//! `vlab shear-box`: the quasi-static compression and shear test of the
//! thesis' Fig. 8.15 on one scene's particles or several (Section 8.5.1.2):
//! normal and shear force-displacement curves, each scene's in its own
//! folder, all of them in one plot per test, and the scenes ordered by
//! their shear stiffness.

use std::io::Write as _;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use clap::{Args, ValueEnum};
use serde::Serialize;

use vlab::atomic_write::{OutputDir, write_atomic};
use vlab::experiment::shear_box::{BoxRun, BoxTest, Loading, ShearBox, run_test};
use vlab::scene::Scene;
use vlab::signals::{Series, SeriesStyle, plot_xy_svg};

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

/// One scene's tests on the bed of one seed, as the JSON summary gives them.
#[derive(Debug, Serialize)]
struct SceneRuns {
    scene: String,
    particles: String,
    seed: u64,
    runs: Vec<BoxRun>,
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
    let result = run_all(&a, &scenes, tests, &out_dir, quiet);
    let all = made.keep_if_ok(result)?;
    write_summary(&out_dir, &all)?;
    for &test in tests {
        plot_test(&out_dir, &all, test)?;
    }
    print_table(&all, tests, &out_dir);
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
        scenes.push(scene);
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

fn run_all(
    a: &ShearBoxArgs,
    scenes: &[Scene],
    tests: &[BoxTest],
    out_dir: &Path,
    quiet: bool,
) -> Result<Vec<SceneRuns>> {
    let mut all = Vec::new();
    for (base, seed) in scenes.iter().flat_map(|s| {
        let seeds = if a.seeds.is_empty() {
            vec![s.simulation.seed]
        } else {
            a.seeds.clone()
        };
        seeds.into_iter().map(move |seed| (s, seed))
    }) {
        let mut scene = super::args::run_alone(base.clone());
        scene.simulation.seed = seed;
        let scene = &scene;
        let label = format!("shear-box {} seed {seed}", scene.name);
        let mut progress = ProgressLine::new(&label, quiet);
        let beds = a.cache.source(&mut |n| progress.warn(n));
        let bed = beds
            .settle(scene, &mut |p| progress.update(p))
            .with_context(|| format!("settling {} in the box", scene.name))?;
        let folder = if a.seeds.len() > 1 {
            out_dir.join(&scene.name).join(format!("seed-{seed}"))
        } else {
            out_dir.join(&scene.name)
        };
        let mut runs = Vec::new();
        for &test in tests {
            let loading = Loading {
                preload_n: match test {
                    BoxTest::Normal => a.normal_preload_n,
                    BoxTest::Shear => a.shear_preload_n,
                },
                speed_mps: a.speed_mps,
                travel_m: match test {
                    BoxTest::Normal => a.normal_travel_m,
                    BoxTest::Shear => a.shear_travel_m,
                },
                points: a.points,
            };
            let run = run_test(&bed, scene, &ShearBox::THESIS, test, loading, &mut |p| {
                progress.update(p)
            })
            .with_context(|| format!("the {} test of {}", test.as_str(), scene.name))?;
            write_curve(&folder, &run)?;
            runs.push(run);
        }
        progress.finish();
        all.push(SceneRuns {
            scene: scene.name.clone(),
            particles: describe_particles(scene),
            seed,
            runs,
        });
    }
    Ok(all)
}

fn describe_particles(scene: &Scene) -> String {
    let p = &scene.particles;
    format!(
        "{} {}s of the volume of a {} m sphere",
        p.count,
        p.shape.as_str(),
        p.diameter_m
    )
}

/// `normal.csv` or `shear.csv` in the scene's folder.
fn write_curve(dir: &Path, run: &BoxRun) -> Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("cannot create {}", dir.display()))?;
    let path = dir.join(format!("{}.csv", run.test.as_str()));
    let (d, f) = match run.test {
        BoxTest::Normal => ("z_test_m", "f_test_z_n"),
        BoxTest::Shear => ("x_test_m", "f_test_x_n"),
    };
    write_atomic(&path, |w| {
        writeln!(
            w,
            "# vlab shear-box {} test: pre-load {} N held (z_test,0 = {:.6e} m), then {} m/s",
            run.test.as_str(),
            run.loading.preload_n,
            run.preload_displacement_m,
            run.loading.speed_mps
        )?;
        writeln!(w, "{d},{f},table_load_n,rings_up_n")?;
        for p in &run.points {
            writeln!(
                w,
                "{:.9e},{:.6e},{:.6e},{:.6e}",
                p.displacement_m, p.force_n, p.table_load_n, p.rings_up_n
            )?;
        }
        Ok(())
    })
    .with_context(|| format!("cannot write {}", path.display()))
}

fn write_summary(out_dir: &Path, all: &[SceneRuns]) -> Result<()> {
    let path = out_dir.join("shear_box.json");
    let text = serde_json::to_string_pretty(all)?;
    write_atomic(&path, |w| writeln!(w, "{text}"))
        .with_context(|| format!("cannot write {}", path.display()))
}

/// The scenes in the order given, each once.
fn scene_names(all: &[SceneRuns]) -> Vec<&str> {
    let mut names: Vec<&str> = Vec::new();
    for s in all {
        if !names.contains(&s.scene.as_str()) {
            names.push(&s.scene);
        }
    }
    names
}

/// The runs of `test` on every seed of scene `name`.
fn runs_of<'a>(all: &'a [SceneRuns], name: &str, test: BoxTest) -> Vec<&'a BoxRun> {
    all.iter()
        .filter(|s| s.scene == name)
        .filter_map(|s| s.runs.iter().find(|r| r.test == test))
        .collect()
}

/// One plot of every scene's curve of `test` (over several seeds, their
/// mean point by point), in mm and N, as SVG and PNG.
fn plot_test(out_dir: &Path, all: &[SceneRuns], test: BoxTest) -> Result<()> {
    let series: Vec<Series> = scene_names(all)
        .into_iter()
        .filter_map(|name| {
            let runs = runs_of(all, name, test);
            let first = runs.first()?;
            let n = runs.len() as f64;
            let points = (0..first.points.len())
                .map(|k| {
                    let f = runs.iter().map(|r| r.points[k].force_n).sum::<f64>() / n;
                    (first.points[k].displacement_m * 1e3, f)
                })
                .collect();
            Some(Series {
                name: if runs.len() > 1 {
                    format!("{name} (mean of {} beds)", runs.len())
                } else {
                    name.to_string()
                },
                points,
                style: SeriesStyle::Line,
            })
        })
        .collect();
    let (title, x, y) = match test {
        BoxTest::Normal => (
            "Normal force-displacement (thesis Fig. 8.16-8.17)",
            "z_test (mm)",
            "F_test,z on the base (N)",
        ),
        BoxTest::Shear => (
            "Shear force-displacement (thesis Fig. 8.18-8.19)",
            "x_test (mm)",
            "F_test,x on the fixed container (N)",
        ),
    };
    for ext in ["svg", "png"] {
        let path = out_dir.join(format!("{}.{ext}", test.as_str()));
        plot_xy_svg(&path, title, x, y, &series)
            .with_context(|| format!("cannot draw {}", path.display()))?;
    }
    Ok(())
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

fn print_table(all: &[SceneRuns], tests: &[BoxTest], out_dir: &Path) {
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
        for name in scene_names(all) {
            let runs = runs_of(all, name, test);
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
