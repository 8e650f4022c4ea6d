//! `vlab host modal`: the modal parameters of a host from the receptance a
//! `vlab host frf` wrote (thesis Section 2.3.1: the host tests), as a lab
//! extracts them on a structure with several modes: each mode's natural
//! frequency, damping ratio, loss factor and modal constant with its
//! one-sigma error ([`vlab::signals::structural::fit_modes`]). Reads any of
//! the three `frf.csv` kinds (random H1, stepped sine, swept sine, told
//! apart by their columns) and writes `modal.json` and `modal.svg`.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use clap::Args;
use realfft::num_complex::Complex64;

use vlab::atomic_write::{OutputDir, write_bytes_atomic};
use vlab::signals::structural::{MAX_MODES, ModalFit, ModalFitOptions, fit_modes};
use vlab::validation::InvalidParameter;

#[derive(Debug, Clone, Args)]
pub struct ModalArgs {
    /// A receptance written by `vlab host frf`: its frf.csv (random: H1;
    /// stepped sine; swept sine).
    #[arg(value_name = "FILE.csv")]
    file: PathBuf,
    /// Modes to fit: the N most prominent peaks of |H| in the band (1 to 12).
    #[arg(long, value_name = "N", default_value = "1", value_parser = parse_modes)]
    modes: usize,
    /// Fit over LOW_HZ:HIGH_HZ only (Hz, both ends included) [default: every
    /// line of the file].
    #[arg(long, value_name = "LOW:HIGH", value_parser = parse_band)]
    band: Option<Band>,
    /// Leave out the residual terms of the modes outside the band.
    #[arg(long = "no-residuals")]
    no_residuals: bool,
    /// Output folder for modal.json and modal.svg [default: the file's folder].
    #[arg(long, value_name = "DIR")]
    out: Option<PathBuf>,
}

/// A frequency band, Hz.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Band {
    low_hz: f64,
    high_hz: f64,
}

/// `--modes`: an integer from 1 to [`MAX_MODES`].
fn parse_modes(s: &str) -> Result<usize, InvalidParameter> {
    s.trim()
        .parse::<usize>()
        .ok()
        .filter(|n| (1..=MAX_MODES).contains(n))
        .ok_or_else(|| {
            InvalidParameter::new(
                "value",
                format!("'{s}'"),
                "",
                format!("an integer from 1 to {MAX_MODES}"),
            )
        })
}

/// `--band LOW:HIGH` in Hz, `0 < LOW < HIGH`, both finite.
fn parse_band(s: &str) -> Result<Band, InvalidParameter> {
    let refuse = || {
        InvalidParameter::new(
            "value",
            format!("'{s}'"),
            "Hz",
            "LOW:HIGH, two finite numbers with 0 < LOW < HIGH",
        )
    };
    let (low, high) = s.split_once(':').ok_or_else(refuse)?;
    let number = |t: &str| t.trim().parse::<f64>().ok().filter(|v| v.is_finite());
    match (number(low), number(high)) {
        (Some(low_hz), Some(high_hz)) if low_hz > 0.0 && low_hz < high_hz => {
            Ok(Band { low_hz, high_hz })
        }
        _ => Err(refuse()),
    }
}

/// Which `frf.csv` a file is, by the columns of its receptance.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum FrfKind {
    RandomH1,
    SteppedSine,
    SweptSine,
}

impl FrfKind {
    const ALL: [FrfKind; 3] = [FrfKind::RandomH1, FrfKind::SteppedSine, FrfKind::SweptSine];

    /// The receptance's real and imaginary columns (m/N).
    fn columns(self) -> (&'static str, &'static str) {
        match self {
            FrfKind::RandomH1 => ("h1_re_m_per_n", "h1_im_m_per_n"),
            FrfKind::SteppedSine => ("receptance_re_m_per_n", "receptance_im_m_per_n"),
            FrfKind::SweptSine => ("h_re_m_per_n", "h_im_m_per_n"),
        }
    }

    fn label(self) -> &'static str {
        match self {
            FrfKind::RandomH1 => "random (H1)",
            FrfKind::SteppedSine => "stepped sine",
            FrfKind::SweptSine => "swept sine",
        }
    }

    fn key(self) -> &'static str {
        match self {
            FrfKind::RandomH1 => "random-h1",
            FrfKind::SteppedSine => "stepped-sine",
            FrfKind::SweptSine => "swept-sine",
        }
    }
}

/// A receptance read from a file.
struct FrfFile {
    kind: FrfKind,
    freq_hz: Vec<f64>,
    h_m_per_n: Vec<Complex64>,
}

/// Reads `path` as one of the [`FrfKind`]s: a header with `freq_hz` and
/// the kind's two columns, then a row of numbers per line.
fn read_frf(path: &Path) -> Result<FrfFile> {
    let text =
        std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))?;
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap_or("").trim_end().split(',').collect();
    let find = |name: &str| header.iter().position(|c| *c == name);
    let found = FrfKind::ALL.iter().find_map(|&kind| {
        let (re, im) = kind.columns();
        Some((kind, find("freq_hz")?, find(re)?, find(im)?))
    });
    let Some((kind, f_col, re_col, im_col)) = found else {
        bail!(
            "{}: not an frf.csv of `vlab host frf`: its header has none of the column pairs \
             h1_re_m_per_n,h1_im_m_per_n (random), receptance_re_m_per_n,receptance_im_m_per_n \
             (stepped sine) or h_re_m_per_n,h_im_m_per_n (swept sine) beside freq_hz",
            path.display()
        );
    };
    let mut file = FrfFile {
        kind,
        freq_hz: Vec::new(),
        h_m_per_n: Vec::new(),
    };
    for (k, line) in lines.enumerate().filter(|(_, l)| !l.trim().is_empty()) {
        let cells: Vec<&str> = line.trim_end().split(',').collect();
        let cell = |i: usize, name: &str| -> Result<f64> {
            let c = cells.get(i).copied().unwrap_or("");
            c.trim()
                .parse::<f64>()
                .ok()
                .filter(|v| v.is_finite())
                .with_context(|| {
                    format!(
                        "{} line {}: {name} = '{c}' is not a finite number",
                        path.display(),
                        k + 2
                    )
                })
        };
        let (re, im) = kind.columns();
        file.freq_hz.push(cell(f_col, "freq_hz")?);
        file.h_m_per_n
            .push(Complex64::new(cell(re_col, re)?, cell(im_col, im)?));
    }
    Ok(file)
}

/// The lines of `file` inside `band` (all without one).
fn in_band(file: &FrfFile, band: Option<Band>, path: &Path) -> Result<(Vec<f64>, Vec<Complex64>)> {
    let keep = |f: f64| band.is_none_or(|b| (b.low_hz..=b.high_hz).contains(&f));
    let (freq_hz, h): (Vec<f64>, Vec<Complex64>) = file
        .freq_hz
        .iter()
        .zip(&file.h_m_per_n)
        .filter(|(f, _)| keep(**f))
        .unzip();
    if freq_hz.is_empty() {
        let (lo, hi) = (file.freq_hz.first(), file.freq_hz.last());
        bail!(
            "--band: no line of {} lies in it (the file's lines span {} to {} Hz)",
            path.display(),
            lo.map_or("-".into(), |f| f.to_string()),
            hi.map_or("-".into(), |f| f.to_string())
        );
    }
    Ok((freq_hz, h))
}

/// Runs the command.
pub fn run(a: ModalArgs) -> Result<()> {
    let file = read_frf(&a.file)?;
    let (freq_hz, h) = in_band(&file, a.band, &a.file)?;
    let options = ModalFitOptions {
        modes: a.modes,
        residuals: !a.no_residuals,
    };
    let fit = fit_modes(&freq_hz, &h, &options).with_context(|| {
        format!(
            "fitting {} mode(s) to {} lines of {} (--modes, --band)",
            a.modes,
            freq_hz.len(),
            a.file.display()
        )
    })?;
    let dir = a.out.clone().unwrap_or_else(|| {
        a.file
            .parent()
            .map(PathBuf::from)
            .unwrap_or_else(|| PathBuf::from("."))
    });
    let made = OutputDir::prepare(&dir)
        .with_context(|| format!("cannot create output folder {}", dir.display()))?;
    print_fit(&a, file.kind, &freq_hz, &fit);
    let written = made.keep_if_ok(write_outputs(&dir, &a.file, file.kind, &freq_hz, &h, &fit))?;
    for p in written {
        println!("wrote {}", p.display());
    }
    Ok(())
}

/// `value +- sigma` with the sigma's two significant digits, or the value
/// alone (six significant digits) and a note where there is no sigma.
fn with_error(value: f64, sigma: Option<f64>) -> String {
    match sigma {
        Some(s) if s > 0.0 && s.is_finite() => {
            let decimals = (1 - s.log10().floor() as i32).clamp(0, 12) as usize;
            format!("{value:.decimals$} +- {s:.decimals$}")
        }
        _ => format!("{value:.6e} (no +-)"),
    }
}

/// The table of modes on standard output, warnings on standard error.
fn print_fit(a: &ModalArgs, kind: FrfKind, freq_hz: &[f64], fit: &ModalFit) {
    let (lo, hi) = (freq_hz[0], freq_hz[freq_hz.len() - 1]);
    println!(
        "{}: {} FRF, {} lines from {lo} to {hi} Hz; {} mode(s){} fitted, {} parameters, {} iterations; residuals {:.3} % rms of |H|",
        a.file.display(),
        kind.label(),
        fit.points,
        fit.modes.len(),
        if fit.residuals.is_some() {
            " and the residual terms of modes outside the band"
        } else {
            ""
        },
        fit.parameters,
        fit.iterations,
        100.0 * fit.residual_rms_rel
    );
    println!(
        "  mode  freq_hz (Hz)           damping_ratio            loss_factor              modal_constant re (1/kg)    im (1/kg)"
    );
    for (r, m) in fit.modes.iter().enumerate() {
        println!(
            "  {:4}  {:21}  {:23}  {:23}  {:26}  {}",
            r + 1,
            with_error(m.freq_hz, m.freq_hz_stderr),
            with_error(m.damping_ratio, m.damping_ratio_stderr),
            with_error(m.loss_factor, m.loss_factor_stderr),
            with_error(
                m.modal_constant_re_per_kg,
                m.modal_constant_re_stderr_per_kg
            ),
            with_error(
                m.modal_constant_im_per_kg,
                m.modal_constant_im_stderr_per_kg
            ),
        );
        if !(lo..=hi).contains(&m.freq_hz) {
            eprintln!(
                "warning: mode {} fitted at {:.4} Hz, outside the band {lo} to {hi} Hz: a peak of noise? fewer --modes or another --band",
                r + 1,
                m.freq_hz
            );
        }
    }
    println!(
        "  (+- : one sigma from the fit's residuals, taken as independent from line to line; a bias of the FRF itself, such as a transient left in its record, is not in it)"
    );
}

/// `modal.json` and, with plots, `modal.svg` into `dir`.
fn write_outputs(
    dir: &Path,
    source: &Path,
    kind: FrfKind,
    freq_hz: &[f64],
    h: &[Complex64],
    fit: &ModalFit,
) -> Result<Vec<PathBuf>> {
    let json = serde_json::json!({
        "source": source.display().to_string(),
        "frf_kind": kind.key(),
        "band_hz": [freq_hz[0], freq_hz[freq_hz.len() - 1]],
        "model": "H(w) = sum_r A_r / (w_r^2 - w^2 + 2 i zeta_r w_r w) + U + L / w^2, w in rad/s, A in 1/kg, U in m/N, L in 1/kg",
        "stderr": "one sigma from the fit's residuals (covariance of the least squares scaled by their variance)",
        "fit": fit,
    });
    let path = dir.join("modal.json");
    let text = serde_json::to_string_pretty(&json).context("modal.json")?;
    write_bytes_atomic(&path, format!("{text}\n").as_bytes())
        .with_context(|| format!("writing {}", path.display()))?;
    let mut written = vec![path];
    #[cfg(feature = "plot")]
    written.push(plot(dir, freq_hz, h, fit)?);
    #[cfg(not(feature = "plot"))]
    let _ = h;
    Ok(written)
}

/// `modal.svg`: the measured |H| and the fitted model in dB re 1 m/N, the
/// model drawn finely around each mode so its peak shows.
#[cfg(feature = "plot")]
fn plot(dir: &Path, freq_hz: &[f64], h: &[Complex64], fit: &ModalFit) -> Result<PathBuf> {
    use vlab::signals::{Series, SeriesStyle, plot_xy_svg};
    let db = |h: Complex64| 20.0 * h.norm().log10();
    let (lo, hi) = (freq_hz[0], freq_hz[freq_hz.len() - 1]);
    let mut grid: Vec<f64> = freq_hz.to_vec();
    for m in &fit.modes {
        let half_width_hz = (10.0 * m.damping_ratio * m.freq_hz).max(1e-6);
        grid.extend((0..=200).map(|k| m.freq_hz + half_width_hz * (k as f64 / 100.0 - 1.0)));
    }
    grid.retain(|f| (lo..=hi).contains(f));
    grid.sort_by(f64::total_cmp);
    grid.dedup();
    let model: Vec<(f64, f64)> = grid
        .iter()
        .map(|&f| (f, db(fit.receptance_m_per_n(f))))
        .filter(|p| p.1.is_finite())
        .collect();
    let measured: Vec<(f64, f64)> = freq_hz.iter().zip(h).map(|(&f, &h)| (f, db(h))).collect();
    let series = [
        Series {
            name: "measured |H|".into(),
            points: measured,
            style: SeriesStyle::Points,
        },
        Series {
            name: format!("fitted, {} mode(s)", fit.modes.len()),
            points: model,
            style: SeriesStyle::Line,
        },
    ];
    let path = dir.join("modal.svg");
    plot_xy_svg(
        &path,
        "Receptance and its modal fit",
        "frequency (Hz)",
        "|H| (dB re 1 m/N)",
        &series,
    )
    .with_context(|| format!("writing {}", path.display()))?;
    Ok(path)
}
