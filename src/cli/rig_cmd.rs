//! `vlab rig`: the built-in rigs (the shaker rigs, the drop-test rig and the
//! host structures), and
//! their TOML, so a user can copy one, change it and pass it with `--rig FILE`.

use anyhow::{Result, bail};
use clap::Args;

use vlab::host::HostSpec;
use vlab::rig::{DropRigSpec, RigFile, RigKind, RigSpec, builtin_rigs, builtin_toml};

#[derive(Debug, Clone, Args)]
pub struct RigArgs {
    /// A built-in rig to show [default: list them all].
    #[arg(value_name = "NAME")]
    name: Option<String>,
    /// Print the rig file (TOML, annotated) instead of a summary.
    #[arg(long)]
    print: bool,
}

/// Names of every built-in rig, for messages.
fn all_names() -> String {
    builtin_rigs()
        .map(|(n, _)| n)
        .collect::<Vec<_>>()
        .join(", ")
}

pub fn run(a: RigArgs) -> Result<()> {
    let Some(name) = a.name else {
        if a.print {
            bail!("--print needs a rig NAME: one of {}", all_names());
        }
        return list();
    };
    let Some((_, kind)) = builtin_rigs().find(|(n, _)| *n == name) else {
        bail!(
            "no built-in rig '{name}': the built-in rigs are {}",
            all_names()
        );
    };
    if a.print {
        print!("{}", builtin_toml(&name).unwrap_or_default());
        return Ok(());
    }
    describe(&name, kind)
}

/// Every built-in rig, its kind and what it is.
fn list() -> Result<()> {
    for (name, kind) in builtin_rigs() {
        let description = match kind {
            RigKind::Shaker => RigSpec::builtin(name)?.description,
            RigKind::DropTest => DropRigSpec::builtin(name)?.description,
            RigKind::Host => HostSpec::builtin(name)?.description,
        };
        println!("{name:14} {kind:10} {description}");
    }
    println!(
        "(vlab rig NAME --print shows a rig's file; copy it, edit it, pass it with --rig FILE)"
    );
    Ok(())
}

/// What one built-in rig is: a drop rig's plate and rate, a host's modes, a
/// shaker rig's enclosure, rate and phase error.
fn describe(name: &str, kind: RigKind) -> Result<()> {
    match kind {
        RigKind::DropTest => {
            let d = DropRigSpec::builtin(name)?;
            println!("{} ({kind} rig): {}", d.name, d.description);
            println!(
                "  plate rings at {:.0} Hz on its transducer; force sampled at {} Hz",
                d.plate_natural_freq_hz(),
                d.daq.sample_rate_hz
            );
        }
        RigKind::Host => {
            let h = HostSpec::builtin(name)?;
            println!("{} ({kind}): {}", h.name, h.description);
            for (i, m) in h.modes.iter().enumerate() {
                println!(
                    "  mode {}: {:.2} Hz, modal mass {} kg, damping ratio {}, k {:.0} N/m, shape {} at the damper, {} at the drive",
                    i + 1,
                    m.natural_freq_hz(),
                    m.modal_mass_kg,
                    m.damping_ratio,
                    m.stiffness(),
                    m.shape_at_damper,
                    m.shape_at_drive
                );
            }
        }
        RigKind::Shaker => {
            let r = RigSpec::builtin(name)?;
            println!("{} ({kind} rig): {}", r.name, r.description);
            println!(
                "  enclosure above the gauge {} kg; default shaker {}; sample rate {} Hz",
                r.enclosure.mass_kg, r.shaker.kind, r.daq.sample_rate_hz
            );
            for f in [20.0, 40.0, 160.0] {
                println!(
                    "  phase error of the model at {f} Hz: {:.4} deg",
                    r.expected_phase_error_rad(f).to_degrees()
                );
            }
        }
    }
    Ok(())
}
