//! Fig. 1: mean-squared velocity <v²>(t) at lambda = 0.5 for several r;
//! (a) tan, Sigma = 3; (b) tanh, Sigma = 0.6. Points: particle simulation
//! (all particles start at v = 0, x = 0, eta = ±Sigma equally likely);
//! solid lines: stationary <v²> from the Fokker-Planck density (paper Eq. (33));
//! dashed lines: <v²>(t) from the time-dependent FP equations (paper's method).

use super::compute::{self, Moments};
use super::plot::{fmt_count, Axis, Color, Dash, Figure, Key, Panel, Series};
use super::{
    curve_seed, fmt_num, grid_of_curves, to_json, Claim, FigureOutput, Options, Parameters,
    Verdict, Which,
};
use irtp::error::Result;
use irtp::model::{Drag, DragLaw, Params};
use irtp::parallel::Progress;
use irtp::sim::{SimSpec, TimeGrid};
use serde::Serialize;

/// A medium: drag law and noise amplitude.
#[derive(Clone, Debug, Serialize)]
pub struct Medium {
    /// Drag law.
    pub drag: DragLaw,
    /// Sigma.
    pub sigma: f64,
}

/// The two media of the paper.
pub const MEDIA: [Medium; 2] = [
    Medium {
        drag: DragLaw::Tan,
        sigma: 3.0,
    },
    Medium {
        drag: DragLaw::Tanh,
        sigma: 0.6,
    },
];

/// Parameters of Fig. 1.
#[derive(Clone, Debug, Serialize)]
pub struct Spec {
    /// Flip rate.
    pub lambda: f64,
    /// Reset velocity.
    pub reset_velocity: f64,
    /// Media, one panel each.
    pub media: Vec<Medium>,
    /// Reset rates (one curve each).
    pub rates: Vec<f64>,
    /// Last time per medium (tanh at lambda = 0.5 relaxes more slowly).
    pub t_max: Vec<f64>,
    /// Recording times (linear grid including t = 0).
    pub samples: usize,
    /// Particles per curve.
    pub particles: u64,
    /// Cells of the stationary FP solve (graded mesh, Richardson-extrapolated <v²>).
    pub fp_cells: usize,
    /// Uniform cells of the time-dependent FP solve per medium (paper: 2000 tan, 1000 tanh).
    pub fp_transient_cells: Vec<usize>,
    /// Start of the time-averaging window for the simulated stationary <v²>,
    /// per medium: late enough that the FP transient is within 1e-4 of stationarity.
    pub burn_in: Vec<f64>,
}

impl Spec {
    /// Full or quick size.
    pub fn new(quick: bool) -> Self {
        Spec {
            lambda: 0.5,
            reset_velocity: 0.0,
            media: MEDIA.to_vec(),
            rates: vec![0.0, 0.5, 2.0, 10.0],
            t_max: vec![5.0, 13.0],
            samples: if quick { 17 } else { 41 },
            particles: if quick { 4_000 } else { 1_000_000 },
            fp_cells: 20_000,
            fp_transient_cells: vec![2000, 1000],
            burn_in: vec![3.0, 9.0],
        }
    }
}

/// Panel title for a medium.
pub fn medium_title(m: &Medium) -> String {
    format!("{}, Σ = {}", m.drag.description(), fmt_num(m.sigma))
}

/// One curve of Fig. 1 (a medium and a reset rate).
#[derive(Clone, Debug)]
pub struct Curve {
    /// Simulated moments at the recording times.
    pub sim: Vec<Moments>,
    /// <v²> of the time-dependent FP equations at the same times.
    pub v2_transient: Vec<f64>,
    /// Stationary numbers.
    pub stationary: Stationary,
}

/// Stationary <v²> of one curve: simulation time average against FP (Eq. (33)).
#[derive(Clone, Debug, Serialize)]
pub struct Stationary {
    /// Drag law.
    pub drag: DragLaw,
    /// Sigma.
    pub sigma: f64,
    /// Reset rate.
    pub r: f64,
    /// Simulated <v²>, time average over [burn_in, t_max].
    pub v2_sim_time_avg: f64,
    /// Its standard error.
    pub v2_sim_err: f64,
    /// Stationary <v²> of the FP density.
    pub v2_fp: f64,
    /// (sim - FP) / SE.
    pub z: f64,
    /// Largest |sim - FP(t)| / FP(t) at t >= burn_in.
    pub max_rel_dev_sim_vs_fp_transient_after_burn_in: f64,
}

/// Numbers behind one medium's claim.
#[derive(Clone, Debug, Serialize)]
pub struct V2Values {
    /// Largest |z| over the rates.
    pub max_abs_z: f64,
    /// FP <v²> per rate.
    pub v2_fp: Vec<f64>,
    /// The rates.
    pub rates: Vec<f64>,
}

/// Compute every curve: `[medium][rate]`.
pub fn compute(spec: &Spec, opts: &Options, progress: &dyn Progress) -> Result<Vec<Vec<Curve>>> {
    grid_of_curves(
        spec.media.len(),
        spec.rates.len(),
        progress,
        |mi, ri, stage| compute_curve(spec, mi, ri, opts, stage),
    )
}

fn compute_curve(
    spec: &Spec,
    mi: usize,
    ri: usize,
    opts: &Options,
    progress: &dyn Progress,
) -> Result<Curve> {
    let (m, r) = (spec.media[mi].clone(), spec.rates[ri]);
    let k = mi * spec.rates.len() + ri;
    let (t_max, burn_in) = (spec.t_max[mi], spec.burn_in[mi]);
    let params = Params::new(m.drag.clone(), m.sigma, spec.lambda, r, spec.reset_velocity)?;
    let sim_spec = SimSpec::new(
        spec.particles,
        TimeGrid::linear(t_max, spec.samples)?,
        burn_in,
        1,
        curve_seed(opts.seed, Which::Fig1, k as u64),
    )?;
    let obs = compute::simulate(&params, &sim_spec, progress)?;
    let fp = compute::fp_stationary(&params, spec.fp_cells)?;
    let sim = compute::moments(&obs);
    // The paper's FP method in time (uniform mesh, explicit upwind).
    let times: Vec<f64> = sim.iter().map(|s| s.t).collect();
    let v2_transient = compute::fp_transient_v2(&params, spec.fp_transient_cells[mi], &times)?;
    let mut dev: f64 = 0.0;
    for (s, &y) in sim.iter().zip(&v2_transient) {
        if s.t >= burn_in {
            dev = dev.max(((s.v2 - y) / y).abs());
        }
    }
    let s = obs.summary();
    let stationary = Stationary {
        drag: m.drag.clone(),
        sigma: m.sigma,
        r,
        v2_sim_time_avg: s.v2,
        v2_sim_err: s.v2_err,
        v2_fp: fp.v2,
        z: (s.v2 - fp.v2) / s.v2_err,
        max_rel_dev_sim_vs_fp_transient_after_burn_in: dev,
    };
    Ok(Curve {
        sim,
        v2_transient,
        stationary,
    })
}

/// Draw Fig. 1: points (simulation), solid (Eq. (33)), dashed (FP(t)).
pub fn plot(spec: &Spec, curves: &[Vec<Curve>]) -> Figure {
    let mut fig = Figure::new("fig1", "Fig. 1: mean-squared velocity ⟨v²⟩(t), λ = 0.5", 2);
    fig.key = vec![
        Key::points(format!(
            "exact sampler, {} particles",
            fmt_count(spec.particles)
        )),
        Key::line("stationary FP, Eq. (33)", Color::Gray, Dash::Solid),
        Key::line("transient FP, Eqs. (11)-(12)", Color::Gray, Dash::Dashed),
    ];
    for (mi, (m, row)) in spec.media.iter().zip(curves).enumerate() {
        let mut panel = Panel::new(
            ["(a)", "(b)"][mi],
            medium_title(m),
            Axis::linear("t"),
            Axis::linear("⟨v²⟩"),
        );
        for (ri, (c, &r)) in row.iter().zip(&spec.rates).enumerate() {
            let lab = Some(format!("r = {}", fmt_num(r)));
            let times: Vec<f64> = c.sim.iter().map(|s| s.t).collect();
            let v2_fp = c.stationary.v2_fp;
            panel.series.push(Series::points(
                lab.clone(),
                Color::Palette(ri),
                "simulation",
                times.clone(),
                c.sim.iter().map(|s| s.v2).collect(),
                c.sim.iter().map(|s| s.v2_err).collect(),
            ));
            panel.series.push(Series::line(
                lab.clone(),
                Color::Palette(ri),
                Dash::Solid,
                "fp_stationary",
                vec![0.0, spec.t_max[mi]],
                vec![v2_fp, v2_fp],
            ));
            panel.series.push(Series::line(
                lab,
                Color::Palette(ri),
                Dash::Dashed,
                "fp_transient",
                times,
                c.v2_transient.clone(),
            ));
        }
        fig.panels.push(panel);
    }
    fig
}

/// One claim per medium: the stationary <v²> decreases with r and the
/// simulation relaxes to it.
pub fn claims(spec: &Spec, curves: &[Vec<Curve>]) -> Vec<Claim> {
    let z_crit = super::z_crit(spec.rates.len());
    let list = |x: &[f64], f: &dyn Fn(f64) -> String| {
        x.iter().map(|&x| f(x)).collect::<Vec<_>>().join(", ")
    };
    spec.media
        .iter()
        .zip(curves)
        .enumerate()
        .map(|(mi, (m, row))| {
            let worst_z = row
                .iter()
                .fold(0.0, |w: f64, c| w.max(c.stationary.z.abs()));
            let ss: Vec<f64> = row.iter().map(|c| c.stationary.v2_fp).collect();
            let decreasing = ss.windows(2).all(|w| w[1] < w[0]);
            Claim {
                id: format!("v2_ss_{}", m.drag),
                figure: "fig1",
                paper: format!(
                    "{}: <v²>(t) relaxes to the Eq. (33) value, which decreases as r increases",
                    m.drag
                ),
                ours: format!(
                    "FP <v²>_ss = [{}] for r = [{}] ({}); simulation time average over [{}, {}] vs FP: max |z| = {:.2} (limit max(4, 1 % Bonferroni) = {:.2})",
                    list(&ss, &|x| format!("{x:.4}")),
                    list(&spec.rates, &fmt_num),
                    if decreasing { "decreasing" } else { "NOT monotone" },
                    fmt_num(spec.burn_in[mi]),
                    fmt_num(spec.t_max[mi]),
                    worst_z,
                    z_crit
                ),
                verdict: if decreasing && worst_z < z_crit {
                    Verdict::Agrees
                } else {
                    Verdict::Differs
                },
                values: to_json(&V2Values {
                    max_abs_z: worst_z,
                    v2_fp: ss,
                    rates: spec.rates.clone(),
                }),
            }
        })
        .collect()
}

/// Compute Fig. 1.
pub fn run(opts: &Options, progress: &dyn Progress) -> Result<FigureOutput> {
    let spec = Spec::new(opts.quick);
    let curves = compute(&spec, opts, progress)?;
    let stationary: Vec<&Stationary> = curves.iter().flatten().map(|c| &c.stationary).collect();
    Ok(FigureOutput {
        which: Which::Fig1,
        figure: plot(&spec, &curves),
        parameters: Parameters {
            stationary: Some(to_json(&stationary)),
            ..Parameters::of(&spec)
        },
        claims: claims(&spec, &curves),
        wall_time_s: 0.0,
    })
}
