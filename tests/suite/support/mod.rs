//! Helpers some of the suite's files share beyond `common`.

pub mod ci_counts;
pub mod devtools;
pub mod fingerprint;
pub mod prolate;
pub mod spreadsheet;
