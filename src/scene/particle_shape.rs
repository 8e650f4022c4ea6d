//! The shape of a scene's particles: spheres, or rigid multi-sphere bodies
//! (Terzioglu's thesis, Chapter 4) dimensioned as Chapter 8 dimensions them.
//!
//! `[particles] shape` is `"sphere"` (the default), `"prolate"` or
//! `"oblate"` (a spheroid of `aspect_ratio` a/b, revolved about its a axis,
//! eq. 8.1–8.2), `"toroid"` (a circular torus of `hole_ratio`
//! (a − b)/(a + b), eq. 8.4), or `"clump"` (the sub-spheres of
//! `clump_file`, rows `x_m,y_m,z_m,radius_m`). Every shape has the volume of
//! the sphere of `diameter_m` (also spelt `equivalent_diameter_m`), as the
//! thesis' particles of one study do. A prolate is Markauskas' analytical
//! placement (Section 4.4.1), a toroid the ring of Section 4.4.2, an oblate
//! the grid fill of Section 4.3 ([`crate::shape`]); `sub_spheres` sets how
//! many (the thesis' 51, 9 and 50 by default, Section 8.2).
//!
//! The DEM body ([`ParticleBody`]) takes its mass and inertia from the union
//! of its sub-spheres (eq. 4.1 and 4.5, measured to 1e-6), in its principal
//! frame: a prolate's long axis is the body's x, an oblate's and a torus's
//! axis of symmetry its z.

use std::collections::HashMap;
use std::path::PathBuf;
use std::sync::{Mutex, OnceLock};

use glam::DVec3;
use serde::{Deserialize, Serialize};

use crate::dem::clumps::ClumpTemplate;
use crate::scene::error::SceneError;
use crate::shape::{self, MultiSphere};
use crate::validation::{Bound, InvalidParameter, count_in, in_range};

/// What the particles of a scene are.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ShapeKind {
    /// Spheres of `diameter_m` (the thesis' damper).
    #[default]
    Sphere,
    /// Prolate spheroids, `aspect_ratio` > 1.
    Prolate,
    /// Oblate spheroids, `aspect_ratio` < 1.
    Oblate,
    /// Circular toroids of `hole_ratio`.
    Toroid,
    /// Bodies of the sub-spheres in `clump_file`.
    Clump,
}

impl ShapeKind {
    /// True for spheres.
    pub fn is_sphere(&self) -> bool {
        *self == ShapeKind::Sphere
    }

    /// The name a scene file gives it.
    pub fn as_str(self) -> &'static str {
        match self {
            ShapeKind::Sphere => "sphere",
            ShapeKind::Prolate => "prolate",
            ShapeKind::Oblate => "oblate",
            ShapeKind::Toroid => "toroid",
            ShapeKind::Clump => "clump",
        }
    }

    /// The thesis' number of sub-spheres (Section 8.2): 51 for prolates, 9
    /// for oblates, 50 for toroids; a clump file says its own.
    pub fn default_sub_spheres(self) -> Option<usize> {
        match self {
            ShapeKind::Prolate => Some(51),
            ShapeKind::Oblate => Some(9),
            ShapeKind::Toroid => Some(50),
            ShapeKind::Sphere | ShapeKind::Clump => None,
        }
    }
}

/// Most sub-spheres a generated body may have.
pub const MAX_SUB_SPHERES: usize = 401;

/// Aspect ratios a spheroid may have: a prolate in (1, 10], an oblate in
/// [0.2, 1).
const PROLATE_MAX: f64 = 10.0;
const OBLATE_MIN: f64 = 0.2;
/// Hole ratios a toroid may have: (0, 0.9].
const HOLE_MAX: f64 = 0.9;

/// The shape keys of `[particles]`, as a scene file gives them.
#[derive(Debug, Clone, Copy)]
pub struct ShapeKeys<'a> {
    pub kind: ShapeKind,
    pub aspect_ratio: Option<f64>,
    pub hole_ratio: Option<f64>,
    pub sub_spheres: Option<usize>,
    pub clump_file: Option<&'a PathBuf>,
}

impl ShapeKeys<'_> {
    /// Refuses a key the shape does not take, a missing key it needs, and a
    /// value out of range, naming the key, its unit and range.
    ///
    /// Over 80 lines: one match over the shapes, each arm the keys it takes and
    /// their ranges; its length is the keys'.
    pub fn validate(&self) -> Result<(), InvalidParameter> {
        let kind = self.kind;
        let shape = format!("particles.shape = \"{}\"", kind.as_str());
        let not_for = |key: &str, value: String, takes: &str| {
            InvalidParameter::new(
                format!("particles.{key}"),
                value,
                "",
                format!("absent for {shape} (it applies to {takes})"),
            )
        };
        let needs = |key: &str, what: &str| {
            InvalidParameter::new(
                format!("particles.{key}"),
                "(missing)",
                "",
                format!("given for {shape}: {what}"),
            )
        };
        let spheroid = matches!(kind, ShapeKind::Prolate | ShapeKind::Oblate);
        match (self.aspect_ratio, spheroid) {
            (Some(a), false) => {
                return Err(not_for("aspect_ratio", a.to_string(), "prolate and oblate"));
            }
            (None, true) => return Err(needs("aspect_ratio", "a/b of the spheroid")),
            (Some(a), true) => {
                let (lo, hi) = if kind == ShapeKind::Prolate {
                    (Bound::Open(1.0), Bound::Closed(PROLATE_MAX))
                } else {
                    (Bound::Closed(OBLATE_MIN), Bound::Open(1.0))
                };
                in_range("particles.aspect_ratio", a, "", lo, hi)?;
            }
            (None, false) => {}
        }
        match (self.hole_ratio, kind == ShapeKind::Toroid) {
            (Some(h), false) => return Err(not_for("hole_ratio", h.to_string(), "toroid")),
            (None, true) => return Err(needs("hole_ratio", "(a - b)/(a + b) of the torus")),
            (Some(h), true) => {
                in_range(
                    "particles.hole_ratio",
                    h,
                    "",
                    Bound::Open(0.0),
                    Bound::Closed(HOLE_MAX),
                )?;
            }
            (None, false) => {}
        }
        match (self.clump_file, kind == ShapeKind::Clump) {
            (Some(f), false) => {
                return Err(not_for(
                    "clump_file",
                    format!("\"{}\"", f.display()),
                    "clump",
                ));
            }
            (None, true) => return Err(needs("clump_file", "a file of x_m,y_m,z_m,radius_m rows")),
            _ => {}
        }
        if let Some(n) = self.sub_spheres {
            if matches!(kind, ShapeKind::Sphere | ShapeKind::Clump) {
                return Err(not_for(
                    "sub_spheres",
                    n.to_string(),
                    "prolate, oblate and toroid",
                ));
            }
            let lo = if kind == ShapeKind::Prolate { 3 } else { 1 };
            count_in("particles.sub_spheres", n, "", lo, Some(MAX_SUB_SPHERES))?;
            if kind == ShapeKind::Prolate && n % 2 == 0 {
                return Err(InvalidParameter::new(
                    "particles.sub_spheres",
                    n,
                    "",
                    "odd for a prolate (2 n + 1 spheres on its axis, Section 4.4.1)",
                ));
            }
        }
        Ok(())
    }

    /// The number of sub-spheres a generated body gets.
    fn sub_sphere_count(&self) -> Option<usize> {
        self.sub_spheres.or(self.kind.default_sub_spheres())
    }

    /// The sub-spheres of one particle of volume-equivalent radius `r_eq_m`
    /// in its generator's frame, and the exact shape's volume and surface
    /// (none for a clump file); `None` for spheres.
    pub fn sub_spheres_of(&self, r_eq_m: f64) -> Result<Option<Generated>, SceneError> {
        let n = self.sub_sphere_count().unwrap_or(0);
        let generated = match self.kind {
            ShapeKind::Sphere => return Ok(None),
            ShapeKind::Prolate | ShapeKind::Oblate => {
                let alpha = self.aspect_ratio.unwrap_or(1.0);
                let s = shape::exact::Spheroid::from_aspect_ratio(alpha, r_eq_m)?;
                let body = if self.kind == ShapeKind::Prolate {
                    shape::prolate::markauskas(&s, n)?.body()
                } else {
                    shape::oblate::grid_fill(&s, n, &shape::oblate::GridFillOptions::default())?
                };
                Generated {
                    body,
                    exact: Some((s.volume_m3(), s.surface_m2())),
                }
            }
            ShapeKind::Toroid => {
                let t =
                    shape::exact::Torus::from_hole_ratio(self.hole_ratio.unwrap_or(0.0), r_eq_m)?;
                Generated {
                    body: shape::toroid::ring(&t, n)?,
                    exact: Some((t.volume_m3(), t.surface_m2())),
                }
            }
            ShapeKind::Clump => {
                let path = self.clump_file.cloned().unwrap_or_default();
                Generated {
                    body: shape::clump_file::read_clump_file(&path)?,
                    exact: None,
                }
            }
        };
        Ok(Some(generated))
    }
}

/// The sub-spheres of one generated particle and its exact shape.
#[derive(Debug, Clone)]
pub struct Generated {
    /// Sub-spheres in the generator's frame.
    pub body: MultiSphere,
    /// The exact shape's volume (m³) and surface (m²); none for a clump file.
    pub exact: Option<(f64, f64)>,
}

impl Generated {
    /// Farthest reach of a sub-sphere surface from the union's centre `c`
    /// (m).
    fn reach_m(&self, c: DVec3) -> f64 {
        self.body
            .subs
            .iter()
            .map(|s| (s.centre_m - c).length() + s.radius_m)
            .fold(0.0, f64::max)
    }
}

/// One particle of a scene of bodies, as the DEM takes it and as `vlab
/// scene` reports it.
#[derive(Debug, Clone)]
pub struct ParticleBody {
    /// The body in its principal frame, with its mass and moments.
    pub template: ClumpTemplate,
    /// Volume of the union of its sub-spheres (m³; eq. 4.1's `V_MS`).
    pub union_volume_m3: f64,
    /// Surface of the union (m²).
    pub union_surface_m2: f64,
    /// The exact shape's volume (m³) and surface (m²); none for a clump.
    pub exact: Option<(f64, f64)>,
    /// Smallest sub-sphere radius (m): the time step's (Section 4.2).
    pub min_sub_radius_m: f64,
    /// Distance from the centre of mass to the farthest sub-sphere surface
    /// (m).
    pub bounding_radius_m: f64,
}

impl ParticleBody {
    /// The body of the shape `keys` at volume-equivalent radius `r_eq_m`
    /// and density `density_kgm3` (`None` for spheres). Measuring a union to
    /// 1e-6 takes a noticeable fraction of a second, and a run asks for its
    /// body several times (time step, mass, pour, cache key), so each body
    /// is measured once per process.
    pub fn of(
        keys: &ShapeKeys,
        r_eq_m: f64,
        density_kgm3: f64,
    ) -> Result<Option<ParticleBody>, SceneError> {
        static MEASURED: OnceLock<Mutex<HashMap<String, ParticleBody>>> = OnceLock::new();
        if keys.kind.is_sphere() {
            return Ok(None);
        }
        let key = format!(
            "{:?} {:?} {:?} {:?} {:?} {} {}",
            keys.kind,
            keys.aspect_ratio.map(f64::to_bits),
            keys.hole_ratio.map(f64::to_bits),
            keys.sub_spheres,
            keys.clump_file,
            r_eq_m.to_bits(),
            density_kgm3.to_bits()
        );
        let memo = MEASURED.get_or_init(|| Mutex::new(HashMap::new()));
        if let Some(b) = memo.lock().ok().and_then(|m| m.get(&key).cloned()) {
            return Ok(Some(b));
        }
        let Some(generated) = keys.sub_spheres_of(r_eq_m)? else {
            return Ok(None);
        };
        let body = ParticleBody::new(&generated, density_kgm3)?;
        if let Ok(mut m) = memo.lock() {
            m.insert(key, body.clone());
        }
        Ok(Some(body))
    }

    /// Builds the DEM body of `generated` at density `density_kgm3`: the
    /// union measured, the sub-spheres moved to the principal frame.
    pub fn new(generated: &Generated, density_kgm3: f64) -> Result<ParticleBody, SceneError> {
        let u = shape::union::union_properties(&generated.body, shape::union::DEFAULT_REL_TOL)?;
        let (moments, axes) = u.principal();
        let to_principal = axes.transpose();
        let c = u.centre_of_mass_m;
        let offsets_m = generated
            .body
            .subs
            .iter()
            .map(|s| to_principal * (s.centre_m - c))
            .collect();
        let radii_m: Vec<f64> = generated.body.subs.iter().map(|s| s.radius_m).collect();
        let min_sub_radius_m = radii_m.iter().copied().fold(f64::INFINITY, f64::min);
        Ok(ParticleBody {
            template: ClumpTemplate {
                offsets_m,
                radii_m,
                mass_kg: density_kgm3 * u.volume_m3,
                inertia_kgm2: moments * density_kgm3,
            },
            union_volume_m3: u.volume_m3,
            union_surface_m2: u.surface_m2,
            exact: generated.exact,
            min_sub_radius_m,
            bounding_radius_m: generated.reach_m(c),
        })
    }

    /// The exact shape's true sphericity (eq. 8.3); none for a clump.
    pub fn sphericity(&self) -> Option<f64> {
        self.exact.map(|(v, s)| shape::exact::true_sphericity(v, s))
    }

    /// True sphericity (eq. 8.3) of the union of the sub-spheres itself,
    /// `(36π V²)^(1/3) / S` with the union's volume and surface: the one a
    /// clump file has, which has no exact shape.
    pub fn union_sphericity(&self) -> f64 {
        shape::exact::true_sphericity(self.union_volume_m3, self.union_surface_m2)
    }

    /// The union's volume error against the exact shape (relative).
    pub fn volume_error(&self) -> Option<f64> {
        self.exact.map(|(v, _)| self.union_volume_m3 / v - 1.0)
    }

    /// The union's surface error against the exact shape (relative).
    pub fn surface_error(&self) -> Option<f64> {
        self.exact.map(|(_, s)| self.union_surface_m2 / s - 1.0)
    }

    /// The smallest mass a contact on the body's surface meets (kg): a
    /// push along `n` at the point `r` from the centre of mass moves that
    /// point as a mass `1 / (1/m + (r × n)·I⁻¹(r × n))` would, less than
    /// the body's mass off its centre line (a prolate struck at an end: a
    /// quarter of it). Searched over every sub-sphere's surface in 200
    /// directions; what sets how short a collision can be (eq. 5.10).
    pub fn least_effective_mass_kg(&self) -> f64 {
        let t = &self.template;
        let directions = fibonacci_directions(200);
        let mut worst: f64 = 0.0;
        for (o, r) in t.offsets_m.iter().zip(&t.radii_m) {
            for n in &directions {
                let arm = (*o + *n * *r).cross(*n);
                worst = worst.max((arm * arm / t.inertia_kgm2).element_sum());
            }
        }
        1.0 / (1.0 / t.mass_kg + worst)
    }

    /// How much faster a sub-sphere can meet a wall than the body's centre
    /// moves: `1 + R_bound / k_min`, with `k_min = √(I_min / m)` the
    /// smallest radius of gyration — the speed of the farthest surface
    /// point when the body spins with as much energy as it moves with.
    pub fn impact_speed_factor(&self) -> f64 {
        let t = &self.template;
        let k_min = (t.inertia_kgm2.min_element() / t.mass_kg).sqrt();
        1.0 + self.bounding_radius_m / k_min
    }
}

/// The farthest reach (m) of a generated particle from the volume-weighted
/// mean of its sub-spheres' centres (near its centre of mass, without
/// measuring the union): for the check that a particle fits the enclosure.
pub fn quick_reach_m(generated: &Generated) -> Result<f64, SceneError> {
    let subs = &generated.body.subs;
    let weight: f64 = subs.iter().map(|s| s.radius_m.powi(3)).sum();
    if subs.is_empty() || !weight.is_finite() || weight <= 0.0 {
        return Err(shape::ShapeError::EmptyBody.into());
    }
    let centre = subs
        .iter()
        .fold(DVec3::ZERO, |c, s| c + s.centre_m * s.radius_m.powi(3))
        / weight;
    Ok(generated.reach_m(centre))
}

/// `n` directions spread evenly over the unit sphere (a Fibonacci lattice).
fn fibonacci_directions(n: usize) -> Vec<DVec3> {
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    (0..n)
        .map(|k| {
            let z = 1.0 - (2 * k + 1) as f64 / n as f64;
            let rho = (1.0 - z * z).sqrt();
            let phi = golden * k as f64;
            DVec3::new(rho * phi.cos(), rho * phi.sin(), z)
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dem::clumps::ClumpTemplate;

    fn body(template: ClumpTemplate) -> ParticleBody {
        ParticleBody {
            bounding_radius_m: template.bounding_radius_m(),
            min_sub_radius_m: template
                .radii_m
                .iter()
                .copied()
                .fold(f64::INFINITY, f64::min),
            template,
            union_volume_m3: 1.0,
            union_surface_m2: 1.0,
            exact: None,
        }
    }

    /// A sphere meets every contact with its whole mass (its arms point
    /// along the normals), to rounding. A body of two spheres 4 mm apart
    /// along x (moments 2:5:5 of m R², as given): a contact on a sphere's
    /// surface pushes along its normal `n` at `o + R n`, whose moment arm
    /// is `o × n`, largest (2 mm, the centre's offset) for `n` across the
    /// axis, so the least mass is `1/(1/m + o²/I_zz)`: the search finds it
    /// within 1 %, and not below the bound with the whole reach
    /// `1/(1/m + R_b²/I_min)`. A search that took the lever to the far tip
    /// (3 mm) or read the smallest moment (about the axis, which this push
    /// does not turn) misses it.
    #[test]
    fn the_least_effective_mass_of_a_sphere_and_a_dumbbell() {
        let s = body(ClumpTemplate::sphere(0.002, 1000.0));
        let m = s.template.mass_kg;
        assert!((s.least_effective_mass_kg() - m).abs() < 1e-12 * m);
        let (m, r) = (1e-3, 0.001);
        let d = body(ClumpTemplate {
            offsets_m: vec![DVec3::new(-0.002, 0.0, 0.0), DVec3::new(0.002, 0.0, 0.0)],
            radii_m: vec![r, r],
            mass_kg: m,
            inertia_kgm2: DVec3::new(2.0, 5.0, 5.0) * (m * r * r),
        });
        let least = d.least_effective_mass_kg();
        let lever = 0.002;
        let across = 1.0 / (1.0 / m + lever * lever / (5.0 * m * r * r));
        let reach = d.bounding_radius_m;
        let bound = 1.0 / (1.0 / m + reach * reach / (2.0 * m * r * r));
        assert!(
            (least / across - 1.0).abs() < 0.01,
            "{least} against {across}"
        );
        assert!(least >= bound, "{least} below the bound {bound}");
    }
}
