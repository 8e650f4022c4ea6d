//! A multi-sphere body read from a text file of sub-spheres, one per line:
//! `x_m,y_m,z_m,radius_m` in the body frame (m), separated by commas or
//! white space. Blank lines and `#` comments (whole-line or trailing) are
//! skipped; the first remaining line may be a header (any line whose first
//! field is not a number). Radii must be finite and > 0, coordinates
//! finite; a file with no sub-sphere is refused. Errors name the 1-based
//! line.

use super::{MultiSphere, ShapeError, SubSphere};
use glam::DVec3;
use std::path::Path;

/// Read the body in `path`.
pub fn read_clump_file(path: &Path) -> Result<MultiSphere, ShapeError> {
    let name = path.display().to_string();
    let text = std::fs::read_to_string(path).map_err(|source| ShapeError::Io {
        path: name.clone(),
        source,
    })?;
    parse_clump(&text, &name)
}

/// Parse clump text; `name` labels errors (a path, or `<text>`).
pub fn parse_clump(text: &str, name: &str) -> Result<MultiSphere, ShapeError> {
    let mut subs = Vec::new();
    let mut seen_data_or_header = false;
    for (idx, raw) in text.lines().enumerate() {
        let line = idx + 1;
        let content = raw.split('#').next().unwrap_or("").trim();
        if content.is_empty() {
            continue;
        }
        let fields: Vec<&str> = content
            .split(|c: char| c == ',' || c.is_whitespace())
            .filter(|f| !f.is_empty())
            .collect();
        let is_header = fields.first().is_some_and(|f| f.parse::<f64>().is_err());
        if is_header && !seen_data_or_header {
            seen_data_or_header = true;
            continue;
        }
        seen_data_or_header = true;
        subs.push(parse_row(&fields, name, line)?);
    }
    if subs.is_empty() {
        return Err(ShapeError::EmptyFile { path: name.into() });
    }
    Ok(MultiSphere::new(subs))
}

/// One `x_m,y_m,z_m,radius_m` row.
fn parse_row(fields: &[&str], name: &str, line: usize) -> Result<SubSphere, ShapeError> {
    let err = |message: String| ShapeError::Parse {
        path: name.into(),
        line,
        message,
    };
    if fields.len() != 4 {
        return Err(err(format!(
            "expected 4 fields x_m,y_m,z_m,radius_m, found {}",
            fields.len()
        )));
    }
    let labels = ["x_m", "y_m", "z_m", "radius_m"];
    let mut v = [0.0; 4];
    for (k, (field, label)) in fields.iter().zip(labels).enumerate() {
        let x: f64 = field
            .parse()
            .map_err(|_| err(format!("{label} '{field}' is not a number")))?;
        if !x.is_finite() {
            return Err(err(format!("{label} {field} is not finite")));
        }
        v[k] = x;
    }
    if v[3] <= 0.0 {
        return Err(err(format!(
            "radius_m {} (m) is out of range: it must be > 0",
            v[3]
        )));
    }
    Ok(SubSphere::new(DVec3::new(v[0], v[1], v[2]), v[3]))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Header, comments, blank lines, comma and space separators all read;
    /// values exact. Catches a header taken as data or a dropped row.
    #[test]
    fn reads_rows_with_header_and_comments() {
        let text = "# a clump\nx_m,y_m,z_m,radius_m\n\n0,0,0,1e-3 # centre\n1.5e-3 0 -2e-4 5e-4\n";
        let body = parse_clump(text, "<text>").unwrap();
        assert_eq!(body.len(), 2);
        assert_eq!(body.subs[1].centre_m, DVec3::new(1.5e-3, 0.0, -2e-4));
        assert_eq!(body.subs[1].radius_m, 5e-4);
    }

    /// Bad rows are refused with their line number: non-positive or
    /// non-finite radius, NaN coordinate, wrong field count, a second
    /// header; an empty file is refused. Catches silent acceptance.
    #[test]
    fn refuses_bad_rows_with_line_numbers() {
        let cases = [
            ("0,0,0,0\n", "line 1", "radius_m 0"),
            ("x,y,z,r\n0,0,0,1\n0,0,0,-1\n", "line 3", "radius_m -1"),
            ("0,0,0,inf\n", "line 1", "not finite"),
            ("# c\nNaN,0,0,1\n", "line 2", "x_m NaN is not finite"),
            ("0,0,1\n", "line 1", "found 3"),
            ("0,0,0,1\nx,y,z,r\n", "line 2", "is not a number"),
        ];
        for (text, line, what) in cases {
            let e = parse_clump(text, "<text>").unwrap_err().to_string();
            assert!(e.contains(line) && e.contains(what), "{text:?}: {e}");
        }
        assert!(matches!(
            parse_clump("# only\nx,y,z,r\n", "<text>"),
            Err(ShapeError::EmptyFile { .. })
        ));
        let missing = read_clump_file(Path::new("/nonexistent/clump.csv"))
            .unwrap_err()
            .to_string();
        assert!(missing.contains("/nonexistent/clump.csv"));
    }
}
