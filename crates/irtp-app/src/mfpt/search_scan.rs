//! `irtp mfpt scan | optimize --xt L | --interval A,B [--x0 X0] --v0 V0`:
//! the search's mean first-passage time against the reset rate, the start
//! or the level, and the reset rate minimising it, through
//! [`irtp::search::optimize`] (the 2-D backward equation with its error
//! estimate; `--method exact` adds the sampler at every scan point).
//!
//! With velocity-only resetting and a one-sided level the mean is infinite
//! at every r: `optimize` refuses naming `--reset-position` (an interval has
//! a finite mean), and a scan's points are refused by the solver.

use super::super::budget::Cost;
use super::super::common::parse_size;
use super::super::{finish, open_out, to_value, Context, Outcome, Results};
use super::search::SearchFlags;
use super::{scan_note, scan_table, table_text, text_lines, Method, OptimizeArgs, Over, ScanArgs};
use clap::Args;
use irtp::mfpt::optimize::{scan_values, Optimum, RateRange};
use irtp::mfpt::{FptSummary, ParticleOptions};
use irtp::search::backward::BackwardOptions;
use irtp::search::clock_optimize::{optimize_clock, ClockOptimum};
use irtp::search::optimize::{self as so, SearchAxis};
use irtp::search::renewal::{RenewalOptions, WaitingTime};
use irtp::search::{self, SearchMethod, SearchProblem, SearchResult};
use irtp::Error;
use serde::Serialize;
use std::time::Instant;

/// The search target of `mfpt scan` and `mfpt optimize` (instead of --vt).
#[derive(Args, Debug, Clone)]
pub(crate) struct SearchTargetArgs {
    /// Search target in position (instead of --vt): the first time x reaches the level L.
    ///
    /// One-sided; with velocity-only resetting its mean is infinite: full resetting,
    /// --reset-position, makes it finite.
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
    /// Cells in x of the coarse mesh of a search's backward equation (refined once and
    /// extrapolated) [default: 64, mfpt optimize 32; --xt or --interval only].
    #[arg(long, allow_hyphen_values = true, value_parser = parse_size)]
    pub(crate) cells_x: Option<usize>,
    /// Cells in v of the coarse mesh of a search's backward equation [default: 32, mfpt
    /// optimize 16; --xt or --interval only].
    #[arg(long, allow_hyphen_values = true, value_parser = parse_size)]
    pub(crate) cells_v: Option<usize>,
}

impl SearchTargetArgs {
    /// Whether a search target (--xt or --interval) was given.
    pub(crate) fn is_search(&self) -> bool {
        self.xt.is_some() || self.interval.is_some()
    }

    /// Refuse the search-only flags with a velocity target.
    pub(crate) fn velocity_only(&self) -> irtp::Result<()> {
        let given = [
            ("--x0", self.x0.map(|x| x.to_string())),
            ("--cells-x", self.cells_x.map(|c| c.to_string())),
            ("--cells-v", self.cells_v.map(|c| c.to_string())),
        ];
        for (flag, value) in given {
            if let Some(v) = value {
                return Err(Error::invalid(
                    flag,
                    v,
                    "only with a search target in position (--xt or --interval)",
                ));
            }
        }
        Ok(())
    }

    /// The validated search problem with `model` and the start velocity.
    fn problem(&self, a: &super::ProblemArgs) -> irtp::Result<SearchProblem> {
        SearchFlags {
            model: &a.model,
            v0: a.v0,
            x0: self.x0,
            xt: self.xt,
            interval: self.interval.as_deref(),
        }
        .problem()
    }

    /// The backward options (the app's budget replaces the library's), the
    /// mesh `(cells_x, cells_v)` by default.
    fn backward(&self, (cx, cv): (usize, usize)) -> irtp::Result<BackwardOptions> {
        let o = BackwardOptions {
            max_work: f64::INFINITY,
            max_memory: f64::INFINITY,
            ..BackwardOptions::with_cells(self.cells_x.unwrap_or(cx), self.cells_v.unwrap_or(cv))
        };
        o.validate().map_err(|e| match e {
            Error::InvalidParameter {
                name,
                value,
                allowed,
            } => Error::InvalidParameter {
                name: if name == "cells_x" {
                    "--cells-x"
                } else {
                    "--cells-v"
                },
                value,
                allowed,
            },
            e => e,
        })?;
        Ok(o)
    }
}

/// The refusal of `--over x0|xt` with a velocity target.
pub(super) fn search_axis_refused(over: Over) -> Error {
    let name = if matches!(over, Over::X0) { "x0" } else { "xt" };
    Error::invalid(
        "--over",
        name,
        "vt or rate with a target velocity (--vt); x0 and xt with a search target (--xt or --interval)",
    )
}

/// The budget's view of `solves` backward solves of `problem`.
fn solve_cost(problem: &SearchProblem, o: &BackwardOptions, solves: f64) -> irtp::Result<Cost> {
    let c = search::backward::estimate(problem, o)?;
    Ok(Cost {
        work: c.work * solves,
        unit: "operations",
        drivers: vec!["cells_x", "cells_v", "rate"],
        memory: c.memory,
        memory_drivers: vec!["cells_x", "cells_v"],
    })
}

/// Bytes held per scan point besides the solver's: its value, its problem,
/// its result row and its cost estimate (the velocity-target scan counts
/// 256 bytes a point).
fn point_bytes() -> f64 {
    (8 + std::mem::size_of::<SearchProblem>() + 256) as f64
}

/// The cost of `--points` solves, each at most the dearer of the two ends'
/// (the scanned rate, start or target runs monotonically between them), and
/// the points' memory: checked before the point list is allocated, so a huge
/// `--points` is refused at once, naming it.
fn points_cost(
    base: &SearchProblem,
    axis: SearchAxis,
    a: &ScanArgs,
    o: &BackwardOptions,
) -> irtp::Result<Cost> {
    let mut per = None::<Cost>;
    for (i, x) in [(0, a.from), (1, a.to)] {
        let p = so::scan_problem(base, axis, x).map_err(|e| blame(e, axis, i, (a.from, a.to)))?;
        let c = solve_cost(&p, o, 1.0).map_err(|e| blame(e, axis, i, (a.from, a.to)))?;
        per = Some(match per {
            Some(q) if q.work >= c.work => q,
            _ => c,
        });
    }
    let per = per.expect("two ends");
    let points = a.points as f64;
    Ok(Cost {
        work: per.work * points,
        drivers: [vec!["points"], per.drivers].concat(),
        memory: per.memory + point_bytes() * points,
        memory_drivers: [vec!["points"], per.memory_drivers].concat(),
        ..per
    })
}

/// The validated inputs of a search scan.
pub(super) struct SearchScanConfig {
    base: SearchProblem,
    axis: SearchAxis,
    values: Vec<f64>,
    problems: Vec<SearchProblem>,
    backward: BackwardOptions,
    /// The sampler's options with --method exact.
    particles: Option<ParticleOptions>,
}

/// A scanned point's error names the scanned parameter; the user typed
/// `--from` / `--to` (the first point is `--from`, a later one lies
/// towards `--to`).
fn blame(e: Error, axis: SearchAxis, point: usize, (from, to): (f64, f64)) -> Error {
    match e {
        Error::InvalidParameter { name, allowed, .. } if name == axis.name() => {
            let (flag, value) = if point == 0 {
                ("--from", from)
            } else {
                ("--to", to)
            };
            Error::invalid(flag, value, allowed)
        }
        Error::InvalidParameter {
            name: "over",
            value,
            allowed,
        } => Error::InvalidParameter {
            name: "--over",
            value,
            allowed,
        },
        other => other,
    }
}

/// Flags → validated search scan: every point checked by the solver and
/// the summed cost against the budget before anything runs.
pub(super) fn scan_config(a: &ScanArgs) -> irtp::Result<SearchScanConfig> {
    let axis = match a.over {
        Over::Rate => SearchAxis::Rate,
        Over::X0 => SearchAxis::X0,
        Over::Xt => SearchAxis::Xt,
        Over::Vt => {
            return Err(Error::invalid(
                "--over",
                "vt",
                "rate, x0 or xt with a search target (--xt or --interval)",
            ))
        }
    };
    let backward = a.search.backward((64, 32))?;
    let base = a.search.problem(&a.problem)?;
    a.output
        .budget
        .check(&points_cost(&base, axis, a, &backward)?)?;
    let values = scan_values(a.from, a.to, a.points, a.log)?;
    let problems = values
        .iter()
        .enumerate()
        .map(|(i, &x)| {
            so::scan_problem(&base, axis, x).map_err(|e| blame(e, axis, i, (a.from, a.to)))
        })
        .collect::<irtp::Result<Vec<_>>>()?;
    let mut cost: Option<Cost> = None;
    for (i, p) in problems.iter().enumerate() {
        let c = solve_cost(p, &backward, 1.0).map_err(|e| blame(e, axis, i, (a.from, a.to)))?;
        cost = Some(cost.map_or(c.clone(), |t| t.then(c)));
    }
    let particles = scan_particles(a)?;
    if let Some(run) = particles {
        for p in &problems {
            let m = SearchMethod::Exact(run);
            m.check(p)?;
            let c = super::search::cost(p, &m)?;
            cost = cost.map(|t| t.then(c));
        }
    }
    a.output.budget.check(&cost.expect("at least two points"))?;
    Ok(SearchScanConfig {
        base,
        axis,
        values,
        problems,
        backward,
        particles,
    })
}

/// The sampler's options of a scan (`--method exact`), None for
/// `backward`; `euler` refused.
fn scan_particles(a: &ScanArgs) -> irtp::Result<Option<ParticleOptions>> {
    a.sim.reject_inapplicable(&a.output)?;
    match a.sim.method {
        Method::Backward => Ok(None),
        Method::Euler | Method::Renewal => Err(Error::invalid(
            "--method",
            if a.sim.method == Method::Euler {
                "euler"
            } else {
                "renewal"
            },
            "backward or exact in a search scan (--xt, --interval)",
        )),
        Method::Exact => Ok(Some(ParticleOptions {
            particles: a.sim.particles(),
            t_max: a.sim.t_max(),
            seed: a.output.seed(),
        })),
    }
}

/// What `run.json` records of a search scan.
#[derive(Serialize)]
struct SearchScanParams<'a> {
    base: &'a SearchProblem,
    over: &'a str,
    values: &'a [f64],
    cells_x: usize,
    cells_v: usize,
    method: Method,
    particles: Option<u64>,
    t_max: Option<f64>,
}

/// The sampler at every point (same seed: common random numbers).
fn sample(
    c: &SearchScanConfig,
    run: ParticleOptions,
    ctx: &Context,
) -> irtp::Result<Vec<FptSummary>> {
    let method = SearchMethod::Exact(run);
    c.problems
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let bar = ctx
                .reporter
                .stage(&format!("point {}", i + 1), run.particles);
            let r = search::solve(p, &method, bar.as_ref())?;
            ctx.check()?;
            match r {
                SearchResult::Particles(s) => Ok(s.stats.summary()),
                _ => unreachable!("the exact method gives particle statistics"),
            }
        })
        .collect()
}

/// The note on points whose meshes are not asymptotic (tau_err NaN).
fn unresolved_note(n: usize) -> String {
    if n == 0 {
        return String::new();
    }
    format!(
        "{n} point(s) unresolved: the meshes are not asymptotic there (tau_err = NaN); \
         raise --cells-x/--cells-v\n"
    )
}

/// Run a search scan: `mfpt_scan.csv` (the velocity scan's columns); a
/// point whose mesh sequence is not asymptotic keeps its extrapolated tau
/// with tau_err NaN (unresolved, counted in the note).
pub(super) fn run_scan(a: &ScanArgs, ctx: &Context) -> irtp::Result<Outcome> {
    let c = scan_config(a)?;
    let out = open_out("mfpt scan", a.output.out.as_deref(), a.output.force.force)?;
    let t0 = Instant::now();
    let points = {
        let bar = ctx
            .reporter
            .stage("mfpt scan (search)", c.values.len() as u64);
        so::scan(&c.base, c.axis, &c.values, &c.backward, bar.as_ref())?
    };
    ctx.check()?;
    let sims = c.particles.map(|run| sample(&c, run, ctx)).transpose()?;
    let wall = t0.elapsed().as_secs_f64();
    let rows: Vec<[f64; 5]> = points
        .iter()
        .map(|p| {
            let s = &p.solution;
            [p.x, s.tau, s.tau_plus, s.tau_minus, s.error_estimate]
        })
        .collect();
    let table = scan_table(c.axis.name(), &rows, sims.as_deref());
    let unresolved = points.iter().filter(|p| !p.solution.asymptotic).count();
    let note = sims.as_deref().map_or(String::new(), scan_note) + &unresolved_note(unresolved);
    let params = SearchScanParams {
        base: &c.base,
        over: c.axis.name(),
        values: &c.values,
        cells_x: c.backward.cells_x,
        cells_v: c.backward.cells_v,
        method: a.sim.method,
        particles: c.particles.map(|r| r.particles),
        t_max: c.particles.map(|r| r.t_max),
    };
    let results = Results {
        method: if sims.is_some() {
            "backward-2d + exact"
        } else {
            "backward-2d"
        }
        .into(),
        seed: c.particles.map(|r| r.seed),
        json: to_value(&super::table_json(&table)),
        parameters: to_value(&params),
        text: table_text(&table) + &note,
        tables: vec![table],
        json_files: Vec::new(),
        wall_time_s: wall,
    };
    finish("mfpt scan", results, out, ctx)
}

/// The validated inputs of a search's optimisation: over the Poisson rate
/// (the 2-D backward equation), or over the reset frequency 1/m of a
/// renewal clock (`--reset-clock`: the renewal route, the law's shape
/// fixed).
pub(super) struct OptimizeConfig {
    problem: SearchProblem,
    range: RateRange,
    backward: BackwardOptions,
    /// The renewal route's options where the problem has a renewal clock.
    renewal: Option<RenewalOptions>,
}

/// Flags → validated search, rate range and mesh; refused where the mean is
/// infinite at every r; the cost (grid, refinement of r*, the optimum; each
/// at most the cost at r_min, whose truncated domain (or horizon) is the
/// longest) checked against the budget.
pub(super) fn optimize_config(a: &OptimizeArgs) -> irtp::Result<OptimizeConfig> {
    if let Some(r) = a.problem.model.rate {
        return Err(Error::invalid(
            "--rate",
            r,
            "not with mfpt optimize, which searches r over {0} ∪ [--r-min, --r-max]",
        ));
    }
    a.output.no_seed("mfpt optimize")?;
    // The screened grid and Brent's refinement solve about a hundred
    // rates, the smallest on long truncated domains (about 1e10 operations at 32 x 16
    // and r = 1e-3): half the scan's cells each way keeps the default run
    // within the default --max-work; the optimum's checked solve refines
    // where its meshes are not asymptotic.
    let backward = a.search.backward((32, 16))?;
    let problem = a.search.problem(&a.problem)?;
    let range = RateRange {
        r_min: a.r_min,
        r_max: a.r_max,
        grid_points: a.grid_points,
        ..RateRange::default()
    };
    if let Some(clock) = &problem.params().schedule().clock {
        range.validate()?;
        let renewal = RenewalOptions {
            cells_x: backward.cells_x,
            cells_v: backward.cells_v,
            max_work: f64::INFINITY,
            max_memory: f64::INFINITY,
            ..RenewalOptions::default()
        };
        let max_work = a.output.budget.max_work;
        let c = optimize_cost(
            &range,
            zero_cost(&problem, &backward)?,
            None,
            max_work,
            |f| {
                let waiting = WaitingTime::Renewal {
                    clock: clock.with_mean(1.0 / f)?,
                };
                let c = search::renewal::estimate(&problem, &waiting, &renewal)?;
                Ok(Cost {
                    work: c.work,
                    unit: "operations",
                    drivers: Vec::new(),
                    memory: c.memory,
                    memory_drivers: vec!["cells_x", "cells_v"],
                })
            },
        )?;
        a.output.budget.check(&Cost {
            drivers: vec!["grid_points", "cells_x", "cells_v", "r_min"],
            ..c
        })?;
        // The optimum's checked solve climbs its mesh ladder within the budget.
        let renewal = RenewalOptions {
            max_work: a.output.budget.max_work,
            max_memory: a.output.budget.max_memory,
            ..renewal
        };
        return Ok(OptimizeConfig {
            problem,
            range,
            backward,
            renewal: Some(renewal),
        });
    }
    so::check_optimizable(&problem, &range)?;
    let max_work = a.output.budget.max_work;
    // The grid rates are screened on half the cells first.
    let screens = || so::screen_work(&problem, &range, &backward);
    let at_zero = zero_cost(&problem, &backward)?;
    let cost = optimize_cost(&range, at_zero, Some(&screens), max_work, |r| {
        solve_cost(&problem.with_rate(r)?, &backward, 1.0)
    })?;
    a.output.budget.check(&Cost {
        drivers: vec!["grid_points", "cells_x", "cells_v", "r_min"],
        ..cost
    })?;
    // The optimum's checked solve climbs its mesh ladder within the budget.
    let backward = BackwardOptions {
        max_work: a.output.budget.max_work,
        max_memory: a.output.budget.max_memory,
        ..backward
    };
    Ok(OptimizeConfig {
        problem,
        range,
        backward,
        renewal: None,
    })
}

/// The estimated work of a rate optimisation ([`so::optimize_rate`],
/// [`optimize_clock`]) from `cost_at(r)`, one solve's: [`so::total_work`]
/// of the grid rates' and `at_zero` (an interval's solve at r = 0), the
/// dearest grid rate's memory; with `screens` (the screening solves' work,
/// [`so::screen_work`]) [`so::screened_total_work`] instead.
/// Where the grid alone at the cheapest rate (r_max: the shortest domain)
/// exceeds `max_work` (half the grid with screening), that lower bound,
/// before any rate is priced or screened.
fn optimize_cost(
    range: &RateRange,
    at_zero: f64,
    screens: Option<&dyn Fn() -> irtp::Result<f64>>,
    max_work: f64,
    cost_at: impl Fn(f64) -> irtp::Result<Cost>,
) -> irtp::Result<Cost> {
    let cheapest = cost_at(range.r_max)?;
    let share = if screens.is_some() { 0.5 } else { 1.0 };
    let floor = share * cheapest.work * range.grid_points as f64;
    if !(floor <= max_work) {
        return Ok(Cost {
            work: floor,
            ..cheapest
        });
    }
    let grid = range
        .grid()
        .into_iter()
        .map(cost_at)
        .collect::<irtp::Result<Vec<_>>>()?;
    let works: Vec<f64> = grid.iter().map(|c| c.work).collect();
    let total = match screens {
        Some(s) => so::screened_total_work(range, &works, at_zero, s()?),
        None => so::total_work(range, &works, at_zero),
    };
    let memory = grid.iter().map(|c| c.memory).fold(0.0, f64::max);
    Ok(Cost {
        work: total,
        memory,
        ..grid.into_iter().next().expect("at least three grid rates")
    })
}

/// The backward solve at r = 0 of an interval (0 for a level: tau = ∞).
fn zero_cost(problem: &SearchProblem, o: &BackwardOptions) -> irtp::Result<f64> {
    Ok(match problem.target() {
        search::PositionTarget::Interval(..) => solve_cost(&problem.with_rate(0.0)?, o, 1.0)?.work,
        search::PositionTarget::Level(_) => 0.0,
    })
}

/// What `irtp mfpt optimize --xt/--interval --json` prints.
#[derive(Serialize)]
struct SearchOptimum<'a> {
    r_opt: f64,
    tau_opt: f64,
    tau_opt_err: f64,
    r_opt_range: (f64, f64),
    tau_plus_opt: f64,
    tau_minus_opt: f64,
    /// tau without resetting: null (infinite) for a one-sided level.
    tau_r0: f64,
    interior: bool,
    at_upper_bound: bool,
    /// With a renewal clock: r_opt is the reset frequency 1/m; the optimal
    /// mean waiting time, its range and the clock there.
    #[serde(skip_serializing_if = "Option::is_none")]
    mean_opt: Option<f64>,
    #[serde(skip_serializing_if = "Option::is_none")]
    mean_opt_range: Option<(f64, f64)>,
    #[serde(skip_serializing_if = "Option::is_none")]
    reset_clock_opt: Option<String>,
    problem: &'a SearchProblem,
    r_min: f64,
    r_max: f64,
    cells_x: usize,
    cells_v: usize,
}

/// Run a search's rate optimisation: `optimum.json`, `rate_grid.csv`.
pub(super) fn run_optimize(a: &OptimizeArgs, ctx: &Context) -> irtp::Result<Outcome> {
    let c = optimize_config(a)?;
    let (problem, range, backward) = (c.problem, c.range, c.backward);
    let out = open_out(
        "mfpt optimize",
        a.output.out.as_deref(),
        a.output.force.force,
    )?;
    let t0 = Instant::now();
    let bar = ctx
        .reporter
        .stage("mfpt optimize (search)", range.grid_points as u64);
    let (best, by_clock): (Optimum, Option<ClockOptimum>) = match &c.renewal {
        Some(renewal) => {
            let o = optimize_clock(&problem, &range, renewal, bar.as_ref())?;
            (o.optimum.clone(), Some(o))
        }
        None => (
            so::optimize_rate(&problem, &range, &backward, bar.as_ref())?.optimum,
            None,
        ),
    };
    drop(bar);
    ctx.check()?;
    let wall = t0.elapsed().as_secs_f64();
    let summary = SearchOptimum {
        r_opt: best.r_opt,
        tau_opt: best.tau_opt,
        tau_opt_err: best.tau_opt_err,
        r_opt_range: best.r_opt_range,
        tau_plus_opt: best.tau_plus_opt,
        tau_minus_opt: best.tau_minus_opt,
        tau_r0: best.tau_r0,
        interior: best.interior,
        at_upper_bound: best.at_upper_bound,
        mean_opt: by_clock.as_ref().map(|o| o.mean),
        mean_opt_range: by_clock.as_ref().map(|o| o.mean_range),
        reset_clock_opt: by_clock
            .as_ref()
            .and_then(|o| o.clock.as_ref().map(|c| c.to_string())),
        problem: &problem,
        r_min: range.r_min,
        r_max: range.r_max,
        cells_x: backward.cells_x,
        cells_v: backward.cells_v,
    };
    let json = to_value(&summary);
    let grid = super::rate_grid(&best.grid);
    let results = Results {
        method: if by_clock.is_some() {
            "renewal route + golden-section".into()
        } else {
            "backward-2d + brent".into()
        },
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
