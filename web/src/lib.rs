//! The browser lab (docs/browser-lab.md): the shake of `vlab shake` — the
//! thesis damper poured, settled, driven through the rig and measured by
//! Yang's method (Terzioglu's thesis, Sections 6.2 and 7.4.2, eq. 7.8–7.12)
//! — run inside a web page, with the bed and the two channels sent to the
//! page while it runs.
//!
//! The same library code as the command line runs here, on one thread: a
//! lab with the same frequency, Γ, orientation, seed, cycles and rig gives
//! the numbers `vlab shake` gives (tests/suite/browser_lab.rs checks it in a real
//! browser). [`run_lab`] is the whole lab as a plain function; the
//! WebAssembly exports at the end of this file only move JSON between it
//! and the page's worker (web/site/lab-worker.js).

use std::cell::RefCell;

use glam::DVec3;
use serde::{Deserialize, Serialize};
use vlab::dem::World;
use vlab::experiment::bed::cache::BedSource;
use vlab::experiment::damper::{Kinematics, Progress, StepObserver};
use vlab::experiment::shake::ShakeSummary;
use vlab::experiment::shake_plan::{ShakePlan, ShakeRequest};
use vlab::export::snapshots::{in_slice, side_view};
use vlab::scene::{Orientation, Scene, SceneOverrides};
use vlab::signals::hysteresis::force_loop;
use vlab::signals::power::HarmonicPower;
use vlab::signals::{Analysis, AnalysisOptions, Trace, analyse_trace};

/// Frames of the bed sent to the page per drive cycle.
pub const FRAMES_PER_CYCLE: u32 = 16;

/// Samples of the recorded channels sent to the page per drive period.
const RECORD_POINTS_PER_PERIOD: usize = 200;

/// What the page asks for: the `vlab shake` flags of the same name.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LabRequest {
    /// Drive frequency (Hz), `--freq`.
    pub freq_hz: f64,
    /// Drive amplitude Γ (peak acceleration / g), `--gamma`.
    pub gamma: f64,
    /// `"vertical"` or `"horizontal"`, `--orientation`.
    pub orientation: String,
    /// Seed of the pour, `--seed`.
    pub seed: u64,
    /// Drive cycles in all, `--cycles`.
    pub cycles: u32,
    /// Steady cycles at the end that are measured, `--steady-cycles`.
    pub steady_cycles: u32,
    /// A built-in rig (`thesis-shaker`, `ideal`), `--rig`.
    pub rig: String,
}

/// What the page is told while the lab runs.
#[derive(Debug, Clone, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum LabEvent {
    /// The enclosure, once, before the drive: for drawing the bed.
    Setup {
        orientation: &'static str,
        radius_mm: f64,
        length_mm: f64,
        stroke_mm: f64,
        peak_speed_mps: f64,
        particles: usize,
    },
    /// How far the run is.
    Progress {
        phase: &'static str,
        fraction: f64,
        cycle: u32,
        sim_time_s: f64,
    },
    /// The bed at one instant of the drive.
    Frame(Frame),
}

/// The bed at one instant: the central slice of the side view (the spheres
/// the plane through the axis cuts), in the lab frame, and the two
/// channels' true values then.
#[derive(Debug, Clone, Serialize)]
pub struct Frame {
    /// Time from the drive start (s).
    pub t_s: f64,
    /// The enclosure's displacement along its axis (mm).
    pub enclosure_mm: f64,
    /// Per sphere in the slice: across, up (mm), radius (mm), speed
    /// relative to the enclosure (m/s); four numbers each.
    pub spheres: Vec<f32>,
    /// The enclosure's acceleration (m/s²).
    pub accel_mps2: f64,
    /// The force the particles exert on the enclosure along its axis (N).
    pub force_n: f64,
}

/// The finished lab: the run's summary (as `summary.json` of `vlab shake`),
/// Yang's method on its record step by step, and the record itself.
#[derive(Debug, Clone, Serialize)]
pub struct LabResult {
    pub summary: ShakeSummary,
    /// Yang's method on the rig's record with the run's phase calibration,
    /// as `vlab analyze` does it: per harmonic `|F_k|`, `|V_k|`, the phase
    /// and `½ Re(F_k V_k*)`.
    pub yang: YangSteps,
    /// The analysed window of the record, thinned for drawing.
    pub record: RecordWindow,
}

/// Yang's method, the numbers of each step.
#[derive(Debug, Clone, Serialize)]
pub struct YangSteps {
    pub drive_freq_hz: f64,
    pub n_periods: usize,
    pub n_samples: usize,
    pub sample_rate_hz: f64,
    pub phase_correction_rad: f64,
    pub force_polarity_reversed: bool,
    /// The first harmonics (as many as `vlab analyze` lists).
    pub per_harmonic: Vec<HarmonicPower>,
    /// The power of every other bin of the spectrum up to the Nyquist
    /// frequency: `power_w` less the listed harmonics' (W).
    pub other_bins_power_w: f64,
    /// `½ Σ Re(F_k V_k*)` over the whole spectrum, phase-corrected (W).
    pub power_w: f64,
    pub energy_per_cycle_j: f64,
    pub efficiency: Option<f64>,
    /// The most energy the drive can put into the particles per cycle,
    /// `E_max` (thesis eq. 6.10), J: the efficiency is `E / E_max`.
    pub e_max_j: f64,
    /// The enclosed area of the force-displacement loop per cycle (J),
    /// before the phase correction.
    pub loop_energy_per_cycle_j: f64,
}

/// The analysed window of the record, every `stride`-th sample.
#[derive(Debug, Clone, Serialize)]
pub struct RecordWindow {
    pub dt_s: f64,
    pub accel_mps2: Vec<f64>,
    pub force_n: Vec<f64>,
    pub displacement_mm: Vec<f64>,
}

/// The scene of a request: the thesis damper with the request's
/// orientation, seed and cycles, as `vlab shake` builds it from its flags.
pub fn lab_scene(req: &LabRequest) -> Result<Scene, String> {
    let orientation = match req.orientation.as_str() {
        "vertical" => Orientation::Vertical,
        "horizontal" => Orientation::Horizontal,
        other => {
            return Err(format!(
                "orientation must be \"vertical\" or \"horizontal\", not {other:?}"
            ));
        }
    };
    SceneOverrides {
        cycles: Some(req.cycles),
        steady_cycles: Some(req.steady_cycles),
        orientation: Some(orientation),
        seed: Some(req.seed),
        dt_s: None,
    }
    .apply(Scene::thesis())
    .map_err(|e| e.to_string())
}

/// Runs the lab of `req`, telling `tell` how it goes; the errors are the
/// library's refusals, worded with the scene key and its valid range.
pub fn run_lab(req: &LabRequest, tell: &mut dyn FnMut(&LabEvent)) -> Result<LabResult, String> {
    let mut request = ShakeRequest::new(lab_scene(req)?, req.freq_hz, req.gamma);
    request.rig = req.rig.clone();
    let plan = ShakePlan::new(request).map_err(|e| e.to_string())?;
    let (scene, drive) = (&plan.scene, &plan.setup.drive);
    let radius_m = 0.5 * scene.enclosure.inner_diameter_m;
    tell(&LabEvent::Setup {
        orientation: scene.enclosure.orientation.as_str(),
        radius_mm: radius_m * 1e3,
        length_mm: scene.enclosure.inner_length_m * 1e3,
        stroke_mm: drive.displacement_amplitude_m() * 1e3,
        peak_speed_mps: drive.velocity_amplitude_mps(),
        particles: scene.particles.count,
    });
    let tell = RefCell::new(tell);
    let mut frames = FrameTaker::new(req.freq_hz, scene.enclosure.orientation, &tell);
    let mut progress = |p: Progress| {
        (tell.borrow_mut())(&LabEvent::Progress {
            phase: p.phase,
            fraction: p.fraction,
            cycle: p.cycle,
            sim_time_s: p.sim_time_s,
        })
    };
    // One bed on the page's one thread: the numbers of `vlab shake --beds 1`.
    let outcome = plan
        .run(&BedSource::Settle, 1, &mut [&mut frames], &mut progress)
        .map_err(|e| e.to_string())?;
    let run = outcome.run;
    let e = &run.experiment;
    let analysis = analyse_trace(
        &e.trace,
        &AnalysisOptions {
            calibration: Some(e.calibration.clone()),
            calibration_name: run.summary.measured.calibration.clone(),
            ..AnalysisOptions::default()
        },
    )
    .map_err(|e| e.to_string())?;
    let e_max_j = plan.setup.drive.e_max_j(run.summary.particle_mass_kg);
    let (yang, record) = yang_steps(&e.trace, &analysis, e_max_j)?;
    Ok(LabResult {
        summary: run.summary,
        yang,
        record,
    })
}

/// Yang's method step by step, and the analysed window of the record, from
/// the `analysis` of `trace`.
fn yang_steps(
    trace: &Trace,
    analysis: &Analysis,
    e_max_j: f64,
) -> Result<(YangSteps, RecordWindow), String> {
    let window = analysis.window_start..analysis.window_start + analysis.n_samples;
    let sign = if analysis.force_polarity.reversed {
        -1.0
    } else {
        1.0
    };
    let channel = |name: &str| -> Result<&[f64], String> {
        let c = trace.channel(name).map_err(|e| e.to_string())?;
        c.samples.get(window.clone()).ok_or_else(|| {
            format!("the record's {name} channel is shorter than the analysed window")
        })
    };
    let force: Vec<f64> = channel("force")?.iter().map(|f| sign * f).collect();
    let accel = channel("acceleration")?;
    let loop_ = force_loop(&force, accel, trace.sample_rate_hz, analysis.n_periods)
        .map_err(|e| e.to_string())?;
    let per_period = analysis.n_samples / analysis.n_periods.max(1);
    let stride = (per_period / RECORD_POINTS_PER_PERIOD).max(1);
    let thin = |v: &[f64], scale: f64| v.iter().step_by(stride).map(|x| x * scale).collect();
    let yang = YangSteps {
        drive_freq_hz: analysis.drive_freq_hz,
        n_periods: analysis.n_periods,
        n_samples: analysis.n_samples,
        sample_rate_hz: trace.sample_rate_hz,
        phase_correction_rad: analysis.phase_correction_rad,
        force_polarity_reversed: analysis.force_polarity.reversed,
        per_harmonic: analysis.per_harmonic.clone(),
        other_bins_power_w: analysis.power_w
            - analysis.per_harmonic.iter().map(|h| h.power_w).sum::<f64>(),
        power_w: analysis.power_w,
        energy_per_cycle_j: analysis.energy_per_cycle_j,
        efficiency: analysis.efficiency,
        e_max_j,
        loop_energy_per_cycle_j: loop_.energy_per_cycle_j,
    };
    let record = RecordWindow {
        dt_s: stride as f64 / trace.sample_rate_hz,
        accel_mps2: thin(accel, 1.0),
        force_n: thin(&force, 1.0),
        displacement_mm: thin(&loop_.displacement_m, 1e3),
    };
    Ok((yang, record))
}

/// The observer that sends the page a [`Frame`] every
/// 1/[`FRAMES_PER_CYCLE`] of a drive period.
struct FrameTaker<'a, 'b> {
    interval_s: f64,
    next: u64,
    orientation: Orientation,
    tell: &'a RefCell<&'b mut dyn FnMut(&LabEvent)>,
}

impl<'a, 'b> FrameTaker<'a, 'b> {
    fn new(
        freq_hz: f64,
        orientation: Orientation,
        tell: &'a RefCell<&'b mut dyn FnMut(&LabEvent)>,
    ) -> Self {
        FrameTaker {
            interval_s: 1.0 / (freq_hz * f64::from(FRAMES_PER_CYCLE)),
            next: 0,
            orientation,
            tell,
        }
    }
}

impl StepObserver for FrameTaker<'_, '_> {
    fn observe(&mut self, t_s: f64, world: &World, enclosure: &Kinematics) {
        if t_s + 0.5 * world.dt_s() < self.next as f64 * self.interval_s {
            return;
        }
        self.next += 1;
        let p = &world.particles;
        let v_enc = DVec3::new(0.0, 0.0, enclosure.velocity_mps);
        let mut spheres = Vec::new();
        for i in 0..p.len() {
            let (across, up, depth) = side_view(self.orientation, p.position[i]);
            if in_slice(depth, p.radius[i]) {
                let speed = (p.velocity[i] - v_enc).length();
                spheres.extend([
                    (across * 1e3) as f32,
                    (up * 1e3) as f32,
                    (p.radius[i] * 1e3) as f32,
                    speed as f32,
                ]);
            }
        }
        let frame = Frame {
            t_s,
            enclosure_mm: enclosure.displacement_m * 1e3,
            spheres,
            accel_mps2: enclosure.acceleration_mps2,
            // The particles push the enclosure with the opposite of the wall force.
            force_n: -world.wall_force().z,
        };
        (self.tell.borrow_mut())(&LabEvent::Frame(frame));
    }
}

/// The WebAssembly interface: the page's worker writes a [`LabRequest`] as
/// JSON into memory from [`lab_alloc`], calls [`lab_run`], and hears every
/// [`LabEvent`], the [`LabResult`] and any error through its import
/// `env.lab_message(kind, ptr, len)`: kind 0 an event, 1 the result, 2 an
/// error (text), each JSON but the error.
#[cfg(target_arch = "wasm32")]
mod wasm {
    use super::{LabRequest, run_lab};

    unsafe extern "C" {
        fn lab_message(kind: u32, ptr: *const u8, len: usize);
    }

    fn send(kind: u32, text: &str) {
        // SAFETY: the worker copies the bytes out before returning.
        unsafe { lab_message(kind, text.as_ptr(), text.len()) }
    }

    /// Room for `len` bytes of request, owned by [`lab_run`] from then on.
    #[unsafe(no_mangle)]
    pub extern "C" fn lab_alloc(len: usize) -> *mut u8 {
        let mut room = Vec::<u8>::with_capacity(len);
        let ptr = room.as_mut_ptr();
        std::mem::forget(room);
        ptr
    }

    /// Runs the lab whose request is the `len` bytes at `ptr` (from
    /// [`lab_alloc`]); returns 0 when it finished, 1 when it was refused.
    ///
    /// # Safety
    /// `ptr` must come from `lab_alloc(len)` with `len` bytes written.
    #[unsafe(no_mangle)]
    pub unsafe extern "C" fn lab_run(ptr: *mut u8, len: usize) -> u32 {
        std::panic::set_hook(Box::new(|info| {
            send(2, &format!("the lab crashed: {info}"))
        }));
        // SAFETY: by the contract above.
        let bytes = unsafe { Vec::from_raw_parts(ptr, len, len) };
        let outcome = serde_json::from_slice::<LabRequest>(&bytes)
            .map_err(|e| format!("bad request: {e}"))
            .and_then(|req| {
                run_lab(&req, &mut |event| {
                    if let Ok(text) = serde_json::to_string(event) {
                        send(0, &text);
                    }
                })
            })
            .and_then(|result| serde_json::to_string(&result).map_err(|e| e.to_string()));
        match outcome {
            Ok(text) => {
                send(1, &text);
                0
            }
            Err(message) => {
                send(2, &message);
                1
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn request() -> LabRequest {
        LabRequest {
            freq_hz: 40.0,
            gamma: 20.0,
            orientation: "vertical".into(),
            seed: 1,
            cycles: 3,
            steady_cycles: 2,
            rig: "thesis-shaker".into(),
        }
    }

    #[test]
    fn bad_requests_are_refused_with_the_key_and_its_range() {
        let refused = |req: LabRequest| run_lab(&req, &mut |_| {}).err().unwrap_or_default();
        let sideways = refused(LabRequest {
            orientation: "sideways".into(),
            ..request()
        });
        assert!(
            sideways.contains("vertical") && sideways.contains("sideways"),
            "{sideways}"
        );
        let flat = refused(LabRequest {
            gamma: 0.0,
            ..request()
        });
        assert!(flat.contains("gamma") && flat.contains("0"), "{flat}");
        let too_strong = refused(LabRequest {
            gamma: 80.0,
            ..request()
        });
        assert!(!too_strong.is_empty(), "Γ 80 is beyond the thesis rig");
        let unknown_rig = refused(LabRequest {
            rig: "no-such-rig".into(),
            ..request()
        });
        assert!(unknown_rig.contains("no-such-rig"), "{unknown_rig}");
        let more_steady_than_cycles = refused(LabRequest {
            steady_cycles: 5,
            ..request()
        });
        assert!(
            more_steady_than_cycles.contains("cycles"),
            "{more_steady_than_cycles}"
        );
    }

    #[test]
    fn a_short_lab_tells_its_setup_then_frames_and_measures() {
        let mut setups = 0;
        let mut frames = Vec::new();
        let result = run_lab(&request(), &mut |e| match e {
            LabEvent::Setup { particles, .. } => {
                assert_eq!(*particles, 358);
                assert!(frames.is_empty(), "the setup comes before the frames");
                setups += 1;
            }
            LabEvent::Frame(f) => frames.push((f.t_s, f.spheres.len())),
            LabEvent::Progress { .. } => {}
        })
        .expect("the lab runs");
        assert_eq!(setups, 1);
        // One frame every 1/16 of a period from t = 0: 16 a cycle, plus the
        // one at the end of the last cycle (within half a step).
        let period = 1.0 / 40.0;
        assert_eq!(
            frames.len(),
            3 * FRAMES_PER_CYCLE as usize + 1,
            "{frames:?}"
        );
        for (k, (t, n)) in frames.iter().enumerate() {
            let want = k as f64 * period / f64::from(FRAMES_PER_CYCLE);
            assert!(
                (t - want).abs() <= result.summary.dt_s,
                "frame {k} at {t} s"
            );
            // The central slice of 358 spheres of 5 mm in a 40 mm cylinder:
            // a few dozen, four numbers each.
            assert!(
                n % 4 == 0 && (40..=400).contains(n),
                "frame {k}: {n} numbers"
            );
        }
        // Yang's steps are the summary's measurement, and the loop's area
        // is the energy before the phase correction (0.1 %).
        let m = &result.summary.measured;
        assert_eq!(result.yang.efficiency, Some(m.efficiency));
        let area = result.yang.loop_energy_per_cycle_j;
        assert!((area - m.uncorrected_energy_per_cycle_j).abs() < 1e-3 * area);
        // The listed harmonics carry the power; the rest of the spectrum
        // (noise, leakage) is a small remainder.
        let (rest, all) = (result.yang.other_bins_power_w, result.yang.power_w);
        assert!(
            rest.abs() < 0.01 * all,
            "the other bins carry {rest} W of {all} W"
        );
        assert_eq!(result.record.accel_mps2.len(), result.record.force_n.len());
    }
}
