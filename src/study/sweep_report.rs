//! What a sweep says, in one value: its rows, each condition's summary over
//! the seeds and where each series peaks (what `vlab sweep --json` prints
//! and Python's `Sweep.summary` holds), and the file's columns cell by cell
//! as sweep.csv writes them (Python's `Sweep.columns`).

use serde::Serialize;

use super::sweep::{COLUMNS, ConditionSummary, SweepFile, SweepRow, row_record, summarise};
use super::sweep_peak::{SeriesPeak, series_peaks};

/// A sweep's report ([`SweepReport::json`] is its text).
#[derive(Debug, Clone, Serialize)]
pub struct SweepReport<'a> {
    /// Each condition's figures over its seeds, in canonical order.
    pub by_condition: Vec<ConditionSummary>,
    /// Where each series' DEM efficiency peaks against Γ.
    pub peaks: Vec<SeriesPeak>,
    /// Every row of the file.
    pub rows: &'a [SweepRow],
    /// The slice of the conditions the file holds (`1/1`: all).
    pub shard: String,
    /// The sweep's identity (its lists of conditions).
    pub sweep_id: &'a str,
}

impl SweepReport<'_> {
    /// The report as `vlab sweep --json` prints it: indented, the keys of
    /// every object sorted by name (as a JSON value keeps them), whatever
    /// order the types declare their fields in.
    pub fn json(&self) -> serde_json::Result<String> {
        serde_json::to_string_pretty(&serde_json::to_value(self)?)
    }
}

impl SweepFile {
    /// The file's report: its rows, each condition's summary and the peaks.
    pub fn report(&self) -> SweepReport<'_> {
        SweepReport {
            by_condition: summarise(self),
            peaks: series_peaks(self),
            rows: &self.rows,
            shard: self.header.shard.to_string(),
            sweep_id: &self.header.sweep_id,
        }
    }

    /// The file's columns, each named as in its header row and holding its
    /// cells as the file writes them (numbers in the shortest text that
    /// reads back to the same bits; `NaN` where a row has none).
    pub fn columns(&self) -> Vec<(&'static str, Vec<String>)> {
        let records: Vec<Vec<String>> = self.rows.iter().map(row_record).collect();
        COLUMNS
            .iter()
            .enumerate()
            .map(|(k, name)| (*name, records.iter().map(|r| r[k].clone()).collect()))
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    fn reference() -> SweepFile {
        let path =
            Path::new(env!("CARGO_MANIFEST_DIR")).join("signals/reference/sweep-steady/sweep.csv");
        SweepFile::read(&path).expect("the reference sweep reads")
    }

    #[test]
    fn columns_read_back_to_the_rows_bits() {
        let file = reference();
        let columns = file.columns();
        assert_eq!(columns.len(), COLUMNS.len());
        let column = |name: &str| {
            &columns
                .iter()
                .find(|(n, _)| *n == name)
                .expect("a column of that name")
                .1
        };
        for (k, row) in file.rows.iter().enumerate() {
            let cell: f64 = column("efficiency")[k].parse().expect("a number");
            assert_eq!(cell.to_bits(), row.efficiency.to_bits(), "row {k}");
            let gamma: f64 = column("gamma")[k].parse().expect("a number");
            assert_eq!(gamma.to_bits(), row.condition.gamma.to_bits(), "row {k}");
            assert_eq!(column("status")[k], row.status.as_str());
        }
    }

    /// Every object's keys in the text, in order (a key is a string
    /// followed by a colon).
    fn keys_sorted_within_every_object(text: &str) -> bool {
        let mut stack: Vec<Vec<String>> = vec![Vec::new()];
        for line in text.lines().map(str::trim) {
            if let Some((key, _)) = line.strip_prefix('"').and_then(|l| l.split_once("\":")) {
                stack.last_mut().expect("an object").push(key.to_string());
            }
            if line.ends_with('{') {
                stack.push(Vec::new());
            }
            if line.starts_with('}') {
                let keys = stack.pop().expect("an open object");
                if keys.windows(2).any(|w| w[0] > w[1]) {
                    return false;
                }
            }
        }
        true
    }

    #[test]
    fn the_report_sorts_every_objects_keys_as_the_command_always_printed_them() {
        let file = reference();
        let text = file.report().json().expect("serialises");
        assert!(keys_sorted_within_every_object(&text), "{text}");
        // As the types declare them, the keys are not sorted (so the check
        // above can fail).
        let declared = serde_json::to_string_pretty(&file.report()).expect("serialises");
        assert!(!keys_sorted_within_every_object(&declared));
        let value: serde_json::Value = serde_json::from_str(&text).expect("reads back");
        assert_eq!(
            value["rows"].as_array().map(Vec::len),
            Some(file.rows.len())
        );
    }
}
