//! `vlab host frf`: the host's frequency response with the damper, by a
//! stepped sine (the lab's receptance, its half-power loss factor, the peak
//! against the host without particles and with their mass as a solid, the
//! power-input estimate of the damper's dissipation against the DEM's, and
//! with `--map` the map-based prediction beside it) or by a periodic random
//! force (H1, H2 and coherence). [`vlab::experiment::host_test::frf`] does the work.

use std::path::{Path, PathBuf};
use std::sync::Mutex;

use anyhow::{Context, Result};
use clap::Args;

use vlab::atomic_write::OutputDir;
use vlab::experiment::host_test::frf::{FrfPoint, SteppedSine};
use vlab::experiment::host_test::frf_outcome::{
    ForceLevels, FrfMaps, RandomForce, RandomFrfOutcome, SteppedSineOutcome, SweptFrfOutcome,
};
use vlab::experiment::host_test::{HostRun, HostTest};
use vlab::host::DissipationMap;
use vlab::host::{Excitation, PeriodicRandom, RandomNoise};
use vlab::scene::Scene;
use vlab::study::dissipation_map::{MapSource, dissipation_map};

use super::{FreqList, HostTestArgs, damper_slug};
use crate::cli::args;
use crate::cli::progress::ProgressLine;

#[derive(Debug, Clone, Args)]
#[command(allow_negative_numbers = true)]
pub struct FrfArgs {
    #[command(flatten)]
    common: HostTestArgs,
    /// Stepped sine: the frequencies (Hz), FROM:TO:STEP or a comma-separated list.
    #[arg(long = "freq", value_name = "LIST", value_parser = super::parse_freqs, required_unless_present_any = ["random", "swept", "noise", "burst"])]
    freqs: Option<FreqList>,
    /// Force amplitude at the drive point (N). A stepped sine takes several,
    /// comma-separated (3,5,8): one stepped sine per level, each in its own
    /// folder force-<N>N, and the receptances side by side in levels.csv and
    /// levels.svg (a linear host's coincide; a granular damper's do not).
    #[arg(long = "force-n", value_name = "N", default_value = "5", value_parser = args::newtons, value_delimiter = ',', num_args = 1..)]
    force_n: Vec<f64>,
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
    /// Stepped sine in one run, up the frequencies and back down, the bed's
    /// and the host's state carried from each step to the next (a lab's
    /// sine controller): shows a jump or hysteresis where the damper has
    /// one. One bed; writes updown.csv, updown.json and updown.svg.
    #[arg(long = "up-down", conflicts_with_all = ["random", "map", "swept", "noise", "burst"])]
    up_down: bool,
    /// Periodic random instead: LOW_HZ:HIGH_HZ:RMS_N:PERIOD_S:SEED (H1, H2,
    /// coherence over --duration-s, the first period dropped).
    #[arg(long, value_name = "KEY", conflicts_with = "freqs")]
    random: Option<String>,
    /// Swept sine instead: START_HZ:END_HZ:SWEEP_S, a linear chirp at
    /// --force-n from rest, then silence until --duration-s (the response
    /// must die out in it); the receptance from the whole record's DFTs.
    #[arg(long, value_name = "KEY", conflicts_with_all = ["freqs", "random", "map"])]
    swept: Option<String>,
    /// True random instead: LOW_HZ:HIGH_HZ:RMS_N:SEED, band-limited noise
    /// that does not repeat, analysed in Hann-windowed blocks of --block-s
    /// overlapping by half (the first block's length dropped).
    #[arg(long, value_name = "KEY", conflicts_with_all = ["freqs", "random", "swept", "map"])]
    noise: Option<String>,
    /// True random: length of a block (s); its lines are 1 / BLOCK_S apart.
    #[arg(long = "block-s", value_name = "S", default_value = "2", value_parser = args::seconds)]
    block_s: f64,
    /// Burst random instead: LOW_HZ:HIGH_HZ:RMS_N:PERIOD_S:ON_FRACTION:SEED,
    /// the noise on for the first ON_FRACTION of every PERIOD_S and off for
    /// the rest; blocks of one period, no window (the response must die out
    /// while off).
    #[arg(long, value_name = "KEY", conflicts_with_all = ["freqs", "random", "swept", "map", "noise"])]
    burst: Option<String>,
    /// Random or swept sine: length of the test (s).
    #[arg(long = "duration-s", value_name = "S", default_value = "8", value_parser = args::seconds)]
    duration_s: f64,
    /// A sweep (its sweep.csv): the map-based model's prediction of the same
    /// stepped sine, drawn beside the measurement.
    /// Given again (`--map COARSE --map FINE`), a later sweep replaces the
    /// conditions it holds: a map refined at the onset by a finer Γ grid
    /// and more seeds there, from a sweep of the same scene and rig.
    #[arg(long, value_name = "FILE")]
    map: Vec<PathBuf>,
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
    let maps = maps(&a, &scene)?;
    let plan = stepped_sine(&a)?;
    let sweep = a.swept.as_deref().map(|k| swept_key(k, &a)).transpose()?;
    let random = random_force(&a)?;
    let carried = match a.up_down {
        true => Some(super::updown::plan(&a.freqs, &plan)?),
        false => None,
    };
    let made = OutputDir::prepare(&out)
        .with_context(|| format!("cannot create output folder {}", out.display()))?;
    if let Some(sweep) = sweep {
        return made.keep_if_ok(swept(&a, sweep, &scene, test, &out, quiet));
    }
    if let Some(force) = random {
        return made.keep_if_ok(self::random(&a, force, &scene, test, &out, quiet));
    }
    if let Some(carried) = carried {
        let run = super::updown::run(&scene, &test, &carried, a.common.cache, &out, quiet);
        return made.keep_if_ok(run);
    }
    let maps = maps.as_ref().map(|(dem, yang)| FrfMaps { dem, yang });
    if a.force_n.len() == 1 {
        made.keep_if_ok(stepped(&a, &scene, &test, &plan, maps, &out, quiet))?;
        println!("wrote {}", out.display());
        return Ok(());
    }
    let mut outcomes = Vec::new();
    for &force_n in &a.force_n {
        let plan = SteppedSine {
            force_n,
            ..plan.clone()
        };
        let dir = out.join(format!("force-{force_n}N"));
        let made_level = std::fs::create_dir_all(&dir)
            .with_context(|| format!("cannot create {}", dir.display()));
        made.keep_if_ok(made_level)?;
        let outcome = stepped(&a, &scene, &test, &plan, maps, &dir, quiet);
        outcomes.push(made.keep_if_ok(outcome)?);
    }
    let levels = ForceLevels {
        outcomes: &outcomes,
    };
    made.keep_if_ok(
        levels
            .write(&out)
            .with_context(|| format!("writing into {}", out.display())),
    )?;
    report_levels(&levels);
    println!("wrote {}", out.display());
    Ok(())
}

/// One stepped sine of `plan`: run, printed, written into `out`.
fn stepped(
    a: &FrfArgs,
    scene: &Scene,
    test: &HostTest,
    plan: &SteppedSine,
    maps: Option<FrfMaps<'_>>,
    out: &Path,
    quiet: bool,
) -> Result<SteppedSineOutcome> {
    let progress = Mutex::new((ProgressLine::new("host frf", quiet), 0usize));
    let total = plan.freqs_hz.len();
    let done = |p: &FrfPoint| {
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
    let outcome = SteppedSineOutcome::run(scene, &beds, test, plan, maps, &done)
        .context("the stepped sine")?;
    report(&outcome);
    outcome
        .write(out)
        .with_context(|| format!("writing into {}", out.display()))?;
    Ok(outcome)
}

/// The levels side by side: at each frequency |X|/F at every force, and
/// how far the levels part.
fn report_levels(levels: &ForceLevels<'_>) {
    let forces: Vec<String> = levels
        .outcomes
        .iter()
        .map(|o| format!("{} N", o.plan.force_n))
        .collect();
    println!(
        "receptance |X|/F (mm/N) at each force ({}):",
        forces.join(", ")
    );
    for (f, row) in levels.rows() {
        let cells: Vec<String> = row.iter().map(|h| format!("{:9.4}", h * 1e3)).collect();
        println!("  {f:7.2} Hz  {}", cells.join("  "));
    }
    let (spread, at_hz) = levels.largest_spread();
    println!(
        "  the levels part by up to {:.2} % (at {at_hz} Hz: the largest over the smallest |X|/F, less 1); a linear host's coincide",
        100.0 * spread
    );
}

/// The map of `--map`: the DEM's efficiency for the model, Yang's for the
/// structure-independent figure at each point's frequency and Γ.
fn maps(a: &FrfArgs, scene: &Scene) -> Result<Option<(DissipationMap, DissipationMap)>> {
    if a.map.is_empty() {
        return Ok(None);
    }
    let (file, label) = super::read_maps(&a.map)?;
    let of = |source| {
        dissipation_map(&file, Some(scene.enclosure.orientation), None, source)
            .with_context(|| format!("--map {label}"))
    };
    Ok(Some((of(MapSource::Dem)?, of(MapSource::Yang)?)))
}

/// The stepped sine of the flags, checked unless the test is the random
/// one (a refusal names the flag).
fn stepped_sine(a: &FrfArgs) -> Result<SteppedSine> {
    let plan = SteppedSine {
        freqs_hz: a.freqs.clone().map(|f| f.0).unwrap_or_default(),
        force_n: a.force_n[0],
        settle_cycles: a.settle_cycles,
        record_cycles: a.record_cycles,
        beds: a.beds,
    };
    let other = a.random.is_some() || a.swept.is_some() || a.noise.is_some() || a.burst.is_some();
    if a.force_n.len() > 1 && (other || a.up_down) {
        anyhow::bail!(
            "--force-n = {:?} N: several force levels are for the stepped sine (--freq alone); --swept, --up-down and --random take one",
            a.force_n
        );
    }
    if let Some(w) = a.force_n.windows(2).find(|w| w[1] <= w[0]) {
        anyhow::bail!(
            "--force-n = {} after {} N: force levels must be ascending",
            w[1],
            w[0]
        );
    }
    if a.force_n.len() > 8 {
        anyhow::bail!(
            "--force-n: {} levels: at most 8 (each is a stepped sine)",
            a.force_n.len()
        );
    }
    if a.random.is_none() && a.swept.is_none() && a.noise.is_none() && a.burst.is_none() {
        for &force_n in &a.force_n[1..] {
            SteppedSine {
                force_n,
                ..plan.clone()
            }
            .validate()
            .map_err(|e| anyhow::Error::from(e.renamed("--force-n")))?;
        }
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
    Ok(plan)
}

/// What the damper power's +- holds: the record's periods, and the
/// bed-to-bed part where it was measured.
fn error_note(points: &[FrfPoint]) -> String {
    use vlab::experiment::host_test::bed_spread::BedToBed;
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

/// Prints the stepped sine: a row per frequency, what cannot be trusted,
/// the peak against the comparisons and the half-power loss factor.
fn report(o: &SteppedSineOutcome) {
    let (test, plan, measured) = (&o.test, &o.plan, &o.measured);
    println!(
        "{} on {}, {} N stepped sine: {} frequencies in {:.1} s wall ({} + {} cycles each)",
        test.damper.label(),
        test.host.name,
        plan.force_n,
        measured.points.len(),
        measured.wall_time_s,
        plan.settle_cycles,
        plan.record_cycles
    );
    println!(
        "  freq_hz  |X|/F mm/N (+- %)     Gamma   P_in W    dE/dt W   damper W (P_in - dE/dt - host)  truth: work on damper W  damper dissipated W{}",
        if o.predicted.is_some() {
            "  map |X|/F mm/N (range claimed)  Yang's map W"
        } else {
            ""
        }
    );
    for k in 0..measured.points.len() {
        report_point(o, k);
    }
    println!("{}", error_note(&measured.points));
    if measured.points.iter().any(|p| p.amplitude_error_is_spread) {
        println!(
            "  |X|/F's +- from the record's periods; * where they are correlated over the record (the host beats): their spread, a cautious error"
        );
    }
    report_peak(o);
    if o.predicted.is_some() {
        println!(
            "  map-based prediction of the same {} frequencies: {:.1} ms",
            measured.points.len(),
            o.predict_ms
        );
    }
}

/// Frequency `k` of the stepped sine: its row, why its +- is not known,
/// its warnings and the empty host's and solid mass's, and whether it
/// was steady.
fn report_point(o: &SteppedSineOutcome, k: usize) {
    let p = &o.measured.points[k];
    println!(
        "  {:7.2}  {:10.4} +- {:<6.3}{} {:5.2}  {:8.5}  {:8.5}  {:8.5} +- {:7.5}            {:10.5}  {:10.5}{}",
        p.freq_hz,
        p.receptance().norm() * 1e3,
        100.0 * p.amplitude_stderr_m / p.amplitude_m,
        if p.amplitude_error_is_spread {
            "*"
        } else {
            " "
        },
        p.gamma,
        p.power_input_w,
        p.host_storage_w,
        p.damper_power_w,
        p.damper_power_stderr_w,
        p.true_damper_work_w,
        p.true_damper_w,
        o.predicted_receptance(k).zip(o.predicted_range(k)).map_or(
            String::new(),
            |(h, (lo, hi))| format!(
                "        {:10.4} ({:.4} .. {:.4}{})  {:12.5}",
                h * 1e3,
                lo * 1e3,
                hi * 1e3,
                if (lo..=hi).contains(&p.receptance().norm()) {
                    ""
                } else {
                    ", the DEM outside"
                },
                o.yang_map_w[k]
            )
        )
    );
    if p.damper_power_stderr_w.is_nan() {
        // The balance uses the record's whole periods less the first and
        // the last.
        let why = if o.plan.record_cycles < 18 {
            "fewer than 16 balanced periods (the first and last recorded cycles are not used)"
        } else {
            "the record's periods are correlated over about its length (the host's response beats)"
        };
        println!("           +- not known: {why}; more --record-cycles");
    }
    for w in o.warnings_at(k) {
        eprintln!("warning: {w}");
    }
    for why in p.unsteady_reasons() {
        println!("           not steady: {why}");
    }
}

/// The peak against the empty host's and the solid mass's, and the
/// half-power loss factors.
fn report_peak(o: &SteppedSineOutcome) {
    let (measured, empty, solid) = (&o.measured, &o.empty, &o.solid);
    println!(
        "  peak {:.4} mm/N at {:.2} Hz: {:+.1} dB against the empty host ({:.4} mm/N at {:.2} Hz), {:+.1} dB against the solid mass ({:.4} mm/N at {:.2} Hz)",
        measured.peak_m_per_n * 1e3,
        measured.peak_freq_hz,
        o.reduction_db(empty),
        empty.peak_m_per_n * 1e3,
        empty.peak_freq_hz,
        o.reduction_db(solid),
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
}

/// The random force of `--random`, `--noise` or `--burst` (with
/// `--block-s`), checked with `--duration-s` before any work; a refused
/// field keeps its name after the flag (`--random rms_n = ...`).
fn random_force(a: &FrfArgs) -> Result<Option<(RandomForce, String)>> {
    let named = |flag: &str, e: vlab::validation::InvalidParameter| match e.key.as_str() {
        "excitation" => anyhow::Error::from(e.renamed(flag)),
        field => anyhow::Error::from(e.renamed(&format!("{flag} {field}"))),
    };
    let (force, key) = if let Some(key) = &a.random {
        let force = PeriodicRandom::parse(key).map_err(|e| named("--random", e))?;
        (RandomForce::from(force), key.clone())
    } else if let Some(key) = &a.noise {
        let noise = RandomNoise::parse(&format!("noise:{key}")).map_err(|e| named("--noise", e))?;
        let force = RandomForce::noise(noise, a.block_s)
            .map_err(|e| anyhow::Error::from(e.renamed("--block-s")))?;
        (force, key.clone())
    } else if let Some(key) = &a.burst {
        let noise = RandomNoise::parse(&format!("burst:{key}")).map_err(|e| named("--burst", e))?;
        (RandomForce::noise(noise, a.block_s)?, key.clone())
    } else {
        return Ok(None);
    };
    RandomFrfOutcome::check_duration(a.duration_s, force)
        .map_err(|e| anyhow::Error::from(e.renamed("--duration-s")))?;
    Ok(Some((force, key)))
}

/// The run of a host test for an outcome's `run` (the run's own warnings
/// printed as it ends), counting in `printed` how many it printed, so that
/// [`print_analysis_warnings`] prints only what the analysis adds.
fn counted_run<'a>(
    scene: &'a Scene,
    a: &'a FrfArgs,
    quiet: bool,
    printed: &'a mut usize,
) -> impl FnOnce(&HostTest) -> Result<HostRun> + 'a {
    move |t| {
        let run = super::run_test(scene, t, a.common.cache, quiet);
        *printed = run.as_ref().map_or(0, |r| r.warnings.len());
        run
    }
}

/// The warnings the analysis added to `run`'s after its first `printed`.
fn print_analysis_warnings(run: &HostRun, printed: usize) {
    for w in run.warnings.get(printed..).unwrap_or_default() {
        eprintln!("host: warning: {}", w.text);
    }
}

/// A random test: H1, H2 and coherence over `--duration-s`.
fn random(
    a: &FrfArgs,
    (force, key): (RandomForce, String),
    scene: &vlab::scene::Scene,
    test: HostTest,
    out: &Path,
    quiet: bool,
) -> Result<()> {
    let mut printed = 0;
    let outcome = RandomFrfOutcome::run(test, force, counted_run(scene, a, quiet, &mut printed))?;
    print_analysis_warnings(&outcome.run, printed);
    outcome
        .write(out)
        .with_context(|| format!("writing into {}", out.display()))?;
    let (low_hz, lowest) = outcome.lowest_coherence();
    println!(
        "{} on {}, {} {}: {} {} averaged, {:.1} s wall; coherence lowest {:.3} at {:.1} Hz",
        outcome.test.damper.label(),
        outcome.test.host.name,
        force.kind(),
        key,
        outcome.frf.blocks,
        match force {
            RandomForce::Periodic(_) => "periods",
            RandomForce::Noise { .. } => "blocks",
        },
        outcome.run.wall_time_s,
        lowest,
        low_hz
    );
    println!("wrote {}", out.display());
    Ok(())
}

/// `--swept START_HZ:END_HZ:SWEEP_S` at `--force-n`, checked with
/// `--duration-s` before any work (a refusal names the flag).
fn swept_key(key: &str, a: &FrfArgs) -> Result<Excitation> {
    let sweep = Excitation::parse(&format!("sweep:{key}:{}", a.force_n[0])).map_err(|e| match e
        .key
        .as_str()
    {
        "force_n" => anyhow::Error::from(e.renamed("--force-n")),
        "excitation" => anyhow::anyhow!("--swept = '{key}': must be START_HZ:END_HZ:SWEEP_S"),
        field => anyhow::Error::from(e.renamed(&format!("--swept {field}"))),
    })?;
    if let Excitation::Sweep { duration_s, .. } = sweep
        && a.duration_s <= duration_s
    {
        anyhow::bail!(
            "--duration-s = {} s: must be longer than the sweep ({duration_s} s): the response must die out in the silence after it",
            a.duration_s
        );
    }
    Ok(sweep)
}

/// The swept sine: the receptance over the sweep's band, its peak and
/// half-power loss factor, and whether the response died out.
fn swept(
    a: &FrfArgs,
    sweep: Excitation,
    scene: &vlab::scene::Scene,
    test: HostTest,
    out: &Path,
    quiet: bool,
) -> Result<()> {
    let mut printed = 0;
    let o = SweptFrfOutcome::run(test, sweep, counted_run(scene, a, quiet, &mut printed))?;
    print_analysis_warnings(&o.run, printed);
    o.write(out)
        .with_context(|| format!("writing into {}", out.display()))?;
    let (peak, at_hz, half) = o.peak();
    println!(
        "{} on {}, swept sine {}-{} Hz at {} N: {} lines in the band, {:.1} s wall; peak {:.4} mm/N at {:.2} Hz",
        o.test.damper.label(),
        o.test.host.name,
        o.band_hz.0,
        o.band_hz.1,
        a.force_n[0],
        o.in_band().count(),
        o.run.wall_time_s,
        peak * 1e3,
        at_hz
    );
    match half {
        Ok(h) => println!(
            "  half-power loss factor {:.4} ({:.2}-{:.2} Hz)",
            h.loss_factor, h.f_low_hz, h.f_high_hz
        ),
        Err(why) => println!("  no half-power loss factor: {why}"),
    }
    println!(
        "  for a linear host the ratio is its receptance; a granular damper's depends on the sweep's rate and direction (compare --up-down)"
    );
    println!("wrote {}", out.display());
    Ok(())
}
