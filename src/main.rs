//! `irtp`: thin binary over the irtp library.

mod cli;

use clap::{Parser, Subcommand};
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
    Analytic(cli::analytic::AnalyticArgs),
    /// Particle simulation (Euler scheme of the paper): moments, densities.
    Simulate(cli::simulate::SimulateArgs),
    /// Mean first-passage time to a target velocity (backward equations or particles).
    Mfpt(cli::mfpt::MfptArgs),
    /// Fokker-Planck solvers: stationary density, <v²>, D_eff; transient <v²>(t).
    Fp(cli::fp::FpArgs),
    /// Regenerate the paper's figures (data, plots, claims).
    Reproduce(cli::reproduce::ReproduceArgs),
}

fn run(cli: Cli) -> anyhow::Result<()> {
    match cli.command {
        Command::Analytic(a) => cli::analytic::run(a),
        Command::Simulate(a) => cli::simulate::run(a),
        Command::Mfpt(a) => cli::mfpt::run(a),
        Command::Fp(a) => cli::fp::run(a),
        Command::Reproduce(a) => cli::reproduce::run(a),
    }
}

fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(c) => c,
        Err(e) => {
            // clap prints help/version on stdout (exit 0) and usage errors on stderr (exit 2).
            let _ = e.print();
            return ExitCode::from(if e.use_stderr() { 2 } else { 0 });
        }
    };
    match run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            let input = e
                .downcast_ref::<irtp::Error>()
                .is_some_and(|e| e.is_input_error());
            eprintln!("irtp: error: {e}");
            ExitCode::from(if input { 2 } else { 1 })
        }
    }
}
