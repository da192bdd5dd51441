//! Fig. 1: mean-squared velocity <v²>(t) at lambda = 0.5 for several r;
//! (a) tan, Sigma = 3; (b) tanh, Sigma = 0.6. Points: particle simulation
//! (all particles start at v = 0, x = 0, eta = ±Sigma equally likely);
//! solid lines: stationary <v²> from the Fokker-Planck density (paper Eq. 17);
//! dashed lines: <v²>(t) from the time-dependent FP equations (paper's method).

use super::compute;
use super::plot::{Axis, Color, Dash, Figure, Panel, Series};
use super::{curve_seed, fmt_num, Claim, FigureOutput, Options, Stage, Verdict, Which};
use crate::error::Result;
use crate::model::{DragLaw, Params};
use crate::parallel::Progress;
use crate::sim::{SimSpec, TimeGrid};
use serde::Serialize;

/// A medium: drag law and noise amplitude.
#[derive(Clone, Copy, Debug, Serialize)]
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
    let name = match m.drag {
        DragLaw::Tan => "shear-thickening, g = tan v",
        DragLaw::Tanh => "shear-thinning, g = tanh v",
        DragLaw::Linear => "Newtonian, g = v",
    };
    format!("{name}, Σ = {}", fmt_num(m.sigma))
}

/// Compute Fig. 1.
pub fn run(opts: &Options, progress: &dyn Progress) -> Result<FigureOutput> {
    let spec = Spec::new(opts.quick);
    let mut fig = Figure::new("fig1", "Fig. 1: mean-squared velocity ⟨v²⟩(t), λ = 0.5", 2);
    let mut claims = Vec::new();
    let n_stages = spec.media.len() * spec.rates.len();
    let mut rows = Vec::new();
    for (mi, m) in spec.media.iter().enumerate() {
        let label = ["(a)", "(b)"][mi];
        let mut panel = Panel::new(
            label,
            medium_title(m),
            Axis::linear("t"),
            Axis::linear("⟨v²⟩"),
        );
        panel.legend_title = Some("solid: Eq. 17, dashed: FP(t)".into());
        let (t_max, burn_in) = (spec.t_max[mi], spec.burn_in[mi]);
        let grid = TimeGrid::linear(t_max, spec.samples)?;
        let mut worst_z: f64 = 0.0;
        let mut ss = Vec::new();
        for (ri, &r) in spec.rates.iter().enumerate() {
            let k = mi * spec.rates.len() + ri;
            let params = Params::new(m.drag, m.sigma, spec.lambda, r, spec.reset_velocity)?;
            let sim_spec = SimSpec::new(
                spec.particles,
                grid.clone(),
                burn_in,
                1,
                curve_seed(opts.seed, Which::Fig1, k as u64),
            )?;
            let obs = compute::simulate(&params, &sim_spec, &Stage::new(progress, k, n_stages))?;
            let fp = compute::fp_stationary(&params, spec.fp_cells)?;
            let lab = Some(format!("r = {}", fmt_num(r)));
            let rows_k = obs.moment_rows();
            panel.series.push(Series::points(
                lab.clone(),
                Color::Palette(ri),
                "simulation",
                rows_k.iter().map(|r| r[0]).collect(),
                rows_k.iter().map(|r| r[3]).collect(),
                rows_k.iter().map(|r| r[4]).collect(),
            ));
            panel.series.push(Series::line(
                lab.clone(),
                Color::Palette(ri),
                Dash::Solid,
                "fp_stationary",
                vec![0.0, t_max],
                vec![fp.v2, fp.v2],
            ));
            // The paper's FP method in time (uniform mesh, explicit upwind), dashed.
            let times: Vec<f64> = rows_k.iter().map(|r| r[0]).collect();
            let tr = compute::fp_transient_v2(&params, spec.fp_transient_cells[mi], &times)?;
            let mut dev: f64 = 0.0;
            for (row, &y) in rows_k.iter().zip(&tr) {
                if row[0] >= burn_in {
                    dev = dev.max(((row[3] - y) / y).abs());
                }
            }
            panel.series.push(Series::line(
                lab,
                Color::Palette(ri),
                Dash::Dashed,
                "fp_transient",
                times,
                tr,
            ));
            let s = obs.summary();
            let z = (s.v2 - fp.v2) / s.v2_err;
            worst_z = worst_z.max(z.abs());
            ss.push(fp.v2);
            rows.push(serde_json::json!({
                "drag": m.drag, "sigma": m.sigma, "r": r,
                "v2_sim_time_avg": s.v2, "v2_sim_err": s.v2_err, "v2_fp": fp.v2, "z": z,
                "max_rel_dev_sim_vs_fp_transient_after_burn_in": dev,
            }));
        }
        let decreasing = ss.windows(2).all(|w| w[1] < w[0]);
        claims.push(Claim {
            id: format!("v2_ss_{}", m.drag),
            figure: "fig1",
            paper: format!(
                "{}: <v²>(t) relaxes to the Eq. 17 value, which decreases as r increases",
                m.drag
            ),
            ours: format!(
                "FP <v²>_ss = [{}] for r = [{}] ({}); simulation time average over [{}, {}] vs FP: max |z| = {:.2} (limit max(4, 1 % Bonferroni) = {:.2})",
                ss.iter().map(|x| format!("{x:.4}")).collect::<Vec<_>>().join(", "),
                spec.rates.iter().map(|x| fmt_num(*x)).collect::<Vec<_>>().join(", "),
                if decreasing { "decreasing" } else { "NOT monotone" },
                fmt_num(burn_in),
                fmt_num(t_max),
                worst_z,
                super::z_crit(spec.rates.len())
            ),
            verdict: if decreasing && worst_z < super::z_crit(spec.rates.len()) {
                Verdict::Agrees
            } else {
                Verdict::Differs
            },
            values: serde_json::json!({ "max_abs_z": worst_z, "v2_fp": ss, "rates": spec.rates }),
        });
        fig.panels.push(panel);
    }
    Ok(FigureOutput {
        which: Which::Fig1,
        figure: fig,
        parameters: serde_json::json!({ "spec": spec, "stationary": rows }),
        claims,
        wall_time_s: 0.0,
    })
}
