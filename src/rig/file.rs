//! One loader for every rig file: the built-in rigs, versioning, the kind tag,
//! strict keys and validation, whatever the kind of rig.
//!
//! A rig file is TOML with `version = 1` and `kind = "shaker"` (the damper
//! rigs of [`super::spec`]), `kind = "drop-test"` (the restitution rig of
//! [`super::drop_spec`]) or `kind = "host"` (a structure carrying the damper,
//! described by the `host` module, which implements [`RigFile`] for it). A file without `kind` is told by its sections
//! (`[shaker]`, `[plate]` or `[[mode]]`). A file of the wrong kind for what was asked is
//! refused by its kind, not by the first key the other kind does not know.
//! The built-in rigs are the files of the top-level `rig/` folder, and the
//! built-in hosts those of `host/`, embedded in the binary. Nothing is merged from a built-in: a rig file is complete.

use std::fmt;
use std::path::Path;

use serde::{Deserialize, Serialize, de::DeserializeOwned};

use super::error::RigError;

/// Version written into, and required of, rig files.
pub const RIG_VERSION: u32 = 1;

/// What a rig file describes.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum RigKind {
    /// A shaker rig that drives and records a damper.
    Shaker,
    /// A drop-test rig: a plate on a force transducer.
    DropTest,
    /// A host structure that carries the damper (its modes).
    Host,
}

impl RigKind {
    /// The tag as written in files.
    pub fn as_str(self) -> &'static str {
        match self {
            RigKind::Shaker => "shaker",
            RigKind::DropTest => "drop-test",
            RigKind::Host => "host",
        }
    }

    /// The kind a file without a `kind` key describes, by its sections.
    fn by_sections(table: &toml::Table) -> Option<RigKind> {
        if table.contains_key("shaker") {
            Some(RigKind::Shaker)
        } else if table.contains_key("plate") {
            Some(RigKind::DropTest)
        } else if table.contains_key("mode") {
            Some(RigKind::Host)
        } else {
            None
        }
    }
}

impl fmt::Display for RigKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

/// The built-in rigs: name, kind, file.
const BUILTIN: [(&str, RigKind, &str); 5] = [
    (
        "thesis-shaker",
        RigKind::Shaker,
        include_str!("../../rig/thesis-shaker.toml"),
    ),
    (
        "ideal",
        RigKind::Shaker,
        include_str!("../../rig/ideal.toml"),
    ),
    (
        "drop-test",
        RigKind::DropTest,
        include_str!("../../rig/drop-test.toml"),
    ),
    (
        "plate-40hz",
        RigKind::Host,
        include_str!("../../host/plate-40hz.toml"),
    ),
    (
        "beam-2mode",
        RigKind::Host,
        include_str!("../../host/beam-2mode.toml"),
    ),
];

/// Names and kinds of the built-in rigs, the default shaker rig first.
pub fn builtin_rigs() -> impl Iterator<Item = (&'static str, RigKind)> {
    BUILTIN.iter().map(|(n, k, _)| (*n, *k))
}

/// The TOML text of a built-in rig of any kind.
pub fn builtin_toml(name: &str) -> Option<&'static str> {
    BUILTIN
        .iter()
        .find(|(n, _, _)| *n == name)
        .map(|(_, _, t)| *t)
}

/// A kind of rig file: how it is checked. Loading, versioning and the
/// built-ins are the provided methods, the same for every kind.
pub trait RigFile: Sized + Serialize + DeserializeOwned {
    /// The kind tag of these files.
    const KIND: RigKind;

    /// Checks every value; a refusal names the key, its unit and valid range.
    fn validate(&self) -> Result<(), RigError>;

    /// Names of the built-in rigs of this kind.
    fn names() -> Vec<&'static str> {
        builtin_rigs()
            .filter(|(_, k)| *k == Self::KIND)
            .map(|(n, _)| n)
            .collect()
    }

    /// A built-in rig of this kind by name.
    fn builtin(name: &str) -> Result<Self, RigError> {
        let unknown = || RigError::UnknownRig {
            name: name.to_string(),
            available: Self::names().join(", "),
        };
        let text = builtin_toml(name).ok_or_else(unknown)?;
        Self::from_toml_str(text, &format!("built-in rig '{name}'"))
    }

    /// Reads a rig file of this kind.
    fn load(path: &Path) -> Result<Self, RigError> {
        let text = std::fs::read_to_string(path).map_err(|source| RigError::Read {
            path: path.to_path_buf(),
            source,
        })?;
        Self::from_toml_str(&text, &path.display().to_string())
    }

    /// A built-in name, else a path to a rig file.
    fn from_name_or_path(name_or_path: &str) -> Result<Self, RigError> {
        if builtin_toml(name_or_path).is_some() {
            return Self::builtin(name_or_path);
        }
        let path = Path::new(name_or_path);
        if path.is_file() {
            return Self::load(path);
        }
        Err(RigError::UnknownRig {
            name: name_or_path.to_string(),
            available: Self::names().join(", "),
        })
    }

    /// Parses and validates TOML text; `origin` names the source in messages.
    /// The version and the kind are checked first, so that a file of another
    /// version or kind is not blamed for keys this one does not know.
    fn from_toml_str(text: &str, origin: &str) -> Result<Self, RigError> {
        if let Ok(table) = text.parse::<toml::Table>() {
            if let Some(v) = table.get("version").and_then(toml::Value::as_integer)
                && v != i64::from(RIG_VERSION)
            {
                return Err(RigError::Version {
                    origin: origin.to_string(),
                    found: u32::try_from(v).unwrap_or(u32::MAX),
                    supported: RIG_VERSION,
                });
            }
            let tagged = table.get("kind").and_then(toml::Value::as_str);
            let found = match tagged {
                Some(tag) => RigKind::deserialize(toml::Value::from(tag)).ok(),
                None => RigKind::by_sections(&table),
            };
            if let Some(found) = found
                && found != Self::KIND
            {
                return Err(RigError::WrongKind {
                    origin: origin.to_string(),
                    found: found.as_str(),
                    wanted: Self::KIND.as_str(),
                });
            }
        }
        let rig: Self = toml::from_str(text).map_err(|e| RigError::Parse {
            origin: origin.to_string(),
            message: e.to_string().trim_end().to_string(),
        })?;
        rig.validate().map_err(|e| match e {
            RigError::Version { found, .. } => RigError::Version {
                origin: origin.to_string(),
                found,
                supported: RIG_VERSION,
            },
            other => RigError::InFile {
                origin: origin.to_string(),
                source: Box::new(other),
            },
        })?;
        Ok(rig)
    }

    /// The rig as TOML (parses back to an equal rig).
    fn to_toml(&self) -> String {
        toml::to_string_pretty(self).unwrap_or_else(|e| format!("# cannot print rig: {e}\n"))
    }
}

/// The checks every kind shares: the version, the kind tag and a name.
pub(crate) fn check_header(
    version: u32,
    kind: RigKind,
    wanted: RigKind,
    name: &str,
) -> Result<(), RigError> {
    if version != RIG_VERSION {
        return Err(RigError::Version {
            origin: format!("rig '{name}'"),
            found: version,
            supported: RIG_VERSION,
        });
    }
    if kind != wanted {
        return Err(RigError::WrongKind {
            origin: format!("rig '{name}'"),
            found: kind.as_str(),
            wanted: wanted.as_str(),
        });
    }
    crate::validation::require(
        !name.trim().is_empty(),
        "name",
        "\"\"",
        "",
        "a non-empty rig name",
    )?;
    Ok(())
}

/// Default `kind` of a shaker rig file that has no `kind` key.
pub(crate) fn shaker_kind() -> RigKind {
    RigKind::Shaker
}

/// Default `kind` of a drop-test rig file that has no `kind` key.
pub(crate) fn drop_test_kind() -> RigKind {
    RigKind::DropTest
}

/// Default `kind` of a host file that has no `kind` key.
pub(crate) fn host_kind() -> RigKind {
    RigKind::Host
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rig::{DropRigSpec, RigSpec};

    #[test]
    fn every_checked_in_rig_file_loads_as_its_kind() {
        let root = Path::new(env!("CARGO_MANIFEST_DIR"));
        let mut seen = 0;
        let entries = std::fs::read_dir(root.join("rig"))
            .expect("rig/ exists")
            .chain(std::fs::read_dir(root.join("host")).expect("host/ exists"));
        for entry in entries {
            let path = entry.expect("entry").path();
            if path.extension().is_none_or(|e| e != "toml") {
                continue;
            }
            let text = std::fs::read_to_string(&path).expect("readable");
            let table: toml::Table = text.parse().expect("valid TOML");
            match table.get("kind").and_then(toml::Value::as_str) {
                Some("shaker") => drop(RigSpec::load(&path).expect("shaker rig")),
                Some("drop-test") => drop(DropRigSpec::load(&path).expect("drop rig")),
                // Loaded by the host module's own test (it sits above rig).
                Some("host") => assert!(path.starts_with(root.join("host"))),
                other => panic!("{}: kind {other:?}", path.display()),
            }
            seen += 1;
        }
        assert_eq!(
            seen,
            BUILTIN.len(),
            "every file in rig/ and host/ is built in"
        );
        for (name, kind) in builtin_rigs() {
            let text = builtin_toml(name).expect("built in");
            assert!(text.contains(&format!("kind = \"{kind}\"")), "{name}");
        }
    }

    #[test]
    fn a_rig_of_the_wrong_kind_is_refused_by_its_kind() {
        let drop_rig = builtin_toml("drop-test").expect("built in");
        let msg = RigSpec::from_toml_str(drop_rig, "d.toml")
            .expect_err("a drop rig is no shaker rig")
            .to_string();
        assert_eq!(
            msg,
            "d.toml is a drop-test rig; a shaker rig is needed here"
        );
        // Without the tag the sections tell.
        let untagged = drop_rig.replace("kind = \"drop-test\"", "");
        let msg = RigSpec::from_toml_str(&untagged, "d.toml")
            .expect_err("still a drop rig")
            .to_string();
        assert!(msg.contains("is a drop-test rig"), "{msg}");
        let shaker = builtin_toml("ideal").expect("built in");
        assert!(DropRigSpec::from_toml_str(shaker, "s.toml").is_err());
        assert_eq!(RigSpec::names(), ["thesis-shaker", "ideal"]);
        assert_eq!(DropRigSpec::names(), ["drop-test"]);
    }
}
