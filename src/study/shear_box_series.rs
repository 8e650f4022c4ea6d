//! The shear box of Terzioglu's thesis, Fig. 8.15, over several scenes and
//! seeds (Section 8.5.1.2): each scene's bed settled once per seed, the
//! normal and the shear test run on it ([`crate::experiment::shear_box`]),
//! every curve written in its scene's folder, one plot per test over the
//! scenes (the mean of their seeds, point by point) and the summary.
//! `vlab shear-box` is its flags, progress and table.

use std::io::Write as _;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::atomic_write::write_atomic;
use crate::experiment::bed::cache::BedSource;
use crate::experiment::damper::Progress;
use crate::experiment::shear_box::{BoxRun, BoxTest, Loading, ShearBox, ShearBoxError, run_test};
use crate::scene::{Scene, SceneError};

/// Which tests to run on which scenes' beds.
#[derive(Debug, Clone)]
pub struct ShearBoxPlan {
    /// Each turned into the box's scene ([`ShearBox::scene`]), with unique
    /// names (each names its folder).
    pub scenes: Vec<Scene>,
    /// The seeds of each scene's beds; empty: each scene's own seed alone.
    pub seeds: Vec<u64>,
    /// The tests, in order, each with its loading.
    pub tests: Vec<(BoxTest, Loading)>,
}

/// One scene's tests on the bed of one seed, as the summary gives them.
#[derive(Debug, Serialize, Deserialize)]
pub struct SceneRuns {
    pub scene: String,
    pub particles: String,
    pub seed: u64,
    pub runs: Vec<BoxRun>,
}

/// What the series reports as it goes.
pub enum ShearBoxEvent<'a> {
    /// A bed of `scene` with `seed` is about to be settled and tested.
    Bed { scene: &'a Scene, seed: u64 },
    /// How the bed's settling or test stands.
    Progress(Progress),
    /// That bed's tests are done.
    BedDone,
}

/// Why the series stopped.
#[derive(Debug, thiserror::Error)]
pub enum ShearBoxSeriesError {
    #[error("settling {scene} in the box")]
    Settle {
        scene: String,
        #[source]
        source: Box<SceneError>,
    },
    #[error("the {test} test of {scene}")]
    Test {
        test: &'static str,
        scene: String,
        #[source]
        source: Box<ShearBoxError>,
    },
    #[error("cannot read {} as a shear box's summary (shear_box.json)", path.display())]
    Read {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("cannot write {}", path.display())]
    Write {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
}

/// Every scene's runs on every seed, in the plan's order.
#[derive(Debug)]
pub struct ShearBoxOutcome {
    pub all: Vec<SceneRuns>,
    /// Whether the plan gave several seeds (each seed's curves then have a
    /// folder of their own inside the scene's).
    several_seeds: bool,
}

impl ShearBoxPlan {
    /// Settles every scene's bed for every seed (from `source`) and runs the
    /// tests on it, telling `on` as it goes.
    pub fn run(
        &self,
        source: &BedSource,
        on: &mut dyn FnMut(ShearBoxEvent),
    ) -> Result<ShearBoxOutcome, ShearBoxSeriesError> {
        let mut all = Vec::new();
        for base in &self.scenes {
            let seeds = match self.seeds.is_empty() {
                true => vec![base.simulation.seed],
                false => self.seeds.clone(),
            };
            for seed in seeds {
                let mut scene = base.clone();
                scene.simulation.seed = seed;
                on(ShearBoxEvent::Bed {
                    scene: &scene,
                    seed,
                });
                let runs = self.run_bed(&scene, source, on)?;
                on(ShearBoxEvent::BedDone);
                all.push(SceneRuns {
                    scene: scene.name.clone(),
                    particles: describe_particles(&scene),
                    seed,
                    runs,
                });
            }
        }
        Ok(ShearBoxOutcome {
            all,
            several_seeds: self.seeds.len() > 1,
        })
    }

    /// The tests on one bed of `scene`.
    fn run_bed(
        &self,
        scene: &Scene,
        source: &BedSource,
        on: &mut dyn FnMut(ShearBoxEvent),
    ) -> Result<Vec<BoxRun>, ShearBoxSeriesError> {
        let bed = source
            .settle(scene, &mut |p| on(ShearBoxEvent::Progress(p)))
            .map_err(|source| ShearBoxSeriesError::Settle {
                scene: scene.name.clone(),
                source: Box::new(source),
            })?;
        let mut runs = Vec::new();
        for &(test, loading) in &self.tests {
            let mut progress = |p| on(ShearBoxEvent::Progress(p));
            let run = run_test(&bed, scene, &ShearBox::THESIS, test, loading, &mut progress)
                .map_err(|source| ShearBoxSeriesError::Test {
                    test: test.as_str(),
                    scene: scene.name.clone(),
                    source: Box::new(source),
                })?;
            runs.push(run);
        }
        Ok(runs)
    }
}

/// The particles of a scene in words: how many, of which shape and size.
fn describe_particles(scene: &Scene) -> String {
    let p = &scene.particles;
    format!(
        "{} {}s of the volume of a {} m sphere",
        p.count,
        p.shape.as_str(),
        p.diameter_m
    )
}

impl ShearBoxOutcome {
    /// The scenes in the order given, each once.
    pub fn scene_names(&self) -> Vec<&str> {
        let mut names: Vec<&str> = Vec::new();
        for s in &self.all {
            if !names.contains(&s.scene.as_str()) {
                names.push(&s.scene);
            }
        }
        names
    }

    /// The runs of `test` on every seed of scene `name`.
    pub fn runs_of(&self, name: &str, test: BoxTest) -> Vec<&BoxRun> {
        self.all
            .iter()
            .filter(|s| s.scene == name)
            .filter_map(|s| s.runs.iter().find(|r| r.test == test))
            .collect()
    }

    /// Writes each curve (`<scene>/normal.csv`, `<scene>/shear.csv`, in a
    /// `seed-N` folder each with several seeds), `shear_box.json` and, with
    /// plots, one plot per test (SVG and PNG) into `dir`, each file
    /// atomically.
    pub fn write(&self, dir: &Path) -> Result<(), ShearBoxSeriesError> {
        for s in &self.all {
            let folder = match self.several_seeds {
                true => dir.join(&s.scene).join(format!("seed-{}", s.seed)),
                false => dir.join(&s.scene),
            };
            for run in &s.runs {
                write_curve(&folder, run)?;
            }
        }
        let path = dir.join("shear_box.json");
        let text = serde_json::to_string_pretty(&self.all).map_err(std::io::Error::other);
        text.and_then(|t| write_atomic(&path, |w| writeln!(w, "{t}")))
            .map_err(|source| ShearBoxSeriesError::Write { path, source })?;
        #[cfg(feature = "plot")]
        self.plot(dir)?;
        Ok(())
    }

    /// Reads back what [`ShearBoxOutcome::write`] wrote to `shear_box.json`:
    /// every run to the bit, so its plots can be redrawn without the hours
    /// of running it (`vlab plot shear_box.json`).
    pub fn read(path: &Path) -> Result<Self, ShearBoxSeriesError> {
        let read = |source| ShearBoxSeriesError::Read {
            path: path.to_path_buf(),
            source,
        };
        let text = std::fs::read_to_string(path).map_err(read)?;
        let all: Vec<SceneRuns> = serde_json::from_str(&text)
            .map_err(|e| read(std::io::Error::new(std::io::ErrorKind::InvalidData, e)))?;
        // A scene with beds of several seeds is what the plan's seeds made.
        let several_seeds = all
            .iter()
            .any(|s| all.iter().filter(|t| t.scene == s.scene).count() > 1);
        Ok(Self { all, several_seeds })
    }

    /// Draws one plot per test the runs hold (`normal` and `shear`, SVG
    /// and PNG) into `dir`; the paths written.
    #[cfg(feature = "plot")]
    pub fn plot(&self, dir: &Path) -> Result<Vec<PathBuf>, ShearBoxSeriesError> {
        let mut written = Vec::new();
        for test in [BoxTest::Normal, BoxTest::Shear] {
            if self
                .all
                .iter()
                .any(|s| s.runs.iter().any(|r| r.test == test))
            {
                written.extend(self.plot_test(dir, test)?);
            }
        }
        Ok(written)
    }

    /// One plot of every scene's curve of `test` (over several seeds, their
    /// mean point by point), in mm and N, as SVG and PNG.
    #[cfg(feature = "plot")]
    fn plot_test(&self, dir: &Path, test: BoxTest) -> Result<Vec<PathBuf>, ShearBoxSeriesError> {
        use crate::signals::{Series, SeriesStyle, plot_xy_svg};
        let series: Vec<Series> = self
            .scene_names()
            .into_iter()
            .filter_map(|name| {
                let runs = self.runs_of(name, test);
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
        let mut written = Vec::new();
        for ext in ["svg", "png"] {
            let path = dir.join(format!("{}.{ext}", test.as_str()));
            plot_xy_svg(&path, title, x, y, &series).map_err(|e| ShearBoxSeriesError::Write {
                path: path.clone(),
                source: std::io::Error::other(e.to_string()),
            })?;
            written.push(path);
        }
        Ok(written)
    }
}

/// `normal.csv` or `shear.csv` in `dir` (made if need be).
fn write_curve(dir: &Path, run: &BoxRun) -> Result<(), ShearBoxSeriesError> {
    let path = dir.join(format!("{}.csv", run.test.as_str()));
    let (d, f) = match run.test {
        BoxTest::Normal => ("z_test_m", "f_test_z_n"),
        BoxTest::Shear => ("x_test_m", "f_test_x_n"),
    };
    std::fs::create_dir_all(dir)
        .and_then(|()| {
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
        })
        .map_err(|source| ShearBoxSeriesError::Write { path, source })
}
