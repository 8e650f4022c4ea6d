//! vlab's CSV text rewritten as a spreadsheet in a given locale exports it.
//! Included by path (`#[path = "support/spreadsheet.rs"]`) from the tests that
//! need it; also the documented step that made
//! `signals/reference/thesis-40Hz-G20/trace-semicolon.csv`.

/// `vlab_csv` (vlab's own CSV text) as a spreadsheet export: `#` comment
/// lines dropped (a spreadsheet does not keep vlab's metadata), header cells
/// in double quotes, `sep` between cells, `.` replaced by `,` in the numbers
/// when `decimal_comma`, CRLF line ends. The digits are kept, so the numbers
/// read back to the same `f64` values.
pub fn export(vlab_csv: &str, sep: &str, decimal_comma: bool) -> String {
    let mut out = String::new();
    for line in vlab_csv.lines().filter(|l| !l.starts_with('#')) {
        let cells: Vec<String> = if line.starts_with("time") {
            line.split(',').map(|c| format!("\"{c}\"")).collect()
        } else if decimal_comma {
            line.split(',').map(|c| c.replace('.', ",")).collect()
        } else {
            line.split(',').map(str::to_string).collect()
        };
        out.push_str(&cells.join(sep));
        out.push_str("\r\n");
    }
    out
}
