//! `vlab rig`: the built-in rigs (the shaker rigs and the drop-test rig), and
//! their TOML, so a user can copy one, change it and pass it with `--rig FILE`.

use anyhow::{Result, bail};
use clap::Args;

use vlab::rig::RigSpec;
use vlab::rig::drop_spec::{DROP_RIG, DROP_RIG_TOML, DropRigSpec};

#[derive(Debug, Clone, Args)]
pub struct RigArgs {
    /// A built-in rig to show [default: list them all].
    #[arg(value_name = "NAME")]
    name: Option<String>,
    /// Print the rig file (TOML, annotated) instead of a summary.
    #[arg(long)]
    print: bool,
}

pub fn run(a: RigArgs) -> Result<()> {
    let Some(name) = a.name else {
        if a.print {
            bail!(
                "--print needs a rig NAME: one of {}, {DROP_RIG}",
                RigSpec::names().join(", ")
            );
        }
        for name in RigSpec::names() {
            let rig = RigSpec::builtin(name)?;
            println!("{name:14} {}", rig.description);
        }
        let drop = DropRigSpec::builtin()?;
        println!("{DROP_RIG:14} {}", drop.description);
        println!(
            "(vlab rig NAME --print shows a rig's file; copy it, edit it, pass it with --rig FILE)"
        );
        return Ok(());
    };
    let text = if name == DROP_RIG {
        DROP_RIG_TOML
    } else {
        match RigSpec::builtin_toml(&name) {
            Some(t) => t,
            None => bail!(
                "no built-in rig '{name}': the built-in rigs are {}, {DROP_RIG}",
                RigSpec::names().join(", ")
            ),
        }
    };
    if a.print {
        print!("{text}");
        return Ok(());
    }
    if name == DROP_RIG {
        let d = DropRigSpec::builtin()?;
        println!("{}: {}", d.name, d.description);
        println!(
            "  plate rings at {:.0} Hz on its transducer; force sampled at {} Hz",
            d.plate_natural_freq_hz(),
            d.daq.sample_rate_hz
        );
    } else {
        let r = RigSpec::builtin(&name)?;
        println!("{}: {}", r.name, r.description);
        println!(
            "  enclosure above the gauge {} kg; default shaker {}; sample rate {} Hz",
            r.enclosure.mass_kg,
            super::shake_name(r.shaker.kind),
            r.daq.sample_rate_hz
        );
        for f in [20.0, 40.0, 160.0] {
            println!(
                "  phase error of the model at {f} Hz: {:.4} deg",
                r.expected_phase_error_rad(f).to_degrees()
            );
        }
    }
    Ok(())
}
