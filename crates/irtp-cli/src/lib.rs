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

/// Inertial run-and-tumble particles with velocity resetting in non-Newtonian media: exact
/// densities, simulations, Fokker-Planck solutions and first-passage times.
#[derive(Parser, Debug)]
#[command(
    name = "irtp",
    version = irtp_app::long_version(),
    about = ABOUT,
    long_about = LONG_ABOUT,
    after_help = EXAMPLES
)]
struct Cli {
    #[command(subcommand)]
    command: TopCommand,
}

/// The first line of `irtp -h`.
const ABOUT: &str = "Inertial run-and-tumble particles with velocity resetting in shear-thinning and \
                     shear-thickening media: exact densities, simulations, Fokker-Planck solutions, \
                     first-passage times";

/// The opening of `irtp --help`: the model and the questions each command answers.
const LONG_ABOUT: &str = "\
Inertial run-and-tumble particles with velocity resetting in shear-thinning and shear-thickening
media. The velocity obeys dv/dt = -g(v) + eta(t): a drag g(v) (tan: shear-thickening, tanh:
shear-thinning, linear, or any other law), a telegraph noise eta = ±Sigma flipping at rate lambda,
and resets to v_r at rate r. irtp computes (closed forms exactly, the others with error estimates):
  - the stationary velocity density P_s(v), exact at r = 0 (analytic) or solved (fp stationary);
  - <v²>(t), <x²>(t) and the effective diffusion coefficient D_eff (fp, simulate);
  - the mean first-passage time tau to a velocity or a position and the resetting rate that
    minimises it (mfpt, mfpt optimize);
  - the paper's figures and claims (reproduce), parameter sweeps (sweep) and their plots (plot).
`irtp <command> --help` says what a command computes, its flags with their defaults, and examples.";

/// The examples that end `irtp --help` (run by the tests).
const EXAMPLES: &str = "\
Examples:
  irtp analytic --drag tanh --sigma 0.6            # exact P_s(v) at r = 0, diverging at the edges
  irtp fp stationary --rate 0.5 --out runs/fp      # P_s(v), <v²> and D_eff at r = 0.5
  irtp plot runs/fp                                # its figure: runs/fp/plot.png
  irtp mfpt optimize --v0 0 --vt 1                 # the resetting rate that minimises tau";

/// The library's commands ([`irtp_paper::Command`]), the sweeps and `plot`.
// Parsed once per run: the size of the largest flag set costs nothing.
#[allow(clippy::large_enum_variant)]
#[derive(Subcommand, Debug)]
enum TopCommand {
    #[command(flatten)]
    App(Command),
    /// Parameter sweeps from a TOML plan: run (sharded, resumable), merge, status, SLURM arrays.
    #[command(long_about = cli::sweep::long_about(), after_help = cli::sweep::EXAMPLES)]
    Sweep(cli::sweep::SweepArgs),
    /// Draw the natural figure of an output directory (a run or a sweep) as PNG or SVG.
    ///
    /// The figure each command's outputs call for (a density, <v²>(t),
    /// tau against the scanned parameter, ...), or a sweep's column over
    /// its crossed axes (a line for one axis, a heat map for two, small
    /// multiples for more).
    #[command(after_help = PLOT_EXAMPLES)]
    Plot(irtp_paper::quicklook::PlotArgs),
}

/// The examples that end `irtp plot --help` (run by the tests).
const PLOT_EXAMPLES: &str = "\
Examples:
  irtp fp stationary --out runs/fp
  irtp plot runs/fp                                # runs/fp/plot.png
  irtp plot runs/fp --out fp.svg                   # as SVG";

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
