//! `vlab shake`: drive the damper at one frequency and amplitude and write what
//! the simulator knows, the DEM truth (`summary.json`, `kinematics.csv`).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use clap::{Args, ValueEnum};
use serde::Serialize;

use vlab::atomic_write::write_bytes_atomic;
use vlab::dem::{Dissipation, LedgerBalance};
use vlab::rig::{RigFile, RigSpec, ShakerKind, check_limits};
use vlab::scene::damper::{DriveOutcome, settle_bed};
use vlab::scene::file::{Orientation, Scene};
use vlab::scene::measurement::{
    CalibrationSource, Measured, ShakeExperiment, ShakeSetup, run_measured_shake,
};
use vlab::scene::record::TruthSamples;
use vlab::signals::{
    PhaseCalibration, Series, SeriesStyle, Trace, TraceMetadata, plot_xy_svg, write_csv,
    write_wav_with_full_scale,
};

use super::args;
use super::progress::ProgressLine;

/// Sample rate of the truth record (Hz), the thesis DAQ's.
pub const TRUTH_SAMPLE_RATE_HZ: f64 = 40_000.0;

#[derive(Debug, Clone, Args)]
#[command(allow_negative_numbers = true)]
pub struct ShakeArgs {
    /// Drive frequency (Hz).
    #[arg(long = "freq", value_name = "HZ", default_value = "40", value_parser = args::freq_hz)]
    pub freq_hz: f64,
    /// Acceleration amplitude Γ: peak enclosure acceleration / g (dimensionless).
    #[arg(long, default_value = "20", value_parser = args::gamma)]
    pub gamma: f64,
    #[command(flatten)]
    pub scene: SceneOverrides,
    /// The rig that measures the damper: a built-in name (thesis-shaker, ideal)
    /// or a rig file (TOML).
    #[arg(long, value_name = "NAME|FILE", default_value = vlab::rig::DEFAULT_RIG)]
    pub rig: String,
    /// How the enclosure is moved [default: the rig's own].
    #[arg(long, value_enum)]
    pub shaker: Option<ShakerChoice>,
    /// Length of the record after the transient cycles (s); sets the number of
    /// steady cycles instead of --steady-cycles.
    #[arg(long = "duration-s", value_name = "S", value_parser = args::seconds, conflicts_with = "steady_cycles")]
    pub duration_s: Option<f64>,
    /// Phase-error table of the rig (from `vlab calibrate`) [default: measure
    /// one now on the empty enclosure at the drive frequency].
    #[arg(long, value_name = "FILE")]
    pub calibration: Option<PathBuf>,
    /// Output folder [default: signals/<scene>-<freq>Hz-G<gamma>].
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
    /// Print the summary as JSON on standard output.
    #[arg(long)]
    pub json: bool,
}

/// The drive, as named on the command line.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum ShakerChoice {
    /// The enclosure follows u = Gamma g / w^2 sin(w t) exactly.
    Prescribed,
    /// A lumped electrodynamic shaker whose motion the particles disturb.
    Electrodynamic,
}

impl ShakerChoice {
    pub fn kind(self) -> ShakerKind {
        match self {
            ShakerChoice::Prescribed => ShakerKind::Prescribed,
            ShakerChoice::Electrodynamic => ShakerKind::Electrodynamic,
        }
    }
}

/// The rig named by `--rig`, its drive, and a refusal of what it cannot do.
pub fn resolve_rig(
    name: &str,
    shaker: Option<ShakerChoice>,
    freq_hz: f64,
    gamma: f64,
    g_mps2: f64,
) -> Result<(RigSpec, ShakerKind)> {
    let rig = RigSpec::from_name_or_path(name).with_context(|| format!("--rig {name}"))?;
    let kind = shaker.map_or(rig.shaker.kind, ShakerChoice::kind);
    check_limits(&rig, freq_hz, gamma, g_mps2)?;
    if kind == ShakerKind::Electrodynamic && rig.shaker.electrodynamic.is_none() {
        bail!(
            "--shaker electrodynamic: rig {} has no [shaker.electrodynamic] section; use --shaker prescribed or --rig thesis-shaker",
            rig.name
        );
    }
    Ok((rig, kind))
}

/// Scene options shared by the commands that run the damper.
#[derive(Debug, Clone, Args)]
pub struct SceneOverrides {
    /// Scene file (TOML) merged over the built-in thesis scene.
    #[arg(long, value_name = "FILE")]
    pub scene: Option<PathBuf>,
    /// Drive cycles in all [scene default: 8].
    #[arg(long)]
    pub cycles: Option<u32>,
    /// Last cycles kept as the steady state [scene default: 5].
    #[arg(long)]
    pub steady_cycles: Option<u32>,
    /// Gravity relative to the drive axis [scene default: vertical].
    #[arg(long, value_enum)]
    pub orientation: Option<Orientation>,
    /// Seed of the random fill [scene default: 1].
    #[arg(long)]
    pub seed: Option<u64>,
    /// Time step (s) [scene default: 1e-6]; at most the Rayleigh limit.
    #[arg(long = "dt-s", value_name = "S", value_parser = args::seconds)]
    pub dt_s: Option<f64>,
}

impl SceneOverrides {
    /// The scene (built-in or file) with the command-line overrides applied and
    /// everything validated; the messages name the flag or key at fault.
    pub fn resolve(&self) -> Result<Scene> {
        let mut scene = match &self.scene {
            Some(path) => Scene::load_over_preset(path)?,
            None => Scene::thesis(),
        };
        if let Some(c) = self.cycles {
            if c == 0 {
                bail!("--cycles 0 is invalid: must be at least 1 drive cycle");
            }
            scene.drive.cycles = c;
        }
        if let Some(s) = self.steady_cycles {
            scene.drive.steady_cycles = s;
        }
        let (cycles, steady) = (scene.drive.cycles, scene.drive.steady_cycles);
        if steady == 0 || steady > cycles {
            bail!("--steady-cycles {steady} is invalid: must lie in [1, --cycles = {cycles}]");
        }
        if let Some(o) = self.orientation {
            scene.enclosure.orientation = o;
        }
        if let Some(seed) = self.seed {
            scene.simulation.seed = seed;
        }
        if let Some(dt) = self.dt_s {
            let limit = scene.rayleigh_limit_s();
            if dt > limit {
                bail!(
                    "--dt-s {dt:.3e} is above the stability limit {limit:.3e} s (Rayleigh estimate, thesis eq. 3.31, for {} m {} spheres): use at most {limit:.3e} s",
                    scene.particles.diameter_m,
                    particle_material_name(&scene)
                );
            }
            scene.simulation.dt_s = vlab::scene::file::TimeStepSpec::Seconds(dt);
        }
        scene.validate().map_err(anyhow::Error::msg)?;
        Ok(scene)
    }
}

fn particle_material_name(scene: &Scene) -> String {
    match &scene.particles.material {
        vlab::scene::file::MaterialSpec::Named(n) => n.clone(),
        vlab::scene::file::MaterialSpec::Inline(_) => "custom".into(),
    }
}

/// Checks that a drive can be resolved by the scene's time step.
pub fn check_drive(scene: &Scene, freq_hz: f64) -> Result<()> {
    let dt = scene.dt_s();
    let period = 1.0 / freq_hz;
    if period < 200.0 * dt {
        bail!(
            "--freq {freq_hz} Hz is too high for the time step {dt:.3e} s: a cycle would take fewer than 200 steps (at most {:.0} Hz)",
            1.0 / (200.0 * dt)
        );
    }
    if period < 4.0 / TRUTH_SAMPLE_RATE_HZ {
        bail!(
            "--freq {freq_hz} Hz is too high for the {TRUTH_SAMPLE_RATE_HZ} Hz record: at most {} Hz",
            TRUTH_SAMPLE_RATE_HZ / 4.0
        );
    }
    Ok(())
}

/// Short text for a number in a folder name: 40 → "40", 2.5 → "2.5".
pub fn compact(x: f64) -> String {
    format!("{x}")
}

#[derive(Debug, Serialize)]
pub struct YieldVelocities {
    pub particle_particle_mps: f64,
    pub particle_wall_mps: f64,
}

/// What the DEM knows: thesis eq. 6.3–6.10.
#[derive(Debug, Serialize)]
pub struct DemTruth {
    /// Dissipated energy per cycle, averaged over the steady cycles (J), eq. 6.9.
    pub energy_per_cycle_j: f64,
    /// Maximum dissipated energy per cycle 4 (Γ g / ω)² M (J), eq. 6.10.
    pub e_max_j: f64,
    /// `energy_per_cycle_j / e_max_j`, eq. 6.8.
    pub efficiency: f64,
    /// Energy dissipated over the steady cycles, by source (J).
    pub dissipated_j: Dissipation,
    /// The same per cycle (J); sums to `energy_per_cycle_j`.
    pub dissipated_per_cycle_j: Dissipation,
    /// Work the enclosure did on the particles per steady cycle (J): what an
    /// input-power measurement sees.
    pub work_in_per_cycle_j: f64,
    /// (work in − dissipated) / dissipated over the steady cycles: zero in a
    /// steady state; otherwise the bed stored or gave back energy.
    pub steadiness_rel: f64,
    /// |ledger residual| / dissipated energy over the whole drive.
    pub ledger_residual_rel: f64,
    /// Energy balance of the whole drive (J).
    pub ledger: LedgerBalance,
    /// Energy balance of the steady cycles (J).
    pub steady_ledger: LedgerBalance,
    /// Largest particle speed seen at a cycle boundary (m/s).
    pub largest_particle_speed_mps: f64,
    /// Largest normal approach speeds at contact onset during the drive (m/s).
    pub largest_impact_speed_mps: YieldVelocities,
    /// Yield velocities of eq. 5.26, when the material has a yield strength.
    pub yield_velocity_mps: Option<YieldVelocities>,
}

impl DemTruth {
    pub fn new(out: &DriveOutcome, scene: &Scene) -> Self {
        DemTruth {
            energy_per_cycle_j: out.energy_per_cycle_j,
            e_max_j: out.e_max_j,
            efficiency: out.efficiency,
            dissipated_j: out.steady.dissipated,
            dissipated_per_cycle_j: out.dissipated_per_cycle,
            work_in_per_cycle_j: out.work_in_per_cycle_j,
            steadiness_rel: out.work_in_per_cycle_j / out.energy_per_cycle_j - 1.0,
            ledger_residual_rel: out.whole.residual_relative(),
            ledger: out.whole,
            steady_ledger: out.steady,
            largest_particle_speed_mps: out.largest_speed_mps,
            largest_impact_speed_mps: YieldVelocities {
                particle_particle_mps: out.impact_speeds.particle_particle_mps,
                particle_wall_mps: out.impact_speeds.particle_wall_mps,
            },
            yield_velocity_mps: scene
                .yield_velocities_mps()
                .map(|(pp, pw)| YieldVelocities {
                    particle_particle_mps: pp,
                    particle_wall_mps: pw,
                }),
        }
    }

    /// Warnings a user must see: impacts beyond yield, a record that is not
    /// steady.
    pub fn warnings(&self, freq_hz: f64) -> Vec<String> {
        let mut w = Vec::new();
        if let Some(y) = &self.yield_velocity_mps {
            let v = &self.largest_impact_speed_mps;
            for (what, speed, limit) in [
                (
                    "particle-particle",
                    v.particle_particle_mps,
                    y.particle_particle_mps,
                ),
                ("particle-wall", v.particle_wall_mps, y.particle_wall_mps),
            ] {
                if speed > limit {
                    w.push(format!(
                        "{what} impacts reached {speed:.2} m/s, above the yield velocity {limit:.2} m/s (thesis eq. 5.26): the contacts would yield and the constant restitution of the model no longer holds (Section 5.5.4)"
                    ));
                }
            }
        }
        if self.steadiness_rel.abs() > 0.02 {
            w.push(format!(
                "the bed is not in a steady state over the record: the enclosure put in {:+.1} % of the energy the DEM dissipated (the bed {} the difference), so any input-power measurement differs from the DEM's dissipation by that much; lengthen the transient with --cycles (at {freq_hz} Hz try {} cycles)",
                100.0 * self.steadiness_rel,
                if self.steadiness_rel < 0.0 { "gave back" } else { "stored" },
                (freq_hz * 0.5).ceil().max(16.0)
            ));
        }
        w
    }
}

#[derive(Debug, Serialize)]
pub struct ShakeSummary {
    pub vlab_version: &'static str,
    pub scene: String,
    pub freq_hz: f64,
    pub gamma: f64,
    pub orientation: &'static str,
    pub n_particles: usize,
    pub particle_mass_kg: f64,
    pub fill_ratio: f64,
    pub seed: u64,
    pub dt_s: f64,
    pub cycles: u32,
    pub steady_cycles: u32,
    /// Drive steps.
    pub steps: u64,
    /// Simulated time spent pouring and settling before the drive (s).
    pub settle_time_s: f64,
    /// Start of the steady window and of the rig's record, from the drive start (s).
    pub steady_start_s: f64,
    pub rig: String,
    pub shaker: &'static str,
    pub sample_rate_hz: f64,
    /// Wall-clock time of the drive's stepping loop (s).
    pub wall_time_s: f64,
    /// Particles × drive steps / `wall_time_s`.
    pub particle_steps_per_s: f64,
    /// Wall-clock time of pouring and settling (s).
    pub settle_wall_time_s: f64,
    pub threads: usize,
    pub dem: DemTruth,
    pub measured: Measured,
    pub warnings: Vec<String>,
    pub files: Vec<String>,
}

/// Runs the command.
pub fn run(a: ShakeArgs, quiet: bool) -> Result<()> {
    let mut scene = a.scene.resolve()?;
    if let Some(d) = a.duration_s {
        let steady = (d * a.freq_hz).ceil().max(2.0) as u32;
        let transient = scene.drive.cycles - scene.drive.steady_cycles;
        scene.drive.cycles = transient + steady;
        scene.drive.steady_cycles = steady;
    }
    check_drive(&scene, a.freq_hz)?;
    if scene.drive.steady_cycles < 2 {
        bail!(
            "--steady-cycles {} is invalid: the rig's record needs at least 2 whole periods for Yang's method",
            scene.drive.steady_cycles
        );
    }
    let g = scene.simulation.gravity_mps2;
    let (rig, kind) = resolve_rig(&a.rig, a.shaker, a.freq_hz, a.gamma, g)?;
    let calibration = match &a.calibration {
        Some(path) => {
            let table = PhaseCalibration::load_json(path)
                .with_context(|| format!("--calibration {}", path.display()))?;
            CalibrationSource::Given(table, format!("table {}", path.display()))
        }
        None => CalibrationSource::OnTheFly,
    };
    let out_dir = a.out.clone().unwrap_or_else(|| {
        PathBuf::from("signals").join(format!(
            "{}-{}Hz-G{}",
            scene.name,
            compact(a.freq_hz),
            compact(a.gamma)
        ))
    });
    let made = OutputDir::prepare(&out_dir)?;
    let mut progress = ProgressLine::new("shake", quiet);
    let setup = ShakeSetup {
        rig,
        shaker: kind,
        freq_hz: a.freq_hz,
        gamma: a.gamma,
        calibration,
    };
    let result = simulate(&scene, &setup, &mut progress);
    progress.finish();
    let (summary, experiment) = made.keep_if_ok(result)?;
    write_outputs(
        &out_dir,
        summary,
        &experiment,
        &scene,
        &setup,
        a.json,
        &mut progress,
    )
}

/// An output folder made before a long run, so that an unwritable path fails
/// at once; if the run fails, every folder it made is removed again (innermost
/// first, and only while empty).
pub struct OutputDir {
    created: Vec<PathBuf>,
}

impl OutputDir {
    pub fn prepare(path: &Path) -> Result<Self> {
        if path.is_file() {
            bail!("--out {} is a file, not a folder", path.display());
        }
        let created: Vec<PathBuf> = path
            .ancestors()
            .take_while(|p| !p.as_os_str().is_empty() && !p.exists())
            .map(Path::to_path_buf)
            .collect();
        std::fs::create_dir_all(path)
            .with_context(|| format!("cannot create output folder {}", path.display()))?;
        Ok(OutputDir { created })
    }

    /// Passes `result` through; on error removes the folders this run made.
    pub fn keep_if_ok<T>(&self, result: Result<T>) -> Result<T> {
        if result.is_err() {
            for dir in &self.created {
                if std::fs::remove_dir(dir).is_err() {
                    break;
                }
            }
        }
        result
    }
}

/// Pours, settles, drives through the rig and measures.
fn simulate(
    scene: &Scene,
    setup: &ShakeSetup,
    progress: &mut ProgressLine,
) -> Result<(ShakeSummary, ShakeExperiment)> {
    let dt = scene.dt_s();
    let bed =
        settle_bed(scene, dt, &mut |p| progress.update(p)).context("preparing the particle bed")?;
    let mut world = bed.world;
    let experiment = run_measured_shake(scene, &mut world, setup, &mut |p| progress.update(p))
        .context("driving and measuring the damper")?;
    let outcome = &experiment.outcome;
    let n = world.particles.len();
    let dem = DemTruth::new(outcome, scene);
    let mut warnings = experiment.measured.clipping.clone();
    warnings.extend(dem.warnings(setup.freq_hz));
    let summary = ShakeSummary {
        vlab_version: env!("CARGO_PKG_VERSION"),
        scene: scene.name.clone(),
        freq_hz: setup.freq_hz,
        gamma: setup.gamma,
        orientation: scene.enclosure.orientation.as_str(),
        n_particles: n,
        particle_mass_kg: world.particles.total_mass_kg(),
        fill_ratio: scene.fill_ratio(),
        seed: scene.simulation.seed,
        dt_s: dt,
        cycles: scene.drive.cycles,
        steady_cycles: scene.drive.steady_cycles,
        steps: outcome.steps,
        settle_time_s: bed.settle_time_s,
        steady_start_s: outcome.steady_start_s,
        rig: setup.rig.name.clone(),
        shaker: experiment.measured.shaker,
        sample_rate_hz: setup.rig.daq.sample_rate_hz,
        wall_time_s: outcome.wall_time_s,
        particle_steps_per_s: (n as u64 * outcome.steps) as f64 / outcome.wall_time_s,
        settle_wall_time_s: bed.wall_time_s,
        threads: rayon::current_num_threads(),
        dem,
        measured: experiment.measured.clone(),
        warnings,
        files: Vec::new(),
    };
    Ok((summary, experiment))
}

/// The truth record as a trace.
pub fn truth_trace(samples: &TruthSamples, summary: &ShakeSummary) -> Result<Trace> {
    let start = samples.time_s.first().copied().unwrap_or(0.0);
    let mut trace = Trace::new(summary.sample_rate_hz, start)?;
    trace.metadata = TraceMetadata {
        source: format!("vlab {} shake: DEM truth", summary.vlab_version),
        rig: "none (DEM truth, no sensors)".into(),
        drive_freq_hz: Some(summary.freq_hz),
        gamma: Some(summary.gamma),
        ..Default::default()
    };
    let columns: [(&str, &str, &Vec<f64>); 6] = [
        ("enclosure_displacement", "m", &samples.displacement_m),
        ("enclosure_velocity", "m/s", &samples.velocity_mps),
        (
            "enclosure_acceleration",
            "m/s^2",
            &samples.acceleration_mps2,
        ),
        ("particle_force_axial", "N", &samples.force_axial_n),
        ("particle_force_x", "N", &samples.force_x_n),
        ("particle_force_y", "N", &samples.force_y_n),
    ];
    for (name, unit, data) in columns {
        trace.add_channel(name, unit, data.clone())?;
    }
    Ok(trace)
}

fn write_outputs(
    dir: &Path,
    mut summary: ShakeSummary,
    e: &ShakeExperiment,
    scene: &Scene,
    setup: &ShakeSetup,
    json: bool,
    progress: &mut ProgressLine,
) -> Result<()> {
    let truth = truth_trace(&e.truth, &summary)?;
    write_csv(&dir.join("kinematics.csv"), &truth)?;
    write_csv(&dir.join("trace.csv"), &e.trace)?;
    // Full scale of the WAV = the ADC's, so that ADC codes are stored exactly.
    let full_scale: BTreeMap<String, f64> = if e.daq.ideal_adc {
        BTreeMap::new()
    } else {
        e.daq
            .channels
            .iter()
            .map(|c| (c.name.clone(), c.full_scale))
            .collect()
    };
    write_wav_with_full_scale(&dir.join("trace.wav"), &e.trace, &full_scale)?;
    e.calibration.save_json(&dir.join("calibration.json"))?;
    plot_record(&dir.join("trace.svg"), &e.trace, scene, setup)?;
    summary.files = [
        "summary.json",
        "trace.csv",
        "trace.wav",
        "trace.wav.json",
        "kinematics.csv",
        "calibration.json",
        "trace.svg",
    ]
    .map(String::from)
    .to_vec();
    let text = serde_json::to_string_pretty(&summary)? + "\n";
    write_bytes_atomic(&dir.join("summary.json"), text.as_bytes())
        .with_context(|| format!("writing {}", dir.join("summary.json").display()))?;
    for w in &summary.warnings {
        progress.note(&format!("warning: {w}"));
    }
    if json {
        print!("{text}");
    } else {
        print_summary(&summary, dir);
    }
    Ok(())
}

/// Two cycles of the record as the thesis plots them (Fig. 7.12): the
/// acceleration and the force divided by the total mass, both in m/s².
fn plot_record(path: &Path, trace: &Trace, scene: &Scene, setup: &ShakeSetup) -> Result<()> {
    let a = &trace.channel(vlab::rig::ACCEL_CHANNEL)?.samples;
    let f = &trace.channel(vlab::rig::FORCE_CHANNEL)?.samples;
    let m_total = setup.rig.enclosure.mass_kg + scene.particle_mass_kg();
    let n = ((2.0 * trace.sample_rate_hz / setup.freq_hz).round() as usize).min(a.len());
    let t = |i: usize| 1e3 * trace.time_s(i);
    // The static weight is a constant offset of the force; remove its mean.
    let f_mean = f[..n].iter().sum::<f64>() / n.max(1) as f64;
    let series = [
        Series {
            name: "acceleration".into(),
            points: (0..n).map(|i| (t(i), a[i])).collect(),
            style: SeriesStyle::Line,
        },
        Series {
            name: "force / (m_enclosure + m_particles), mean removed".into(),
            points: (0..n).map(|i| (t(i), (f[i] - f_mean) / m_total)).collect(),
            style: SeriesStyle::Line,
        },
    ];
    plot_xy_svg(
        path,
        &format!(
            "{} damper, {} Hz, Gamma {}: rig {} record (cf. thesis Fig. 7.12)",
            scene.name, setup.freq_hz, setup.gamma, setup.rig.name
        ),
        "time from the record start (ms)",
        "m/s^2",
        &series,
    )?;
    Ok(())
}

fn print_summary(s: &ShakeSummary, dir: &Path) {
    let d = &s.dem;
    let m = &s.measured;
    let pc = &d.dissipated_per_cycle_j;
    let total = pc.total().max(f64::MIN_POSITIVE);
    println!(
        "{} damper, {} Hz, Gamma {}, {}: {} particles ({:.4} kg, fill {:.3}), dt {:.1e} s, seed {}",
        s.scene,
        s.freq_hz,
        s.gamma,
        s.orientation,
        s.n_particles,
        s.particle_mass_kg,
        s.fill_ratio,
        s.dt_s,
        s.seed
    );
    println!(
        "  DEM truth (last {} of {} cycles):",
        s.steady_cycles, s.cycles
    );
    println!(
        "    energy dissipated per cycle   {:.4e} J",
        d.energy_per_cycle_j
    );
    println!("    E_max = 4 (Gamma g / w)^2 M   {:.4e} J", d.e_max_j);
    println!("    damping efficiency            {:.3}", d.efficiency);
    println!(
        "    by source: particle-particle normal {:.1} %, tangential {:.1} %; particle-wall normal {:.1} %, tangential {:.1} %",
        100.0 * pc.pp_normal / total,
        100.0 * pc.pp_tangential / total,
        100.0 * pc.pw_normal / total,
        100.0 * pc.pw_tangential / total
    );
    println!(
        "    energy ledger residual        {:.1e} of the dissipated energy",
        d.ledger_residual_rel
    );
    println!(
        "  measured by rig {} ({} shaker), Yang's method over {} periods:",
        s.rig, s.shaker, m.n_periods
    );
    println!(
        "    energy per cycle              {:.4e} J  ({:+.2} % vs DEM)",
        m.energy_per_cycle_j,
        100.0 * m.error_vs_dem_rel
    );
    println!("    damping efficiency            {:.3}", m.efficiency);
    println!(
        "    phase correction              {:.3} mrad ({})",
        1e3 * m.phase_correction_rad,
        m.calibration
    );
    println!(
        "    without the correction        {:.4e} J  ({:+.2} % vs DEM; predicted leak {:+.2} %)",
        m.uncorrected_energy_per_cycle_j,
        100.0 * m.uncorrected_error_vs_dem_rel,
        100.0 * m.predicted_leak_per_cycle_j / d.energy_per_cycle_j
    );
    println!(
        "  speed {:.2} M particle-steps/s ({} thread{}), drive {:.1} s, settling {:.1} s",
        s.particle_steps_per_s / 1e6,
        s.threads,
        if s.threads == 1 { "" } else { "s" },
        s.wall_time_s,
        s.settle_wall_time_s
    );
    println!("  wrote {}", dir.display());
}
