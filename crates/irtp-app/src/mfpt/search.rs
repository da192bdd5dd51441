//! `irtp mfpt --xt L | --interval A,B [--x0 X0] --v0 V0 --method exact`: the
//! search problem, first passage in position, through the library's one
//! entry point `irtp::search::solve`.
//!
//! `--method exact` runs the exact sampler, `--method backward` (the
//! default) the 2-D backward equation (`--cells-x`, `--cells-v`; Richardson
//! error estimate); `euler` is refused naming `--method`. Where the mean search
//! time is infinite (velocity-only resetting and a one-sided level) the run
//! succeeds (exit 0) with `tau` null, `infinite_mean` true, the reason in
//! `infinite_mean_reason` and the fitted tail exponent of S(t) in
//! `tail_exponent`; `survival.csv` holds the Kaplan-Meier curve.

use super::super::budget::{self, Cost};
use super::super::common::ModelArgs;
use super::super::{finish, open_out, to_value, Context, Outcome, Results};
use super::{survival_table, text_lines, DirectArgs, Method};
use irtp::mfpt::{FptStats, FptSummary, ParticleOptions};
use irtp::parallel::NoProgress;
use irtp::search::{
    self, PositionTarget, SearchMethod, SearchProblem, SearchResult, TailFit, INFINITE_MEAN_REASON,
};
use irtp::Error;
use serde::Serialize;
use std::time::Instant;

/// The validated inputs of a search.
pub(crate) struct SearchConfig {
    pub(crate) problem: SearchProblem,
    pub(crate) method: SearchMethod,
}

/// `A,B` → the interval target (both numbers; the order is checked with
/// the start by [`SearchProblem::new`]).
fn parse_interval(s: &str) -> irtp::Result<PositionTarget> {
    let bad = || Error::invalid("interval", s, "two numbers A,B with A < x0 < B");
    let (a, b) = s.split_once(',').ok_or_else(bad)?;
    let a: f64 = a.trim().parse().map_err(|_| bad())?;
    let b: f64 = b.trim().parse().map_err(|_| bad())?;
    Ok(PositionTarget::Interval(a, b))
}

/// The flags of a search problem, from `irtp mfpt` or `irtp mfpt distribution`.
pub(crate) struct SearchFlags<'a> {
    pub(crate) model: &'a ModelArgs,
    pub(crate) v0: Option<f64>,
    pub(crate) x0: Option<f64>,
    pub(crate) xt: Option<f64>,
    pub(crate) interval: Option<&'a str>,
}

impl SearchFlags<'_> {
    /// Flags → validated problem.
    pub(crate) fn problem(&self) -> irtp::Result<SearchProblem> {
        let target = match (self.xt, self.interval) {
            (Some(l), _) => PositionTarget::Level(l),
            (None, Some(s)) => parse_interval(s)?,
            (None, None) => unreachable!("a search has --xt or --interval"),
        };
        let params = self.model.params()?;
        let v0 = self
            .v0
            .ok_or_else(|| Error::invalid("--v0", "missing", "a velocity"))?;
        SearchProblem::new(params, self.x0.unwrap_or(0.0), v0, target)
    }
}

/// The refusal of the Euler method for a search (`name`: the method
/// given).
pub(crate) fn only_exact(name: &str) -> Error {
    Error::invalid(
        "--method",
        name,
        "exact or backward with a search target in position (--xt, --interval)",
    )
}

/// The exact method for `problem` with `run`, validated and its cost
/// checked against `budget` before any output exists.
pub(crate) fn exact_method(
    problem: &SearchProblem,
    run: ParticleOptions,
    budget: &budget::BudgetArgs,
) -> irtp::Result<SearchMethod> {
    let method = SearchMethod::Exact(run);
    method.check(problem)?;
    budget.check(&cost(problem, &method)?)?;
    Ok(method)
}

/// Flags → validated problem and method, the cost checked before any
/// output exists.
pub(super) fn config(a: &DirectArgs) -> irtp::Result<SearchConfig> {
    let flags = a.target.search(&a.problem.model, a.problem.v0);
    match a.sim.method {
        Method::Euler => Err(only_exact("euler")),
        Method::Backward => {
            let problem = flags.problem()?;
            let method = backward_method(&problem, a.cells_x, a.cells_v, &a.output.budget)?;
            Ok(SearchConfig { problem, method })
        }
        Method::Exact => {
            a.sim.reject_inapplicable(&a.output)?;
            let problem = flags.problem()?;
            let run = ParticleOptions {
                particles: a.sim.particles(),
                t_max: a.sim.t_max(),
                seed: a.output.seed(),
            };
            let method = exact_method(&problem, run, &a.output.budget)?;
            Ok(SearchConfig { problem, method })
        }
    }
}

/// The backward method on a coarse mesh of `cells_x` × `cells_v` (refined
/// once), validated and its cost checked against `budget` (the solver's
/// own refusals of a problem it cannot solve come first).
fn backward_method(
    problem: &SearchProblem,
    cells_x: usize,
    cells_v: usize,
    budget: &budget::BudgetArgs,
) -> irtp::Result<SearchMethod> {
    let opts = search::backward::BackwardOptions {
        max_work: f64::INFINITY,
        max_memory: f64::INFINITY,
        ..search::backward::BackwardOptions::with_cells(cells_x, cells_v)
    };
    let method = SearchMethod::Backward(opts);
    let named = |e: Error| match e {
        Error::InvalidParameter {
            name: n @ ("cells_x" | "cells_v"),
            value,
            allowed,
        } => Error::InvalidParameter {
            name: if n == "cells_x" {
                "--cells-x"
            } else {
                "--cells-v"
            },
            value,
            allowed,
        },
        e => e,
    };
    let cost = method.cost(problem).map_err(named)?.expect("a mesh method");
    budget.check(&Cost {
        work: cost.work,
        unit: "operations",
        drivers: vec!["cells_x", "cells_v", "rate"],
        memory: cost.memory,
        memory_drivers: vec!["cells_x", "cells_v"],
    })?;
    Ok(method)
}

/// Particles of the pilot run that estimates the mean time in flight.
const PILOT_PARTICLES: u64 = 32;
/// Events the pilot may spend in all (about 10 ms).
const PILOT_EVENTS: f64 = 1e5;

/// Work of a search: each particle runs until min(T, t_max), with events
/// at most at `Schedule::event_rate_bound`. E[min(T, t_max)] comes from a
/// pilot of [`PILOT_PARTICLES`] particles censored at the time they can
/// afford ([`PILOT_EVENTS`]); a pilot particle still in flight there is
/// counted as running to t_max (infinite t_max: an infinite estimate,
/// refused).
pub(super) fn cost(problem: &SearchProblem, method: &SearchMethod) -> irtp::Result<Cost> {
    let run = method.particles().expect("a particle method");
    let p = problem.params();
    let rate = p.schedule().event_rate_bound(p.lambda(), p.rate());
    let cap = (PILOT_EVENTS / (PILOT_PARTICLES as f64 * rate.max(1e-300))).min(run.t_max);
    let pilot = search::exact::stats(problem, cap, PILOT_PARTICLES, run.seed, &NoProgress)?;
    let s = pilot.summary();
    let time = if cap >= run.t_max {
        s.rmst
    } else {
        s.rmst + s.censored_fraction * (run.t_max - cap)
    };
    let mut drivers = vec!["particles", "lambda", "rate", "t_max"];
    drivers.extend(p.schedule().cost_drivers());
    let per = rate * time + 2.0;
    Ok(budget::particles(
        run.particles,
        per,
        "particle events",
        drivers,
        0,
        0,
    ))
}

/// What `irtp mfpt --xt/--interval --json` prints.
#[derive(Serialize)]
pub(crate) struct SearchReport {
    method: &'static str,
    problem: SearchProblem,
    /// null where the mean is infinite or any particle is censored.
    tau: f64,
    tau_plus: f64,
    tau_minus: f64,
    /// Whether the mean search time is infinite (then tau is null).
    infinite_mean: bool,
    #[serde(skip_serializing_if = "Option::is_none")]
    infinite_mean_reason: Option<&'static str>,
    /// The fitted tail S(t) ~ t^-theta where the mean is infinite, else null.
    tail_exponent: Option<TailFit>,
    tau_err: f64,
    tau_plus_err: f64,
    tau_minus_err: f64,
    particles: u64,
    censored: u64,
    censored_fraction: f64,
    rmst: f64,
    rmst_err: f64,
    tau_lower_bound: Option<f64>,
    t_max: f64,
    seed: u64,
}

impl SearchReport {
    pub(crate) fn new(
        c: &SearchConfig,
        s: &FptSummary,
        finite: bool,
        tail: Option<TailFit>,
    ) -> Self {
        let run = c.method.particles().expect("a particle method");
        let mean = |x: f64| if finite { x } else { f64::NAN };
        SearchReport {
            method: c.method.name(),
            problem: c.problem,
            tau: mean(s.tau),
            tau_plus: mean(s.tau_plus),
            tau_minus: mean(s.tau_minus),
            infinite_mean: !finite,
            infinite_mean_reason: (!finite).then_some(INFINITE_MEAN_REASON),
            tail_exponent: tail,
            tau_err: mean(s.tau_err),
            tau_plus_err: mean(s.tau_plus_err),
            tau_minus_err: mean(s.tau_minus_err),
            particles: s.particles,
            censored: s.censored,
            censored_fraction: s.censored_fraction,
            rmst: s.rmst,
            rmst_err: s.rmst_err,
            tau_lower_bound: s.tau_lower_bound,
            t_max: run.t_max,
            seed: run.seed,
        }
    }
}

/// The flags leading the text report: an infinite mean (with the tail),
/// or censored particles.
pub(crate) fn note(r: &SearchReport) -> String {
    if r.infinite_mean {
        let tail = r.tail_exponent.map_or(
            "the survival curve has too few resolved points for a tail fit".into(),
            |f| {
                format!(
                    "S(t) ~ t^-theta with theta = {} over t in [{}, {}]",
                    super::super::format::fmt_pm(f.theta, f.theta_err),
                    super::super::format::fmt_sig(f.t_from),
                    super::super::format::fmt_sig(f.t_to)
                )
            },
        );
        return format!("INFINITE MEAN: tau is not reported: {INFINITE_MEAN_REASON}.\n{tail}\n");
    }
    if r.censored == 0 {
        return String::new();
    }
    format!(
        "CENSORED: {} of {} particles had not reached the target by t_max = {}: tau is NOT \
         estimated; tau > rmst = {} (a lower bound); a larger --t-max estimates tau.\n",
        r.censored,
        r.particles,
        super::super::format::fmt_sig(r.t_max),
        super::super::format::fmt_pm(r.rmst, r.rmst_err)
    )
}

/// Solve a validated search with a progress stage (particles only: the
/// particle statistics and report).
pub(crate) fn solve(c: &SearchConfig, ctx: &Context) -> irtp::Result<(FptStats, SearchReport)> {
    let total = c.method.particles().map_or(1, |r| r.particles);
    let result = {
        let bar = ctx.reporter.stage("search", total);
        search::solve(&c.problem, &c.method, bar.as_ref())?
    };
    ctx.check()?;
    match result {
        SearchResult::Particles(r) => {
            let report = SearchReport::new(c, &r.stats.summary(), r.mean_is_finite, r.tail);
            Ok((r.stats, report))
        }
        _ => unreachable!("a particle method gives particle statistics"),
    }
}

/// What `irtp mfpt --xt/--interval --method backward --json` prints.
#[derive(Serialize)]
struct BackwardReport {
    method: &'static str,
    problem: SearchProblem,
    #[serde(flatten)]
    solution: search::backward::SearchSolution,
}

/// Run a search: `summary.json`, `run.json`, `mfpt.json` and, by
/// particles, `survival.csv`.
pub(super) fn run(a: &DirectArgs, ctx: &Context) -> irtp::Result<Outcome> {
    let c = config(a)?;
    let out = open_out("mfpt", a.output.out.as_deref(), a.output.force.force)?;
    let t0 = Instant::now();
    let (json, seed, tables, note_text) = if c.method.particles().is_some() {
        let (stats, report) = solve(&c, ctx)?;
        let json = to_value(&report);
        let table = survival_table(&stats.survival());
        (json, Some(report.seed), vec![table], note(&report))
    } else {
        let result = {
            let _bar = ctx.reporter.stage("search (backward equation)", 1);
            search::solve(&c.problem, &c.method, &irtp::parallel::NoProgress)?
        };
        ctx.check()?;
        let SearchResult::Backward(solution) = result else {
            unreachable!("the backward method gives a backward solution")
        };
        let report = BackwardReport {
            method: c.method.name(),
            problem: c.problem,
            solution,
        };
        (to_value(&report), None, vec![], String::new())
    };
    let wall = t0.elapsed().as_secs_f64();
    let results = Results {
        method: c.method.name().into(),
        seed,
        json: json.clone(),
        parameters: json.clone(),
        tables,
        json_files: vec![("mfpt.json", json.clone())],
        text: note_text + &text_lines(&json),
        wall_time_s: wall,
    };
    finish("mfpt", results, out, ctx)
}
