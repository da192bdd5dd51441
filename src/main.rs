//! `irtp`: thin binary over the irtp library.

mod cli;

use clap::Parser;
use irtp::app::{self, Cli};
use std::process::ExitCode;

fn run(cli: Cli) -> anyhow::Result<()> {
    let reporter = cli::progress::Bars;
    let ctx = app::Context::new(&reporter);
    let outcome = app::run(&cli.command, &ctx)?;
    cli::present(&outcome, cli.command.json())
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
        Ok(()) => ExitCode::SUCCESS,
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
