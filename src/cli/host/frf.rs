//! `vlab host frf`: the host's frequency response with the damper, by a
//! stepped sine (the lab's receptance, its half-power loss factor, the peak
//! against the host without particles and with their mass as a solid, the
//! power-input estimate of the damper's dissipation against the DEM's, and
//! with `--map` the map-based prediction beside it) or by a periodic random
//! force (H1, H2 and coherence). [`vlab::experiment::host_frf`] does the work.

use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::time::Instant;

use anyhow::{Context, Result};
use clap::Args;

use vlab::atomic_write::OutputDir;
use vlab::experiment::host_frf::{SteppedSine, SteppedSineResult, random_frf, run_stepped_sine};
use vlab::experiment::host_test::{Damper, HostTest};
use vlab::host::Excitation;
use vlab::host::map_model::stepped_sine;
use vlab::signals::{Series, SeriesStyle, plot_xy_svg};
use vlab::study::dissipation_map::{MapSource, dissipation_map};
use vlab::study::sweep::SweepFile;

use super::{FreqList, HostTestArgs, damper_slug, write_records, write_text};
use crate::cli::args;
use crate::cli::progress::ProgressLine;

#[derive(Debug, Clone, Args)]
#[command(allow_negative_numbers = true)]
pub struct FrfArgs {
    #[command(flatten)]
    common: HostTestArgs,
    /// Stepped sine: the frequencies (Hz), FROM:TO:STEP or a comma-separated list.
    #[arg(long = "freq", value_name = "LIST", value_parser = super::parse_freqs, required_unless_present = "random")]
    freqs: Option<FreqList>,
    /// Stepped sine: force amplitude at the drive point (N).
    #[arg(long = "force-n", value_name = "N", default_value = "5", value_parser = args::newtons)]
    force_n: f64,
    /// Stepped sine: cycles to settle at each frequency (from a steady
    /// response of the host with half the particles' mass and a dashpot of
    /// efficiency 0.5).
    #[arg(long = "settle-cycles", value_name = "N", default_value = "30")]
    settle_cycles: u32,
    /// Stepped sine: cycles measured at each frequency.
    #[arg(long = "record-cycles", value_name = "N", default_value = "20")]
    record_cycles: u32,
    /// Stepped sine: independent beds run at every frequency (seeds derived
    /// from --seed as `vlab shake --beds` derives them), each point their
    /// mean and its +- their spread; with one bed the +- is the record's,
    /// and the bed-to-bed part is added only where it was measured. Costs N
    /// times one bed.
    #[arg(long, value_name = "N", default_value_t = 1)]
    beds: u32,
    /// Periodic random instead: LOW_HZ:HIGH_HZ:RMS_N:PERIOD_S:SEED (H1, H2,
    /// coherence over --duration-s, the first period dropped).
    #[arg(long, value_name = "KEY", conflicts_with = "freqs")]
    random: Option<String>,
    /// Periodic random: length of the test (s).
    #[arg(long = "duration-s", value_name = "S", default_value = "8", value_parser = args::seconds)]
    duration_s: f64,
    /// A sweep (its sweep.csv): the map-based model's prediction of the same
    /// stepped sine, drawn beside the measurement.
    #[arg(long, value_name = "FILE")]
    map: Option<PathBuf>,
    /// Output folder [default: signals/host-frf-<host>-<damper>].
    #[arg(long, value_name = "DIR")]
    out: Option<PathBuf>,
}

pub fn run(a: FrfArgs, quiet: bool) -> Result<()> {
    let (scene, test) = a
        .common
        .test(Excitation::Release { x0_m: 1e-3 }, a.duration_s)?;
    let out = a.out.clone().unwrap_or_else(|| {
        PathBuf::from("signals").join(format!(
            "host-frf-{}-{}",
            test.host.name,
            damper_slug(test.damper)
        ))
    });
    // The map: the DEM's efficiency for the model, Yang's for the
    // structure-independent figure at each point's frequency and Γ.
    let maps = match &a.map {
        Some(path) => {
            let file =
                SweepFile::read(path).with_context(|| format!("--map {}", path.display()))?;
            let of = |source| {
                dissipation_map(&file, Some(scene.enclosure.orientation), None, source)
                    .with_context(|| format!("--map {}", path.display()))
            };
            Some((of(MapSource::Dem)?, of(MapSource::Yang)?))
        }
        None => None,
    };
    let freqs = a.freqs.clone().map(|f| f.0).unwrap_or_default();
    let plan = SteppedSine {
        freqs_hz: freqs.clone(),
        force_n: a.force_n,
        settle_cycles: a.settle_cycles,
        record_cycles: a.record_cycles,
        beds: a.beds,
    };
    if a.random.is_none() {
        plan.validate().map_err(|e| {
            let flag = match e.key.as_str() {
                "record_cycles" => "--record-cycles",
                "settle_cycles" => "--settle-cycles",
                "force_n" => "--force-n",
                "beds" => "--beds",
                _ => "--freq",
            };
            anyhow::Error::from(e.renamed(flag))
        })?;
    }
    let made = OutputDir::prepare(&out)
        .with_context(|| format!("cannot create output folder {}", out.display()))?;
    if let Some(key) = &a.random {
        return made.keep_if_ok(random(&a, key, &scene, test, &out, quiet));
    }
    let progress = Mutex::new((ProgressLine::new("host frf", quiet), 0usize));
    let total = freqs.len();
    let done = |p: &vlab::experiment::host_frf::FrfPoint| {
        if let Ok(mut g) = progress.lock() {
            g.1 += 1;
            let n = g.1;
            g.0.note(&format!(
                "  {n}/{total}: {:.2} Hz, Gamma {:.2}, {:.1} s wall",
                p.freq_hz, p.gamma, p.wall_time_s
            ));
        }
    };
    let beds = a.common.cache.source(&mut |n| eprintln!("{n}"));
    let mut measured = made.keep_if_ok(
        run_stepped_sine(&scene, &beds, &test, &plan, &done).context("the stepped sine"),
    )?;
    if let Some((map, _)) = &maps {
        for p in &mut measured.points {
            if let Some(why) = map.outside(p.freq_hz, p.gamma) {
                p.warnings.push(format!(
                    "the DEM drove the damper to Gamma {:.1}, where the map cannot answer: {why}; the map's prediction and Yang's map W at this point are guesses",
                    p.gamma
                ));
            }
        }
    }
    // The comparisons a lab makes: the host without particles and with
    // their mass as a solid (linear, a second each).
    let compare = |damper: Damper| -> Result<SteppedSineResult> {
        let mut t: HostTest = test.clone();
        t.damper = damper;
        run_stepped_sine(&scene, &beds, &t, &plan, &|_| {}).context("the comparison")
    };
    let empty = compare(Damper::Empty)?;
    let solid = compare(Damper::Solid)?;
    let started = Instant::now();
    let predicted = maps
        .as_ref()
        .map(|(m, _)| stepped_sine(m, &test.host, &freqs, a.force_n));
    let predict_ms = started.elapsed().as_secs_f64() * 1e3;
    // Yang's energy per cycle at each point's frequency and amplitude, as
    // power.
    let yang_w: Vec<f64> = measured
        .points
        .iter()
        .map(|p| {
            maps.as_ref().map_or(f64::NAN, |(_, yang)| {
                let d = yang.damper_at(p.freq_hz, p.amplitude_m);
                let v =
                    d.gamma * scene.simulation.gravity_mps2 / (std::f64::consts::TAU * p.freq_hz);
                d.efficiency * 4.0 * v * v * yang.particle_mass_kg * p.freq_hz
            })
        })
        .collect();
    report(
        &a,
        &test,
        &measured,
        (&empty, &solid),
        (predicted.as_deref(), &yang_w),
        predict_ms,
        &out,
    )
}

/// What the damper power's +- holds: the record's periods, and the
/// bed-to-bed part where it was measured.
fn error_note(points: &[vlab::experiment::host_frf::FrfPoint]) -> String {
    use vlab::experiment::bed_spread::BedToBed;
    if let Some(BedToBed::Ensemble { beds }) = points.first().map(|p| p.bed_to_bed) {
        return format!(
            "  the damper's +- is one sigma of the mean over the {beds} beds run at each frequency, from their spread (Student's t on {}), never less than their records' errors make it",
            crate::cli::shake::degrees_of_freedom(beds.saturating_sub(1) as usize)
        );
    }
    let measured: Vec<String> = points
        .iter()
        .filter_map(|p| match p.bed_to_bed {
            BedToBed::Measured { rel, beds } => Some(format!(
                "{:.1} % at {} Hz ({beds} beds)",
                100.0 * rel,
                p.freq_hz
            )),
            BedToBed::NotMeasured | BedToBed::Ensemble { .. } => None,
        })
        .collect();
    let record = "the damper's +- is one sigma from the record's periods, each balanced for the host's stored energy";
    if measured.len() == points.len() {
        format!(
            "  {record}, and the bed-to-bed part measured here: {}",
            measured.join(", ")
        )
    } else if measured.is_empty() {
        format!(
            "  {record} alone: independent beds can spread more (on plate-40hz at 5 N, by 7 % of the damper's power at 39 Hz and 9 % at 44 Hz; docs/host.md)"
        )
    } else {
        format!(
            "  {record}; the bed-to-bed part added where measured ({}), not at the other frequencies",
            measured.join(", ")
        )
    }
}

/// A frequency's predicted response and how many roots it had.
type Predicted = (vlab::host::map_model::SteadyResponse, usize);

fn report(
    a: &FrfArgs,
    test: &HostTest,
    measured: &SteppedSineResult,
    (empty, solid): (&SteppedSineResult, &SteppedSineResult),
    (predicted, yang_w): (Option<&[Predicted]>, &[f64]),
    predict_ms: f64,
    out: &Path,
) -> Result<()> {
    println!(
        "{} on {}, {} N stepped sine: {} frequencies in {:.1} s wall ({} + {} cycles each)",
        test.damper.label(),
        test.host.name,
        a.force_n,
        measured.points.len(),
        measured.wall_time_s,
        a.settle_cycles,
        a.record_cycles
    );
    println!(
        "  freq_hz  |X|/F mm/N  Gamma   P_in W    dE/dt W   damper W (P_in - dE/dt - host)  truth: work on damper W  damper dissipated W{}",
        if predicted.is_some() {
            "  map |X|/F mm/N  Yang's map W"
        } else {
            ""
        }
    );
    let mut csv = String::from(
        "freq_hz,receptance_re_m_per_n,receptance_im_m_per_n,amplitude_m,gamma,true_amplitude_m,power_input_w,host_storage_w,damper_power_w,damper_power_stderr_w,damper_power_record_stderr_w,true_input_w,true_host_w,true_damper_work_w,true_damper_w,host_energy_drift_w,steady,empty_receptance_m_per_n,solid_receptance_m_per_n,predicted_receptance_m_per_n,yang_map_w\n",
    );
    for (k, p) in measured.points.iter().enumerate() {
        let pred = predicted
            .and_then(|v| v.iter().find(|(r, _)| r.freq_hz == p.freq_hz))
            .map(|(r, _)| r.amplitude_m / a.force_n);
        println!(
            "  {:7.2}  {:10.4}  {:5.2}  {:8.5}  {:8.5}  {:8.5} +- {:7.5}            {:10.5}  {:10.5}{}",
            p.freq_hz,
            p.receptance().norm() * 1e3,
            p.gamma,
            p.power_input_w,
            p.host_storage_w,
            p.damper_power_w,
            p.damper_power_stderr_w,
            p.true_damper_work_w,
            p.true_damper_w,
            pred.map_or(String::new(), |h| format!(
                "        {:10.4}  {:12.5}",
                h * 1e3,
                yang_w[k]
            ))
        );
        if p.damper_power_stderr_w.is_nan() {
            // The balance uses the record's whole periods less the first
            // and the last.
            let why = if a.record_cycles < 18 {
                "fewer than 16 balanced periods (the first and last recorded cycles are not used)"
            } else {
                "the record's periods are correlated over about its length (the host's response beats)"
            };
            println!("           +- not known: {why}; more --record-cycles");
        }
        for w in &p.warnings {
            eprintln!("warning: {} Hz: {w}", p.freq_hz);
        }
        for (what, other) in [("the empty host", empty), ("the solid mass", solid)] {
            for w in other.points.get(k).map_or(&[][..], |q| &q.warnings[..]) {
                eprintln!(
                    "warning: {} Hz, {what} (the comparison, and the dB against it): {w}",
                    p.freq_hz
                );
            }
        }
        if !p.steady {
            println!(
                "           not steady: the host's stored energy moved by {:.4} W over the record ({:+.1} % of the input; booked in the balance, but the damper is not at its steady state: more --settle-cycles)",
                p.host_storage_w,
                100.0 * p.host_storage_w / p.power_input_w
            );
        }
        csv.push_str(&format!(
            "{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}\n",
            p.freq_hz,
            p.receptance_re,
            p.receptance_im,
            p.amplitude_m,
            p.gamma,
            p.true_amplitude_m,
            p.power_input_w,
            p.host_storage_w,
            p.damper_power_w,
            p.damper_power_stderr_w,
            p.damper_power_record_stderr_w,
            p.true_input_w,
            p.true_host_w,
            p.true_damper_work_w,
            p.true_damper_w,
            p.host_energy_drift_w,
            p.steady,
            empty.points[k].receptance().norm(),
            solid.points[k].receptance().norm(),
            pred.unwrap_or(f64::NAN),
            yang_w[k]
        ));
    }
    println!("{}", error_note(&measured.points));
    let reduction =
        |other: &SteppedSineResult| 20.0 * (measured.peak_m_per_n / other.peak_m_per_n).log10();
    println!(
        "  peak {:.4} mm/N at {:.2} Hz: {:+.1} dB against the empty host ({:.4} mm/N at {:.2} Hz), {:+.1} dB against the solid mass ({:.4} mm/N at {:.2} Hz)",
        measured.peak_m_per_n * 1e3,
        measured.peak_freq_hz,
        reduction(empty),
        empty.peak_m_per_n * 1e3,
        empty.peak_freq_hz,
        reduction(solid),
        solid.peak_m_per_n * 1e3,
        solid.peak_freq_hz
    );
    match (&measured.half_power, &measured.half_power_note) {
        (Some(h), _) => println!(
            "  half-power loss factor {:.4} ({:.2}-{:.2} Hz); the empty host's {}",
            h.loss_factor,
            h.f_low_hz,
            h.f_high_hz,
            match (&empty.half_power, &empty.half_power_note) {
                (Some(e), _) => format!("{:.4}", e.loss_factor),
                (None, Some(why)) => format!("not measured: {why}"),
                (None, None) => "not measured".to_string(),
            }
        ),
        (None, Some(why)) => println!("  no half-power loss factor: {why}"),
        _ => {}
    }
    if predicted.is_some() {
        println!(
            "  map-based prediction of the same {} frequencies: {:.1} ms",
            measured.points.len(),
            predict_ms
        );
    }
    write_text(&out.join("frf.csv"), &csv)?;
    let json = serde_json::json!({
        "host": test.host,
        "damper": test.damper,
        "force_n": a.force_n,
        "settle_cycles": a.settle_cycles,
        "record_cycles": a.record_cycles,
        "measured": measured,
        "empty": empty,
        "solid": solid,
        "predicted": predicted.map(|v| v.iter().map(|(r, n)| serde_json::json!({"response": r, "roots": n})).collect::<Vec<_>>()),
        "predict_ms": predict_ms,
    });
    write_text(&out.join("frf.json"), &serde_json::to_string_pretty(&json)?)?;
    plot_frf(out, test, measured, empty, solid, predicted, a.force_n)?;
    println!("wrote {}", out.display());
    Ok(())
}

/// `frf-magnitude.svg` (dB re 1 m/N) and `frf-phase.svg`.
fn plot_frf(
    dir: &Path,
    test: &HostTest,
    measured: &SteppedSineResult,
    empty: &SteppedSineResult,
    solid: &SteppedSineResult,
    predicted: Option<&[Predicted]>,
    force_n: f64,
) -> Result<()> {
    let db = |h: f64| 20.0 * h.log10();
    let mag = |r: &SteppedSineResult| -> Vec<(f64, f64)> {
        r.points
            .iter()
            .map(|p| (p.freq_hz, db(p.receptance().norm())))
            .collect()
    };
    let phase = |r: &SteppedSineResult| -> Vec<(f64, f64)> {
        r.points
            .iter()
            .map(|p| (p.freq_hz, p.receptance().arg().to_degrees()))
            .collect()
    };
    let line = |name: &str, points| Series {
        name: name.into(),
        points,
        style: SeriesStyle::Line,
    };
    let mut series = vec![
        line("empty host", mag(empty)),
        line("particles' mass as a solid", mag(solid)),
        Series {
            name: format!("{} (coupled DEM)", test.damper.label()),
            points: mag(measured),
            style: SeriesStyle::Points,
        },
    ];
    let mut phases = vec![
        line("empty host", phase(empty)),
        line("particles' mass as a solid", phase(solid)),
        Series {
            name: format!("{} (coupled DEM)", test.damper.label()),
            points: phase(measured),
            style: SeriesStyle::Points,
        },
    ];
    if let Some(p) = predicted {
        series.push(line(
            "map-based model",
            p.iter()
                .map(|(r, _)| (r.freq_hz, db(r.amplitude_m / force_n)))
                .collect(),
        ));
        phases.push(line(
            "map-based model",
            p.iter()
                .map(|(r, _)| (r.freq_hz, r.phase_rad.to_degrees()))
                .collect(),
        ));
    }
    plot_xy_svg(
        &dir.join("frf-magnitude.svg"),
        &format!(
            "Receptance at the damper, {} N at the drive, {}",
            force_n, test.host.name
        ),
        "frequency (Hz)",
        "|X / F| (dB re 1 m/N)",
        &series,
    )?;
    plot_xy_svg(
        &dir.join("frf-phase.svg"),
        &format!("Phase of the receptance, {}", test.host.name),
        "frequency (Hz)",
        "phase of X / F (degrees)",
        &phases,
    )?;
    Ok(())
}

fn random(
    a: &FrfArgs,
    key: &str,
    scene: &vlab::scene::Scene,
    mut test: HostTest,
    out: &Path,
    quiet: bool,
) -> Result<()> {
    test.excitation = Excitation::parse(&format!("random:{key}"))
        .map_err(|e| anyhow::Error::from(e.renamed("--random")))?;
    let Excitation::Lines { lines, .. } = &test.excitation else {
        anyhow::bail!("--random {key}: not a periodic random force");
    };
    let period_s = key
        .split(':')
        .nth(3)
        .and_then(|p| p.parse::<f64>().ok())
        .unwrap_or(1.0);
    if a.duration_s < 3.0 * period_s {
        anyhow::bail!(
            "--duration-s = {} s: must be at least three periods of the random force ({} s each): one dropped, two averaged",
            a.duration_s,
            period_s
        );
    }
    let band = (
        lines.first().map_or(0.0, |l| l.freq_hz),
        lines.last().map_or(0.0, |l| l.freq_hz),
    );
    let run = super::run_test(scene, &test, a.common.cache, quiet)?;
    let frf = random_frf(&run, &test.rig, period_s)?;
    write_records(out, &run)?;
    let mut csv = String::from(
        "freq_hz,h1_re_m_per_n,h1_im_m_per_n,h2_re_m_per_n,h2_im_m_per_n,coherence,h1_magnitude_stderr_rel\n",
    );
    let mut h1 = Vec::new();
    let mut h2 = Vec::new();
    let mut coh = Vec::new();
    for (k, f) in frf.freq_hz.iter().enumerate() {
        if *f < band.0 || *f > band.1 {
            continue;
        }
        csv.push_str(&format!(
            "{},{},{},{},{},{},{}\n",
            f,
            frf.h1[k].re,
            frf.h1[k].im,
            frf.h2[k].re,
            frf.h2[k].im,
            frf.coherence[k],
            frf.magnitude_stderr_rel(k)
        ));
        h1.push((*f, 20.0 * frf.h1[k].norm().log10()));
        h2.push((*f, 20.0 * frf.h2[k].norm().log10()));
        coh.push((*f, frf.coherence[k]));
    }
    write_text(&out.join("frf.csv"), &csv)?;
    plot_xy_svg(
        &out.join("frf-magnitude.svg"),
        &format!(
            "H1 and H2 of the receptance, periodic random, {}",
            test.host.name
        ),
        "frequency (Hz)",
        "|X / F| (dB re 1 m/N)",
        &[
            Series {
                name: "H1".into(),
                points: h1,
                style: SeriesStyle::Line,
            },
            Series {
                name: "H2".into(),
                points: h2,
                style: SeriesStyle::Line,
            },
        ],
    )?;
    plot_xy_svg(
        &out.join("coherence.svg"),
        &format!("Coherence, periodic random, {}", test.host.name),
        "frequency (Hz)",
        "coherence",
        &[Series {
            name: "coherence".into(),
            points: coh.clone(),
            style: SeriesStyle::Line,
        }],
    )?;
    let low = coh
        .iter()
        .cloned()
        .fold((f64::NAN, 2.0), |b, p| if p.1 < b.1 { p } else { b });
    println!(
        "{} on {}, periodic random {}: {} periods averaged, {:.1} s wall; coherence lowest {:.3} at {:.1} Hz",
        test.damper.label(),
        test.host.name,
        key,
        frf.blocks,
        run.wall_time_s,
        low.1,
        low.0
    );
    println!("wrote {}", out.display());
    Ok(())
}
