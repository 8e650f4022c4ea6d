//! `vlab press`: a scene's particle, held, pressed onto a plate of the
//! enclosure's material, horizontally or vertically; its normal and
//! tangential force-deformation curves (thesis Section 5.4, Fig. 5.8 and
//! 5.10), and for a toroid lying flat the depth of its ripples (eq. 5.19).

use std::io::Write as _;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use clap::{Args, ValueEnum};

use glam::DVec3;
use vlab::atomic_write::write_atomic;
use vlab::dem::ContactLaw;
use vlab::dem::clumps::ClumpTemplate;
use vlab::experiment::press::{
    NormalPoint, PressConfig, TangentialPoint, half_size_m, heights_m, normal_curve,
    tangential_curve, toroid_ripple_m,
};
use vlab::scene::{Scene, ShapeKind, contact_laws};

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
    let shape = scene.particles.shape;
    let template = match scene.particle_body()? {
        Some(b) => b.template,
        None => ClumpTemplate::sphere(scene.radius_m(), scene.particle_material().density_kgm3),
    };
    let config = match a.config {
        Config::Horizontal => PressConfig::Horizontal,
        Config::Vertical => PressConfig::Vertical,
    };
    let (normal, slide) = config.axes(shape);
    let half_m = half_size_m(&template, normal);
    let law = contact_laws(&scene).particle_wall;
    let normal_pts = normal_curve(
        &law,
        &template,
        normal,
        a.max_deformation * half_m,
        a.points,
    );
    let tangential_pts = tangential_curve(
        &law,
        &template,
        (normal, slide),
        a.preload * half_m,
        (4.0 * a.preload * half_m * law.friction, a.points),
    );
    let last = normal_pts.last().copied().unwrap_or(NormalPoint {
        deformation_m: 0.0,
        force_n: 0.0,
        touching: 0,
    });
    println!(
        "{} ({} sub-spheres) pressed {} onto a plate of the enclosure's material: half-size {:.3} mm along the press",
        shape.as_str(),
        template.len(),
        config.as_str(),
        half_m * 1e3
    );
    println!(
        "  normal      at {:.4} of the half-size ({:.2} um): {:.4} N, {} sub-sphere(s) touching",
        a.max_deformation,
        last.deformation_m * 1e6,
        last.force_n,
        last.touching
    );
    print_held(&a, &law, &template, normal, &tangential_pts, half_m);
    let ripple = ripple_report(shape, config, &template, &normal_pts, half_m);
    if let Some(r) = &ripple {
        println!("  {}", r.text);
    }
    if let Some(dir) = &a.out {
        write_out(dir, &normal_pts, &tangential_pts, half_m, ripple.as_ref())?;
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

/// The tangential curve's end: how far the body slid at the preload and
/// the force that held it, against mu times the normal force there.
fn print_held(
    a: &PressArgs,
    law: &ContactLaw,
    template: &ClumpTemplate,
    normal: DVec3,
    tangential_pts: &[TangentialPoint],
    half_m: f64,
) {
    let slid = tangential_pts.last().map_or(0.0, |p| p.force_n);
    println!(
        "  tangential  held at {:.4} of the half-size, slid {:.2} um: {:.4} N (mu times the normal force there: {:.4} N)",
        a.preload,
        tangential_pts.last().map_or(0.0, |p| p.displacement_m) * 1e6,
        slid,
        law.friction
            * vlab::experiment::press::normal_force_n(
                law,
                template,
                &heights_m(template, normal),
                a.preload * half_m
            )
            .0
    );
}

/// A toroid lying flat: its ripple depth, exact and by eq. 5.19.
struct Ripple {
    exact_m: f64,
    eq_5_19_m: f64,
    text: String,
}

fn ripple_report(
    shape: ShapeKind,
    config: PressConfig,
    template: &ClumpTemplate,
    curve: &[NormalPoint],
    half_m: f64,
) -> Option<Ripple> {
    if shape != ShapeKind::Toroid || config != PressConfig::Horizontal {
        return None;
    }
    let b = template.radii_m.first().copied()?;
    let a = template.offsets_m.first()?.length();
    let n = template.len();
    let (exact_m, eq_5_19_m) = toroid_ripple_m(a, b, n);
    let beyond = curve.iter().filter(|p| p.deformation_m > exact_m).count();
    Some(Ripple {
        exact_m,
        eq_5_19_m,
        text: format!(
            "ripples     {:.2} um deep between the {n} sub-spheres (eq. 5.19: {:.2} um; {:.2e} of the tube radius, {:.2e} of the centre circle's diameter 2a): deeper than that the multi-sphere toroid is stiffer than the smooth one (Section 5.4.4); {beyond} of the curve's points are deeper",
            exact_m * 1e6,
            eq_5_19_m * 1e6,
            exact_m / half_m,
            exact_m / (2.0 * a),
        ),
    })
}

fn write_out(
    dir: &Path,
    normal: &[NormalPoint],
    tangential: &[TangentialPoint],
    half_m: f64,
    ripple: Option<&Ripple>,
) -> Result<()> {
    std::fs::create_dir_all(dir).with_context(|| format!("creating {}", dir.display()))?;
    write_atomic(&dir.join("normal.csv"), |w| {
        writeln!(
            w,
            "deformation_m,deformation_ratio,force_n,touching_sub_spheres"
        )?;
        for p in normal {
            writeln!(
                w,
                "{:e},{:e},{:e},{}",
                p.deformation_m,
                p.deformation_m / half_m,
                p.force_n,
                p.touching
            )?;
        }
        Ok(())
    })
    .with_context(|| format!("writing {}", dir.join("normal.csv").display()))?;
    write_atomic(&dir.join("tangential.csv"), |w| {
        writeln!(w, "displacement_m,displacement_ratio,force_n")?;
        for p in tangential {
            writeln!(
                w,
                "{:e},{:e},{:e}",
                p.displacement_m,
                p.displacement_m / half_m,
                p.force_n
            )?;
        }
        Ok(())
    })
    .with_context(|| format!("writing {}", dir.join("tangential.csv").display()))?;
    let json = serde_json::json!({
        "half_size_m": half_m,
        "ripple_m": ripple.map(|r| r.exact_m),
        "ripple_eq_5_19_m": ripple.map(|r| r.eq_5_19_m),
    });
    let text = serde_json::to_string_pretty(&json)?;
    write_atomic(&dir.join("press.json"), |w| w.write_all(text.as_bytes()))
        .with_context(|| format!("writing {}", dir.join("press.json").display()))?;
    Ok(())
}
