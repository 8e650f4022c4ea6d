//! Motional phases: indicators measured on a driven bed and a heuristic that
//! names the phase (thesis Sections 6.3–6.4 and 7.6).
//!
//! The thesis named each condition's phase by watching animations and velocity
//! fields (Section 6.3); vlab measures what those observations rest on:
//!
//! From the force record (the particles' axial force on the enclosure, which a
//! lab gets as force − m_enclosure · acceleration, Section 7.6):
//! - **collective impacts** per cycle: short pulses in which the bed as a whole
//!   strikes an end cap, far above what a bed moving with the enclosure needs
//!   (`|F| > IMPACT_FORCE_FACTOR · M g (Γ + 1)`, M the particle mass) and
//!   carrying a sizeable share of the bed's momentum (impulse at least
//!   `IMPACT_MIN_IMPULSE · M Γ g / ω`), counted apart for the bottom cap and
//!   the lid (whichever way gravity points), with their mean impulse;
//! - their **phase** relative to the nearest peak of the enclosure's speed
//!   (degrees of the drive cycle, negative before the peak): the thesis' optimum
//!   bouncing bed and fluidisation strike at the velocity peak (Fig. 6.10, 6.18,
//!   7.12, 7.15), stronger drives earlier.
//!
//! From the DEM state, sampled [`SAMPLES_PER_CYCLE`] times a steady cycle:
//! - the **fraction of particles in contact** (with anything), its mean and
//!   its lowest value in a cycle;
//! - the **bed's centre of mass relative to the enclosure** along the drive
//!   axis: its mean offset from the settled bed and its excursion over a cycle,
//!   both divided by the effective clearance (eq. 6.13 with close packing);
//! - the **granular temperature** `Σ m |v − v_cm|² / (3 M)`, the particles'
//!   velocity fluctuation about the bed's mean, divided by the enclosure's peak
//!   speed squared, (Γ g / ω)².
//!
//! [`classify`] is a **heuristic**, not a definition: fixed thresholds on these
//! indicators, chosen on the thesis damper (358 spheres of 5 mm, fill 0.466,
//! vertical, 20–80 Hz) and documented on [`PhaseThresholds`]. Phases change
//! gradually (the thesis says so), so a condition near a boundary can take
//! either name; other beds may need other thresholds.

use glam::DVec3;
use serde::{Deserialize, Serialize};

use crate::dem::World;
use crate::drive::Drive;
use crate::experiment::damper::{Kinematics, StepObserver};
use crate::experiment::record::TruthSamples;

/// DEM samples per steady cycle for the state indicators.
pub const SAMPLES_PER_CYCLE: u32 = 64;

/// A collective impact is a force pulse above this multiple of the largest
/// force a bed moving with the enclosure needs, `M g (Γ + 1)`...
pub const IMPACT_FORCE_FACTOR: f64 = 2.0;
/// ... whose impulse is at least this multiple of the bed's momentum at the
/// enclosure's peak speed, `M Γ g / ω` (a bed meeting the enclosure head-on
/// and stopping dead on it transfers 2). Weaker pulses are single particles
/// or a loose cloud landing (thesis: the collisions' intensity falls in the
/// convection phases, Section 6.4.3.2).
pub const IMPACT_MIN_IMPULSE: f64 = 0.25;

/// The motional phases the heuristic names (thesis Sections 2.5, 6.4).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
pub enum MotionalPhase {
    /// The bed moves with the enclosure; negligible relative motion (Section 6.4.2).
    #[serde(rename = "solid-like")]
    SolidLike,
    /// Once a cycle the bed strikes the enclosure and loosens near the free
    /// surface, the deep layers staying packed (local fluidisation, Fig. 6.20).
    #[serde(rename = "local fluidisation")]
    LocalFluidisation,
    /// The whole bed lifts off and loosens once a cycle (global fluidisation and
    /// the transition phase, Fig. 6.19–6.20).
    #[serde(rename = "global fluidisation")]
    GlobalFluidisation,
    /// The packed bed flies across the clearance and strikes both end caps each
    /// cycle (Section 6.4.1).
    #[serde(rename = "bouncing bed")]
    BouncingBed,
    /// An elevated, agitated cloud over fast particles, no strong collective
    /// impact (Leidenfrost effect, buoyancy convection, Fig. 6.21).
    #[serde(rename = "convection/Leidenfrost")]
    ConvectionLeidenfrost,
}

impl MotionalPhase {
    /// The name written in files and plots.
    pub fn as_str(self) -> &'static str {
        match self {
            MotionalPhase::SolidLike => "solid-like",
            MotionalPhase::LocalFluidisation => "local fluidisation",
            MotionalPhase::GlobalFluidisation => "global fluidisation",
            MotionalPhase::BouncingBed => "bouncing bed",
            MotionalPhase::ConvectionLeidenfrost => "convection/Leidenfrost",
        }
    }

    /// A short tag for map cells.
    pub fn abbreviation(self) -> &'static str {
        match self {
            MotionalPhase::SolidLike => "S",
            MotionalPhase::LocalFluidisation => "LF",
            MotionalPhase::GlobalFluidisation => "GF",
            MotionalPhase::BouncingBed => "BB",
            MotionalPhase::ConvectionLeidenfrost => "C",
        }
    }

    /// Parses [`MotionalPhase::as_str`].
    pub fn parse(s: &str) -> Option<Self> {
        [
            MotionalPhase::SolidLike,
            MotionalPhase::LocalFluidisation,
            MotionalPhase::GlobalFluidisation,
            MotionalPhase::BouncingBed,
            MotionalPhase::ConvectionLeidenfrost,
        ]
        .into_iter()
        .find(|p| p.as_str() == s)
    }
}

/// The indicators of one driven condition, over its steady cycles.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PhaseIndicators {
    /// Collective impacts per cycle, both end caps.
    pub impacts_per_cycle: f64,
    /// Of which on the bottom cap (z = 0 of the enclosure).
    pub bottom_impacts_per_cycle: f64,
    /// Of which on the lid (z = L).
    pub lid_impacts_per_cycle: f64,
    /// Mean phase of the impacts from the nearest enclosure-speed peak
    /// (degrees, negative before the peak); NaN without impacts.
    pub impact_phase_deg: f64,
    /// Mean impulse of an impact / (M Γ g / ω): 2 for a bed that meets the
    /// enclosure head-on at its peak speed and stops dead on it; NaN without impacts.
    pub impact_impulse_rel: f64,
    /// Mean fraction of particles touching something.
    pub contact_fraction: f64,
    /// Lowest fraction of particles touching something in a cycle (mean over cycles).
    pub contact_fraction_min: f64,
    /// Mean offset of the bed's centre of mass from the settled bed, along the
    /// axis, / effective clearance.
    pub com_offset_rel: f64,
    /// Excursion (max − min) of the bed's centre of mass relative to the
    /// enclosure in a cycle, / effective clearance (mean over cycles).
    pub com_range_rel: f64,
    /// Granular temperature / (Γ g / ω)².
    pub granular_temperature_rel: f64,
}

/// Thresholds of the heuristic in [`classify`], checked in this order:
///
/// 1. **bouncing bed**: collective impacts on both end caps, each at least
///    `both_ends_min` per cycle, and a centre of mass that travels at least
///    `bouncing_min_com_range` of the clearance;
/// 2. fewer than `collective_min_impacts` collective impacts a cycle and at
///    least `dense_min_contact_fraction` of the particles in contact on
///    average: the bed rides on the enclosure, **solid-like** while its
///    granular temperature stays below `solid_max_temperature`, else **local
///    fluidisation** (only the top layers agitated);
/// 3. fewer than `collective_min_impacts` collective impacts a cycle and the
///    bed held up, its centre of mass at least `convection_min_com_offset` of
///    the clearance above the settled bed: **convection/Leidenfrost**;
/// 4. otherwise fluidisation: **local** while at least
///    `global_max_contact_fraction` of the particles touch something on
///    average (the deep layers stay packed), **global** below.
///
/// Chosen on the thesis damper, vertical, at 20, 40 and 80 Hz, Γ 1–40, seeds
/// 1–3 (vlab's 8-cycle runs, thesis-shaker rig; `signals/reference/sweep-thesis/`):
/// at Γ 1 no impact, 84–94 % of the particles in contact, temperature
/// 0.0002–0.0017 at 20–40 Hz but up to 0.025 at 80 Hz; at Γ 1.5 one strong
/// impact a cycle and 46–51 % in contact; at Γ 2–5 one a cycle (fewer at 80
/// Hz) and 17–38 %; at 40 Hz Γ 8–12 and 80 Hz Γ 20–40 weak pulses or none with
/// the bed 0.05–0.2 clearances up; from the bouncing-bed onset on, one impact
/// on each cap a cycle and an excursion of 0.55–0.6 clearances.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct PhaseThresholds {
    pub both_ends_min: f64,
    pub bouncing_min_com_range: f64,
    pub collective_min_impacts: f64,
    pub dense_min_contact_fraction: f64,
    pub solid_max_temperature: f64,
    pub convection_min_com_offset: f64,
    pub global_max_contact_fraction: f64,
}

impl Default for PhaseThresholds {
    fn default() -> Self {
        PhaseThresholds {
            both_ends_min: 0.5,
            bouncing_min_com_range: 0.5,
            collective_min_impacts: 0.5,
            dense_min_contact_fraction: 0.8,
            solid_max_temperature: 0.005,
            convection_min_com_offset: 0.03,
            global_max_contact_fraction: 0.4,
        }
    }
}

/// Names the motional phase of `ind` by the heuristic of [`PhaseThresholds`].
pub fn classify(ind: &PhaseIndicators, t: &PhaseThresholds) -> MotionalPhase {
    if ind.bottom_impacts_per_cycle >= t.both_ends_min
        && ind.lid_impacts_per_cycle >= t.both_ends_min
        && ind.com_range_rel >= t.bouncing_min_com_range
    {
        return MotionalPhase::BouncingBed;
    }
    let collective = ind.impacts_per_cycle >= t.collective_min_impacts;
    if !collective && ind.contact_fraction >= t.dense_min_contact_fraction {
        return if ind.granular_temperature_rel < t.solid_max_temperature {
            MotionalPhase::SolidLike
        } else {
            MotionalPhase::LocalFluidisation
        };
    }
    if !collective && ind.com_offset_rel >= t.convection_min_com_offset {
        return MotionalPhase::ConvectionLeidenfrost;
    }
    if ind.contact_fraction < t.global_max_contact_fraction {
        MotionalPhase::GlobalFluidisation
    } else {
        MotionalPhase::LocalFluidisation
    }
}

/// Collective impacts found in a force record.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImpactStats {
    pub cycles: f64,
    pub bottom: usize,
    pub lid: usize,
    /// Mean phase from the nearest enclosure-speed peak (degrees); NaN if none.
    pub phase_deg: f64,
    /// Mean impulse / (M Γ g / ω); NaN if none.
    pub impulse_rel: f64,
}

/// Finds collective impacts in the samples of `rec` from `start_s` on: runs of
/// samples with `|F| > IMPACT_FORCE_FACTOR M g (Γ + 1)` (runs closer than 2 %
/// of a period merged) whose impulse is at least `IMPACT_MIN_IMPULSE M Γ g /
/// ω`, each one impact on the bottom cap (the particles push the enclosure
/// towards −z) or the lid (+z), timed at its force-weighted centroid.
pub fn collective_impacts(
    rec: &TruthSamples,
    start_s: f64,
    drive: &Drive,
    particle_mass_kg: f64,
) -> ImpactStats {
    let (gamma, g_mps2) = (drive.gamma(), drive.gravity_mps2());
    let period = drive.period_s();
    let omega = drive.omega_rad_s();
    let threshold = IMPACT_FORCE_FACTOR * particle_mass_kg * g_mps2 * (gamma + 1.0);
    let v_scale = particle_mass_kg * gamma * g_mps2 / omega;
    let first = rec.time_s.partition_point(|&t| t < start_s - 1e-12);
    let n = rec.len();
    let dt = if n > 1 {
        rec.time_s[1] - rec.time_s[0]
    } else {
        0.0
    };
    let cycles = if n > first && dt > 0.0 {
        ((rec.time_s[n - 1] - rec.time_s[first] + dt) / period).max(0.0)
    } else {
        0.0
    };
    let gap = (0.02 * period / dt.max(f64::MIN_POSITIVE)).ceil() as usize;
    // Pulses: (impulse, impulse-weighted time) of each merged run above threshold.
    let mut pulses: Vec<(f64, f64, f64)> = Vec::new(); // (impulse N s, sum F t, sum |F|)
    let mut last_above: Option<usize> = None;
    for k in first..n {
        let f = rec.force_axial_n[k];
        if f.abs() <= threshold {
            continue;
        }
        let merge = last_above.is_some_and(|l| k - l <= gap);
        if !merge {
            pulses.push((0.0, 0.0, 0.0));
        }
        if let Some(p) = pulses.last_mut() {
            p.0 += f * dt;
            p.1 += f.abs() * rec.time_s[k];
            p.2 += f.abs();
        }
        last_above = Some(k);
    }
    let (mut bottom, mut lid) = (0, 0);
    let (mut phase_sum, mut impulse_sum) = (0.0, 0.0);
    pulses.retain(|p| p.0.abs() >= IMPACT_MIN_IMPULSE * v_scale);
    for &(impulse, ft, fsum) in &pulses {
        if impulse < 0.0 {
            bottom += 1;
        } else {
            lid += 1;
        }
        let t = ft / fsum;
        phase_sum += phase_from_speed_peak_deg(rec, t, period);
        impulse_sum += impulse.abs() / v_scale;
    }
    let count = pulses.len() as f64;
    ImpactStats {
        cycles,
        bottom,
        lid,
        phase_deg: if count > 0.0 {
            phase_sum / count
        } else {
            f64::NAN
        },
        impulse_rel: if count > 0.0 {
            impulse_sum / count
        } else {
            f64::NAN
        },
    }
}

/// Phase (degrees of the cycle) of `t` from the nearest extremum of the
/// recorded enclosure velocity within half a period; negative before it.
fn phase_from_speed_peak_deg(rec: &TruthSamples, t: f64, period: f64) -> f64 {
    let lo = rec.time_s.partition_point(|&s| s < t - 0.25 * period);
    let hi = rec.time_s.partition_point(|&s| s <= t + 0.25 * period);
    let mut best = None::<(f64, f64)>;
    for k in lo..hi {
        let speed = rec.velocity_mps[k].abs();
        if best.is_none_or(|(s, _)| speed > s) {
            best = Some((speed, rec.time_s[k]));
        }
    }
    match best {
        Some((_, t_peak)) => 360.0 * (t - t_peak) / period,
        None => f64::NAN,
    }
}

/// Sums of one cycle's samples of the DEM state.
#[derive(Debug, Clone, Copy)]
struct CycleSums {
    samples: u64,
    contact: f64,
    com: f64,
    temperature: f64,
    min_contact: f64,
    com_lo: f64,
    com_hi: f64,
}

impl Default for CycleSums {
    fn default() -> Self {
        CycleSums {
            samples: 0,
            contact: 0.0,
            com: 0.0,
            temperature: 0.0,
            min_contact: f64::INFINITY,
            com_lo: f64::INFINITY,
            com_hi: f64::NEG_INFINITY,
        }
    }
}

/// Samples the DEM state of a drive for the state indicators, cycle by cycle,
/// so that the indicators can be taken over whichever steady window the drive
/// ends with (a drive run until steady knows its window only at the end); a
/// [`StepObserver`] to pass to the drive.
#[derive(Debug, Clone)]
pub struct PhaseObserver {
    sample_from_s: f64,
    period_s: f64,
    sample_every: u64,
    clearance_m: f64,
    speed_scale_mps: f64,
    steps: u64,
    rest_com_m: Option<f64>,
    counts: Vec<u32>,
    /// Indexed by the cycle of the drive (0-based).
    cycles: Vec<CycleSums>,
}

impl PhaseObserver {
    /// Samples from `sample_from_s` (from the drive start; the earliest the
    /// steady window can begin) on, `SAMPLES_PER_CYCLE` times a cycle of
    /// `drive`, stepped at `dt_s`; `clearance_m` scales the centre-of-mass
    /// indicators and the drive's velocity amplitude the speeds.
    pub fn new(drive: &Drive, dt_s: f64, sample_from_s: f64, clearance_m: f64) -> Self {
        let period = drive.period_s();
        PhaseObserver {
            sample_from_s,
            period_s: period,
            sample_every: ((period / dt_s / SAMPLES_PER_CYCLE as f64).round() as u64).max(1),
            clearance_m,
            speed_scale_mps: drive.velocity_amplitude_mps(),
            steps: 0,
            rest_com_m: None,
            counts: Vec::new(),
            cycles: Vec::new(),
        }
    }

    /// The indicators over the cycles from `steady_start_s` (from the drive
    /// start) on, with the impacts found in the force record over the same
    /// window.
    pub fn indicators(&self, impacts: &ImpactStats, steady_start_s: f64) -> PhaseIndicators {
        let first = (steady_start_s / self.period_s).round().max(0.0) as usize;
        let window = self.cycles.iter().skip(first).filter(|c| c.samples > 0);
        let (mut samples, mut contact, mut com, mut temperature) = (0u64, 0.0, 0.0, 0.0);
        let (mut cycles, mut min_contact, mut com_range) = (0u64, 0.0, 0.0);
        for c in window {
            samples += c.samples;
            contact += c.contact;
            com += c.com;
            temperature += c.temperature;
            cycles += 1;
            min_contact += c.min_contact;
            com_range += c.com_hi - c.com_lo;
        }
        let n = samples.max(1) as f64;
        let c = cycles.max(1) as f64;
        let h = self.clearance_m.max(f64::MIN_POSITIVE);
        let per_cycle = |k: usize| {
            if impacts.cycles > 0.0 {
                k as f64 / impacts.cycles
            } else {
                0.0
            }
        };
        PhaseIndicators {
            impacts_per_cycle: per_cycle(impacts.bottom + impacts.lid),
            bottom_impacts_per_cycle: per_cycle(impacts.bottom),
            lid_impacts_per_cycle: per_cycle(impacts.lid),
            impact_phase_deg: impacts.phase_deg,
            impact_impulse_rel: impacts.impulse_rel,
            contact_fraction: contact / n,
            contact_fraction_min: min_contact / c,
            com_offset_rel: (com / n - self.rest_com_m.unwrap_or(0.0)) / h,
            com_range_rel: com_range / c / h,
            granular_temperature_rel: temperature
                / n
                / (self.speed_scale_mps * self.speed_scale_mps),
        }
    }
}

/// Centre of mass of the particles (each body once) relative to the enclosure along its axis
/// (m), and the mass-weighted velocity fluctuation `Σ m |v − v_cm|² / (3 M)`.
fn bed_state(world: &World) -> (f64, f64) {
    let p = &world.particles;
    let m_total = p.total_mass_kg();
    let mut com = DVec3::ZERO;
    let mut momentum = DVec3::ZERO;
    for (m, x, v) in p.movers() {
        com += x * m;
        momentum += v * m;
    }
    com /= m_total;
    let v_cm = momentum / m_total;
    let mut fluct = 0.0;
    for (m, _, v) in p.movers() {
        fluct += m * (v - v_cm).length_squared();
    }
    let axis = world.walls.axis;
    (
        com.dot(axis) - world.walls.displacement_m,
        fluct / (3.0 * m_total),
    )
}

impl StepObserver for PhaseObserver {
    fn observe(&mut self, t_s: f64, world: &World, _enclosure: &Kinematics) {
        self.steps += 1;
        if self.rest_com_m.is_none() {
            self.rest_com_m = Some(bed_state(world).0);
        }
        if t_s < self.sample_from_s - 1e-12 || self.steps % self.sample_every != 0 {
            return;
        }
        // A sample within a rounding error of a cycle's end belongs to the next.
        let cycle = (t_s / self.period_s + 1e-9).floor().max(0.0) as usize;
        if self.cycles.len() <= cycle {
            self.cycles.resize(cycle + 1, CycleSums::default());
        }
        world.contacts_per_particle(&mut self.counts);
        let n = self.counts.len().max(1) as f64;
        let touching = self.counts.iter().filter(|&&c| c > 0).count() as f64 / n;
        let (com, temperature) = bed_state(world);
        let c = &mut self.cycles[cycle];
        c.samples += 1;
        c.contact += touching;
        c.com += com;
        c.temperature += temperature;
        c.min_contact = c.min_contact.min(touching);
        c.com_lo = c.com_lo.min(com);
        c.com_hi = c.com_hi.max(com);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    fn base() -> PhaseIndicators {
        PhaseIndicators {
            impacts_per_cycle: 1.0,
            bottom_impacts_per_cycle: 1.0,
            lid_impacts_per_cycle: 0.0,
            impact_phase_deg: 0.0,
            impact_impulse_rel: 1.0,
            contact_fraction: 0.5,
            contact_fraction_min: 0.1,
            com_offset_rel: 0.05,
            com_range_rel: 0.03,
            granular_temperature_rel: 0.02,
        }
    }

    #[test]
    fn the_heuristic_names_each_phase_by_its_indicators() {
        let t = PhaseThresholds::default();
        assert_eq!(classify(&base(), &t), MotionalPhase::LocalFluidisation);
        let global = PhaseIndicators {
            contact_fraction: 0.25,
            ..base()
        };
        assert_eq!(classify(&global, &t), MotionalPhase::GlobalFluidisation);
        let solid = PhaseIndicators {
            impacts_per_cycle: 0.0,
            bottom_impacts_per_cycle: 0.0,
            contact_fraction: 0.9,
            contact_fraction_min: 0.85,
            com_range_rel: 0.001,
            granular_temperature_rel: 1e-4,
            ..base()
        };
        assert_eq!(classify(&solid, &t), MotionalPhase::SolidLike);
        let agitated = PhaseIndicators {
            granular_temperature_rel: 0.02,
            ..solid
        };
        assert_eq!(classify(&agitated, &t), MotionalPhase::LocalFluidisation);
        let bouncing = PhaseIndicators {
            impacts_per_cycle: 2.0,
            lid_impacts_per_cycle: 1.0,
            com_range_rel: 0.9,
            ..base()
        };
        assert_eq!(classify(&bouncing, &t), MotionalPhase::BouncingBed);
        let leidenfrost = PhaseIndicators {
            impacts_per_cycle: 0.0,
            bottom_impacts_per_cycle: 0.0,
            contact_fraction: 0.15,
            com_offset_rel: 0.15,
            com_range_rel: 0.4,
            ..base()
        };
        assert_eq!(
            classify(&leidenfrost, &t),
            MotionalPhase::ConvectionLeidenfrost
        );
        for p in [
            MotionalPhase::SolidLike,
            MotionalPhase::LocalFluidisation,
            MotionalPhase::GlobalFluidisation,
            MotionalPhase::BouncingBed,
            MotionalPhase::ConvectionLeidenfrost,
        ] {
            assert_eq!(MotionalPhase::parse(p.as_str()), Some(p));
        }
    }

    #[test]
    fn impacts_are_pulses_counted_by_end_and_timed_from_the_speed_peak() {
        // 40 Hz, 4 cycles at 40 kHz; velocity cos, so speed peaks at t = k T / 2.
        let f = 40.0;
        let rate = 40_000.0;
        let n = 4000;
        let mut rec = TruthSamples::default();
        let (m, gamma, g) = (0.03, 20.0, 9.81);
        for k in 0..n {
            let t = k as f64 / rate;
            let w = 2.0 * PI * f;
            rec.time_s.push(t);
            rec.velocity_mps.push((w * t).cos());
            // A bottom-cap pulse 10 degrees after each speed peak at t = j T,
            // and a lid pulse at each t = (j + 1/2) T; 0.5 ms wide, 100 N.
            let phase = (t * f).fract();
            let near = |c: f64| (phase - c).abs() * (1.0 / f) < 0.25e-3;
            let force = if near(10.0 / 360.0) {
                -100.0
            } else if near(0.5) {
                100.0
            } else {
                -m * g
            };
            rec.force_axial_n.push(force);
        }
        let drive = Drive::new(f, gamma, g).expect("a valid drive");
        let s = collective_impacts(&rec, 0.0, &drive, m);
        assert!((s.cycles - 4.0).abs() < 1e-6, "{}", s.cycles);
        assert_eq!((s.bottom, s.lid), (4, 4));
        assert!((s.phase_deg - 5.0).abs() < 1.0, "{}", s.phase_deg);
    }
}
