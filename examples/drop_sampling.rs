//! How the drop-test restitution estimate (thesis eq. 7.5) depends on the
//! sample rate: drops of printed and smooth acrylic (e = 0.83, 0.91) from 5 to
//! 50 mm recorded at 200, 50 and 20 kHz, each triple's estimate compared with
//! the restitution the DEM contact realised at its middle impact. A triple
//! whose middle impact the detector missed counts as 100 % off. The last
//! block repeats 20 kHz with a detection threshold of 0.05 N (ten noise rms)
//! instead of the default 10 % of the largest peak.
//!
//! Run with `cargo run --release --example drop_sampling` (about 8 s).

use vlab::experiment::drop::{DropParticle, DropSetup, run_drop};
use vlab::signals::ImpactParams;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    println!(
        "particle         height   rate       impacts  triples  missed  COR mean  realised  worst triple  mean error  run"
    );
    for particle in [DropParticle::AcrylicPrinted, DropParticle::AcrylicSmooth] {
        for (rate, threshold_n) in [
            (200_000.0, None),
            (50_000.0, None),
            (20_000.0, None),
            (20_000.0, Some(0.05)),
        ] {
            for height in [0.005, 0.01, 0.02, 0.05] {
                let mut setup = DropSetup::preset(particle, height)?;
                setup.rig.daq.sample_rate_hz = rate;
                let out = run_drop(&setup)?;
                let params = ImpactParams {
                    threshold_n,
                    ..ImpactParams::default()
                };
                let est = out.estimate(&params, setup.gravity_mps2)?;
                let cor = &est.result.cor;
                let worst = cor
                    .cor_per_triple
                    .iter()
                    .zip(&est.realised_per_triple)
                    .map(|(c, r)| r.map_or(1.0, |r| (c / r - 1.0).abs()))
                    .fold(0.0, f64::max);
                let realised = est.realised_mean().unwrap_or(f64::NAN);
                println!(
                    "{:16} {:5.3} m  {:6.0} Hz{} {:7}  {:7}  {:6}  {:.5}   {:.5}   {:9.3} %  {:+8.3} %  {:.2} s",
                    particle.name(),
                    height,
                    rate,
                    if threshold_n.is_some() { "*" } else { " " },
                    est.result.detection.impacts.len(),
                    cor.cor_per_triple.len(),
                    cor.growing_gaps().len(),
                    cor.cor_mean,
                    realised,
                    100.0 * worst,
                    100.0 * (cor.cor_mean / realised - 1.0),
                    out.wall_time_s
                );
            }
        }
    }
    Ok(())
}
