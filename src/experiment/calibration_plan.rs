//! The rig's phase-error calibration on the empty enclosure (Terzioglu's
//! thesis, Section 7.4.2, Fig. 7.9) as a plan: the rig and its shaker, the
//! frequencies and amplitudes, the run's length; checked whole before
//! anything runs ([`CalibrationPlan::check`]), then run into the table that
//! `vlab calibrate` writes and `--calibration` reads. No particles, so no
//! DEM: only the shaker, the transducers and the digitiser run.

use serde::Serialize;

use crate::drive::Drive;
use crate::rig::{RigSpec, ShakerKind};
use crate::scene::SceneError;
use crate::signals::PhaseCalibration;
use crate::validation::InvalidParameter;

use super::measurement::calibrate_rig;
use super::shake::resolve_rig;

/// What a calibration is asked to run.
#[derive(Debug, Clone, PartialEq)]
pub struct CalibrationPlan {
    /// A built-in rig's name or a rig file.
    pub rig: String,
    /// The shaker instead of the rig's own.
    pub shaker: Option<ShakerKind>,
    pub freqs_hz: Vec<f64>,
    /// Amplitudes (peak acceleration / g) at each frequency, averaged.
    pub gammas: Vec<f64>,
    /// Drive cycles at each point, of which the last `record_cycles` are
    /// recorded.
    pub cycles: u32,
    pub record_cycles: u32,
    /// Time step of the shaker's model (s).
    pub dt_s: f64,
}

/// One frequency of the table, beside the rig model's own phase error.
#[derive(Debug, Clone, Serialize)]
pub struct CalibrationRow {
    pub freq_hz: f64,
    pub phase_error_rad: f64,
    pub spread_rad: f64,
    pub amplitudes: usize,
    pub rig_model_phase_error_rad: f64,
}

impl CalibrationPlan {
    /// The rig, checked to do every (frequency, amplitude) of the plan under
    /// gravity `g_mps2`; the plan's own ranges checked first, each refusal
    /// naming its key (`record_cycles`, `dt_s`, `freqs_hz`, `rig`).
    pub fn check(&self, g_mps2: f64) -> Result<RigSpec, SceneError> {
        if self.record_cycles < 2 || self.record_cycles > self.cycles {
            return Err(InvalidParameter::new(
                "record_cycles",
                self.record_cycles,
                "",
                format!("in [2, cycles = {}]", self.cycles),
            )
            .into());
        }
        let mut resolved = None;
        for &f in &self.freqs_hz {
            for &gamma in &self.gammas {
                let drive = Drive::new(f, gamma, g_mps2)?;
                resolved = Some(resolve_rig(&self.rig, self.shaker, &drive)?);
            }
        }
        let Some(rig) = resolved else {
            return Err(InvalidParameter::new(
                "freqs_hz",
                format!(
                    "{} frequencies x {} amplitudes",
                    self.freqs_hz.len(),
                    self.gammas.len()
                ),
                "",
                "at least one of each",
            )
            .into());
        };
        let sample_s = 1.0 / rig.daq.sample_rate_hz;
        if !(self.dt_s > 0.0 && self.dt_s <= sample_s) {
            return Err(InvalidParameter::new(
                "dt_s",
                self.dt_s,
                "s",
                format!(
                    "in (0, {sample_s}]: at most one sample period at {} Hz",
                    rig.daq.sample_rate_hz
                ),
            )
            .into());
        }
        Ok(rig)
    }

    /// Runs the empty enclosure on `rig` (from [`Self::check`]) at every
    /// point: the table, and each frequency's row beside the rig model.
    pub fn run(
        &self,
        rig: &RigSpec,
        g_mps2: f64,
    ) -> Result<(PhaseCalibration, Vec<CalibrationRow>), SceneError> {
        let table = calibrate_rig(
            rig,
            rig.shaker.kind,
            &self.freqs_hz,
            &self.gammas,
            g_mps2,
            self.dt_s,
            self.cycles,
            self.record_cycles,
            1,
        )?
        .table;
        let rows = table
            .points
            .iter()
            .map(|e| CalibrationRow {
                freq_hz: e.freq_hz,
                phase_error_rad: e.phase_error_rad,
                spread_rad: e.spread_rad,
                amplitudes: e.n_amplitudes,
                rig_model_phase_error_rad: rig.expected_phase_error_rad(e.freq_hz),
            })
            .collect();
        Ok((table, rows))
    }
}
