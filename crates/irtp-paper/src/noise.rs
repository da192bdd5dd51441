//! Beyond the paper: its questions under other active noises. The paper
//! (Howlader, Mondal & Das) drives the particle with the symmetric
//! telegraph noise ±Sigma; here the questions of its Figs. 2/3 (the
//! stationary density), 6 (D_eff ∝ r⁻² for r > 1, whatever g) and 7 (an
//! optimal resetting rate for tan, none for tanh) are asked again under an
//! asymmetric telegraph noise (+Sigma, -Sigma/2), run-pause-tumble
//! (±Sigma → 0 at rate lambda, 0 → ±Sigma at rate lambda each), the
//! telegraph noise with thermal noise added, and thermal noise alone, in
//! the paper's two media (tan, Sigma = 3; tanh, Sigma = 0.6), lambda = 1,
//! resets to v_r = 0 with the noise state kept (docs/equations.md, "Noise
//! kinds").
//!
//! Per medium, three panels:
//! - P_s(v) at r = 1 for every noise (stationary Fokker-Planck with N
//!   coupled densities and the thermal diffusion), checked against the
//!   samplers' time-averaged <v²> (the exact sampler without thermal noise,
//!   Euler-Maruyama at dt and dt/2, extrapolated, with it);
//! - D_eff r² against r (Fokker-Planck, exact from the generator), with the
//!   large-r limit D_a + 2T of every noise (below);
//! - tau_r / tau_0 against r for the paper's first passage v₀ = -0.249 →
//!   v_t = 0.5 (backward equations, N coupled, second order with thermal
//!   noise; `mfpt::optimize_rate`'s grid).
//!
//! The large-r limit. With v reset to 0 at rate r ≫ lambda, g'(0), the
//! velocity is v ≈ ∫ (a_η + sqrt(2T) ξ) dt since the last reset. The
//! thermal part is independent across resets: C(t) = (2T/r) e^{-r t},
//! ∫ C = 2T/r². The active part keeps its state across a reset: for t
//! spanning resets, C(t) ≈ C_a(t)/r² with C_a the force's autocorrelation,
//! ∫ C_a dt = D_a = `<(a - <a>) β>`, `Q β = -(a - <a>)` (Eq. (N7)). So
//! D_eff r² → D_a + 2T, whatever g: the paper's Sigma²/(2 lambda) is D_a of
//! the telegraph noise.

use super::fig1::Medium;
use super::plot::{Axis, Color, Dash, Figure, Key, Panel, Series};
use super::{
    compute, curve_seed, fmt_num, grid_of_curves, z_crit, Claim, FigureOutput, Options, Parameters,
    Verdict, Which,
};
use irtp::error::Result;
use irtp::mfpt::{self, BackwardOptions, OptimizeOptions, Problem};
use irtp::model::noise::{chain, NoiseModel};
use irtp::model::{DragLaw, Params};
use irtp::parallel::{NoProgress, Progress};
use irtp::sim::{self, Method, SimSpec, TimeGrid};
use serde::Serialize;

/// One noise of the figure, relative to a medium's (Sigma, lambda, v_u).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum NoiseKind {
    /// The paper's: ±Sigma at rate lambda.
    Paper,
    /// +Sigma and -Sigma/2, leaving each at rate lambda.
    Asymmetric,
    /// ±Sigma → 0 at rate lambda, 0 → ±Sigma at rate lambda each.
    RunPauseTumble,
    /// The paper's with thermal noise, T = `thermal_fraction` v_u².
    TelegraphThermal,
    /// Thermal noise alone, the same T.
    Thermal,
}

impl NoiseKind {
    /// Every noise, in plotting order.
    pub const ALL: [NoiseKind; 5] = [
        NoiseKind::Paper,
        NoiseKind::Asymmetric,
        NoiseKind::RunPauseTumble,
        NoiseKind::TelegraphThermal,
        NoiseKind::Thermal,
    ];

    /// Legend text.
    pub fn label(self) -> &'static str {
        match self {
            NoiseKind::Paper => "telegraph ±Σ (paper)",
            NoiseKind::Asymmetric => "asymmetric +Σ, -Σ/2",
            NoiseKind::RunPauseTumble => "run-pause-tumble",
            NoiseKind::TelegraphThermal => "telegraph + thermal",
            NoiseKind::Thermal => "thermal alone",
        }
    }

    /// The noise spec and temperature in a medium (None: the paper's noise
    /// from sigma and lambda).
    fn spec(self, m: &Medium, lambda: f64, t: f64) -> (Option<String>, f64) {
        let s = m.sigma;
        match self {
            NoiseKind::Paper => (None, 0.0),
            NoiseKind::Asymmetric => (
                Some(format!(
                    "telegraph:plus={s},minus={},rate_plus={lambda},rate_minus={lambda}",
                    s / 2.0
                )),
                0.0,
            ),
            NoiseKind::RunPauseTumble => (
                Some(format!(
                    "rpt:sigma={s},alpha={lambda},beta={}",
                    2.0 * lambda
                )),
                0.0,
            ),
            NoiseKind::TelegraphThermal => {
                (Some(format!("telegraph:sigma={s},lambda={lambda}")), t)
            }
            NoiseKind::Thermal => (Some("none".into()), t),
        }
    }
}

/// Parameters of the noise figure.
#[derive(Clone, Debug, Serialize)]
pub struct Spec {
    /// The paper's media: tan (Sigma = 3), tanh (Sigma = 0.6).
    pub media: Vec<Medium>,
    /// The noises.
    pub noises: Vec<NoiseKind>,
    /// Flip rate lambda (and the rates of run-pause-tumble).
    pub lambda: f64,
    /// Temperature of the thermal noises, in units of v_u² of the paper's
    /// noise in the medium.
    pub thermal_fraction: f64,
    /// Reset rate of the density panel and of the sampler checks.
    pub density_rate: f64,
    /// Cells of the stationary FP solves.
    pub fp_cells: usize,
    /// Rates of the D_eff panel.
    pub deff_rates: Vec<f64>,
    /// Cells of its FP solves (the density at r = 10³ is a spike of width
    /// ~Sigma/r at v_r: its D_eff needs a fine mesh; the solve is O(N)).
    pub deff_cells: usize,
    /// The first passage of Fig. 7: v₀ → v_t.
    pub passage: (f64, f64),
    /// Rates searched by the optimiser.
    pub r_range: (f64, f64),
    /// Points of its coarse grid.
    pub grid_points: usize,
    /// Cells of the backward solves.
    pub mfpt_cells: usize,
    /// Sampler checks: particles.
    pub particles: u64,
    /// Their run time and burn-in.
    pub t_max: f64,
    /// Start of their averaging window.
    pub burn_in: f64,
    /// Euler step of the thermal checks (and dt/2).
    pub dt: f64,
}

impl Spec {
    /// Full or quick size.
    pub fn new(quick: bool) -> Self {
        let law = |s: &str| s.parse::<DragLaw>().expect("a built-in law");
        Spec {
            media: vec![
                Medium {
                    drag: law("tan"),
                    sigma: 3.0,
                },
                Medium {
                    drag: law("tanh"),
                    sigma: 0.6,
                },
            ],
            noises: NoiseKind::ALL.to_vec(),
            lambda: 1.0,
            thermal_fraction: 0.05,
            density_rate: 1.0,
            fp_cells: if quick { 2000 } else { 8000 },
            deff_rates: super::media::spaced(0.1, 1000.0, if quick { 5 } else { 13 }, true),
            deff_cells: if quick { 8_000 } else { 40_000 },
            passage: (-0.249, 0.5),
            r_range: (1e-2, 1e2),
            grid_points: if quick { 9 } else { 25 },
            mfpt_cells: 2000,
            particles: if quick { 200 } else { 2000 },
            t_max: if quick { 50.0 } else { 200.0 },
            burn_in: 10.0,
            dt: if quick { 2e-3 } else { 1e-3 },
        }
    }

    /// The temperature of the thermal noises in medium `m`.
    fn temperature(&self, m: &Medium) -> Result<f64> {
        let vu = Params::new(m.drag.clone(), m.sigma, self.lambda, 0.0, 0.0)?.v_upper();
        Ok(self.thermal_fraction * vu * vu)
    }

    /// The parameters of `noise` in `m` at rate r (v_r = 0, noise kept).
    pub fn params(&self, m: &Medium, noise: NoiseKind, r: f64) -> Result<Params> {
        match noise.spec(m, self.lambda, self.temperature(m)?) {
            (None, _) => Params::new(m.drag.clone(), m.sigma, self.lambda, r, 0.0),
            (Some(spec), t) => {
                Params::with_noise(m.drag.clone(), NoiseModel::parse(&spec, t)?, r, 0.0)
            }
        }
    }
}

/// Everything computed for one (medium, noise).
#[derive(Clone, Debug, Serialize)]
pub struct NoiseResult {
    /// The noise.
    pub noise: NoiseKind,
    /// Its spec (None: the paper's, from sigma and lambda).
    pub spec: Option<String>,
    /// Its temperature.
    pub temperature: f64,
    /// P_s(v) at `density_rate`: (v, P).
    pub density: (Vec<f64>, Vec<f64>),
    /// `<v>` and `<v²>` of that density.
    pub moments: (f64, f64),
    /// The sampler's <v²> and its SE (extrapolated in dt with thermal
    /// noise), and z against the FP value.
    pub sampled_v2: (f64, f64, f64),
    /// (r, D_eff) over `deff_rates`.
    pub d_eff: Vec<(f64, f64)>,
    /// The large-r limit of D_eff r²: D_a + 2T.
    pub d_eff_limit: f64,
    /// tau(r) / tau(0) on the optimiser's grid.
    pub ratio: Vec<(f64, f64)>,
    /// tau without resetting.
    pub tau_r0: f64,
    /// The optimum: r*, tau* / tau_0, interior.
    pub optimum: (f64, f64, bool),
}

/// ∫ C_a dt = `<(a - <a>) β>`, `Q β = -(a - <a>)` (Eq. (N7)), plus 2T: the
/// limit of D_eff r² at large r (module docs).
pub fn large_rate_limit(p: &Params) -> Result<f64> {
    let c = p.chain()?;
    let mean: f64 = c.pi.iter().zip(&c.levels).map(|(p, a)| p * a).sum();
    let f: Vec<f64> = c.levels.iter().map(|a| a - mean).collect();
    let b: Vec<f64> = f.iter().map(|x| -x).collect();
    let beta = chain::poisson(&c.q, &c.pi, &b)?;
    let d_a: f64 = (0..f.len()).map(|s| c.pi[s] * f[s] * beta[s]).sum();
    Ok(d_a + 2.0 * c.temperature)
}

/// The sampler's time-averaged <v²>: exact without thermal noise, Euler at
/// dt and dt/2 (extrapolated, 2 m(dt/2) - m(dt)) with it.
fn sampled_v2(spec: &Spec, p: &Params, seed: u64, progress: &dyn Progress) -> Result<(f64, f64)> {
    let grid = TimeGrid::linear(spec.t_max, 2)?;
    let run = |method: Method, seed: u64| -> Result<(f64, f64)> {
        let s = SimSpec::new(spec.particles, grid.clone(), spec.burn_in, 50, seed)?;
        let o = sim::simulate(p, &s, method, progress)?.summary();
        Ok((o.v2, o.v2_err))
    };
    if p.chain()?.temperature == 0.0 {
        return run(Method::Exact, seed);
    }
    let (a, ea) = run(Method::euler(spec.dt), seed)?;
    let (b, eb) = run(Method::euler(spec.dt / 2.0), seed.wrapping_add(1))?;
    Ok((2.0 * b - a, (4.0 * eb * eb + ea * ea).sqrt()))
}

/// One (medium, noise).
fn compute_one(
    spec: &Spec,
    m: &Medium,
    noise: NoiseKind,
    seed: u64,
    progress: &dyn Progress,
) -> Result<NoiseResult> {
    let p = spec.params(m, noise, spec.density_rate)?;
    let d = compute::fp_stationary(&p, spec.fp_cells)?;
    let mean: f64 =
        d.v.iter()
            .zip(&d.p)
            .zip(&d.widths)
            .map(|((v, p), w)| v * p * w)
            .sum();
    let (v2, v2_err) = sampled_v2(spec, &p, seed, progress)?;
    let d_eff = spec
        .deff_rates
        .iter()
        .map(|&r| {
            Ok((
                r,
                compute::fp_stationary(&spec.params(m, noise, r)?, spec.deff_cells)?.d_eff,
            ))
        })
        .collect::<Result<Vec<_>>>()?;
    let base = Problem::new(spec.params(m, noise, 0.0)?, spec.passage.0, spec.passage.1)?;
    let o = mfpt::optimize_rate(
        &base,
        &OptimizeOptions {
            r_min: spec.r_range.0,
            r_max: spec.r_range.1,
            grid_points: spec.grid_points,
            backward: BackwardOptions::with_cells(spec.mfpt_cells),
        },
        &NoProgress,
    )?;
    let (spec_text, temperature) = noise.spec(m, spec.lambda, spec.temperature(m)?);
    Ok(NoiseResult {
        noise,
        spec: spec_text,
        temperature,
        density: (d.v.clone(), d.p.clone()),
        moments: (mean, d.v2),
        sampled_v2: (v2, v2_err, (v2 - d.v2) / v2_err),
        d_eff,
        d_eff_limit: large_rate_limit(&p)?,
        ratio: o.grid.iter().map(|&(r, t)| (r, t / o.tau_r0)).collect(),
        tau_r0: o.tau_r0,
        optimum: (o.r_opt, o.tau_opt / o.tau_r0, o.interior),
    })
}

/// Every (medium, noise), all at once.
pub fn compute(
    spec: &Spec,
    opts: &Options,
    progress: &dyn Progress,
) -> Result<Vec<Vec<NoiseResult>>> {
    grid_of_curves(
        spec.media.len(),
        spec.noises.len(),
        progress,
        |mi, ni, stage| {
            let seed = curve_seed(opts.seed, Which::Noise, (mi * 16 + ni) as u64);
            compute_one(spec, &spec.media[mi], spec.noises[ni], seed, stage)
        },
    )
}

/// Three panels per medium: P_s(v), D_eff r², tau_r / tau_0.
pub fn plot(spec: &Spec, rows: &[Vec<NoiseResult>]) -> Figure {
    let mut fig = Figure::new(
        "noise",
        format!(
            "Other active noises: λ = {}, v_{{r}} = 0 (noise kept), T = {} vᵤ²",
            fmt_num(spec.lambda),
            fmt_num(spec.thermal_fraction)
        ),
        3,
    );
    fig.key = vec![
        Key::line(
            "Fokker-Planck / backward equations",
            Color::Gray,
            Dash::Solid,
        ),
        Key::line("large-r limit (D_a + 2T) / r²", Color::Gray, Dash::Dashed),
    ];
    let letters = b"abcdefghijklmnopqrstuvwxyz";
    for (mi, res) in rows.iter().enumerate() {
        let label = |k: usize| format!("({})", letters[(3 * mi + k) % 26] as char);
        let title = super::media::medium_title(&spec.media[mi], if mi == 0 { 1 } else { -1 });
        // Thermal tails fall to 1e-30 and below: drawn down to 1e-3.
        let mut dens = Panel::new(
            label(0),
            title,
            Axis::linear("v"),
            Axis::log("P_{s}").range(1e-3, 1e3),
        );
        let mut deff = Panel::new(
            label(1),
            "D_{eff} r² against r".to_string(),
            Axis::log("r"),
            Axis::log("D_{eff} r²"),
        );
        let mut tau = Panel::new(
            label(2),
            format!("v₀ = {} → vₜ = {}", spec.passage.0, spec.passage.1),
            Axis::log("r"),
            Axis::log("τ_{r} / τ_{0}"),
        );
        for (ni, n) in res.iter().enumerate() {
            let c = Color::Palette(ni);
            let name = Some(n.noise.label().to_string());
            let (v, p): (Vec<f64>, Vec<f64>) = n
                .density
                .0
                .iter()
                .zip(&n.density.1)
                .filter(|(_, &p)| p >= 1e-3)
                .map(|(&v, &p)| (v, p))
                .unzip();
            dens.series
                .push(Series::line(name.clone(), c, Dash::Solid, "fp", v, p));
            let (r, d): (Vec<f64>, Vec<f64>) = n.d_eff.iter().map(|&(r, d)| (r, d * r * r)).unzip();
            let limit = vec![n.d_eff_limit; r.len()];
            deff.series.push(Series::line(
                name.clone(),
                c,
                Dash::Solid,
                "fp",
                r.clone(),
                d,
            ));
            deff.series
                .push(Series::line(None, c, Dash::Dashed, "limit", r, limit));
            let (x, y): (Vec<f64>, Vec<f64>) =
                n.ratio.iter().copied().filter(|p| p.1 <= 100.0).unzip();
            tau.series
                .push(Series::line(name, c, Dash::Solid, "backward", x, y));
        }
        fig.panels.extend([dens, deff, tau]);
    }
    fig
}

/// The claims: samplers vs FP, D_eff ∝ r⁻² and its limit, the optimum.
pub fn claims(spec: &Spec, rows: &[Vec<NoiseResult>]) -> Vec<Claim> {
    let mut out = vec![sampler_claim(spec, rows)];
    out.extend(
        rows.iter()
            .enumerate()
            .map(|(mi, r)| deff_claim(spec, mi, r)),
    );
    out.extend(
        rows.iter()
            .enumerate()
            .map(|(mi, r)| optimum_claim(spec, mi, r)),
    );
    out
}

fn medium_name(spec: &Spec, mi: usize) -> String {
    format!(
        "{}, Σ = {}",
        spec.media[mi].drag,
        fmt_num(spec.media[mi].sigma)
    )
}

fn sampler_claim(spec: &Spec, rows: &[Vec<NoiseResult>]) -> Claim {
    let all: Vec<(usize, &NoiseResult)> = rows
        .iter()
        .enumerate()
        .flat_map(|(mi, r)| r.iter().map(move |n| (mi, n)))
        .collect();
    let limit = z_crit(all.len());
    let worst = all
        .iter()
        .map(|(_, n)| n.sampled_v2.2.abs())
        .fold(0.0, f64::max);
    let list = all
        .iter()
        .map(|(mi, n)| {
            format!(
                "{} / {}: FP {:.4}, sampled {:.4} ± {:.4}",
                medium_name(spec, *mi),
                n.noise.label(),
                n.moments.1,
                n.sampled_v2.0,
                n.sampled_v2.1
            )
        })
        .collect::<Vec<_>>()
        .join("; ");
    Claim {
        id: "noise_sampler_vs_fp".into(),
        figure: "noise",
        paper: "particle simulation and FP solution agree (Figs. 2-3), here under other noises".into(),
        ours: format!(
            "stationary <v²> at r = {}: {list}; max |z| = {worst:.2} over {} cases (limit {limit:.2})",
            fmt_num(spec.density_rate),
            all.len()
        ),
        verdict: if worst <= limit {
            Verdict::Agrees
        } else {
            Verdict::Differs
        },
        values: serde_json::json!({"max_abs_z": worst, "limit": limit}),
    }
}

/// D_eff ∝ r⁻² at large r: the local exponent between the two largest
/// rates within 0.1 of -2, and D_eff r² within 10 % of D_a + 2T there.
fn deff_claim(spec: &Spec, mi: usize, res: &[NoiseResult]) -> Claim {
    let mut ok = true;
    let parts = res
        .iter()
        .map(|n| {
            let k = n.d_eff.len();
            let ((r1, d1), (r2, d2)) = (n.d_eff[k - 2], n.d_eff[k - 1]);
            let slope = (d2 / d1).ln() / (r2 / r1).ln();
            let ratio = d2 * r2 * r2 / n.d_eff_limit;
            ok &= (slope + 2.0).abs() < 0.1 && (ratio - 1.0).abs() < 0.1;
            format!(
                "{}: exponent {slope:.3} at r = {}-{}, D r² / (D_a + 2T) = {ratio:.3} (D_a + 2T = {:.4})",
                n.noise.label(),
                fmt_num(r1),
                fmt_num(r2),
                n.d_eff_limit
            )
        })
        .collect::<Vec<_>>()
        .join("; ");
    Claim {
        id: format!("noise_deff_r_minus_2_{}", spec.media[mi].drag.spec()),
        figure: "noise",
        paper: "D_eff ∝ r⁻² for r > 1, whatever g(v) (Fig. 6), D r² → Σ²/(2λ); here under every noise".into(),
        ours: format!(
            "{}: {parts}. Criterion: exponent within 0.1 of -2 and D r² within 10 % of the limit D_a + 2T (D_a = ∫ C_a dt of the active force, Eq. (N7); 2T from the thermal noise) at the largest rates",
            medium_name(spec, mi)
        ),
        verdict: if ok { Verdict::Agrees } else { Verdict::Partly },
        values: serde_json::Value::Array(res.iter().map(summary_json).collect()),
    }
}

/// A (medium, noise) result without its density (the CSV has it).
fn summary_json(n: &NoiseResult) -> serde_json::Value {
    serde_json::json!({
        "noise": n.noise,
        "spec": n.spec,
        "temperature": n.temperature,
        "moments": n.moments,
        "sampled_v2": n.sampled_v2,
        "d_eff": n.d_eff,
        "d_eff_limit": n.d_eff_limit,
        "tau_r0": n.tau_r0,
        "optimum": n.optimum,
    })
}

/// The paper: an optimum for tan (small/moderate lambda), none for tanh.
fn optimum_claim(spec: &Spec, mi: usize, res: &[NoiseResult]) -> Claim {
    let expect = mi == 0;
    let changed: Vec<&str> = res
        .iter()
        .filter(|n| n.optimum.2 != expect)
        .map(|n| n.noise.label())
        .collect();
    let parts = res
        .iter()
        .map(|n| {
            if n.optimum.2 {
                format!(
                    "{}: r* = {:.3}, τ*/τ₀ = {:.4}",
                    n.noise.label(),
                    n.optimum.0,
                    n.optimum.1
                )
            } else {
                format!("{}: none (τ₀ = {:.4})", n.noise.label(), n.tau_r0)
            }
        })
        .collect::<Vec<_>>()
        .join("; ");
    Claim {
        id: format!("noise_optimum_{}", spec.media[mi].drag.spec()),
        figure: "noise",
        paper: format!(
            "v_t = 0.5: an optimal resetting rate exists for tan at small/moderate λ, never for tanh (Fig. 7); here {} under every noise",
            if expect { "tan" } else { "tanh" }
        ),
        ours: format!(
            "{}, v₀ = {} → vₜ = {}, λ = {}: {parts}; the paper's answer changes for: {}",
            medium_name(spec, mi),
            spec.passage.0,
            spec.passage.1,
            fmt_num(spec.lambda),
            if changed.is_empty() {
                "none".to_string()
            } else {
                changed.join(", ")
            }
        ),
        verdict: if changed.is_empty() {
            Verdict::Agrees
        } else {
            Verdict::Partly
        },
        values: serde_json::json!({}),
    }
}

/// Compute the figure.
pub fn run(opts: &Options, progress: &dyn Progress) -> Result<FigureOutput> {
    let spec = Spec::new(opts.quick);
    let rows = compute(&spec, opts, progress)?;
    Ok(FigureOutput {
        which: Which::Noise,
        figure: plot(&spec, &rows),
        parameters: Parameters::of(&spec),
        claims: claims(&spec, &rows),
        wall_time_s: 0.0,
    })
}
