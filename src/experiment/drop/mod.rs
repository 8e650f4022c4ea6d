//! The drop test (thesis Section 7.3, Fig. 7.3-7.5): one sphere released above
//! the base plate of the drop rig bounces until it rests; the plate rings on its
//! force transducer after every impact, and the transducer's force is recorded
//! through the rig's channel. The lab's estimator (`signals::impacts`, eq.
//! 7.3-7.5) then finds the impacts in that record and turns the gaps between
//! them into restitution, which can be checked against what the DEM contact
//! really did.
//!
//! The scene builds only what it needs: one sphere, one flat plate (a DEM wall
//! that moves with the rig's plate), gravity. No enclosure, no shaker; the
//! engine's neighbour list holds no pairs.
//!
//! # Time stepping
//!
//! The rig ticks on a fixed clock `h` (its channel filters are discretised at
//! it): `h = T_s / ceil(T_s / h_max)`, an integer fraction of the sample period
//! `T_s`, with `h_max = min(t_c / 100, T_ring / 100)`, `t_c` the Hertz contact
//! duration (eq. 5.10) at the fastest impact (the first: `sqrt(2 g h)`) and
//! `T_ring` the plate's natural period. On the built-in rig, 5 mm acrylic and
//! 5-50 mm drops, `h` is 0.31-0.38 us: 100-190 steps per contact (slower
//! impacts last longer), 260-320 per ring period.
//!
//! The DEM steps at `h` while the sphere is in contact or closer to the plate
//! than [`DropNumerics::approach_margin_m`] (20 um, a thousand times the plate's
//! ring amplitude). In free flight above that it takes one long step, up to
//! [`DropNumerics::max_flight_step_s`] (1 ms) and never past the instant its
//! parabola reaches the margin, while the rig ticks through it with zero force.
//! Velocity Verlet is exact for a body under constant gravity (`x += v dt +
//! g dt^2 / 2`), and the plate's zero-order-hold step is exact too, so the long
//! steps change nothing but the rounding. The test
//! `flight_steps_do_not_bias_the_bounce` runs the same drop with `h` everywhere:
//! the first bounces agree to rounding (contact times within 0.1 ns), and the
//! realised and estimated restitution agree on average within 3e-4. Later
//! bounces do drift apart, because the engine's realised restitution depends on
//! where within a step a contact starts (a swing of about +-3e-4 over one step
//! at 100 steps per contact, +-1e-4 at 400): a rounding-level change in one
//! arrival grows about a hundredfold per bounce. Halving `h` moves the mean
//! realised restitution by less than 3e-4 (test
//! `halving_the_step_changes_neither_the_model_nor_the_estimate`). A run costs
//! 5-7 M rig ticks per 2 s record and 10^4-10^5 DEM steps, about 0.3 s.
//!
//! # What the DEM says ([`DemImpact`])
//!
//! For each contact: the onset and end (overlap zero crossings, interpolated),
//! the sphere's speed at both (from the free-flight parabola through the step
//! around them), and two restitutions:
//!
//! - `bounce_cor`, the sphere's own rebound / impact speed: eq. 7.2's
//!   definition, what the gaps between impacts measure (the plate is at rest
//!   again long before the next impact): the model's realised restitution,
//!   which [`DropEstimate::realised_per_triple`] pairs with each triple's
//!   estimate (its middle impact) and [`DropOutcome::realised_cor`] averages;
//! - `contact_cor`, the same relative to the plate: the contact law's own
//!   restitution. The two differ by the plate's speed when the sphere leaves
//!   (the plate is still ringing), at most `m (1 + e) / (e m_plate)`, 0.17 %
//!   for acrylic on the built-in plate.
//!
//! Both come out 0.1-0.2 % below the configured `e`: the `exact` restitution
//! mode calibrates a head-on impact on a fixed wall without gravity, and here
//! gravity acts during the contact and the plate takes energy into its ring.
//!
//! Once a rebound is slower than [`DropNumerics::rest_speed_fraction`] (2 %) of
//! the first impact's speed (a transducer pulse ~50 times below the first, a
//! fifth of the estimator's default threshold) or a contact lasts longer than
//! 1 ms, the sphere is taken to rest on the plate: the DEM stops and the rig
//! carries the sphere's weight to the end of the record.
//!
//! # Several heights
//!
//! [`summarise_drops`] gathers the drops of one sphere from several heights
//! into what `vlab drop` writes as `drop.json` ([`DropSummary`]): every
//! triple's estimate beside the model's realised restitution.

use crate::clock::Stopwatch;
use crate::rig::{DROP_RIG, RigFile};

use glam::DVec3;
use serde::Serialize;

use crate::dem::hertz_theory;
use crate::dem::material::{Material, effective_youngs_pa, sphere_mass_kg};
use crate::dem::{ContactLaw, Numerics, Particles, RestitutionMode, Walls, World};
use crate::rig::{DropRig, DropRigReport, DropRigSpec, Plate};
use crate::scene::SceneError;
use crate::scene::validity::sphere_wall_yield_velocity_mps;
use crate::signals::{
    DropTestResult, ImpactParams, SignalsError, Trace, TraceMetadata, estimate_cor,
};
use crate::stats::mean_std;
use crate::validation::{self, Bound, InvalidParameter, in_range, non_negative, positive, require};
use crate::warning::{FileKey, RunWarning};

pub mod series;

/// Gravity of the drop scene, m/s^2 (as the thesis scene).
pub const DROP_GRAVITY_MPS2: f64 = 9.81;
/// Default sphere diameter, m (the thesis' 5 mm spheres).
pub const DEFAULT_DIAMETER_M: f64 = 0.005;
/// Lowest drop height, m: below it the bounces come faster than the
/// estimator's 2 ms hold-off allows and sink into the transducer noise.
pub const MIN_HEIGHT_M: f64 = 1e-3;
/// Friction coefficient of the sphere on the plate, 1. Irrelevant to a
/// head-on drop (no tangential motion); stated for completeness.
pub const DROP_FRICTION: f64 = 0.3;

/// The built-in particles of the drop test (thesis Section 7.3).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DropParticle {
    /// Smooth acrylic sphere: measured COR 0.91 (thesis Fig. 7.5).
    AcrylicSmooth,
    /// 3D-printed acrylic sphere, rough: measured COR 0.83 (thesis Fig. 7.5).
    AcrylicPrinted,
    /// Hardened steel ball, e = 0.90: the value typically measured for steel
    /// balls on steel at low speed. The thesis measured no steel in the drop
    /// rig; against the steel plate it yields above 0.30 m/s (eq. 5.26), i.e.
    /// from a 4.5 mm drop, so most drops warn (the model's constant e then
    /// overstates it; the thesis quotes 0.57 at 2.4 m/s, Section 5.5.4).
    Steel,
}

impl DropParticle {
    /// All presets, in the order the CLI lists them.
    pub const ALL: [DropParticle; 3] = [
        DropParticle::AcrylicSmooth,
        DropParticle::AcrylicPrinted,
        DropParticle::Steel,
    ];

    /// Preset name (`acrylic-smooth`, ...).
    pub fn name(self) -> &'static str {
        match self {
            DropParticle::AcrylicSmooth => "acrylic-smooth",
            DropParticle::AcrylicPrinted => "acrylic-printed",
            DropParticle::Steel => "steel",
        }
    }

    /// Material name.
    pub fn material_name(self) -> &'static str {
        match self {
            DropParticle::AcrylicSmooth | DropParticle::AcrylicPrinted => "acrylic",
            DropParticle::Steel => "steel",
        }
    }

    /// Elastic constants (thesis Table 6.2 acrylic, Table 5.1 steel).
    pub fn material(self) -> Material {
        match self {
            DropParticle::AcrylicSmooth | DropParticle::AcrylicPrinted => Material::ACRYLIC,
            DropParticle::Steel => Material::STEEL,
        }
    }

    /// Coefficient of restitution on the plate, 1.
    pub fn restitution(self) -> f64 {
        match self {
            DropParticle::AcrylicSmooth => 0.91,
            DropParticle::AcrylicPrinted => 0.83,
            DropParticle::Steel => 0.90,
        }
    }

    /// The preset called `name`.
    pub fn from_name(name: &str) -> Option<DropParticle> {
        Self::ALL.into_iter().find(|p| p.name() == name)
    }
}

/// Numerical choices of the drop scene (module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DropNumerics {
    /// Rig ticks (and DEM steps in contact) per Hertz contact duration at the
    /// fastest impact.
    pub steps_per_contact: f64,
    /// Rig ticks per natural period of the plate.
    pub steps_per_ring_period: f64,
    /// Gap below which the DEM steps at the rig's tick, m.
    pub approach_margin_m: f64,
    /// Longest DEM step in free flight, s; the tick or less makes every step
    /// fine.
    pub max_flight_step_s: f64,
    /// The sphere is taken to rest once it rebounds slower than this fraction
    /// of the first impact's speed.
    pub rest_speed_fraction: f64,
}

impl Default for DropNumerics {
    fn default() -> Self {
        DropNumerics {
            steps_per_contact: 100.0,
            steps_per_ring_period: 100.0,
            approach_margin_m: 20e-6,
            max_flight_step_s: 1e-3,
            rest_speed_fraction: 0.02,
        }
    }
}

/// Everything that defines one drop.
#[derive(Debug, Clone, PartialEq)]
pub struct DropSetup {
    /// Name of the sphere for messages and metadata (`acrylic-smooth`, ...).
    pub particle_name: String,
    /// The sphere's material.
    pub material: Material,
    /// Sphere diameter, m.
    pub diameter_m: f64,
    /// Configured restitution of the sphere-plate contact, in (0, 1].
    pub restitution: f64,
    /// Friction coefficient, 1 (irrelevant head-on).
    pub friction: f64,
    /// Release height: gap between the sphere's bottom and the plate's top, m.
    pub height_m: f64,
    /// The rig (its sample rate is the record's).
    pub rig: DropRigSpec,
    /// Gravity, m/s^2.
    pub gravity_mps2: f64,
    /// Seed of the channel noise.
    pub seed: u64,
    /// Time stepping.
    pub numerics: DropNumerics,
}

impl DropSetup {
    /// A preset particle of the default diameter dropped from `height_m` on
    /// the built-in rig, seed 1.
    pub fn preset(particle: DropParticle, height_m: f64) -> Result<DropSetup, SceneError> {
        Ok(DropSetup {
            particle_name: particle.name().to_string(),
            material: particle.material(),
            diameter_m: DEFAULT_DIAMETER_M,
            restitution: particle.restitution(),
            friction: DROP_FRICTION,
            height_m,
            rig: DropRigSpec::builtin(DROP_RIG)?,
            gravity_mps2: DROP_GRAVITY_MPS2,
            seed: 1,
            numerics: DropNumerics::default(),
        })
    }

    /// Sphere radius, m.
    pub fn radius_m(&self) -> f64 {
        0.5 * self.diameter_m
    }

    /// Sphere mass, kg.
    pub fn sphere_mass_kg(&self) -> f64 {
        sphere_mass_kg(self.radius_m(), self.material.density_kgm3)
    }

    /// The plate's surface as a contact material (its density is never used:
    /// the plate is a DEM wall; its mass lives in the rig).
    pub fn plate_material(&self) -> Material {
        let p = &self.rig.plate;
        Material {
            youngs_pa: p.youngs_pa,
            poisson: p.poisson,
            density_kgm3: f64::INFINITY,
            yield_strength_pa: p.yield_strength_pa,
        }
    }

    /// "acrylic-smooth sphere on the steel plate"-like label.
    pub fn pair_label(&self) -> String {
        format!(
            "{} sphere on the {} plate",
            self.particle_name, self.rig.name
        )
    }

    /// Speed of the first impact, `sqrt(2 g h)`, m/s.
    pub fn first_impact_speed_mps(&self) -> f64 {
        (2.0 * self.gravity_mps2 * self.height_m).sqrt()
    }

    /// Hertz contact duration (eq. 5.10) of the sphere on the plate at
    /// `speed_mps`, s.
    pub fn contact_duration_s(&self, speed_mps: f64) -> f64 {
        hertz_theory::contact_duration_s(
            self.sphere_mass_kg(),
            effective_youngs_pa(&self.material, &self.plate_material()),
            self.radius_m(),
            speed_mps,
        )
    }

    /// Yield velocity of the sphere on the plate (eq. 5.26), m/s.
    pub fn yield_velocity_mps(&self) -> Option<f64> {
        sphere_wall_yield_velocity_mps(&self.material, &self.plate_material(), self.radius_m())
    }

    /// The transducer's first pulse at the fastest impact and the lowest
    /// sample rate that puts one sample in it.
    pub fn min_sample_rate_hz(&self) -> Result<SamplingLimit, SceneError> {
        let plate = Plate::from_spec(&self.rig)?;
        let pulse =
            plate.first_pulse_duration_s(self.contact_duration_s(self.first_impact_speed_mps()));
        Ok(SamplingLimit {
            first_pulse_s: pulse,
            min_rate_hz: 1.0 / pulse,
        })
    }

    /// A warning when the sample rate resolves the impacts only barely: fewer
    /// than two samples per first pulse, or the plate's ring above the Nyquist
    /// frequency (it aliases). Point-sampled, an impact can then be caught near
    /// its zero crossings, timed a ring period late or missed altogether; the
    /// estimate shows a missed impact as a triple with `e > 1`. The sample
    /// rate is named by its rig key, `daq.sample_rate_hz`.
    pub fn sampling_warning(&self) -> Result<Option<RunWarning>, SceneError> {
        self.sampling_warning_naming("daq.sample_rate_hz")
    }

    /// [`DropSetup::sampling_warning`] with the sample rate named `name` (a
    /// caller's own name for the value: the flag that set it); the warning's
    /// advice is the rig key, `daq.sample_rate_hz`.
    pub fn sampling_warning_naming(&self, name: &str) -> Result<Option<RunWarning>, SceneError> {
        let fs = self.rig.daq.sample_rate_hz;
        let pulse = self.min_sample_rate_hz()?.first_pulse_s;
        let ring_hz = Plate::from_spec(&self.rig)?.ring_freq_hz();
        let good = (2.0 / pulse).max(2.0 * ring_hz);
        if fs >= good {
            return Ok(None);
        }
        let text = format!(
            "{name} {fs} Hz barely resolves the impacts: the transducer's first pulse \
             ({:.1} us) spans {:.1} sample periods and the plate's {:.1} kHz ring is {} the \
             {:.1} kHz Nyquist frequency, so an impact can be sampled near its zero crossings, \
             timed a ring period late or missed (use at least {:.0} Hz, or a lower detection \
             threshold; the thesis used 200000 Hz)",
            1e6 * pulse,
            pulse * fs,
            ring_hz / 1e3,
            if 2.0 * ring_hz > fs { "above" } else { "below" },
            fs / 2e3,
            good.ceil()
        );
        Ok(Some(RunWarning::advising(
            text,
            FileKey("daq.sample_rate_hz"),
        )))
    }

    /// The rig's tick (module docs), s.
    pub fn tick_s(&self) -> f64 {
        let tc = self.contact_duration_s(self.first_impact_speed_mps());
        let ring = 1.0 / self.rig.plate_natural_freq_hz();
        let h_max =
            (tc / self.numerics.steps_per_contact).min(ring / self.numerics.steps_per_ring_period);
        let period = 1.0 / self.rig.daq.sample_rate_hz;
        period / (period / h_max).ceil()
    }

    /// Impact times of an ideal bounce with the configured restitution and a
    /// rigid plate, s: `t_1 = sqrt(2 h / g)`, then gaps `2 v_1 e^k / g`,
    /// `k = 1, 2, ...`.
    pub fn predicted_impact_times_s(&self, count: usize) -> Vec<f64> {
        let g = self.gravity_mps2;
        let v1 = self.first_impact_speed_mps();
        let mut t = (2.0 * self.height_m / g).sqrt();
        let mut out = Vec::with_capacity(count);
        for k in 0..count {
            out.push(t);
            t += 2.0 * v1 * self.restitution.powi(k as i32 + 1) / g;
        }
        out
    }

    /// Checks every value; a refusal ([`SceneError::Invalid`]) names the field
    /// (or rig key), its unit and valid range. The sample rate or height
    /// refused because the record could not hold the impacts is one too: its
    /// valid range says why.
    pub fn validate(&self) -> Result<(), SceneError> {
        self.material.validate().map_err(|e| e.within("material"))?;
        in_range(
            "diameter_m",
            self.diameter_m,
            "m",
            Bound::Open(0.0),
            Bound::Closed(0.1),
        )?;
        let e = validation::restitution("restitution", self.restitution)?;
        validation::friction("friction", self.friction)?;
        let h = positive("height_m", self.height_m, "m")?;
        require(
            h >= MIN_HEIGHT_M,
            "height_m",
            h,
            "m",
            format!(
                "at least {MIN_HEIGHT_M} m: lower bounces come faster than the estimator's 2 ms \
                 hold-off and sink into the transducer noise"
            ),
        )?;
        let g = positive("gravity_mps2", self.gravity_mps2, "m/s^2")?;
        self.rig.validate()?;
        let fs = self.rig.daq.sample_rate_hz;
        let SamplingLimit {
            first_pulse_s: pulse,
            min_rate_hz: min_rate,
        } = self.min_sample_rate_hz()?;
        if fs < min_rate {
            let v = self.first_impact_speed_mps();
            return Err(InvalidParameter::new(
                "daq.sample_rate_hz",
                fs,
                "Hz",
                format!(
                    "at least {:.0} Hz to resolve the impacts: a contact of the {} at {v:.3} m/s \
                     lasts {:.1} us (Hertz, thesis eq. 5.10) and the transducer's first pulse \
                     {:.1} us (the plate rings at {:.1} kHz); one sample per pulse is the least \
                     (the thesis used 200000 Hz)",
                    min_rate.ceil(),
                    self.pair_label(),
                    1e6 * self.contact_duration_s(v),
                    1e6 * pulse,
                    Plate::from_spec(&self.rig)?.ring_freq_hz() / 1e3,
                ),
            )
            .into());
        }
        // Four impacts, the last at least 5 ms before the end of the record.
        let length = self.rig.record.length_s;
        let fourth = self.predicted_impact_times_s(4)[3];
        let room = length - 5e-3;
        if fourth > room {
            // t_4 = sqrt(2 h / g) (1 + 2 (e + e^2 + e^3)).
            let factor = 1.0 + 2.0 * (e + e * e + e * e * e);
            let max_height_m = 0.5 * g * (room.max(0.0) / factor).powi(2);
            return Err(InvalidParameter::new(
                "height_m",
                h,
                "m",
                format!(
                    "at most {max_height_m:.3} m: from higher the fourth impact would come at \
                     {fourth:.3} s, too late for the {length} s record (record.length_s of rig \
                     '{}'), and the estimator needs four impacts for two triples",
                    self.rig.name
                ),
            )
            .into());
        }
        let n = self.numerics;
        let at_least_20 =
            |key: &str, x: f64| in_range(key, x, "", Bound::Closed(20.0), Bound::Unbounded);
        at_least_20("numerics.steps_per_contact", n.steps_per_contact)?;
        at_least_20("numerics.steps_per_ring_period", n.steps_per_ring_period)?;
        positive("numerics.approach_margin_m", n.approach_margin_m, "m")?;
        positive("numerics.max_flight_step_s", n.max_flight_step_s, "s")?;
        non_negative("numerics.rest_speed_fraction", n.rest_speed_fraction, "")?;
        Ok(())
    }
}

/// One contact of the sphere with the plate, as the DEM resolved it.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct DemImpact {
    /// Contact start (overlap crosses zero), s from the release.
    pub onset_time_s: f64,
    /// Contact end, s.
    pub end_time_s: f64,
    /// Sphere's speed at the start, m/s (downward).
    pub arrival_speed_mps: f64,
    /// Sphere's speed at the end, m/s (upward).
    pub departure_speed_mps: f64,
    /// `departure / arrival`: the sphere's own restitution (eq. 7.2).
    pub bounce_cor: f64,
    /// The same relative to the plate: the contact law's restitution.
    pub contact_cor: f64,
    /// Largest contact force, N.
    pub peak_contact_force_n: f64,
}

/// The transducer's first pulse at a drop's fastest impact and the lowest
/// sample rate that puts one sample in it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SamplingLimit {
    /// Duration of the first pulse, s.
    pub first_pulse_s: f64,
    /// `1 / first_pulse_s`, Hz.
    pub min_rate_hz: f64,
}

/// What one drop produced.
#[derive(Debug, Clone)]
pub struct DropOutcome {
    /// The force record (channel `force`, N, from the release).
    pub trace: Trace,
    /// The rig's report (clipping, full scale).
    pub rig_report: DropRigReport,
    /// Every contact, in order.
    pub impacts: Vec<DemImpact>,
    /// The rig's tick and the DEM step in contact, s.
    pub tick_s: f64,
    /// DEM steps taken, all kinds.
    pub dem_steps: u64,
    /// DEM steps taken at the tick.
    pub fine_steps: u64,
    /// When the sphere was taken to rest, s (None: still bouncing at the end).
    pub rest_time_s: Option<f64>,
    /// Hertz contact duration at the first impact, s.
    pub first_contact_duration_s: f64,
    /// Wall-clock time of the run, s.
    pub wall_time_s: f64,
}

/// The estimator's result on a drop record, with the DEM's truth for each triple.
#[derive(Debug, Clone)]
pub struct DropEstimate {
    /// Detected impacts and the restitution from their gaps.
    pub result: DropTestResult,
    /// For each detected impact, the DEM contact it belongs to: the nearest
    /// whose start lies between 1 ms before the detected onset and two sample
    /// periods after it.
    pub matched: Vec<Option<usize>>,
    /// For each triple, the DEM `bounce_cor` of its middle impact.
    pub realised_per_triple: Vec<Option<f64>>,
}

impl DropEstimate {
    /// Mean of the realised restitution over the triples that have one.
    pub fn realised_mean(&self) -> Option<f64> {
        let v: Vec<f64> = self.realised_per_triple.iter().flatten().copied().collect();
        (!v.is_empty()).then(|| v.iter().sum::<f64>() / v.len() as f64)
    }
}

impl DropOutcome {
    /// Runs the estimator on the record (channel `force`, gravity `g_mps2`)
    /// and pairs each triple with the realised restitution of its middle impact.
    pub fn estimate(
        &self,
        params: &ImpactParams,
        g_mps2: f64,
    ) -> Result<DropEstimate, SignalsError> {
        let result = estimate_cor(&self.trace, crate::rig::DROP_FORCE_CHANNEL, params, g_mps2)?;
        // A detected onset lies after the contact's start by the pulse's rise
        // to the threshold, or up to two sample periods before it when the
        // interpolated crossing undershoots between coarse samples.
        let early = 2.0 / self.trace.sample_rate_hz;
        let matched: Vec<Option<usize>> = result
            .detection
            .impacts
            .iter()
            .map(|imp| {
                self.impacts
                    .iter()
                    .enumerate()
                    .filter(|(_, d)| {
                        let lag = imp.onset_time_s - d.onset_time_s;
                        lag > -early && lag < 1e-3
                    })
                    .min_by(|(_, a), (_, b)| {
                        let da = (imp.onset_time_s - a.onset_time_s).abs();
                        let db = (imp.onset_time_s - b.onset_time_s).abs();
                        da.total_cmp(&db)
                    })
                    .map(|(i, _)| i)
            })
            .collect();
        let realised_per_triple = (0..result.cor.cor_per_triple.len())
            .map(|k| matched[k + 1].map(|i| self.impacts[i].bounce_cor))
            .collect();
        Ok(DropEstimate {
            result,
            matched,
            realised_per_triple,
        })
    }

    /// Mean `bounce_cor` over all contacts: the model's realised restitution.
    pub fn realised_cor(&self) -> Option<f64> {
        (!self.impacts.is_empty()).then(|| {
            self.impacts.iter().map(|d| d.bounce_cor).sum::<f64>() / self.impacts.len() as f64
        })
    }
}

/// A contact in progress.
#[derive(Debug, Clone, Copy)]
struct OpenContact {
    onset_time_s: f64,
    arrival_mps: f64,
    relative_arrival_mps: f64,
    peak_force_n: f64,
}

/// Runs one drop: release, bounces, rest, to the end of the rig's record.
pub fn run_drop(setup: &DropSetup) -> Result<DropOutcome, SceneError> {
    setup.validate()?;
    let start = Stopwatch::start();
    let tick = setup.tick_s();
    let mut rig = DropRig::new(&setup.rig, tick, setup.seed)?;
    let length = setup.rig.record.length_s;
    let n_ticks = (length / tick).round() as u64;
    rig.reserve(length);
    let mut world = drop_world(setup, tick)?;
    let log = bounce_to_the_end(setup, &mut rig, &mut world, tick, n_ticks)?;
    let (trace, rig_report) = rig.finish(drop_metadata(setup))?;
    Ok(DropOutcome {
        trace,
        rig_report,
        impacts: log.impacts,
        tick_s: tick,
        dem_steps: world.steps,
        fine_steps: log.fine_steps,
        rest_time_s: log.rest_time_s,
        first_contact_duration_s: setup.contact_duration_s(setup.first_impact_speed_mps()),
        wall_time_s: start.elapsed().as_secs_f64(),
    })
}

/// The drop scene's world at time step `tick_s`: the sphere at rest at its
/// release height above the plate, under gravity.
fn drop_world(setup: &DropSetup, tick_s: f64) -> Result<World, SceneError> {
    let r = setup.radius_m();
    let law = ContactLaw::new(
        &setup.material,
        &setup.plate_material(),
        setup.restitution,
        setup.friction,
        RestitutionMode::Exact,
    );
    let mut particles = Particles::default();
    particles.push(
        DVec3::new(0.0, 0.0, r + setup.height_m),
        DVec3::ZERO,
        DVec3::ZERO,
        r,
        setup.material.density_kgm3,
    );
    Ok(World::new(
        particles,
        Walls::plate(),
        law,
        law,
        DVec3::new(0.0, 0.0, -setup.gravity_mps2),
        Numerics::with_dt(tick_s),
    )?)
}

/// The metadata of a drop's force record.
fn drop_metadata(setup: &DropSetup) -> TraceMetadata {
    TraceMetadata {
        source: format!(
            "vlab {} drop: {} ({} m, e = {}) from {} m",
            env!("CARGO_PKG_VERSION"),
            setup.particle_name,
            setup.diameter_m,
            setup.restitution,
            setup.height_m
        ),
        ..Default::default()
    }
}

/// Steps the rig to `n_ticks` of `tick_s` and the DEM with it (module docs:
/// one long step in free flight, the tick near and in contact), the plate
/// carrying the sphere's weight once it rests.
fn bounce_to_the_end(
    setup: &DropSetup,
    rig: &mut DropRig,
    world: &mut World,
    tick_s: f64,
    n_ticks: u64,
) -> Result<BounceLog, SceneError> {
    let tick = tick_s;
    let g = setup.gravity_mps2;
    let r = setup.radius_m();
    let nums = setup.numerics;
    let weight_n = world.particles.mass[0] * g;
    let max_flight_ticks = ((nums.max_flight_step_s / tick).floor() as u64).max(1);
    let rest_speed = nums.rest_speed_fraction * setup.first_impact_speed_mps();
    let mut force_on_plate = 0.0;
    let mut log = BounceLog {
        impacts: Vec::new(),
        open: None,
        rest_time_s: None,
        fine_steps: 0,
        prev: (0.0, -setup.height_m, 0.0, 0.0),
    };
    while rig.ticks() < n_ticks {
        if log.rest_time_s.is_some() {
            rig.tick(-weight_n);
            continue;
        }
        let z = world.particles.position[0].z;
        let v = world.particles.velocity[0].z;
        let gap = z - r - rig.plate().displacement_m();
        let n = if log.open.is_none() && gap > nums.approach_margin_m {
            // Time for the free-flight parabola to come down to the margin.
            let d = gap - nums.approach_margin_m;
            let t_reach = (v + (v * v + 2.0 * g * d).sqrt()) / g;
            ((t_reach / tick).floor() as u64)
                .clamp(1, max_flight_ticks)
                .min(n_ticks - rig.ticks())
        } else {
            1
        };
        let mut x = rig.plate().displacement_m();
        for _ in 0..n {
            x = rig.tick(force_on_plate);
        }
        world.numerics.dt_s = n as f64 * tick;
        world.step(x)?;
        if n == 1 {
            log.fine_steps += 1;
        }
        force_on_plate = -world.wall_force().z;
        let z = world.particles.position[0].z;
        let after = (
            rig.time_s(),
            r - (z - x),
            world.particles.velocity[0].z,
            rig.plate().velocity_mps(),
        );
        log.record(after, force_on_plate, g, rest_speed);
    }
    Ok(log)
}

/// The contacts of a drop so far.
#[derive(Debug, Clone)]
struct BounceLog {
    /// Every contact closed, in order.
    impacts: Vec<DemImpact>,
    /// The contact in progress.
    open: Option<OpenContact>,
    /// When the sphere was taken to rest, s.
    rest_time_s: Option<f64>,
    /// DEM steps taken at the tick.
    fine_steps: u64,
    /// State after the previous DEM step: time, overlap, sphere velocity, plate velocity.
    prev: (f64, f64, f64, f64),
}

impl BounceLog {
    /// Takes the state after a DEM step, `(t, overlap, v, vp)` as
    /// [`BounceLog::prev`], with the sphere's force on the plate: opens,
    /// follows or closes a contact (onset and end interpolated at the
    /// overlap's zero crossing, speeds from the free-flight parabola), and
    /// takes the sphere to rest after a rebound slower than `rest_speed` or a
    /// millisecond pressed onto the plate.
    fn record(
        &mut self,
        after: (f64, f64, f64, f64),
        force_on_plate: f64,
        g: f64,
        rest_speed: f64,
    ) {
        let (t, overlap, v, vp) = after;
        let (t0, overlap0, v0, vp0) = self.prev;
        match self.open.as_mut() {
            None if overlap > 0.0 => {
                let frac = (-overlap0 / (overlap - overlap0)).clamp(0.0, 1.0);
                let t_on = t0 + frac * (t - t0);
                let v_on = v0 - g * (t_on - t0);
                self.open = Some(OpenContact {
                    onset_time_s: t_on,
                    arrival_mps: -v_on,
                    relative_arrival_mps: vp0 - v_on,
                    peak_force_n: force_on_plate.abs(),
                });
            }
            Some(c) if overlap > 0.0 => {
                c.peak_force_n = c.peak_force_n.max(force_on_plate.abs());
                if t - c.onset_time_s > 1e-3 {
                    // Pressed onto the plate for a millisecond: at rest.
                    self.rest_time_s = Some(t);
                }
            }
            Some(c) => {
                let frac = (overlap0 / (overlap0 - overlap)).clamp(0.0, 1.0);
                let t_off = t0 + frac * (t - t0);
                let v_off = v + g * (t - t_off);
                self.impacts.push(DemImpact {
                    onset_time_s: c.onset_time_s,
                    end_time_s: t_off,
                    arrival_speed_mps: c.arrival_mps,
                    departure_speed_mps: v_off,
                    bounce_cor: v_off / c.arrival_mps,
                    contact_cor: (v_off - vp) / c.relative_arrival_mps,
                    peak_contact_force_n: c.peak_force_n,
                });
                self.open = None;
                if v_off < rest_speed {
                    self.rest_time_s = Some(t_off);
                }
            }
            None => {}
        }
        self.prev = after;
    }
}

/// Text for a height in a file name: 0.05 -> "50", 0.0125 -> "12.5" (mm).
pub fn millimetres(h_m: f64) -> String {
    format!("{}", (h_m * 1e6).round() / 1e3)
}

/// One height's record and what was made of it.
#[derive(Debug, Clone, Serialize)]
pub struct DropRunSummary {
    pub height_m: f64,
    /// `sqrt(2 g h)`, m/s.
    pub first_impact_speed_mps: f64,
    /// Hertz contact duration at the first impact (eq. 5.10), s.
    pub contact_duration_s: f64,
    pub impacts_detected: usize,
    pub onset_times_s: Vec<f64>,
    /// COR of each triple (eq. 7.5).
    pub cor_per_triple: Vec<f64>,
    /// Speed at the middle impact of each triple (eq. 7.3), m/s.
    pub impact_speeds_mps: Vec<f64>,
    pub cor_mean: f64,
    pub cor_std: f64,
    /// DEM restitution (bounce) of each triple's middle impact.
    pub realised_model_cor_per_triple: Vec<Option<f64>>,
    pub realised_model_cor: Option<f64>,
    /// Triples whose gaps grew (a missed or false impact).
    pub growing_gap_triples: Vec<usize>,
    pub threshold_n: f64,
    pub holdoff_s: f64,
    pub peak_transducer_force_n: f64,
    pub clipped_samples: u64,
    /// Every contact the DEM resolved.
    pub dem_impacts: Vec<DemImpact>,
    pub rest_time_s: Option<f64>,
    pub tick_s: f64,
    pub dem_steps: u64,
    pub fine_steps: u64,
    pub wall_time_s: f64,
    /// The record's files: `force-h<mm>mm.csv`, `.wav`, `.wav.json`.
    pub files: Vec<String>,
}

/// Everything `drop.json` says about a drop test of one sphere from one or
/// several heights.
#[derive(Debug, Clone, Serialize)]
pub struct DropSummary {
    pub vlab_version: &'static str,
    pub particle: String,
    pub material: &'static str,
    pub diameter_m: f64,
    /// The contact law's configured restitution (exact mode).
    pub configured_cor: f64,
    pub rig: String,
    pub sample_rate_hz: f64,
    pub gravity_mps2: f64,
    pub seed: u64,
    /// Mean of every triple's COR over all heights.
    pub cor_mean: f64,
    /// Sample standard deviation of the same.
    pub cor_std: f64,
    pub cor_per_triple: Vec<f64>,
    /// Speed at each triple's middle impact, m/s.
    pub impact_speeds_mps: Vec<f64>,
    /// Heights of each triple, m.
    pub heights_m: Vec<f64>,
    /// Mean DEM restitution of the triples' middle impacts: the sphere's own
    /// rebound / impact speed (eq. 7.2).
    pub realised_model_cor: Option<f64>,
    pub realised_model_cor_per_triple: Vec<Option<f64>>,
    /// The same relative to the moving plate: the contact law's restitution.
    pub realised_contact_cor: Option<f64>,
    /// `cor_mean / realised_model_cor - 1`.
    pub cor_error_rel: Option<f64>,
    /// Yield velocity of the sphere on the plate (eq. 5.26), m/s.
    pub yield_velocity_mps: Option<f64>,
    /// Lowest accepted sample rate: one sample per first pulse, Hz.
    pub min_sample_rate_hz: f64,
    pub warnings: Vec<RunWarning>,
    pub runs: Vec<DropRunSummary>,
    pub files: Vec<String>,
}

/// What `drop.json` says about one height's drop `out` from set-up `s` and
/// the estimate `est` made on its record.
fn run_summary(s: &DropSetup, out: &DropOutcome, est: &DropEstimate) -> DropRunSummary {
    let cor = &est.result.cor;
    let n = cor.cor_per_triple.len();
    let speeds = cor.impact_speeds_mps[..n].to_vec();
    let stem = format!("force-h{}mm", millimetres(s.height_m));
    DropRunSummary {
        height_m: s.height_m,
        first_impact_speed_mps: s.first_impact_speed_mps(),
        contact_duration_s: out.first_contact_duration_s,
        impacts_detected: est.result.detection.impacts.len(),
        onset_times_s: est.result.detection.onset_times_s(),
        cor_per_triple: cor.cor_per_triple.clone(),
        impact_speeds_mps: speeds,
        cor_mean: cor.cor_mean,
        cor_std: cor.cor_std,
        realised_model_cor_per_triple: est.realised_per_triple.clone(),
        realised_model_cor: est.realised_mean(),
        growing_gap_triples: cor.growing_gaps(),
        threshold_n: est.result.detection.threshold_n,
        holdoff_s: est.result.detection.holdoff_s,
        peak_transducer_force_n: out.rig_report.peak_transducer_force_n,
        clipped_samples: out.rig_report.clipped,
        dem_impacts: out.impacts.clone(),
        rest_time_s: out.rest_time_s,
        tick_s: out.tick_s,
        dem_steps: out.dem_steps,
        fine_steps: out.fine_steps,
        wall_time_s: out.wall_time_s,
        files: vec![
            format!("{stem}.csv"),
            format!("{stem}.wav"),
            format!("{stem}.wav.json"),
        ],
    }
}

/// The summary of drops `setups` (the same sphere and rig from one or
/// several heights; at least one) and their `runs`, with the `warnings` the
/// caller has for them; `material` names the sphere's material.
pub fn summarise_drops(
    setups: &[DropSetup],
    runs: &[(DropOutcome, DropEstimate)],
    material: &'static str,
    warnings: Vec<RunWarning>,
) -> Result<DropSummary, SceneError> {
    let first = setups
        .first()
        .ok_or_else(|| InvalidParameter::new("setups", "[]", "", "a list of at least one drop"))?;
    let mut all_cor = Vec::new();
    let mut all_speed = Vec::new();
    let mut all_height = Vec::new();
    let mut all_realised = Vec::new();
    let mut contact = Vec::new();
    let mut run_summaries = Vec::new();
    for (s, (out, est)) in setups.iter().zip(runs) {
        let cor = &est.result.cor;
        let n = cor.cor_per_triple.len();
        all_cor.extend_from_slice(&cor.cor_per_triple);
        all_speed.extend_from_slice(&cor.impact_speeds_mps[..n]);
        all_height.extend(std::iter::repeat_n(s.height_m, n));
        all_realised.extend_from_slice(&est.realised_per_triple);
        contact
            .extend((0..n).filter_map(|k| est.matched[k + 1].map(|i| out.impacts[i].contact_cor)));
        run_summaries.push(run_summary(s, out, est));
    }
    let cor = mean_std(&all_cor);
    let realised: Vec<f64> = all_realised.iter().flatten().copied().collect();
    let realised_model_cor = (!realised.is_empty()).then(|| mean_std(&realised).mean);
    let mut files: Vec<String> = run_summaries.iter().flat_map(|r| r.files.clone()).collect();
    files.extend(
        [
            "results.csv",
            "cor-vs-speed.svg",
            "cor-vs-speed.png",
            "drop.json",
        ]
        .map(String::from),
    );
    let mut min_sample_rate_hz = 0.0f64;
    for s in setups {
        min_sample_rate_hz = min_sample_rate_hz.max(s.min_sample_rate_hz()?.min_rate_hz);
    }
    Ok(DropSummary {
        vlab_version: env!("CARGO_PKG_VERSION"),
        particle: first.particle_name.clone(),
        material,
        diameter_m: first.diameter_m,
        configured_cor: first.restitution,
        rig: first.rig.name.clone(),
        sample_rate_hz: first.rig.daq.sample_rate_hz,
        gravity_mps2: first.gravity_mps2,
        seed: first.seed,
        cor_mean: cor.mean,
        cor_std: cor.std,
        cor_per_triple: all_cor,
        impact_speeds_mps: all_speed,
        heights_m: all_height,
        realised_model_cor,
        realised_model_cor_per_triple: all_realised,
        realised_contact_cor: (!contact.is_empty()).then(|| mean_std(&contact).mean),
        cor_error_rel: realised_model_cor.map(|r| cor.mean / r - 1.0),
        yield_velocity_mps: first.yield_velocity_mps(),
        min_sample_rate_hz,
        warnings,
        runs: run_summaries,
        files,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn presets_and_predicted_schedule() {
        let s = DropSetup::preset(DropParticle::AcrylicSmooth, 0.05).expect("preset");
        assert_eq!(DropParticle::from_name("steel"), Some(DropParticle::Steel));
        assert_eq!(DropParticle::from_name("glass"), None);
        // First impact at sqrt(2 h / g) = 0.1010 s, 0.990 m/s; gaps 2 v e^k / g.
        let t = s.predicted_impact_times_s(3);
        assert!((t[0] - 0.100_96).abs() < 1e-5);
        assert!((t[1] - t[0] - 2.0 * 0.990_45 * 0.91 / 9.81).abs() < 1e-4);
        assert!(((t[2] - t[1]) / (t[1] - t[0]) - 0.91).abs() < 1e-12);
        // 5 mm acrylic on steel at 0.99 m/s: about 32 us (hand estimate 2.87 (m^2 / E*^2 R v)^0.2).
        let tc = s.contact_duration_s(s.first_impact_speed_mps());
        assert!((tc - 32.2e-6).abs() < 0.5e-6, "{tc}");
        // Tick: an integer fraction of 5 us, at most t_c / 100.
        let h = s.tick_s();
        assert!(
            h <= tc / 100.0 && (5e-6 / h - (5e-6 / h).round()).abs() < 1e-9,
            "{h}"
        );
    }

    #[test]
    fn validation_names_field_unit_and_range() {
        let msg = |f: &dyn Fn(&mut DropSetup)| {
            let mut s = DropSetup::preset(DropParticle::AcrylicSmooth, 0.05).expect("preset");
            f(&mut s);
            s.validate().expect_err("refused").to_string()
        };
        assert_eq!(
            msg(&|s| s.height_m = 0.0),
            "height_m = 0 m: must be positive and finite"
        );
        assert!(msg(&|s| s.height_m = -0.01).starts_with("height_m = -0.01 m:"));
        assert!(msg(&|s| s.height_m = 0.0005).contains("at least 0.001 m"));
        let high = msg(&|s| s.height_m = 1.0);
        assert!(
            high.starts_with("height_m = 1 m: must be at most 0.545 m")
                && high.contains("the 2 s record"),
            "{high}"
        );
        assert!(msg(&|s| s.restitution = 1.2).contains("(0, 1]"));
        let slow = msg(&|s| s.rig.daq.sample_rate_hz = 10_000.0);
        assert!(
            slow.starts_with("daq.sample_rate_hz = 10000 Hz: must be at least 1")
                && slow.contains("lasts 32."),
            "{slow}"
        );
    }
}
