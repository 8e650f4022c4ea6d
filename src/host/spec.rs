//! A host structure as a file gives it: a few modes, each with its natural
//! frequency (or stiffness), modal mass, damping ratio and its mode-shape
//! values at the damper and at the drive point.
//!
//! A host file is a rig file of `kind = "host"` (one loader,
//! [`crate::rig::RigFile`]): `version = 1`, strict keys, and one `[[mode]]`
//! table per mode. The modal parameters are those of the host with the
//! *empty* enclosure attached, as a modal test of the bare structure gives
//! them; the particles are what vlab adds. A mode's equation is
//!
//! `m_r q_r'' + 2 ζ_r ω_r m_r q_r' + ω_r² m_r q_r = φ_r(d) F_d + φ_r(e) F_e`,
//!
//! with the displacement at the damper `x_d = Σ φ_r(d) q_r` and at the drive
//! point `x_e = Σ φ_r(e) q_r`; a single-degree-of-freedom host is one mode
//! with both shape values 1. The built-in hosts are the files of `host/`:
//! `plate-40hz` (one mode, thesis-sized) and `beam-2mode`.

use std::f64::consts::TAU;

use serde::{Deserialize, Serialize};

use crate::rig::RigError;
use crate::rig::file::{RigFile, RigKind, check_header, host_kind};
use crate::validation::{Bound, InvalidParameter, count_in, in_range, positive, require};

/// The built-in host `vlab host` commands use when none is named.
pub const DEFAULT_HOST: &str = "plate-40hz";

/// Most modes a host may have.
pub const MAX_MODES: usize = 8;

/// Highest natural frequency a host may have, Hz: the DEM step and the
/// 40 kHz record resolve it (at least 8 samples a period).
pub const MAX_MODE_FREQ_HZ: f64 = 5_000.0;

/// A host structure: its modes.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HostSpec {
    /// File format version; must be [`crate::rig::RIG_VERSION`].
    pub version: u32,
    /// Always `host` (optional in files).
    #[serde(default = "host_kind")]
    pub kind: RigKind,
    /// Host name, written into trace metadata.
    pub name: String,
    /// One or two sentences on what this host is.
    #[serde(default)]
    pub description: String,
    /// The modes, each a `[[mode]]` table.
    #[serde(rename = "mode")]
    pub modes: Vec<ModeSpec>,
}

/// One mode of the host (with the empty enclosure attached).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ModeSpec {
    /// Undamped natural frequency, Hz; give this or `stiffness_n_per_m`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub freq_hz: Option<f64>,
    /// Modal stiffness, N/m; give this or `freq_hz`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub stiffness_n_per_m: Option<f64>,
    /// Modal mass, kg (for a single-degree-of-freedom host, its mass
    /// including the empty enclosure).
    pub modal_mass_kg: f64,
    /// Viscous damping ratio ζ, 1, in [0, 1).
    pub damping_ratio: f64,
    /// Mode-shape value at the damper, 1.
    #[serde(default = "unit_shape")]
    pub shape_at_damper: f64,
    /// Mode-shape value at the drive point, 1.
    #[serde(default = "unit_shape")]
    pub shape_at_drive: f64,
}

fn unit_shape() -> f64 {
    1.0
}

impl ModeSpec {
    /// A mode of natural frequency `freq_hz`, modal mass `modal_mass_kg` and
    /// damping ratio `damping_ratio`, with both shape values 1.
    pub fn sdof(freq_hz: f64, modal_mass_kg: f64, damping_ratio: f64) -> Self {
        ModeSpec {
            freq_hz: Some(freq_hz),
            stiffness_n_per_m: None,
            modal_mass_kg,
            damping_ratio,
            shape_at_damper: 1.0,
            shape_at_drive: 1.0,
        }
    }

    /// Undamped natural angular frequency ω_r, rad/s.
    pub fn omega_rad_s(&self) -> f64 {
        match (self.freq_hz, self.stiffness_n_per_m) {
            (Some(f), _) => TAU * f,
            (None, Some(k)) => (k / self.modal_mass_kg).sqrt(),
            (None, None) => f64::NAN,
        }
    }

    /// Undamped natural frequency, Hz.
    pub fn natural_freq_hz(&self) -> f64 {
        self.omega_rad_s() / TAU
    }

    /// Modal stiffness `m_r ω_r²`, N/m.
    pub fn stiffness(&self) -> f64 {
        self.modal_mass_kg * self.omega_rad_s().powi(2)
    }

    /// Modal viscous damping `2 ζ_r ω_r m_r`, N s/m.
    pub fn damping_n_s_per_m(&self) -> f64 {
        2.0 * self.damping_ratio * self.omega_rad_s() * self.modal_mass_kg
    }

    fn validate(&self) -> Result<(), InvalidParameter> {
        in_range(
            "modal_mass_kg",
            self.modal_mass_kg,
            "kg",
            Bound::Open(0.0),
            Bound::Closed(1e6),
        )?;
        let resolved = |key: &str, f: f64| {
            in_range(
                key,
                f,
                "Hz",
                Bound::Open(0.0),
                Bound::Closed(MAX_MODE_FREQ_HZ),
            )
            .map_err(|e| e.because("the DEM step and the 40 kHz record resolve it"))
        };
        match (self.freq_hz, self.stiffness_n_per_m) {
            (Some(f), None) => {
                resolved("freq_hz", f)?;
            }
            (None, Some(k)) => {
                positive("stiffness_n_per_m", k, "N/m")?;
                resolved(
                    "sqrt(stiffness_n_per_m / modal_mass_kg) / 2 pi",
                    self.natural_freq_hz(),
                )?;
            }
            (f, k) => {
                return Err(InvalidParameter::new(
                    "freq_hz",
                    format!("{f:?} with stiffness_n_per_m = {k:?}"),
                    "",
                    "given, or stiffness_n_per_m given, but not both",
                ));
            }
        }
        in_range(
            "damping_ratio",
            self.damping_ratio,
            "",
            Bound::Closed(0.0),
            Bound::Open(1.0),
        )
        .map_err(|e| e.because("an underdamped mode"))?;
        for (key, value) in [
            ("shape_at_damper", self.shape_at_damper),
            ("shape_at_drive", self.shape_at_drive),
        ] {
            in_range(key, value, "", Bound::Unbounded, Bound::Unbounded)?;
        }
        Ok(())
    }
}

impl HostSpec {
    /// A single-degree-of-freedom host: one mode at `freq_hz` of mass
    /// `mass_kg` (including the empty enclosure) and damping ratio
    /// `damping_ratio`, damper and drive on the mass. Validated.
    pub fn sdof(
        name: &str,
        freq_hz: f64,
        mass_kg: f64,
        damping_ratio: f64,
    ) -> Result<Self, RigError> {
        let host = HostSpec {
            version: crate::rig::RIG_VERSION,
            kind: RigKind::Host,
            name: name.to_string(),
            description: format!(
                "one mode at {freq_hz} Hz, {mass_kg} kg, damping ratio {damping_ratio}"
            ),
            modes: vec![ModeSpec::sdof(freq_hz, mass_kg, damping_ratio)],
        };
        host.validate()?;
        Ok(host)
    }

    /// The mode of the lowest natural frequency (a valid host has one).
    pub fn first_mode(&self) -> Option<&ModeSpec> {
        self.modes
            .iter()
            .min_by(|a, b| a.natural_freq_hz().total_cmp(&b.natural_freq_hz()))
    }

    /// The lowest natural frequency, Hz.
    pub fn lowest_freq_hz(&self) -> f64 {
        self.modes
            .iter()
            .map(ModeSpec::natural_freq_hz)
            .fold(f64::INFINITY, f64::min)
    }

    /// The highest natural frequency, Hz.
    pub fn highest_freq_hz(&self) -> f64 {
        self.modes
            .iter()
            .map(ModeSpec::natural_freq_hz)
            .fold(0.0, f64::max)
    }
}

impl RigFile for HostSpec {
    const KIND: RigKind = RigKind::Host;

    fn validate(&self) -> Result<(), RigError> {
        check_header(self.version, self.kind, Self::KIND, &self.name)?;
        count_in("mode", self.modes.len(), "modes", 1, Some(MAX_MODES))?;
        for (i, mode) in self.modes.iter().enumerate() {
            mode.validate()
                .map_err(|e| e.within(&format!("mode[{i}]")))?;
        }
        require(
            self.modes.iter().any(|m| m.shape_at_damper != 0.0),
            "mode[*].shape_at_damper",
            "0 in every mode",
            "",
            "non-zero in at least one mode (the damper must move)",
        )?;
        require(
            self.modes.iter().any(|m| m.shape_at_drive != 0.0),
            "mode[*].shape_at_drive",
            "0 in every mode",
            "",
            "non-zero in at least one mode (the drive must move the host)",
        )?;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_file_in_host_loads_as_a_host() {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("host");
        let mut seen = 0;
        for entry in std::fs::read_dir(&dir).expect("host/ exists") {
            let path = entry.expect("entry").path();
            if path.extension().is_some_and(|e| e == "toml") {
                drop(HostSpec::load(&path).expect("a host"));
                seen += 1;
            }
        }
        assert_eq!(
            seen,
            HostSpec::names().len(),
            "every file in host/ is built in"
        );
    }

    #[test]
    fn the_built_in_hosts_load_and_give_their_documented_figures() {
        let plate = HostSpec::builtin("plate-40hz").expect("built in");
        assert_eq!(plate.modes.len(), 1);
        let m = plate.modes[0];
        // k = m (2 pi f)^2 = 0.5 x 251.33^2 = 31 583 N/m.
        assert!((m.stiffness() - 31_582.7).abs() < 1.0, "{}", m.stiffness());
        // 6 N at resonance with 3 % total damping: X = F / (2 zeta k) = 3.2 mm,
        // Gamma = X w^2 / g = 20.2 (the file's comment).
        let x = 6.0 / (2.0 * 0.03 * m.stiffness());
        let gamma = x * m.omega_rad_s().powi(2) / 9.81;
        assert!((gamma - 20.0).abs() < 0.5, "{gamma}");
        let beam = HostSpec::builtin("beam-2mode").expect("built in");
        assert_eq!(beam.modes.len(), 2);
        assert!((beam.highest_freq_hz() - 251.0).abs() < 1e-9);
        assert_eq!(HostSpec::names(), ["plate-40hz", "beam-2mode"]);
    }

    #[test]
    fn a_wrong_host_is_refused_with_its_key_unit_and_range() {
        let text = crate::rig::builtin_toml("plate-40hz").expect("built in");
        let refuse = |from: &str, to: &str| {
            assert!(text.contains(from), "{from}");
            HostSpec::from_toml_str(&text.replace(from, to), "h.toml")
                .expect_err(to)
                .to_string()
        };
        let msg = refuse("damping_ratio = 0.003", "damping_ratio = 1.5");
        assert!(
            msg.contains("mode[0].damping_ratio = 1.5: must be in [0, 1) (an underdamped mode)"),
            "{msg}"
        );
        let msg = refuse("freq_hz = 40.0", "freq_hz = -40.0");
        assert!(
            msg.contains("mode[0].freq_hz = -40 Hz: must be in (0, 5000]"),
            "{msg}"
        );
        let msg = refuse("freq_hz = 40.0", "freq_hz = 40.0\nstiffness_n_per_m = 1e4");
        assert!(msg.contains("but not both"), "{msg}");
        let msg = refuse("modal_mass_kg = 0.5", "modal_mass_kg = 0.0");
        assert!(msg.contains("mode[0].modal_mass_kg = 0 kg"), "{msg}");
        let msg = refuse("shape_at_damper = 1.0", "shape_at_damper = 0.0");
        assert!(msg.contains("the damper must move"), "{msg}");
        let msg = refuse("modal_mass_kg", "modal_mas_kg");
        assert!(msg.contains("unknown field `modal_mas_kg`"), "{msg}");
        // A shaker rig is not a host.
        let shaker = crate::rig::builtin_toml("ideal").expect("built in");
        let msg = HostSpec::from_toml_str(shaker, "s.toml")
            .expect_err("not a host")
            .to_string();
        assert_eq!(msg, "s.toml is a shaker rig; a host rig is needed here");
        // A stiffness instead of a frequency: the same mode.
        let k = refuse("freq_hz = 40.0", "stiffness_n_per_m = -5.0");
        assert!(k.contains("mode[0].stiffness_n_per_m = -5 N/m"), "{k}");
        let by_k = HostSpec::from_toml_str(
            &text.replace("freq_hz = 40.0", "stiffness_n_per_m = 31582.734"),
            "k.toml",
        )
        .expect("valid");
        assert!((by_k.modes[0].natural_freq_hz() - 40.0).abs() < 1e-4);
    }
}
