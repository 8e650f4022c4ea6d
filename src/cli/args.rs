//! Parsers for command-line values that state their unit and valid range when
//! they refuse something.

/// Parses a number and checks it with `valid`, or says what `valid` wants.
fn number(s: &str, valid: impl Fn(f64) -> bool, wants: &str) -> Result<f64, String> {
    let v: f64 = s
        .trim()
        .parse()
        .map_err(|_| format!("'{s}' is not a number"))?;
    if valid(v) {
        Ok(v)
    } else {
        Err(wants.to_string())
    }
}

/// A positive, finite number.
fn positive(s: &str, unit: &str) -> Result<f64, String> {
    number(
        s,
        |v| v > 0.0 && v.is_finite(),
        &format!("must be positive and finite ({unit})"),
    )
    .map_err(|e| {
        if e.ends_with("a number") {
            format!("{e} ({unit})")
        } else {
            e
        }
    })
}

/// Frequency in Hz, positive and finite.
pub fn freq_hz(s: &str) -> Result<f64, String> {
    positive(s, "Hz")
}

/// Dimensionless acceleration amplitude Γ, positive and finite.
pub fn gamma(s: &str) -> Result<f64, String> {
    positive(s, "dimensionless, peak acceleration / g")
}

/// A length in metres, positive and finite.
pub fn metres(s: &str) -> Result<f64, String> {
    positive(s, "m")
}

/// A time in seconds, positive and finite.
pub fn seconds(s: &str) -> Result<f64, String> {
    positive(s, "s")
}

/// A speed in m/s, positive and finite.
pub fn speed_mps(s: &str) -> Result<f64, String> {
    positive(s, "m/s")
}

/// A pressure or modulus in Pa, positive and finite.
pub fn pascals(s: &str) -> Result<f64, String> {
    positive(s, "Pa")
}

/// A mass in kg, positive and finite.
pub fn positive_kg(s: &str) -> Result<f64, String> {
    positive(s, "kg")
}

/// A density in kg/m³, positive and finite.
pub fn density(s: &str) -> Result<f64, String> {
    positive(s, "kg/m^3")
}

/// Coefficient of restitution in (0, 1].
pub fn restitution(s: &str) -> Result<f64, String> {
    number(
        s,
        |v| v > 0.0 && v <= 1.0,
        "the coefficient of restitution must lie in (0, 1] (dimensionless)",
    )
}

/// Coefficient of friction, ≥ 0 and finite.
pub fn friction(s: &str) -> Result<f64, String> {
    number(
        s,
        |v| v >= 0.0 && v.is_finite(),
        "the coefficient of friction must be >= 0 and finite (dimensionless)",
    )
}

/// Poisson's ratio in (-1, 0.5).
pub fn poisson(s: &str) -> Result<f64, String> {
    number(
        s,
        |v| v > -1.0 && v < 0.5,
        "Poisson's ratio must lie in (-1, 0.5) (dimensionless)",
    )
}

/// A finite number (any sign).
pub fn finite(s: &str) -> Result<f64, String> {
    number(s, |v| v.is_finite(), "must be finite")
}

/// At least one thread.
pub fn threads(s: &str) -> Result<usize, String> {
    let v: usize = s
        .trim()
        .parse()
        .map_err(|_| format!("'{s}' is not a whole number of threads"))?;
    if v >= 1 {
        Ok(v)
    } else {
        Err("must be at least 1 thread".into())
    }
}

/// A sample rate in Hz: a positive whole number (WAV headers hold whole
/// hertz), at most 1 MHz (a drop record of 2 s is then 2 M samples).
pub fn sample_rate_hz(s: &str) -> Result<f64, String> {
    let v = positive(s, "Hz")?;
    if v.fract() != 0.0 || v > 1e6 {
        return Err("must be a whole number of hertz, at most 1000000 (Hz)".into());
    }
    Ok(v)
}

/// An acceleration in m/s^2, positive and finite.
pub fn acceleration(s: &str) -> Result<f64, String> {
    positive(s, "m/s^2")
}

/// A force in N, positive and finite.
pub fn newtons(s: &str) -> Result<f64, String> {
    positive(s, "N")
}

/// A duration in seconds, zero or positive and finite.
pub fn non_negative_seconds(s: &str) -> Result<f64, String> {
    let v: f64 = s
        .trim()
        .parse()
        .map_err(|_| format!("'{s}' is not a number (s)"))?;
    if v >= 0.0 && v.is_finite() {
        Ok(v)
    } else {
        Err("must be zero or positive, and finite (s)".into())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn messages_state_unit_and_range() {
        assert!(freq_hz("-3").unwrap_err().contains("Hz"));
        assert!(freq_hz("nan").unwrap_err().contains("positive and finite"));
        assert!(freq_hz("abc").unwrap_err().contains("not a number"));
        assert!(restitution("1.2").unwrap_err().contains("(0, 1]"));
        assert!(friction("-0.1").unwrap_err().contains(">= 0"));
        assert!(sample_rate_hz("2e5").is_ok());
        assert!(sample_rate_hz("200000.5").unwrap_err().contains("whole"));
        assert!(sample_rate_hz("2e7").unwrap_err().contains("1000000 (Hz)"));
        assert!(non_negative_seconds("-1").unwrap_err().contains("(s)"));
    }
}
