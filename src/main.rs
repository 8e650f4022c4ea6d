//! The `vlab` command line: a virtual granular-damper laboratory.
//!
//! Library errors are typed; here they gain context and are printed as one line
//! (`error: <what> : <why>`), and the process exits non-zero.

mod cli;

fn main() -> std::process::ExitCode {
    cli::main()
}
