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
    /// Seed of the random fill [default: the scene's].
    #[arg(long)]
    seed: Option<u64>,
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

/// One scene's tests, as the JSON summary gives them.
#[derive(Debug, Serialize)]
struct SceneRuns {
    scene: String,
    particles: String,
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
        let mut scene = match file {
            Some(_) => Scene::load_or_thesis(file)?,
            None => chapter_8_spheres(),
        };
        if let Some(seed) = a.seed {
            scene.simulation.seed = seed;
        }
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
    for scene in scenes {
        let mut progress = ProgressLine::new(&format!("shear-box {}", scene.name), quiet);
        let beds = a.cache.source(&mut |n| progress.warn(n));
        let bed = beds
            .settle(scene, &mut |p| progress.update(p))
            .with_context(|| format!("settling {} in the box", scene.name))?;
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
            write_curve(&out_dir.join(&scene.name), &run)?;
            runs.push(run);
        }
        progress.finish();
        all.push(SceneRuns {
            scene: scene.name.clone(),
            particles: describe_particles(scene),
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

/// One plot of every scene's curve of `test`, in mm and N, as SVG and PNG.
fn plot_test(out_dir: &Path, all: &[SceneRuns], test: BoxTest) -> Result<()> {
    let series: Vec<Series> = all
        .iter()
        .filter_map(|s| {
            let run = s.runs.iter().find(|r| r.test == test)?;
            Some(Series {
                name: s.scene.clone(),
                points: run
                    .points
                    .iter()
                    .map(|p| (p.displacement_m * 1e3, p.force_n))
                    .collect(),
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
            "  {:<16} {:>11} {:>12} {:>12} {:>12} {:>11} {:>10}",
            "scene",
            "z_test,0 mm",
            "F @ 1/4 (N)",
            "F @ 1/2 (N)",
            "F @ end (N)",
            "mean F (N)",
            "M steps/s"
        );
        let mut order: Vec<(f64, &str)> = Vec::new();
        for s in all {
            let Some(run) = s.runs.iter().find(|r| r.test == test) else {
                continue;
            };
            let travel = run.loading.travel_m;
            let mean = mean_force_n(run);
            order.push((mean, &s.scene));
            println!(
                "  {:<16} {:>11.4} {:>12.2} {:>12.2} {:>12.2} {:>11.2} {:>10.2}",
                s.scene,
                run.preload_displacement_m * 1e3,
                force_at_n(run, 0.25 * travel),
                force_at_n(run, 0.5 * travel),
                force_at_n(run, travel),
                mean,
                run.particle_steps_per_s / 1e6
            );
        }
        if order.len() > 1 {
            order.sort_by(|a, b| a.0.total_cmp(&b.0));
            let names: Vec<&str> = order.iter().map(|o| o.1).collect();
            println!(
                "  stiffness order, by the mean force (one bed each: compare seeds before trusting it): {}",
                names.join(" < ")
            );
        }
    }
    println!(
        "wrote {} (a folder per scene with its curves, shear_box.json, plots)",
        out_dir.display()
    );
}
