//! The `irtp` command line as a library: [`run_cli`] parses the arguments
//! with clap, runs the command and prints its report, exactly as the `irtp`
//! binary (`src/main.rs`, which only calls it) and the Python package's
//! `irtp` console script (the extension calls it with `sys.argv`) do, so
//! both are the same program.

pub mod cli;

use clap::{Parser, Subcommand};
use irtp_paper::Command;
use std::ffi::OsString;
use std::io::Write;

/// Inertial run-and-tumble particles with velocity resetting in non-Newtonian media.
#[derive(Parser, Debug)]
#[command(name = "irtp", version = irtp_app::long_version(), about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: TopCommand,
}

/// The library's commands ([`irtp_paper::Command`]), the sweeps and `plot`.
// Parsed once per run: the size of the largest flag set costs nothing.
#[allow(clippy::large_enum_variant)]
#[derive(Subcommand, Debug)]
enum TopCommand {
    #[command(flatten)]
    App(Command),
    /// Parameter sweeps from a TOML plan: run (sharded, resumable), merge, status, SLURM arrays.
    Sweep(cli::sweep::SweepArgs),
    /// Draw the natural figure of an output directory (a run or a sweep) as PNG or SVG.
    Plot(irtp_paper::quicklook::PlotArgs),
}

/// Run the command; the exit code on success (0; `sweep` may report 3;
/// 130 or 143 after SIGINT or SIGTERM).
fn run(cli: Cli) -> anyhow::Result<u8> {
    match cli.command {
        TopCommand::App(command) => {
            cli::signals::install()?;
            let reporter = cli::progress::Bars;
            let ctx = irtp_app::Context::new(&reporter);
            let outcome = match (command.run(&ctx), cli::signals::received()) {
                (Err(_), Some((code, name))) => {
                    eprintln!(
                        "irtp: interrupted by {name}: stopped; unfinished results were not written \
                         (figures `reproduce` finished are kept)"
                    );
                    return Ok(code);
                }
                (outcome, _) => outcome?,
            };
            cli::present(&outcome, command.json())?;
            Ok(0)
        }
        TopCommand::Sweep(a) => cli::sweep::run(a),
        TopCommand::Plot(a) => {
            let path = irtp_paper::quicklook::run(&a)?;
            println!("wrote {}", path.display());
            Ok(0)
        }
    }
}

/// A command line clap refused. Help and version go to stdout (exit 0). A
/// missing subcommand (bare `irtp`, `irtp fp`) prints the usage to stderr;
/// every other usage error is one line on stderr naming what is wrong,
/// including the names of missing required flags (exit 2).
fn usage_error(e: clap::Error) -> u8 {
    use clap::error::ErrorKind;
    if !e.use_stderr() {
        let _ = e.print();
        return 0;
    }
    if e.kind() == ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand {
        let _ = e.print();
        return 2;
    }
    let msg = shorten_value(&one_line(&e.render().to_string()));
    let see = if msg.contains("--help") {
        ""
    } else {
        " (see --help)"
    };
    eprintln!("irtp: error: {msg}{see}");
    2
}

/// The value clap quotes in `invalid value '...' for '--flag'`, cut as
/// every echoed value is ([`irtp::error::echo`]: a huge expression is not
/// printed back whole).
fn shorten_value(msg: &str) -> String {
    const PREFIX: &str = "invalid value '";
    let Some(start) = msg.find(PREFIX).map(|i| i + PREFIX.len()) else {
        return msg.to_string();
    };
    let Some(len) = msg[start..].find("' for '") else {
        return msg.to_string();
    };
    let value = irtp::error::echo(&msg[start..start + len]);
    format!("{}{value}{}", &msg[..start], &msg[start + len..])
}

/// clap's message in one line: its first line, continued by the indented
/// lines that follow a trailing colon (the list of missing flags).
fn one_line(rendered: &str) -> String {
    let mut lines = rendered.lines().filter(|l| !l.trim().is_empty());
    let first = lines.next().unwrap_or("");
    let mut msg = first.strip_prefix("error: ").unwrap_or(first).to_string();
    if msg.ends_with(':') {
        let items: Vec<&str> = lines
            .take_while(|l| l.starts_with(' '))
            .map(str::trim)
            .collect();
        msg = format!("{} {}", msg, items.join(", "));
    }
    msg
}

/// Parse the command line: clap's checks, then the flags that do not
/// apply to the chosen method or target ([`irtp_app::applies`]).
fn parse(args: Vec<OsString>) -> Result<Cli, u8> {
    use clap::{CommandFactory, FromArgMatches};
    let mut command = Cli::command();
    let matches = command.try_get_matches_from_mut(args);
    let matches = matches.map_err(usage_error)?;
    if let Err(e) = irtp_app::applies::check(&matches) {
        eprintln!("irtp: error: {}", e.message_with(cli::flag_for));
        return Err(2);
    }
    Cli::from_arg_matches(&matches).map_err(|e| usage_error(e.format(&mut command)))
}

/// Run the `irtp` command line `args` (the program name first, as
/// `std::env::args_os()` gives it) and return its exit status: 0; 2 for
/// bad input, 4 for a numerical failure, 1 otherwise; `sweep` may report
/// 3; 130 or 143 after SIGINT or SIGTERM. Standard output and error are
/// flushed before it returns (a caller may exit without Rust's cleanup).
pub fn run_cli(args: Vec<OsString>) -> u8 {
    let code = match parse(args) {
        Ok(c) => report(run(c)),
        Err(code) => code,
    };
    let _ = std::io::stdout().flush();
    let _ = std::io::stderr().flush();
    code
}

/// The exit status of a run, its error printed as one line.
fn report(outcome: anyhow::Result<u8>) -> u8 {
    match outcome {
        Ok(code) => code,
        Err(e) => {
            // Library errors name parameters (`t_max`); the user typed flags (`--t-max`).
            let lib = e.downcast_ref::<irtp::Error>();
            let msg = lib.map_or_else(|| e.to_string(), |l| l.message_with(cli::flag_for));
            eprintln!("irtp: error: {msg}");
            match lib {
                Some(l) if l.is_input_error() => 2,
                Some(l) if l.is_numerical() => 4,
                _ => 1,
            }
        }
    }
}
