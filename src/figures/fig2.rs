//! Figs. 2 and 3: stationary velocity densities P_s^r(v).
//! Fig. 2: tan, Sigma = 3, lambda ∈ {0.9, 7, 15, 25}; Fig. 3: tanh,
//! Sigma = 0.6, lambda ∈ {0.5, 0.85, 1.2, 3}. Points: time-averaged
//! histograms of the particle simulation; coloured lines: stationary
//! Fokker-Planck solution; black: the analytic r = 0 density (paper Eqs.
//! Neqn17 and apeqn18a) with its simulation points.
//!
//! Exact facts used by the claims (derived from the stationary forward
//! equations of the simulated process, state-preserving reset to v_r = 0):
//! - P = P+ + P- is continuous at 0 but its slope jumps:
//!   P'(0+) - P'(0-) = -r (2 lambda + r - g'(0)) / Sigma². Subtracting the
//!   two stationary equations gives Sigma P' - (g Q)' = -(2 lambda + r) Q with
//!   Q = P+ - P-, and the reset source makes Q jump by r / Sigma at 0.
//!   So a cusp exists for every r > 0 (a peak when 2 lambda + r > g'(0) = 1).
//! - Near the edges P ~ (v_u - v)^a with a = (lambda + r)/g'(v_u) - 1: the
//!   density diverges for a < 0, vanishes with infinite slope for 0 < a < 1
//!   and with zero slope for a > 1, so the transitions sit at
//!   r_0 = g'(v_u) - lambda and r_1 = 2 g'(v_u) - lambda.

use super::compute;
use super::fig1::medium_title;
use super::plot::{Axis, Color, Dash, Figure, Panel, Series};
use super::{curve_seed, fmt_num, Claim, FigureOutput, Options, Stage, Verdict, Which};
use crate::error::Result;
use crate::model::{Drag, DragLaw, Params};
use crate::parallel::{NoProgress, Progress};
use crate::sim::{Observables, SimSpec, TimeGrid};
use serde::Serialize;

/// Which of the two density figures.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub enum Medium {
    /// Fig. 2: tan, Sigma = 3.
    Tan,
    /// Fig. 3: tanh, Sigma = 0.6.
    Tanh,
}

/// Parameters of Fig. 2 / 3.
#[derive(Clone, Debug, Serialize)]
pub struct Spec {
    /// Drag law.
    pub drag: DragLaw,
    /// Sigma.
    pub sigma: f64,
    /// One panel per flip rate.
    pub lambdas: Vec<f64>,
    /// One curve per reset rate (r = 0 drawn in black).
    pub rates: Vec<f64>,
    /// Reset velocity.
    pub reset_velocity: f64,
    /// Smallest number of particles per curve.
    pub particles: u64,
    /// Target of equivalent independent samples per curve: a pilot run of
    /// `pilot_particles` measures how many independent stationary samples
    /// one particle's time average is worth, n₁ = Var_ss(v²) / (N SE²(<v²>)),
    /// with Var_ss(v²) from the FP density; the curve then gets
    /// clamp(1.2 target / n₁, particles, max_particles) particles.
    pub target_equivalent: f64,
    /// Particles of the sizing pilot run (own seed, not part of the result).
    pub pilot_particles: u64,
    /// Largest number of particles per curve.
    pub max_particles: u64,
    /// Time averaging window [burn_in, t_max] per particle.
    pub burn_in: f64,
    /// End of each trajectory.
    pub t_max: f64,
    /// Histogram bins on (v_l, v_u).
    pub bins: usize,
    /// Fokker-Planck cells of the stationary solve (graded mesh; the paper
    /// used 2000 (tan) and 1000 (tanh) uniform cells). Lines are drawn
    /// through at most `line_points` of them.
    pub fp_cells: usize,
    /// Points per drawn FP line.
    pub line_points: usize,
    /// Edge behaviour at r = 0 per panel as the paper's text states it
    /// (cases (i)-(iv) / (a)-(d)): "diverges", "cusp" (zero, infinite slope), "flat".
    pub paper_r0_edge: Vec<String>,
}

impl Spec {
    /// Full or quick size.
    pub fn new(m: Medium, quick: bool) -> Self {
        let (drag, sigma, lambdas, rates, cells, classes) = match m {
            Medium::Tan => (
                DragLaw::Tan,
                3.0,
                vec![0.9, 7.0, 15.0, 25.0],
                vec![0.0, 1.0, 5.0, 15.0, 30.0],
                100_000,
                ["diverges", "diverges", "cusp", "flat"],
            ),
            Medium::Tanh => (
                DragLaw::Tanh,
                0.6,
                vec![0.5, 0.85, 1.2, 3.0],
                vec![0.0, 0.2, 0.5, 2.0, 5.0],
                100_000,
                ["diverges", "cusp", "cusp", "flat"],
            ),
        };
        Spec {
            drag,
            sigma,
            lambdas,
            rates,
            reset_velocity: 0.0,
            particles: if quick { 1_000 } else { 20_000 },
            target_equivalent: if quick { 2e4 } else { 1e6 },
            pilot_particles: if quick { 200 } else { 2_000 },
            max_particles: if quick { 2_000 } else { 200_000 },
            burn_in: 5.0,
            t_max: if quick { 10.0 } else { 30.0 },
            bins: if quick { 40 } else { 80 },
            fp_cells: cells,
            line_points: 1200,
            paper_r0_edge: classes.iter().map(|c| c.to_string()).collect(),
        }
    }
}

/// One-sided slopes of p at v = 0 from quadratic least-squares fits on
/// [lo, hi] and [-hi, -lo] (away from the unresolved kink); returns
/// (left slope, right slope).
pub fn one_sided_slopes(v: &[f64], p: &[f64], lo: f64, hi: f64) -> (f64, f64) {
    let fit = |sign: f64| {
        // Fit p = c0 + c1 u + c2 u² with u = sign * v in [lo, hi].
        let mut s = [[0.0f64; 3]; 3];
        let mut b = [0.0f64; 3];
        for (&vv, &pp) in v.iter().zip(p) {
            let u = sign * vv;
            if u >= lo && u <= hi {
                let phi = [1.0, u, u * u];
                for i in 0..3 {
                    for j in 0..3 {
                        s[i][j] += phi[i] * phi[j];
                    }
                    b[i] += phi[i] * pp;
                }
            }
        }
        let c = solve3(s, b);
        sign * c[1]
    };
    (fit(-1.0), fit(1.0))
}

fn solve3(mut a: [[f64; 3]; 3], mut b: [f64; 3]) -> [f64; 3] {
    for k in 0..3 {
        let piv = (k..3)
            .max_by(|&i, &j| a[i][k].abs().total_cmp(&a[j][k].abs()))
            .expect("non-empty");
        a.swap(k, piv);
        b.swap(k, piv);
        for i in k + 1..3 {
            let f = a[i][k] / a[k][k];
            let row = a[k];
            for (x, y) in a[i][k..].iter_mut().zip(&row[k..]) {
                *x -= f * y;
            }
            b[i] -= f * b[k];
        }
    }
    let mut x = [0.0; 3];
    for i in (0..3).rev() {
        let s: f64 = (i + 1..3).map(|j| a[i][j] * x[j]).sum();
        x[i] = (b[i] - s) / a[i][i];
    }
    x
}

/// Mean of a finite-volume density (cell averages `p` on cells with `edges`)
/// over [a, b].
pub fn bin_average(edges: &[f64], p: &[f64], a: f64, b: f64) -> f64 {
    let mut s = 0.0;
    for (i, &pi) in p.iter().enumerate() {
        let (lo, hi) = (edges[i].max(a), edges[i + 1].min(b));
        if hi > lo {
            s += pi * (hi - lo);
        }
    }
    s / (b - a)
}

/// Indices of about `n` points spread evenly in v over a (possibly graded)
/// mesh, plus both ends and the point nearest v = 0 (the cusp).
pub fn decimate(v: &[f64], n: usize) -> Vec<usize> {
    let (lo, hi) = (v[0], v[v.len() - 1]);
    let step = (hi - lo) / n.max(1) as f64;
    let i0 = (0..v.len())
        .min_by(|&i, &j| v[i].abs().total_cmp(&v[j].abs()))
        .unwrap_or(0);
    let mut out = vec![0];
    for i in 1..v.len() {
        if v[i] - v[out[out.len() - 1]] >= step || i == i0 || i == v.len() - 1 {
            out.push(i);
        }
    }
    out
}

/// Positions of the local maxima of the FP density in |v| < 0.995 v_u
/// (strict maxima over ±8 cells; the cusp at 0 counts).
pub fn local_maxima(v: &[f64], p: &[f64], vu: f64) -> Vec<f64> {
    const K: usize = 8;
    let mut out = Vec::new();
    for i in K..v.len().saturating_sub(K) {
        if v[i].abs() >= 0.995 * vu {
            continue;
        }
        if (1..=K).all(|k| p[i] > p[i - k] && p[i] >= p[i + k]) {
            out.push(v[i]);
        }
    }
    out
}

/// Seed index offset of the sizing pilots (disjoint from the curves' indices).
const PILOT_SEED_OFFSET: u64 = 1 << 32;

/// Stationary variance of v², <v⁴> - <v²>², from an FP density (cell masses).
pub fn stationary_var_v2(fp: &compute::Density) -> f64 {
    let (mut m2, mut m4) = (0.0, 0.0);
    for ((&v, &p), &w) in fp.v.iter().zip(&fp.p).zip(&fp.widths) {
        let v2 = v * v;
        m2 += v2 * p * w;
        m4 += v2 * v2 * p * w;
    }
    m4 - m2 * m2
}

/// Number of independent draws from P_s that would give the same standard
/// error on <v²> as the simulation's time average: Var_ss(v²) / SE².
pub fn equivalent_samples(var_v2: f64, obs: &Observables) -> f64 {
    let se = obs.v2_time_avg.sem();
    var_v2 / (se * se)
}

/// Edge class of an exponent a: P ~ (v_u - v)^a.
pub fn edge_class(a: f64) -> &'static str {
    if a < 0.0 {
        "diverges"
    } else if a < 1.0 {
        "cusp"
    } else {
        "flat"
    }
}

/// Exact slope jump P'(0+) - P'(0-) = -r (2 lambda + r - g'(0)) / Sigma².
pub fn slope_jump_exact(p: &Params) -> f64 {
    let r = p.rate();
    -r * (2.0 * p.lambda() + r - p.drag().derivative(0.0)) / (p.sigma() * p.sigma())
}

/// Compute Fig. 2 (tan) or Fig. 3 (tanh).
pub fn run(medium: Medium, opts: &Options, progress: &dyn Progress) -> Result<FigureOutput> {
    let spec = Spec::new(medium, opts.quick);
    let which = match medium {
        Medium::Tan => Which::Fig2,
        Medium::Tanh => Which::Fig3,
    };
    let m = super::fig1::Medium {
        drag: spec.drag,
        sigma: spec.sigma,
    };
    let mut fig = Figure::new(
        which.name(),
        format!(
            "Fig. {}: stationary velocity density P_s(v), {}",
            if which == Which::Fig2 { 2 } else { 3 },
            medium_title(&m)
        ),
        2,
    );
    let grid = TimeGrid::linear(spec.t_max, 2)?;
    let n_stages = spec.lambdas.len() * spec.rates.len();
    let mut worst_sim_z: f64 = 0.0;
    let mut bins_total = 0usize;
    let mut worst_r0_rel: f64 = 0.0;
    let mut cusp_rows = Vec::new();
    let mut edge_rows = Vec::new();
    let mut fp_vs_sim = Vec::new();
    let mut shape_rows = Vec::new();
    let mut fewest_equivalent = f64::INFINITY;
    let mut worst_v2_z: f64 = 0.0;
    let gp_edge_of = |p: &Params| p.drag().derivative(p.v_upper());
    for (li, &lambda) in spec.lambdas.iter().enumerate() {
        let label = ["(a)", "(b)", "(c)", "(d)"][li % 4];
        let p0 = Params::new(spec.drag, spec.sigma, lambda, 0.0, spec.reset_velocity)?;
        let vu = p0.v_upper();
        let gpe = gp_edge_of(&p0);
        let mut panel = Panel::new(
            label,
            format!("λ = {}", fmt_num(lambda)),
            Axis::linear("v"),
            Axis::linear("P_s(v)"),
        );
        panel.legend_title = Some("points: sim., lines: FP".into());
        let mut bulk_max: f64 = 0.0;
        for (ri, &r) in spec.rates.iter().enumerate() {
            let k = li * spec.rates.len() + ri;
            let params = p0.with_rate(r)?;
            let fp = compute::fp_stationary(&params, spec.fp_cells)?;
            let var_v2 = stationary_var_v2(&fp);
            let spec_for = |n: u64, index: u64| {
                SimSpec::new(
                    n,
                    grid.clone(),
                    spec.burn_in,
                    spec.bins,
                    curve_seed(opts.seed, which, index),
                )
            };
            // Sizing pilot (its own seed stream; results discarded).
            let pilot = compute::simulate(
                &params,
                &spec_for(spec.pilot_particles, PILOT_SEED_OFFSET + k as u64)?,
                &NoProgress,
            )?;
            let n_per_particle = equivalent_samples(var_v2, &pilot) / spec.pilot_particles as f64;
            // 20 % margin for the pilot's own sampling error.
            let particles = ((1.2 * spec.target_equivalent / n_per_particle).ceil() as u64)
                .clamp(spec.particles, spec.max_particles);
            let obs = compute::simulate(
                &params,
                &spec_for(particles, k as u64)?,
                &Stage::new(progress, k, n_stages),
            )?;
            let equivalent = equivalent_samples(var_v2, &obs);
            let dens = obs.density_rows();
            let color = if r == 0.0 {
                Color::Black
            } else {
                Color::Palette(ri - 1)
            };
            let lab = Some(format!("r = {}", fmt_num(r)));
            panel.series.push(Series::points(
                lab.clone(),
                color,
                "simulation",
                dens.iter().map(|d| d[0]).collect(),
                dens.iter().map(|d| d[1]).collect(),
                dens.iter().map(|d| d[2]).collect(),
            ));
            if r == 0.0 {
                let exact = compute::r0_density(&params, &fp.v)?;
                // FP at r = 0 against the analytic density, in the bulk.
                for ((&v, &pe), &pf) in fp.v.iter().zip(&exact).zip(&fp.p) {
                    if v.abs() < 0.8 * vu {
                        worst_r0_rel = worst_r0_rel.max(((pf - pe) / pe).abs());
                    }
                }
                let keep = decimate(&fp.v, spec.line_points);
                panel.series.push(Series::line(
                    lab,
                    Color::Black,
                    Dash::Solid,
                    "analytic",
                    keep.iter().map(|&i| fp.v[i]).collect(),
                    keep.iter().map(|&i| exact[i]).collect(),
                ));
                panel.series.push(Series::line(
                    Some("r = 0, FP".into()),
                    Color::Gray,
                    Dash::Dashed,
                    "fp",
                    keep.iter().map(|&i| fp.v[i]).collect(),
                    keep.iter().map(|&i| fp.p[i]).collect(),
                ));
            } else {
                let keep = decimate(&fp.v, spec.line_points);
                panel.series.push(Series::line(
                    lab,
                    color,
                    Dash::Solid,
                    "fp",
                    keep.iter().map(|&i| fp.v[i]).collect(),
                    keep.iter().map(|&i| fp.p[i]).collect(),
                ));
            }
            // Bulk height (|v| < 0.85 v_u) sets the y range: edge divergences
            // at small lambda would otherwise flatten the picture.
            for (&v, &p) in fp.v.iter().zip(&fp.p) {
                if v.abs() < 0.85 * vu {
                    bulk_max = bulk_max.max(p);
                }
            }
            // Simulation vs FP: bin averages of the FP density against the
            // histogram, in bins away from the edges.
            let w = obs.bin_width();
            let mut zmax: f64 = 0.0;
            let mut compared = 0usize;
            for d in &dens {
                // Bins in the Gaussian regime of the estimator only (relative
                // SE < 10 %): in rarely visited bins the SE is not a width.
                if d[0].abs() > 0.9 * vu || !(d[2] > 0.0 && d[2] < 0.1 * d[1]) {
                    continue;
                }
                compared += 1;
                let (a, b) = (d[0] - w / 2.0, d[0] + w / 2.0);
                let avg = bin_average(&fp.edges, &fp.p, a, b);
                zmax = zmax.max(((d[1] - avg) / d[2]).abs());
            }
            worst_sim_z = worst_sim_z.max(zmax);
            bins_total += compared;
            shape_rows.push(serde_json::json!({
                "lambda": lambda, "r": r,
                "edge_exponent": (lambda + r) / gpe - 1.0,
                "interior_maxima": local_maxima(&fp.v, &fp.p, vu),
            }));
            fp_vs_sim.push(serde_json::json!({
                "lambda": lambda, "r": r, "max_abs_z": zmax, "bins_compared": compared,
                "particles": particles, "equivalent_samples": equivalent,
                "v2_sim": obs.v2_time_avg.mean(), "v2_sim_err": obs.v2_time_avg.sem(), "v2_fp": fp.v2,
            }));
            fewest_equivalent = fewest_equivalent.min(equivalent);
            worst_v2_z =
                worst_v2_z.max(((obs.v2_time_avg.mean() - fp.v2) / obs.v2_time_avg.sem()).abs());
            if r > 0.0 {
                // Cell width at v = 0 (the mesh is graded only near the edges).
                let i0 = (0..fp.v.len())
                    .min_by(|&i, &j| fp.v[i].abs().total_cmp(&fp.v[j].abs()))
                    .unwrap_or(0);
                let h = fp.widths[i0];
                // Fit windows on the decay scale Sigma/(lambda + r) of the cusp.
                let scale = spec.sigma / (lambda + r);
                let (sl, sr) =
                    one_sided_slopes(&fp.v, &fp.p, (1e-3 * scale).max(2.0 * h), 0.02 * scale);
                let exact = slope_jump_exact(&params);
                cusp_rows.push(serde_json::json!({
                    "lambda": lambda, "r": r, "slope_left": sl, "slope_right": sr,
                    "jump_fp": sr - sl, "jump_exact": exact,
                }));
            }
        }
        edge_rows.push(serde_json::json!({
            "lambda": lambda,
            "g_prime_edge": gpe,
            "r_no_divergence": (gpe - lambda).max(0.0),
            "r_flat_edge": (2.0 * gpe - lambda).max(0.0),
            "exponents": spec.rates.iter().map(|&r| (lambda + r) / gpe - 1.0).collect::<Vec<_>>(),
            "class_r0": edge_class(lambda / gpe - 1.0),
            "class_r0_paper": spec.paper_r0_edge[li],
            "class_rmax": edge_class((lambda + spec.rates[spec.rates.len() - 1]) / gpe - 1.0),
        }));
        let top = 1.25 * bulk_max;
        panel.y = panel.y.clone().range(0.0, top);
        panel.x = panel.x.clone().range(-vu, vu);
        fig.panels.push(panel);
    }

    // Fig. 3(a) text: "around r = 2 two local maxima emerge near ±v_u". Scan
    // r finely with the FP solver and report where near-edge maxima exist.
    let p_first = Params::new(
        spec.drag,
        spec.sigma,
        spec.lambdas[0],
        0.0,
        spec.reset_velocity,
    )?;
    let edge_max_scan = if medium == Medium::Tanh {
        let rs: Vec<f64> = (0..=40)
            .map(|i| 10f64.powf(-2.0 + 2.5 * i as f64 / 40.0))
            .collect();
        let vu = p_first.v_upper();
        let mut with = Vec::new();
        for &r in &rs {
            let fp = compute::fp_stationary(&p_first.with_rate(r)?, 20_000)?;
            if local_maxima(&fp.v, &fp.p, vu)
                .iter()
                .any(|v| v.abs() > 0.5 * vu)
            {
                with.push(r);
            }
        }
        let text = if with.is_empty() {
            "none".to_string()
        } else {
            format!("{:.3}, {:.3}", with[0], with[with.len() - 1])
        };
        Some((rs, text, with))
    } else {
        None
    };
    let mut claims = Vec::new();
    let fname = which.name();
    // Cusp at v = 0.
    let mut worst_jump_rel: f64 = 0.0;
    for c in &cusp_rows {
        let (a, b) = (
            c["jump_fp"].as_f64().unwrap_or(f64::NAN),
            c["jump_exact"].as_f64().unwrap_or(f64::NAN),
        );
        worst_jump_rel = worst_jump_rel.max(((a - b) / b).abs());
    }
    let big = cusp_rows.last().cloned().unwrap_or_default();
    claims.push(Claim {
        id: format!("cusp_at_zero_{}", spec.drag),
        figure: fname,
        paper: "a cusp-like singularity at v = 0 appears for sufficiently large r and sharpens as r grows".into(),
        ours: format!(
            "slope jump P'(0+) - P'(0-) = -r(2λ + r - 1)/Σ² exactly (every r > 0, growing ~r²); FP matches it within {:.1}% over all panels (e.g. λ = {}, r = {}: FP {:.3}, exact {:.3}). The cusp is present at every r > 0, not only at large r",
            100.0 * worst_jump_rel,
            big["lambda"], big["r"],
            big["jump_fp"].as_f64().unwrap_or(f64::NAN),
            big["jump_exact"].as_f64().unwrap_or(f64::NAN),
        ),
        verdict: if worst_jump_rel < 0.15 { Verdict::Partly } else { Verdict::Differs },
        values: serde_json::json!(cusp_rows),
    });
    // Edge behaviour.
    let edge_text: Vec<String> = edge_rows
        .iter()
        .map(|e| {
            format!(
                "λ = {}: divergence ends at r₀ = {:.3}, slope flat from r₁ = {:.3}",
                e["lambda"],
                e["r_no_divergence"].as_f64().unwrap_or(f64::NAN),
                e["r_flat_edge"].as_f64().unwrap_or(f64::NAN)
            )
        })
        .collect();
    // r = 0 classes against the paper's cases, and every panel ends flat at the largest r.
    let classes_ok = edge_rows
        .iter()
        .all(|e| e["class_r0"] == e["class_r0_paper"] && e["class_rmax"] == "flat");
    let (paper_edge, verdict_edge) = match medium {
        Medium::Tan => (
            "tails change with r from divergent, through cusp-like decay to zero, to zero with horizontal slope (λ = 0.9, 7 diverge at r = 0; λ = 15 cusp; λ = 25 horizontal)",
            if classes_ok { Verdict::Agrees } else { Verdict::Differs },
        ),
        Medium::Tanh => (
            "λ = 0.5: 'around r = 2' two maxima near ±v_u replace the edge divergence; λ = 0.85, 1.2: infinite edge slope turns horizontal with r; λ = 3 horizontal throughout",
            if classes_ok { Verdict::Partly } else { Verdict::Differs },
        ),
    };
    claims.push(Claim {
        id: format!("edge_exponent_{}", spec.drag),
        figure: fname,
        paper: paper_edge.into(),
        ours: format!(
            "edge exponent a = (λ + r)/g'(v_u) - 1 with g'(v_u) = {:.3}: {}{}",
            gp_edge_of(&Params::new(spec.drag, spec.sigma, 1.0, 0.0, 0.0)?),
            edge_text.join("; "),
            if let Some(sc) = &edge_max_scan {
                format!(
                    ". λ = 0.5, FP scan of r ∈ [{}, {}]: local maxima near the edges (|v| > v_u/2) exist for r ∈ [{}], i.e. right after the divergence ends at r₀ = {:.3}, not 'around r = 2'",
                    fmt_num(sc.0[0]),
                    fmt_num(sc.0[sc.0.len() - 1]),
                    sc.1,
                    (gp_edge_of(&p_first) - spec.lambdas[0]).max(0.0)
                )
            } else {
                String::new()
            }
        ),
        verdict: verdict_edge,
        values: serde_json::json!({
            "panels": edge_rows,
            "shapes": shape_rows,
            "near_edge_maxima_rates": edge_max_scan.as_ref().map(|s| s.2.clone()),
        }),
    });
    claims.push(Claim {
        id: format!("fp_vs_simulation_{}", spec.drag),
        figure: fname,
        paper: "particle simulation and FP solution agree; FP at r = 0 reproduces the analytic density".into(),
        ours: format!(
            "max |sim - FP|/SE over {} bins with |v| < 0.9 v_u and relative SE < 10 %: {:.2} (limit max(4, 1 % Bonferroni) = {:.2}); FP vs analytic r = 0 (|v| < 0.8 v_u): max relative difference {:.2e}; time-averaged <v²> vs FP Eq. 17 over {} curves: max |z| = {:.2}; every curve is worth at least {:.2e} independent stationary samples (Var_ss(v²)/SE²(<v²>))",
            bins_total, worst_sim_z, super::z_crit(bins_total), worst_r0_rel, fp_vs_sim.len(), worst_v2_z, fewest_equivalent
        ),
        verdict: if worst_sim_z < super::z_crit(bins_total)
            && worst_v2_z < super::z_crit(fp_vs_sim.len())
            && worst_r0_rel < 0.01
        {
            Verdict::Agrees
        } else {
            Verdict::Differs
        },
        values: serde_json::json!({"max_abs_z": worst_sim_z, "r0_max_rel": worst_r0_rel, "per_curve": fp_vs_sim}),
    });
    Ok(FigureOutput {
        which,
        figure: fig,
        parameters: serde_json::json!({ "spec": spec }),
        claims,
        wall_time_s: 0.0,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn slopes_of_a_kink() {
        let v: Vec<f64> = (0..401).map(|i| -1.0 + i as f64 / 200.0).collect();
        let p: Vec<f64> = v
            .iter()
            .map(|v| 1.0 - 2.0 * v.abs() + 0.5 * v * v)
            .collect();
        let (l, r) = one_sided_slopes(&v, &p, 0.02, 0.3);
        assert!((l - 2.0).abs() < 1e-9 && (r + 2.0).abs() < 1e-9, "{l} {r}");
    }

    #[test]
    fn bin_average_of_cells() {
        let edges = [0.0, 1.0, 3.0];
        let p = [1.0, 4.0];
        assert!((bin_average(&edges, &p, 0.5, 2.0) - (0.5 + 4.0) / 1.5).abs() < 1e-15);
        let d = decimate(&[-1.0, -0.5, -0.01, 0.02, 0.5, 1.0], 2);
        assert_eq!(d, vec![0, 2, 5]);
    }

    /// The exact slope jump at v = 0 is what the FP solver produces.
    #[test]
    fn fp_reproduces_slope_jump() {
        for (d, s, l, r) in [
            (DragLaw::Tan, 3.0, 0.9, 1.0),
            (DragLaw::Tanh, 0.6, 3.0, 5.0),
        ] {
            let p = Params::new(d, s, l, r, 0.0).unwrap();
            let fp = compute::fp_stationary(&p, 20_000).unwrap();
            let sc = s / (l + r);
            let (a, b) = one_sided_slopes(&fp.v, &fp.p, 1e-3 * sc, 0.02 * sc);
            let e = slope_jump_exact(&p);
            assert!(
                ((b - a) - e).abs() < 2e-3 * e.abs(),
                "{d}: {} vs {e}",
                b - a
            );
        }
    }

    #[test]
    fn jump_sign() {
        let p = Params::new(DragLaw::Tan, 3.0, 0.9, 5.0, 0.0).unwrap();
        assert!((slope_jump_exact(&p) + 5.0 * (1.8 + 5.0 - 1.0) / 9.0).abs() < 1e-12);
    }
}
