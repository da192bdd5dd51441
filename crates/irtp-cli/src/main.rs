//! `irtp`: thin binary over the irtp library (the command line itself is
//! [`irtp_cli::run_cli`], shared with the Python package's console script).

use std::process::ExitCode;

fn main() -> ExitCode {
    ExitCode::from(irtp_cli::run_cli(std::env::args_os().collect()))
}
