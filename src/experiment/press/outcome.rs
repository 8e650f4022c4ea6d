//! The press of [`crate::experiment::press`] as an experiment: a scene's particle and a
//! plan (which way, how deep, how hard held) in, both curves, the force
//! that held the body and, for a toroid lying flat, its ripples (thesis eq.
//! 5.19) out, with the files a lab keeps (`normal.csv`, `tangential.csv`,
//! `press.json`). `vlab press` checks its flags, runs it and prints it.

use std::io::Write as _;
use std::path::{Path, PathBuf};

use crate::atomic_write::write_atomic;
use crate::dem::clumps::ClumpTemplate;
use crate::scene::particle_shape::ShapeKind;
use crate::scene::{Scene, SceneError, contact_laws};

use crate::experiment::press::{
    NormalPoint, PressConfig, TangentialPoint, half_size_m, heights_m, normal_curve,
    normal_force_n, tangential_curve, toroid_ripple_m,
};

/// How the body is pressed: which way, how deep, at what pre-load it
/// slides, and how many points each curve has.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PressPlan {
    pub config: PressConfig,
    /// Deepest normal deformation, a fraction of the body's half-size along
    /// the press.
    pub max_deformation: f64,
    /// Normal deformation held while the plate slides, the same fraction.
    pub preload: f64,
    pub points: usize,
}

/// A toroid lying flat: how deep its surface dips between sub-spheres,
/// exactly and by eq. 5.19, and how many points of the normal curve lie
/// deeper.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ripple {
    pub exact_m: f64,
    pub eq_5_19_m: f64,
    /// The centre circle's radius `a` (m).
    pub centre_radius_m: f64,
    pub sub_spheres: usize,
    pub points_deeper: usize,
}

/// Both curves of one body and what they say.
#[derive(Debug, Clone)]
pub struct PressOutcome {
    pub plan: PressPlan,
    pub shape: ShapeKind,
    pub sub_spheres: usize,
    /// The body's half-size along the press (m).
    pub half_m: f64,
    pub normal: Vec<NormalPoint>,
    pub tangential: Vec<TangentialPoint>,
    /// The friction coefficient of the plate's contact and the normal force
    /// at the pre-load: the tangential curve's ceiling is their product.
    pub friction: f64,
    pub preload_normal_n: f64,
    pub ripple: Option<Ripple>,
}

impl PressOutcome {
    /// Presses `scene`'s particle onto a plate of its enclosure's material
    /// as `plan` says.
    pub fn run(scene: &Scene, plan: PressPlan) -> Result<PressOutcome, SceneError> {
        let shape = scene.particles.shape;
        let template = match scene.particle_body()? {
            Some(b) => b.template,
            None => ClumpTemplate::sphere(scene.radius_m(), scene.particle_material().density_kgm3),
        };
        let (normal, slide) = plan.config.axes(shape);
        let half_m = half_size_m(&template, normal);
        let law = contact_laws(scene).particle_wall;
        let (deepest_m, held_m) = (plan.max_deformation * half_m, plan.preload * half_m);
        let normal_pts = normal_curve(&law, &template, normal, deepest_m, plan.points);
        let slide_m = 4.0 * held_m * law.friction;
        let tangential = tangential_curve(
            &law,
            &template,
            (normal, slide),
            held_m,
            (slide_m, plan.points),
        );
        let heights = heights_m(&template, normal);
        let preload_normal_n = normal_force_n(&law, &template, &heights, held_m).0;
        let ripple = ripple(shape, plan.config, &template, &normal_pts);
        Ok(PressOutcome {
            plan,
            shape,
            sub_spheres: template.len(),
            half_m,
            normal: normal_pts,
            tangential,
            friction: law.friction,
            preload_normal_n,
            ripple,
        })
    }

    /// Writes `normal.csv`, `tangential.csv` and `press.json` into `dir`
    /// (made if need be), each file atomically.
    pub fn write(&self, dir: &Path) -> Result<(), SceneError> {
        let fail = |path: PathBuf| move |source| SceneError::Write { path, source };
        std::fs::create_dir_all(dir).map_err(fail(dir.to_path_buf()))?;
        let half_m = self.half_m;
        let path = dir.join("normal.csv");
        write_atomic(&path, |w| {
            writeln!(
                w,
                "deformation_m,deformation_ratio,force_n,touching_sub_spheres"
            )?;
            for p in &self.normal {
                let ratio = p.deformation_m / half_m;
                writeln!(
                    w,
                    "{:e},{:e},{:e},{}",
                    p.deformation_m, ratio, p.force_n, p.touching
                )?;
            }
            Ok(())
        })
        .map_err(fail(path))?;
        let path = dir.join("tangential.csv");
        write_atomic(&path, |w| {
            writeln!(w, "displacement_m,displacement_ratio,force_n")?;
            for p in &self.tangential {
                let ratio = p.displacement_m / half_m;
                writeln!(w, "{:e},{:e},{:e}", p.displacement_m, ratio, p.force_n)?;
            }
            Ok(())
        })
        .map_err(fail(path))?;
        let json = serde_json::json!({
            "half_size_m": half_m,
            "ripple_m": self.ripple.map(|r| r.exact_m),
            "ripple_eq_5_19_m": self.ripple.map(|r| r.eq_5_19_m),
        });
        let path = dir.join("press.json");
        serde_json::to_string_pretty(&json)
            .map_err(std::io::Error::other)
            .and_then(|text| write_atomic(&path, |w| w.write_all(text.as_bytes())))
            .map_err(fail(path))
    }
}

/// The ripples of a toroid lying flat (none for any other body or way).
fn ripple(
    shape: ShapeKind,
    config: PressConfig,
    template: &ClumpTemplate,
    curve: &[NormalPoint],
) -> Option<Ripple> {
    if shape != ShapeKind::Toroid || config != PressConfig::Horizontal {
        return None;
    }
    let b = template.radii_m.first().copied()?;
    let a = template.offsets_m.first()?.length();
    let n = template.len();
    let (exact_m, eq_5_19_m) = toroid_ripple_m(a, b, n);
    Some(Ripple {
        exact_m,
        eq_5_19_m,
        centre_radius_m: a,
        sub_spheres: n,
        points_deeper: curve.iter().filter(|p| p.deformation_m > exact_m).count(),
    })
}
