//! The tests of what lies beyond Rust on the Python side, one test binary
//! (as tests/suite/ is for vlab itself): the package's pytest run and the
//! teaching notebooks, side by side on both cores.

#[path = "../../../tests/suite/support/ci_counts.rs"]
mod ci_counts;
mod common;
mod notebooks;
mod package;
