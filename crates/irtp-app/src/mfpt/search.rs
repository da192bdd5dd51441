//! `irtp mfpt --xt L | --interval A,B [--x0 X0] --v0 V0 --method exact`: the
//! search problem, first passage in position, through the library's one
//! entry point `irtp::search::solve`.
//!
//! `--method exact` runs the exact sampler, `--method backward` (the
//! default) the 2-D backward equation (`--cells-x`, `--cells-v`; Richardson
//! error estimate), `--method renewal` the renewal route of full resetting
//! (`--cells-x`, `--cells-v`, `--time-steps`, `--horizon-tail`), `--method
//! euler` the Euler scheme at `--dt` and dt/2, extrapolated to dt → 0
//! (`survival.csv` from the run at dt/2). Where the mean search
//! time is infinite (velocity-only resetting and a one-sided level) the run
//! succeeds (exit 0) with `tau` null, `infinite_mean` true, the reason in
//! `infinite_mean_reason` and the fitted tail exponent of S(t) in
//! `tail_exponent`; `survival.csv` holds the Kaplan-Meier curve.

use super::super::budget::{self, Cost};
use super::super::common::ModelArgs;
use super::super::{finish, open_out, to_value, Context, Outcome, Results, Table};
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

/// The exact method for `problem` with `run`, validated and its cost
/// checked against `budget` before any output exists.
pub(crate) fn exact_method(
    problem: &SearchProblem,
    run: ParticleOptions,
    budget: &budget::BudgetArgs,
) -> irtp::Result<SearchMethod> {
    particle_method(problem, SearchMethod::Exact(run), budget)
}

/// A particle method, validated and its cost checked against `budget`.
fn particle_method(
    problem: &SearchProblem,
    method: SearchMethod,
    budget: &budget::BudgetArgs,
) -> irtp::Result<SearchMethod> {
    method.check(problem)?;
    budget.check(&cost(problem, &method)?)?;
    Ok(method)
}

/// Flags → validated problem and method, the cost checked before any
/// output exists.
pub(super) fn config(a: &DirectArgs) -> irtp::Result<SearchConfig> {
    let flags = a.target.search(&a.problem.model, a.problem.v0);
    a.reject_renewal_flags()?;
    a.sim.reject_inapplicable(&a.output)?;
    let problem = flags.problem()?;
    let run = ParticleOptions {
        particles: a.sim.particles(),
        t_max: a.sim.t_max(),
        seed: a.output.seed(),
    };
    let budget = &a.output.budget;
    let method = match a.sim.method {
        Method::Euler => {
            let dt = a.sim.dt();
            particle_method(&problem, SearchMethod::Euler { dt, run }, budget)?
        }
        Method::Exact => particle_method(&problem, SearchMethod::Exact(run), budget)?,
        Method::Backward => {
            // The budget also bounds the finer meshes a sequence that is
            // not yet asymptotic needs (checked before each one).
            let opts = search::backward::BackwardOptions {
                max_work: budget.max_work,
                max_memory: budget.max_memory,
                ..search::backward::BackwardOptions::with_cells(a.cells_x, a.cells_v)
            };
            mesh_method(&problem, SearchMethod::Backward(opts), budget)?
        }
        Method::Renewal => {
            let defaults = search::renewal::RenewalOptions::default();
            let opts = search::renewal::RenewalOptions {
                cells_x: a.cells_x,
                cells_v: a.cells_v,
                steps: a.time_steps.unwrap_or(defaults.steps),
                tail: a.horizon_tail.unwrap_or(defaults.tail),
                max_work: budget.max_work,
                max_memory: budget.max_memory,
                ..defaults
            };
            mesh_method(&problem, SearchMethod::Renewal(opts), budget)?
        }
    };
    Ok(SearchConfig { problem, method })
}

/// The library's option names → the flags that set them.
fn flag_of(name: &'static str) -> &'static str {
    match name {
        "cells_x" => "--cells-x",
        "cells_v" => "--cells-v",
        "steps" => "--time-steps",
        "tail" => "--horizon-tail",
        n => n,
    }
}

/// A mesh method (backward or renewal), validated and its cost checked
/// against `budget` (the solver's own refusals of a problem it cannot
/// solve come first, naming the flags).
fn mesh_method(
    problem: &SearchProblem,
    method: SearchMethod,
    budget: &budget::BudgetArgs,
) -> irtp::Result<SearchMethod> {
    let named = |e: Error| match e {
        Error::InvalidParameter {
            name,
            value,
            allowed,
        } => Error::InvalidParameter {
            name: flag_of(name),
            value,
            allowed,
        },
        e => e,
    };
    let cost = method.cost(problem).map_err(named)?.expect("a mesh method");
    let extra: &[&'static str] = match method {
        SearchMethod::Renewal(_) => &["time_steps", "horizon_tail"],
        _ => &[],
    };
    let drivers = search::backward::mesh_drivers(problem, extra);
    budget.check(&Cost {
        work: cost.work,
        unit: "operations",
        memory_drivers: drivers.clone(),
        drivers,
        memory: cost.memory,
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
    let (per, unit) = match *method {
        // Steps of the runs at dt and dt/2.
        SearchMethod::Euler { dt, .. } => {
            drivers.push("dt");
            (3.0 * time / dt + 2.0, "Euler particle steps")
        }
        _ => (rate * time + 2.0, "particle events"),
    };
    Ok(budget::particles(run.particles, per, unit, drivers, 0, 0))
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
            problem: c.problem.clone(),
            tau: mean(s.tau),
            tau_plus: mean(s.tau_plus),
            tau_minus: mean(s.tau_minus),
            infinite_mean: !finite,
            infinite_mean_reason: (!finite).then(|| reason_of(&c.problem)),
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
        let why = r.infinite_mean_reason.unwrap_or(INFINITE_MEAN_REASON);
        return format!("INFINITE MEAN: tau is not reported: {why}.\n{tail}\n");
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

/// Why the mean search time of `problem` is infinite (its own cause).
fn reason_of(problem: &SearchProblem) -> &'static str {
    problem
        .infinite_mean_reason()
        .unwrap_or(INFINITE_MEAN_REASON)
}

/// The text note of a mesh method's answer: an infinite mean leads it.
fn mesh_note(problem: &SearchProblem, infinite: bool) -> String {
    if infinite {
        format!("INFINITE MEAN (tau = inf): {}.\n", reason_of(problem))
    } else {
        String::new()
    }
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
    #[serde(skip_serializing_if = "Option::is_none")]
    infinite_mean_reason: Option<&'static str>,
    #[serde(flatten)]
    solution: search::backward::SearchSolution,
}

/// What `irtp mfpt --xt/--interval --method renewal --json` prints: the
/// options (provenance) and the solution.
#[derive(Serialize)]
struct RenewalReport {
    method: &'static str,
    problem: SearchProblem,
    options: search::renewal::RenewalOptions,
    #[serde(skip_serializing_if = "Option::is_none")]
    infinite_mean_reason: Option<&'static str>,
    #[serde(flatten)]
    solution: search::renewal::RenewalSolution,
}

/// What `irtp mfpt --xt/--interval --method euler --json` prints: the
/// extrapolated tau (null where the mean is infinite or a run censored),
/// and the summaries of the runs at dt and dt/2.
#[derive(Serialize)]
struct EulerReport {
    method: &'static str,
    problem: SearchProblem,
    tau: f64,
    tau_err: f64,
    tau_plus: f64,
    tau_plus_err: f64,
    tau_minus: f64,
    tau_minus_err: f64,
    /// tau(dt/2) - tau(dt), the measured step bias.
    step_bias: f64,
    infinite_mean: bool,
    #[serde(skip_serializing_if = "Option::is_none")]
    infinite_mean_reason: Option<&'static str>,
    tail_exponent: Option<TailFit>,
    dt: f64,
    particles: u64,
    t_max: f64,
    seed: u64,
    /// The run at dt.
    coarse: FptSummary,
    /// The run at dt/2.
    fine: FptSummary,
}

/// The report, survival table and text note of an Euler search.
fn euler_report(c: &SearchConfig, e: search::EulerSearch) -> (EulerReport, Table, String) {
    let run = c.method.particles().expect("a particle method");
    let (tau, tau_plus, tau_minus, tau_err) = SearchResult::Euler(e.clone()).tau();
    let m = |v: f64| if e.mean_is_finite { v } else { f64::NAN };
    let x = e.extrapolated;
    let (coarse, fine) = (e.coarse.summary(), e.fine.summary());
    let notes = [&coarse, &fine].map(|s| note(&SearchReport::new(c, s, e.mean_is_finite, e.tail)));
    let report = EulerReport {
        method: c.method.name(),
        problem: c.problem.clone(),
        tau,
        tau_err,
        tau_plus,
        tau_plus_err: m(x.tau_plus_err),
        tau_minus,
        tau_minus_err: m(x.tau_minus_err),
        step_bias: m(x.step_bias),
        infinite_mean: !e.mean_is_finite,
        infinite_mean_reason: (!e.mean_is_finite).then(|| reason_of(&c.problem)),
        tail_exponent: e.tail,
        dt: e.dt,
        particles: run.particles,
        t_max: run.t_max,
        seed: run.seed,
        coarse,
        fine,
    };
    let text = if notes[0].is_empty() {
        notes[1].clone()
    } else {
        notes[0].clone()
    };
    (report, survival_table(&e.fine.survival()), text)
}

/// The report of a solved search: (JSON, seed, tables, text note).
pub(crate) fn report_of(
    c: &SearchConfig,
    result: SearchResult,
) -> (serde_json::Value, Option<u64>, Vec<Table>, String) {
    let (method, problem) = (c.method.name(), c.problem.clone());
    match result {
        SearchResult::Particles(r) => {
            let report = SearchReport::new(c, &r.stats.summary(), r.mean_is_finite, r.tail);
            let table = survival_table(&r.stats.survival());
            (
                to_value(&report),
                Some(report.seed),
                vec![table],
                note(&report),
            )
        }
        SearchResult::Euler(e) => {
            let (report, table, text) = euler_report(c, e);
            (to_value(&report), Some(report.seed), vec![table], text)
        }
        SearchResult::Backward(solution) => {
            let inf = solution.infinite_mean;
            let note = mesh_note(&problem, inf);
            let report = BackwardReport {
                method,
                infinite_mean_reason: inf.then(|| reason_of(&problem)),
                problem,
                solution,
            };
            (to_value(&report), None, vec![], note)
        }
        SearchResult::Renewal(solution) => {
            let SearchMethod::Renewal(options) = c.method else {
                unreachable!("the renewal route gives a renewal solution")
            };
            let inf = solution.infinite_mean;
            let note = mesh_note(&problem, inf);
            let report = RenewalReport {
                method,
                infinite_mean_reason: inf.then(|| reason_of(&problem)),
                problem,
                options,
                solution,
            };
            (to_value(&report), None, vec![], note)
        }
    }
}

/// Run a search: `summary.json`, `run.json`, `mfpt.json` and, by
/// particles, `survival.csv`.
pub(super) fn run(a: &DirectArgs, ctx: &Context) -> irtp::Result<Outcome> {
    let c = config(a)?;
    let out = open_out("mfpt", a.output.out.as_deref(), a.output.force.force)?;
    let t0 = Instant::now();
    let result = {
        // A mesh method reports millions of operations of its estimate.
        let (label, total) = match c.method.particles() {
            Some(r) => ("search", r.particles),
            None => ("search (mesh)", 1),
        };
        let bar = ctx.reporter.stage(label, total);
        search::solve(&c.problem, &c.method, bar.as_ref())?
    };
    ctx.check()?;
    write(&c, result, t0.elapsed().as_secs_f64(), out, ctx)
}

/// Write a solved search's outputs (`wall`: its computing time).
pub(crate) fn write(
    c: &SearchConfig,
    result: SearchResult,
    wall: f64,
    out: Option<crate::io::OutputDir>,
    ctx: &Context,
) -> irtp::Result<Outcome> {
    let (json, seed, tables, note_text) = report_of(c, result);
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
