//! `vlab impact`: one collision, measured against Hertz theory (thesis Fig.
//! 5.17–5.21), with an optional contact trace.

use std::path::PathBuf;

use anyhow::{Context, Result, bail};
use clap::{Args, ValueEnum};
use serde::Serialize;

use vlab::dem::{Material, RestitutionMode};
use vlab::experiment::impact::{ImpactOutcome, ImpactSetup, Target, run_impact};
use vlab::scene::material_preset;
use vlab::signals::{Trace, TraceMetadata, write_csv};

use super::args;

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Against {
    Wall,
    Sphere,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum WallKind {
    /// The wall is of the sphere's material.
    Same,
    /// The wall does not deform.
    Rigid,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum MaterialName {
    Acrylic,
    Steel,
    Aluminium,
}

#[derive(Debug, Clone, Args)]
#[command(allow_negative_numbers = true)]
pub struct ImpactArgs {
    /// What the sphere hits.
    #[arg(long, value_enum, default_value = "wall")]
    against: Against,
    /// Wall material, with --against wall.
    #[arg(long, value_enum, default_value = "same")]
    wall: WallKind,
    /// Wall Young's modulus (Pa); overrides --wall.
    #[arg(long = "wall-youngs-pa", value_parser = args::pascals)]
    wall_youngs_pa: Option<f64>,
    /// Wall Poisson's ratio (with --wall-youngs-pa) [default: the sphere's].
    #[arg(long = "wall-poisson", value_parser = args::poisson)]
    wall_poisson: Option<f64>,
    /// Sphere material preset.
    #[arg(long, value_enum, default_value = "acrylic")]
    material: MaterialName,
    /// Sphere Young's modulus (Pa), overriding the preset.
    #[arg(long = "youngs-pa", value_parser = args::pascals)]
    youngs_pa: Option<f64>,
    /// Sphere Poisson's ratio, overriding the preset.
    #[arg(long, value_parser = args::poisson)]
    poisson: Option<f64>,
    /// Sphere density (kg/m^3), overriding the preset.
    #[arg(long = "density-kgm3", value_parser = args::density)]
    density_kgm3: Option<f64>,
    /// Sphere radius (m).
    #[arg(long = "radius-m", default_value = "0.0025", value_parser = args::metres)]
    radius_m: f64,
    /// Relative approach speed (m/s).
    #[arg(long = "speed-mps", default_value = "1", value_parser = args::speed_mps)]
    speed_mps: f64,
    /// Incidence angle from the normal (degrees), in [0, 90).
    #[arg(long = "angle-deg", default_value = "0", value_parser = args::finite)]
    angle_deg: f64,
    /// Spin about the axis normal to the plane of incidence (rad/s); positive
    /// is the rolling sense of the tangential motion.
    #[arg(long = "spin-rad-s", default_value = "0", value_parser = args::finite)]
    spin_rad_s: f64,
    /// Coefficient of restitution e, in (0, 1].
    #[arg(long, default_value = "0.86", value_parser = args::restitution)]
    cor: f64,
    /// Coefficient of friction μ, >= 0.
    #[arg(long, default_value = "0.52", value_parser = args::friction)]
    mu: f64,
    /// How the damping follows from e.
    #[arg(long = "restitution-mode", value_enum, default_value = "exact")]
    restitution_mode: Mode,
    /// Time step (s) [default: the Hertz contact duration / 400].
    #[arg(long = "dt-s", value_parser = args::seconds)]
    dt_s: Option<f64>,
    /// Write the contact history (time, overlap, forces) to this CSV file.
    #[arg(long, value_name = "FILE")]
    trace: Option<PathBuf>,
    /// Print the result as JSON.
    #[arg(long)]
    json: bool,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Mode {
    Exact,
    Thesis,
}

#[derive(Debug, Serialize)]
struct ImpactReport<'a> {
    contact_duration_s: f64,
    max_overlap_m: f64,
    max_normal_force_n: f64,
    normal_restitution: f64,
    rebound_speed_mps: f64,
    rebound_angle_deg: f64,
    rebound_spin_rad_s: f64,
    dissipated_j: f64,
    configured_restitution: f64,
    restitution_mode: &'a str,
    hertz_contact_duration_s: f64,
    hertz_max_overlap_m: f64,
    hertz_max_normal_force_n: f64,
    dt_s: f64,
    steps: u64,
}

impl ImpactArgs {
    /// The flags that set each field of [`ImpactSetup`].
    fn flags() -> args::FlagKeys {
        [
            ("material.youngs_pa", "--youngs-pa"),
            ("material.poisson", "--poisson"),
            ("material.density_kgm3", "--density-kgm3"),
            ("target.youngs_pa", "--wall-youngs-pa"),
            ("target.poisson", "--wall-poisson"),
            ("radius_m", "--radius-m"),
            ("speed_mps", "--speed-mps"),
            ("angle_deg", "--angle-deg"),
            ("spin_rad_s", "--spin-rad-s"),
            ("restitution", "--cor"),
            ("friction", "--mu"),
            ("dt_s", "--dt-s"),
        ]
        .into_iter()
        .fold(args::FlagKeys::new(), |f, (key, flag)| {
            f.set(true, key, flag)
        })
    }

    /// The sphere's material: the preset of `--material` with the flags'
    /// own values over it.
    fn material(&self) -> Material {
        let name = match self.material {
            MaterialName::Acrylic => "acrylic",
            MaterialName::Steel => "steel",
            MaterialName::Aluminium => "aluminium",
        };
        let mut material = material_preset(name).unwrap_or(Material::ACRYLIC);
        if let Some(e) = self.youngs_pa {
            material.youngs_pa = e;
        }
        if let Some(nu) = self.poisson {
            material.poisson = nu;
        }
        if let Some(rho) = self.density_kgm3 {
            material.density_kgm3 = rho;
        }
        material
    }

    fn setup(&self) -> Result<ImpactSetup> {
        let material = self.material();
        let target = match self.against {
            Against::Sphere => {
                if self.wall_youngs_pa.is_some() || self.wall_poisson.is_some() {
                    bail!("--wall-youngs-pa and --wall-poisson apply only with --against wall");
                }
                Target::Sphere
            }
            Against::Wall => Target::Wall(match (self.wall_youngs_pa, self.wall) {
                (Some(e), _) => Material {
                    youngs_pa: e,
                    poisson: self.wall_poisson.unwrap_or(material.poisson),
                    ..material
                },
                (None, WallKind::Rigid) => Material::rigid(),
                (None, WallKind::Same) => material,
            }),
        };
        let setup = ImpactSetup {
            material,
            radius_m: self.radius_m,
            target,
            speed_mps: self.speed_mps,
            angle_deg: self.angle_deg,
            spin_rad_s: self.spin_rad_s,
            restitution: self.cor,
            friction: self.mu,
            mode: match self.restitution_mode {
                Mode::Exact => RestitutionMode::Exact,
                Mode::Thesis => RestitutionMode::Thesis,
            },
            dt_s: self.dt_s,
        };
        setup
            .validate()
            .map_err(|e| Self::flags().name_flags(e.into()))?;
        if let Some(dt) = self.dt_s {
            let t_c = setup.hertz_duration_s();
            if dt > t_c / 10.0 {
                bail!(
                    "--dt-s {dt:.3e} is too coarse: the collision lasts {t_c:.3e} s (Hertz, thesis eq. 5.10); use at most {:.3e} s (10 steps per contact; 400 is the default)",
                    t_c / 10.0
                );
            }
        }
        Ok(setup)
    }
}

pub fn run(a: ImpactArgs) -> Result<()> {
    let setup = a.setup()?;
    if let Some(path) = &a.trace {
        if path.is_dir() {
            bail!("--trace {} is a folder, not a file", path.display());
        }
        let parent = path.parent().filter(|p| !p.as_os_str().is_empty());
        if let Some(folder) = parent.filter(|p| !p.is_dir()) {
            bail!(
                "--trace {}: folder {} does not exist",
                path.display(),
                folder.display()
            );
        }
    }
    let out = run_impact(&setup).context("simulating the collision")?;
    if let Some(path) = &a.trace {
        write_trace(path, &out, &setup)?;
    }
    let mode = match a.restitution_mode {
        Mode::Exact => "exact",
        Mode::Thesis => "thesis",
    };
    let report = ImpactReport {
        contact_duration_s: out.contact_duration_s,
        max_overlap_m: out.max_overlap_m,
        max_normal_force_n: out.max_normal_force_n,
        normal_restitution: out.normal_restitution,
        rebound_speed_mps: out.rebound_speed_mps,
        rebound_angle_deg: out.rebound_angle_deg,
        rebound_spin_rad_s: out.rebound_spin_rad_s,
        dissipated_j: out.dissipated_j,
        configured_restitution: a.cor,
        restitution_mode: mode,
        hertz_contact_duration_s: out.hertz_duration_s,
        hertz_max_overlap_m: out.hertz_max_overlap_m,
        hertz_max_normal_force_n: out.hertz_max_force_n,
        dt_s: out.dt_s,
        steps: out.steps,
    };
    if a.json {
        println!("{}", serde_json::to_string_pretty(&report)?);
    } else {
        print_report(&report, &a);
    }
    Ok(())
}

fn write_trace(path: &std::path::Path, out: &ImpactOutcome, setup: &ImpactSetup) -> Result<()> {
    let start = out.trace.first().map(|s| s.time_s).unwrap_or(0.0);
    let mut trace = Trace::new(1.0 / out.dt_s, start)?;
    trace.metadata = TraceMetadata {
        source: format!(
            "vlab {} impact: {} m/s at {} deg",
            env!("CARGO_PKG_VERSION"),
            setup.speed_mps,
            setup.angle_deg
        ),
        rig: "none (DEM contact history)".into(),
        ..Default::default()
    };
    let column = |f: fn(&vlab::experiment::impact::ImpactSample) -> f64| -> Vec<f64> {
        out.trace.iter().map(f).collect()
    };
    trace.add_channel("overlap", "m", column(|s| s.overlap_m))?;
    trace.add_channel("normal_force", "N", column(|s| s.normal_force_n))?;
    trace.add_channel("tangential_force", "N", column(|s| s.tangential_force_n))?;
    Ok(write_csv(path, &trace)?)
}

fn print_report(r: &ImpactReport, a: &ImpactArgs) {
    let rel = |x: f64, y: f64| 100.0 * (x / y - 1.0);
    let name = |v: Option<clap::builder::PossibleValue>| {
        v.map(|p| p.get_name().to_string()).unwrap_or_default()
    };
    println!(
        "{} sphere, radius {} m, against a {}, {} m/s at {} deg, spin {} rad/s, e = {} ({} mode), mu = {}",
        name(a.material.to_possible_value()),
        a.radius_m,
        name(a.against.to_possible_value()),
        a.speed_mps,
        a.angle_deg,
        a.spin_rad_s,
        a.cor,
        r.restitution_mode,
        a.mu
    );
    println!("                         simulated      Hertz (eq. 5.8, 5.10)");
    println!(
        "  contact duration     {:.4e} s   {:.4e} s  ({:+.2} %)",
        r.contact_duration_s,
        r.hertz_contact_duration_s,
        rel(r.contact_duration_s, r.hertz_contact_duration_s)
    );
    println!(
        "  max overlap          {:.4e} m   {:.4e} m  ({:+.2} %)",
        r.max_overlap_m,
        r.hertz_max_overlap_m,
        rel(r.max_overlap_m, r.hertz_max_overlap_m)
    );
    println!(
        "  max normal force     {:.4e} N   {:.4e} N  (elastic reference)",
        r.max_normal_force_n, r.hertz_max_normal_force_n
    );
    println!("  normal restitution   {:.4}", r.normal_restitution);
    println!(
        "  rebound              {:.4} m/s at {:.2} deg from the normal, spin {:.2} rad/s",
        r.rebound_speed_mps, r.rebound_angle_deg, r.rebound_spin_rad_s
    );
    println!("  dissipated           {:.4e} J", r.dissipated_j);
    println!("  time step            {:.3e} s, {} steps", r.dt_s, r.steps);
}
