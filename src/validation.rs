//! One vocabulary for refusing a value, used by every layer.
//!
//! A value that is out of its valid range is an [`InvalidParameter`]: the key
//! that names it (a scene-file key such as `particles.diameter_m`, a rig-file key
//! such as `daq.bits`, or a function parameter such as `freq_hz`), the value as
//! given, its unit and what would have been valid. Every refusal renders the same
//! way:
//!
//! ```text
//! particles.diameter_m = -0.005 m: must be positive and finite
//! contact.particle_particle.restitution = 1.2: must be in (0, 1]
//! ```
//!
//! Library code names keys and parameters, never command-line flags; the `vlab`
//! binary renames a key to the flag that set it ([`InvalidParameter::renamed`]).
//! The checks below are the only copies of "positive", "non-negative", "finite"
//! and "in a range" in the crate.

use std::fmt;

/// A value outside its valid range.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub struct InvalidParameter {
    /// Scene or rig key (`particles.diameter_m`), or a parameter name (`freq_hz`).
    pub key: String,
    /// The offending value, as written.
    pub value: String,
    /// Its unit (`m`, `Hz`, `V/N`); empty when dimensionless.
    pub unit: String,
    /// What would have been valid, in words (`positive and finite`, `in (0, 1]`).
    pub valid: String,
}

impl fmt::Display for InvalidParameter {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} = {}", self.key, self.value)?;
        if !self.unit.is_empty() {
            write!(f, " {}", self.unit)?;
        }
        write!(f, ": must be {}", self.valid)
    }
}

impl InvalidParameter {
    /// A refusal of `value` for `key`.
    pub fn new(
        key: impl Into<String>,
        value: impl fmt::Display,
        unit: &str,
        valid: impl Into<String>,
    ) -> Self {
        InvalidParameter {
            key: key.into(),
            value: value.to_string(),
            unit: unit.to_string(),
            valid: valid.into(),
        }
    }

    /// The same refusal under another name (the flag that set the value).
    pub fn renamed(&self, key: &str) -> Self {
        InvalidParameter {
            key: key.to_string(),
            ..self.clone()
        }
    }

    /// The same refusal with `reason` after what is valid, in parentheses:
    /// `in [0, 1)` becomes `in [0, 1) (an underdamped plate)`.
    pub fn because(mut self, reason: &str) -> Self {
        self.valid = format!("{} ({reason})", self.valid);
        self
    }

    /// The same refusal with `prefix.` in front of the key (`particles.` +
    /// `material.poisson`).
    pub fn within(mut self, prefix: &str) -> Self {
        if !prefix.is_empty() {
            self.key = format!("{prefix}.{}", self.key);
        }
        self
    }
}

/// Result of a check.
pub type Checked<T> = Result<T, InvalidParameter>;

/// One end of a range.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Bound {
    /// The end value itself is allowed.
    Closed(f64),
    /// The end value itself is not allowed.
    Open(f64),
    /// No limit on this side (the value must still be finite).
    Unbounded,
}

impl Bound {
    fn admits_above(self, x: f64) -> bool {
        match self {
            Bound::Closed(lo) => x >= lo,
            Bound::Open(lo) => x > lo,
            Bound::Unbounded => true,
        }
    }

    fn admits_below(self, x: f64) -> bool {
        match self {
            Bound::Closed(hi) => x <= hi,
            Bound::Open(hi) => x < hi,
            Bound::Unbounded => true,
        }
    }
}

/// The words for a range: `positive and finite`, `>= 0 and finite`,
/// `in (0, 1]`, `<= 4 and finite`.
pub fn describe_range(lo: Bound, hi: Bound) -> String {
    match (lo, hi) {
        (Bound::Open(0.0), Bound::Unbounded) => "positive and finite".into(),
        (Bound::Open(a), Bound::Unbounded) => format!("> {a} and finite"),
        (Bound::Closed(a), Bound::Unbounded) => format!(">= {a} and finite"),
        (Bound::Unbounded, Bound::Open(b)) => format!("< {b}"),
        (Bound::Unbounded, Bound::Closed(b)) => format!("<= {b}"),
        (Bound::Unbounded, Bound::Unbounded) => "finite".into(),
        (lo, hi) => {
            let (l, a) = match lo {
                Bound::Closed(a) => ('[', a),
                Bound::Open(a) => ('(', a),
                Bound::Unbounded => ('(', f64::NEG_INFINITY),
            };
            let (b, r) = match hi {
                Bound::Closed(b) => (b, ']'),
                Bound::Open(b) => (b, ')'),
                Bound::Unbounded => (f64::INFINITY, ')'),
            };
            format!("in {l}{a}, {b}{r}")
        }
    }
}

/// Checks that `value` is finite and lies between `lo` and `hi`.
pub fn in_range(key: &str, value: f64, unit: &str, lo: Bound, hi: Bound) -> Checked<f64> {
    if value.is_finite() && lo.admits_above(value) && hi.admits_below(value) {
        Ok(value)
    } else {
        Err(InvalidParameter::new(
            key,
            value,
            unit,
            describe_range(lo, hi),
        ))
    }
}

/// Checks that `value` is positive and finite.
pub fn positive(key: &str, value: f64, unit: &str) -> Checked<f64> {
    in_range(key, value, unit, Bound::Open(0.0), Bound::Unbounded)
}

/// Checks that `value` is zero or positive, and finite.
pub fn non_negative(key: &str, value: f64, unit: &str) -> Checked<f64> {
    in_range(key, value, unit, Bound::Closed(0.0), Bound::Unbounded)
}

/// Checks that `value` is finite (any sign).
pub fn finite(key: &str, value: f64, unit: &str) -> Checked<f64> {
    in_range(key, value, unit, Bound::Unbounded, Bound::Unbounded)
}

/// Checks a whole number against an inclusive range `lo..=hi`.
pub fn count_in<T>(key: &str, value: T, unit: &str, lo: T, hi: Option<T>) -> Checked<T>
where
    T: PartialOrd + fmt::Display + Copy,
{
    let ok = value >= lo && hi.is_none_or(|h| value <= h);
    if ok {
        Ok(value)
    } else {
        let valid = match hi {
            Some(h) => format!("an integer in {lo}..={h}"),
            None => format!("at least {lo}"),
        };
        Err(InvalidParameter::new(key, value, unit, valid))
    }
}

/// A refusal with free words for what is valid, when `ok` is false.
pub fn require<T: fmt::Display>(
    ok: bool,
    key: &str,
    value: T,
    unit: &str,
    valid: impl Into<String>,
) -> Checked<()> {
    if ok {
        Ok(())
    } else {
        Err(InvalidParameter::new(key, value, unit, valid))
    }
}

/// The coefficient of restitution, in (0, 1] (thesis Section 5.5.3).
pub fn restitution(key: &str, e: f64) -> Checked<f64> {
    in_range(key, e, "", Bound::Open(0.0), Bound::Closed(1.0))
}

/// The coefficient of friction, >= 0 and finite (thesis eq. 5.16).
pub fn friction(key: &str, mu: f64) -> Checked<f64> {
    non_negative(key, mu, "")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_shape_for_every_refusal() {
        let e = positive("particles.diameter_m", -0.005, "m").unwrap_err();
        assert_eq!(
            e.to_string(),
            "particles.diameter_m = -0.005 m: must be positive and finite"
        );
        let e = restitution("contact.particle_wall.restitution", 1.2).unwrap_err();
        assert_eq!(
            e.to_string(),
            "contact.particle_wall.restitution = 1.2: must be in (0, 1]"
        );
        let e = friction("mu", -0.1).unwrap_err();
        assert_eq!(e.to_string(), "mu = -0.1: must be >= 0 and finite");
        let e = count_in("daq.bits", 0u32, "bits", 1, Some(32)).unwrap_err();
        assert_eq!(
            e.to_string(),
            "daq.bits = 0 bits: must be an integer in 1..=32"
        );
        assert_eq!(
            e.renamed("--bits").to_string(),
            "--bits = 0 bits: must be an integer in 1..=32"
        );
        let e = positive("youngs_pa", 0.0, "Pa")
            .unwrap_err()
            .within("particles.material");
        assert_eq!(e.key, "particles.material.youngs_pa");
    }

    #[test]
    fn ranges_refuse_nan_and_infinities() {
        assert!(positive("x", f64::NAN, "m").is_err());
        assert!(positive("x", f64::INFINITY, "m").is_err());
        assert!(finite("x", f64::NEG_INFINITY, "m").is_err());
        assert!(non_negative("x", 0.0, "m").is_ok());
        assert!(non_negative("x", -1e-300, "m").is_err());
        assert!(restitution("e", 1.0).is_ok());
        assert!(restitution("e", 0.0).is_err());
        let poisson = in_range("nu", 0.5, "", Bound::Open(-1.0), Bound::Open(0.5));
        assert_eq!(poisson.unwrap_err().valid, "in (-1, 0.5)");
        assert_eq!(
            describe_range(Bound::Closed(0.0), Bound::Open(1.0)),
            "in [0, 1)"
        );
    }
}
