//! Study (b): a single collision against Hertz theory (thesis eq. 5.8,
//! 5.10) and the scene's damped collision against its restitution.

use super::*;

/// Study (b): one collision per resolution.
pub(super) fn impact_study(
    scene: &Scene,
    plan: &AccuracyPlan,
) -> Result<(Vec<AccuracyRow>, ImpactAccuracy), SceneError> {
    let pp = scene.contact.particle_wall;
    let speed = scene.expected_impact_speed_mps(&scene.drive(plan.freq_hz, plan.gamma)?);
    let base = ImpactSetup {
        material: scene.particle_material(),
        radius_m: scene.radius_m(),
        target: Target::Wall(scene.wall_material()),
        speed_mps: speed,
        angle_deg: 0.0,
        spin_rad_s: 0.0,
        restitution: pp.restitution,
        friction: pp.friction,
        mode: scene.contact.restitution_mode,
        dt_s: None,
    };
    let t_c = base.hertz_duration_s();
    let mut rows = Vec::new();
    let mut overlap_pts = Vec::new();
    let mut duration_pts = Vec::new();
    let mut restitution_pts = Vec::new();
    let scene_n = scene.simulation.steps_per_contact;
    let mut at_scene = (f64::NAN, f64::NAN, f64::NAN, f64::NAN);
    let mut best_gap = f64::INFINITY;
    for &n in &plan.steps_per_contact {
        let (e_overlap, e_dur, e_exact, e_rest) = impact_rows(&base, n, t_c / n, &mut rows)?;
        overlap_pts.push((n, e_overlap));
        duration_pts.push((n, e_exact));
        restitution_pts.push((n, e_rest));
        if (n - scene_n).abs() < best_gap {
            best_gap = (n - scene_n).abs();
            at_scene = (e_overlap, e_dur, e_exact, e_rest);
        }
    }
    let order = |pts: &[(f64, f64)]| log_log_slope(pts).map(|s| -s);
    Ok((
        rows,
        ImpactAccuracy {
            speed_mps: speed,
            hertz_duration_s: t_c,
            order_max_overlap: order(&overlap_pts),
            order_duration_exact: order(&duration_pts),
            order_restitution: order(&restitution_pts),
            scene_steps_per_contact: scene_n,
            max_overlap_error_rel: at_scene.0,
            duration_error_rel_eq_5_10: at_scene.1,
            duration_error_rel_exact: at_scene.2,
            restitution_error_rel: at_scene.3,
        },
    ))
}

/// The collision of `base` at `n` steps per contact (time step `dt` s),
/// elastic and with the scene's law, as rows added to `rows`; returns the
/// relative errors of the overlap, the duration against eq. 5.10 and against
/// the exact integral, and of the restitution.
pub(super) fn impact_rows(
    base: &ImpactSetup,
    n: f64,
    dt: f64,
    rows: &mut Vec<AccuracyRow>,
) -> Result<(f64, f64, f64, f64), SceneError> {
    let speed = base.speed_mps;
    let t0 = Stopwatch::start();
    let elastic = run_impact(&ImpactSetup {
        restitution: 1.0,
        friction: 0.0,
        dt_s: Some(dt),
        ..*base
    })?;
    let wall_elastic = t0.elapsed().as_secs_f64();
    let t1 = Stopwatch::start();
    let damped = run_impact(&ImpactSetup {
        dt_s: Some(dt),
        ..*base
    })?;
    let wall_damped = t1.elapsed().as_secs_f64();
    let exact_duration = 2.0 * HERTZ_DURATION_INTEGRAL * elastic.hertz_max_overlap_m / speed;
    let mut push = |quantity, estimate, reference, wall, note: &str| {
        let mut row = AccuracyRow::new(
            "impact",
            "steps_per_contact",
            n,
            quantity,
            estimate,
            reference,
            f64::NAN,
            wall,
        );
        row.note = note.into();
        let e = row.error_rel;
        rows.push(row);
        e
    };
    let e_overlap = push(
        "max_overlap_m",
        elastic.max_overlap_m,
        elastic.hertz_max_overlap_m,
        wall_elastic,
        "e = 1 against Terzioglu 2023, eq. 5.8",
    );
    let e_dur = push(
        "contact_duration_s",
        elastic.contact_duration_s,
        elastic.hertz_duration_s,
        wall_elastic,
        "e = 1 against twice Terzioglu 2023, eq. 5.10",
    );
    let e_exact = push(
        "contact_duration_exact_s",
        elastic.contact_duration_s,
        exact_duration,
        wall_elastic,
        "e = 1 against the exact Hertz integral 2 I delta_max / v",
    );
    push(
        "elastic_restitution",
        elastic.normal_restitution,
        1.0,
        wall_elastic,
        "e = 1: energy the integration loses or makes",
    );
    let e_rest = push(
        "restitution",
        damped.normal_restitution,
        base.restitution,
        wall_damped,
        "the scene's particle-wall law against its configured e (wall time includes calibrating the exact-restitution damping)",
    );
    Ok((e_overlap, e_dur, e_exact, e_rest))
}
