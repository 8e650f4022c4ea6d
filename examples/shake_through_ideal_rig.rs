//! Does what `vlab shake --rig ideal --orientation horizontal` does, through
//! the library: a smaller damper (200 spheres, from a scene file's text laid
//! over the thesis preset), shaken at 40 Hz, Γ 10 through the perfect lab, with
//! the DEM's dissipation beside what Yang's method measures. Run it optimised:
//!
//! ```text
//! cargo run --release --example shake_through_ideal_rig
//! ```

use vlab::experiment::measurement::{CalibrationSource, ShakeSetup};
use vlab::experiment::shake::{resolve_rig, run_shake, shake_drive};
use vlab::scene::{Scene, SceneError};

fn main() -> Result<(), SceneError> {
    let scene = Scene::merge_over_preset(
        "[particles]\ncount = 200\n[enclosure]\norientation = \"horizontal\"\n",
        "example scene",
    )?;
    let (freq_hz, gamma) = (40.0, 10.0);
    let drive = shake_drive(&scene, freq_hz, gamma)?;
    let rig = resolve_rig("ideal", None, &drive)?;
    let setup = ShakeSetup {
        rig,
        drive,
        noise_seed: scene.simulation.seed,
        calibration: CalibrationSource::OnTheFly,
    };
    let run = run_shake(&scene, &setup, &mut |_| {})?;
    let s = &run.summary;
    println!(
        "{} spheres, {freq_hz} Hz, Gamma {gamma}, {}: efficiency {:.3} (DEM), {:.3} (measured, {:+.3} %)",
        s.n_particles,
        s.orientation,
        s.dem.efficiency,
        s.measured.efficiency,
        100.0 * s.measured.error_vs_dem_rel
    );
    Ok(())
}
