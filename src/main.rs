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
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Exact r = 0 stationary velocity density: regime, <v^2>, density.csv.
    Analytic(app::analytic::AnalyticArgs),
    /// Particle simulation (exact event-driven sampler, or the paper's Euler scheme): moments, densities.
    Simulate(app::simulate::SimulateArgs),
    /// Mean first-passage time to a target velocity (backward equations or particles).
    Mfpt(app::mfpt::MfptArgs),
    /// Fokker-Planck solvers: stationary density, <v²>, D_eff; transient <v²>(t).
    Fp(app::fp::FpArgs),
    /// Regenerate the paper's figures (data, plots, claims).
    Reproduce(app::reproduce::ReproduceArgs),
}

fn run(cli: Cli) -> anyhow::Result<()> {
    let reporter = cli::progress::Bars;
    let ctx = app::Context::new(&reporter);
    let (outcome, json) = match &cli.command {
        Command::Analytic(a) => (app::analytic::run(a, &ctx)?, a.json),
        Command::Simulate(a) => (app::simulate::run(a, &ctx)?, a.output.json),
        Command::Mfpt(a) => (app::mfpt::run(a, &ctx)?, a.json()),
        Command::Fp(a) => (app::fp::run(a, &ctx)?, a.json()),
        Command::Reproduce(a) => (app::reproduce::run(a, &ctx)?, false),
    };
    cli::present(&outcome, json)
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
