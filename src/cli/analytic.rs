//! `irtp analytic`: exact r = 0 stationary density, its regime and moments.

use super::common::NoiseArgs;
use clap::Args;
use irtp::analytic::r0::{EdgeBehaviour, Extremum, Normalisation, R0Density};
use irtp::io::{OutputDir, Provenance};
use irtp::{DragLaw, Error};
use serde::Serialize;
use std::path::PathBuf;

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

/// Chebyshev points of the first kind on (v_l, v_u), ascending: interior, and
/// clustered toward the (possibly singular) edges.
fn grid(vu: f64, n: usize) -> Vec<f64> {
    (0..n)
        .map(|i| -vu * (std::f64::consts::PI * (i as f64 + 0.5) / n as f64).cos())
        .collect()
}

/// Run `irtp analytic`.
pub fn run(args: AnalyticArgs) -> anyhow::Result<()> {
    let t0 = std::time::Instant::now();
    let params = args.noise.params(args.rate, 0.0)?;
    if args.points < 2 {
        return Err(Error::invalid("--points", args.points, "points >= 2").into());
    }
    let d = R0Density::from_params(&params)?;
    let reg = d.regime();
    let (vl, vu) = d.bounds();
    let NoiseArgs {
        drag,
        sigma,
        lambda,
    } = args.noise;
    let report = Report {
        drag,
        sigma,
        lambda,
        rate: args.rate,
        v_lower: vl,
        v_upper: vu,
        v2: d.v2(),
        v4: d.moment(4),
        regime: reg.label.clone(),
        regime_description: reg.description.clone(),
        edge_exponent: reg.edge_exponent,
        edge: reg.edge,
        extrema: reg.extrema.clone(),
        normalisation: d.normalisation(),
    };
    if let Some(dir) = &args.out {
        let mut out = OutputDir::new(dir)?;
        let rows: Vec<[f64; 3]> = grid(vu, args.points)
            .into_iter()
            .map(|v| [v, d.pdf(v), d.cdf(v)])
            .collect();
        out.write_csv("density.csv", &["v", "p", "cdf"], rows)?;
        out.write_json("summary.json", &report)?;
        let run = RunParams {
            drag,
            sigma,
            lambda,
            rate: args.rate,
            points: args.points,
        };
        out.commit_with_provenance(Provenance::new(
            "analytic",
            "exact r=0 density; adaptive Gauss-Kronrod normalisation",
            None,
            run,
            t0.elapsed().as_secs_f64(),
        ))?;
    }
    if args.json {
        super::print_json(&report)?;
    } else {
        println!("{drag} drag, Sigma = {sigma}, lambda = {lambda}, r = 0: v in ({vl:.6}, {vu:.6})");
        println!("regime {}", reg.description);
        println!("<v^2> = {:.15e}   <v^4> = {:.15e}", report.v2, report.v4);
        if let Some(dir) = &args.out {
            println!("wrote {}", dir.display());
        }
    }
    Ok(())
}
