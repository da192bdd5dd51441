//! The commands of the `irtp` program as library calls, shared by every
//! front end (the `irtp` binary, the Python module).
//!
//! Each command has one home here: its flags (clap `Args`, which are also the
//! Python keyword arguments and their defaults), their validation into a
//! config, the computation, and the files it writes. A front end parses its
//! input into the `Args`, calls the command's `run` with a [`Context`], and
//! presents the returned [`Outcome`]: the binary prints its text or JSON; the
//! Python module hands out its tables as numpy arrays. The same `Args` give
//! the same numbers, bit for bit, through either.
//!
//! Layering: this crate sits above the core (`irtp`) and below the paper's
//! figures (`irtp-paper`, which adds `reproduce`) and the front ends.

pub mod analytic;
mod analytic_noise;
pub mod applies;
pub mod budget;
pub mod common;
pub mod format;
pub mod fp;
pub mod fp_msd;
pub mod fpt;
pub mod help;
pub mod io;
pub mod keywords;
pub mod lock;
pub mod mfpt;
pub mod simulate;
pub mod sweep;

/// The version every provenance file records (the workspace's).
pub const VERSION: &str = env!("CARGO_PKG_VERSION");
/// The git revision of the build, where it was built from a checkout.
pub const GIT_REVISION: Option<&str> = option_env!("IRTP_GIT_REVISION");

/// `0.1.0 (git <revision>)`: the version and git revision every provenance
/// file records (`irtp --version`; the Python module's `__version__` and
/// `__git_revision__`).
pub fn long_version() -> &'static str {
    static TEXT: std::sync::OnceLock<String> = std::sync::OnceLock::new();
    TEXT.get_or_init(|| match GIT_REVISION {
        Some(rev) => format!("{VERSION} (git {rev})"),
        None => format!("{VERSION} (no git revision: built outside a checkout)"),
    })
}

use crate::io::{out_in_use, OutputDir, Previous, Provenance};
use clap::{Parser, Subcommand};
use irtp::error::{Error, Result};
use irtp::parallel::Progress;
use serde::Serialize;
use serde_json::Value;
use std::path::{Path, PathBuf};

/// Inertial run-and-tumble particles with velocity resetting in non-Newtonian media.
#[derive(Parser, Debug)]
#[command(name = "irtp", version, about, long_about = None)]
pub struct Cli {
    /// The command.
    #[command(subcommand)]
    pub command: Command,
}

/// The commands of `irtp`.
// Parsed once per run: the size of the largest flag set costs nothing.
#[allow(clippy::large_enum_variant)]
#[derive(Subcommand, Debug)]
pub enum Command {
    /// Exact stationary velocity density P_s(v) at r = 0, its regime and <v²> (closed form).
    ///
    /// The r = 0 stationary density of the velocity in closed form: the
    /// regime (peaks inside the interval or at its edges), the edge
    /// exponent, <v²>, <v⁴> and density.csv. With linear drag also r > 0
    /// and other noises (Eqs. (N3)-(N6)); an asymmetric telegraph noise at
    /// r = 0 with any drag (Eq. (N8)). Nothing is sampled or discretised.
    #[command(after_help = help::ANALYTIC)]
    Analytic(analytic::AnalyticArgs),
    /// Simulate particles: <v²>(t), <x²>(t), P_s(v) and D_eff (exact sampler or Euler scheme).
    ///
    /// Independent particles from v = 0, x = 0: the moments ⟨v⟩, ⟨v²⟩,
    /// <x²> on a time grid, the stationary velocity histogram over
    /// [--burn-in, --t-max] and D_eff, with standard errors. `--method
    /// exact` (default) samples the process event by event with no time
    /// step; `--method euler` is the paper's scheme (Eqs. (30)-(32)).
    #[command(after_help = help::SIMULATE)]
    Simulate(simulate::SimulateArgs),
    /// Mean first-passage time tau to a target velocity --vt or, a search, a position --xt/--interval.
    ///
    /// tau from --v0 to the target velocity --vt by the backward equations
    /// (default, with an error estimate) or by particles (--method exact or
    /// euler); with --xt or --interval, the search: first passage of the
    /// position x (with --reset-position the mean is finite; --method
    /// renewal integrates over the reset clock). Subcommands scan a
    /// parameter, find the optimal reset rate, or give the whole
    /// distribution of the first-passage time.
    #[command(after_help = help::MFPT)]
    Mfpt(mfpt::MfptArgs),
    /// Fokker-Planck solvers: stationary P_s(v), <v²>, exact D_eff; transient <v²>(t); <x²>(t).
    ///
    /// Deterministic solutions of the forward (Fokker-Planck) equations of
    /// the velocity (Eqs. (11)-(12)), with no sampling noise: `stationary`
    /// (density, moments, D_eff), `transient` (from the paper's initial
    /// condition) and `msd` (position moments by the moment chain).
    #[command(after_help = help::FP)]
    Fp(fp::FpArgs),
}

/// What a command's flags do, one implementation per command: the one
/// place a new command is wired in is [`Command::args`].
pub trait Runnable {
    /// Whether `--json` was given.
    fn json(&self) -> bool;
    /// Validate the flags as the run would (ranges, combinations), without
    /// computing anything.
    fn validate(&self) -> Result<()>;
    /// Whether the command draws random numbers (so takes `--seed`):
    /// simulations and particle first-passage methods; the deterministic
    /// solvers refuse a seed.
    fn uses_seed(&self) -> bool;
    /// Run the command.
    fn run(&self, ctx: &Context) -> Result<Outcome>;
}

impl Command {
    /// The command's flags, behind the one interface every command shares.
    pub fn args(&self) -> &dyn Runnable {
        match self {
            Command::Analytic(a) => a,
            Command::Simulate(a) => a,
            Command::Mfpt(a) => a,
            Command::Fp(a) => a,
        }
    }

    /// Whether `--json` was given.
    pub fn json(&self) -> bool {
        self.args().json()
    }
}

impl Runnable for analytic::AnalyticArgs {
    fn json(&self) -> bool {
        self.json
    }
    fn validate(&self) -> Result<()> {
        self.config().map(drop)
    }
    fn uses_seed(&self) -> bool {
        false
    }
    fn run(&self, ctx: &Context) -> Result<Outcome> {
        analytic::run(self, ctx)
    }
}

impl Runnable for simulate::SimulateArgs {
    fn json(&self) -> bool {
        self.output.json
    }
    fn validate(&self) -> Result<()> {
        self.config().map(drop)
    }
    fn uses_seed(&self) -> bool {
        true
    }
    fn run(&self, ctx: &Context) -> Result<Outcome> {
        simulate::run(self, ctx)
    }
}

impl Runnable for mfpt::MfptArgs {
    fn json(&self) -> bool {
        mfpt::MfptArgs::json(self)
    }
    fn validate(&self) -> Result<()> {
        mfpt::MfptArgs::validate(self)
    }
    fn uses_seed(&self) -> bool {
        mfpt::MfptArgs::uses_seed(self)
    }
    fn run(&self, ctx: &Context) -> Result<Outcome> {
        mfpt::run(self, ctx)
    }
}

impl Runnable for fp::FpArgs {
    fn json(&self) -> bool {
        fp::FpArgs::json(self)
    }
    fn validate(&self) -> Result<()> {
        fp::FpArgs::validate(self)
    }
    fn uses_seed(&self) -> bool {
        false
    }
    fn run(&self, ctx: &Context) -> Result<Outcome> {
        fp::run(self, ctx)
    }
}

/// Validate a command's flags as its run would (ranges, combinations),
/// without computing anything.
pub fn validate(command: &Command) -> Result<()> {
    command.args().validate()
}

/// Whether a command draws random numbers (so takes `--seed`).
pub fn uses_seed(command: &Command) -> bool {
    command.args().uses_seed()
}

/// Run a command.
pub fn run(command: &Command, ctx: &Context) -> Result<Outcome> {
    command.args().run(ctx)
}

/// How a front end shows progress and asks a run to stop.
pub trait Reporter: Sync {
    /// A progress observer for one stage of work (`label`, `total` units);
    /// dropping it ends the stage (a terminal bar is cleared).
    fn stage(&self, label: &str, total: u64) -> Box<dyn Progress + '_>;
    /// Whether the caller wants the run stopped (then the run returns
    /// [`Error::Interrupted`] and writes nothing).
    fn cancelled(&self) -> bool {
        false
    }
}

/// A reporter that shows nothing and never cancels.
pub struct Quiet;

impl Reporter for Quiet {
    fn stage(&self, _label: &str, _total: u64) -> Box<dyn Progress + '_> {
        Box::new(irtp::parallel::NoProgress)
    }
}

/// What a run needs from its front end.
pub struct Context<'a> {
    /// Progress and cancellation.
    pub reporter: &'a dyn Reporter,
    /// The command line recorded in `run.json` (the binary's own argv; the
    /// Python module records the equivalent `irtp ...` command line).
    pub argv: Vec<String>,
}

impl<'a> Context<'a> {
    /// A context recording this process's command line.
    pub fn new(reporter: &'a dyn Reporter) -> Self {
        Context {
            reporter,
            argv: std::env::args().collect(),
        }
    }

    /// [`Error::Interrupted`] when the reporter asked to stop: a cancelled
    /// computation's partial result is never returned nor written.
    pub fn check(&self) -> Result<()> {
        if self.reporter.cancelled() {
            Err(Error::Interrupted)
        } else {
            Ok(())
        }
    }
}

/// One result table: the columns of a CSV file the command writes.
#[derive(Clone, Debug, PartialEq)]
pub struct Table {
    /// File stem (`moments` for `moments.csv`).
    pub name: &'static str,
    /// Column names, in file order.
    pub header: Vec<String>,
    /// Columns (each as long as the table).
    pub columns: Vec<Vec<f64>>,
}

impl Table {
    /// A table from its header and rows.
    pub fn from_rows<R: AsRef<[f64]>>(
        name: &'static str,
        header: &[&str],
        rows: impl IntoIterator<Item = R>,
    ) -> Self {
        let mut columns = vec![Vec::new(); header.len()];
        for row in rows {
            for (c, x) in columns.iter_mut().zip(row.as_ref()) {
                c.push(*x);
            }
        }
        Table {
            name,
            header: header.iter().map(|h| h.to_string()).collect(),
            columns,
        }
    }

    /// Number of rows.
    pub fn len(&self) -> usize {
        self.columns.first().map_or(0, Vec::len)
    }

    /// Whether the table has no rows.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    fn write(&self, out: &mut OutputDir) -> Result<()> {
        let header: Vec<&str> = self.header.iter().map(String::as_str).collect();
        let rows = (0..self.len()).map(|i| self.columns.iter().map(|c| c[i]).collect::<Vec<_>>());
        out.write_csv(&format!("{}.csv", self.name), &header, rows)
    }
}

/// Values accepted under a former name: (flag, old value, current value).
const OLD_NAMES: &[(&str, &str, &str)] = &[("--method", "ode", "backward")];

/// A warning for each value of `argv` given by its former name
/// ([`OLD_NAMES`]): the run goes on under the current one.
fn old_names(argv: &[String]) -> Vec<String> {
    let mut found = Vec::new();
    for (i, arg) in argv.iter().enumerate() {
        for &(flag, old, new) in OLD_NAMES {
            let value = match arg.strip_prefix(flag) {
                Some(v) if v.strip_prefix('=') == Some(old) => true,
                Some("") => argv.get(i + 1).map(String::as_str) == Some(old),
                _ => false,
            };
            if value {
                found.push(format!(
                    "{flag} {old} is the former name of {flag} {new}; it runs {flag} {new}"
                ));
            }
        }
    }
    found
}

/// The result of one command: what it computed, its provenance and the
/// files it wrote.
#[derive(Clone, Debug)]
pub struct Outcome {
    /// The command (`simulate`, `fp stationary`, ...).
    pub command: &'static str,
    /// What the command computed.
    pub results: Results,
    /// `run.json` as written (or as it would be written without `--out`).
    pub provenance: Value,
    /// `summary.json` as written (and as `--json` prints it): see [`summary`].
    pub summary: Value,
    /// The output directory and the files written there, when one was given.
    pub written: Option<(PathBuf, Vec<PathBuf>)>,
    /// Warnings for the user (files in `--out` that `--force` left alone).
    pub warnings: Vec<String>,
}

/// What a command computed: what `--json` prints, the tables and the text
/// report; [`Outcome`] adds the provenance and the files written.
#[derive(Clone, Debug)]
pub struct Results {
    /// The numerical method, as recorded in `run.json`.
    pub method: String,
    /// The master seed of a stochastic method.
    pub seed: Option<u64>,
    /// What `--json` prints (one object, or one object per row for a scan).
    pub json: Value,
    /// The `parameters` object of `run.json`.
    pub parameters: Value,
    /// The tables (`<name>.csv` in the output directory).
    pub tables: Vec<Table>,
    /// Further JSON files of the output directory (`mfpt.json`, ...);
    /// `summary.json` is written by `finish` for every command.
    pub json_files: Vec<(&'static str, Value)>,
    /// The text-mode report (without the list of written files).
    pub text: String,
    /// Wall-clock seconds of the computation.
    pub wall_time_s: f64,
}

impl Results {
    /// The table with this name.
    pub fn table(&self, name: &str) -> Option<&Table> {
        self.tables.iter().find(|t| t.name == name)
    }
}

/// JSON value of a serialisable result (these never fail: plain structs of
/// numbers and strings).
pub(crate) fn to_value<T: Serialize>(v: &T) -> Value {
    serde_json::to_value(v).expect("result structs serialise to JSON")
}

/// Open the output directory, if any, before computing (a bad path fails at
/// once). A directory holding files irtp did not write, or the outputs of
/// another command, is refused unless `force`; a previous run of the same
/// command is replaced at commit (without `force`, only by a run with the
/// same parameters: checked by [`finish`]).
pub(crate) fn open_out(
    command: &str,
    dir: Option<&Path>,
    force: bool,
) -> Result<Option<OutputDir>> {
    let Some(dir) = dir else {
        return Ok(None);
    };
    let out = OutputDir::new(dir)?;
    // The default picture of `irtp plot` is not in a rerun's way.
    let prev = Previous::read(dir, &[io::PLOT_FILE.to_string()])?;
    prev.refuse_changed(dir)?;
    let other = prev.command().filter(|c| *c != command);
    if !force {
        if !prev.foreign.is_empty() {
            return Err(out_in_use(
                dir,
                format!("{}, which irtp did not write", prev.foreign_list()),
            ));
        }
        if let Some(c) = other {
            return Err(out_in_use(dir, format!("the outputs of `irtp {c}`")));
        }
    }
    let mut out = out.replacing(prev.ours.clone());
    if force && !prev.foreign.is_empty() {
        out.warn(prev.left_alone(dir));
    }
    match prev.run {
        Some(run) if !force => Ok(Some(out.expecting(run))),
        _ => Ok(Some(out)),
    }
}

/// Refuse to replace a previous run of the same command with other
/// parameters, method or seed.
fn same_run(out: &OutputDir, prov: &Value) -> Result<()> {
    let Some(prev) = out.previous() else {
        return Ok(());
    };
    let mut differ: Vec<String> = ["method", "seed"]
        .into_iter()
        .filter(|k| prev[k] != prov[k])
        .map(String::from)
        .collect();
    match (
        prev["parameters"].as_object(),
        prov["parameters"].as_object(),
    ) {
        (Some(a), Some(b)) => differ.extend(
            a.keys()
                .chain(b.keys().filter(|k| !a.contains_key(*k)))
                .filter(|k| a.get(*k) != b.get(*k))
                .cloned(),
        ),
        _ if prev["parameters"] != prov["parameters"] => differ.push("parameters".into()),
        _ => {}
    }
    if differ.is_empty() {
        return Ok(());
    }
    Err(out_in_use(
        out.target(),
        format!(
            "a run of `irtp {}` with other {}",
            prov["command"].as_str().unwrap_or("?"),
            differ.join(", ")
        ),
    ))
}

/// The schema name of `summary.json` and of the `--json` object.
pub const SUMMARY_SCHEMA: &str = "irtp.summary/1";

/// The keys of `run.json` repeated under `provenance` in `summary.json`.
const PROVENANCE_KEYS: [&str; 8] = [
    "software",
    "version",
    "git_revision",
    "argv",
    "seed",
    "threads",
    "wall_time_s",
    "finished_unix",
];

/// The one output object of every command, written as `summary.json` and
/// printed by `--json`: `schema`, `command`, `method`, `params` (the run
/// parameters, as in `run.json`), `results` (what the command computed,
/// each value with its error where it has one) and `provenance` (the
/// version, revision, seed, command line and time of `run.json`).
pub fn summary(command: &str, r: &Results, run: &Value) -> Value {
    let provenance: serde_json::Map<String, Value> = PROVENANCE_KEYS
        .iter()
        .map(|k| (k.to_string(), run[*k].clone()))
        .collect();
    serde_json::json!({
        "schema": SUMMARY_SCHEMA,
        "command": command,
        "method": r.method,
        "params": r.parameters,
        "results": r.json,
        "provenance": provenance,
    })
}

/// A non-finite number in a result table is never returned nor written.
fn refuse_non_finite(command: &'static str, tables: &[Table]) -> Result<()> {
    for t in tables {
        for (h, c) in t.header.iter().zip(&t.columns) {
            if let Some((i, x)) = c.iter().enumerate().find(|(_, x)| !x.is_finite()) {
                return Err(Error::Numerical {
                    method: command,
                    reason: format!(
                        "{h} = {x} in row {i} of {}.csv: the computation overflowed for these parameters; refused",
                        t.name
                    ),
                });
            }
        }
    }
    Ok(())
}

/// Check for cancellation, then write the tables, the JSON files and
/// `run.json` (all or nothing) and assemble the [`Outcome`].
pub(crate) fn finish(
    command: &'static str,
    results: Results,
    out: Option<OutputDir>,
    ctx: &Context,
) -> Result<Outcome> {
    ctx.check()?;
    let r = &results;
    // First-passage tables mark a tau beyond the f64 range (the target is
    // practically never reached) as inf, point by point; every other table
    // holds only finite numbers.
    if !command.starts_with("mfpt") {
        refuse_non_finite(command, &r.tables)?;
    }
    let prov = Provenance::new(
        command,
        r.method.clone(),
        r.seed,
        &r.parameters,
        r.wall_time_s,
    )
    .with_argv(ctx.argv.clone());
    let mut warnings = old_names(&ctx.argv);
    let summary = summary(command, r, &to_value(&prov));
    let (provenance, written) = match out {
        None => (to_value(&prov), None),
        Some(mut o) => {
            same_run(&o, &to_value(&prov))?;
            warnings.extend_from_slice(o.warnings());
            for t in &r.tables {
                t.write(&mut o)?;
            }
            for (name, v) in &r.json_files {
                o.write_json(name, v)?;
            }
            o.write_json("summary.json", &summary)?;
            // A stop asked for while the files were staged: nothing is committed.
            ctx.check()?;
            let target = o.target().to_path_buf();
            let (prov, files) = o.commit_with_provenance_value(prov)?;
            (prov, Some((target, files)))
        }
    };
    Ok(Outcome {
        command,
        results,
        provenance,
        summary,
        written,
        warnings,
    })
}
