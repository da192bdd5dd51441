//! `irtp`: thin binary over the irtp library (the command line itself is
//! [`irtp_cli::run_cli`], shared with the Python package's console script).

use std::process::ExitCode;

fn main() -> ExitCode {
    // A closed pipe (`irtp ... | head`) ends the program quietly, as it
    // ends every Unix filter, instead of a panic in `print!`: Rust starts
    // programs with SIGPIPE ignored.
    #[cfg(unix)]
    // SAFETY: restoring the default disposition of one signal before any
    // thread is started.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
    ExitCode::from(irtp_cli::run_cli(std::env::args_os().collect()))
}
