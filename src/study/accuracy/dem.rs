//! Study (a): the DEM's time step, cycles and seeds (the module docs of
//! [`super`]): each figure's rows, the time step's findings and which error
//! dominates.

use super::*;

/// Study (a) from the runs.
///
/// Over 80 lines: study (a)'s figures filled field by field from the runs, each
/// from the ones before.
pub(super) fn dem_study(
    scene: &Scene,
    plan: &AccuracyPlan,
    seed_runs: &[&DriveRun],
    dt_runs: &[&DriveRun],
    settle_wall_s: &[f64],
    rayleigh: f64,
    default_dt: f64,
) -> (Vec<AccuracyRow>, DemAccuracy) {
    let t = plan.transient_cycles as usize;
    let s = plan.seed_steady_cycles as usize;
    // run_accuracy refused an invalid drive before any run.
    let e_max = scene
        .drive(plan.freq_hz, plan.gamma)
        .map_or(f64::NAN, |d| d.e_max_j(scene.particle_mass_kg()));
    let mut rows = Vec::new();

    // Seeds and the pooled reference.
    let series: Vec<Vec<f64>> = seed_runs.iter().map(|r| r.cycle_energies(t)).collect();
    let seed_stats: Vec<MeanStderr> = series.iter().map(|x| mean_stderr(x)).collect();
    let means: Vec<f64> = seed_stats.iter().map(|m| m.mean).collect();
    let pooled = means.iter().sum::<f64>() / means.len() as f64;
    let pooled_stderr = (seed_stats
        .iter()
        .map(|m| m.stderr_or_nan().powi(2))
        .sum::<f64>())
    .sqrt()
        / seed_stats.len() as f64;
    let run_wall = |i: usize, cycles: usize| -> f64 {
        let r = seed_runs[i];
        settle_wall_s[r.job.seed_index] + r.cycle_wall_s.get(cycles).copied().unwrap_or(r.wall_s)
    };
    for (i, m) in seed_stats.iter().enumerate() {
        let seed = plan.seeds[seed_runs[i].job.seed_index] as f64;
        rows.extend(seed_rows(seed, m, pooled, e_max, run_wall(i, t + s)));
    }
    let seed_spread_rel = sample_sd(&means) / pooled;
    let seed_stderr_rms_rel = (seed_stats
        .iter()
        .map(|m| (m.stderr_or_nan() / pooled).powi(2))
        .sum::<f64>()
        / seed_stats.len() as f64)
        .sqrt();

    rows.extend(cycle_rows(plan, &series, &seed_stats, pooled, &run_wall));
    let pooled_series: Vec<f64> = series.iter().flatten().copied().collect();
    let spread = sample_sd(&pooled_series) / pooled;
    let lag1 = mean_stderr(&series[0]).lag1;
    let cycles_for_1pct = (spread / 0.01).powi(2) * (1.0 + lag1) / (1.0 - lag1);

    let default_x = default_dt / rayleigh;
    let (dt_rows, step) =
        time_step_study(plan, seed_runs, dt_runs, settle_wall_s, default_x, e_max);
    rows.extend(dt_rows);
    let dominant = dominant_error(
        plan,
        &step,
        default_x,
        seed_stats[0].relative().unwrap_or(f64::NAN),
        seed_spread_rel,
    );
    let dem = DemAccuracy {
        rayleigh_step_s: rayleigh,
        default_dt_s: default_dt,
        default_dt_over_rayleigh: default_x,
        reference_dt_over_rayleigh: step.ref_x,
        default_dt_error_rel: step.default_err,
        default_dt_error_stderr_rel: step.default_se,
        default_dt_integrator_rel: step.default_integrator,
        integrator_order: step.integrator_order,
        failed: step.failed,
        seed_energy_per_cycle_j: means,
        pooled_energy_per_cycle_j: pooled,
        pooled_stderr_rel: pooled_stderr / pooled,
        pooled_efficiency: pooled / e_max,
        seed_spread_rel,
        seed_stderr_rms_rel,
        cycles_for_1pct,
        dominant,
    };
    (rows, dem)
}

/// Study (a)'s rows of one seed: its mean energy per cycle and efficiency
/// against the seeds' `pooled` mean (J), `e_max` (J) scaling energies to
/// efficiencies, `wall` its wall time (s).
pub(super) fn seed_rows(
    seed: f64,
    m: &MeanStderr,
    pooled: f64,
    e_max: f64,
    wall: f64,
) -> Vec<AccuracyRow> {
    [("energy_per_cycle_j", 1.0), ("efficiency", 1.0 / e_max)]
        .into_iter()
        .map(|(quantity, scale)| {
            AccuracyRow::new(
                "dem",
                "seed",
                seed,
                quantity,
                m.mean * scale,
                pooled * scale,
                m.stderr_or_nan() / pooled,
                wall,
            )
        })
        .collect()
}

/// Study (a)'s rows of steady cycles: for each count of `plan`, the energy
/// per cycle over that many cycles (of the first seed, or whole seeds'
/// means) against the `pooled` mean, and the rms spread of disjoint blocks
/// of `series` that long; `run_wall(i, cycles)` is seed run `i`'s wall time
/// to `cycles` cycles (s).
pub(super) fn cycle_rows(
    plan: &AccuracyPlan,
    series: &[Vec<f64>],
    seed_stats: &[MeanStderr],
    pooled: f64,
    run_wall: &dyn Fn(usize, usize) -> f64,
) -> Vec<AccuracyRow> {
    let t = plan.transient_cycles as usize;
    let s = plan.seed_steady_cycles as usize;
    let mut rows = Vec::new();
    for &n in &plan.cycle_counts {
        let n = n as usize;
        let (estimate, stderr, wall) = if n <= s {
            let m = mean_stderr(&series[0][..n]);
            (m.mean, m.stderr_or_nan(), run_wall(0, t + n))
        } else {
            let k = n / s;
            let m = seed_stats[..k].iter().map(|m| m.mean).sum::<f64>() / k as f64;
            let se = seed_stats[..k]
                .iter()
                .map(|m| m.stderr_or_nan().powi(2))
                .sum::<f64>()
                .sqrt()
                / k as f64;
            (m, se, (0..k).map(|i| run_wall(i, t + s)).sum())
        };
        let mut row = AccuracyRow::new(
            "dem",
            "steady_cycles",
            n as f64,
            "energy_per_cycle_j",
            estimate,
            pooled,
            stderr / pooled,
            wall,
        );
        if n == s * series.len() {
            row.note = "the reference itself".into();
        }
        rows.push(row);
        let BlockSpread {
            rms_rel: rms,
            blocks,
        } = block_rms_rel(series, n, pooled);
        if blocks >= 2 {
            let mut row = AccuracyRow::new(
                "dem",
                "steady_cycles",
                n as f64,
                "block_rms_rel",
                rms,
                f64::NAN,
                rms / (2.0 * blocks as f64).sqrt(),
                wall,
            );
            row.error_rel = rms;
            row.note = format!("rms deviation of {blocks} disjoint blocks of {n} cycles");
            rows.push(row);
        }
    }
    rows
}

/// One time step of study (a): its energy per cycle over the first
/// `dt_steady_cycles` steady cycles, the integrator's energy error, the
/// fewest steps a collision was planned to take and the fewest counted, the
/// wall time (s), or why the run stopped.
pub(super) struct DtPoint {
    x: f64,
    mean: MeanStderr,
    integrator_rel: f64,
    planned_steps: f64,
    /// NaN when no collision was counted (or the run stopped).
    counted_steps: f64,
    wall: f64,
    error: Option<String>,
}

/// What the time-step study found, at the scene's default step against the
/// finest one that ran (`ref_x`, × Rayleigh).
pub(super) struct TimeStepFindings {
    ref_x: f64,
    default_err: f64,
    default_se: f64,
    default_integrator: f64,
    integrator_order: Option<f64>,
    failed: Vec<String>,
}

/// The point of run `r` at `x` × Rayleigh.
pub(super) fn dt_point(
    plan: &AccuracyPlan,
    settle_wall_s: &[f64],
    x: f64,
    r: &DriveRun,
) -> DtPoint {
    let t = plan.transient_cycles as usize;
    let n_dt = plan.dt_steady_cycles as usize;
    let wall_end = r.cycle_wall_s.get(t + n_dt).copied().unwrap_or(r.wall_s);
    let wall = settle_wall_s[r.job.seed_index] + wall_end;
    match &r.outcome {
        Ok(o) => {
            let snaps = &o.cycle_snapshots;
            let e = energies(&snaps[..=(t + n_dt).min(snaps.len() - 1)], t);
            let b = LedgerBalance::between(&snaps[0], &snaps[(t + n_dt).min(snaps.len() - 1)]);
            DtPoint {
                x,
                mean: mean_stderr(&e),
                integrator_rel: b.integrator_j / b.dissipated_j,
                planned_steps: o.planned_steps_per_contact,
                counted_steps: o
                    .fewest_counted_steps_per_contact
                    .map_or(f64::NAN, f64::from),
                wall,
                error: None,
            }
        }
        Err(e) => DtPoint {
            x,
            mean: MeanStderr {
                mean: f64::NAN,
                ..MeanStderr::default()
            },
            integrator_rel: f64::NAN,
            planned_steps: f64::NAN,
            counted_steps: f64::NAN,
            wall,
            error: Some(e.clone()),
        },
    }
}

/// Study (a)'s time steps: the runs of `dt_runs` and the first seed's run at
/// the default step `default_x` (× Rayleigh), each against the finest step
/// that ran; `e_max` (J) scales energies to efficiencies.
pub(super) fn time_step_study(
    plan: &AccuracyPlan,
    seed_runs: &[&DriveRun],
    dt_runs: &[&DriveRun],
    settle_wall_s: &[f64],
    default_x: f64,
    e_max: f64,
) -> (Vec<AccuracyRow>, TimeStepFindings) {
    let mut points: Vec<DtPoint> = dt_runs
        .iter()
        .filter_map(|r| {
            r.job
                .dt_over_rayleigh
                .map(|x| dt_point(plan, settle_wall_s, x, r))
        })
        .collect();
    points.push(dt_point(plan, settle_wall_s, default_x, seed_runs[0]));
    points.sort_by(|a, b| a.x.total_cmp(&b.x));
    let reference = points.iter().find(|p| p.error.is_none());
    let (ref_x, ref_mean) = reference
        .map(|p| (p.x, p.mean))
        .unwrap_or((f64::NAN, MeanStderr::default()));
    let mut rows = Vec::new();
    let mut failed = Vec::new();
    for p in &points {
        let note = if p.x == default_x {
            format!(
                "the scene's default step (seed {} run, first {} steady cycles)",
                plan.seeds[0], plan.dt_steady_cycles
            )
        } else if p.x == ref_x {
            "the reference (finest step)".into()
        } else {
            String::new()
        };
        if let Some(e) = &p.error {
            failed.push(format!("{} x Rayleigh: {e}", p.x));
        }
        rows.extend(dt_rows(p, ref_mean, e_max, note));
    }
    let at_default = points.iter().find(|p| p.x == default_x);
    let (default_err, default_se, default_integrator) = at_default
        .map(|p| {
            (
                p.mean.mean / ref_mean.mean - 1.0,
                (p.mean.stderr_or_nan().powi(2) + ref_mean.stderr_or_nan().powi(2)).sqrt()
                    / ref_mean.mean,
                p.integrator_rel,
            )
        })
        .unwrap_or((f64::NAN, f64::NAN, f64::NAN));
    let integrator_order = log_log_slope(
        &points
            .iter()
            .filter(|p| p.error.is_none())
            .map(|p| (p.x, p.integrator_rel))
            .collect::<Vec<_>>(),
    );
    let findings = TimeStepFindings {
        ref_x,
        default_err,
        default_se,
        default_integrator,
        integrator_order,
        failed,
    };
    (rows, findings)
}

/// The rows of time-step point `p` against the reference `ref_mean`: energy
/// per cycle and efficiency (with `note`, or why the run stopped), the
/// integrator's error, the fewest steps per contact counted and planned.
pub(super) fn dt_rows(
    p: &DtPoint,
    ref_mean: MeanStderr,
    e_max: f64,
    note: String,
) -> Vec<AccuracyRow> {
    let mut rows = Vec::new();
    let se = if p.error.is_some() {
        f64::NAN
    } else {
        (p.mean.stderr_or_nan().powi(2) + ref_mean.stderr_or_nan().powi(2)).sqrt() / ref_mean.mean
    };
    let note = match &p.error {
        Some(e) => format!("stopped: {e}"),
        None => note,
    };
    for (quantity, scale) in [("energy_per_cycle_j", 1.0), ("efficiency", 1.0 / e_max)] {
        let mut row = AccuracyRow::new(
            "dem",
            "dt_over_rayleigh",
            p.x,
            quantity,
            p.mean.mean * scale,
            ref_mean.mean * scale,
            se,
            p.wall,
        );
        row.note = note.clone();
        rows.push(row);
    }
    let mut row = AccuracyRow::new(
        "dem",
        "dt_over_rayleigh",
        p.x,
        "integrator_rel",
        p.integrator_rel,
        0.0,
        f64::NAN,
        p.wall,
    );
    row.error_rel = p.integrator_rel;
    row.note = "integration energy error / dissipated energy, whole run".into();
    rows.push(row);
    for (quantity, steps, note) in [
        (
            "fewest_counted_steps_per_contact",
            p.counted_steps,
            "fewest steps counted over the collisions that began and ended in the run",
        ),
        (
            "planned_steps_per_contact",
            p.planned_steps,
            "fewest steps a collision was planned to take: Hertz duration (eq. 5.10) at its approach speed / dt",
        ),
    ] {
        let mut row = AccuracyRow::new(
            "dem",
            "dt_over_rayleigh",
            p.x,
            quantity,
            steps,
            f64::NAN,
            f64::NAN,
            p.wall,
        );
        row.error_rel = f64::NAN;
        row.note = note.into();
        rows.push(row);
    }
    rows
}

/// Which error dominates at the default step, in words: the discretisation
/// error of `step` against the relative standard error of one run
/// (`default_stderr`) and the seeds' spread.
pub(super) fn dominant_error(
    plan: &AccuracyPlan,
    step: &TimeStepFindings,
    default_x: f64,
    default_stderr: f64,
    seed_spread_rel: f64,
) -> String {
    let (default_err, default_se) = (step.default_err, step.default_se);
    if default_se.is_nan() {
        // Too few cycles for an error (crate::stats needs 16): no verdict
        // can be drawn from the difference alone.
        return format!(
            "not known: at the default time step the energy per cycle is {:+.2} % off {} x Rayleigh over {} cycles, too few for a standard error of the difference (at least 16), so whether that is discretisation or chance is not known; the seeds' means spread by {:.2} %",
            100.0 * default_err,
            step.ref_x,
            plan.dt_steady_cycles,
            100.0 * seed_spread_rel
        );
    }
    let resolved = default_err.abs() > 2.0 * default_se;
    if !resolved {
        format!(
            "statistics: at the default time step ({default_x:.3} x Rayleigh) the discretisation error of the energy per cycle is not resolved, {:+.2} % +- {:.2} % against {} x Rayleigh over {} cycles (the integrator's own energy error is {:.1e} of the dissipation), while one run of {} steady cycles has a standard error of {:.2} % and the seeds' means spread by {:.2} %",
            100.0 * default_err,
            100.0 * default_se,
            step.ref_x,
            plan.dt_steady_cycles,
            step.default_integrator,
            plan.seed_steady_cycles,
            100.0 * default_stderr,
            100.0 * seed_spread_rel
        )
    } else if default_err.abs() > seed_spread_rel {
        format!(
            "discretisation: at the default time step the energy per cycle is {:+.2} % +- {:.2} % off the finest step, more than the seeds' spread of {:.2} %",
            100.0 * default_err,
            100.0 * default_se,
            100.0 * seed_spread_rel
        )
    } else {
        format!(
            "statistics: the default time step is {:+.2} % +- {:.2} % off the finest step, less than the seeds' spread of {:.2} %",
            100.0 * default_err,
            100.0 * default_se,
            100.0 * seed_spread_rel
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn findings(default_err: f64, default_se: f64) -> TimeStepFindings {
        TimeStepFindings {
            ref_x: 0.025,
            default_err,
            default_se,
            default_integrator: 1e-4,
            integrator_order: Some(2.0),
            failed: Vec::new(),
        }
    }

    #[test]
    fn a_verdict_needs_the_differences_error() {
        let plan = AccuracyPlan::quick(40.0, 20.0);
        // Without its error, a 1 % difference is neither resolved nor not:
        // the verdict says so (it said "not resolved, +1.06 % +- NaN %").
        let unknown = dominant_error(&plan, &findings(0.0106, f64::NAN), 0.1, 0.005, 0.01);
        assert!(unknown.starts_with("not known"), "{unknown}");
        assert!(!unknown.contains("NaN"), "{unknown}");
        let noise = dominant_error(&plan, &findings(0.0106, 0.01), 0.1, 0.005, 0.02);
        assert!(noise.starts_with("statistics"), "{noise}");
        let step = dominant_error(&plan, &findings(0.05, 0.005), 0.1, 0.005, 0.02);
        assert!(step.starts_with("discretisation"), "{step}");
    }
}
