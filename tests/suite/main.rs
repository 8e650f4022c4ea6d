//! vlab's integration tests, one test binary: each file of this folder is a
//! module, as each was a binary of its own before. One binary links the
//! library once instead of some fifty times, and its harness runs every test
//! on both cores at once, where cargo ran the binaries one after another
//! (docs/performance.md, the CI rows). Run one file's tests with
//! `cargo test --test suite cli_shake::`, an ignored long one with
//! `cargo test --release --test suite -- --ignored coverage::`.
//!
//! `tests/step_allocations.rs` stays a binary of its own: it counts every
//! allocation of its process, which other tests running beside it would
//! make.

mod common;
mod support;

mod analyze_checks;
mod browser_lab;
mod checks_before_work;
mod cli_accuracy;
mod cli_bench;
mod cli_cache;
mod cli_determinism;
mod cli_drop;
mod cli_errors;
mod cli_impact;
mod cli_measure;
mod cli_replay;
mod cli_shake;
mod cli_sweep;
mod clump_physics;
mod collision_steps;
mod contact_physics;
mod coverage;
mod dem_physics;
mod docs;
mod drop_physics;
mod extreme_scenes;
mod figures;
mod host_cli;
mod isa_determinism;
mod lab_files;
mod lammps_export;
mod layering;
mod map_model_coverage;
mod maps_thesis;
mod measurement;
mod measurement_chain;
mod modal_fit;
mod phase_heuristic;
mod reference_records;
mod rig_channels;
mod settling;
mod shapes_scene;
mod shear_box;
mod signals_roundtrip;
mod slurm_script;
mod steady_thesis;
mod team_wake_model;
mod thread_determinism;
