//! `irtp`: thin binary over the irtp library.

mod cli;

use clap::{Parser, Subcommand};
use irtp::app;
use std::process::ExitCode;

/// Inertial run-and-tumble particles with velocity resetting in non-Newtonian media.
#[derive(Parser, Debug)]
#[command(name = "irtp", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: TopCommand,
}

/// The library's commands ([`app::Command`]) and the sweeps.
#[derive(Subcommand, Debug)]
enum TopCommand {
    #[command(flatten)]
    App(app::Command),
    /// Parameter sweeps from a TOML plan: run (sharded, resumable), merge, status, SLURM arrays.
    Sweep(cli::sweep::SweepArgs),
}

/// Run the command; the exit code on success (0; `sweep` may report 3;
/// 130 or 143 after SIGINT or SIGTERM).
fn run(cli: Cli) -> anyhow::Result<u8> {
    match cli.command {
        TopCommand::App(command) => {
            cli::signals::install()?;
            let reporter = cli::progress::Bars;
            let ctx = app::Context::new(&reporter);
            let outcome = match (app::run(&command, &ctx), cli::signals::received()) {
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
    }
}

fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(c) => c,
        Err(e) => {
            // Help/version go to stdout (exit 0). Usage errors: clap's first line only, so that
            // every input error is one line on stderr (exit 2).
            if !e.use_stderr() {
                let _ = e.print();
                return ExitCode::SUCCESS;
            }
            let rendered = e.render().to_string();
            let first = rendered
                .lines()
                .find(|l| !l.trim().is_empty())
                .unwrap_or("");
            let first = first.strip_prefix("error: ").unwrap_or(first);
            eprintln!("irtp: error: {first} (see --help)");
            return ExitCode::from(2);
        }
    };
    match run(cli) {
        Ok(code) => ExitCode::from(code),
        Err(e) => {
            // Library errors name parameters (`t_max`); the user typed flags (`--t-max`).
            let lib = e.downcast_ref::<irtp::Error>();
            let input = lib.is_some_and(|e| e.is_input_error());
            let msg = lib.map_or_else(|| e.to_string(), |l| l.message_with(cli::flag_for));
            eprintln!("irtp: error: {msg}");
            ExitCode::from(if input { 2 } else { 1 })
        }
    }
}
