//! `irtp mfpt`: mean first-passage time to a target velocity.
//!
//! - `irtp mfpt --v0 V0 --vt VT [--method backward|euler|exact]`: one problem;
//! - `irtp mfpt --xt L | --interval A,B [--x0 X0] --v0 V0 --method exact`: the
//!   search problem, first passage in position (the `search` submodule);
//! - `irtp mfpt scan --over vt|rate --from A --to B --points K [--log]`;
//! - `irtp mfpt optimize --vt VT [--r-min --r-max]`: optimal reset rate;
//! - `irtp mfpt scan|optimize --xt L | --interval A,B ...`: the same for the
//!   search (the `search_scan` submodule);
//! - `irtp mfpt distribution --vt VT [--method backward|exact]`: the
//!   first-passage-time distribution ([`super::fpt`]).
//!
//! Every method runs through the library's one entry point, `irtp::mfpt::solve`.
//! Particle methods never present a mean over censored samples: when any
//! particle has not arrived by `--t-max`, tau is null and the restricted mean
//! `rmst` is reported as `tau_lower_bound`, flagged in the text report; the
//! Kaplan-Meier curve is `survival.csv` ([`irtp::mfpt::survival`]).
//! To add a method: a [`Method`] variant, its arm in `SimArgs::config` and
//! the library's [`irtp::mfpt::Method`].

use super::common::{ModelArgs, OutputArgs};
use super::{finish, open_out, to_value, Context, Outcome, Results, Table};
use clap::{Args, Subcommand, ValueEnum};
use irtp::mfpt::backward::{profile, BackwardOptions, BackwardSolution, Profile};
use irtp::mfpt::{
    self, FptSummary, MfptResult, OptimizeOptions, ParticleOptions, Problem, ScanAxis, ScanPoint,
    SurvivalCurve,
};
use irtp::Error;
use serde::Serialize;
use std::time::Instant;

pub(crate) mod parts;
pub(crate) mod search;
mod search_scan;

/// `irtp mfpt`.
#[derive(Args, Debug)]
#[command(args_conflicts_with_subcommands = true, subcommand_negates_reqs = true)]
pub struct MfptArgs {
    /// `scan` or `optimize`; none: one problem.
    #[command(subcommand)]
    pub command: Option<MfptCommand>,
    /// The flags of one problem.
    #[command(flatten)]
    pub direct: DirectArgs,
}

/// The subcommands of `irtp mfpt`.
#[derive(Subcommand, Debug)]
pub enum MfptCommand {
    /// tau over a range of the target velocity, the reset rate or (a search) x0 or xt (paper Fig. 7).
    ///
    /// One first-passage problem per point of --over from --from to --to
    /// (--points values, --log spacing): tau with its error estimate,
    /// written as mfpt_scan.csv with --out. --over vt or rate: a target
    /// velocity; --over x0 or xt: a search (--xt or --interval).
    #[command(after_help = crate::help::MFPT_SCAN)]
    Scan(ScanArgs),
    /// The reset rate r* minimising tau, searched over r in {0} ∪ [--r-min, --r-max].
    ///
    /// Answers whether resetting helps: tau(r) on a log grid of
    /// --grid-points rates brackets the minimum, a golden-section search in
    /// log r (Brent's method for a search) refines it, and r = 0 is compared;
    /// r* = 0 when resetting does not shorten the first passage. A target
    /// velocity --vt or a search (--xt or --interval with
    /// --reset-position).
    #[command(after_help = crate::help::MFPT_OPTIMIZE)]
    Optimize(OptimizeArgs),
    /// The distribution of the first-passage time: S(t), f(t), mean and variance.
    ///
    /// The survival S(t) and density f(t) from the time-dependent
    /// backward equations (default), or the sampled histogram and
    /// Kaplan-Meier curve of the exact particle sampler (--method exact);
    /// the mean and variance of the first-passage time.
    #[command(after_help = crate::help::MFPT_DISTRIBUTION)]
    Distribution(super::fpt::DistributionArgs),
}

/// Start and discretisation of the backward equations.
#[derive(Args, Debug, Clone)]
pub(super) struct ProblemArgs {
    #[command(flatten)]
    pub(super) model: ModelArgs,
    /// Initial velocity v_0 (inside (v_l, v_u), on the same side of v_t as v_r).
    #[arg(long, required = true, allow_hyphen_values = true)]
    pub(super) v0: Option<f64>,
    /// Cells of the backward-equation mesh on [v_l, v_t].
    #[arg(long, default_value_t = 20_000, allow_hyphen_values = true, value_parser = super::common::parse_size)]
    pub(super) cells: usize,
}

/// How tau is computed.
#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Method {
    /// Backward equations solved directly (second order, with error
    /// estimate); `ode` is its former name, still accepted with a warning.
    #[value(alias = "ode")]
    Backward,
    /// Particle simulation with the Euler scheme (paper Eqs. (30)-(32)).
    Euler,
    /// Exact event-driven particle sampler: no time step, no overshoot.
    Exact,
    /// The state-resolved renewal route of a search under full resetting
    /// (--xt or --interval with --reset-position): the reset-free survival by
    /// the time-dependent 2-D backward equation, renewed at the resets.
    Renewal,
}

/// Particle-simulation flags.
#[derive(Args, Debug, Clone)]
struct SimArgs {
    /// Method: backward (the backward equations), euler or exact (particles), renewal
    /// (a search under full resetting).
    #[arg(long, value_enum, default_value = "backward")]
    method: Method,
    /// Particles (half start in +Sigma, half in -Sigma) [default: 10000;
    /// particle methods only].
    #[arg(long, allow_hyphen_values = true, value_parser = super::common::parse_count)]
    particles: Option<u64>,
    /// Euler time step (O(dt) bias, including an overshoot of at most dt)
    /// [default: 1e-3; --method euler only].
    #[arg(long, allow_hyphen_values = true)]
    dt: Option<f64>,
    /// Censoring time of the particles [default: 1e4; particle methods only].
    ///
    /// If any has not arrived by t-max, tau is not reported
    /// (null; `censored`, `censored_fraction` say how many) and `rmst` ± `rmst_err`, the
    /// restricted mean E[min(T, t-max)], is its lower bound `tau_lower_bound` (tau > rmst).
    /// With --out, survival.csv holds the Kaplan-Meier survival curve S(t) (t, survival,
    /// survival_err, at_risk); a scan adds censored_fraction, rmst_sim, rmst_sim_err columns
    /// and writes tau_sim as nan (JSON null) at censored points.
    #[arg(long, allow_hyphen_values = true)]
    t_max: Option<f64>,
}

/// The target of a first passage, in velocity (`--vt`) or in position
/// (`--xt`, `--interval`, from `--x0`): `irtp mfpt` and `irtp mfpt
/// distribution`.
#[derive(Args, Debug, Clone)]
pub(crate) struct TargetArgs {
    /// Target velocity v_t (v_l < v_t < v_u).
    #[arg(long, required_unless_present_any = ["xt", "interval"], allow_hyphen_values = true)]
    pub(crate) vt: Option<f64>,
    /// Search target in position (instead of --vt): the first time x reaches the level L.
    ///
    /// One-sided. With velocity-only resetting the mean search time is infinite: tau is
    /// null, `infinite_mean` true, and the tail exponent of S(t) is reported (--method exact).
    #[arg(long, value_name = "L", allow_hyphen_values = true, conflicts_with_all = ["vt", "interval"])]
    pub(crate) xt: Option<f64>,
    /// Search target in position (instead of --vt): the first exit of x from the open
    /// interval (A, B), A < x0 < B.
    #[arg(
        long,
        value_name = "A,B",
        allow_hyphen_values = true,
        conflicts_with = "vt"
    )]
    pub(crate) interval: Option<String>,
    /// Initial position x_0 of a search (--xt or --interval) [default: 0].
    #[arg(long, value_name = "X0", allow_hyphen_values = true)]
    pub(crate) x0: Option<f64>,
}

impl TargetArgs {
    /// Whether a search target in position (--xt or --interval) was given.
    pub(crate) fn is_search(&self) -> bool {
        self.xt.is_some() || self.interval.is_some()
    }

    /// The target velocity (refusing --x0, which only a search takes).
    pub(crate) fn velocity(&self) -> irtp::Result<f64> {
        if let Some(x0) = self.x0 {
            return Err(Error::invalid(
                "--x0",
                x0,
                "only with a search target in position (--xt or --interval)",
            ));
        }
        self.vt
            .ok_or_else(|| Error::invalid("--vt", "missing", "a velocity"))
    }

    /// The search's flags with `model` and the start velocity `v0`.
    pub(crate) fn search<'a>(
        &'a self,
        model: &'a super::common::ModelArgs,
        v0: Option<f64>,
    ) -> search::SearchFlags<'a> {
        search::SearchFlags {
            model,
            v0,
            x0: self.x0,
            xt: self.xt,
            interval: self.interval.as_deref(),
        }
    }
}

/// `irtp mfpt` for one problem.
#[derive(Args, Debug)]
pub struct DirectArgs {
    #[command(flatten)]
    problem: ProblemArgs,
    #[command(flatten)]
    target: TargetArgs,
    /// Cells in x of the coarse mesh of a search's backward equation (--xt or
    /// --interval with --method backward; refined once and extrapolated).
    #[arg(long, default_value_t = 64)]
    cells_x: usize,
    /// Cells in v of the coarse mesh of a search's backward equation.
    #[arg(long, default_value_t = 32)]
    cells_v: usize,
    /// Time steps to the horizon of the renewal route's reset-free survival (TR-BDF2; also
    /// run with twice as many and extrapolated) [default: 100; --method renewal only].
    #[arg(long, allow_hyphen_values = true, value_parser = super::common::parse_size)]
    time_steps: Option<usize>,
    /// The renewal route's horizon: the reset clock's survival where its integrals stop
    /// [default: 1e-8; --method renewal only].
    ///
    /// Below this survival (Poisson clock; a periodic clock stops at its period) the
    /// integrals stop; the bound on the cut tail is reported.
    #[arg(long, allow_hyphen_values = true)]
    horizon_tail: Option<f64>,
    #[command(flatten)]
    sim: SimArgs,
    #[command(flatten)]
    output: OutputArgs,
}

/// `irtp mfpt scan`.
#[derive(Args, Debug)]
pub struct ScanArgs {
    #[command(flatten)]
    problem: ProblemArgs,
    /// Target velocity (needed with --over rate, unless a search target --xt or --interval is given).
    #[arg(long, allow_hyphen_values = true)]
    vt: Option<f64>,
    #[command(flatten)]
    search: search_scan::SearchTargetArgs,
    /// Scanned quantity (x0 and xt: a search, --xt or --interval).
    #[arg(long, value_enum)]
    over: Over,
    /// First value.
    #[arg(long, allow_hyphen_values = true)]
    from: f64,
    /// Last value.
    #[arg(long, allow_hyphen_values = true)]
    to: f64,
    /// Number of values (>= 2).
    #[arg(long, default_value_t = 21, allow_hyphen_values = true, value_parser = super::common::parse_size)]
    points: usize,
    /// Logarithmic spacing (needs from, to > 0).
    #[arg(long)]
    log: bool,
    #[command(flatten)]
    sim: SimArgs,
    #[command(flatten)]
    output: OutputArgs,
}

/// The scanned quantity of `irtp mfpt scan`.
#[derive(ValueEnum, Clone, Copy, Debug)]
pub enum Over {
    /// Target velocity v_t.
    Vt,
    /// Reset rate r.
    Rate,
    /// Start position x_0 of a search (--xt or --interval).
    X0,
    /// Level L of a one-sided search (--xt; the given value is replaced).
    Xt,
}

/// `irtp mfpt optimize`.
#[derive(Args, Debug)]
pub struct OptimizeArgs {
    #[command(flatten)]
    problem: ProblemArgs,
    /// Target velocity v_t (or a search target, --xt or --interval).
    #[arg(long, required_unless_present_any = ["xt", "interval"], allow_hyphen_values = true)]
    vt: Option<f64>,
    #[command(flatten)]
    search: search_scan::SearchTargetArgs,
    /// Smallest positive r of the search grid (r = 0 is always compared).
    #[arg(long, default_value_t = 1e-3, allow_hyphen_values = true)]
    r_min: f64,
    /// Largest r of the search grid.
    #[arg(long, default_value_t = 1e3, allow_hyphen_values = true)]
    r_max: f64,
    /// Points of the coarse log grid.
    #[arg(long, default_value_t = 61, allow_hyphen_values = true, value_parser = super::common::parse_size)]
    grid_points: usize,
    #[command(flatten)]
    output: OutputArgs,
}

impl MfptArgs {
    /// Whether `--json` was given.
    pub fn json(&self) -> bool {
        match &self.command {
            None => self.direct.output.json,
            Some(MfptCommand::Scan(a)) => a.output.json,
            Some(MfptCommand::Optimize(a)) => a.output.json,
            Some(MfptCommand::Distribution(a)) => a.json(),
        }
    }
}

impl MfptArgs {
    /// Whether the chosen method is a particle method (takes `--seed`).
    pub fn uses_seed(&self) -> bool {
        match &self.command {
            None => self.direct.sim.method.is_particles(),
            Some(MfptCommand::Scan(a)) => a.sim.method.is_particles(),
            Some(MfptCommand::Optimize(_)) => false,
            Some(MfptCommand::Distribution(a)) => a.uses_seed(),
        }
    }

    /// Validate the flags (every point of a scan) without solving.
    pub(crate) fn validate(&self) -> irtp::Result<()> {
        match &self.command {
            None if self.direct.is_search() => search::config(&self.direct).map(drop),
            None => self.direct.config().map(drop),
            Some(MfptCommand::Scan(a)) if a.search.is_search() => {
                search_scan::scan_config(a).map(drop)
            }
            Some(MfptCommand::Scan(a)) => a.config().map(drop),
            Some(MfptCommand::Optimize(a)) if a.search.is_search() => {
                search_scan::optimize_config(a).map(drop)
            }
            Some(MfptCommand::Optimize(a)) => a.config().map(drop),
            Some(MfptCommand::Distribution(a)) => a.validate(),
        }
    }
}

/// Run `irtp mfpt [scan | optimize]`.
pub fn run(args: &MfptArgs, ctx: &Context) -> irtp::Result<Outcome> {
    match &args.command {
        None if args.direct.is_search() => search::run(&args.direct, ctx),
        None => run_direct(&args.direct, ctx),
        Some(MfptCommand::Scan(a)) if a.search.is_search() => search_scan::run_scan(a, ctx),
        Some(MfptCommand::Scan(a)) => run_scan(a, ctx),
        Some(MfptCommand::Optimize(a)) if a.search.is_search() => search_scan::run_optimize(a, ctx),
        Some(MfptCommand::Optimize(a)) => run_optimize(a, ctx),
        Some(MfptCommand::Distribution(a)) => super::fpt::run(a, ctx),
    }
}

impl ProblemArgs {
    /// Flags → validated problem (start v_0, target `vt`) and mesh.
    pub(super) fn config(&self, vt: f64) -> irtp::Result<(Problem, BackwardOptions)> {
        let params = self.model.params()?;
        let v0 = self
            .v0
            .ok_or_else(|| Error::invalid("--v0", "missing", "a velocity"))?;
        let problem = Problem::new(params, v0, vt)?;
        let opts = BackwardOptions::with_cells(self.cells);
        opts.validate()?;
        Ok((problem, opts))
    }
}

impl Method {
    /// Whether this is a particle method (takes --seed, --particles, --t-max).
    pub(crate) fn is_particles(self) -> bool {
        matches!(self, Method::Euler | Method::Exact)
    }
}

impl SimArgs {
    fn particles(&self) -> u64 {
        self.particles.unwrap_or(10_000)
    }
    fn dt(&self) -> f64 {
        self.dt.unwrap_or(1e-3)
    }
    fn t_max(&self) -> f64 {
        self.t_max.unwrap_or(1e4)
    }

    /// A flag of a method not chosen is an error, never ignored.
    fn reject_inapplicable(&self, output: &OutputArgs) -> irtp::Result<()> {
        let particle_only = [
            ("--particles", self.particles.map(|n| n.to_string())),
            ("--t-max", self.t_max.map(|t| t.to_string())),
        ];
        if !self.method.is_particles() {
            output.no_seed(match self.method {
                Method::Renewal => "the renewal route (--method renewal)",
                _ => "the backward-equation method (--method backward)",
            })?;
            for (flag, value) in particle_only {
                if let Some(v) = value {
                    return Err(Error::invalid(
                        flag,
                        v,
                        "only with a particle method (--method exact or euler)",
                    ));
                }
            }
        }
        match (self.method, self.dt) {
            (Method::Euler, _) | (_, None) => Ok(()),
            (_, Some(dt)) => Err(Error::invalid(
                "--dt",
                dt,
                "only with --method euler (the other methods have no time step)",
            )),
        }
    }

    /// Flags → the library's method (`backward` for the ODE), checked
    /// against every problem it will run on before anything runs.
    fn config(
        &self,
        problems: &[Problem],
        backward: BackwardOptions,
        output: &OutputArgs,
    ) -> irtp::Result<mfpt::Method> {
        self.reject_inapplicable(output)?;
        let run = ParticleOptions {
            particles: self.particles(),
            t_max: self.t_max(),
            seed: output.seed(),
        };
        let method = match self.method {
            Method::Backward => mfpt::Method::Backward(backward),
            Method::Euler => mfpt::Method::Euler { dt: self.dt(), run },
            Method::Exact => mfpt::Method::Exact(run),
            Method::Renewal => {
                return Err(Error::invalid(
                    "--method",
                    "renewal",
                    "backward, euler or exact with a target velocity (--vt): the renewal \
                     route solves a search in position under full resetting (--xt or \
                     --interval with --reset-position)",
                ))
            }
        };
        for p in problems {
            method.check(p)?;
        }
        let cost = problems
            .iter()
            .map(|p| method_cost(&method, p, backward.cells))
            .reduce(super::budget::Cost::then);
        if let Some(cost) = cost {
            output.budget.check(&cost)?;
        }
        Ok(method)
    }
}

/// Work and memory of one problem. Backward equations: about 100 operations
/// and 200 bytes per cell (measured: 2e6 cells, 6.6 s, 396 MB). Particles:
/// each runs until its first passage, on average tau (from the backward
/// equations on a coarse mesh: [`coarse_tau`]), at most t_max;
/// exact events come at rate lambda + r (with a periodic clock or a
/// refractory period, their bound `Schedule::event_rate_bound`; with a
/// noise model at most max_s q_s + r: `Params::event_rate_bound`), Euler
/// steps every dt.
fn method_cost(method: &mfpt::Method, p: &Problem, cells: usize) -> super::budget::Cost {
    let backward = super::budget::mesh(cells, 100.0, 256.0, vec!["cells"]);
    let Some(run) = method.particles() else {
        return backward.per_drag_evaluation(&p.params().drag());
    };
    let t = coarse_tau(p).map_or(run.t_max, |tau| tau.min(run.t_max));
    let params = p.params();
    let (per, unit, mut drivers) = match method {
        mfpt::Method::Euler { dt, .. } => (
            t / dt + 1.0,
            "Euler particle steps",
            vec!["particles", "t_max", "dt"],
        ),
        _ => (
            params.event_rate_bound() * t + 2.0,
            "particle events",
            vec!["particles", "lambda", "rate", "t_max"],
        ),
    };
    drivers.extend(params.schedule().cost_drivers());
    let cost = super::budget::particles(run.particles, per, unit, drivers, 0, 0);
    match method {
        // The exact sampler reads the law's flows from tables built once.
        mfpt::Method::Euler { .. } => cost.per_drag_evaluation(&params.drag()),
        _ => cost,
    }
}

/// tau from the backward equations on a coarse mesh (1000 cells), for the
/// cost estimate: of the problem, or where they do not run its schedule's
/// modifiers (a noise model, a fixed refractory period) of the problem
/// under its Poisson resetting alone, as the paper's noise is estimated
/// with a periodic clock; None where that fails too.
fn coarse_tau(p: &Problem) -> Option<f64> {
    let opts = BackwardOptions::with_cells(1000);
    if let Ok(s) = mfpt::backward::solve(p, &opts) {
        return Some(s.tau);
    }
    if p.params().schedule().is_plain() {
        return None;
    }
    let params = p.params().with_schedule(Default::default()).ok()?;
    let poisson = Problem::new(params, p.v0(), p.vt()).ok()?;
    mfpt::backward::solve(&poisson, &opts).ok().map(|s| s.tau)
}

/// tau of one problem by `method`, with a progress stage for particles.
fn estimate(
    method: &mfpt::Method,
    problem: &Problem,
    label: &str,
    ctx: &Context,
) -> irtp::Result<MfptResult> {
    let total = method.particles().map_or(1, |run| run.particles);
    let bar = ctx.reporter.stage(label, total);
    let result = mfpt::solve(problem, method, bar.as_ref())?;
    ctx.check()?;
    Ok(result)
}

/// The particle summary of a particle method's result.
fn summary(r: &MfptResult) -> FptSummary {
    r.summary().expect("a particle method")
}
/// What `irtp mfpt --json` prints.
#[derive(Serialize)]
struct Report {
    method: Method,
    problem: Problem,
    /// null (NaN) for particles when any is censored.
    tau: f64,
    tau_plus: f64,
    tau_minus: f64,
    #[serde(skip_serializing_if = "Option::is_none")]
    cells: Option<usize>,
    #[serde(skip_serializing_if = "Option::is_none")]
    error_estimate: Option<f64>,
    #[serde(flatten)]
    sim: Option<SimReport>,
}

/// The particle methods' part of [`Report`].
#[derive(Serialize)]
struct SimReport {
    tau_err: f64,
    tau_plus_err: f64,
    tau_minus_err: f64,
    particles: u64,
    censored: u64,
    censored_fraction: f64,
    rmst: f64,
    rmst_err: f64,
    /// rmst when any particle is censored (tau > rmst), else null.
    tau_lower_bound: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    dt: Option<f64>,
    t_max: f64,
    seed: u64,
}

impl Report {
    fn backward(problem: Problem, s: &BackwardSolution) -> Self {
        Report {
            method: Method::Backward,
            problem,
            tau: s.tau,
            tau_plus: s.tau_plus,
            tau_minus: s.tau_minus,
            cells: Some(s.cells),
            error_estimate: Some(s.error_estimate),
            sim: None,
        }
    }

    fn particles(m: Method, problem: Problem, method: &mfpt::Method, s: &FptSummary) -> Self {
        let run = method.particles().expect("a particle method");
        let sim = SimReport {
            tau_err: s.tau_err,
            tau_plus_err: s.tau_plus_err,
            tau_minus_err: s.tau_minus_err,
            particles: s.particles,
            censored: s.censored,
            censored_fraction: s.censored_fraction,
            rmst: s.rmst,
            rmst_err: s.rmst_err,
            tau_lower_bound: s.tau_lower_bound,
            dt: match *method {
                mfpt::Method::Euler { dt, .. } => Some(dt),
                _ => None,
            },
            t_max: run.t_max,
            seed: run.seed,
        };
        Report {
            method: m,
            problem,
            tau: s.tau,
            tau_plus: s.tau_plus,
            tau_minus: s.tau_minus,
            cells: None,
            error_estimate: None,
            sim: Some(sim),
        }
    }

    fn seed(&self) -> Option<u64> {
        self.sim.as_ref().map(|s| s.seed)
    }
}

/// The flag of a censored particle estimate, leading the text report.
fn censoring_note(s: &FptSummary) -> String {
    if s.censored == 0 {
        return String::new();
    }
    format!(
        "CENSORED: {} of {} particles ({}%) had not reached vt by t_max = {}: tau is NOT estimated \
         (the mean of the arrived particles is no estimate of it).\n\
         tau > rmst = {} (the restricted mean E[min(T, t_max)], a lower bound); \
         a larger --t-max estimates tau.\n",
        s.censored,
        s.particles,
        super::format::fmt_sig(100.0 * s.censored_fraction),
        super::format::fmt_sig(s.t_max),
        super::format::fmt_pm(s.rmst, s.rmst_err)
    )
}

/// `survival.csv`: the Kaplan-Meier survival curve of the passage times.
pub(super) fn survival_table(c: &SurvivalCurve) -> Table {
    let rows = (0..c.t.len()).map(|i| {
        [
            c.t[i],
            c.survival[i],
            c.survival_err[i],
            c.at_risk[i] as f64,
        ]
    });
    Table::from_rows(
        "survival",
        &["t", "survival", "survival_err", "at_risk"],
        rows,
    )
}

/// `key = value` lines of a JSON object (its `problem` left out): a value
/// with an `<key>_err` beside it as `value ± error` (2 significant digits
/// of the error), other numbers to 10 significant digits.
pub(super) fn text_lines(v: &serde_json::Value) -> String {
    let mut text = String::new();
    let Some(obj) = v.as_object() else {
        return text;
    };
    let err_of = |k: &str| obj.get(&format!("{k}_err")).and_then(|e| e.as_f64());
    for (k, x) in obj {
        let paired = k
            .strip_suffix("_err")
            .is_some_and(|base| obj.get(base).is_some_and(|b| b.is_f64()));
        if k == "problem" || paired {
            continue;
        }
        let shown = match (x, err_of(k)) {
            (serde_json::Value::Number(n), Some(e)) if n.is_f64() => {
                super::format::fmt_pm(n.as_f64().unwrap_or(f64::NAN), e)
            }
            (serde_json::Value::Number(n), _) if n.is_f64() => {
                super::format::fmt_digits(n.as_f64().unwrap_or(f64::NAN), 10)
            }
            (serde_json::Value::String(s), _) => s.clone(),
            _ => x.to_string(),
        };
        text += &format!("{k} = {shown}\n");
    }
    text
}

/// The validated inputs of `irtp mfpt`.
struct DirectConfig {
    problem: Problem,
    backward: BackwardOptions,
    method: mfpt::Method,
}

impl DirectArgs {
    /// The renewal route's flags are an error with any other method.
    pub(crate) fn reject_renewal_flags(&self) -> irtp::Result<()> {
        if self.sim.method == Method::Renewal {
            return Ok(());
        }
        let given = [
            ("--time-steps", self.time_steps.map(|n| n.to_string())),
            ("--horizon-tail", self.horizon_tail.map(|t| t.to_string())),
        ];
        for (flag, value) in given {
            if let Some(v) = value {
                return Err(Error::invalid(flag, v, "only with --method renewal"));
            }
        }
        Ok(())
    }

    /// Whether a search target in position (--xt or --interval) was given.
    fn is_search(&self) -> bool {
        self.target.is_search()
    }

    fn config(&self) -> irtp::Result<DirectConfig> {
        let vt = self.target.velocity()?;
        self.reject_renewal_flags()?;
        let (problem, backward) = self.problem.config(vt)?;
        let method = self
            .sim
            .config(std::slice::from_ref(&problem), backward, &self.output)?;
        Ok(DirectConfig {
            problem,
            backward,
            method,
        })
    }
}

fn run_direct(a: &DirectArgs, ctx: &Context) -> irtp::Result<Outcome> {
    let c = a.config()?;
    let out = open_out("mfpt", a.output.out.as_deref(), a.output.force.force)?;
    let t0 = Instant::now();
    let result = estimate(&c.method, &c.problem, "mfpt", ctx)?;
    write_direct(a, &c, result, (t0, 0.0), out, ctx)
}

/// Write the outputs of a solved velocity-target problem. The wall time
/// reported is `clock.1` plus the time since `clock.0` (the backward
/// profile is computed here).
fn write_direct(
    a: &DirectArgs,
    c: &DirectConfig,
    result: MfptResult,
    clock: (Instant, f64),
    out: Option<crate::io::OutputDir>,
    ctx: &Context,
) -> irtp::Result<Outcome> {
    let (report, table, note) = match result {
        MfptResult::Backward(s) => {
            let prof = profile(&c.problem, &c.backward)?;
            (
                Report::backward(c.problem.clone(), &s),
                profile_table(&prof),
                String::new(),
            )
        }
        MfptResult::Particles(st) => {
            let s = st.summary();
            (
                Report::particles(a.sim.method, c.problem.clone(), &c.method, &s),
                survival_table(&st.survival()),
                censoring_note(&s),
            )
        }
    };
    let wall = clock.1 + clock.0.elapsed().as_secs_f64();
    let json = to_value(&report);
    let results = Results {
        method: method_name(report.method).into(),
        seed: report.seed(),
        json: json.clone(),
        parameters: json.clone(),
        tables: vec![table],
        json_files: vec![("mfpt.json", json.clone())],
        text: note + &text_lines(&json),
        wall_time_s: wall,
    };
    finish("mfpt", results, out, ctx)
}

/// `profile.csv`: tau± and their mean against the start velocity.
fn profile_table(p: &Profile) -> Table {
    let rows = (0..p.v.len()).map(|i| [p.v[i], p.tau[i], p.tau_plus[i], p.tau_minus[i]]);
    Table::from_rows("profile", &["v0", "tau", "tau_plus", "tau_minus"], rows)
}

fn method_name(m: Method) -> &'static str {
    match m {
        Method::Backward => "backward-box",
        Method::Euler => "euler",
        Method::Exact => "exact",
        Method::Renewal => "renewal",
    }
}

/// The validated inputs of `irtp mfpt scan`.
struct ScanConfig {
    base: Problem,
    axis: ScanAxis,
    values: Vec<f64>,
    /// The problem at every value.
    problems: Vec<Problem>,
    backward: BackwardOptions,
    /// How tau is computed at every point besides the backward equations.
    method: mfpt::Method,
}

impl ScanArgs {
    /// Flags → validated config: every point (and the particle flags
    /// there) is checked before any work.
    fn config(&self) -> irtp::Result<ScanConfig> {
        // Before the points are allocated: one backward solve per point.
        let per_point = super::budget::mesh(self.problem.cells, 100.0, 0.0, vec!["cells"]);
        self.output.budget.check(&super::budget::Cost {
            work: per_point.work * self.points as f64,
            drivers: vec!["points", "cells"],
            memory: 256.0 * self.points as f64 + 256.0 * self.problem.cells as f64,
            memory_drivers: vec!["points", "cells"],
            ..per_point
        })?;
        self.search.velocity_only()?;
        let values = mfpt::optimize::scan_values(self.from, self.to, self.points, self.log)?;
        let (axis, vt) = match (self.over, self.vt) {
            (Over::X0 | Over::Xt, _) => return Err(search_scan::search_axis_refused(self.over)),
            (Over::Vt, Some(vt)) => {
                return Err(Error::invalid(
                    "--vt",
                    vt,
                    "only with --over rate (with --over vt the targets run from --from to --to)",
                ))
            }
            (Over::Vt, None) => (ScanAxis::Vt, values[0]),
            (Over::Rate, vt) => (
                ScanAxis::Rate,
                vt.ok_or_else(|| {
                    Error::invalid(
                        "--vt",
                        "missing",
                        "a target velocity (required with --over rate)",
                    )
                })?,
            ),
        };
        let scanned = |i: usize, e: Error| blame_scan_end(e, axis, i, (self.from, self.to));
        let (base, backward) = self.problem.config(vt).map_err(|e| scanned(0, e))?;
        let problems = values
            .iter()
            .enumerate()
            .map(|(i, &x)| mfpt::optimize::scan_problem(&base, axis, x).map_err(|e| scanned(i, e)))
            .collect::<irtp::Result<Vec<_>>>()?;
        let method = self.sim.config(&problems, backward, &self.output)?;
        Ok(ScanConfig {
            base,
            axis,
            values,
            problems,
            backward,
            method,
        })
    }
}

/// A scanned point's error names the scanned parameter (`vt`, `rate`); the
/// user typed `--from` / `--to`. The points run from `--from` to `--to`, so
/// the first point failing is `--from` itself or lies towards `--to`.
fn blame_scan_end(e: Error, axis: ScanAxis, point: usize, (from, to): (f64, f64)) -> Error {
    let scanned = match axis {
        ScanAxis::Vt => "vt",
        ScanAxis::Rate => "rate",
    };
    match e {
        Error::InvalidParameter { name, allowed, .. } if name == scanned => {
            let (flag, value) = if point == 0 {
                ("--from", from)
            } else {
                ("--to", to)
            };
            Error::invalid(flag, value, allowed)
        }
        other => other,
    }
}

/// The rows (x, tau, tau+, tau-, error estimate) of a velocity scan.
fn scan_rows(points: &[ScanPoint]) -> Vec<[f64; 5]> {
    points
        .iter()
        .map(|p| {
            let s = &p.solution;
            [p.x, s.tau, s.tau_plus, s.tau_minus, s.error_estimate]
        })
        .collect()
}

/// `mfpt_scan.csv`: the backward rows `points` (x, tau, tau+, tau-, error
/// estimate) and, with particles, the sampled columns.
fn scan_table(xname: &'static str, points: &[[f64; 5]], sims: Option<&[FptSummary]>) -> Table {
    let mut header = vec![xname, "tau", "tau_plus", "tau_minus", "error_estimate"];
    if sims.is_some() {
        header.extend([
            "tau_sim",
            "tau_sim_err",
            "tau_plus_sim",
            "tau_plus_sim_err",
            "tau_minus_sim",
            "tau_minus_sim_err",
            "censored",
            "censored_fraction",
            "rmst_sim",
            "rmst_sim_err",
        ]);
    }
    let rows = points
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let mut row = p.to_vec();
            if let Some(sims) = sims {
                let m = &sims[i];
                row.extend([
                    m.tau,
                    m.tau_err,
                    m.tau_plus,
                    m.tau_plus_err,
                    m.tau_minus,
                    m.tau_minus_err,
                    m.censored as f64,
                    m.censored_fraction,
                    m.rmst,
                    m.rmst_err,
                ]);
            }
            row
        })
        .collect::<Vec<_>>();
    Table::from_rows("mfpt_scan", &header, rows)
}

/// The flag of scan points with censored particles, after the table text.
fn scan_note(sims: &[FptSummary]) -> String {
    let k = sims.iter().filter(|s| s.censored > 0).count();
    if k == 0 {
        return String::new();
    }
    format!(
        "# CENSORED at {k} of {} points (censored > 0): tau_sim is NOT estimated there (nan); \
         tau > rmst_sim, the restricted mean E[min(T, t_max)]; a larger --t-max estimates tau.\n",
        sims.len()
    )
}

#[derive(Serialize)]
struct ScanParams<'a> {
    base: &'a Problem,
    over: &'a str,
    values: &'a [f64],
    cells: usize,
    method: Method,
    particles: Option<u64>,
    dt: Option<f64>,
    t_max: Option<f64>,
}

fn run_scan(a: &ScanArgs, ctx: &Context) -> irtp::Result<Outcome> {
    let c = a.config()?;
    let out = open_out("mfpt scan", a.output.out.as_deref(), a.output.force.force)?;
    let t0 = Instant::now();
    let points = {
        let bar = ctx.reporter.stage("mfpt scan", c.values.len() as u64);
        mfpt::scan(&c.base, c.axis, &c.values, &c.backward, bar.as_ref())?
    };
    ctx.check()?;
    // Common random numbers: every point uses the same seed, so the
    // curve is smooth and differences between points are precise.
    let sim = c.method.particles().is_some();
    let sims = if sim {
        let run = |(i, p): (usize, &Problem)| {
            estimate(&c.method, p, &format!("point {}", i + 1), ctx).map(|r| summary(&r))
        };
        Some(
            c.problems
                .iter()
                .enumerate()
                .map(run)
                .collect::<irtp::Result<Vec<_>>>()?,
        )
    } else {
        None
    };
    let wall = t0.elapsed().as_secs_f64();
    let xname = match a.over {
        Over::Vt => "vt",
        _ => "rate",
    };
    let table = scan_table(xname, &scan_rows(&points), sims.as_deref());
    let note = sims.as_deref().map_or(String::new(), scan_note);
    let params = ScanParams {
        base: &c.base,
        over: xname,
        values: &c.values,
        cells: a.problem.cells,
        method: a.sim.method,
        particles: sim.then_some(a.sim.particles()),
        dt: (a.sim.method == Method::Euler).then_some(a.sim.dt()),
        t_max: sim.then_some(a.sim.t_max()),
    };
    let results = Results {
        method: method_name(a.sim.method).into(),
        seed: sim.then_some(a.output.seed()),
        json: to_value(&table_json(&table)),
        parameters: to_value(&params),
        text: table_text(&table) + &note,
        tables: vec![table],
        json_files: Vec::new(),
        wall_time_s: wall,
    };
    finish("mfpt scan", results, out, ctx)
}

/// The table as CSV text.
fn table_text(t: &Table) -> String {
    let mut text = t.header.join(",") + "\n";
    for i in 0..t.len() {
        let s: Vec<String> = t
            .columns
            .iter()
            .map(|c| crate::io::format_float(c[i]))
            .collect();
        text += &(s.join(",") + "\n");
    }
    text
}

/// One JSON object per row, keyed by the header.
fn table_json(t: &Table) -> Vec<serde_json::Map<String, serde_json::Value>> {
    (0..t.len())
        .map(|i| {
            t.header
                .iter()
                .zip(&t.columns)
                .map(|(h, c)| (h.clone(), serde_json::json!(c[i])))
                .collect()
        })
        .collect()
}

impl OptimizeArgs {
    /// Flags → validated problem and search range (checked before any
    /// output is created).
    fn config(&self) -> irtp::Result<(Problem, OptimizeOptions)> {
        if let Some(r) = self.problem.model.rate {
            return Err(Error::invalid(
                "--rate",
                r,
                "not with mfpt optimize, which searches r over {0} ∪ [--r-min, --r-max]",
            ));
        }
        self.output.no_seed("mfpt optimize")?;
        self.search.velocity_only()?;
        let vt = self
            .vt
            .ok_or_else(|| Error::invalid("--vt", "missing", "a target velocity"))?;
        let (problem, backward) = self.problem.config(vt)?;
        let opts = OptimizeOptions {
            r_min: self.r_min,
            r_max: self.r_max,
            grid_points: self.grid_points,
            backward,
        };
        opts.validate()?;
        // The coarse grid, then a golden-section refinement (about 60 solves).
        let solves = self.grid_points as f64 + 60.0;
        let per_solve = super::budget::mesh(self.problem.cells, 100.0, 256.0, vec!["cells"]);
        self.output.budget.check(
            &super::budget::Cost {
                work: per_solve.work * solves,
                drivers: vec!["grid_points", "cells"],
                ..per_solve
            }
            .per_drag_evaluation(&problem.params().drag()),
        )?;
        Ok((problem, opts))
    }
}

#[derive(Serialize)]
struct OptimizeSummary<'a> {
    r_opt: f64,
    tau_opt: f64,
    tau_opt_err: f64,
    r_opt_range: (f64, f64),
    tau_plus_opt: f64,
    tau_minus_opt: f64,
    tau_r0: f64,
    dtau_dr_r0: f64,
    interior: bool,
    at_upper_bound: bool,
    problem: &'a Problem,
    r_min: f64,
    r_max: f64,
}

fn run_optimize(a: &OptimizeArgs, ctx: &Context) -> irtp::Result<Outcome> {
    let (problem, opts) = a.config()?;
    let out = open_out(
        "mfpt optimize",
        a.output.out.as_deref(),
        a.output.force.force,
    )?;
    let t0 = Instant::now();
    let best = {
        let bar = ctx.reporter.stage("mfpt optimize", opts.grid_points as u64);
        mfpt::optimize_rate(&problem, &opts, bar.as_ref())?
    };
    let wall = t0.elapsed().as_secs_f64();
    let summary = OptimizeSummary {
        r_opt: best.r_opt,
        tau_opt: best.tau_opt,
        tau_opt_err: best.tau_opt_err,
        r_opt_range: best.r_opt_range,
        tau_plus_opt: best.tau_plus_opt,
        tau_minus_opt: best.tau_minus_opt,
        tau_r0: best.tau_r0,
        dtau_dr_r0: best.dtau_dr_r0,
        interior: best.interior,
        at_upper_bound: best.at_upper_bound,
        problem: &problem,
        r_min: opts.r_min,
        r_max: opts.r_max,
    };
    let json = to_value(&summary);
    let grid = rate_grid(&best.grid);
    let results = Results {
        method: "backward-box + golden-section".into(),
        seed: None,
        json: json.clone(),
        parameters: json.clone(),
        tables: vec![grid],
        json_files: vec![("optimum.json", json.clone())],
        text: text_lines(&json),
        wall_time_s: wall,
    };
    finish("mfpt optimize", results, out, ctx)
}

/// `rate_grid.csv` of an optimisation: the coarse grid (r, tau). Rates
/// where tau exceeds the f64 range (the target is practically never
/// reached) have no number to tabulate: left out.
pub(super) fn rate_grid(grid: &[(f64, f64)]) -> Table {
    Table::from_rows(
        "rate_grid",
        &["rate", "tau"],
        grid.iter()
            .filter(|(_, t)| t.is_finite())
            .map(|&(r, t)| [r, t]),
    )
}
