//! Study (c): Yang's method (thesis eq. 7.8–7.12) against the DEM truth,
//! the rig's chain re-run on one recorded drive with changed settings
//! (record length, noise, ADC bits, a residual phase error).

use super::*;

/// A chain's record of the truth: force and acceleration, and the sample rate.
pub(super) struct Chained {
    force: Vec<f64>,
    accel: Vec<f64>,
    fs_hz: f64,
}

/// Runs the chain of `rig` on the truth record from `feed_start_s`, keeping
/// the record from `record_start_s`; with `particles` false, on the empty
/// enclosure (same motion, no particle force).
pub(super) fn rechain(
    rig: &RigSpec,
    truth: &TruthSamples,
    feed_start_s: f64,
    record_start_s: f64,
    static_weight_n: f64,
    seed: u64,
    particles: bool,
) -> Result<Chained, SceneError> {
    let fs = rig.daq.sample_rate_hz;
    let dt = truth
        .time_s
        .get(1)
        .zip(truth.time_s.first())
        .map_or(1.0 / fs, |(b, a)| b - a);
    let mut daq = Daq::new(rig, dt.min(1.0 / fs), record_start_s, seed)?;
    let span = truth.time_s.last().copied().unwrap_or(0.0) - record_start_s;
    daq.reserve(span.max(0.0) + 0.01);
    let first = truth.time_s.partition_point(|&t| t < feed_start_s - 1e-12);
    for i in first..truth.len() {
        let a = truth.acceleration_mps2[i];
        let fp = if particles {
            truth.force_axial_n[i]
        } else {
            0.0
        };
        let f = transducer_force_n(rig.enclosure.mass_kg, a, fp, static_weight_n);
        daq.push(truth.time_s[i], a, f);
    }
    let (trace, _) = daq.finish(TraceMetadata::default())?;
    Ok(Chained {
        force: trace.channel(crate::rig::FORCE_CHANNEL)?.samples.clone(),
        accel: trace.channel(crate::rig::ACCEL_CHANNEL)?.samples.clone(),
        fs_hz: trace.sample_rate_hz,
    })
}

/// The rig's chain replayed on the first seed's truth record, and Yang's
/// method on what it records (study (c)).
pub(super) struct YangBench<'a> {
    truth: &'a TruthSamples,
    /// Drive frequency (Hz) and its angular frequency (rad/s).
    freq_hz: f64,
    omega: f64,
    feed_start_s: f64,
    record_start_s: f64,
    static_weight_n: f64,
    seed: u64,
    /// The calibration record's noise seed.
    calibration_seed: u64,
}

impl YangBench<'_> {
    /// A chain setting `r`: the record, its calibration record (the empty
    /// enclosure) and the wall time both took (s).
    fn chain(&self, r: &RigSpec) -> Result<(Chained, Chained, f64), SceneError> {
        let t0 = Stopwatch::start();
        let (feed, record, weight) = (self.feed_start_s, self.record_start_s, self.static_weight_n);
        let full = rechain(r, self.truth, feed, record, weight, self.seed, true)?;
        let empty = rechain(
            r,
            self.truth,
            feed,
            record,
            weight,
            self.calibration_seed,
            false,
        )?;
        Ok((full, empty, t0.elapsed().as_secs_f64()))
    }

    /// Samples of `c` in `n` periods.
    fn samples(&self, c: &Chained, n: usize) -> usize {
        ((n as f64 * c.fs_hz / self.freq_hz).round() as usize).min(c.force.len())
    }

    /// The empty enclosure's phase error over the first n periods.
    fn calibrate(&self, c: &Chained, n: usize) -> Result<f64, SceneError> {
        let len = self.samples(c, n);
        Ok(
            estimate_phase_error(&c.force[..len], &c.accel[..len], c.fs_hz, self.freq_hz)?
                .phase_error_rad,
        )
    }

    /// Yang over the first n periods, less the phase error `phi_rad`.
    fn estimate(&self, c: &Chained, n: usize, phi_rad: f64) -> Result<f64, SceneError> {
        let len = self.samples(c, n);
        let options = PowerOptions {
            phase_correction: PhaseCorrection::TimeDelay(phi_rad / self.omega),
            ..PowerOptions::default()
        };
        Ok(yang_power(
            &c.force[..len],
            &c.accel[..len],
            c.fs_hz,
            self.freq_hz,
            &options,
        )?
        .energy_per_cycle_j)
    }
}

/// The DEM's truth over the cycles of run `run` after `transient` cycles:
/// dissipation and work per cycle over the first `n`.
pub(super) fn truth_window(run: &DriveRun, transient: usize, n: usize) -> (f64, f64) {
    let snaps: &[LedgerSnapshot] = run
        .outcome
        .as_ref()
        .map(|o| o.cycle_snapshots.as_slice())
        .unwrap_or(&[]);
    let (Some(a), Some(b)) = (snaps.get(transient), snaps.get(transient + n)) else {
        return (f64::NAN, f64::NAN);
    };
    let bal = LedgerBalance::between(a, b);
    (bal.dissipated_j / n as f64, bal.work_in_j / n as f64)
}

/// Study (c): Yang's method on the first seed's record.
pub(super) fn yang_study(
    scene: &Scene,
    rig: &RigSpec,
    plan: &AccuracyPlan,
    run: &DriveRun,
    settle_wall_s: f64,
    dem: &DemAccuracy,
) -> Result<(Vec<AccuracyRow>, YangAccuracy), SceneError> {
    let t = plan.transient_cycles as usize;
    let empty = TruthSamples::default();
    let bench = yang_bench(scene, rig, plan, run.truth.as_ref().unwrap_or(&empty));
    let baseline = plan.baseline_record_periods() as usize;
    let dem_wall =
        |n: usize| settle_wall_s + run.cycle_wall_s.get(t + n).copied().unwrap_or(run.wall_s);

    let (full, empty_rec, chain_s) = bench.chain(rig)?;
    let RecordPeriods {
        mut rows,
        baseline_err,
        baseline_phi,
    } = record_period_rows(
        &bench,
        plan,
        run,
        (&full, &empty_rec),
        &|n| dem_wall(n) + chain_s,
        dem.pooled_energy_per_cycle_j,
    )?;
    let (dissipated, _) = truth_window(run, t, baseline);
    let base_wall = dem_wall(baseline);
    rows.extend(chain_setting_rows(
        &bench, rig, plan, baseline, dissipated, base_wall,
    )?);
    let (phase_rows, error_per_mrad) = residual_phase_rows(
        &bench,
        &full,
        plan,
        baseline,
        baseline_phi,
        dissipated,
        base_wall + chain_s,
    )?;
    rows.extend(phase_rows);
    Ok((
        rows,
        YangAccuracy {
            rig: rig.name.clone(),
            baseline_record_periods: baseline as u32,
            baseline_error_vs_work_rel: baseline_err.chain,
            baseline_unsteadiness_rel: baseline_err.unsteadiness,
            baseline_error_rel: baseline_err.vs_dissipated,
            rig_phase_error_rad: rig.expected_phase_error_rad(plan.freq_hz),
            calibrated_phase_error_rad: baseline_phi,
            error_per_mrad,
        },
    ))
}

/// Study (c)'s bench: the DEM's `truth` record of a drive of `plan` put
/// through the chain of `rig` from the end of its first cycle, recorded
/// after the transient cycles.
pub(super) fn yang_bench<'a>(
    scene: &Scene,
    rig: &RigSpec,
    plan: &AccuracyPlan,
    truth: &'a TruthSamples,
) -> YangBench<'a> {
    let f = plan.freq_hz;
    let period = 1.0 / f;
    let weight = match scene.enclosure.orientation {
        Orientation::Vertical => rig.enclosure.mass_kg * scene.simulation.gravity_mps2,
        Orientation::Horizontal => 0.0,
    };
    let record_start = f64::from(plan.transient_cycles) * period;
    // The prescribed sine starts at full velocity into the resting bed: the
    // first sample of the drive carries a slam (about -180 N on the thesis
    // rig's 60-sphere test bed) that an AC-coupled chain turns into a slowly
    // decaying offset across the record. A lab's chain runs long before the
    // record; feed it from the end of the first cycle.
    YangBench {
        truth,
        freq_hz: f,
        omega: 2.0 * PI * f,
        feed_start_s: period.min(record_start),
        record_start_s: record_start,
        static_weight_n: weight,
        seed: scene.simulation.seed,
        // The calibration's noise: another seed, so its noise is its own.
        calibration_seed: scene.simulation.seed ^ 0x5eed_ca1b,
    }
}

/// Study (c)'s rows of residual phase errors: Yang on the `record` over
/// `baseline` periods, corrected by the calibrated `baseline_phi` (rad) plus
/// each residual of `plan`, against the DEM's `dissipated` energy per cycle
/// (J); `wall` is the wall time to there (s). Also the error's slope per
/// mrad (from zero to the largest residual), when both were run.
pub(super) fn residual_phase_rows(
    bench: &YangBench,
    record: &Chained,
    plan: &AccuracyPlan,
    baseline: usize,
    baseline_phi: f64,
    dissipated: f64,
    wall: f64,
) -> Result<(Vec<AccuracyRow>, Option<f64>), SceneError> {
    let mut rows = Vec::new();
    let mut phase_pts = Vec::new();
    for &mrad in &plan.residual_phase_mrad {
        let t1 = Stopwatch::start();
        let e = bench.estimate(record, baseline, baseline_phi + 1e-3 * mrad)?;
        let row = residual_phase_row(
            mrad,
            e,
            dissipated,
            wall + t1.elapsed().as_secs_f64(),
            baseline,
            baseline_phi,
        );
        phase_pts.push((mrad, row.error_rel));
        rows.push(row);
    }
    let error_per_mrad = {
        let zero = phase_pts.iter().find(|p| p.0 == 0.0).map(|p| p.1);
        let far = phase_pts
            .iter()
            .filter(|p| p.0 != 0.0)
            .max_by(|a, b| a.0.abs().total_cmp(&b.0.abs()));
        zero.zip(far).map(|(z, (m, e))| (e - z) / m)
    };
    Ok((rows, error_per_mrad))
}

/// Study (c)'s row of a residual phase error of `mrad` left after the
/// calibrated `baseline_phi` (rad) over `baseline` periods: Yang's estimate
/// `e` against the DEM's `dissipated` energy per cycle (J).
pub(super) fn residual_phase_row(
    mrad: f64,
    e: f64,
    dissipated: f64,
    wall: f64,
    baseline: usize,
    baseline_phi: f64,
) -> AccuracyRow {
    let mut row = AccuracyRow::new(
        "yang",
        "residual_phase_mrad",
        mrad,
        "energy_per_cycle_j",
        e,
        dissipated,
        f64::NAN,
        wall,
    );
    row.note = format!(
        "correction {:.4} mrad (calibrated {:.4} mrad + residual), {baseline} periods",
        1e3 * baseline_phi + mrad,
        1e3 * baseline_phi
    );
    row
}

/// Yang's error at the baseline record length, in its two parts and whole.
pub(super) struct BaselineErrors {
    /// Against the enclosure's work in: the chain's error.
    chain: f64,
    /// The work in against the DEM dissipation: the bed's unsteadiness.
    unsteadiness: f64,
    /// Against the DEM dissipation: both together.
    vs_dissipated: f64,
}

/// What [`record_period_rows`] gives.
pub(super) struct RecordPeriods {
    rows: Vec<AccuracyRow>,
    /// Errors at the baseline length.
    baseline_err: BaselineErrors,
    /// The phase error calibrated at the baseline length (rad).
    baseline_phi: f64,
}

/// Study (c)'s rows of record lengths: Yang on the `record` (and on its
/// empty-enclosure `calibration`) over each length of `plan`, against the
/// DEM's dissipation and work over the same cycles and the `pooled` mean
/// (J); `wall(n)` is the wall time to `n` periods (s).
pub(super) fn record_period_rows(
    bench: &YangBench,
    plan: &AccuracyPlan,
    run: &DriveRun,
    chained: (&Chained, &Chained),
    wall: &dyn Fn(usize) -> f64,
    pooled: f64,
) -> Result<RecordPeriods, SceneError> {
    let t = plan.transient_cycles as usize;
    let baseline = plan.baseline_record_periods() as usize;
    let mut rows = Vec::new();
    let mut baseline_err = BaselineErrors {
        chain: f64::NAN,
        unsteadiness: f64::NAN,
        vs_dissipated: f64::NAN,
    };
    let mut baseline_phi = f64::NAN;
    let cycle_energies = run.cycle_energies(t);
    for &n in &plan.record_periods {
        let n = n as usize;
        let t1 = Stopwatch::start();
        let (length_rows, phi) = record_length_rows(
            bench,
            chained,
            n,
            &|| wall(n) + t1.elapsed().as_secs_f64(),
            truth_window(run, t, n),
            (&cycle_energies, pooled),
        )?;
        if n == baseline {
            baseline_err = BaselineErrors {
                chain: length_rows[0].error_rel,
                unsteadiness: length_rows[1].error_rel,
                vs_dissipated: length_rows[2].error_rel,
            };
            baseline_phi = phi;
        }
        rows.extend(length_rows);
    }
    Ok(RecordPeriods {
        rows,
        baseline_err,
        baseline_phi,
    })
}

/// Study (c)'s five rows of a record of `n` periods, and the phase error
/// calibrated on it (rad), the chain's error first: Yang on the `record`
/// against the DEM's work per cycle over the same cycles (the chain), that
/// work against the dissipation per cycle (the bed's unsteadiness), Yang
/// against the dissipation (both: the error against the DEM truth), all from
/// `(dissipated, work)` (J); Yang on the `calibration` record itself (the
/// chain's false energy); Yang against the `pooled` mean with the standard
/// error of the first `n` of the bed's `cycle_energies` (J). `wall()` is the
/// wall time to there (s), taken once both are calibrated and estimated.
pub(super) fn record_length_rows(
    bench: &YangBench,
    (record, calibration): (&Chained, &Chained),
    n: usize,
    wall: &dyn Fn() -> f64,
    (dissipated, work): (f64, f64),
    (cycle_energies, pooled): (&[f64], f64),
) -> Result<(Vec<AccuracyRow>, f64), SceneError> {
    let phi = bench.calibrate(calibration, n)?;
    let e = bench.estimate(record, n, phi)?;
    let wall = wall();
    let row = |quantity: &'static str, value: f64, reference: f64, stderr_rel: f64| {
        AccuracyRow::new(
            "yang",
            "record_periods",
            n as f64,
            quantity,
            value,
            reference,
            stderr_rel,
            wall,
        )
    };
    let note = format!("calibrated phase error {:.4} mrad", 1e3 * phi);
    let mut vs_work = row("energy_per_cycle_vs_work_j", e, work, f64::NAN);
    vs_work.note = "against the enclosure's work over the same cycles: the chain alone".into();
    let mut unsteady = row("work_in_per_cycle_j", work, dissipated, f64::NAN);
    unsteady.note =
        "the enclosure's work against the DEM dissipation over the same cycles: the bed's unsteadiness"
            .into();
    let mut vs_dissipated = row("energy_per_cycle_j", e, dissipated, f64::NAN);
    vs_dissipated.note = format!(
        "against the DEM dissipation over the same cycles: the chain and the unsteadiness; {note}"
    );
    // The chain's false energy: Yang on the calibration record itself.
    let false_e = bench.estimate(calibration, n, phi)?;
    let mut empty = row(
        "empty_enclosure_energy_per_cycle_j",
        false_e,
        work,
        f64::NAN,
    );
    empty.error_rel = false_e / work;
    empty.note = "Yang on the calibration record (no particles), relative to the work in: the chain's own false energy".into();
    let se = mean_stderr(&cycle_energies[..n.min(cycle_energies.len())]).stderr_or_nan();
    let mut vs_mean = row("energy_per_cycle_vs_bed_mean_j", e, pooled, se / pooled);
    vs_mean.note = "against the bed's long-run mean (all seeds): chain and statistics".into();
    Ok((vec![vs_work, unsteady, vs_dissipated, empty, vs_mean], phi))
}

/// Study (c)'s rows of chain settings: the noise factors and ADC bits of
/// `plan` on `rig`, each calibrated and estimated over `baseline` periods
/// against the DEM's `dissipated` energy per cycle (J); `base_wall` is the
/// DEM's wall time to there (s).
pub(super) fn chain_setting_rows(
    bench: &YangBench,
    rig: &RigSpec,
    plan: &AccuracyPlan,
    baseline: usize,
    dissipated: f64,
    base_wall: f64,
) -> Result<Vec<AccuracyRow>, SceneError> {
    let mut rows = Vec::new();
    let mut setting = |parameter: &'static str,
                       value: f64,
                       r: &RigSpec,
                       note: String|
     -> Result<(), SceneError> {
        let t1 = Stopwatch::start();
        let (full, empty_rec, _) = bench.chain(r)?;
        let phi = bench.calibrate(&empty_rec, baseline)?;
        let e = bench.estimate(&full, baseline, phi)?;
        let mut row = AccuracyRow::new(
            "yang",
            parameter,
            value,
            "energy_per_cycle_j",
            e,
            dissipated,
            f64::NAN,
            base_wall + t1.elapsed().as_secs_f64(),
        );
        row.note = format!(
            "{note}, {baseline} periods, calibrated {:.4} mrad",
            1e3 * phi
        );
        rows.push(row);
        Ok(())
    };
    for &k in &plan.noise_factors {
        let mut r = rig.clone();
        r.force.noise_rms *= k;
        r.accelerometer.noise_rms *= k;
        let note = format!(
            "noise {:.3e} N and {:.3e} m/s^2 rms",
            r.force.noise_rms, r.accelerometer.noise_rms
        );
        setting("noise_factor", k, &r, note)?;
    }
    for &bits in &plan.adc_bits {
        let mut r = rig.clone();
        r.daq.bits = bits;
        r.daq.ideal_adc = false;
        let lsb_n = 2.0 * r.daq.full_scale_v
            / 2f64.powi(bits as i32)
            / (r.force.sensitivity * r.force.conditioner_gain);
        setting(
            "adc_bits",
            f64::from(bits),
            &r,
            format!("force LSB {lsb_n:.3e} N"),
        )?;
    }
    Ok(rows)
}
