//! Traces as CSV text: what a lab exports and what a spreadsheet reads. No
//! thesis equation lives here.
//!
//! # Format written by vlab
//!
//! ```text
//! # vlab trace
//! # sample_rate_hz: 40000
//! # start_time_s: 0
//! # metadata: {"source":"vlab shake","rig":"thesis-shaker",...}
//! time [s],force [N],acceleration [m/s^2]
//! 0,0.25,-3.5
//! 0.000025,0.2501,-3.49
//! ```
//!
//! - Optional leading comment lines `# key: value`. The keys read are
//!   `sample_rate_hz`, `start_time_s` and `metadata` (one line of JSON, a
//!   [`TraceMetadata`]); other comment lines are ignored.
//! - A header whose cells are `name [unit]`: the unit in square brackets after
//!   the name (`force [N]`, `acceleration [m/s^2]`; `gain []` for an empty
//!   unit). The first column is time in seconds: `time [s]` (also read:
//!   `t [s]`, `time_s`, `t_s`). A header cell without brackets is read as a
//!   name with an empty unit, so plain lab headers such as `force_n` load.
//! - One row per sample, comma-separated, no quoting. Numbers are written with
//!   Rust's shortest round-trip formatting (`{}`), so reading back gives
//!   bit-identical `f64` samples. Time is written as `start_time_s + i / fs`.
//!
//! # Reading
//!
//! [`read_csv`] reads vlab files and plain lab CSVs (header, no comments).
//! With a `sample_rate_hz` comment the time column is checked against it;
//! without one the rate is inferred from the time column, `(n-1) / (t_last -
//! t_0)`, taken as the nearest whole number of hertz when that is within 1 ppm.
//! Either way every time value must lie on the uniform grid within
//! [`TIME_GRID_REL_TOL`] of a sample period. Blank lines are skipped; a UTF-8
//! byte-order mark is tolerated; CRLF line ends are fine.

use std::collections::BTreeSet;
use std::fmt::Write as _;
use std::io::Write as _;
use std::path::Path;

use super::error::{CsvErrorKind, Result, SignalsError};
use super::trace::{Trace, TraceMetadata};
use crate::atomic_write::write_atomic;

/// How far a time value may be from the uniform grid, as a fraction of the
/// sample period.
pub const TIME_GRID_REL_TOL: f64 = 1e-6;

/// Writes `trace` to `path` as CSV (atomically; see the module docs).
pub fn write_csv(path: &Path, trace: &Trace) -> Result<()> {
    trace.validate()?;
    let csv_err = |line, kind| SignalsError::Csv {
        path: path.to_path_buf(),
        line,
        kind,
    };
    for c in &trace.channels {
        if !writable(&c.name) || !writable(&c.unit) || c.name.is_empty() {
            return Err(csv_err(
                0,
                CsvErrorKind::Unwritable {
                    name: c.name.clone(),
                    unit: c.unit.clone(),
                },
            ));
        }
    }
    let metadata = serde_json::to_string(&trace.metadata).map_err(|source| SignalsError::Json {
        path: path.to_path_buf(),
        source,
    })?;
    let mut head = String::new();
    // Writing to a String cannot fail.
    let _ = writeln!(head, "# vlab trace");
    let _ = writeln!(head, "# sample_rate_hz: {}", trace.sample_rate_hz);
    let _ = writeln!(head, "# start_time_s: {}", trace.start_time_s);
    let _ = writeln!(head, "# metadata: {metadata}");
    head.push_str("time [s]");
    for c in &trace.channels {
        let _ = write!(head, ",{} [{}]", c.name, c.unit);
    }
    head.push('\n');
    write_atomic(path, |out| {
        out.write_all(head.as_bytes())?;
        let mut row = String::new();
        for i in 0..trace.len() {
            row.clear();
            let _ = write!(row, "{}", trace.time_s(i));
            for c in &trace.channels {
                let _ = write!(row, ",{}", c.samples[i]);
            }
            row.push('\n');
            out.write_all(row.as_bytes())?;
        }
        Ok(())
    })
    .map_err(|source| SignalsError::Io {
        path: path.to_path_buf(),
        source,
    })
}

/// True when `s` can sit in a header cell and be parsed back unchanged.
fn writable(s: &str) -> bool {
    s == s.trim() && !s.contains([',', '[', ']', '"', '\n', '\r'])
}

/// Reads a CSV trace (see the module docs for what is accepted).
pub fn read_csv(path: &Path) -> Result<Trace> {
    let text = std::fs::read_to_string(path).map_err(|source| SignalsError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    parse_csv(&text).map_err(|(line, kind)| SignalsError::Csv {
        path: path.to_path_buf(),
        line,
        kind,
    })
}

/// A parse failure: one-based line number and what is wrong.
type ParseError = (usize, CsvErrorKind);

/// What the leading comments declared.
#[derive(Default)]
struct Declared {
    sample_rate_hz: Option<f64>,
    start_time_s: Option<f64>,
    metadata: TraceMetadata,
}

/// Parses CSV text into a trace; errors carry one-based line numbers.
fn parse_csv(text: &str) -> Result<Trace, ParseError> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut lines = text
        .lines()
        .enumerate()
        .map(|(i, l)| (i + 1, l.trim()))
        .filter(|(_, l)| !l.is_empty());

    let mut declared = Declared::default();
    let (header_line, header) = loop {
        match lines.next() {
            None => return Err((1, CsvErrorKind::Empty)),
            Some((n, l)) if l.starts_with('#') => parse_comment(n, l, &mut declared)?,
            Some(found) => break found,
        }
    };
    let columns = parse_header(header_line, header)?;

    let n_cols = columns.len() + 1;
    let mut time = Vec::new();
    let mut row_lines = Vec::new();
    let mut data: Vec<Vec<f64>> = vec![Vec::new(); columns.len()];
    for (n, l) in lines {
        let cells: Vec<&str> = l.split(',').collect();
        if cells.len() != n_cols {
            return Err((
                n,
                CsvErrorKind::Ragged {
                    expected: n_cols,
                    got: cells.len(),
                },
            ));
        }
        row_lines.push(n);
        for (j, cell) in cells.iter().enumerate() {
            let header = if j == 0 {
                "time"
            } else {
                columns[j - 1].0.as_str()
            };
            let value = parse_number(n, header, cell)?;
            if j == 0 {
                time.push(value);
            } else {
                data[j - 1].push(value);
            }
        }
    }
    if time.len() < 2 {
        return Err((header_line, CsvErrorKind::TooFewRows { got: time.len() }));
    }
    let (sample_rate_hz, start_time_s) = sample_grid(&time, &declared, &row_lines)?;
    let mut trace = Trace::new(sample_rate_hz, start_time_s).map_err(|e| {
        (
            header_line,
            CsvErrorKind::BadComment {
                key: "sample_rate_hz".into(),
                problem: e.to_string(),
            },
        )
    })?;
    trace.metadata = declared.metadata;
    for ((name, unit), samples) in columns.into_iter().zip(data) {
        // Names were checked unique and samples finite above; this cannot fail,
        // but report it as a header problem rather than panic if it ever does.
        trace
            .add_channel(name.clone(), unit, samples)
            .map_err(|e| {
                (
                    header_line,
                    CsvErrorKind::BadHeader {
                        column: 0,
                        header: name,
                        problem: e.to_string(),
                    },
                )
            })?;
    }
    Ok(trace)
}

/// Reads one `# key: value` comment into `declared`.
fn parse_comment(line: usize, text: &str, declared: &mut Declared) -> Result<(), ParseError> {
    let body = text.trim_start_matches('#').trim();
    let Some((key, value)) = body.split_once(':') else {
        return Ok(());
    };
    let (key, value) = (key.trim(), value.trim());
    let bad = |problem: String| {
        (
            line,
            CsvErrorKind::BadComment {
                key: key.to_string(),
                problem,
            },
        )
    };
    let number = |value: &str| {
        value
            .parse::<f64>()
            .ok()
            .filter(|x| x.is_finite())
            .ok_or_else(|| bad(format!("'{value}' is not a finite number")))
    };
    match key {
        "sample_rate_hz" => {
            let fs = number(value)?;
            if fs <= 0.0 {
                return Err(bad(format!("{fs} Hz: must be positive and finite")));
            }
            declared.sample_rate_hz = Some(fs);
        }
        "start_time_s" => declared.start_time_s = Some(number(value)?),
        "metadata" => {
            declared.metadata = serde_json::from_str(value)
                .map_err(|e| bad(format!("invalid metadata JSON: {e}")))?;
        }
        _ => {}
    }
    Ok(())
}

/// Splits the header into (name, unit) per data column, checking the time column.
fn parse_header(line: usize, header: &str) -> Result<Vec<(String, String)>, ParseError> {
    let mut cells = header.split(',').map(str::trim);
    let first = cells.next().unwrap_or_default();
    let (time_name, time_unit) = split_name_unit(first);
    let is_time = matches!(
        (time_name.to_ascii_lowercase().as_str(), time_unit),
        ("time" | "t", Some("s")) | ("time_s" | "t_s", None)
    );
    if !is_time {
        return Err((
            line,
            CsvErrorKind::MissingTimeColumn {
                found: first.to_string(),
            },
        ));
    }
    let mut seen = BTreeSet::new();
    let mut columns = Vec::new();
    for (j, cell) in cells.enumerate() {
        let column = j + 2;
        let bad = |problem: &str| {
            (
                line,
                CsvErrorKind::BadHeader {
                    column,
                    header: cell.to_string(),
                    problem: problem.to_string(),
                },
            )
        };
        let (name, unit) = split_name_unit(cell);
        if name.is_empty() {
            return Err(bad("empty channel name"));
        }
        if !seen.insert(name.to_string()) {
            return Err(bad("channel name used twice"));
        }
        columns.push((name.to_string(), unit.unwrap_or_default().to_string()));
    }
    if columns.is_empty() {
        return Err((line, CsvErrorKind::NoDataColumns));
    }
    Ok(columns)
}

/// `"force [N]"` -> `("force", Some("N"))`; `"force_n"` -> `("force_n", None)`.
fn split_name_unit(cell: &str) -> (&str, Option<&str>) {
    if let Some(inner) = cell.strip_suffix(']')
        && let Some((name, unit)) = inner.rsplit_once('[')
    {
        return (name.trim(), Some(unit.trim()));
    }
    (cell, None)
}

fn parse_number(line: usize, column: &str, cell: &str) -> Result<f64, ParseError> {
    let text = cell.trim();
    let value = text.parse::<f64>().map_err(|_| {
        (
            line,
            CsvErrorKind::NotANumber {
                column: column.to_string(),
                text: text.to_string(),
            },
        )
    })?;
    if !value.is_finite() {
        return Err((
            line,
            CsvErrorKind::NonFinite {
                column: column.to_string(),
                value,
            },
        ));
    }
    Ok(value)
}

/// Sample rate and start time from the declarations and the time column,
/// checking the time column lies on the uniform grid. `row_lines[i]` is the
/// file line of sample `i`, for error messages.
fn sample_grid(
    time: &[f64],
    declared: &Declared,
    row_lines: &[usize],
) -> Result<(f64, f64), ParseError> {
    let start = declared.start_time_s.unwrap_or(time[0]);
    let rate = match declared.sample_rate_hz {
        Some(fs) => fs,
        None => {
            let span = time[time.len() - 1] - time[0];
            let fs = (time.len() - 1) as f64 / span;
            if !(span > 0.0 && fs.is_finite()) {
                return Err((
                    row_lines[1],
                    CsvErrorKind::NonUniformTime {
                        time_s: time[1],
                        expected_s: time[0],
                        step_s: span / (time.len() - 1) as f64,
                        rel_tol: TIME_GRID_REL_TOL,
                    },
                ));
            }
            let whole = fs.round();
            if whole > 0.0
                && (whole - fs).abs() <= 1e-6 * fs
                && off_grid(time, start, whole).is_none()
            {
                whole
            } else {
                fs
            }
        }
    };
    match off_grid(time, start, rate) {
        None => Ok((rate, start)),
        Some(i) => Err((
            row_lines[i],
            CsvErrorKind::NonUniformTime {
                time_s: time[i],
                expected_s: start + i as f64 / rate,
                step_s: 1.0 / rate,
                rel_tol: TIME_GRID_REL_TOL,
            },
        )),
    }
}

/// Index of the first time value farther than the tolerance from the grid.
fn off_grid(time: &[f64], start: f64, rate: f64) -> Option<usize> {
    let tol = TIME_GRID_REL_TOL / rate;
    time.iter()
        .enumerate()
        .position(|(i, &t)| (t - (start + i as f64 / rate)).abs() > tol)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::signals::trace::Sensitivity;

    fn scratch(tag: &str) -> std::path::PathBuf {
        let dir = std::env::temp_dir().join(format!("vlab-csv-{tag}-{}", std::process::id()));
        std::fs::create_dir_all(&dir).expect("scratch dir");
        dir
    }

    fn awkward_trace() -> Trace {
        let mut t = Trace::new(40_000.0, 1.25).expect("trace");
        let n = 500;
        // Values that stress round-tripping: thirds, tiny, huge, negative zero.
        let force: Vec<f64> = (0..n)
            .map(|i| match i % 5 {
                0 => i as f64 / 3.0,
                1 => -1e-300 * i as f64,
                2 => 1.7976931348623157e300 / (i as f64 + 1.0),
                3 => -0.0,
                _ => (i as f64 * 0.1).sin(),
            })
            .collect();
        let accel: Vec<f64> = (0..n).map(|i| (i as f64).sqrt() * -9.81).collect();
        t.add_channel("force", "N", force).expect("force");
        t.add_channel("acceleration", "m/s^2", accel)
            .expect("accel");
        t.add_channel("gain", "", vec![2.0; n]).expect("gain");
        t.metadata.source = "unit test".into();
        t.metadata.rig = "thesis-shaker".into();
        t.metadata.drive_freq_hz = Some(40.0);
        t.metadata.gamma = Some(20.0);
        t.metadata.sensitivities.insert(
            "acceleration".into(),
            Sensitivity {
                value: 10.2,
                unit: "mV/(m/s^2)".into(),
            },
        );
        t.metadata.extra.insert(
            "note".into(),
            serde_json::json!("line one\nline two, with comma"),
        );
        t
    }

    #[test]
    fn write_read_is_bit_identical() {
        let dir = scratch("rt");
        let path = dir.join("trace.csv");
        let t = awkward_trace();
        write_csv(&path, &t).expect("write");
        let back = read_csv(&path).expect("read");
        assert_eq!(back.sample_rate_hz.to_bits(), t.sample_rate_hz.to_bits());
        assert_eq!(back.start_time_s.to_bits(), t.start_time_s.to_bits());
        assert_eq!(back.metadata, t.metadata);
        assert_eq!(back.channels.len(), 3);
        for (a, b) in back.channels.iter().zip(&t.channels) {
            assert_eq!((&a.name, &a.unit), (&b.name, &b.unit));
            let bits = |c: &[f64]| c.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&a.samples), bits(&b.samples), "channel {}", a.name);
        }
        let header = std::fs::read_to_string(&path).expect("text");
        assert!(header.contains("\ntime [s],force [N],acceleration [m/s^2],gain []\n"));
        std::fs::remove_dir_all(dir).ok();
    }

    #[test]
    fn plain_lab_csv_infers_the_rate() {
        // Times printed to 7 decimals at 40 kHz are exact on the grid.
        let mut text = String::from("\u{feff}time_s,accel_mps2,force [N]\r\n");
        for i in 0..100 {
            text.push_str(&format!(
                "{:.7},{},{}\r\n",
                2.0 + i as f64 * 25e-6,
                i,
                -(i as f64)
            ));
        }
        let t = parse_csv(&text).expect("parse");
        assert_eq!(t.sample_rate_hz, 40_000.0);
        assert_eq!(t.start_time_s, 2.0);
        assert_eq!(t.len(), 100);
        assert_eq!(t.channels[0].name, "accel_mps2");
        assert_eq!(t.channels[0].unit, "");
        assert_eq!(t.channels[1].unit, "N");
        // A non-integer rate is kept as inferred (3 Hz spacing of 1/3 s); tol 1e-12.
        let t = parse_csv("time [s],x [m]\n0,1\n0.3333333333333333,2\n0.6666666666666666,3\n")
            .expect("thirds");
        assert!((t.sample_rate_hz - 3.0).abs() < 1e-12);
    }

    fn kind(text: &str) -> (usize, CsvErrorKind) {
        parse_csv(text).expect_err("must fail")
    }

    #[test]
    fn each_bad_input_has_its_error() {
        assert!(matches!(kind(""), (1, CsvErrorKind::Empty)));
        assert!(matches!(
            kind("# only a comment\n\n"),
            (1, CsvErrorKind::Empty)
        ));
        assert!(matches!(
            kind("force [N],time [s]\n1,0\n2,1\n"),
            (1, CsvErrorKind::MissingTimeColumn { .. })
        ));
        assert!(matches!(
            kind("time [s]\n0\n1\n"),
            (1, CsvErrorKind::NoDataColumns)
        ));
        assert!(matches!(
            kind("time [s],f [N],f [kN]\n0,1,2\n1,1,2\n"),
            (1, CsvErrorKind::BadHeader { column: 3, .. })
        ));
        match kind("time [s],force [N]\n0,1\n0.1,abc\n0.2,3\n") {
            (3, CsvErrorKind::NotANumber { column, text }) => {
                assert_eq!((column.as_str(), text.as_str()), ("force", "abc"));
            }
            other => panic!("{other:?}"),
        }
        assert!(matches!(
            kind("time [s],force [N]\n0,1\n0.1,NaN\n"),
            (3, CsvErrorKind::NonFinite { .. })
        ));
        assert!(matches!(
            kind("time [s],force [N],a [m/s^2]\n0,1,2\n0.1,3\n"),
            (
                3,
                CsvErrorKind::Ragged {
                    expected: 3,
                    got: 2
                }
            )
        ));
        assert!(matches!(
            kind("time [s],force [N]\n0,1\n"),
            (1, CsvErrorKind::TooFewRows { got: 1 })
        ));
        assert!(matches!(
            kind("time [s],force [N]\n0,1\n0.1,2\n0.25,3\n0.3,4\n"),
            (4, CsvErrorKind::NonUniformTime { .. })
        ));
        // Declared rate that the time column contradicts.
        assert!(matches!(
            kind("# sample_rate_hz: 20\ntime [s],f [N]\n0,1\n0.1,2\n"),
            (4, CsvErrorKind::NonUniformTime { .. })
        ));
        assert!(matches!(
            kind("# sample_rate_hz: zero\ntime [s],f [N]\n0,1\n0.1,2\n"),
            (1, CsvErrorKind::BadComment { .. })
        ));
        assert!(matches!(
            kind("# metadata: {\"rigg\": 1}\ntime [s],f [N]\n0,1\n0.1,2\n"),
            (1, CsvErrorKind::BadComment { .. })
        ));
        // The file-level error names path and line.
        let dir = scratch("err");
        let path = dir.join("bad.csv");
        std::fs::write(&path, "time [s],force [N]\n0,1\n0.1,abc\n").expect("write");
        let msg = read_csv(&path).expect_err("bad").to_string();
        assert!(
            msg.ends_with("bad.csv: line 3: column 'force': 'abc' is not a number"),
            "{msg}"
        );
        assert!(matches!(
            read_csv(&dir.join("absent.csv")),
            Err(SignalsError::Io { .. })
        ));
        std::fs::remove_dir_all(dir).ok();
    }

    #[test]
    fn unwritable_names_are_refused_before_writing() {
        let dir = scratch("names");
        let path = dir.join("x.csv");
        let mut t = Trace::new(10.0, 0.0).expect("trace");
        t.add_channel("a,b", "N", vec![1.0, 2.0])
            .expect("name is fine in memory");
        assert!(matches!(
            write_csv(&path, &t),
            Err(SignalsError::Csv {
                kind: CsvErrorKind::Unwritable { .. },
                ..
            })
        ));
        assert!(!path.exists());
        std::fs::remove_dir_all(dir).ok();
    }
}
