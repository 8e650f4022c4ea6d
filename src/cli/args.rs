//! Command-line values: parsers that refuse a value with the crate's one
//! [`InvalidParameter`], and the renaming of library keys to the flags that set
//! them, so that a bad flag reads like a bad key in a scene or rig file:
//!
//! ```text
//! error: --freq = -40 Hz: must be positive and finite
//! error: particles.diameter_m = -0.005 m: must be positive and finite
//! ```
//!
//! Also the options several commands share: the scene flags
//! ([`SceneArgs`]) and the phase-calibration source.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::{Context, Result};
use clap::Args;
use clap::error::{ContextKind, ContextValue, ErrorKind};
use vlab::experiment::measurement::CalibrationSource;
use vlab::scene::{Orientation, Scene, SceneOverrides};
use vlab::signals::PhaseCalibration;
use vlab::validation::{Bound, InvalidParameter, in_range};

/// Placeholder key of a refused flag value; [`parse_error`] puts the flag there.
const FLAG: &str = "value";

/// Parses a number and checks it against `lo`..`hi`.
fn number(s: &str, unit: &str, lo: Bound, hi: Bound) -> Result<f64, InvalidParameter> {
    let v: f64 = s
        .trim()
        .parse()
        .map_err(|_| InvalidParameter::new(FLAG, format!("'{s}'"), unit, "a number"))?;
    in_range(FLAG, v, unit, lo, hi)
}

/// A positive, finite number in `unit`.
fn positive(s: &str, unit: &str) -> Result<f64, InvalidParameter> {
    number(s, unit, Bound::Open(0.0), Bound::Unbounded)
}

/// Frequency in Hz, positive and finite.
pub fn freq_hz(s: &str) -> Result<f64, InvalidParameter> {
    positive(s, "Hz")
}

/// Dimensionless acceleration amplitude Γ (peak acceleration / g), positive.
pub fn gamma(s: &str) -> Result<f64, InvalidParameter> {
    positive(s, "")
}

/// A length in metres, positive and finite.
pub fn metres(s: &str) -> Result<f64, InvalidParameter> {
    positive(s, "m")
}

/// A time in seconds, positive and finite.
pub fn seconds(s: &str) -> Result<f64, InvalidParameter> {
    positive(s, "s")
}

/// A duration in seconds, zero or positive and finite.
pub fn non_negative_seconds(s: &str) -> Result<f64, InvalidParameter> {
    number(s, "s", Bound::Closed(0.0), Bound::Unbounded)
}

/// A speed in m/s, positive and finite.
pub fn speed_mps(s: &str) -> Result<f64, InvalidParameter> {
    positive(s, "m/s")
}

/// An impulse in N s, positive and finite.
pub fn newton_seconds(s: &str) -> Result<f64, InvalidParameter> {
    positive(s, "N s")
}

/// A pressure or modulus in Pa, positive and finite.
pub fn pascals(s: &str) -> Result<f64, InvalidParameter> {
    positive(s, "Pa")
}

/// A mass in kg, positive and finite.
pub fn positive_kg(s: &str) -> Result<f64, InvalidParameter> {
    positive(s, "kg")
}

/// A density in kg/m³, positive and finite.
pub fn density(s: &str) -> Result<f64, InvalidParameter> {
    positive(s, "kg/m^3")
}

/// An acceleration in m/s^2, positive and finite.
pub fn acceleration(s: &str) -> Result<f64, InvalidParameter> {
    positive(s, "m/s^2")
}

/// A force in N, positive and finite.
pub fn newtons(s: &str) -> Result<f64, InvalidParameter> {
    positive(s, "N")
}

/// Coefficient of restitution in (0, 1].
pub fn restitution(s: &str) -> Result<f64, InvalidParameter> {
    number(s, "", Bound::Open(0.0), Bound::Closed(1.0))
}

/// Coefficient of friction, >= 0 and finite.
pub fn friction(s: &str) -> Result<f64, InvalidParameter> {
    number(s, "", Bound::Closed(0.0), Bound::Unbounded)
}

/// Poisson's ratio in (-1, 0.5).
pub fn poisson(s: &str) -> Result<f64, InvalidParameter> {
    number(s, "", Bound::Open(-1.0), Bound::Open(0.5))
}

/// A finite number (any sign).
pub fn finite(s: &str) -> Result<f64, InvalidParameter> {
    number(s, "", Bound::Unbounded, Bound::Unbounded)
}

/// A sample rate in Hz: a positive whole number (WAV headers hold whole
/// hertz), at most 1 MHz (a drop record of 2 s is then 2 M samples).
pub fn sample_rate_hz(s: &str) -> Result<f64, InvalidParameter> {
    let v = positive(s, "Hz")?;
    if v.fract() != 0.0 || v > 1e6 {
        return Err(InvalidParameter::new(
            FLAG,
            v,
            "Hz",
            "a whole number of hertz, at most 1000000",
        ));
    }
    Ok(v)
}

/// At least one thread.
pub fn threads(s: &str) -> Result<usize, InvalidParameter> {
    let v: usize = s
        .trim()
        .parse()
        .map_err(|_| InvalidParameter::new(FLAG, format!("'{s}'"), "", "a whole number"))?;
    vlab::validation::count_in(FLAG, v, "", 1, None)
}

/// The bed's options: the scene, and what of it a flag may change short of
/// the drive's length (the host commands, whose length is their own).
#[derive(Debug, Clone, Args)]
pub struct BedArgs {
    /// Scene file (TOML) merged over the built-in thesis scene.
    #[arg(long, value_name = "FILE")]
    pub scene: Option<PathBuf>,
    /// Gravity relative to the drive axis [scene default: vertical].
    #[arg(long, value_enum)]
    pub orientation: Option<Orientation>,
    /// Seed of the random fill [scene default: 1].
    #[arg(long)]
    pub seed: Option<u64>,
    /// Time step (s) [scene default: every collision resolved by 25 steps at
    /// the largest expected impact speed]; at most the Rayleigh limit.
    #[arg(long = "dt-s", value_name = "S", value_parser = seconds)]
    pub dt_s: Option<f64>,
}

/// `scene` for a bed run alone: its step may use every thread the command
/// has (`--threads`). Beds run side by side take shares instead
/// ([`vlab::experiment::ensemble::thread_shares`]).
pub fn run_alone(mut scene: Scene) -> Scene {
    scene.simulation.step_threads = rayon::current_num_threads();
    scene
}

impl BedArgs {
    /// The scene (built-in or file) with the command-line overrides applied and
    /// everything validated; a refusal names the flag or the key at fault.
    pub fn resolve(&self) -> Result<Scene> {
        self.resolve_with(None, None)
    }

    fn resolve_with(&self, cycles: Option<u32>, steady_cycles: Option<u32>) -> Result<Scene> {
        let scene = Scene::load_or_thesis(self.scene.as_deref())?;
        let overrides = SceneOverrides {
            cycles,
            steady_cycles,
            orientation: self.orientation,
            seed: self.seed,
            dt_s: self.dt_s,
        };
        let flags = FlagKeys::drive(
            cycles.is_some(),
            steady_cycles.is_some(),
            self.dt_s.is_some(),
        );
        overrides
            .apply(scene)
            .map_err(|e| flags.name_flags(e.into()))
    }
}

/// Scene options shared by the commands that drive the damper on the
/// shaker: the bed's, and the drive's length.
#[derive(Debug, Clone, Args)]
pub struct SceneArgs {
    #[command(flatten)]
    pub bed: BedArgs,
    /// Drive cycles in all, fixing the count [scene default: run until steady:
    /// input work and dissipation within 1 %, error of the energy per cycle
    /// below 1 % and the drift across the window shown small (at least 16
    /// cycles), at most 400 cycles].
    #[arg(long)]
    pub cycles: Option<u32>,
    /// Last cycles kept as the steady window; alone, the steady rule's
    /// transient cycles then this many [scene default: 5 of --cycles].
    #[arg(long)]
    pub steady_cycles: Option<u32>,
}

impl SceneArgs {
    /// The scene keys these flags set.
    pub fn flags(&self) -> FlagKeys {
        FlagKeys::drive(
            self.cycles.is_some(),
            self.steady_cycles.is_some(),
            self.bed.dt_s.is_some(),
        )
    }

    /// The scene (built-in or file) with the command-line overrides applied and
    /// everything validated; a refusal names the flag or the key at fault.
    pub fn resolve(&self) -> Result<Scene> {
        self.bed.resolve_with(self.cycles, self.steady_cycles)
    }
}

/// The `--calibration FILE` table, or one measured on the fly on the empty
/// enclosure when no file is given.
pub fn calibration_source(path: Option<&Path>) -> anyhow::Result<CalibrationSource> {
    Ok(match path {
        Some(path) => {
            let table = PhaseCalibration::load_json(path)
                .with_context(|| format!("--calibration {}", path.display()))?;
            CalibrationSource::Given(table, format!("table {}", path.display()))
        }
        None => CalibrationSource::OnTheFly,
    })
}

/// Prints a command-line error and gives the exit status (2, a usage error).
/// A value one of the parsers above refused is printed with its flag as the
/// key, in the crate's one shape; everything else as clap words it.
pub fn parse_error(e: clap::Error) -> ExitCode {
    let refused = std::error::Error::source(&e).and_then(|s| s.downcast_ref::<InvalidParameter>());
    let flag = match e.get(ContextKind::InvalidArg) {
        Some(ContextValue::String(arg)) => arg.split([' ', '=']).next().map(str::to_string),
        _ => None,
    };
    match (e.kind(), refused, flag) {
        (ErrorKind::ValueValidation, Some(p), Some(flag)) => {
            eprintln!("error: {}", p.renamed(&flag));
            ExitCode::from(2)
        }
        _ => {
            // Help and version print to standard output and exit 0.
            let code = e.exit_code();
            let _ = e.print();
            ExitCode::from(u8::try_from(code).unwrap_or(2))
        }
    }
}

/// Library keys that this run's flags set: a refusal the library words with
/// the key (`drive.cycles`) is shown with the flag (`--cycles`).
#[derive(Debug, Clone, Default)]
pub struct FlagKeys(Vec<(String, String)>);

impl FlagKeys {
    /// No flag maps to a key.
    pub fn new() -> Self {
        FlagKeys::default()
    }

    /// The drive's scene keys, set by `--cycles`, `--steady-cycles` and
    /// `--dt-s` (when given).
    pub fn drive(cycles: bool, steady_cycles: bool, dt_s: bool) -> Self {
        FlagKeys::new()
            .set(cycles, "drive.cycles", "--cycles")
            .set(steady_cycles, "drive.steady_cycles", "--steady-cycles")
            .set(dt_s, "simulation.dt_s", "--dt-s")
    }

    /// `key` was set by `flag` (when `given`).
    pub fn set(mut self, given: bool, key: &str, flag: &str) -> Self {
        if given {
            self.0.push((key.to_string(), flag.to_string()));
        }
        self
    }

    /// What to call `key`: the flag that set it, else the key itself.
    pub fn name<'a>(&'a self, key: &'a str) -> &'a str {
        self.flag(key).unwrap_or(key)
    }

    /// The flag that set `key`, if any.
    fn flag(&self, key: &str) -> Option<&str> {
        self.0
            .iter()
            .find(|(k, _)| k == key)
            .map(|(_, f)| f.as_str())
    }

    /// The error, with a refused key renamed to its flag.
    pub fn name_flags(&self, err: anyhow::Error) -> anyhow::Error {
        let renamed = err
            .chain()
            .find_map(|c| c.downcast_ref::<InvalidParameter>())
            .and_then(|p| self.flag(&p.key).map(|f| p.renamed(f)));
        match renamed {
            Some(p) => anyhow::Error::new(p),
            None => err,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn messages_state_unit_and_range() {
        let shown = |r: Result<f64, InvalidParameter>| r.unwrap_err().renamed("--x").to_string();
        assert_eq!(
            shown(freq_hz("-3")),
            "--x = -3 Hz: must be positive and finite"
        );
        assert!(shown(freq_hz("nan")).contains("positive and finite"));
        assert_eq!(shown(freq_hz("abc")), "--x = 'abc' Hz: must be a number");
        assert!(shown(restitution("1.2")).contains("(0, 1]"));
        assert!(shown(friction("-0.1")).contains(">= 0"));
        assert!(sample_rate_hz("2e5").is_ok());
        assert!(shown(sample_rate_hz("200000.5")).contains("whole"));
        assert!(shown(sample_rate_hz("2e7")).contains("1000000"));
        assert!(shown(non_negative_seconds("-1")).contains(" s: "));
    }

    #[test]
    fn library_keys_are_shown_as_the_flags_that_set_them() {
        let flags = FlagKeys::new().set(true, "drive.cycles", "--cycles").set(
            false,
            "simulation.seed",
            "--seed",
        );
        let err = anyhow::Error::new(InvalidParameter::new("drive.cycles", 0, "", "at least 1"))
            .context("resolving the scene");
        assert_eq!(
            flags.name_flags(err).to_string(),
            "--cycles = 0: must be at least 1"
        );
        let err = anyhow::Error::new(InvalidParameter::new("simulation.seed", 0, "", "odd"));
        assert!(
            flags
                .name_flags(err)
                .to_string()
                .starts_with("simulation.seed")
        );
    }
}
