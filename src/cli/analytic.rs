//! `irtp analytic`: exact r = 0 stationary density, its regime and moments.

use super::common::NoiseArgs;
use clap::Args;
use irtp::analytic::r0::{EdgeBehaviour, Extremum, Normalisation, R0Density};
use irtp::io::{OutputDir, Provenance};
use irtp::numerics::grid::chebyshev;
use irtp::{DragLaw, Error, Params};
use serde::Serialize;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Flags of `irtp analytic`: the shared `--drag --sigma --lambda`, and its own
/// `--rate` (default 0, the only admissible value) instead of the resetting flags.
#[derive(Args, Debug, Clone)]
#[command(mut_arg("lambda", |a| a.help("Flip rate lambda of the telegraph noise (> 0)")))]
pub struct AnalyticArgs {
    /// `--drag --sigma --lambda`.
    #[command(flatten)]
    pub noise: NoiseArgs,
    /// Reset rate: the closed form exists only for r = 0 (any other value is rejected).
    #[arg(long, short = 'r', default_value_t = 0.0, allow_hyphen_values = true)]
    pub rate: f64,
    /// Number of points of density.csv (interior Chebyshev points, clustered at the edges).
    #[arg(long, default_value_t = 1001, allow_hyphen_values = true)]
    pub points: usize,
    /// Directory to write density.csv and run.json into.
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Print one JSON object with the results on stdout.
    #[arg(long)]
    pub json: bool,
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
struct Config {
    params: Params,
    points: usize,
}

impl AnalyticArgs {
    /// Flags → validated config (the closed form exists only for r = 0).
    fn config(&self) -> irtp::Result<Config> {
        let params = self.noise.params(self.rate, 0.0)?;
        if self.points < 2 {
            return Err(Error::invalid("--points", self.points, "points >= 2"));
        }
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

/// density.csv (Chebyshev points: interior, clustered toward the possibly
/// singular edges), summary.json and run.json.
fn write(dir: &Path, c: &Config, d: &R0Density, report: &Report, t0: Instant) -> irtp::Result<()> {
    let mut out = OutputDir::new(dir)?;
    let (vl, vu) = d.bounds();
    let rows: Vec<[f64; 3]> = chebyshev(vl, vu, c.points)
        .into_iter()
        .map(|v| [v, d.pdf(v), d.cdf(v)])
        .collect();
    out.write_csv("density.csv", &["v", "p", "cdf"], rows)?;
    out.write_json("summary.json", report)?;
    let run = RunParams {
        drag: report.drag,
        sigma: report.sigma,
        lambda: report.lambda,
        rate: report.rate,
        points: c.points,
    };
    out.commit_with_provenance(Provenance::new(
        "analytic",
        "exact r=0 density; adaptive Gauss-Kronrod normalisation",
        None,
        run,
        t0.elapsed().as_secs_f64(),
    ))?;
    Ok(())
}

/// Run `irtp analytic`.
pub fn run(args: AnalyticArgs) -> anyhow::Result<()> {
    let t0 = Instant::now();
    let c = args.config()?;
    let d = R0Density::from_params(&c.params)?;
    let report = report(&c.params, &d);
    if let Some(dir) = &args.out {
        write(dir, &c, &d, &report, t0)?;
    }
    if args.json {
        super::print_json(&report)?;
    } else {
        let (drag, sigma, lambda) = (report.drag, report.sigma, report.lambda);
        let (vl, vu) = (report.v_lower, report.v_upper);
        println!("{drag} drag, Sigma = {sigma}, lambda = {lambda}, r = 0: v in ({vl:.6}, {vu:.6})");
        println!("regime {}", report.regime_description);
        println!("<v^2> = {:.15e}   <v^4> = {:.15e}", report.v2, report.v4);
        if let Some(dir) = &args.out {
            println!("wrote {}", dir.display());
        }
    }
    Ok(())
}
