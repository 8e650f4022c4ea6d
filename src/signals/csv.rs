//! Traces as CSV text: what a lab exports and what a spreadsheet reads. No
//! thesis equation lives here. The `csv` crate splits and quotes the text;
//! this module adds vlab's conventions (comments, units, the time column) and
//! the dialects real lab exports use.
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
//!   unit). The first column is time in seconds: `time [s]` (also read: `t`,
//!   `time`, `Time`, `TIME`, `time_s`, `t_s`, any of them with the unit
//!   `[s]`; see [`super::column_names`]). A header cell without brackets is
//!   read as a name with an empty unit, so plain lab headers such as
//!   `force_n` load. A record read as a [`Table`] ([`read_csv_table`]) may
//!   have its time column anywhere, found by those names or named by the
//!   caller.
//! - One row per sample, comma-separated, no quoting (a channel name or unit
//!   that would need quotes is refused). Samples are written with Rust's
//!   shortest round-trip formatting (`{}`), so reading back gives
//!   bit-identical `f64` samples.
//! - Time in s, as the sample index over the rate: `(k + i) / fs` for sample
//!   `i` when the start time is `k / fs` for a whole `k` (within
//!   [`START_ON_GRID_REL_TOL`] of a sample period), so that at 40 kHz sample 1
//!   of a record starting at 0 reads `0.000025`; `start_time_s + i / fs`
//!   otherwise. The exact start time is kept in the `start_time_s` comment.
//!
//! # Reading
//!
//! [`read_csv`] reads vlab files and the CSVs lab software exports:
//!
//! - fields separated by `,`, `;` or a tab, optionally in double quotes
//!   (`"force [N]"`), with or without a trailing separator on each line;
//! - numbers with `.` or `,` as the decimal mark (`0,25;1,5e-3`); thousands
//!   separators are not read;
//! - `#` comment lines (the leading ones may declare the keys above; later
//!   ones are skipped), blank lines, a UTF-8 byte-order mark, CRLF line ends,
//!   empty spreadsheet rows (`;;;`), and a spreadsheet's `sep=;` first line
//!   naming the separator.
//!
//! The dialect is detected unless [`CsvReadOptions`] (through
//! [`read_csv_with`]) names it:
//!
//! - separator: the one of `;`, tab and `,` that appears in the header line
//!   outside quotes; if several do, the one that splits the first data row into
//!   as many cells as the header. Anything else is refused as ambiguous, as is
//!   a detected `,`-separated file with a row of more cells than its header
//!   (the sign of decimal commas in a comma-separated file).
//! - decimal mark: `,` if a number holds a comma (unquoted, only possible when
//!   the separator is `;` or a tab), `.` otherwise. A file that uses both is
//!   refused, naming the line that decided the mark.
//!
//! Refused besides: text that is not UTF-8 (a spreadsheet's "CSV UTF-8" is),
//! a quoted cell that spans lines, a bare carriage return inside a line.
//!
//! With a `sample_rate_hz` comment the time column is checked against it;
//! without one the rate is inferred from the time column, `(n-1) / (t_last -
//! t_0)`, taken as the nearest whole number of hertz when that is within 1 ppm.
//! Either way every time value must lie on the uniform grid within
//! [`TIME_GRID_REL_TOL`] of a sample period. Errors name the line (one-based,
//! counting every line of the file) and what is wrong with it.

use std::borrow::Cow;
use std::collections::{BTreeMap, BTreeSet};
use std::fmt::Write as _;
use std::io::Write as _;
use std::path::Path;

use super::column_names::{is_time_name, time_column_index};
use super::error::{CsvErrorKind, InvalidParameter, Result, SignalsError};
use super::table::{Table, TableFormat};
use super::trace::{Channel, Trace, TraceMetadata};
use crate::atomic_write::write_atomic;

/// How far a time value may be from the uniform grid, as a fraction of the
/// sample period.
pub const TIME_GRID_REL_TOL: f64 = 1e-6;

/// How close the start time must be to a whole number `k` of sample periods,
/// as a fraction of a period, for the time column to be written as
/// `(k + i) / fs`.
pub const START_ON_GRID_REL_TOL: f64 = 1e-9;

/// The field separators vlab reads: comma, semicolon, tab.
pub const DELIMITERS: [u8; 3] = [b',', b';', b'\t'];

/// How to read a CSV file's dialect. A `None` field is detected from the
/// file (see the module docs); `Default` detects both.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct CsvReadOptions {
    /// Field separator, one of [`DELIMITERS`].
    pub delimiter: Option<u8>,
    /// `true`: numbers use `,` as the decimal mark (`0,25`); `false`: `.`.
    pub decimal_comma: Option<bool>,
}

/// Parses a separator as typed on a command line: `,`, `;`, a tab character,
/// `\t` or `tab`; anything else is refused as the parameter `delimiter`.
pub fn parse_delimiter(text: &str) -> std::result::Result<u8, InvalidParameter> {
    match text {
        "," => Ok(b','),
        ";" => Ok(b';'),
        "\t" | "\\t" | "tab" | "TAB" => Ok(b'\t'),
        other => Err(InvalidParameter::new(
            "delimiter",
            format!("'{other}'"),
            "",
            "',', ';' or tab (the separators vlab reads)",
        )),
    }
}

/// A separator as shown in messages.
fn delimiter_name(d: u8) -> String {
    match d {
        b'\t' => "tab".to_string(),
        d => format!("'{}'", d as char),
    }
}

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
    let mut header = vec!["time [s]".to_string()];
    header.extend(
        trace
            .channels
            .iter()
            .map(|c| format!("{} [{}]", c.name, c.unit)),
    );
    let time = TimeColumn::of(trace);
    write_atomic(path, |out| {
        out.write_all(head.as_bytes())?;
        let mut w = csv::WriterBuilder::new().from_writer(out);
        w.write_record(&header)?;
        let mut cell = String::new();
        for i in 0..trace.len() {
            cell.clear();
            let _ = write!(cell, "{}", time.at(i));
            w.write_field(&cell)?;
            for c in &trace.channels {
                cell.clear();
                let _ = write!(cell, "{}", c.samples[i]);
                w.write_field(&cell)?;
            }
            w.write_record(None::<&[u8]>)?;
        }
        w.flush()
    })
    .map_err(|source| SignalsError::Io {
        path: path.to_path_buf(),
        source,
    })
}

/// The time column as written: sample index over rate, from the start's
/// place on the sample grid when it has one.
struct TimeColumn {
    sample_rate_hz: f64,
    start_time_s: f64,
    /// `k` with `start_time_s = k / sample_rate_hz`, when there is one.
    start_index: Option<f64>,
}

impl TimeColumn {
    fn of(trace: &Trace) -> Self {
        let fs = trace.sample_rate_hz;
        let k = (trace.start_time_s * fs).round();
        // Beyond 2^53 whole numbers are no longer exact in f64.
        let on_grid = k.abs() < 2f64.powi(53)
            && ((trace.start_time_s - k / fs) * fs).abs() <= START_ON_GRID_REL_TOL;
        Self {
            sample_rate_hz: fs,
            start_time_s: trace.start_time_s,
            start_index: on_grid.then_some(k),
        }
    }

    /// Time of sample `i`, in s.
    fn at(&self, i: usize) -> f64 {
        match self.start_index {
            Some(k) => (k + i as f64) / self.sample_rate_hz,
            None => self.start_time_s + i as f64 / self.sample_rate_hz,
        }
    }
}

/// True when `s` can sit in a header cell unquoted and be parsed back unchanged.
fn writable(s: &str) -> bool {
    s == s.trim() && !s.contains([',', '[', ']', '"', '\n', '\r'])
}

/// Reads a CSV trace, detecting its dialect (see the module docs).
pub fn read_csv(path: &Path) -> Result<Trace> {
    read_csv_with(path, &CsvReadOptions::default())
}

/// Reads a CSV trace with the separator and decimal mark given in `options`
/// (each detected when `None`).
pub fn read_csv_with(path: &Path, options: &CsvReadOptions) -> Result<Trace> {
    let text = read_utf8(path)?;
    parse_csv_with(&text, options).map_err(|(line, kind)| SignalsError::Csv {
        path: path.to_path_buf(),
        line,
        kind,
    })
}

/// The file's text, refused with the line of the first byte that is not UTF-8.
pub(crate) fn read_utf8(path: &Path) -> Result<String> {
    let bytes = std::fs::read(path).map_err(|source| SignalsError::Io {
        path: path.to_path_buf(),
        source,
    })?;
    String::from_utf8(bytes).map_err(|e| {
        let bytes = e.as_bytes();
        let at = e.utf8_error().valid_up_to();
        let line = 1 + bytes[..at].iter().filter(|&&b| b == b'\n').count();
        let byte = bytes.get(at).copied().unwrap_or_default();
        SignalsError::Csv {
            path: path.to_path_buf(),
            line,
            kind: CsvErrorKind::NotUtf8 { byte },
        }
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
    /// Every other `# key: value` comment, as text.
    comments: BTreeMap<String, String>,
}

/// Parses CSV text of any dialect, detected.
#[cfg(test)]
fn parse_csv(text: &str) -> Result<Trace, ParseError> {
    parse_csv_with(text, &CsvReadOptions::default())
}

/// Parses CSV text into a trace; errors carry one-based line numbers.
fn parse_csv_with(text: &str, options: &CsvReadOptions) -> Result<Trace, ParseError> {
    let raw = parse_rows(text, options, TimeAt::First)?;
    let header_line = raw.header_line;
    if raw.time.len() < 2 {
        return Err((
            header_line,
            CsvErrorKind::TooFewRows {
                got: raw.time.len(),
            },
        ));
    }
    let (sample_rate_hz, start_time_s) = sample_grid(&raw.time, &raw.declared, &raw.row_lines)?;
    let mut trace = Trace::new(sample_rate_hz, start_time_s).map_err(|e| {
        (
            header_line,
            CsvErrorKind::BadComment {
                key: "sample_rate_hz".into(),
                problem: e.to_string(),
            },
        )
    })?;
    trace.metadata = raw.declared.metadata;
    for ((name, unit), samples) in raw.columns.into_iter().zip(raw.data) {
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

/// Reads a CSV file as a [`Table`]: the same dialects, header and comments as
/// [`read_csv_with`], but the time column is kept as written, not checked
/// against a uniform grid (a record from another program, whose time axis the
/// caller validates, e.g. with [`Table::uniform_step_s`]). The time column
/// may stand anywhere: it is the one called `time_column` when given (its
/// name without the unit, or the whole header cell), else the first of a time
/// name ([`super::column_names`]); its unit, when the header gives one, must
/// be `s`.
pub fn read_csv_table(
    path: &Path,
    options: &CsvReadOptions,
    time_column: Option<&str>,
) -> Result<Table> {
    let csv_err = |line, kind| SignalsError::Csv {
        path: path.to_path_buf(),
        line,
        kind,
    };
    let text = read_utf8(path)?;
    let raw = parse_rows(&text, options, TimeAt::Named(time_column))
        .map_err(|(line, kind)| csv_err(line, kind))?;
    let time_header = raw.time_header.clone();
    let columns = raw
        .columns
        .into_iter()
        .zip(raw.data)
        .map(|((name, unit), samples)| Channel {
            name,
            unit,
            samples,
        })
        .collect();
    let mut comments = raw.declared.comments;
    if let Some(fs) = raw.declared.sample_rate_hz {
        comments.insert("sample_rate_hz".into(), fs.to_string());
    }
    Ok(Table {
        path: path.to_path_buf(),
        format: TableFormat::Csv,
        time_column: time_header,
        time_s: raw.time,
        columns,
        metadata: raw.declared.metadata,
        comments,
        lines: raw.row_lines,
    })
}

/// What [`parse_rows`] read: the header, the columns and the leading comments.
struct RawRows {
    /// One-based line of the header.
    header_line: usize,
    /// The time column's header cell.
    time_header: String,
    /// (name, unit) per data column.
    columns: Vec<(String, String)>,
    time: Vec<f64>,
    data: Vec<Vec<f64>>,
    declared: Declared,
    /// File line of each row.
    row_lines: Vec<usize>,
}

/// Which column of a CSV holds time.
#[derive(Debug, Clone, Copy)]
enum TimeAt<'a> {
    /// The first, which must have a time name (a vlab trace).
    First,
    /// The one of the name given, else the first of a time name (a record of
    /// named columns).
    Named(Option<&'a str>),
}

/// Parses CSV text of any dialect into its rows; errors carry one-based line
/// numbers. The time axis is not checked here.
fn parse_rows(text: &str, options: &CsvReadOptions, time: TimeAt) -> Result<RawRows, ParseError> {
    if let Some(d) = options.delimiter
        && !DELIMITERS.contains(&d)
    {
        return Err((
            0,
            CsvErrorKind::UnsupportedDelimiter {
                delimiter: d as char,
            },
        ));
    }
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let lead = leading_block(text)?;
    let (kept, record_lines) = kept_records(&text[lead.offset..], lead.header_line)?;
    let named = options.delimiter.or(lead.sep);
    let delimiter = match named {
        Some(d) => d,
        None => detect_delimiter(lead.header_line, &kept)?,
    };
    let mut reader = csv::ReaderBuilder::new()
        .has_headers(false)
        .delimiter(delimiter)
        .flexible(true)
        .trim(csv::Trim::All)
        .from_reader(kept.as_bytes());
    let mut rows = Rows {
        mark: DecimalMark::new(options.decimal_comma),
        detected_comma: named.is_none() && delimiter == b',',
        header: None,
        time: Vec::new(),
        data: Vec::new(),
        row_lines: Vec::new(),
    };
    let mut record = csv::StringRecord::new();
    for &n in &record_lines {
        match reader.read_record(&mut record) {
            Ok(true) => {}
            Ok(false) => break,
            Err(e) => {
                return Err((
                    n,
                    CsvErrorKind::Syntax {
                        problem: e.to_string(),
                    },
                ));
            }
        }
        rows.record(n, &record, time)?;
    }
    let Some(header) = rows.header else {
        return Err((lead.header_line, CsvErrorKind::Empty));
    };
    Ok(RawRows {
        header_line: lead.header_line,
        time_header: header.time_header,
        columns: header.columns,
        time: rows.time,
        data: rows.data,
        declared: lead.declared,
        row_lines: rows.row_lines,
    })
}

/// The block before a CSV's header: blank lines, `# key: value` comments, a
/// spreadsheet's `sep=` line.
struct Leading {
    declared: Declared,
    /// The separator a `sep=` line names.
    sep: Option<u8>,
    /// One-based line of the header.
    header_line: usize,
    /// Byte offset of the header line in the text.
    offset: usize,
}

/// Reads the leading block of `text` line by line, up to the header.
fn leading_block(text: &str) -> Result<Leading, ParseError> {
    let mut declared = Declared::default();
    let mut sep = None;
    let mut offset = 0;
    let mut line = 0;
    loop {
        let rest = &text[offset..];
        if rest.is_empty() {
            return Err((1, CsvErrorKind::Empty));
        }
        line += 1;
        let end = rest.find('\n').map_or(rest.len(), |e| e + 1);
        let raw = rest[..end].trim_end_matches(['\n', '\r']);
        let trimmed = raw.trim();
        if trimmed.starts_with('#') {
            parse_comment(line, trimmed, &mut declared)?;
        } else if let Some(named) = raw.strip_prefix("sep=") {
            sep = Some(match named.as_bytes() {
                [d] if DELIMITERS.contains(d) => *d,
                _ => {
                    return Err((
                        line,
                        CsvErrorKind::AmbiguousDelimiter {
                            problem: format!("'sep={named}' names no separator vlab reads"),
                        },
                    ));
                }
            });
        } else if !trimmed.is_empty() {
            return Ok(Leading {
                declared,
                sep,
                header_line: line,
                offset,
            });
        }
        offset += end;
    }
}

/// The lines from the header on, with comments and blank lines taken out:
/// one record per kept line, and each record's file line. The csv crate does
/// not report reliable line numbers around comments and blank lines, hence
/// this pass.
fn kept_records(body: &str, header_line: usize) -> Result<(String, Vec<usize>), ParseError> {
    let mut kept = String::with_capacity(body.len());
    let mut record_lines = Vec::new();
    for (k, l) in body.lines().enumerate() {
        let n = header_line + k;
        let t = l.trim();
        if t.is_empty() || t.starts_with('#') {
            continue;
        }
        let syntax = |problem: &str| {
            (
                n,
                CsvErrorKind::Syntax {
                    problem: problem.to_string(),
                },
            )
        };
        if l.contains('\r') {
            return Err(syntax(
                "a carriage return inside the line: save the file with LF or CRLF line ends",
            ));
        }
        if l.bytes().filter(|&b| b == b'"').count() % 2 == 1 {
            return Err(syntax(
                "unbalanced double quote: a quoted cell must open and close on its line",
            ));
        }
        kept.push_str(l);
        kept.push('\n');
        record_lines.push(n);
    }
    Ok((kept, record_lines))
}

/// A CSV header as read: the data columns and where time is.
struct Header {
    /// (name, unit) per data column, in file order.
    columns: Vec<(String, String)>,
    /// Zero-based cell of the time column.
    time_index: usize,
    /// The time column's header cell.
    time_header: String,
}

/// The header and rows read so far.
struct Rows {
    mark: DecimalMark,
    /// The separator was detected as `,` (rows longer than the header then
    /// suggest decimal commas).
    detected_comma: bool,
    header: Option<Header>,
    time: Vec<f64>,
    data: Vec<Vec<f64>>,
    row_lines: Vec<usize>,
}

impl Rows {
    /// Takes record `record` of file line `n`: the header if none was read
    /// yet, else a row of numbers.
    fn record(
        &mut self,
        n: usize,
        record: &csv::StringRecord,
        time: TimeAt,
    ) -> Result<(), ParseError> {
        // A spreadsheet's empty rows (";;;") are blank lines.
        if record.iter().all(str::is_empty) {
            return Ok(());
        }
        // A separator closing every line leaves an empty last cell: drop it.
        let used = match record.len() {
            k if k > 1 && record[k - 1].is_empty() => k - 1,
            k => k,
        };
        let Some(header) = &self.header else {
            let cells: Vec<&str> = record.iter().take(used).collect();
            let header = parse_header(n, &cells, time)?;
            self.data = vec![Vec::new(); header.columns.len()];
            self.header = Some(header);
            return Ok(());
        };
        let n_cols = header.columns.len() + 1;
        if used != n_cols {
            return Err(ragged(n, n_cols, used, self.detected_comma));
        }
        self.row_lines.push(n);
        for (j, cell) in record.iter().take(used).enumerate() {
            if j == header.time_index {
                let value = self.mark.parse(n, "time", cell)?;
                self.time.push(value);
            } else {
                let k = if j < header.time_index { j } else { j - 1 };
                let value = self.mark.parse(n, &header.columns[k].0, cell)?;
                self.data[k].push(value);
            }
        }
        Ok(())
    }
}

/// A row of line `n` with `used` cells where the header has `n_cols`.
fn ragged(n: usize, n_cols: usize, used: usize, detected_comma: bool) -> ParseError {
    if detected_comma && used > n_cols {
        return (
            n,
            CsvErrorKind::AmbiguousDelimiter {
                problem: format!(
                    "the header splits into {n_cols} columns at ',' but this row into \
                     {used} cells: numbers with decimal commas in a ','-separated file? \
                     They cannot be told apart from the separators unless quoted"
                ),
            },
        );
    }
    (
        n,
        CsvErrorKind::Ragged {
            expected: n_cols,
            got: used,
        },
    )
}

/// How often `d` occurs in `line` outside double quotes.
fn count_unquoted(line: &str, d: u8) -> usize {
    let mut quoted = false;
    let mut n = 0;
    for &b in line.as_bytes() {
        if b == b'"' {
            quoted = !quoted;
        } else if b == d && !quoted {
            n += 1;
        }
    }
    n
}

/// The separator of the `kept` lines (header first), see the module docs.
fn detect_delimiter(header_line: usize, kept: &str) -> Result<u8, ParseError> {
    let mut lines = kept.lines();
    let header = lines.next().unwrap_or_default();
    let first_row = lines.next();
    let present: Vec<(u8, usize)> = [b';', b'\t', b',']
        .into_iter()
        .map(|d| (d, count_unquoted(header, d)))
        .filter(|&(_, n)| n > 0)
        .collect();
    match present.as_slice() {
        [] => return Ok(b','),
        [(d, _)] => return Ok(*d),
        _ => {}
    }
    let fitting: Vec<u8> = first_row.map_or_else(Vec::new, |row| {
        present
            .iter()
            .filter(|&&(d, n)| count_unquoted(row, d) == n)
            .map(|&(d, _)| d)
            .collect()
    });
    if let [d] = fitting.as_slice() {
        return Ok(*d);
    }
    let listed = present
        .iter()
        .map(|&(d, n)| format!("{} ({n}x)", delimiter_name(d)))
        .collect::<Vec<_>>()
        .join(" and ");
    Err((
        header_line,
        CsvErrorKind::AmbiguousDelimiter {
            problem: format!(
                "the header holds {listed} outside quotes and the first data row does not tell \
                 which one separates the columns"
            ),
        },
    ))
}

/// The file's decimal mark: given, or decided by the first number that has one.
struct DecimalMark {
    /// `Some(true)`: `,`; `Some(false)`: `.`; `None`: not yet seen.
    comma: Option<bool>,
    /// Where it was decided: line and cell, or `None` when it was given.
    decided_by: Option<(usize, String)>,
}

impl DecimalMark {
    fn new(given: Option<bool>) -> Self {
        Self {
            comma: given,
            decided_by: None,
        }
    }

    /// Parses one numeric cell (already trimmed) of column `column` on `line`.
    fn parse(&mut self, line: usize, column: &str, cell: &str) -> Result<f64, ParseError> {
        let bad = |problem: String| {
            (
                line,
                CsvErrorKind::DecimalMark {
                    column: column.to_string(),
                    text: cell.to_string(),
                    problem,
                },
            )
        };
        let has_comma = cell.contains(',');
        if has_comma && cell.contains('.') {
            return Err(bad(
                "has both ',' and '.': thousands separators are not read".into(),
            ));
        }
        if has_comma || cell.contains('.') {
            match (self.comma, &self.decided_by) {
                (None, _) => {
                    self.comma = Some(has_comma);
                    self.decided_by = Some((line, cell.to_string()));
                }
                (Some(comma), _) if comma == has_comma => {}
                (Some(comma), Some((first_line, first))) => {
                    let (this, that) = if comma { (".", ",") } else { (",", ".") };
                    return Err(bad(format!(
                        "has '{this}' as the decimal mark but line {first_line} ('{first}') has \
                         '{that}': one file, one decimal mark"
                    )));
                }
                (Some(comma), None) => {
                    return Err(bad(if comma {
                        "has a '.' but the decimal mark was given as ','".into()
                    } else {
                        "has a ',' but the decimal mark was given as '.'".into()
                    }));
                }
            }
        }
        let text = if has_comma {
            Cow::Owned(cell.replace(',', "."))
        } else {
            Cow::Borrowed(cell)
        };
        let value = text.parse::<f64>().map_err(|_| {
            (
                line,
                CsvErrorKind::NotANumber {
                    column: column.to_string(),
                    text: cell.to_string(),
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
        _ => {
            declared.comments.insert(key.to_string(), value.to_string());
        }
    }
    Ok(())
}

/// Splits the header cells into (name, unit) per data column and finds the
/// time column (`time`), checking its unit.
fn parse_header(line: usize, cells: &[&str], time: TimeAt) -> Result<Header, ParseError> {
    let split: Vec<(&str, Option<&str>)> = cells.iter().map(|c| split_name_unit(c)).collect();
    let names: Vec<&str> = split.iter().map(|&(name, _)| name).collect();
    let time_index = match time {
        TimeAt::First => {
            if !names.first().is_some_and(|name| is_time_name(name)) {
                return Err((
                    line,
                    CsvErrorKind::MissingTimeColumn {
                        found: cells.first().copied().unwrap_or_default().to_string(),
                    },
                ));
            }
            0
        }
        TimeAt::Named(given) => time_column_index(&names, given)
            .or_else(|| given.and_then(|g| cells.iter().position(|c| *c == g)))
            .ok_or_else(|| {
                (
                    line,
                    CsvErrorKind::NoTimeColumn {
                        given: given.map(str::to_string),
                        names: names.join(", "),
                    },
                )
            })?,
    };
    if let (_, Some(unit)) = split[time_index]
        && unit != "s"
    {
        return Err((
            line,
            CsvErrorKind::TimeUnit {
                header: cells[time_index].to_string(),
                unit: unit.to_string(),
            },
        ));
    }
    let mut seen = BTreeSet::new();
    let mut columns = Vec::new();
    for (j, &cell) in cells.iter().enumerate() {
        if j == time_index {
            continue;
        }
        let column = j + 1;
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
        let (name, unit) = split[j];
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
    Ok(Header {
        columns,
        time_index,
        time_header: cells[time_index].to_string(),
    })
}

/// `"force [N]"` -> `("force", Some("N"))`; `"force_n"` -> `("force_n", None)`.
fn split_name_unit(cell: &str) -> (&str, Option<&str>) {
    if let Some(inner) = cell.strip_suffix(']')
        && let Some((name, unit)) = inner.rsplit_once('[')
    {
        return (name.trim(), Some(unit.trim()));
    }
    (cell.trim(), None)
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

    /// The time cells of a written file, as text.
    fn time_cells(path: &std::path::Path) -> Vec<String> {
        std::fs::read_to_string(path)
            .expect("text")
            .lines()
            .skip(5)
            .map(|l| l.split(',').next().unwrap_or_default().to_string())
            .collect()
    }

    #[test]
    fn time_is_written_as_sample_index_over_rate() {
        let dir = scratch("time");
        let path = dir.join("t.csv");
        let write_read = |start: f64| {
            let mut t = Trace::new(40_000.0, start).expect("trace");
            t.add_channel("x", "m", vec![1.0 / 3.0, -0.0, 2e-300, 7.0])
                .expect("x");
            write_csv(&path, &t).expect("write");
            let back = read_csv(&path).expect("read");
            assert_eq!(back.start_time_s.to_bits(), start.to_bits());
            let bits = |c: &[f64]| c.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(
                bits(&back.channels[0].samples),
                bits(&t.channels[0].samples)
            );
            (t, time_cells(&path))
        };
        // Starts on the 40 kHz grid: (k + i) / fs, shortest text.
        let on_grid: [(f64, [&str; 4]); 4] = [
            (0.0, ["0", "0.000025", "0.00005", "0.000075"]),
            // A start that should be 0, off by rounding, as another program
            // may declare it (vlab's DAQ puts a start on a sample at 0 exactly,
            // `rig::Daq::finish`).
            (
                -1.3877787807814457e-17,
                ["0", "0.000025", "0.00005", "0.000075"],
            ),
            (
                3000.0 / 40_000.0,
                ["0.075", "0.075025", "0.07505", "0.075075"],
            ),
            (-0.01, ["-0.01", "-0.009975", "-0.00995", "-0.009925"]),
        ];
        for (start, expected) in on_grid {
            assert_eq!(write_read(start).1, expected, "start {start:e}");
        }
        // 0.4 of a period off the grid: start + i / fs, as the trace computes it
        // (which is not the shortest decimal: 0.000035000000000000004).
        let (t, cells) = write_read(1e-5);
        let expected: Vec<String> = (0..4).map(|i| format!("{}", t.time_s(i))).collect();
        assert_eq!(cells, expected);
        assert_eq!(cells[1], "0.000035000000000000004");
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
    fn time_column_by_any_common_name_in_seconds() {
        for name in [
            "t", "time", "Time", "TIME", "time_s", "t_s", "time [s]", "t [s]",
        ] {
            let t = parse_csv(&format!("{name},x [m]\n0,1\n0.5,2\n"))
                .unwrap_or_else(|e| panic!("{name}: {}", e.1));
            assert_eq!(t.sample_rate_hz, 2.0, "{name}");
        }
        let (line, k) = kind("time [ms],x\n0,1\n1,2\n");
        assert_eq!(line, 1);
        assert!(k.to_string().contains("'time [ms]' is in ms"), "{k}");
        let (_, k) = kind("zeit,x\n0,1\n1,2\n");
        assert!(
            k.to_string().contains("'zeit'") && k.to_string().contains("t, time, time_s or t_s"),
            "{k}"
        );
        // A record of named columns: time anywhere, found or named.
        let text = "x [m],Time [s],stamp [s]\n1,0,5\n3,1,6\n";
        let options = CsvReadOptions::default();
        let raw = parse_rows(text, &options, TimeAt::Named(None)).expect("found");
        assert_eq!(raw.time_header, "Time [s]");
        assert_eq!(raw.time, vec![0.0, 1.0]);
        assert_eq!(raw.data, vec![vec![1.0, 3.0], vec![5.0, 6.0]]);
        for given in ["stamp", "stamp [s]"] {
            let raw = parse_rows(text, &options, TimeAt::Named(Some(given))).expect("named");
            assert_eq!(raw.time, vec![5.0, 6.0], "{given}");
            assert_eq!(raw.columns[1].0, "Time");
        }
        let (_, k) = parse_rows(text, &options, TimeAt::Named(Some("x")))
            .err()
            .expect("in m");
        assert!(k.to_string().contains("'x [m]' is in m"), "{k}");
        let (_, k) = parse_rows(text, &options, TimeAt::Named(Some("clock")))
            .err()
            .expect("absent");
        assert!(
            k.to_string()
                .contains("no column 'clock' (given as the time column) among [x, Time, stamp]"),
            "{k}"
        );
        let (_, k) = parse_rows("a,b\n0,1\n", &options, TimeAt::Named(None))
            .err()
            .expect("none");
        assert!(k.to_string().contains("no time column among [a, b]"), "{k}");
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

    /// The trace every dialect below spells: 4 samples at 40 kHz from 0.075 s.
    fn dialect_reference() -> Trace {
        let mut t = Trace::new(40_000.0, 0.075).expect("trace");
        t.add_channel("force", "N", vec![0.25, -1.5e-3, 12.0, 0.0])
            .expect("force");
        t.add_channel("acceleration", "m/s^2", vec![1.0, 2.5, -3.25, 1e-7])
            .expect("accel");
        t
    }

    /// Rows of [`dialect_reference`] with `sep` between cells, `comma` for
    /// decimal commas, `end` at the end of each line.
    fn rows(sep: &str, comma: bool, end: &str) -> String {
        let rows = [
            ["0.075", "0.25", "1"],
            ["0.075025", "-1.5e-3", "2.5"],
            ["0.07505", "12", "-3.25"],
            ["0.075075", "0.0", "1e-7"],
        ];
        rows.iter()
            .map(|r| {
                let cells: Vec<String> = r
                    .iter()
                    .map(|c| {
                        if comma {
                            c.replace('.', ",")
                        } else {
                            c.to_string()
                        }
                    })
                    .collect();
                format!("{}{end}", cells.join(sep))
            })
            .collect()
    }

    fn same_trace(a: &Trace, b: &Trace, what: &str) {
        assert_eq!(a.sample_rate_hz, b.sample_rate_hz, "{what}: rate");
        assert_eq!(
            a.start_time_s.to_bits(),
            b.start_time_s.to_bits(),
            "{what}: start"
        );
        assert_eq!(a.channels, b.channels, "{what}: channels");
    }

    /// Each dialect a lab exports, with what it must be read as when named.
    /// A table of fixtures, one entry per dialect: its length is the number
    /// of dialects, not steps to split.
    fn dialects() -> Vec<(&'static str, String, CsvReadOptions)> {
        let named = |d: u8, comma: bool| CsvReadOptions {
            delimiter: Some(d),
            decimal_comma: Some(comma),
        };
        vec![
            (
                "plain",
                format!(
                    "time [s],force [N],acceleration [m/s^2]\n{}",
                    rows(",", false, "\n")
                ),
                named(b',', false),
            ),
            (
                "quoted headers",
                format!(
                    "\"time [s]\",\"force [N]\",\"acceleration [m/s^2]\"\n{}",
                    rows(",", false, "\n")
                ),
                named(b',', false),
            ),
            (
                "quoted decimal commas, comma-separated",
                format!(
                    "time [s],force [N],acceleration [m/s^2]\n{}",
                    rows("\",\"", true, "\"\n")
                        .replace('\n', "\n\"")
                        .trim_end_matches('"')
                )
                .replacen("]\n", "]\n\"", 1),
                named(b',', true),
            ),
            (
                "semicolon, decimal comma",
                format!(
                    "time [s];force [N];acceleration [m/s^2]\n{}",
                    rows(";", true, "\n")
                ),
                named(b';', true),
            ),
            (
                "semicolon, decimal point",
                format!(
                    "time [s];force [N];acceleration [m/s^2]\n{}",
                    rows(";", false, "\n")
                ),
                named(b';', false),
            ),
            (
                "tab, decimal comma",
                format!(
                    "time [s]\tforce [N]\tacceleration [m/s^2]\n{}",
                    rows("\t", true, "\n")
                ),
                named(b'\t', true),
            ),
            (
                "tab, decimal point",
                format!(
                    "time [s]\tforce [N]\tacceleration [m/s^2]\n{}",
                    rows("\t", false, "\n")
                ),
                named(b'\t', false),
            ),
            (
                "comments everywhere",
                format!(
                    "# exported by a scope\n\n# channel 1: force\ntime [s],force [N],acceleration [m/s^2]\n# data\n{}\n# end\n",
                    rows(",", false, "\n")
                ),
                named(b',', false),
            ),
            (
                "CRLF, BOM, quoted, semicolon, decimal comma, trailing separator, empty rows",
                format!(
                    "\u{feff}\"time [s]\";\"force [N]\";\"acceleration [m/s^2]\";\r\n{};;;\r\n;;;\r\n",
                    rows(";", true, ";\r\n")
                ),
                named(b';', true),
            ),
            (
                "spreadsheet sep= line",
                format!(
                    "sep=;\r\ntime [s];force [N];acceleration, lab [m/s^2]\r\n{}",
                    rows(";", true, "\r\n")
                ),
                named(b';', true),
            ),
        ]
    }

    #[test]
    fn each_dialect_reads_the_same_trace_detected_or_named() {
        let mut expected = dialect_reference();
        for (what, text, named) in dialects() {
            if what == "spreadsheet sep= line" {
                expected.channels[1].name = "acceleration, lab".into();
            }
            let detected = parse_csv(&text).unwrap_or_else(|e| panic!("{what}: {e:?}\n{text}"));
            same_trace(&detected, &expected, what);
            let given = parse_csv_with(&text, &named).unwrap_or_else(|e| panic!("{what}: {e:?}"));
            same_trace(&given, &detected, what);
        }
    }

    #[test]
    fn ambiguous_dialects_are_refused_with_the_line() {
        // Unquoted decimal commas in a comma-separated file.
        match kind("# x\ntime [s],force [N]\n0,25,1,5\n0,5,2\n") {
            (3, CsvErrorKind::AmbiguousDelimiter { problem }) => {
                assert!(problem.contains("decimal commas"), "{problem}")
            }
            other => panic!("{other:?}"),
        }
        // Named, the same file is plainly ragged.
        let comma = CsvReadOptions {
            delimiter: Some(b','),
            ..CsvReadOptions::default()
        };
        assert!(matches!(
            parse_csv_with("time [s],force [N]\n0,25,1,5\n", &comma),
            Err((
                2,
                CsvErrorKind::Ragged {
                    expected: 2,
                    got: 4
                }
            ))
        ));
        // ';' and ',' both split header and first row alike.
        match kind("time [s];force [N],x [m]\n0;1,2\n1;2,3\n") {
            (1, CsvErrorKind::AmbiguousDelimiter { problem }) => {
                assert!(problem.contains("';' (1x) and ',' (1x)"), "{problem}")
            }
            other => panic!("{other:?}"),
        }
        // Two decimal marks in one file: the line that decided is named.
        match kind("time [s];f [N]\n0;1,5\n0,1;2.5\n") {
            (
                3,
                CsvErrorKind::DecimalMark {
                    column,
                    text,
                    problem,
                },
            ) => {
                assert_eq!((column.as_str(), text.as_str()), ("f", "2.5"));
                assert!(problem.contains("line 2 ('1,5')"), "{problem}");
            }
            other => panic!("{other:?}"),
        }
        assert!(matches!(
            kind("time [s];f [N]\n0;1.234,5\n0,1;2\n"),
            (2, CsvErrorKind::DecimalMark { .. })
        ));
        // A mark that contradicts the one given.
        let comma_mark = CsvReadOptions {
            decimal_comma: Some(true),
            ..CsvReadOptions::default()
        };
        assert!(matches!(
            parse_csv_with("time [s];f [N]\n0;1\n0.1;2\n", &comma_mark),
            Err((3, CsvErrorKind::DecimalMark { .. }))
        ));
        let point_mark = CsvReadOptions {
            decimal_comma: Some(false),
            ..CsvReadOptions::default()
        };
        assert!(matches!(
            parse_csv_with("time [s];f [N]\n0;1\n0,1;2\n", &point_mark),
            Err((3, CsvErrorKind::DecimalMark { .. }))
        ));
        assert!(matches!(
            kind("sep=|\ntime [s]|f [N]\n0|1\n"),
            (1, CsvErrorKind::AmbiguousDelimiter { .. })
        ));
        let pipe = CsvReadOptions {
            delimiter: Some(b'|'),
            ..CsvReadOptions::default()
        };
        assert!(matches!(
            parse_csv_with("time [s]|f [N]\n0|1\n", &pipe),
            Err((0, CsvErrorKind::UnsupportedDelimiter { delimiter: '|' }))
        ));
    }

    #[test]
    fn line_numbers_count_every_line_of_the_file() {
        // Comments and blank lines after the header, CRLF, a BOM.
        let text = "\u{feff}# a\r\n\r\ntime [s];f [N]\r\n# b\r\n0;1\r\n\r\n  \r\n0,1;x\r\n";
        match kind(text) {
            (8, CsvErrorKind::NotANumber { column, text }) => {
                assert_eq!((column.as_str(), text.as_str()), ("f", "x"));
            }
            other => panic!("{other:?}"),
        }
        assert!(matches!(
            kind("time [s],f [N]\n0,1\n\"0.1,2\n"),
            (3, CsvErrorKind::Syntax { .. })
        ));
        // Carriage returns alone (old Mac text) make one long line.
        assert!(matches!(
            kind("time [s],f [N]\r0,1\r0.1,2\r"),
            (1, CsvErrorKind::Syntax { .. })
        ));
    }

    #[test]
    fn text_that_is_not_utf8_is_refused_with_its_line() {
        let dir = scratch("latin1");
        let path = dir.join("latin1.csv");
        // 0xB5 is the micro sign in Latin-1.
        std::fs::write(&path, b"time [s],x [m]\n0,1\n1,2 \xb5m\n").expect("write");
        let err = read_csv(&path).expect_err("latin-1");
        assert!(
            matches!(
                err,
                SignalsError::Csv {
                    line: 3,
                    kind: CsvErrorKind::NotUtf8 { byte: 0xB5 },
                    ..
                }
            ),
            "{err}"
        );
        std::fs::remove_dir_all(dir).ok();
    }

    #[test]
    fn delimiter_names_from_the_command_line() {
        assert_eq!(parse_delimiter(","), Ok(b','));
        assert_eq!(parse_delimiter(";"), Ok(b';'));
        for tab in ["\t", "\\t", "tab"] {
            assert_eq!(parse_delimiter(tab), Ok(b'\t'));
        }
        assert!(
            parse_delimiter("|")
                .unwrap_err()
                .to_string()
                .contains("',', ';' or tab")
        );
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
