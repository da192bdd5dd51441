//! Beyond the paper: the search. Does resetting help a particle find a
//! target in *position*, and does the medium decide it, as it does for the
//! velocity target (`irtp reproduce media`)?
//!
//! Every medium of [`super::media`] (its Sigma), lambda = 1, the start
//! (x_0, v_0) = (0, 0) with the noise state ±Sigma equally likely, resets
//! to v_r = 0 with the noise state kept. Lengths are in units of each
//! medium's run length ℓ = v_u / lambda (so that "the same search" means
//! the same place relative to how far the particle runs between flips, as
//! `reproduce media` fixes velocities relative to v_u). Three protocols,
//! tau(r) from the 2-D backward equation ([`irtp::search::optimize`]) and
//! r* from the one minimiser of `mfpt optimize`:
//! - full resetting (x → x_r = 0, v → 0) and the one-sided level L = ℓ;
//! - full resetting and the asymmetric interval (-ℓ, 10ℓ);
//! - velocity-only resetting (v → 0, x kept) and the same interval.
//!
//! With velocity-only resetting the one-sided level has an infinite mean
//! at every r (x is unbounded, S(t) ~ t^(-1/2)): the exact sampler's
//! Kaplan-Meier S(t) and its fitted tail exponent stand for it
//! ([`irtp::search::fit_tail`]). Sampler check points (the exact
//! event-driven sampler at r* and 2 r*, or 0.25 and 0.5 without an optimum)
//! test each backward curve.

use super::fig1::Medium;
use super::plot::{fmt_count, Axis, Color, Dash, Figure, Key, Panel, Series};
use super::{
    curve_seed, fmt_num, grid_of_curves, to_json, z_crit, Claim, FigureOutput, Options, Parameters,
    Verdict, Which,
};
use irtp::error::Result;
use irtp::mfpt::optimize::RateRange;
use irtp::model::reset::Schedule;
use irtp::model::Params;
use irtp::parallel::{NoProgress, Progress};
use irtp::search::backward::{self, BackwardOptions};
use irtp::search::{exact, fit_tail, optimize, PositionTarget, SearchProblem, TailFit};
use serde::Serialize;

/// The resetting protocols and targets of the tau(r) curves.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Protocol {
    /// Full resetting, one-sided level.
    FullLevel,
    /// Full resetting, interval.
    FullInterval,
    /// Velocity-only resetting, interval.
    VelocityInterval,
}

impl Protocol {
    /// The three, in plotting order.
    pub const ALL: [Protocol; 3] = [
        Protocol::FullLevel,
        Protocol::FullInterval,
        Protocol::VelocityInterval,
    ];

    /// Legend text.
    fn label(self) -> &'static str {
        match self {
            Protocol::FullLevel => "full, level L",
            Protocol::FullInterval => "full, interval",
            Protocol::VelocityInterval => "velocity-only, interval",
        }
    }
}

/// Parameters of the search figure.
#[derive(Clone, Debug, Serialize)]
pub struct Spec {
    /// Media: law and Sigma (those of `reproduce media`).
    pub media: Vec<Medium>,
    /// Shear-thickening (+1), Newtonian (0), shear-thinning (-1).
    pub kinds: Vec<i8>,
    /// Flip rate.
    pub lambda: f64,
    /// Start position x_0 (= the reset position x_r of full resetting).
    pub x0: f64,
    /// Start velocity v_0 (= the reset velocity v_r).
    pub v0: f64,
    /// The one-sided level L, in units of ℓ = v_u / lambda.
    pub level: f64,
    /// The interval (a, b), in units of ℓ.
    pub interval: (f64, f64),
    /// Rates searched by the optimiser.
    pub range: RateRange,
    /// Coarse mesh of the backward equation (refined once).
    pub cells: (usize, usize),
    /// Sampled searches per check point.
    pub particles: u64,
    /// Censoring time of a check, in units of its backward tau.
    pub t_max_over_tau: f64,
    /// A check is sampled only when its expected cost, particles ×
    /// (lambda + r) × tau events, is at most this.
    pub events_per_check: f64,
    /// Velocity-only resetting and the level: reset rate of the tail run.
    pub tail_rate: f64,
    /// Its particles.
    pub tail_particles: u64,
    /// Its censoring time.
    pub tail_t_max: f64,
}

impl Spec {
    /// Full or quick size.
    pub fn new(quick: bool) -> Self {
        let media = super::media::Spec::new(quick);
        Spec {
            media: media.media,
            kinds: media.kinds,
            lambda: 1.0,
            x0: 0.0,
            v0: 0.0,
            level: 1.0,
            interval: (-1.0, 10.0),
            range: RateRange {
                r_min: 1e-2,
                r_max: 1e2,
                grid_points: if quick { 17 } else { 25 },
                // r* to 1e-4: far below its error range from the mesh.
                rtol: 1e-4,
            },
            cells: if quick { (32, 8) } else { (64, 16) },
            particles: if quick { 4_000 } else { 40_000 },
            t_max_over_tau: 100.0,
            events_per_check: if quick { 1e7 } else { 1e9 },
            tail_rate: 1.0,
            tail_particles: if quick { 4_000 } else { 40_000 },
            tail_t_max: if quick { 1e4 } else { 1e5 },
        }
    }

    /// The backward options.
    fn backward(&self) -> BackwardOptions {
        BackwardOptions::with_cells(self.cells.0, self.cells.1)
    }

    /// The problem of `protocol` in medium `m` (rate 0; the optimiser sets it).
    fn problem(&self, m: &Medium, protocol: Protocol) -> Result<SearchProblem> {
        let p = Params::new(m.drag.clone(), m.sigma, self.lambda, 0.0, self.v0)?;
        let l = self.scale(&p);
        let (full, target) = match protocol {
            Protocol::FullLevel => (true, PositionTarget::Level(self.level * l)),
            Protocol::FullInterval => (true, self.interval_target(l)),
            Protocol::VelocityInterval => (false, self.interval_target(l)),
        };
        let p = if full {
            p.with_schedule(Schedule::parse(None, Some(self.x0), None)?)?
        } else {
            p
        };
        SearchProblem::new(p, self.x0, self.v0, target)
    }

    /// The length unit ℓ = v_u / lambda.
    fn scale(&self, p: &Params) -> f64 {
        p.v_upper() / self.lambda
    }

    fn interval_target(&self, l: f64) -> PositionTarget {
        PositionTarget::Interval(self.interval.0 * l, self.interval.1 * l)
    }
}

/// One sampler check: (r, tau backward, its error estimate, tau sampled,
/// SE, z), z with the SE and the error estimate in quadrature.
pub type Check = (f64, f64, f64, f64, f64, f64);

/// tau(r) of one protocol in one medium.
#[derive(Clone, Debug, Serialize)]
pub struct RateCurve {
    /// The protocol.
    pub protocol: Protocol,
    /// (r, tau) on the optimiser's grid.
    pub grid: Vec<(f64, f64)>,
    /// tau without resetting (+∞, JSON null, for the level).
    pub tau_r0: f64,
    /// Minimising rate (0: resetting does not help).
    pub r_opt: f64,
    /// The rates r* may lie between given the error estimates.
    pub r_opt_range: (f64, f64),
    /// tau at r*.
    pub tau_opt: f64,
    /// Its error estimate.
    pub tau_opt_err: f64,
    /// Interior optimum (r* > 0 and tau* < tau(0)).
    pub interior: bool,
    /// The minimum sits at r_max.
    pub at_upper_bound: bool,
    /// Sampler checks.
    pub checks: Vec<Check>,
}

/// The velocity-only search for the level: infinite mean, its survival.
#[derive(Clone, Debug, Serialize)]
pub struct Tail {
    /// Kaplan-Meier S(t) at the survival grid's times (S > 0).
    pub survival: Vec<(f64, f64)>,
    /// The fitted exponent (None where the curve is too short).
    pub fit: Option<TailFit>,
}

/// Everything computed for one medium.
#[derive(Clone, Debug, Serialize)]
pub struct MediumResult {
    /// Velocity bound v_u.
    pub v_upper: f64,
    /// One curve per [`Protocol::ALL`].
    pub curves: Vec<RateCurve>,
    /// Velocity-only resetting and the level.
    pub tail: Tail,
}

/// The exact sampler against the backward equation at rate `r` (None:
/// beyond `events_per_check`).
fn check(
    spec: &Spec,
    base: &SearchProblem,
    r: f64,
    seed: u64,
    progress: &dyn Progress,
) -> Result<Option<Check>> {
    let pr = base.with_rate(r)?;
    let b = backward::solve(&pr, &spec.backward())?;
    let events = spec.particles as f64 * (spec.lambda + r) * b.tau;
    if !(events <= spec.events_per_check) {
        return Ok(None);
    }
    let s = exact::stats(
        &pr,
        spec.t_max_over_tau * b.tau,
        spec.particles,
        seed,
        progress,
    )?;
    let s = s.summary();
    let z = (s.tau - b.tau) / s.tau_err.hypot(b.error_estimate);
    Ok(Some((r, b.tau, b.error_estimate, s.tau, s.tau_err, z)))
}

/// tau(r), r* and the sampler checks of one protocol.
fn rate_curve(
    spec: &Spec,
    m: &Medium,
    protocol: Protocol,
    seed: u64,
    progress: &dyn Progress,
) -> Result<RateCurve> {
    let base = spec.problem(m, protocol)?;
    let o = optimize::optimize_rate(&base, &spec.range, &spec.backward(), &NoProgress)?.optimum;
    let r_mid = if o.r_opt > 0.0 { o.r_opt } else { 0.25 };
    let checks = [r_mid, 2.0 * r_mid]
        .into_iter()
        .enumerate()
        .filter_map(|(k, r)| {
            check(spec, &base, r, seed.wrapping_add(k as u64), progress).transpose()
        })
        .collect::<Result<Vec<_>>>()?;
    Ok(RateCurve {
        protocol,
        grid: o.grid,
        tau_r0: o.tau_r0,
        r_opt: o.r_opt,
        r_opt_range: o.r_opt_range,
        tau_opt: o.tau_opt,
        tau_opt_err: o.tau_opt_err,
        interior: o.interior,
        at_upper_bound: o.at_upper_bound,
        checks,
    })
}

/// The velocity-only search for the level: S(t) and its tail exponent.
fn tail(spec: &Spec, m: &Medium, seed: u64, progress: &dyn Progress) -> Result<Tail> {
    let p = Params::new(
        m.drag.clone(),
        m.sigma,
        spec.lambda,
        spec.tail_rate,
        spec.v0,
    )?;
    let level = PositionTarget::Level(spec.level * spec.scale(&p));
    let pr = SearchProblem::new(p, spec.x0, spec.v0, level)?;
    let stats = exact::stats(&pr, spec.tail_t_max, spec.tail_particles, seed, progress)?;
    let c = stats.survival();
    let survival =
        c.t.iter()
            .zip(&c.survival)
            .filter(|(&t, &s)| t > 0.0 && s > 0.0)
            .map(|(&t, &s)| (t, s))
            .collect();
    Ok(Tail {
        survival,
        fit: fit_tail(&stats),
    })
}

/// Compute every medium: the three curves and the tail, in parallel.
pub fn compute(spec: &Spec, opts: &Options, progress: &dyn Progress) -> Result<Vec<MediumResult>> {
    let n = Protocol::ALL.len();
    let rows = grid_of_curves(spec.media.len(), n + 1, progress, |mi, ci, stage| {
        let m = &spec.media[mi];
        let seed = curve_seed(opts.seed, Which::Search, (mi * 8 + ci) as u64 * 2);
        if ci < n {
            rate_curve(spec, m, Protocol::ALL[ci], seed, stage).map(Part::Curve)
        } else {
            tail(spec, m, seed, stage).map(Part::Tail)
        }
    })?;
    rows.into_iter()
        .zip(&spec.media)
        .map(|(row, m)| {
            let mut curves = Vec::new();
            let mut tail = None;
            for part in row {
                match part {
                    Part::Curve(c) => curves.push(c),
                    Part::Tail(t) => tail = Some(t),
                }
            }
            Ok(MediumResult {
                v_upper: Params::new(m.drag.clone(), m.sigma, spec.lambda, 0.0, 0.0)?.v_upper(),
                curves,
                tail: tail.expect("one tail per medium"),
            })
        })
        .collect()
}

/// One cell of the compute grid.
enum Part {
    Curve(RateCurve),
    Tail(Tail),
}

fn title(spec: &Spec, mi: usize) -> String {
    super::media::medium_title(&spec.media[mi], spec.kinds[mi])
}

/// Two panels per medium: tau(r) of the three protocols with sampler
/// points, and S(t) of velocity-only resetting with the level.
pub fn plot(spec: &Spec, rows: &[MediumResult]) -> Figure {
    let mut fig = Figure::new(
        "search",
        format!(
            "The search: (x₀, v₀) = (0, 0), level L = {} ℓ, interval ({} ℓ, {} ℓ), ℓ = vᵤ/λ, λ = {}, v_{{r}} = 0",
            fmt_num(spec.level),
            fmt_num(spec.interval.0),
            fmt_num(spec.interval.1),
            fmt_num(spec.lambda)
        ),
        2,
    );
    fig.key = vec![
        Key::points(format!(
            "exact sampler, {} searches per point",
            fmt_count(spec.particles)
        )),
        Key::line("2-D backward equation", Color::Gray, Dash::Solid),
        Key::line("t^-1/2", Color::Gray, Dash::Dashed),
    ];
    let letters = "abcdefghijklmnopqrstuvwxyz".as_bytes();
    for (mi, res) in rows.iter().enumerate() {
        let label = |k: usize| format!("({})", letters[(2 * mi + k) % 26] as char);
        let mut tau = Panel::new(label(0), title(spec, mi), Axis::log("r"), Axis::log("τ"));
        for (ci, c) in res.curves.iter().enumerate() {
            // Drawn up to 100 times the optimum (tau grows like e^{r L/v_u} beyond).
            let (x, y): (Vec<f64>, Vec<f64>) = c
                .grid
                .iter()
                .copied()
                .filter(|p| p.1 <= 100.0 * c.tau_opt)
                .unzip();
            let color = Color::Palette(ci);
            let name = Some(c.protocol.label().to_string());
            tau.series
                .push(Series::line(name, color, Dash::Solid, "backward", x, y));
            let x = c.checks.iter().map(|k| k.0).collect();
            let y = c.checks.iter().map(|k| k.3).collect();
            let e = c.checks.iter().map(|k| k.4).collect();
            tau.series
                .push(Series::points(None, color, "simulation", x, y, e));
        }
        fig.panels.push(tau);
        fig.panels.push(tail_panel(spec, label(1), &res.tail));
    }
    fig
}

/// S(t) of the velocity-only search for the level, with t^-1/2 through
/// its last point.
fn tail_panel(spec: &Spec, label: String, t: &Tail) -> Panel {
    let mut p = Panel::new(
        label,
        format!(
            "velocity-only, level: S(t), r = {}",
            fmt_num(spec.tail_rate)
        ),
        Axis::log("t"),
        Axis::log("S(t)"),
    );
    let (x, y): (Vec<f64>, Vec<f64>) = t.survival.iter().copied().unzip();
    p.series.push(Series::line(
        Some("sampled S(t)".into()),
        Color::Palette(3),
        Dash::Solid,
        "simulation",
        x.clone(),
        y.clone(),
    ));
    if let (Some(&tl), Some(&sl)) = (x.last(), y.last()) {
        let guide = x.iter().map(|&s| sl * (s / tl).powf(-0.5)).collect();
        p.series.push(Series::line(
            None,
            Color::Gray,
            Dash::Dashed,
            "guide",
            x,
            guide,
        ));
    }
    p
}

/// The media (law specs) where `protocol` has an interior optimum, and
/// those where it has none.
fn split(spec: &Spec, rows: &[MediumResult], protocol: Protocol) -> (Vec<String>, Vec<String>) {
    let (mut with, mut without) = (Vec::new(), Vec::new());
    for (m, res) in spec.media.iter().zip(rows) {
        let c = res.curves.iter().find(|c| c.protocol == protocol);
        if c.is_some_and(|c| c.interior) {
            with.push(m.drag.spec());
        } else {
            without.push(m.drag.spec());
        }
    }
    (with, without)
}

fn list(v: &[String]) -> String {
    if v.is_empty() {
        "none".into()
    } else {
        v.join(", ")
    }
}

/// r* with its range and tau* with its error, or "none".
fn fmt_optimum(c: &RateCurve) -> String {
    if !c.interior {
        return format!(
            "none (r* = 0, τ(0) = {:.4}, r* < {:.3} within the errors)",
            c.tau_r0, c.r_opt_range.1
        );
    }
    let edge = if c.at_upper_bound { " (at r_max)" } else { "" };
    let gain = if c.tau_r0.is_finite() {
        format!("τ*/τ(0) = {:.3}", c.tau_opt / c.tau_r0)
    } else {
        "τ(0) = ∞".into()
    };
    format!(
        "r* = {:.3} ∈ [{:.3}, {:.3}]{edge}, τ* = {:.4} ± {:.1e}, {gain}",
        c.r_opt, c.r_opt_range.0, c.r_opt_range.1, c.tau_opt, c.tau_opt_err
    )
}

/// Per protocol: r* in every medium; whether the answer "resetting helps"
/// is the same in every medium.
fn protocol_claim(spec: &Spec, rows: &[MediumResult], protocol: Protocol) -> Claim {
    let (with, without) = split(spec, rows, protocol);
    let per: Vec<String> = spec
        .media
        .iter()
        .zip(rows)
        .filter_map(|(m, res)| {
            let c = res.curves.iter().find(|c| c.protocol == protocol)?;
            Some(format!("{}: {}", m.drag.spec(), fmt_optimum(c)))
        })
        .collect();
    let curves: Vec<&RateCurve> = rows
        .iter()
        .flat_map(|r| r.curves.iter().filter(|c| c.protocol == protocol))
        .collect();
    let (paper, verdict) = match protocol {
        Protocol::FullLevel => (
            "(beyond the paper) full resetting makes the search for a one-sided level finite (τ(0) = ∞) with an interior optimum r* in every medium",
            if with.len() == rows.len() && curves.iter().all(|c| !c.at_upper_bound) {
                Verdict::Agrees
            } else {
                Verdict::Differs
            },
        ),
        _ => (
            "(beyond the paper) whether resetting helps this search (an interior r*) is the same in every medium",
            if with.is_empty() || without.is_empty() {
                Verdict::Agrees
            } else {
                Verdict::Differs
            },
        ),
    };
    Claim {
        id: format!(
            "search_{}",
            to_json(&protocol).as_str().unwrap_or("protocol")
        ),
        figure: "search",
        paper: paper.into(),
        ours: format!(
            "{}: {}; interior optimum in: {}; none in: {}",
            protocol.label(),
            per.join("; "),
            list(&with),
            list(&without)
        ),
        verdict,
        values: to_json(&curves),
    }
}

/// Velocity-only resetting with the level: theta = 1/2 in every medium.
fn tail_claim(spec: &Spec, rows: &[MediumResult]) -> Claim {
    let limit = z_crit(rows.len());
    let mut worst = 0.0f64;
    let mut missing = 0;
    let per: Vec<String> = spec
        .media
        .iter()
        .zip(rows)
        .map(|(m, r)| match r.tail.fit {
            Some(f) => {
                let z = (f.theta - 0.5) / f.theta_err;
                worst = worst.max(z.abs());
                format!(
                    "{}: θ = {:.3} ± {:.3} (z = {z:.2}, t ∈ [{}, {}])",
                    m.drag.spec(),
                    f.theta,
                    f.theta_err,
                    fmt_num(f.t_from),
                    fmt_num(f.t_to)
                )
            }
            None => {
                missing += 1;
                format!("{}: too few resolved points", m.drag.spec())
            }
        })
        .collect();
    let verdict = if missing > 0 || !(worst <= limit) {
        Verdict::Differs
    } else {
        Verdict::Agrees
    };
    Claim {
        id: "search_velocity_level_tail".into(),
        figure: "search",
        paper: "(beyond the paper) with velocity-only resetting the mean search time for a one-sided level is infinite: S(t) ~ t^-θ with θ = 1/2 (v_r = 0: zero mean velocity)".into(),
        ours: format!(
            "exact sampler, r = {}, {} searches, censored at t = {}: {}; max |z| = {worst:.2} (limit {limit:.2})",
            fmt_num(spec.tail_rate),
            fmt_count(spec.tail_particles),
            fmt_num(spec.tail_t_max),
            per.join("; ")
        ),
        verdict,
        values: to_json(&rows.iter().map(|r| r.tail.fit).collect::<Vec<_>>()),
    }
}

/// The sampler against the backward equation at every check point.
fn sampler_claim(spec: &Spec, rows: &[MediumResult]) -> Claim {
    let checks: Vec<&Check> = rows
        .iter()
        .flat_map(|r| r.curves.iter().flat_map(|c| c.checks.iter()))
        .collect();
    let limit = z_crit(checks.len());
    let worst = checks.iter().map(|k| k.5.abs()).fold(0.0, f64::max);
    let unresolved = checks.iter().filter(|k| !k.5.is_finite()).count();
    let verdict = if unresolved > 0 || !(worst <= limit) {
        Verdict::Differs
    } else {
        Verdict::Agrees
    };
    Claim {
        id: "search_sampler_vs_backward".into(),
        figure: "search",
        paper: "(beyond the paper) the exact search sampler agrees with the 2-D backward equation".into(),
        ours: format!(
            "{} check points ({} searches each, at r* and 2 r*, or 0.25 and 0.5; those above {:.0e} expected events left to the backward equation): max |z| = {worst:.2} (limit {limit:.2}; SE and the backward error estimate in quadrature; {unresolved} censored)",
            checks.len(),
            fmt_count(spec.particles),
            spec.events_per_check
        ),
        verdict,
        values: serde_json::json!({ "max_z": worst, "checks": checks.len() }),
    }
}

/// The question of the figure: does the medium decide whether resetting
/// helps the search, as it does for the velocity target?
fn conclusion_claim(spec: &Spec, rows: &[MediumResult]) -> Claim {
    let mut parts = Vec::new();
    let mut decides = false;
    for protocol in Protocol::ALL {
        let (with, without) = split(spec, rows, protocol);
        decides |= !with.is_empty() && !without.is_empty();
        parts.push(format!(
            "{}: helps in {} of {} media",
            protocol.label(),
            with.len(),
            rows.len()
        ));
    }
    Claim {
        id: "search_medium_decides".into(),
        figure: "search",
        paper: "(beyond the paper; the velocity target's finding, media_optimum_and_rheology) the medium decides whether resetting helps".into(),
        ours: format!(
            "{}: for the search the resetting protocol and the target's geometry decide, {}",
            parts.join("; "),
            if decides { "and the medium too for at least one protocol" } else { "not the medium" }
        ),
        verdict: if decides { Verdict::Partly } else { Verdict::Differs },
        values: serde_json::json!({}),
    }
}

/// Per protocol, the tail, the sampler checks and the conclusion.
pub fn claims(spec: &Spec, rows: &[MediumResult]) -> Vec<Claim> {
    let mut out: Vec<Claim> = Protocol::ALL
        .into_iter()
        .map(|p| protocol_claim(spec, rows, p))
        .collect();
    out.push(tail_claim(spec, rows));
    out.push(sampler_claim(spec, rows));
    out.push(conclusion_claim(spec, rows));
    out
}

/// Compute the figure.
pub fn run(opts: &Options, progress: &dyn Progress) -> Result<FigureOutput> {
    let spec = Spec::new(opts.quick);
    let rows = compute(&spec, opts, progress)?;
    Ok(FigureOutput {
        which: Which::Search,
        figure: plot(&spec, &rows),
        parameters: Parameters::of(&spec),
        claims: claims(&spec, &rows),
        wall_time_s: 0.0,
    })
}
