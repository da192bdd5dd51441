//! `irtp analytic`: exact r = 0 stationary density, its regime and moments;
//! with `--noise`/`--temperature` the closed forms of another noise model
//! (docs/equations.md, "Noise kinds"): linear drag's `<v>`, `<v²>`, drift
//! and D_eff (Eqs. (N3)-(N6), any noise, r ≥ 0), and the r = 0 density of
//! an asymmetric telegraph noise (Eq. (N8), any drag).

use super::common::NoiseArgs;
use super::format::{fmt_digits, fmt_sig};
use super::{finish, open_out, to_value, Context, Outcome, Results, Table};
use clap::Args;
use irtp::analytic::r0::{EdgeBehaviour, Extremum, Normalisation, R0Density};
use irtp::numerics::grid::chebyshev;
use irtp::{DragLaw, Error, Params};
use serde::Serialize;
use std::path::PathBuf;
use std::time::Instant;

/// Flags of `irtp analytic`: the shared `--drag --sigma --lambda`, and its own
/// `--rate` (default 0, the only admissible value but with linear drag) and
/// `--reset-velocity` instead of the resetting flags.
#[derive(Args, Debug, Clone)]
#[command(mut_arg("lambda", |a| a.help("Flip rate lambda of the telegraph noise (> 0)")))]
pub struct AnalyticArgs {
    /// `--drag --sigma --lambda`.
    #[command(flatten)]
    pub noise: NoiseArgs,
    /// Reset rate r: 0, or any r with linear drag.
    ///
    /// The closed-form density exists only without resetting; with linear
    /// drag the moments have closed forms at any r, with any noise and
    /// temperature (Eqs. (N3)-(N6)).
    #[arg(long, short = 'r', default_value_t = 0.0, allow_hyphen_values = true)]
    pub rate: f64,
    /// Reset velocity v_r of the Poisson resetting, only with linear drag
    /// (with another drag only 0, as nothing resets at r = 0) [default: 0].
    #[arg(long, allow_hyphen_values = true)]
    pub reset_velocity: Option<f64>,
    /// Number of points of density.csv (interior Chebyshev points, clustered at the edges).
    #[arg(long, default_value_t = 1001, allow_hyphen_values = true, value_parser = super::common::parse_size)]
    pub points: usize,
    /// Directory to write density.csv and run.json into.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// `--force`.
    #[command(flatten)]
    pub force: super::common::ForceArgs,
    /// Print one JSON object with the results on stdout.
    #[arg(long)]
    pub json: bool,
    /// `--max-work --max-memory`.
    #[command(flatten)]
    pub budget: super::budget::BudgetArgs,
}

#[derive(Serialize)]
struct Report {
    drag: DragLaw,
    sigma: f64,
    lambda: f64,
    rate: f64,
    v_lower: f64,
    v_upper: f64,
    v2: f64,
    v4: f64,
    regime: String,
    regime_description: String,
    edge_exponent: f64,
    edge: EdgeBehaviour,
    extrema: Vec<Extremum>,
    normalisation: Normalisation,
}

#[derive(Serialize)]
struct RunParams {
    drag: DragLaw,
    sigma: f64,
    lambda: f64,
    rate: f64,
    points: usize,
}

/// The validated inputs of `irtp analytic`.
pub(crate) struct Config {
    params: Params,
    points: usize,
}

impl AnalyticArgs {
    /// Flags → validated config (the closed form exists only for r = 0).
    pub(crate) fn config(&self) -> irtp::Result<Config> {
        let params = self
            .noise
            .params(self.rate, self.reset_velocity.unwrap_or(0.0))?;
        // The paper's noise with another drag has its closed form at r = 0
        // only, where nothing resets: v_r other than 0 would be ignored.
        let linear = matches!(params.drag(), DragLaw::Linear);
        if let (None, Some(v), false) = (params.noise(), self.reset_velocity, linear) {
            if v != 0.0 {
                return Err(Error::invalid(
                    "reset_velocity",
                    v,
                    "0 (or none) with the paper's noise and this drag (its closed form is at \
                     r = 0); another reset velocity with linear drag",
                ));
            }
        }
        if self.points < 2 {
            return Err(Error::invalid("--points", self.points, "points >= 2"));
        }
        // About 100 operations and 64 bytes per density point (measured:
        // 4.5 µs and 37 MB for 1e6 points).
        let cost = super::budget::mesh(self.points, 100.0, 64.0, vec!["points"]);
        self.budget.check(
            &super::budget::Cost {
                memory_drivers: vec!["points"],
                ..cost
            }
            .per_drag_evaluation(&params.drag()),
        )?;
        Ok(Config {
            params,
            points: self.points,
        })
    }
}

fn report(params: &Params, d: &R0Density) -> Report {
    let reg = d.regime();
    let (v_lower, v_upper) = d.bounds();
    Report {
        drag: params.drag(),
        sigma: params.sigma(),
        lambda: params.lambda(),
        rate: params.rate(),
        v_lower,
        v_upper,
        v2: d.v2(),
        v4: d.moment(4),
        regime: reg.label.clone(),
        regime_description: reg.description.clone(),
        edge_exponent: reg.edge_exponent,
        edge: reg.edge,
        extrema: reg.extrema.clone(),
        normalisation: d.normalisation(),
    }
}

/// Run `irtp analytic`: the density at `--points` Chebyshev points
/// (interior, clustered toward the possibly singular edges) as
/// `density.csv`, the report as `summary.json`, and `run.json`.
pub fn run(args: &AnalyticArgs, ctx: &Context) -> irtp::Result<Outcome> {
    let t0 = Instant::now();
    let c = args.config()?;
    // Linear drag with resetting: the closed forms of any noise (N3)-(N6),
    // the paper's included.
    let linear_reset = matches!(c.params.drag(), DragLaw::Linear)
        && (c.params.rate() != 0.0 || args.reset_velocity.is_some_and(|v| v != 0.0));
    if c.params.noise().is_some() || linear_reset {
        return super::analytic_noise::run(args, &c.params, c.points, ctx, t0);
    }
    let out = open_out("analytic", args.out.as_deref(), args.force.force)?;
    let d = R0Density::from_params(&c.params)?;
    let report = report(&c.params, &d);
    if !(report.v2.is_finite() && report.v4.is_finite()) {
        return Err(Error::Overflow {
            method: "analytic",
            quantity: "<v^4>",
            meaning:
                "the velocity bound v_u is too large (v_u^4 beyond ~1e308); use a smaller sigma",
        });
    }
    let (vl, vu) = d.bounds();
    let rows = chebyshev(vl, vu, c.points)
        .into_iter()
        .map(|v| [v, d.pdf(v), d.cdf(v)]);
    let density = Table::from_rows("density", &["v", "p", "cdf"], rows);
    let run = RunParams {
        drag: report.drag.clone(),
        sigma: report.sigma,
        lambda: report.lambda,
        rate: report.rate,
        points: c.points,
    };
    let json = to_value(&report);
    let results = Results {
        method: "exact r=0 density; adaptive Gauss-Kronrod normalisation".into(),
        seed: None,
        json,
        parameters: to_value(&run),
        tables: vec![density],
        json_files: Vec::new(),
        text: text_report(&report),
        wall_time_s: t0.elapsed().as_secs_f64(),
    };
    finish("analytic", results, out, ctx)
}

fn text_report(report: &Report) -> String {
    let f = fmt_sig;
    format!(
        "{} drag, Sigma = {}, lambda = {}, r = 0: v in ({}, {})\n\
         regime {}\n<v^2> = {}   <v^4> = {}\n",
        report.drag,
        f(report.sigma),
        f(report.lambda),
        f(report.v_lower),
        f(report.v_upper),
        report.regime_description,
        fmt_digits(report.v2, 15),
        fmt_digits(report.v4, 15)
    )
}
