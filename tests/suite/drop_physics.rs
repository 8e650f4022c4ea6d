//! The drop test against its own ground truth (thesis Section 7.3): the
//! restitution the lab's estimator (eq. 7.5) finds in the simulated force
//! record, against the restitution the DEM contact realised, for the thesis'
//! two particles (e = 0.83 printed, 0.91 smooth) dropped from 5, 10, 20 and
//! 50 mm; how it degrades at 50 and 20 kHz; and that the scene's long
//! free-flight steps and its step size do not bias the bounce.
//!
//! Measured on this machine (printed / smooth, worst triple over the four
//! heights; mean over triples in brackets), error of the estimate against the
//! realised restitution:
//! - 200 kHz: 0.19 % / 0.10 % (mean within 0.08 % / 0.04 %);
//! - 50 kHz: 0.22 % / 0.09 % (0.08 % / 0.03 %): as good as 200 kHz;
//! - 20 kHz: the plate's 10.1 kHz ring lies above the Nyquist frequency and
//!   the first pulse (~65 us) spans 1.3 samples; impacts sampled near their
//!   zero crossings fall below the threshold and are missed, two gaps merge,
//!   and triples read 0.4-2.5 (errors up to 170 %, means off by up to 12 %).
//!   The triples between missed impacts stay within ~0.3 %. A lower
//!   threshold (0.05 N, ten noise rms) catches most missed impacts but adds
//!   the slow last bounces, whose short gaps 20 kHz times to 1-2 %.
//!
//! Realised against configured: the sphere's own rebound / impact speed is
//! 0.9088 for e = 0.91 and 0.8287 for e = 0.83 (-0.13 %, -0.16 %): gravity
//! acts during the contact and the plate takes some energy into its ring
//! (the `exact` restitution mode calibrates a fixed wall without gravity).
//!
//! The estimate's own bias: each gap includes one contact duration, so
//! `T(k+1)/T(k) = e + (1 - e) g t_c / (2 v)` to first order: +0.01 % at 1 m/s,
//! +0.1 % at 0.05 m/s for e = 0.83 (the slow end of a 5 mm drop). This is the
//! thesis' "time gaps are much larger than the contact durations", quantified.

use std::sync::OnceLock;

use vlab::experiment::drop::{DropEstimate, DropOutcome, DropParticle, DropSetup, run_drop};
use vlab::signals::ImpactParams;

const HEIGHTS_M: [f64; 4] = [0.005, 0.01, 0.02, 0.05];
const PARTICLES: [DropParticle; 2] = [DropParticle::AcrylicPrinted, DropParticle::AcrylicSmooth];

struct Run {
    setup: DropSetup,
    particle: DropParticle,
    height_m: f64,
    out: DropOutcome,
    est: DropEstimate,
}

fn drop_at(particle: DropParticle, height_m: f64, rate_hz: f64) -> Run {
    let mut setup = DropSetup::preset(particle, height_m).expect("preset");
    setup.rig.daq.sample_rate_hz = rate_hz;
    let out = run_drop(&setup).expect("drop runs");
    let est = out
        .estimate(&ImpactParams::default(), setup.gravity_mps2)
        .expect("estimate");
    Run {
        setup,
        particle,
        height_m,
        out,
        est,
    }
}

/// All eight drops at one rate, computed once per test binary.
fn runs(rate_hz: u32) -> &'static [Run] {
    static R200: OnceLock<Vec<Run>> = OnceLock::new();
    static R50: OnceLock<Vec<Run>> = OnceLock::new();
    static R20: OnceLock<Vec<Run>> = OnceLock::new();
    let cell = match rate_hz {
        200_000 => &R200,
        50_000 => &R50,
        _ => &R20,
    };
    cell.get_or_init(|| {
        PARTICLES
            .iter()
            .flat_map(|&p| HEIGHTS_M.iter().map(move |&h| (p, h)))
            .map(|(p, h)| drop_at(p, h, f64::from(rate_hz)))
            .collect()
    })
}

/// Largest |estimate / realised - 1| over the triples, and of the means.
fn errors(r: &Run) -> (f64, f64) {
    let cor = &r.est.result.cor;
    let worst = cor
        .cor_per_triple
        .iter()
        .zip(&r.est.realised_per_triple)
        .map(|(c, real)| (c / real.expect("every triple's middle impact matched") - 1.0).abs())
        .fold(0.0, f64::max);
    let mean = (cor.cor_mean / r.est.realised_mean().expect("realised") - 1.0).abs();
    (worst, mean)
}

#[test]
fn estimate_within_half_a_percent_of_the_realised_restitution_at_200_khz() {
    for r in runs(200_000) {
        let cor = &r.est.result.cor;
        let label = format!("{} from {} m", r.particle.name(), r.height_m);
        // Enough record for many triples: at least 10 for e = 0.83, 20 for 0.91.
        assert!(
            cor.cor_per_triple.len() >= 10,
            "{label}: {} triples",
            cor.cor_per_triple.len()
        );
        assert!(cor.growing_gaps().is_empty(), "{label}: a missed impact");
        let (worst, mean) = errors(r);
        // The tolerance, 0.5 % for every triple (measured: <= 0.19 %).
        assert!(
            worst < 0.005,
            "{label}: worst triple off by {:.3} %",
            100.0 * worst
        );
        assert!(mean < 0.002, "{label}: mean off by {:.3} %", 100.0 * mean);
        // Detected onsets lie after the contact starts, within the first pulse.
        for (imp, m) in r.est.result.detection.impacts.iter().zip(&r.est.matched) {
            let d = &r.out.impacts[m.expect("matched")];
            let lag = imp.onset_time_s - d.onset_time_s;
            assert!(lag > -5e-6 && lag < 70e-6, "{label}: onset lag {lag} s");
        }
    }
}

#[test]
fn realised_restitution_is_the_configured_one_less_gravity_and_plate() {
    for r in runs(200_000) {
        let e = r.particle.restitution();
        let label = format!("{} from {} m", r.particle.name(), r.height_m);
        // The impacts that form triples (faster than 10 % of the first).
        let fast: Vec<_> = r
            .out
            .impacts
            .iter()
            .filter(|d| d.arrival_speed_mps > 0.1 * r.out.impacts[0].arrival_speed_mps)
            .collect();
        assert!(fast.len() >= 10, "{label}");
        for d in fast {
            // Gravity during the contact and the plate's ring cost 0.1-0.2 %.
            let bounce = d.bounce_cor / e - 1.0;
            assert!(
                bounce < -0.0005 && bounce > -0.003,
                "{label}: bounce {}",
                d.bounce_cor
            );
            // Relative to the (still ringing) plate: within 0.5 % of e. The two
            // differ by the plate's speed when the sphere leaves, at most the
            // impulse over its mass, m (1 + e) v / m_p: 0.17 % of the sphere's.
            assert!(
                (d.contact_cor / e - 1.0).abs() < 0.005,
                "{label}: contact {}",
                d.contact_cor
            );
            let m_ratio = r.setup.sphere_mass_kg() / r.setup.rig.plate.mass_kg;
            let bound = m_ratio * (1.0 + e) / e;
            assert!(
                (d.contact_cor / d.bounce_cor - 1.0).abs() < bound,
                "{label}: {d:?}"
            );
        }
    }
}

#[test]
fn estimate_does_not_depend_on_the_drop_height() {
    // Thesis Fig. 7.5: below yield, COR is the same at every impact velocity.
    for p in PARTICLES {
        let rs: Vec<&Run> = runs(200_000).iter().filter(|r| r.particle == p).collect();
        let means: Vec<f64> = rs.iter().map(|r| r.est.result.cor.cor_mean).collect();
        let all: Vec<f64> = rs
            .iter()
            .flat_map(|r| r.est.result.cor.cor_per_triple.clone())
            .collect();
        let grand = all.iter().sum::<f64>() / all.len() as f64;
        let spread = means.iter().copied().fold(f64::NEG_INFINITY, f64::max)
            - means.iter().copied().fold(f64::INFINITY, f64::min);
        // Means of 5 to 50 mm drops within 0.1 % of each other (measured 0.02 %).
        assert!(
            spread / grand < 1e-3,
            "{}: height means {means:?}",
            p.name()
        );
        // Every triple, impact speeds 0.04-0.9 m/s, within 0.15 % of the grand mean.
        for c in &all {
            assert!(
                (c / grand - 1.0).abs() < 1.5e-3,
                "{}: {c} vs {grand}",
                p.name()
            );
        }
        // And the grand mean is the preset's e within 0.3 %.
        assert!(
            (grand / p.restitution() - 1.0).abs() < 3e-3,
            "{}: {grand}",
            p.name()
        );
    }
}

#[test]
fn at_50_khz_the_estimate_is_as_good_and_at_20_khz_impacts_are_missed() {
    for r in runs(50_000) {
        let (worst, mean) = errors(r);
        let label = format!("50 kHz, {} from {} m", r.particle.name(), r.height_m);
        assert!(r.est.result.cor.growing_gaps().is_empty(), "{label}");
        assert!(worst < 0.005 && mean < 0.002, "{label}: {worst} {mean}");
    }
    // At 20 kHz the run is allowed (one sample per first pulse) with a warning,
    // and the record loses impacts: some triples read e + e^2 > 1.
    let mut setup = DropSetup::preset(DropParticle::AcrylicSmooth, 0.05).expect("preset");
    setup.rig.daq.sample_rate_hz = 20_000.0;
    setup.validate().expect("20 kHz is accepted");
    let warning = setup.sampling_warning().expect("checks").expect("warns");
    assert!(
        warning
            .text
            .contains("above the 10.0 kHz Nyquist frequency"),
        "{warning}"
    );
    let broken = runs(20_000)
        .iter()
        .filter(|r| !r.est.result.cor.growing_gaps().is_empty())
        .count();
    let worst = runs(20_000)
        .iter()
        .map(errors_or_missed)
        .fold(0.0, f64::max);
    assert!(
        broken >= 4,
        "{broken} of 8 records at 20 kHz missed an impact"
    );
    assert!(worst > 0.5, "worst triple at 20 kHz off by only {worst}");
}

/// Worst triple error, counting unmatched middles as 100 %.
fn errors_or_missed(r: &Run) -> f64 {
    r.est
        .result
        .cor
        .cor_per_triple
        .iter()
        .zip(&r.est.realised_per_triple)
        .map(|(c, real)| real.map_or(1.0, |x| (c / x - 1.0).abs()))
        .fold(0.0, f64::max)
}

fn short_drop(max_flight_step_s: f64, steps_per_contact: f64) -> (DropOutcome, DropEstimate) {
    let mut s = DropSetup::preset(DropParticle::AcrylicPrinted, 0.005).expect("preset");
    s.rig.record.length_s = 0.3;
    s.numerics.max_flight_step_s = max_flight_step_s;
    s.numerics.steps_per_contact = steps_per_contact;
    let out = run_drop(&s).expect("drop runs");
    let est = out
        .estimate(&ImpactParams::default(), s.gravity_mps2)
        .expect("estimate");
    (out, est)
}

fn mean(x: impl Iterator<Item = f64>) -> f64 {
    let v: Vec<f64> = x.collect();
    v.iter().sum::<f64>() / v.len() as f64
}

/// The estimate's mean error against the realised restitution.
fn mean_error(est: &DropEstimate) -> f64 {
    est.result.cor.cor_mean / est.realised_mean().expect("realised") - 1.0
}

#[test]
fn flight_steps_do_not_bias_the_bounce() {
    // Long free-flight steps (default, up to 1 ms) against the tick everywhere.
    let (long, long_est) = short_drop(1e-3, 100.0);
    let (fine, fine_est) = short_drop(1e-12, 100.0);
    assert!(fine.fine_steps == fine.dem_steps && long.dem_steps < fine.dem_steps / 20);
    assert!(long.impacts.len() >= 8 && fine.impacts.len() >= 8);
    // Free flight is exact either way, so the first bounces agree to rounding.
    // Later ones drift apart: the DEM's realised restitution depends on where
    // within a step a contact starts (about +-3e-4 over a step at 100 steps
    // per contact), which amplifies a rounding difference ~100-fold per bounce.
    for (a, b) in long.impacts.iter().zip(&fine.impacts).take(2) {
        assert!((a.onset_time_s - b.onset_time_s).abs() < 1e-10);
        assert!((a.bounce_cor - b.bounce_cor).abs() < 1e-8);
    }
    // On average nothing moves: realised means within 3e-4 (the scatter of
    // single impacts is 1-2e-4), estimate errors both within 0.1 %.
    let m = |o: &DropOutcome| mean(o.impacts.iter().take(8).map(|d| d.bounce_cor));
    assert!(
        (m(&long) - m(&fine)).abs() < 3e-4,
        "{} vs {}",
        m(&long),
        m(&fine)
    );
    assert!(mean_error(&long_est).abs() < 1e-3 && mean_error(&fine_est).abs() < 1e-3);
}

#[test]
fn halving_the_step_changes_neither_the_model_nor_the_estimate() {
    let (base, base_est) = short_drop(1e-3, 100.0);
    let (half, half_est) = short_drop(1e-3, 200.0);
    assert!(half.tick_s < 0.6 * base.tick_s);
    let m = |o: &DropOutcome| mean(o.impacts.iter().take(8).map(|d| d.bounce_cor));
    // The model's realised restitution within 3e-4 (0.04 %) ...
    assert!(
        (m(&base) - m(&half)).abs() < 3e-4,
        "{} vs {}",
        m(&base),
        m(&half)
    );
    // ... and the estimate still within 0.1 % of it.
    assert!(mean_error(&base_est).abs() < 1e-3 && mean_error(&half_est).abs() < 1e-3);
}
