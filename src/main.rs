//! The `vlab` command line: a virtual granular-damper laboratory.
//!
//! Library errors are typed; here they gain context and are printed as one line
//! (`error: <what> : <why>`), and the process exits non-zero.

mod cli;

fn main() -> std::process::ExitCode {
    // A reader that stops reading (`vlab host frf ... | head`) ends the
    // process quietly, as it ends a C program, instead of a panic with a
    // backtrace from the next `println!` (Rust ignores SIGPIPE by default).
    #[cfg(unix)]
    // SAFETY: resetting one signal's disposition to its default at the start
    // of main, before any other thread exists, touches no Rust state.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
    cli::main()
}
