//! The drop-test rig description (thesis Section 7.3, Fig. 7.3): base plate,
//! the transducer mount it rings on, the force channel and the digitiser.
//!
//! A drop rig is a TOML file of `version = 1` with strict keys, like the shaker
//! rigs of [`super::spec`] but with its own sections (`[plate]`, `[mount]`,
//! `[force]`, `[daq]`, `[record]`); `[force]` and `[daq]` are the same tables as
//! in a shaker rig. The built-in `drop-test` rig is `rig/drop-test.toml`,
//! embedded in the binary; every number in it is commented with its unit and
//! why it is plausible (the thesis gives only the 200 kHz sample rate).
//!
//! This module knows nothing of the DEM: the plate's elastic constants are plain
//! numbers here; the scene turns them into a contact material.

use serde::{Deserialize, Serialize};

use super::channel_spec::ChannelParams;
use super::error::{RigError, positive};
use super::file::{RigFile, RigKind, check_header, drop_test_kind};
use super::spec::{DaqSpec, ForceSpec};
use crate::validation::{Bound, in_range};

/// Name of the built-in drop rig.
pub const DROP_RIG: &str = "drop-test";

/// Longest record a drop rig may ask for, s (memory: 1 min at 1 MHz is 480 MB).
pub const MAX_RECORD_LENGTH_S: f64 = 60.0;

/// A complete drop-test rig.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DropRigSpec {
    /// File format version; must be [`super::file::RIG_VERSION`].
    pub version: u32,
    /// Always `drop-test` (optional in files).
    #[serde(default = "drop_test_kind")]
    pub kind: RigKind,
    /// Rig name, written into trace metadata.
    pub name: String,
    /// One or two sentences on what this rig is.
    #[serde(default)]
    pub description: String,
    /// The base plate the sphere hits.
    pub plate: PlateSpec,
    /// The transducer and its mounting, as a spring and a damper to ground.
    pub mount: MountSpec,
    /// The force transducer's channel (as `[force]` of a shaker rig).
    pub force: ForceSpec,
    /// The digitiser.
    pub daq: DaqSpec,
    /// What is recorded.
    pub record: RecordSpec,
}

/// The base plate: its mass and the elastic constants of its surface.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PlateSpec {
    /// Mass carried by the transducer (plate and the transducer's top), kg.
    pub mass_kg: f64,
    /// Young's modulus of the plate, Pa.
    pub youngs_pa: f64,
    /// Poisson's ratio of the plate, 1, in (-1, 0.5).
    pub poisson: f64,
    /// Yield strength of the plate, Pa; absent = it never yields first.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub yield_strength_pa: Option<f64>,
}

/// The transducer and its mounting as one spring and damper to ground.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MountSpec {
    /// Axial stiffness, N/m.
    pub stiffness_n_per_m: f64,
    /// Damping ratio of the plate on the mount, 1, in [0, 1).
    pub damping_ratio: f64,
}

/// What is recorded.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RecordSpec {
    /// Record length from the release of the sphere, s.
    pub length_s: f64,
}

impl DropRigSpec {
    /// The force channel in common terms.
    pub fn force_channel(&self) -> ChannelParams {
        self.force.params()
    }

    /// Undamped natural frequency of the plate on its mount, Hz.
    pub fn plate_natural_freq_hz(&self) -> f64 {
        (self.mount.stiffness_n_per_m / self.plate.mass_kg).sqrt() / (2.0 * std::f64::consts::PI)
    }
}

impl RigFile for DropRigSpec {
    const KIND: RigKind = RigKind::DropTest;

    fn validate(&self) -> Result<(), RigError> {
        check_header(self.version, self.kind, Self::KIND, &self.name)?;
        let p = &self.plate;
        positive("plate.mass_kg", p.mass_kg, "kg")?;
        positive("plate.youngs_pa", p.youngs_pa, "Pa")?;
        in_range(
            "plate.poisson",
            p.poisson,
            "",
            Bound::Open(-1.0),
            Bound::Open(0.5),
        )?;
        if let Some(y) = p.yield_strength_pa {
            positive("plate.yield_strength_pa", y, "Pa")?;
        }
        positive(
            "mount.stiffness_n_per_m",
            self.mount.stiffness_n_per_m,
            "N/m",
        )?;
        in_range(
            "mount.damping_ratio",
            self.mount.damping_ratio,
            "",
            Bound::Closed(0.0),
            Bound::Open(1.0),
        )
        .map_err(|e| e.because("an underdamped plate, as a transducer mount is"))?;
        self.daq.validate()?;
        self.force_channel().validate(self.daq.sample_rate_hz)?;
        in_range(
            "record.length_s",
            self.record.length_s,
            "s",
            Bound::Open(0.0),
            Bound::Closed(MAX_RECORD_LENGTH_S),
        )?;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::Path;

    const DROP_RIG_TOML: &str = include_str!("../../rig/drop-test.toml");

    #[test]
    fn builtin_parses_round_trips_and_matches_the_checked_in_file() {
        let rig = DropRigSpec::builtin(DROP_RIG).expect("built in");
        assert_eq!(rig.name, DROP_RIG);
        assert_eq!(rig.daq.sample_rate_hz, 200_000.0, "thesis Section 7.3");
        let back = DropRigSpec::from_toml_str(&rig.to_toml(), "printed").expect("reparses");
        assert_eq!(back, rig);
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("rig/drop-test.toml");
        assert_eq!(DropRigSpec::load(&path).expect("file parses"), rig);
        // The comment's figure: 10.1 kHz.
        assert!((rig.plate_natural_freq_hz() - 10_066.0).abs() < 1.0);
    }

    #[test]
    fn bad_values_name_key_unit_and_range() {
        let text = DROP_RIG_TOML.replace("damping_ratio = 0.04", "damping_ratio = 1.5");
        let msg = DropRigSpec::from_toml_str(&text, "t.toml")
            .expect_err("overdamped")
            .to_string();
        assert!(
            msg.starts_with("t.toml: mount.damping_ratio = 1.5: must be in [0, 1)"),
            "{msg}"
        );
        let text = DROP_RIG_TOML.replace("mass_kg = 0.10", "mass_kg = -0.1");
        let msg = DropRigSpec::from_toml_str(&text, "t.toml")
            .expect_err("negative mass")
            .to_string();
        assert!(msg.contains("plate.mass_kg = -0.1 kg"), "{msg}");
        let text = DROP_RIG_TOML.replace("[plate]", "[plate]\ncolour = 1");
        let msg = DropRigSpec::from_toml_str(&text, "t.toml")
            .expect_err("unknown key")
            .to_string();
        assert!(msg.contains("colour"), "{msg}");
        let text = DROP_RIG_TOML.replace("version = 1", "version = 3");
        let msg = DropRigSpec::from_toml_str(&text, "t.toml")
            .expect_err("version")
            .to_string();
        assert!(msg.contains("version = 3"), "{msg}");
        let text = DROP_RIG_TOML.replace("length_s = 2.0", "length_s = 0.0");
        let msg = DropRigSpec::from_toml_str(&text, "t.toml")
            .expect_err("empty record")
            .to_string();
        assert!(msg.contains("record.length_s = 0 s"), "{msg}");
    }
}
