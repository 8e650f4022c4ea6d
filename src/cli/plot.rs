//! `vlab plot FILE`: redraws a plot from the CSV it was drawn from. A
//! `sweep.csv` gives its efficiency curves and map; any other vlab CSV record
//! (a trace, kinematics, drop-test results) is drawn column against the first
//! column.

use std::path::PathBuf;

use anyhow::{Context, Result};
use clap::Args;

use vlab::signals::plot::plot_channels;
use vlab::signals::read_trace;
use vlab::study::sweep::{SWEEP_MAGIC, SweepFile};
use vlab::study::sweep_plot::plot_sweep;

#[derive(Debug, Clone, Args)]
pub struct PlotArgs {
    /// The CSV file: a sweep.csv, or a trace/record CSV.
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
    let head = std::fs::read_to_string(&a.file)
        .with_context(|| format!("cannot read {}", a.file.display()))?;
    if head.starts_with(SWEEP_MAGIC) {
        let file = SweepFile::read(&a.file)?;
        for p in plot_sweep(&file, &dir)? {
            println!("wrote {}", p.display());
        }
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
