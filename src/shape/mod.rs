//! Multi-sphere particle shapes: the geometry of non-spherical grains built
//! from overlapping spheres, before any of it reaches the DEM.
//!
//! The thesis models prolate and oblate spheroids and circular toroids by the
//! multi-sphere approach (Chapter 4; the particles of Chapter 8.2): a rigid
//! clump of overlapping sub-spheres whose contacts are ordinary sphere
//! contacts. This module builds such clumps in a body frame and measures how
//! well they stand for the smooth shape they replace:
//!
//! - [`exact`]: the smooth shapes themselves: spheroid (aspect ratio
//!   α = a/b, eq. 8.1–8.2) and circular torus (hole ratio
//!   h = (a − b)/(a + b), eq. 8.4), their volume, surface and true
//!   sphericity (eq. 8.3; Tables 8.1 and 8.2);
//! - [`prolate`]: Markauskas' analytical placement of 2n + 1 sub-spheres on
//!   the axis of a prolate spheroid (Section 4.4.1, eq. 4.8–4.15);
//! - [`toroid`]: n identical sub-spheres on the centre circle of a torus'
//!   tube (Section 4.4.2, eq. 4.26–4.29);
//! - [`oblate`]: the grid fill of Section 4.3 for oblate spheroids, reduced to
//!   a requested count;
//! - [`section`]: the exact area and perimeter of a union of discs, for the
//!   two-dimensional accuracy checks of eq. 4.16–4.25 and 4.30–4.34;
//! - [`union`]: the volume, centre of mass, inertia tensor, principal axes
//!   and surface area of the union of the sub-spheres (eq. 4.1, 4.2, 4.5 use
//!   the union, not a sum over overlapping spheres);
//! - [`clump_file`]: a body read from a `x_m,y_m,z_m,radius_m` text file;
//! - [`report`]: a generated body against its exact shape, and volume error
//!   against sub-sphere count (the data of Fig. 4.7 and Fig. 4.11).
//!
//! Units are SI (m, m², m³); a body's density is uniform, so its inertia is
//! given per unit density (m⁵) and scales with the material's.

pub mod clump_file;
pub mod exact;
pub mod oblate;
pub mod prolate;
pub mod report;
pub mod section;
pub mod toroid;
pub mod union;

use glam::DVec3;
use thiserror::Error;

/// One sphere of a clump, in the clump's body frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SubSphere {
    /// Centre in the body frame (m).
    pub centre_m: DVec3,
    /// Radius (m).
    pub radius_m: f64,
}

impl SubSphere {
    /// A sub-sphere at `centre_m` of radius `radius_m`.
    pub fn new(centre_m: DVec3, radius_m: f64) -> Self {
        Self { centre_m, radius_m }
    }
}

/// A rigid clump of overlapping sub-spheres in its body frame.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct MultiSphere {
    /// The sub-spheres.
    pub subs: Vec<SubSphere>,
}

impl MultiSphere {
    /// The clump of `subs`.
    pub fn new(subs: Vec<SubSphere>) -> Self {
        Self { subs }
    }

    /// The smallest sub-sphere radius (m): it sets the DEM time step of a
    /// multi-sphere grain (Section 4.2, with eq. 3.31). `None` for an empty
    /// clump.
    pub fn min_radius_m(&self) -> Option<f64> {
        self.subs.iter().map(|s| s.radius_m).reduce(f64::min)
    }

    /// Number of sub-spheres.
    pub fn len(&self) -> usize {
        self.subs.len()
    }

    /// Whether the clump has no sub-sphere.
    pub fn is_empty(&self) -> bool {
        self.subs.is_empty()
    }
}

/// Why a shape could not be built, read or measured.
#[derive(Debug, Error)]
pub enum ShapeError {
    /// A parameter outside its valid range; `unit` is "dimensionless" for
    /// ratios.
    #[error("{name} {value} ({unit}) is out of range: {valid}")]
    OutOfRange {
        /// Parameter name as the caller spells it.
        name: &'static str,
        /// The value given.
        value: f64,
        /// Its unit.
        unit: &'static str,
        /// The valid range, in words.
        valid: String,
    },
    /// A sub-sphere count the generator cannot honour.
    #[error("n_subs {n_subs} (count) is out of range: {valid}")]
    SubCount {
        /// The count asked for.
        n_subs: usize,
        /// The valid counts, in words.
        valid: String,
    },
    /// Too few toroid sub-spheres for neighbours to overlap (eq. 4.27).
    #[error(
        "n_subs {n_subs} (count) is too few for a toroid with a = {a_m} m, b = {b_m} m: \
         neighbouring sub-spheres overlap only when 2 a sin(pi / n_subs) < 2 b, i.e. \
         n_subs >= {n_min} (the exact form of eq. 4.27)"
    )]
    TooFewToroidSubs {
        /// The count asked for.
        n_subs: usize,
        /// The smallest count whose neighbours overlap.
        n_min: usize,
        /// Centre-circle radius (m).
        a_m: f64,
        /// Tube radius (m).
        b_m: f64,
    },
    /// Too few prolate sub-spheres for the placement to hold together.
    #[error(
        "n_subs {n_subs} (count) is too few for a prolate of aspect_ratio {aspect_ratio}: \
         the spacing of eq. 4.15 leaves neighbouring sub-spheres {gap_m} m apart; the least \
         odd count whose neighbours all overlap is {n_min}"
    )]
    DetachedProlate {
        /// The count asked for.
        n_subs: usize,
        /// The spheroid's a/b.
        aspect_ratio: f64,
        /// The widest gap between neighbours (m).
        gap_m: f64,
        /// The least count that connects.
        n_min: usize,
    },
    /// A clump with no sub-sphere where one is needed.
    #[error("the body has no sub-sphere")]
    EmptyBody,
    /// The union integration did not reach its tolerance.
    #[error(
        "the union integration stopped at an estimated relative error {achieved:e}, \
         above the requested rel_tol {requested:e} (dimensionless): ask a looser rel_tol \
         (the default is 1e-6)"
    )]
    ToleranceNotReached {
        /// Requested relative tolerance.
        requested: f64,
        /// Estimated relative error when it stopped.
        achieved: f64,
    },
    /// A clump file could not be read.
    #[error("cannot read clump file {path}: {source}")]
    Io {
        /// The file.
        path: String,
        /// The cause.
        #[source]
        source: std::io::Error,
    },
    /// A clump file line that is not `x_m,y_m,z_m,radius_m`.
    #[error("clump file {path}, line {line}: {message}")]
    Parse {
        /// The file (or `<text>` for a string).
        path: String,
        /// 1-based line number.
        line: usize,
        /// What is wrong.
        message: String,
    },
    /// A clump file with no sub-sphere row.
    #[error("clump file {path} has no sub-sphere row (expected x_m,y_m,z_m,radius_m lines)")]
    EmptyFile {
        /// The file (or `<text>` for a string).
        path: String,
    },
}

/// An error for `value` of `name` outside its valid range.
pub(crate) fn out_of_range(
    name: &'static str,
    value: f64,
    unit: &'static str,
    valid: impl Into<String>,
) -> ShapeError {
    ShapeError::OutOfRange {
        name,
        value,
        unit,
        valid: valid.into(),
    }
}

/// `Ok(value)` when it is finite and strictly positive, else the range error.
pub(crate) fn positive(
    name: &'static str,
    value: f64,
    unit: &'static str,
) -> Result<f64, ShapeError> {
    if value.is_finite() && value > 0.0 {
        Ok(value)
    } else {
        Err(out_of_range(name, value, unit, "it must be finite and > 0"))
    }
}

/// `n` nearly uniform unit directions (the Fibonacci lattice on the
/// sphere), for the tests' surface sampling.
#[cfg(test)]
pub(crate) fn fibonacci_directions(n: usize) -> Vec<DVec3> {
    let golden = std::f64::consts::PI * (3.0 - 5f64.sqrt());
    (0..n)
        .map(|i| {
            let z = 1.0 - (2.0 * i as f64 + 1.0) / n as f64;
            let rho = (1.0 - z * z).sqrt();
            let phi = golden * i as f64;
            DVec3::new(rho * phi.cos(), rho * phi.sin(), z)
        })
        .collect()
}
