//! The lab hardware (thesis Sections 7.3-7.4 and 7.6; docs/design.md, "The rig"):
//! the shaker that moves the enclosure, the force transducer and the
//! accelerometer on it, the signal conditioner and the digitiser.
//!
//! - [`file`]: the one rig-file loader: built-in rigs, version, kind tag,
//!   strict keys, validation ([`RigFile`]);
//! - [`spec`]: shaker rigs (`kind = "shaker"`) and the built-in rigs
//!   `thesis-shaker` (default) and `ideal`; the model's own phase error;
//! - [`channel_spec`]: one transducer channel as a rig file gives it
//!   ([`ChannelSpec`]) and in common terms ([`ChannelParams`]), with its
//!   response and checks;
//! - [`motion`]: the one enclosure-motion abstraction ([`EnclosureMotion`],
//!   [`Kinematics`]), the prescribed sine of eq. 6.2 / 7.6 ([`SineMotion`])
//!   and a recorded motion replayed ([`RecordedMotion`], `vlab replay`);
//! - [`shaker`]: the rig's drive, prescribed or a lumped electrodynamic
//!   shaker whose motion the particles disturb, with the rig's stroke and
//!   acceleration limits;
//! - [`transducer`]: what the force gauge reads, `m_enc a - F_p + W`;
//! - [`channel`]: one channel: sensitivity, gain, AC coupling, anti-alias
//!   filter, sampling with skew, noise, ADC;
//! - [`daq`]: both channels sampled into a [`crate::signals::Trace`];
//! - [`drop_spec`]: drop-test rigs (`kind = "drop-test"`,
//!   `rig/drop-test.toml` built in);
//! - [`plate`]: the drop rig's base plate ringing on its force transducer;
//! - [`drop_rig`]: plate and force channel on one clock, recording a drop test;
//! - [`filter`], [`discretise`], [`noise`]: the numerical pieces.
//!
//! The rig sees the damper only as the axial force the particles exert on the
//! enclosure: this module imports neither `dem` nor `scene`. SI units
//! throughout. Per DEM step, [`EnclosureMotion::advance`] and [`Daq::push`]
//! do O(1) work and do not allocate.
//!
//! A `vlab shake` step, in order: `k = shaker.advance(t, dt, f_p)` ->
//! DEM step with the enclosure at `k.displacement_m` ->
//! `daq.push(t, a, transducer_force_n(m_enc, a, f_p, w))` with
//! `a = k.acceleration_mps2`.

pub mod channel;
pub mod channel_spec;
pub mod daq;
pub mod discretise;
pub mod drop_rig;
pub mod drop_spec;
pub mod error;
pub mod file;
pub mod filter;
pub mod motion;
pub mod noise;
pub mod plate;
pub mod shaker;
pub mod spec;
pub mod transducer;

pub use channel::{Adc, MeasurementChannel};
pub use channel_spec::{
    Acceleration, ChannelParams, ChannelQuantity, ChannelSpec, Force, LowPassSpec, Sampling,
};
pub use daq::{ACCEL_CHANNEL, ChannelReport, Daq, DaqReport, FORCE_CHANNEL};
pub use drop_rig::{DROP_FORCE_CHANNEL, DropRig, DropRigReport};
pub use drop_spec::{DROP_RIG, DropRigSpec, MountSpec, PlateSpec, RecordSpec};
pub use error::{Result, RigError};
pub use file::{RIG_VERSION, RigFile, RigKind, builtin_rigs, builtin_toml};
pub use motion::{EnclosureMotion, Kinematics, RecordedMotion, SineMotion};
pub use plate::Plate;
pub use shaker::{ElectrodynamicShaker, Shaker, ShakerReport, check_limits};
pub use spec::{
    AccelerometerSpec, DEFAULT_RIG, DaqSpec, ElectrodynamicSpec, EnclosureSpec, ForceSpec, RigSpec,
    ShakerKind, ShakerSpec,
};
pub use transducer::transducer_force_n;
