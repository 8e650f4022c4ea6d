//! `vlab shake` end to end on the thesis scene.

#![cfg(all(feature = "cli", feature = "plot"))]

use crate::common;

use common::{Scratch, run_summary};
use vlab::signals::read_csv;

/// The thesis scene at 40 Hz, Gamma 20: the energy ledger closes within 1e-3 of
/// the dissipated energy, the summary carries what the issue lists, and the
/// 40 kHz record agrees with the ledger on the work the enclosure did.
#[test]
fn thesis_scene_ledger_closes_and_record_agrees() {
    let dir = Scratch::new("shake-thesis");
    let (o, s) = run_summary(
        &dir,
        &[
            "--quiet", "shake", "--freq", "40", "--gamma", "20", "--beds", "2",
        ],
        "run",
    );
    for key in [
        "freq_hz",
        "gamma",
        "orientation",
        "n_particles",
        "dt_s",
        "steps",
        "wall_time_s",
        "particle_steps_per_s",
    ] {
        assert!(s.get(key).is_some(), "summary.json lacks {key}");
    }
    let dem = &s["dem"];
    for key in [
        "energy_per_cycle_j",
        "e_max_j",
        "efficiency",
        "integrator_rel",
    ] {
        assert!(dem[key].is_f64(), "dem.{key} missing");
    }
    for key in ["pp_normal", "pp_tangential", "pw_normal", "pw_tangential"] {
        assert!(dem["dissipated_j"][key].as_f64().expect(key) > 0.0);
    }
    // The energy check: the integration's own energy error is small (the
    // books' residual is an identity, asserted in debug builds, not shown).
    assert!(dem.get("ledger_residual_rel").is_none());
    let integrator = dem["integrator_rel"].as_f64().expect("integrator");
    assert!(
        integrator.abs() < 1e-3,
        "integration error {integrator:.2e} of the dissipated energy"
    );
    assert_eq!(s["n_particles"], 358);
    // Without --noise-seed the rig's noise is seeded by the bed's seed.
    assert_eq!(s["noise_seed"], s["seed"]);
    // The default drive runs until steady, at the step that resolves every
    // collision: the steps are the cycles driven at that step (to one step a
    // cycle), and the window says it is steady.
    let cycles = dem["cycles"].as_f64().expect("cycles");
    let dt = s["dt_s"].as_f64().expect("dt");
    let steps = s["steps"].as_f64().expect("steps");
    assert!(
        (steps - cycles / (40.0 * dt)).abs() <= cycles,
        "{steps} steps for {cycles} cycles at dt {dt:e} s"
    );
    assert_eq!(dem["steadiness"]["reached"], true, "{}", dem["steadiness"]);
    // Steps per collision: the fastest collision counted, and what the
    // time-step rule planned for it, both at least 20 (24.2 planned, 25
    // counted, measured on the 2-core VM), and the fewest counted over every
    // collision (a glancing contact: 1); the fewest planned is at most the
    // fastest collision's (to its f32 rounding); the summary prints each as
    // summary.json has it.
    let fastest = dem["fastest_collision_counted_steps"]
        .as_u64()
        .expect("counted");
    let planned_fastest = dem["fastest_collision_planned_steps"]
        .as_f64()
        .expect("planned");
    let fewest = dem["fewest_counted_steps_per_contact"]
        .as_u64()
        .expect("fewest");
    let planned = dem["planned_steps_per_contact"].as_f64().expect("planned");
    assert!(
        fastest >= 20 && planned >= 20.0,
        "{fastest} counted, {planned} planned"
    );
    assert!(fewest >= 1 && fewest <= fastest && planned <= planned_fastest * (1.0 + 1e-6));
    let stdout = String::from_utf8_lossy(&o.stdout);
    let line = format!(
        "steps per collision           fastest collision counted {fastest} (the time-step rule planned {planned_fastest:.1}); fewest counted {fewest} (a glancing or interrupted contact); fewest planned {planned:.1}"
    );
    assert!(stdout.contains(&line), "{stdout}\nlacks\n{line}");
    // The first bed's +- is its window's alone (below 1 % of the mean, the
    // default rule), and its efficiency's the same relative error.
    let mean = dem["energy_per_cycle_j"].as_f64().expect("mean");
    let window = dem["energy_per_cycle_stderr_j"].as_f64().expect("window");
    assert!(
        window > 0.0 && window < 0.01 * mean,
        "window {window} of {mean}"
    );
    let eta = dem["efficiency_stderr"].as_f64().expect("efficiency error");
    let e_max = dem["e_max_j"].as_f64().expect("E_max");
    assert!(
        (eta - window / e_max).abs() < 1e-12,
        "{eta} vs {window} / {e_max}"
    );
    // The ensemble of two beds: the first is this one (seed 1), the second
    // seed 1 000 001; its figure is their mean, its +- their spread over
    // sqrt(2) times Student's 68 % quantile on 1 degree of freedom (1.8125
    // by the expansion vlab uses), and beds.csv lists both.
    let e = &s["ensemble"];
    assert_eq!(e["beds"], 2, "{e}");
    let rows = e["rows"].as_array().expect("rows");
    assert_eq!(rows[0]["seed"], 1);
    assert_eq!(rows[1]["seed"], 1_000_001);
    assert_eq!(rows[0]["dem_efficiency"], dem["efficiency"]);
    let (a, b) = (
        rows[0]["dem_efficiency"].as_f64().expect("bed 1"),
        rows[1]["dem_efficiency"].as_f64().expect("bed 2"),
    );
    let fig = &e["dem_efficiency"];
    assert!((fig["mean"].as_f64().expect("mean") - 0.5 * (a + b)).abs() < 1e-12);
    let want = (a - b).abs() / 2f64.sqrt() / 2f64.sqrt() * 1.8125;
    assert!(
        (fig["stderr"].as_f64().expect("stderr") - want).abs() < 1e-12,
        "{fig} against {want}"
    );
    let csv = std::fs::read_to_string(dir.path("run/beds.csv")).expect("beds.csv");
    assert_eq!(csv.lines().count(), 3, "{csv}");
    // The allowance for a longer drive: 21 % of the mean over the root of
    // the window's cycles, beside the +-, not in it.
    let mean = fig["mean"].as_f64().expect("mean");
    let allowance = fig["longer_drive"].as_f64().expect("longer_drive");
    let window = s["steady_cycles"].as_f64().expect("steady cycles");
    assert!(
        (allowance - 0.21 / window.sqrt() * mean).abs() < 1e-12 * mean,
        "{allowance} of {mean} over {window} cycles"
    );
    assert!(stdout.contains("longer drive"), "{stdout}");
    // cycles.csv: each bed's energy per cycle from the drive's start, their
    // mean, and the window; over the window the first bed's column averages
    // to its figure and the mean column to the ensemble's (within 1e-4: a
    // figure is the window's energy over its length in time, whose cycles
    // end on steps, 1/20 000 of a period).
    #[cfg(feature = "plot")]
    assert!(dir.path("run/cycles.svg").is_file() && dir.path("run/cycles.png").is_file());
    let cycles = std::fs::read_to_string(dir.path("run/cycles.csv")).expect("cycles.csv");
    let mut lines = cycles.lines();
    assert_eq!(
        lines.next(),
        Some("cycle,in_window,mean_dissipated_j,bed_1_dissipated_j,bed_2_dissipated_j")
    );
    let rows: Vec<Vec<f64>> = lines
        .map(|l| l.split(',').map(|v| v.parse().expect("number")).collect())
        .collect();
    assert_eq!(rows.len() as u64, s["cycles"].as_u64().expect("cycles"));
    let window: Vec<&Vec<f64>> = rows.iter().filter(|r| r[1] == 1.0).collect();
    assert_eq!(
        window.len() as u64,
        s["steady_cycles"].as_u64().expect("steady cycles")
    );
    let avg = |col: usize| window.iter().map(|r| r[col]).sum::<f64>() / window.len() as f64;
    let bed1 = dem["energy_per_cycle_j"].as_f64().expect("energy");
    let both = e["dem_energy_per_cycle_j"]["mean"].as_f64().expect("mean");
    assert!((avg(3) - bed1).abs() < 1e-4 * bed1, "{} vs {bed1}", avg(3));
    assert!((avg(2) - both).abs() < 1e-4 * both, "{} vs {both}", avg(2));
    assert!(
        stdout.contains("ensemble of 2 beds")
            && stdout.contains("Student's t on 1 degree of freedom"),
        "{stdout}"
    );

    // The steady work of the enclosure, from the record: ∫ F_walls→particles · v dt,
    // with F_walls→particles = -F_particles→enclosure.
    let trace = read_csv(&dir.path("run/kinematics.csv")).expect("kinematics.csv parses");
    assert_eq!(trace.sample_rate_hz, 40_000.0);
    let t0 = s["steady_start_s"].as_f64().expect("steady start");
    let v = &trace
        .channel("enclosure_velocity")
        .expect("velocity")
        .samples;
    let f = &trace
        .channel("particle_force_axial")
        .expect("force")
        .samples;
    let ts = 1.0 / trace.sample_rate_hz;
    let work: f64 = (0..trace.len())
        .filter(|&i| trace.time_s(i) > t0 + 0.5 * ts)
        .map(|i| -f[i] * v[i] * ts)
        .sum();
    let ledger_work = dem["steady_ledger"]["work_in_j"].as_f64().expect("work");
    let rel = (work - ledger_work).abs() / ledger_work;
    assert!(
        rel < 0.01,
        "record work {work:.5} J vs ledger {ledger_work:.5} J"
    );

    // The record replayed through the same rig (`vlab replay`, issue 12),
    // calibrated and measured by the same functions, measures what the shake
    // measured, within 0.1 % (measured on the 2-core VM at fc23db4: -0.048 %,
    // of which -0.041 % is the 40 kHz rows' loss of the DEM's work, the rest
    // the two chains' errors, -0.021 % vs the record and -0.014 % vs the DEM).
    let (_, r) = run_summary(&dir, &["replay", "run/kinematics.csv"], "replay");
    let shake = s["measured"]["power_w"].as_f64().expect("shake power");
    let replay = r["measured"]["power_w"].as_f64().expect("replay power");
    assert!(
        (replay / shake - 1.0).abs() < 1e-3,
        "replay {replay} W vs shake {shake} W"
    );
}

/// The energy books at the default time step and at half of it (issue 9,
/// item 4), on a short drive of the thesis bed at 40 Hz, Γ 20 (3 cycles, the
/// last 2 the window; the ideal rig, since the books not the measurement are
/// under test). The integration's own energy error, the energy check, falls
/// as dt² for velocity Verlet: by a factor in [3, 5] when the step halves
/// (measured 5.79e-4 to 1.40e-4, x4.1); a first-order integrator, or a
/// dissipation booked in the wrong channel, would not.
#[test]
fn the_integration_error_is_second_order_in_dt() {
    let dir = Scratch::new("shake-ledger-dt");
    let run = |extra: &[&str], out: &str| -> serde_json::Value {
        let mut args = vec![
            "--quiet",
            "shake",
            "--beds",
            "1",
            "--rig",
            "ideal",
            "--cycles",
            "3",
            "--steady-cycles",
            "2",
        ];
        args.extend_from_slice(extra);
        run_summary(&dir, &args, out).1
    };
    let full = run(&[], "dt");
    let dt = full["dt_s"].as_f64().expect("dt_s");
    let half_dt = format!("{:e}", 0.5 * dt);
    let half = run(&["--dt-s", &half_dt], "half-dt");
    assert_eq!(half["dt_s"].as_f64(), Some(0.5 * dt), "--dt-s {half_dt}");
    let figure = |s: &serde_json::Value, key: &str| {
        s["dem"][key]
            .as_f64()
            .unwrap_or_else(|| panic!("dem.{key} missing"))
    };
    let (e1, e2) = (
        figure(&full, "integrator_rel"),
        figure(&half, "integrator_rel"),
    );
    let ratio = e1 / e2;
    eprintln!(
        "dt {dt:.4e} s: integration error {e1:.2e}; dt/2: integration error {e2:.2e}; ratio {ratio:.2}"
    );
    assert!(
        (3.0..=5.0).contains(&ratio),
        "integration error {e1:.2e} at dt, {e2:.2e} at dt/2: ratio {ratio:.2}, not second order"
    );
}

/// `--noise-seed` seeds the rig's noise and nothing else: the same bed
/// (`--seed 3`) measured twice with noise seeds 5 and 6 has the same DEM
/// truth, byte for byte, and a different record; the summary and the record
/// say which noise seed made them. (Thesis rig, 3 cycles, the last 2 recorded.)
/// Two cycles are too few for a stated error: the summary holds none and
/// the printout says why.
#[test]
fn the_noise_seed_changes_the_record_not_the_bed() {
    let dir = Scratch::new("shake-noise-seed");
    let run = |noise_seed: &str, out: &str| -> (std::process::Output, serde_json::Value) {
        let args = [
            "--quiet",
            "shake",
            "--beds",
            "1",
            "--cycles",
            "3",
            "--steady-cycles",
            "2",
            "--seed",
            "3",
            "--noise-seed",
            noise_seed,
        ];
        run_summary(&dir, &args, out)
    };
    let ((oa, a), (_, b)) = (run("5", "a"), run("6", "b"));
    for key in ["energy_per_cycle_stderr_j", "efficiency_stderr"] {
        assert!(a["dem"][key].is_null(), "dem.{key}: {}", a["dem"][key]);
        assert!(a["measured"][key].is_null(), "measured.{key}");
    }
    assert!(a["dem"]["steadiness"]["stderr_rel"].is_null());
    let printed = String::from_utf8_lossy(&oa.stdout);
    assert!(
        printed.contains("J (+- not known: fewer than 16 steady cycles)"),
        "{printed}"
    );
    for (s, noise_seed) in [(&a, 5), (&b, 6)] {
        assert_eq!(s["seed"], 3);
        assert_eq!(s["noise_seed"], noise_seed);
    }
    let bytes = |p: &str| std::fs::read(dir.path(p)).unwrap_or_else(|e| panic!("{p}: {e}"));
    assert!(
        bytes("a/kinematics.csv") == bytes("b/kinematics.csv"),
        "the DEM truth depends on the noise seed"
    );
    let record = |p: &str| read_csv(&dir.path(p)).unwrap_or_else(|e| panic!("{p}: {e}"));
    let (ra, rb) = (record("a/trace.csv"), record("b/trace.csv"));
    assert_eq!(ra.metadata.extra["rig_noise_seed"], 5);
    assert_eq!(rb.metadata.extra["rig_noise_seed"], 6);
    let force = |t: &vlab::signals::Trace| {
        t.channel(vlab::rig::FORCE_CHANNEL)
            .expect("force channel")
            .samples
            .clone()
    };
    let (fa, fb) = (force(&ra), force(&rb));
    assert_eq!(fa.len(), fb.len());
    let differ = fa.iter().zip(&fb).filter(|(x, y)| x != y).count();
    assert!(
        differ > fa.len() / 2,
        "only {differ} of {} force samples differ between noise seeds 5 and 6",
        fa.len()
    );
}
