//! `irtp mfpt distribution`: the first-passage-time distribution.
//!
//! - `--method backward` (default): S±(t) and f±(t) = -dS±/dt at v_0 from the
//!   time-dependent backward equations on a `--grid linear|log` of `--points`
//!   times up to `--t-max` ([`irtp::mfpt::distribution()`]), and the moments
//!   tau, E(T²), variance and coefficient of variation from the stationary
//!   equations L T1 = -1, L T2 = -2 T1 ([`irtp::mfpt::backward::moments`]);
//!   `distribution.csv` at every output time (the atom at the flow time is
//!   reported as a point mass: S+ drops by it, f is the density of the rest).
//! - `--method exact`: the exact first-passage sampler's arrival-time
//!   histogram (`histogram.csv`, density with its standard error on the
//!   fixed log grid of [`irtp::mfpt::survival`]) and the Kaplan-Meier
//!   survival curve (`survival.csv`, censored at `--t-max`), so the two
//!   overlay.
//! - `--xt L | --interval A,B [--x0 X0] --method exact`: the same for the
//!   search time (first passage in position, [`irtp::search`]).

use super::common::{ModelArgs, OutputArgs};
use super::mfpt::search::{self, SearchConfig};
use super::mfpt::ProblemArgs;
use super::simulate::GridArg;
use super::{finish, open_out, to_value, Context, Outcome, Results, Table};
use clap::{Args, ValueEnum};
use irtp::mfpt::survival::edges;
use irtp::mfpt::{
    self, backward, BackwardOptions, Distribution, DistributionOptions, FptStats, ParticleOptions,
    Problem,
};
use irtp::search::distribution::DistributionOptions as SearchDistOptions;
use irtp::sim::TimeGrid;
use irtp::Error;
use serde::Serialize;
use std::time::Instant;

/// How the distribution is computed.
#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum DistMethod {
    /// Time-dependent backward equations (monotone upwind scheme, atom split off exactly, two meshes extrapolated; TR-BDF2 in time);
    /// `ode` is its former name, still accepted with a warning.
    #[value(alias = "ode")]
    Backward,
    /// Exact event-driven first-passage sampler: histogram and Kaplan-Meier curve.
    Exact,
}

/// `irtp mfpt distribution`.
#[derive(Args, Debug)]
pub struct DistributionArgs {
    #[command(flatten)]
    model: ModelArgs,
    /// Initial velocity v_0 (inside (v_l, v_u), on the same side of v_t as v_r).
    #[arg(long, allow_hyphen_values = true)]
    v0: f64,
    /// Cells of the backward-equation mesh on [v_l, v_t].
    ///
    /// The upwind scheme
    /// runs on cells/2 and on cells and extrapolates; the stationary moments
    /// use the box scheme on cells. The distribution's mean agrees with tau
    /// to 1e-7-1e-5 at 4000 cells (error ~ cells⁻²); S(t) to the reported
    /// mesh_error.
    #[arg(long, default_value_t = 4000, allow_hyphen_values = true, value_parser = super::common::parse_size)]
    cells: usize,
    #[command(flatten)]
    target: super::mfpt::TargetArgs,
    /// Method: backward (S(t), f(t) from the backward equations) or exact (sampled histogram).
    #[arg(long, value_enum, default_value = "backward")]
    method: DistMethod,
    /// Last output time (backward) or censoring time of the particles (exact)
    /// [default: 10 tau (backward), 100 tau (exact), tau from the backward equations].
    #[arg(long, allow_hyphen_values = true)]
    t_max: Option<f64>,
    /// Output times, t = 0 included [default: 201; backward only].
    #[arg(long, allow_hyphen_values = true, value_parser = super::common::parse_size)]
    points: Option<usize>,
    /// Time grid [default: linear; backward only].
    #[arg(long, value_enum)]
    grid: Option<GridArg>,
    /// First non-zero time of a log grid [default: 1e-4 t-max; --grid log only].
    #[arg(long, allow_hyphen_values = true)]
    t_min: Option<f64>,
    /// Relative tolerance of the time stepping [default: 1e-4; backward only].
    #[arg(long, allow_hyphen_values = true)]
    rtol: Option<f64>,
    /// Particles, half started in each noise state [default: 100000; exact only].
    #[arg(long, allow_hyphen_values = true, value_parser = super::common::parse_count)]
    particles: Option<u64>,
    /// Cells in x of the coarse mesh of a search's backward distribution (--xt or --interval
    /// with --method backward; refined once and extrapolated) [default: 32].
    #[arg(long, allow_hyphen_values = true, value_parser = super::common::parse_size)]
    cells_x: Option<usize>,
    /// Cells in v of that mesh [default: 16].
    #[arg(long, allow_hyphen_values = true, value_parser = super::common::parse_size)]
    cells_v: Option<usize>,
    #[command(flatten)]
    output: OutputArgs,
}

/// A search's distribution: by particles, or by the backward equation.
enum SearchDist {
    Particles(SearchConfig),
    Backward(SearchBackward),
}

/// The validated inputs of a search's backward distribution.
struct SearchBackward {
    problem: irtp::search::SearchProblem,
    opts: SearchDistOptions,
}

/// The validated inputs.
struct Config {
    problem: Problem,
    t_max: f64,
    kind: Kind,
}

enum Kind {
    Backward(TimeGrid, DistributionOptions),
    Exact(ParticleOptions),
}

/// A flag that does not apply to the chosen method.
fn refuse(flag: &'static str, value: Option<String>, only: &str) -> irtp::Result<()> {
    match value {
        Some(v) => Err(Error::invalid(flag, v, format!("only with {only}"))),
        None => Ok(()),
    }
}

impl DistributionArgs {
    /// Whether the chosen method draws random numbers.
    pub fn uses_seed(&self) -> bool {
        self.method == DistMethod::Exact
    }

    /// Whether `--json` was given.
    pub fn json(&self) -> bool {
        self.output.json
    }

    /// A flag of the other method is an error, never ignored.
    fn reject_inapplicable(&self) -> irtp::Result<()> {
        let s = |x: Option<f64>| x.map(|v| v.to_string());
        match self.method {
            DistMethod::Backward => {
                self.output
                    .no_seed("the backward equations (--method backward)")?;
                let p = self.particles.map(|n| n.to_string());
                refuse("--particles", p, "--method exact")
            }
            DistMethod::Exact => {
                let only = "--method backward (the sampler's histogram has its fixed log grid)";
                refuse("--points", self.points.map(|n| n.to_string()), only)?;
                refuse("--grid", self.grid.map(|g| format!("{g:?}")), only)?;
                refuse("--t-min", s(self.t_min), only)?;
                refuse("--rtol", s(self.rtol), only)
            }
        }?;
        if self.grid != Some(GridArg::Log) {
            refuse("--t-min", s(self.t_min), "--grid log")?;
        }
        Ok(())
    }

    /// Validate the flags (the same checks as a run, before any work).
    pub(super) fn validate(&self) -> irtp::Result<()> {
        if self.is_search() {
            return self.search_config().map(drop);
        }
        self.refuse_search_mesh()?;
        self.config().map(drop)
    }

    /// Whether a search target in position (--xt or --interval) was given.
    fn is_search(&self) -> bool {
        self.target.is_search()
    }

    /// The search problem's config: the exact method (its flags checked as
    /// for a velocity target, t-max default 1e4 and finite), or the backward
    /// equation ([`SearchBackward`]).
    fn search_config(&self) -> irtp::Result<SearchDist> {
        if self.method == DistMethod::Backward {
            return self.search_backward().map(SearchDist::Backward);
        }
        self.reject_inapplicable()?;
        self.refuse_search_mesh()?;
        let flags = self.target.search(&self.model, Some(self.v0));
        let problem = flags.problem()?;
        let t_max = self.t_max.unwrap_or(1e4);
        if !(t_max > 0.0 && t_max.is_finite()) {
            return Err(Error::invalid("--t-max", t_max, "0 < t-max < inf"));
        }
        let run = ParticleOptions {
            particles: self.particles.unwrap_or(100_000),
            t_max,
            seed: self.output.seed(),
        };
        let method = search::exact_method(&problem, run, &self.output.budget)?;
        Ok(SearchDist::Particles(SearchConfig { problem, method }))
    }

    /// --cells-x and --cells-v only with a search's backward distribution.
    fn refuse_search_mesh(&self) -> irtp::Result<()> {
        let only = "--method backward with a search target (--xt or --interval)";
        refuse("--cells-x", self.cells_x.map(|n| n.to_string()), only)?;
        refuse("--cells-v", self.cells_v.map(|n| n.to_string()), only)
    }

    /// The search's backward distribution: a fixed step (`--points` - 1
    /// steps to `--t-max`; no log grid, no --rtol), t-max default 10 tau
    /// (tau from the stationary solve on a 16 × 8 mesh), its cost checked.
    fn search_backward(&self) -> irtp::Result<SearchBackward> {
        self.reject_inapplicable()?;
        let only = "--method backward with a time grid of fixed steps for a search (--points)";
        refuse("--grid", self.grid.map(|g| format!("{g:?}")), only)?;
        refuse("--rtol", self.rtol.map(|r| r.to_string()), only)?;
        let problem = self.target.search(&self.model, Some(self.v0)).problem()?;
        let named = |e: Error| match e {
            Error::InvalidParameter {
                name,
                value,
                allowed,
            } => Error::InvalidParameter {
                name: match name {
                    "cells_x" => "--cells-x",
                    "cells_v" => "--cells-v",
                    "steps" => "--points",
                    "t_max" => "--t-max",
                    n => n,
                },
                value,
                allowed,
            },
            e => e,
        };
        let t_max = match self.t_max {
            Some(t) => t,
            None => {
                let coarse = irtp::search::backward::BackwardOptions::with_cells(16, 8);
                10.0 * irtp::search::backward::solve(&problem, &coarse)?.tau
            }
        };
        let opts = SearchDistOptions {
            // The budget also bounds the finer meshes of a mesh sequence
            // that is not yet asymptotic (checked before each one).
            mesh: irtp::search::backward::BackwardOptions {
                max_work: self.output.budget.max_work,
                max_memory: self.output.budget.max_memory,
                ..irtp::search::backward::BackwardOptions::with_cells(
                    self.cells_x.unwrap_or(32),
                    self.cells_v.unwrap_or(16),
                )
            },
            t_max,
            steps: self.points.unwrap_or(201).saturating_sub(1),
        };
        let cost = irtp::search::distribution::estimate(&problem, &opts).map_err(named)?;
        self.output.budget.check(&super::budget::Cost {
            work: cost.work,
            unit: "operations",
            drivers: vec!["cells_x", "cells_v", "points", "xt", "rate"],
            memory: cost.memory,
            memory_drivers: vec!["cells_x", "cells_v", "xt"],
        })?;
        Ok(SearchBackward { problem, opts })
    }

    fn config(&self) -> irtp::Result<Config> {
        self.reject_inapplicable()?;
        let vt = self.target.velocity()?;
        let problem_args = ProblemArgs {
            model: self.model.clone(),
            v0: Some(self.v0),
            cells: self.cells,
        };
        let (problem, backward) = problem_args.config(vt)?;
        // Before the time stepping: the stationary solve (cost ~ cells).
        self.output.budget.check(
            &super::budget::mesh(self.cells, 100.0, 256.0, vec!["cells"])
                .per_drag_evaluation(&problem.params().drag()),
        )?;
        // A noise model the distribution does not run is refused by name
        // before tau (which the backward equations refuse for it) is needed.
        irtp::capability::check_noise(irtp::capability::Solver::FptDistribution, problem.params())?;
        if problem.params().noise().is_some() && self.method == DistMethod::Backward {
            mfpt::distribution::check_problem(&problem)?;
        }
        // tau sets the default t-max; a protocol the backward equations
        // refuse is an error of the backward method, and leaves the exact
        // one without a default.
        let tau = match backward::solve(&problem, &BackwardOptions::with_cells(1000)) {
            Ok(s) => s.tau,
            Err(e @ (Error::InvalidParameter { .. } | Error::Unsupported { .. }))
                if self.method == DistMethod::Backward =>
            {
                return Err(e)
            }
            Err(_) => f64::INFINITY,
        };
        let factor = match self.method {
            DistMethod::Backward => 10.0,
            DistMethod::Exact => 100.0,
        };
        let t_max = match self.t_max {
            Some(t) => t,
            None if tau.is_finite() => factor * tau,
            None => {
                return Err(Error::invalid(
                    "--t-max",
                    "missing",
                    "a time > 0 (no backward estimate of tau to scale it: tau overflows)",
                ))
            }
        };
        if !(t_max > 0.0 && t_max.is_finite()) {
            return Err(Error::invalid("--t-max", t_max, "0 < t-max < inf"));
        }
        let kind = match self.method {
            DistMethod::Backward => self.backward_kind(&problem, backward, t_max, tau)?,
            DistMethod::Exact => self.exact_kind(&problem, t_max, tau)?,
        };
        Ok(Config {
            problem,
            t_max,
            kind,
        })
    }

    fn backward_kind(
        &self,
        problem: &Problem,
        backward: BackwardOptions,
        t_max: f64,
        tau: f64,
    ) -> irtp::Result<Kind> {
        let points = self.points.unwrap_or(201);
        let name = |e: Error| match e {
            Error::InvalidParameter {
                name: "samples",
                value,
                allowed,
            } => Error::InvalidParameter {
                name: "--points",
                value,
                allowed,
            },
            e => e,
        };
        let grid = match self.grid.unwrap_or(GridArg::Linear) {
            GridArg::Linear => TimeGrid::linear(t_max, points),
            GridArg::Log => TimeGrid::log(self.t_min.unwrap_or(1e-4 * t_max), t_max, points),
        }
        .map_err(name)?;
        let opts = DistributionOptions {
            backward,
            rtol: self.rtol.unwrap_or(1e-4),
            atol: 1e-3 * self.rtol.unwrap_or(1e-4),
            ..DistributionOptions::default()
        };
        opts.validate().map_err(|e| match e {
            Error::InvalidParameter {
                name: "rtol",
                value,
                allowed,
            } => Error::InvalidParameter {
                name: "--rtol",
                value,
                allowed,
            },
            e => e,
        })?;
        // Time steps: measured 440-600 at rtol 1e-4 for 1000-16000 cells
        // (~ rtol^(-1/3)), more for t_max far beyond tau; each step three
        // band solves on both meshes (1.5 cells, 2 unknowns, ~40 operations
        // each). Memory: the bands, factors and stage vectors.
        let cells = backward.cells as f64;
        let steps = 800.0 * (1e-4 / opts.rtol).cbrt()
            + 1e3 * (1.0 + (t_max / tau.max(1e-300)).ln().max(0.0));
        // A noise model of N states: N unknowns per node, bandwidth N
        // (1 for the paper's two states).
        let states = match problem.params().noise() {
            Some(_) => problem.params().chain()?.states() as f64,
            None => 2.0,
        };
        let per_node = (0.5 * states).max(1.0);
        self.output.budget.check(
            &super::budget::Cost {
                work: steps * cells * 400.0 * per_node * per_node,
                unit: "cell updates",
                drivers: vec!["cells", "t_max", "rtol"],
                memory: 2.0 * cells * 8.0 * 40.0 * per_node + 64.0 * points as f64,
                memory_drivers: vec!["cells", "points"],
            }
            .per_drag_evaluation(&problem.params().drag()),
        )?;
        Ok(Kind::Backward(grid, opts))
    }

    fn exact_kind(&self, problem: &Problem, t_max: f64, tau: f64) -> irtp::Result<Kind> {
        let run = ParticleOptions {
            particles: self.particles.unwrap_or(100_000),
            t_max,
            seed: self.output.seed(),
        };
        // The histogram's halves are the ±Sigma starts for the paper's
        // noise; with a noise model (any finite-state noise at T = 0) two
        // independent halves of the particles started from π (Eq. (N47)).
        irtp::capability::check_noise(
            irtp::capability::Solver::FptDistributionExact,
            problem.params(),
        )?;
        let method = mfpt::Method::Exact(run);
        method.check(problem)?;
        let p = problem.params();
        let per = p.event_rate_bound() * tau.min(t_max) + 2.0;
        let mut drivers = vec!["particles", "lambda", "rate", "t_max"];
        drivers.extend(p.schedule().cost_drivers());
        let cost = super::budget::particles(run.particles, per, "particle events", drivers, 0, 0);
        self.output.budget.check(&cost)?;
        Ok(Kind::Exact(run))
    }
}

/// What `irtp mfpt distribution --json` prints.
#[derive(Serialize)]
struct Report<'a> {
    method: DistMethod,
    problem: &'a Problem,
    t_max: f64,
    #[serde(flatten)]
    moments: Moments,
    #[serde(flatten)]
    backward: Option<BackwardPart>,
    #[serde(flatten)]
    exact: Option<ExactPart>,
}

/// Moments of either method (the sampler's are means over the particles).
#[derive(Serialize)]
struct Moments {
    tau: f64,
    tau_plus: f64,
    tau_minus: f64,
    second_moment: f64,
    variance: f64,
    cv: f64,
    variance_plus: f64,
    variance_minus: f64,
    cv_plus: f64,
    cv_minus: f64,
}

#[derive(Serialize)]
struct BackwardPart {
    cells: usize,
    points: usize,
    rtol: f64,
    /// E(T) of the distribution (exact in time, extrapolated in the mesh).
    distribution_mean: f64,
    /// E(T²) likewise.
    distribution_second_moment: f64,
    /// ∫_0^t_end S dt: the mean of the time-dependent solution.
    mean_time_integral: f64,
    /// 2 ∫_0^t_end t S dt.
    second_moment_time_integral: f64,
    t_end: f64,
    tail_mass: f64,
    atom_time: f64,
    atom_mass: f64,
    /// max |S_fine - S_coarse| over the output times: the discretisation
    /// error of the finer of the two meshes extrapolated.
    mesh_error: f64,
    /// max |f_fine - f_coarse| outside the smeared window: the same for f.
    mesh_error_density: f64,
    /// Within atom_time ± 6 atom_spread f is smeared by the mesh.
    atom_spread: f64,
    steps: usize,
    rejected_steps: usize,
    /// With a noise model: one atom per state whose flow reaches v_t
    /// (`atom_time` is the earliest, `atom_mass` their π-weighted sum);
    /// absent for the paper's noise.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    atoms: Vec<irtp::mfpt::Atom>,
}

#[derive(Serialize)]
struct ExactPart {
    tau_err: f64,
    particles: u64,
    censored: u64,
    censored_fraction: f64,
    rmst: f64,
    rmst_err: f64,
    seed: u64,
}

/// Run `irtp mfpt distribution` for a search target in position:
/// `histogram.csv`, `survival.csv`, `distribution.json` (the report of
/// `irtp mfpt --xt/--interval`).
fn run_search(a: &DistributionArgs, ctx: &Context) -> irtp::Result<Outcome> {
    let c = match a.search_config()? {
        SearchDist::Particles(c) => c,
        SearchDist::Backward(b) => return run_search_backward(a, &b, ctx),
    };
    let out = open_out(
        "mfpt distribution",
        a.output.out.as_deref(),
        a.output.force.force,
    )?;
    let t0 = Instant::now();
    let (st, report) = search::solve(&c, ctx)?;
    let wall = t0.elapsed().as_secs_f64();
    let json = to_value(&report);
    let results = Results {
        method: c.method.name().into(),
        seed: Some(a.output.seed()),
        json: json.clone(),
        parameters: json.clone(),
        tables: vec![
            histogram_table(&st),
            super::mfpt::survival_table(&st.survival()),
        ],
        json_files: vec![("distribution.json", json.clone())],
        text: search::note(&report) + &super::mfpt::text_lines(&json),
        wall_time_s: wall,
    };
    finish("mfpt distribution", results, out, ctx)
}

/// What `irtp mfpt distribution --xt/--interval --method backward --json`
/// prints: the options (provenance) and the solution's summary.
#[derive(Serialize)]
struct SearchBackwardReport<'a> {
    method: &'static str,
    problem: &'a irtp::search::SearchProblem,
    options: &'a SearchDistOptions,
    /// ∫_0^t_max S dt = E[min(T, t_max)].
    restricted_mean: f64,
    /// S(t_max) and its error estimate.
    survival_t_max: f64,
    survival_t_max_err: f64,
    mesh_error: f64,
    time_error: f64,
    truncation_error: f64,
    mesh: irtp::search::backward::MeshInfo,
}

/// `distribution.csv` (t, survival, survival_err, density) and
/// `distribution.json` of a search's backward distribution.
fn run_search_backward(
    a: &DistributionArgs,
    c: &SearchBackward,
    ctx: &Context,
) -> irtp::Result<Outcome> {
    let out = open_out(
        "mfpt distribution",
        a.output.out.as_deref(),
        a.output.force.force,
    )?;
    let t0 = Instant::now();
    let d = {
        let _bar = ctx
            .reporter
            .stage("search distribution (backward equation)", 1);
        irtp::search::distribution::solve(&c.problem, &c.opts)?
    };
    ctx.check()?;
    let n = d.t.len() - 1;
    let report = SearchBackwardReport {
        method: "backward",
        problem: &c.problem,
        options: &c.opts,
        restricted_mean: d.restricted_mean,
        survival_t_max: d.survival[n],
        survival_t_max_err: d.survival_err[n],
        mesh_error: d.mesh_error,
        time_error: d.time_error,
        truncation_error: d.truncation_error,
        mesh: d.mesh,
    };
    let rows = (0..=n).map(|i| [d.t[i], d.survival[i], d.survival_err[i], d.density[i]]);
    let header = ["t", "survival", "survival_err", "density"];
    let json = to_value(&report);
    let results = Results {
        method: "backward-upwind 2-D (2-mesh, 2-step Richardson) + TR-BDF2".into(),
        seed: None,
        json: json.clone(),
        parameters: json.clone(),
        tables: vec![Table::from_rows("distribution", &header, rows)],
        json_files: vec![("distribution.json", json.clone())],
        text: super::mfpt::text_lines(&json),
        wall_time_s: t0.elapsed().as_secs_f64(),
    };
    finish("mfpt distribution", results, out, ctx)
}

/// Run `irtp mfpt distribution`.
pub fn run(a: &DistributionArgs, ctx: &Context) -> irtp::Result<Outcome> {
    if a.is_search() {
        return run_search(a, ctx);
    }
    a.refuse_search_mesh()?;
    let c = a.config()?;
    let out = open_out(
        "mfpt distribution",
        a.output.out.as_deref(),
        a.output.force.force,
    )?;
    let t0 = Instant::now();
    let (report, tables) = match &c.kind {
        Kind::Backward(grid, opts) => {
            let d = {
                let _bar = ctx.reporter.stage("mfpt distribution", 1);
                mfpt::distribution(&c.problem, grid.times(), opts)?
            };
            ctx.check()?;
            let table = distribution_table(&d)?;
            (backward_report(&c, opts, &d), vec![table])
        }
        Kind::Exact(run) => {
            let st = {
                let bar = ctx.reporter.stage("mfpt", run.particles);
                let method = mfpt::Method::Exact(*run);
                mfpt::solve(&c.problem, &method, bar.as_ref())?
            };
            ctx.check()?;
            let st = st.stats().expect("a particle method").clone();
            let tables = vec![
                histogram_table(&st),
                super::mfpt::survival_table(&st.survival()),
            ];
            (exact_report(&c, &st, run.seed), tables)
        }
    };
    let wall = t0.elapsed().as_secs_f64();
    let json = to_value(&report);
    let results = Results {
        method: match a.method {
            DistMethod::Backward => {
                "backward-upwind (atom exact, 2-mesh Richardson) + TR-BDF2".into()
            }
            DistMethod::Exact => "exact".into(),
        },
        seed: a.uses_seed().then_some(a.output.seed()),
        json: json.clone(),
        parameters: json.clone(),
        tables,
        json_files: vec![("distribution.json", json.clone())],
        text: super::mfpt::text_lines(&json),
        wall_time_s: wall,
    };
    finish("mfpt distribution", results, out, ctx)
}

fn backward_report<'a>(c: &'a Config, opts: &DistributionOptions, d: &Distribution) -> Report<'a> {
    let m = &d.moments;
    Report {
        method: DistMethod::Backward,
        problem: &c.problem,
        t_max: c.t_max,
        moments: Moments {
            tau: m.tau,
            tau_plus: m.tau_plus,
            tau_minus: m.tau_minus,
            second_moment: m.second,
            variance: m.variance,
            cv: m.cv,
            variance_plus: m.variance_plus,
            variance_minus: m.variance_minus,
            cv_plus: m.cv_plus,
            cv_minus: m.cv_minus,
        },
        backward: Some(BackwardPart {
            cells: m.cells,
            points: d.t.len(),
            rtol: opts.rtol,
            distribution_mean: d.mean,
            distribution_second_moment: d.second,
            mean_time_integral: d.mean_time_integral,
            second_moment_time_integral: d.second_time_integral,
            t_end: d.t_end,
            tail_mass: d.tail_mass,
            atom_time: d.atom_time,
            atom_mass: d.atom_mass,
            mesh_error: d.mesh_error,
            mesh_error_density: d.mesh_error_density,
            atom_spread: d.atom_spread,
            steps: d.steps,
            rejected_steps: d.rejected,
            atoms: d.atoms.clone(),
        }),
        exact: None,
    }
}

fn exact_report<'a>(c: &'a Config, st: &FptStats, seed: u64) -> Report<'a> {
    let s = st.summary();
    // E[T²] per start state from the sums of squares (NaN when censored).
    let m2 = |acc: &irtp::stats::MeanAcc, censored: u64| {
        if censored == 0 {
            acc.sum_sq / acc.n as f64
        } else {
            f64::NAN
        }
    };
    let (qp, qm) = (
        m2(&st.arrived[0], st.censored_in[0]),
        m2(&st.arrived[1], st.censored_in[1]),
    );
    let second = 0.5 * (qp + qm);
    let variance = second - s.tau * s.tau;
    let (vp, vm) = (qp - s.tau_plus * s.tau_plus, qm - s.tau_minus * s.tau_minus);
    Report {
        method: DistMethod::Exact,
        problem: &c.problem,
        t_max: c.t_max,
        moments: Moments {
            tau: s.tau,
            tau_plus: s.tau_plus,
            tau_minus: s.tau_minus,
            second_moment: second,
            variance,
            cv: variance.sqrt() / s.tau,
            variance_plus: vp,
            variance_minus: vm,
            cv_plus: vp.sqrt() / s.tau_plus,
            cv_minus: vm.sqrt() / s.tau_minus,
        },
        backward: None,
        exact: Some(ExactPart {
            tau_err: s.tau_err,
            particles: s.particles,
            censored: s.censored,
            censored_fraction: s.censored_fraction,
            rmst: s.rmst,
            rmst_err: s.rmst_err,
            seed,
        }),
    }
}

/// `distribution.csv`: S and f (mixture, +, -) at the output times.
fn distribution_table(d: &Distribution) -> irtp::Result<Table> {
    let rows = (0..d.t.len()).map(|i| {
        [
            d.t[i],
            d.survival[i],
            d.density[i],
            d.survival_plus[i],
            d.density_plus[i],
            d.survival_minus[i],
            d.density_minus[i],
        ]
    });
    let header = [
        "t",
        "survival",
        "density",
        "survival_plus",
        "density_plus",
        "survival_minus",
        "density_minus",
    ];
    Ok(Table::from_rows("distribution", &header, rows))
}

/// `histogram.csv`: the sampled first-passage-time density of the mixture
/// per bin (t_lo, t_hi], (count+/N+ + count-/N-)/2/width, with its binomial
/// standard error; bins of the fixed log grid up to t_max (empty leading
/// bins left out).
fn histogram_table(st: &FptStats) -> Table {
    let e = edges(st.t_max);
    let n_plus = (st.particles_in(0)) as f64;
    let n_minus = (st.particles_in(1)) as f64;
    let first = (0..=e.len())
        .find(|&j| st.arrivals.counts[0][j] + st.arrivals.counts[1][j] > 0)
        .unwrap_or(e.len());
    let rows = (first..=e.len()).map(|j| {
        let lo = if j == 0 { 0.0 } else { e[j - 1] };
        let hi = if j < e.len() { e[j] } else { st.t_max };
        let (cp, cm) = (
            st.arrivals.counts[0][j] as f64,
            st.arrivals.counts[1][j] as f64,
        );
        let (pp, pm) = (cp / n_plus, cm / n_minus);
        let var = pp * (1.0 - pp) / n_plus + pm * (1.0 - pm) / n_minus;
        let w = hi - lo;
        [lo, hi, 0.5 * (pp + pm) / w, 0.5 * var.sqrt() / w, cp + cm]
    });
    let header = ["t_lo", "t_hi", "density", "density_err", "count"];
    Table::from_rows("histogram", &header, rows)
}
