//! `vlab press`: a scene's particle, held, pressed onto a plate of the
//! enclosure's material, horizontally or vertically; its normal and
//! tangential force-deformation curves (thesis Section 5.4, Fig. 5.8 and
//! 5.10), and for a toroid lying flat the depth of its ripples (eq. 5.19).

use std::path::PathBuf;

use anyhow::{Context, Result, bail};
use clap::{Args, ValueEnum};

use vlab::experiment::press::outcome::{PressOutcome, PressPlan};
use vlab::experiment::press::{NormalPoint, PressConfig};
use vlab::scene::Scene;

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Config {
    /// A prolate across its long axis, an oblate or a toroid along its axis
    /// (a toroid lying flat).
    Horizontal,
    /// A prolate end-on, an oblate or a toroid across its axis (a toroid on
    /// its rim).
    Vertical,
}

#[derive(Debug, Clone, Args)]
pub struct PressArgs {
    /// Scene file whose particle is pressed (merged over the built-in thesis
    /// scene, whose particle is a 5 mm sphere).
    #[arg(long, value_name = "FILE")]
    scene: Option<PathBuf>,
    /// How the plate meets the body.
    #[arg(long, value_enum, default_value = "horizontal")]
    config: Config,
    /// Deepest deformation, as a fraction of the body's half-size along the
    /// press (the thesis' normalisation, eq. 5.17), in (0, 0.5].
    #[arg(long, default_value = "0.05")]
    max_deformation: f64,
    /// Normal deformation held while the plate slides, as a fraction of the
    /// half-size, in (0, max-deformation].
    #[arg(long, default_value = "0.01")]
    preload: f64,
    /// Points on each curve (10 to 100000).
    #[arg(long, default_value = "200")]
    points: usize,
    /// Write normal.csv, tangential.csv and press.json to this folder.
    #[arg(long, value_name = "DIR")]
    out: Option<PathBuf>,
}

pub fn run(a: PressArgs) -> Result<()> {
    check(&a)?;
    let scene = Scene::load_or_thesis(a.scene.as_deref())?;
    let plan = PressPlan {
        config: match a.config {
            Config::Horizontal => PressConfig::Horizontal,
            Config::Vertical => PressConfig::Vertical,
        },
        max_deformation: a.max_deformation,
        preload: a.preload,
        points: a.points,
    };
    let o = PressOutcome::run(&scene, plan)?;
    let last = o.normal.last().copied().unwrap_or(NormalPoint {
        deformation_m: 0.0,
        force_n: 0.0,
        touching: 0,
    });
    println!(
        "{} ({} sub-spheres) pressed {} onto a plate of the enclosure's material: half-size {:.3} mm along the press",
        o.shape.as_str(),
        o.sub_spheres,
        plan.config.as_str(),
        o.half_m * 1e3
    );
    println!(
        "  normal      at {:.4} of the half-size ({:.2} um): {:.4} N, {} sub-sphere(s) touching",
        a.max_deformation,
        last.deformation_m * 1e6,
        last.force_n,
        last.touching
    );
    let held = o.tangential.last();
    println!(
        "  tangential  held at {:.4} of the half-size, slid {:.2} um: {:.4} N (mu times the normal force there: {:.4} N)",
        a.preload,
        held.map_or(0.0, |p| p.displacement_m) * 1e6,
        held.map_or(0.0, |p| p.force_n),
        o.friction * o.preload_normal_n
    );
    if let Some(r) = &o.ripple {
        println!(
            "  ripples     {:.2} um deep between the {} sub-spheres (eq. 5.19: {:.2} um; {:.2e} of the tube radius, {:.2e} of the centre circle's diameter 2a): deeper than that the multi-sphere toroid is stiffer than the smooth one (Section 5.4.4); {} of the curve's points are deeper",
            r.exact_m * 1e6,
            r.sub_spheres,
            r.eq_5_19_m * 1e6,
            r.exact_m / o.half_m,
            r.exact_m / (2.0 * r.centre_radius_m),
            r.points_deeper
        );
    }
    if let Some(dir) = &a.out {
        o.write(dir)
            .with_context(|| format!("writing into {}", dir.display()))?;
        println!("wrote {}", dir.display());
    }
    Ok(())
}

/// The flags' ranges, each refusal naming the flag.
fn check(a: &PressArgs) -> Result<()> {
    if !(a.max_deformation > 0.0 && a.max_deformation <= 0.5) {
        bail!(
            "--max-deformation = {}: must be in (0, 0.5] (a fraction of the body's half-size along the press)",
            a.max_deformation
        );
    }
    if !(a.preload > 0.0 && a.preload <= a.max_deformation) {
        bail!(
            "--preload = {}: must be in (0, {}] (a fraction of the half-size, at most --max-deformation)",
            a.preload,
            a.max_deformation
        );
    }
    if !(10..=100_000).contains(&a.points) {
        bail!("--points = {}: must be in [10, 100000]", a.points);
    }
    Ok(())
}
