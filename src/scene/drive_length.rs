//! How long a damper is driven: a fixed count of cycles (the thesis: 8, the last
//! 5 measured, Section 6.2) or until the bed is steady, and what steady means.
//! The scene file's `[drive] cycles` key parses into a [`DriveLength`].

/// How long the drive runs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum DriveLength {
    /// Exactly `cycles` cycles; the last `steady_cycles` are the steady window
    /// (the thesis: 8 and 5).
    Fixed { cycles: u32, steady_cycles: u32 },
    /// Until steady (see [`SteadyCriteria`]), at least `min_cycles`, at most
    /// `max_cycles`; the first 3/8 of the cycles are the transient.
    UntilSteady {
        min_cycles: u32,
        max_cycles: u32,
        criteria: SteadyCriteria,
    },
}

impl DriveLength {
    /// Most cycles the drive can take.
    pub fn max_cycles(&self) -> u32 {
        match *self {
            DriveLength::Fixed { cycles, .. } => cycles,
            DriveLength::UntilSteady { max_cycles, .. } => max_cycles,
        }
    }

    /// Fewest cycles before the steady window starts: the window never begins
    /// earlier than this.
    pub fn min_transient_cycles(&self) -> u32 {
        match *self {
            DriveLength::Fixed {
                cycles,
                steady_cycles,
            } => cycles - steady_cycles,
            DriveLength::UntilSteady { min_cycles, .. } => transient_cycles(min_cycles),
        }
    }
}

/// The transient part of `cycles` cycles run until steady: the first 3/8 (the
/// thesis' 3 of 8), at least one.
pub fn transient_cycles(cycles: u32) -> u32 {
    (3 * cycles / 8).max(1)
}

/// When a drive is steady: over the steady window the work the enclosure put
/// in and the energy the bed dissipated agree within `balance_rel` (of the
/// dissipation, or of `E_max` per cycle for a bed that dissipates next to
/// nothing), and the energy per cycle has a one-sigma error below
/// `stderr_rel` of its mean (from the cycle-to-cycle spread, see
/// [`crate::stats`]); the window must also hold
/// [`crate::stats::MIN_SERIES_VALUES`] cycles and show no trend (see
/// `crate::experiment::damper`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SteadyCriteria {
    pub balance_rel: f64,
    pub stderr_rel: f64,
}

impl Default for SteadyCriteria {
    fn default() -> Self {
        SteadyCriteria {
            balance_rel: 0.01,
            stderr_rel: 0.01,
        }
    }
}
