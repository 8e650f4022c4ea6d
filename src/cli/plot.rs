//! `vlab plot FILE`: redraws a plot from the CSV it was drawn from. A
//! `sweep.csv` gives its efficiency curves and map; an `accuracy.csv` (with
//! its `summary.json`) the accuracy study's three plots; a stepped sine's
//! `frf.csv` (with its `frf.json`) its receptance; a shear box's
//! `shear_box.json` its normal and shear curves; any other vlab CSV record
//! (a trace, kinematics, drop-test results) is drawn column against the first
//! column.

use std::path::PathBuf;

use anyhow::{Context, Result};
use clap::Args;

use vlab::experiment::host_test::frf_figure::{is_stepped_sine_csv, redraw_magnitude};
use vlab::signals::plot::plot_channels;
use vlab::signals::read_trace;
use vlab::study::accuracy::read_back::{is_accuracy_csv, redraw_plots};
use vlab::study::shear_box_series::ShearBoxOutcome;
use vlab::study::sweep::{SWEEP_MAGIC, SweepFile};
use vlab::study::sweep_plot::plot_sweep;

#[derive(Debug, Clone, Args)]
pub struct PlotArgs {
    /// The file: a sweep.csv, an accuracy.csv, a stepped sine's frf.csv, a
    /// shear box's shear_box.json, or a trace/record CSV.
    #[arg(value_name = "FILE")]
    file: PathBuf,
    /// Output folder [default: the file's folder].
    #[arg(long, value_name = "DIR")]
    out: Option<PathBuf>,
}

/// Runs the command.
pub fn run(a: PlotArgs) -> Result<()> {
    let dir = a.out.clone().unwrap_or_else(|| {
        a.file
            .parent()
            .map(PathBuf::from)
            .unwrap_or_else(|| PathBuf::from("."))
    });
    std::fs::create_dir_all(&dir).with_context(|| format!("cannot create {}", dir.display()))?;
    if a.file.extension().is_some_and(|e| e == "json") {
        let outcome = ShearBoxOutcome::read(&a.file)?;
        for p in outcome.plot(&dir)? {
            println!("wrote {}", p.display());
        }
        return Ok(());
    }
    let head = std::fs::read_to_string(&a.file)
        .with_context(|| format!("cannot read {}", a.file.display()))?;
    if head.starts_with(SWEEP_MAGIC) {
        let file = SweepFile::read(&a.file)?;
        for p in plot_sweep(&file, &dir)? {
            println!("wrote {}", p.display());
        }
        return Ok(());
    }
    if is_accuracy_csv(&head) {
        for p in redraw_plots(&a.file, &dir)? {
            println!("wrote {}", p.display());
        }
        return Ok(());
    }
    if is_stepped_sine_csv(&head) {
        println!("wrote {}", redraw_magnitude(&a.file, &dir)?.display());
        return Ok(());
    }
    let trace = read_trace(&a.file).with_context(|| format!("reading {}", a.file.display()))?;
    let stem = a
        .file
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "plot".into());
    let title = a.file.display().to_string();
    for path in plot_channels(&trace, &title, &dir, &stem)? {
        println!("wrote {}", path.display());
    }
    Ok(())
}
