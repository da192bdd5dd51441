//! `irtp simulate`: particle simulation of the IRTP with resetting.

use super::common::{ModelArgs, OutputArgs};
use super::format::{fmt_pm, fmt_sig};
use super::{finish, open_out, to_value, Context, Outcome, Results, Table};
use clap::{Args, ValueEnum};
use irtp::sim::euler::{EulerPlan, EventSampling};
use irtp::sim::{Observables, PositionHistogram, SimSpec, SimSummary, TimeGrid};
use irtp::Params;
use serde::Serialize;
use std::time::Instant;

/// Simulation method.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum MethodArg {
    /// Exact event-driven sampler: no time step, no discretisation bias.
    Exact,
    /// Euler scheme of the paper (Eqs. (30)-(32)).
    Euler,
}

/// Time grid kind for the moments.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum GridArg {
    /// Equally spaced from 0 to t_max.
    Linear,
    /// t = 0, then log-spaced from --t-min to t_max.
    Log,
}

/// Event sampler of the Euler scheme.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum EventsArg {
    /// Geometric waiting times between resets / flips (fast, same law).
    Geometric,
    /// Two uniform draws per step, literally as in the paper.
    Bernoulli,
}

/// Simulate N independent particles; write moments.csv, density.csv, run.json.
#[derive(Args, Debug)]
pub struct SimulateArgs {
    #[command(flatten)]
    pub model: ModelArgs,
    #[command(flatten)]
    pub output: OutputArgs,
    /// Number of independent particles.
    #[arg(long, default_value_t = 20_000, allow_hyphen_values = true, value_parser = super::common::parse_count)]
    pub particles: u64,
    /// Euler time step (must be < 1/max g'(v) and < 1/rate) [default with
    /// --method euler: 1e-3; not accepted by the exact method, which has no step].
    #[arg(long, allow_hyphen_values = true)]
    pub dt: Option<f64>,
    /// Final time.
    #[arg(long, default_value_t = 20.0, allow_hyphen_values = true)]
    pub t_max: f64,
    /// Number of recording times for the moments.
    #[arg(long, default_value_t = 201, allow_hyphen_values = true, value_parser = super::common::parse_size)]
    pub samples: usize,
    /// Recording grid.
    #[arg(long, value_enum, default_value_t = GridArg::Linear)]
    pub grid: GridArg,
    /// First non-zero time of a log grid.
    #[arg(long, default_value_t = 1e-2, allow_hyphen_values = true)]
    pub t_min: f64,
    /// Start of the stationary averaging window [burn_in, t_max].
    #[arg(long, default_value_t = 10.0, allow_hyphen_values = true)]
    pub burn_in: f64,
    /// Histogram bins on (v_l, v_u).
    #[arg(long, default_value_t = 100, allow_hyphen_values = true, value_parser = super::common::parse_size)]
    pub bins: usize,
    /// Simulation method.
    #[arg(long, value_enum, default_value_t = MethodArg::Exact)]
    pub method: MethodArg,
    /// How the Euler scheme draws resets and flips (same law either way)
    /// [default with --method euler: geometric].
    #[arg(long, value_enum)]
    pub events: Option<EventsArg>,
}

#[derive(Serialize)]
struct RunParameters<'a> {
    model: &'a Params,
    particles: u64,
    dt: Option<f64>,
    t_max: f64,
    samples: usize,
    grid: GridArg,
    t_min: Option<f64>,
    burn_in: f64,
    bins: usize,
    events: Option<EventSampling>,
    seed: u64,
    steps_per_particle: Option<u64>,
}

/// The `results` of `irtp simulate`: both methods have the same keys, a
/// count of work is `steps` (Euler time steps, summed over particles) or
/// `events` (the exact sampler's flips, resets and recording stops), the
/// other `null`.
#[derive(Serialize)]
struct JsonOut<'a> {
    method: &'a str,
    /// The Euler scheme's event sampler (`--events`).
    event_sampling: Option<EventSampling>,
    dt: Option<f64>,
    #[serde(flatten)]
    summary: SimSummary,
    events: Option<u64>,
    wall_time_s: f64,
    particle_steps_per_s: Option<f64>,
    events_per_s: Option<f64>,
    out: Option<String>,
}

impl JsonOut<'_> {
    /// The summary with its count of work under its name: `steps` for
    /// Euler, `events` for the exact sampler.
    fn to_value(&self) -> serde_json::Value {
        let mut v = to_value(self);
        if self.events.is_some() {
            v["steps"] = serde_json::Value::Null;
        }
        v
    }
}

/// The Euler scheme's setup: step, event sampler and step plan.
struct EulerSetup {
    dt: f64,
    events: EventSampling,
    plan: EulerPlan,
}

/// The validated inputs of `irtp simulate`.
pub(crate) struct Config {
    params: Params,
    spec: SimSpec,
    /// `None`: the exact sampler.
    euler: Option<EulerSetup>,
}

impl Config {
    fn method(&self) -> &'static str {
        match self.euler {
            Some(_) => "euler",
            None => "exact",
        }
    }
    fn dt(&self) -> Option<f64> {
        self.euler.as_ref().map(|e| e.dt)
    }
    /// The core's method for this run.
    fn sim_method(&self) -> irtp::sim::Method {
        match &self.euler {
            Some(e) => irtp::sim::Method::Euler {
                dt: e.dt,
                events: e.events,
            },
            None => irtp::sim::Method::Exact,
        }
    }

    fn events(&self) -> Option<EventSampling> {
        self.euler.as_ref().map(|e| e.events)
    }
}

impl SimulateArgs {
    /// Flags → validated config, before anything touches the file system.
    pub(crate) fn config(&self) -> irtp::Result<Config> {
        let params = self.model.params()?;
        self.output.budget.check(&self.cost(&params)?)?;
        let grid = match self.grid {
            GridArg::Linear => TimeGrid::linear(self.t_max, self.samples)?,
            GridArg::Log => TimeGrid::log(self.t_min, self.t_max, self.samples)?,
        };
        let spec = SimSpec::new(
            self.particles,
            grid,
            self.burn_in,
            self.bins,
            self.output.seed(),
        )?;
        let euler = match self.method {
            MethodArg::Euler => Some(self.euler_setup(&params, &spec)?),
            MethodArg::Exact => {
                self.reject_euler_flags()?;
                None
            }
        };
        Ok(Config {
            params,
            spec,
            euler,
        })
    }

    /// Work and memory, from the flags before anything is allocated: Euler
    /// steps, or exact-sampler events (flips, resets and the ends of
    /// refractory periods, [`Params::event_rate_bound`]: a noise model's
    /// fastest state,
    /// plus one flow evaluation per recording time).
    fn cost(&self, p: &Params) -> irtp::Result<super::budget::Cost> {
        let t_max = irtp::error::finite("t_max", self.t_max)?;
        let samples = self.samples as f64;
        // Each particle also sweeps its histogram once (occupation times).
        let bins = self.bins as f64;
        let (per, unit, mut drivers) = match self.method {
            MethodArg::Euler => (
                t_max / self.dt.unwrap_or(1e-3) + samples + bins,
                "Euler particle steps",
                vec!["particles", "t_max", "dt", "bins"],
            ),
            MethodArg::Exact => (
                p.event_rate_bound() * t_max + samples + bins + 1.0,
                "particle events",
                vec![
                    "particles",
                    if p.noise().is_some() {
                        "noise"
                    } else {
                        "lambda"
                    },
                    "rate",
                    "t_max",
                    "samples",
                    "bins",
                ],
            ),
        };
        // A step refused by validation (dt <= 0, NaN) gives a meaningless
        // estimate: leave the refusal to the check that names it. An
        // infinite estimate from valid flags (lambda + r overflowing) stays.
        drivers.extend(p.schedule().cost_drivers());
        let bad_dt = self.method == MethodArg::Euler && !(self.dt.unwrap_or(1e-3) > 0.0);
        let per = if bad_dt || per.is_nan() || per < 0.0 {
            0.0
        } else {
            per
        };
        let cost =
            super::budget::particles(self.particles, per, unit, drivers, self.samples, self.bins);
        Ok(match self.method {
            MethodArg::Euler => cost.per_drag_evaluation(&p.drag()),
            // The exact sampler reads the law's flows from tables built once.
            MethodArg::Exact => cost,
        })
    }

    fn euler_setup(&self, params: &Params, spec: &SimSpec) -> irtp::Result<EulerSetup> {
        let dt = self.dt.unwrap_or(1e-3);
        let plan = EulerPlan::new(params, spec, dt)?;
        let events = match self.events.unwrap_or(EventsArg::Geometric) {
            EventsArg::Geometric => EventSampling::Geometric,
            EventsArg::Bernoulli => EventSampling::Bernoulli,
        };
        Ok(EulerSetup { dt, events, plan })
    }

    /// The exact sampler takes neither `--dt` nor `--events`.
    fn reject_euler_flags(&self) -> irtp::Result<()> {
        if let Some(dt) = self.dt {
            return Err(irtp::Error::invalid(
                "--dt",
                dt,
                "only with --method euler (the exact sampler has no time step)",
            ));
        }
        if let Some(e) = self.events {
            return Err(irtp::Error::invalid(
                "--events",
                format!("{e:?}").to_lowercase(),
                "only with --method euler (the exact sampler draws exact event times)",
            ));
        }
        Ok(())
    }
}

/// Run `irtp simulate`: validate, simulate, write `moments.csv`,
/// `density.csv` and `run.json` when `--out` is given.
pub fn run(a: &SimulateArgs, ctx: &Context) -> irtp::Result<Outcome> {
    let c = a.config()?;
    let out = open_out("simulate", a.output.out.as_deref(), a.output.force.force)?;
    let start = Instant::now();
    let obs = {
        let bar = ctx.reporter.stage("simulate", c.spec.particles);
        irtp::sim::simulate(&c.params, &c.spec, c.sim_method(), bar.as_ref())?
    };
    report(a, &c, &obs, start.elapsed().as_secs_f64(), out, ctx)
}

/// Every sampled velocity lies in (v_l, v_u), so every mean of v² lies in
/// [0, v_u²] (to rounding): a simulation that breaks this has lost
/// precision (tanh within 1e-12 of its limit Sigma = 1) and is refused.
fn check_invariants(c: &Config, obs: &Observables) -> irtp::Result<()> {
    let (lo, hi) = c.params.bounds();
    let top = lo.abs().max(hi.abs()).powi(2) * (1.0 + 1e-9);
    let means = obs.v2.iter().chain(std::iter::once(&obs.v2_time_avg));
    for (k, m) in means.enumerate() {
        let v2 = m.mean();
        // A non-finite mean is the overflow refusal of `finish`, with its own message.
        if m.n > 0 && v2.is_finite() && !(v2 >= 0.0 && v2 <= top) {
            return Err(irtp::Error::Numerical {
                method: "simulate",
                reason: format!(
                    "a mean of v² is {v2:e} (record {k}), outside [0, v_u² = {top:e}]: the \
                     sampler lost precision for these parameters; refused"
                ),
            });
        }
    }
    Ok(())
}

/// The outcome of a simulation's observables: JSON, tables, text, files.
fn report(
    a: &SimulateArgs,
    c: &Config,
    obs: &Observables,
    wall: f64,
    out: Option<crate::io::OutputDir>,
    ctx: &Context,
) -> irtp::Result<Outcome> {
    ctx.check()?;
    check_invariants(c, obs)?;
    let summary = obs.summary();
    let rate = summary.steps as f64 / wall;
    let exact = c.euler.is_none();
    let json = JsonOut {
        method: c.method(),
        event_sampling: c.events(),
        dt: c.dt(),
        summary: summary.clone(),
        events: exact.then_some(summary.steps),
        wall_time_s: wall,
        particle_steps_per_s: (!exact).then_some(rate),
        events_per_s: exact.then_some(rate),
        out: out.as_ref().map(|o| o.target().display().to_string()),
    };
    let mut tables = vec![
        Table::from_rows("moments", &Observables::MOMENT_HEADER, obs.moment_rows()),
        Table::from_rows("density", &Observables::DENSITY_HEADER, obs.density_rows()),
    ];
    if let Some(h) = &obs.position {
        tables.push(Table::from_rows(
            "position",
            &PositionHistogram::HEADER,
            h.rows(),
        ));
    }
    let results = Results {
        method: c.method().to_string(),
        seed: Some(c.spec.seed),
        json: json.to_value(),
        parameters: to_value(&run_parameters(a, c)),
        tables,
        json_files: Vec::new(),
        text: text_report(a, c, &summary, wall),
        wall_time_s: wall,
    };
    finish("simulate", results, out, ctx)
}

/// A simulation in parts: the run `a` describes, cut into `parts`
/// contiguous ranges of particle units ([`irtp::sim::simulate_units`]),
/// each computable anywhere; [`Parts::assemble`] of all parts' unit totals
/// gives [`run`]'s outcome, bit for bit.
pub struct Parts<'a> {
    args: &'a SimulateArgs,
    config: Config,
    method: irtp::sim::Method,
    /// Number of parts.
    pub parts: u64,
}

impl<'a> Parts<'a> {
    /// `parts` parts of the run `a` (at least one unit of particles each).
    pub fn new(a: &'a SimulateArgs, parts: u64) -> irtp::Result<Parts<'a>> {
        let config = a.config()?;
        let method = config.sim_method();
        let units = irtp::sim::unit_count(config.spec.particles);
        if !(parts >= 1 && parts <= units) {
            return Err(irtp::Error::invalid(
                "particle_parts",
                parts,
                format!(
                    "1 ..= {units} for {} particles (parts of whole {}-particle units)",
                    config.spec.particles,
                    irtp::parallel::UNIT
                ),
            ));
        }
        Ok(Parts {
            args: a,
            config,
            method,
            parts,
        })
    }

    /// The unit totals of part `k` (0-based).
    pub fn compute(&self, k: u64, ctx: &Context) -> irtp::Result<Vec<Observables>> {
        let units = irtp::sim::unit_count(self.config.spec.particles);
        let range = k * units / self.parts..(k + 1) * units / self.parts;
        let c = &self.config;
        let bar = ctx.reporter.stage("simulate part", c.spec.particles);
        let r = irtp::sim::simulate_units(&c.params, &c.spec, self.method, range, bar.as_ref())?;
        ctx.check()?;
        Ok(r)
    }

    /// The outcome of the whole run from every part's unit totals (in part
    /// order) and the parts' summed wall time: written to `--out` as [`run`] would.
    pub fn assemble(
        &self,
        units: &[Observables],
        wall: f64,
        ctx: &Context,
    ) -> irtp::Result<Outcome> {
        let c = &self.config;
        let out = open_out(
            "simulate",
            self.args.output.out.as_deref(),
            self.args.output.force.force,
        )?;
        let obs = irtp::sim::combine_units(&c.params, &c.spec, self.method, units)?;
        report(self.args, c, &obs, wall, out, ctx)
    }
}

/// The `parameters` object of `run.json`.
fn run_parameters<'a>(a: &SimulateArgs, c: &'a Config) -> RunParameters<'a> {
    RunParameters {
        model: &c.params,
        particles: c.spec.particles,
        dt: c.dt(),
        t_max: c.spec.grid.t_max(),
        samples: a.samples,
        grid: a.grid,
        t_min: (a.grid == GridArg::Log).then_some(a.t_min),
        burn_in: a.burn_in,
        bins: a.bins,
        events: c.events(),
        seed: c.spec.seed,
        steps_per_particle: c.euler.as_ref().map(|e| e.plan.steps),
    }
}

/// The text-mode report (numbers to their significant digits).
fn text_report(a: &SimulateArgs, c: &Config, s: &SimSummary, wall: f64) -> String {
    let p = &c.params;
    let rate = fmt_sig(s.steps as f64 / wall);
    let noise = match p.noise() {
        Some(m) => format!("noise {}, T = {}", m.spec(), fmt_sig(m.temperature())),
        None => format!(
            "sigma = {}, lambda = {}",
            fmt_sig(p.sigma()),
            fmt_sig(p.lambda())
        ),
    };
    let model = format!(
        "{} drag, {noise}, r = {}, v_r = {}",
        p.drag(),
        fmt_sig(p.rate()),
        fmt_sig(p.reset_velocity())
    ) + &p
        .reset_spec()
        .map_or(String::new(), |s| format!(", reset {s}"))
        + &p.schedule()
            .features()
            .iter()
            .map(|f| format!(", {} {}", f.flag(), p.schedule().spec_of(*f)))
            .collect::<String>();
    let (burn_in, t_max) = (fmt_sig(a.burn_in), fmt_sig(s.t_max));
    let mut text = match &c.euler {
        Some(e) => format!(
            "euler ({} event sampling), {model}: {} particles x {} steps of dt = {} in {wall:.2} s ({rate} particle-steps/s)\n",
            format!("{:?}", e.events).to_lowercase(),
            s.particles,
            e.plan.steps,
            fmt_sig(e.dt)
        ),
        None => format!(
            "exact (event-driven, no time step), {model}: {} particles, {} events in {wall:.2} s ({rate} events/s)\n",
            s.particles, s.steps
        ),
    };
    text += &format!(
        "stationary <v^2> = {}, <v> = {} (time average over [{burn_in}, {t_max}])\n",
        fmt_pm(s.v2, s.v2_err),
        fmt_pm(s.v_mean, s.v_mean_err)
    );
    text += &format!(
        "at t = {t_max}: <v^2> = {}, <x^2> = {}\n",
        fmt_pm(s.v2_final, s.v2_final_err),
        fmt_pm(s.x2_final, s.x2_final_err)
    );
    if !s.atoms.is_empty() {
        text += &format!(
            "point mass of the stationary law (not in density.csv): {}\n",
            super::fp::atoms_text(&s.atoms).trim_start()
        );
    }
    if let (Some([lo, hi]), Some(out), Some(err)) = (s.x_range, s.x_outside, s.x_outside_err) {
        text += &format!(
            "position resetting: P_s(x) at t = {t_max} on [{}, {}] (position.csv), mass outside {}; <x> = {}\n",
            fmt_sig(lo),
            fmt_sig(hi),
            fmt_pm(out, err),
            fmt_pm(s.x_final, s.x_final_err)
        );
    }
    if let (Some(d), Some(e)) = (s.d_eff_msd, s.d_eff_msd_err) {
        text += &format!(
            "Eq. (36) fit <x^2> = 2 D t + c over [{burn_in}, {t_max}]: D = {}\n",
            fmt_pm(d, e)
        );
    }
    text
}
