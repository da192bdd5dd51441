//! Direct solve of the MFPT backward equations (see [`crate::mfpt`]).
//!
//! Discretisation: box (midpoint) scheme on a piecewise-smooth mesh of
//! [v_l, v_t] with v_0 and v_r as nodes, and v = 0 where g jumps there or
//! where g'(0) = ∞ (then graded towards 0, see `kink_node`; and graded
//! towards v_t when v_t is close to v_u). On each cell [v_i, v_{i+1}] both
//! first-order equations are imposed at the midpoint with tau± averaged
//! over the two nodes: second order on any mesh, and no coefficient is ever
//! evaluated at v_l, where the - drift vanishes. There the ODE has a regular
//! singular point: besides the regular solution, the homogeneous one grows as
//! (v - v_l)^{-(lambda + r)/g'(v_l)}, so regularity (tau- finite) reduces
//! the equation of the - state at v_l to the algebraic relation
//! `(lambda + r) tau-(v_l) - lambda tau+(v_l) - r tau-(v_r) = 1`.
//! Together with tau+(v_t) = 0 this closes the system. The + state
//! integrates from v_t downwards, the - state from v_l upwards (their
//! characteristic directions), so both boundary conditions are natural.
//!
//! Unknowns (tau+_0, tau-_0, tau+_1, ...) give a banded matrix (2 below,
//! 2 above the diagonal) plus two columns for the non-local reset values
//! tau±(v_r). Those are moved to the right-hand side (bordering): four
//! band solves with one LU factorisation ([`crate::numerics::band`]) and a
//! 2×2 system ([`crate::numerics::bordered`]), O(N) in all.
//!
//! One engine (the `engine` submodule) runs every noise: the paper's and
//! any noise model's finite-state chain, at temperature 0 by this box
//! scheme with N states per node, with thermal noise by an exponentially
//! fitted scheme (docs/equations.md, Eqs. (N30)-(N36)). The paper's noise
//! is its two-state case, its rows placed as above and its 2×2 bordering
//! kept ([`solve`], [`profile`], [`rate_derivative_at_zero`],
//! [`solve_states`] for every state's mean).

mod engine;

pub use engine::BARRIER;
pub(super) use engine::{Finite, Space, Telegraph};

use super::Problem;
use crate::error::{Error, Result};
use crate::model::noise::chain::Chain;
use crate::model::reset::Reset;
use crate::model::Drag;
use crate::numerics::band::Band;
use engine::Setup;
use serde::{Deserialize, Serialize};

/// Which drift the ± states carry in the backward equations.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum DriftSign {
    /// ±Sigma - g(v): the process that is simulated (paper Eq. (5)). Correct.
    #[default]
    Simulated,
    /// g(v) ± Sigma as printed in the paper's Eqs. (26)-(27), with the
    /// paper's boundary conditions. Kept only to demonstrate the sign error.
    PaperPrinted,
}

/// Options of the backward solver.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct BackwardOptions {
    /// Number of cells on [v_l, v_t] (distributed over the segments cut by
    /// v_0 and v_r, at least 2 each).
    pub cells: usize,
    /// Drift convention (always [`DriftSign::Simulated`] except in tests).
    pub drift: DriftSign,
}

impl Default for BackwardOptions {
    fn default() -> Self {
        BackwardOptions {
            cells: 20_000,
            drift: DriftSign::Simulated,
        }
    }
}

impl BackwardOptions {
    /// Options with a given number of cells.
    pub fn with_cells(cells: usize) -> Self {
        BackwardOptions {
            cells,
            ..Default::default()
        }
    }
    /// 8 ≤ cells ≤ 2·10⁶ (the band matrix takes ~110 bytes per cell).
    pub fn validate(&self) -> Result<()> {
        if self.cells < 8 || self.cells > 2_000_000 {
            return Err(Error::invalid("cells", self.cells, "8 <= cells <= 2000000"));
        }
        Ok(())
    }
}

/// MFPT at v_0 from the backward equations.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct BackwardSolution {
    /// tau = (tau+ + tau-)/2 (paper Eq. (28)).
    pub tau: f64,
    /// Start in the +Sigma state.
    pub tau_plus: f64,
    /// Start in the -Sigma state.
    pub tau_minus: f64,
    /// Cells actually used.
    pub cells: usize,
    /// Discretisation error estimate of tau: |tau_N - tau_{N/2}| / 3
    /// (Richardson, second order); NaN where not computed.
    pub error_estimate: f64,
}

/// tau±(v) on the whole mesh, in the user's frame (v increasing).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Profile {
    /// Mesh nodes.
    pub v: Vec<f64>,
    /// tau(v): the mean over the initial noise state, (tau+ + tau-)/2
    /// for the paper's noise, Σ_s π_s T_s(v) for a noise model.
    pub tau: Vec<f64>,
    /// tau+(v) (a noise model: the state of highest level).
    pub tau_plus: Vec<f64>,
    /// tau-(v) (a noise model: the state of lowest level).
    pub tau_minus: Vec<f64>,
    /// Index of v_0 in `v`.
    pub start: usize,
}

impl Profile {
    /// The solution at v_0.
    pub fn at_start(&self) -> BackwardSolution {
        let (p, m) = (self.tau_plus[self.start], self.tau_minus[self.start]);
        BackwardSolution {
            tau: self.tau[self.start],
            tau_plus: p,
            tau_minus: m,
            cells: self.v.len() - 1,
            error_estimate: f64::NAN,
        }
    }
}

/// Mesh of [v_l, v_t] (canonical, upward frame) with v_0 and v_r as nodes:
/// uniform per segment, except the last one when v_t is close to v_u.
#[derive(Clone)]
pub(super) struct Mesh {
    /// Nodes, increasing.
    pub(super) v: Vec<f64>,
    /// Index of v_0.
    pub(super) start: usize,
    /// Index of v_r (for a random target: of its centre when inside
    /// (v_l, v_t), else of v_0; unused then).
    pub(super) reset: usize,
    /// A random target's node weights w_j: the reset value of state s is
    /// Σ_j w_j x_s(v_j) = ∫ x_s dQ for x_s linear on each cell (w_j: the
    /// target's integral of the hat function of node j; the mass beyond
    /// v_t, where a reset is the passage, weighs x = 0); None for a point
    /// target (the node `reset`).
    pub(super) weights: Option<Vec<f64>>,
}

/// Mesh of [v_l, v_t] for `p` (canonical frame): a point target is a node,
/// a random one gets node weights ([`Mesh::weights`]).
pub(super) fn mesh(p: &Problem, cells: usize) -> Result<Mesh> {
    mesh_on(p, p.params().v_lower(), p.params().v_upper(), &[], cells)
}

/// [`mesh`] on [v_l, v_t] for the interval (v_l, v_u) of the velocity
/// (the noise model's, or a truncation with thermal noise), with `extra`
/// velocities inside (v_l, v_t) as nodes too (the fixed points of a noise
/// model's levels).
pub(super) fn mesh_on(p: &Problem, vl: f64, vu: f64, extra: &[f64], cells: usize) -> Result<Mesh> {
    let point = p.params().reset().point();
    // A random target's centre is a node too (a narrow target then weighs
    // that node alone, as the point target would).
    let centre = p.params().reset().target().centre();
    let vr = point.unwrap_or(if centre > vl && centre < p.vt() {
        centre
    } else {
        p.v0()
    });
    let mut cuts = vec![vl, p.v0(), vr, p.vt()];
    cuts.extend(extra.iter().filter(|&&x| x > vl && x < p.vt()));
    // A jump of g at v = 0 (Coulomb friction) sits on a node, so that every
    // cell's midpoint drift is smooth on the cell (second order kept).
    if p.params().drag().static_friction() > 0.0 && vl < 0.0 && 0.0 < p.vt() {
        cuts.push(0.0);
    }
    // Where g'(0) = ∞ (g ~ |v|^n, n < 1) tau has |v|^(1+n) terms at 0:
    // 0 is a node and the cells next to it are graded (kink_nodes).
    let kink = match p.params().kink_exponent()? {
        Some(n) if vl < 0.0 && 0.0 < p.vt() => {
            cuts.push(0.0);
            // The last segment may need the log grading towards v_u: it
            // then starts halfway to v_t, not at the kink.
            if p.vt() > 0.0 && !cuts.iter().any(|&c| c > 0.0 && c < p.vt()) {
                cuts.push(0.5 * p.vt());
            }
            Some(3.0 / (1.0 + n))
        }
        _ => None,
    };
    cuts.sort_by(|a, b| a.total_cmp(b));
    cuts.dedup();
    let total = p.vt() - vl;
    let mut v = vec![vl];
    let segments = cuts.len() - 1;
    let mut used = 0usize;
    for (i, w) in cuts.windows(2).enumerate() {
        let (a, b) = (w[0], w[1]);
        let last = i + 1 == segments;
        // Cells in proportion to length; the last segment takes the rounding
        // remainder, so the mesh has exactly `cells` cells when it can.
        let n = if last {
            cells.saturating_sub(used).max(2)
        } else {
            ((cells as f64 * (b - a) / total).round() as usize).max(2)
        };
        used += n;
        // Near v_u the + drift Sigma - g(v) ≈ g'(v_u)(v_u - v) vanishes and
        // tau+ varies like ln(v_u - v): when v_t is close to v_u, up to half
        // of the last segment's cells are spaced uniformly in ln(v_u - v)
        // (node density 1/H + 1/(alpha (v_u - v))), smoothly switched on as
        // v_u - v_t drops below a quarter of the segment length.
        let (da, dt) = (vu - a, vu - b);
        let weight = if last {
            0.5 * (1.0 - 4.0 * dt / (b - a)).max(0.0)
        } else {
            0.0
        };
        let (nu, nl) = (
            (1.0 - weight) * n as f64 / (b - a),
            weight * n as f64 / (da / dt).ln(),
        );
        let count = |x: f64| nu * (x - a) + nl * (da / (vu - x)).ln();
        let density = |x: f64| nu + nl / (vu - x);
        let mut x = a;
        for k in 1..=n {
            if k % (1 << 14) == 0 {
                crate::parallel::check_stop()?;
            }
            // Last node of each segment exactly at the cut.
            x = if k == n {
                b
            } else if let Some(y) = kink_node(kink, a, b, k as f64 / n as f64) {
                y
            } else if weight == 0.0 {
                a + (b - a) * k as f64 / n as f64
            } else {
                graded_node(&count, &density, k as f64, x, b)?
            };
            v.push(x);
        }
    }
    let find = |x: f64| v.iter().position(|&y| y == x).expect("cut is a node");
    let weights = target_weights(p, &v);
    Ok(Mesh {
        start: find(p.v0()),
        reset: find(vr),
        v,
        weights,
    })
}

/// Node at mesh parameter s ∈ (0, 1) of a segment [a, b] that ends at a
/// kink of g at 0 (g ~ |v|^n, n < 1, grading exponent q = 3/(1+n)):
/// |v| = |b - a| s^q from the kink. The |v|^(1+n) terms of tau, and the
/// higher |v|^(1+jn), become powers s^(q(1+jn)) ≥ s³ of the mesh
/// parameter, smooth enough for the box scheme's second order (and its
/// Richardson error estimate). None where the segment does not touch a
/// kink.
fn kink_node(q: Option<f64>, a: f64, b: f64, s: f64) -> Option<f64> {
    let q = q?;
    if a == 0.0 {
        Some(b * s.powf(q))
    } else if b == 0.0 {
        Some(a * (1.0 - s).powf(q))
    } else {
        None
    }
}

/// A random target's node weights on the nodes `v` of `p`'s mesh (see
/// [`Mesh::weights`]); None for a point target.
pub(super) fn target_weights(p: &Problem, v: &[f64]) -> Option<Vec<f64>> {
    let reset = p.params().reset();
    reset.point().is_none().then(|| {
        let target = reset.target();
        let vu = p.params().v_upper();
        let total = target.mass(-vu, vu);
        let mut w = vec![0.0; v.len()];
        for (i, c) in v.windows(2).enumerate() {
            if !(c[1] > c[0]) {
                continue; // a node repeated (v0 or v_r on a mesh node)
            }
            // The cell's mass split by the hat functions of its two nodes.
            let mass = target.mass(c[0], c[1]);
            let upper = (target.moment_from(c[0], c[1]) / (c[1] - c[0])).clamp(0.0, mass);
            w[i] += (mass - upper) / total;
            w[i + 1] += upper / total;
        }
        w
    })
}

impl Mesh {
    /// The reset value of a nodal function x (node j ↦ x(j)): x(v_r) at
    /// the reset node for a point target, Σ_j w_j x(j) for a random one.
    pub(super) fn reset_value(&self, x: impl Fn(usize) -> f64) -> f64 {
        match &self.weights {
            None => x(self.reset),
            Some(w) => w.iter().enumerate().map(|(j, wj)| wj * x(j)).sum(),
        }
    }
}

/// The node y ∈ [lo, hi] with count(y) = target, by Newton from lo (count
/// is increasing and convex, so after the first step the iterates approach
/// from above); [`Error::NotConverged`] if 50 steps do not settle it.
fn graded_node(
    count: &dyn Fn(f64) -> f64,
    density: &dyn Fn(f64) -> f64,
    target: f64,
    lo: f64,
    hi: f64,
) -> Result<f64> {
    const STEPS: usize = 50;
    let mut y = lo;
    let (mut step, mut tolerance) = (f64::INFINITY, 0.0);
    for _ in 0..STEPS {
        let next = (y + (target - count(y)) / density(y)).clamp(lo, hi);
        (step, tolerance) = ((next - y).abs(), 1e-15 * (1.0 + y.abs()));
        if step <= tolerance {
            return Ok(next);
        }
        y = next;
    }
    Err(Error::NotConverged {
        method: "mfpt mesh grading (Newton)",
        iterations: STEPS,
        residual: step,
        tolerance,
    })
}

/// Drifts (a+, a-) at v.
#[inline]
fn drifts<D: Drag>(g: D, sigma: f64, v: f64, sign: DriftSign) -> (f64, f64) {
    let f = g.force(v);
    match sign {
        DriftSign::Simulated => (sigma - f, -sigma - f),
        DriftSign::PaperPrinted => (f + sigma, f - sigma),
    }
}

/// The probability that a reset of `p` (canonical frame) lands at or
/// beyond v_t, where it is the passage: 1 - Σ_j w_j in exact arithmetic.
pub(super) fn beyond(p: &Problem) -> f64 {
    let target = p.params().reset().target();
    let vu = p.params().v_upper();
    target.mass(p.vt(), vu) / target.mass(-vu, vu)
}

/// The mean first-passage time per noise state at v_0 (any noise: the
/// paper's has the states (+Sigma, -Sigma)).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct NoiseSolution {
    /// τ = Σ_s π_s T_s(v_0): the initial state drawn from the stationary law.
    pub tau: f64,
    /// T_s(v_0) for each state s (in the noise's order).
    pub per_state: Vec<f64>,
    /// The noise levels a_s.
    pub levels: Vec<f64>,
    /// The stationary law π.
    pub pi: Vec<f64>,
    /// Cells used.
    pub cells: usize,
    /// Error estimate of τ: |τ_N - τ_{N/2}| / 3 at T = 0 (box scheme,
    /// second order), |τ_N - τ_{N/2}| with thermal noise (the fitted
    /// scheme is between first and second order); NaN where not computed.
    pub error_estimate: f64,
    /// The truncation point of a thermal problem (user's frame); NaN at
    /// T = 0.
    pub truncation: f64,
}

impl NoiseSolution {
    /// As a [`BackwardSolution`]: tau_plus starts in the state of highest
    /// level, tau_minus in the state of lowest level.
    pub fn summary(&self) -> BackwardSolution {
        let (hi, lo) = extreme_states(&self.levels);
        BackwardSolution {
            tau: self.tau,
            tau_plus: self.per_state[hi],
            tau_minus: self.per_state[lo],
            cells: self.cells,
            error_estimate: self.error_estimate,
        }
    }
}

/// Indices of the highest and lowest level (first of equals).
pub(super) fn extreme_states(levels: &[f64]) -> (usize, usize) {
    let mut hi = 0;
    let mut lo = 0;
    for (s, &a) in levels.iter().enumerate() {
        if a > levels[hi] {
            hi = s;
        }
        if a < levels[lo] {
            lo = s;
        }
    }
    (hi, lo)
}

/// The setup of `problem` on `cells` cells: the noise a method runs
/// ([`crate::capability::check_noise`]; with a noise model also the
/// protocol, [`crate::capability::check`]), the cells in range.
fn setup_checked(problem: &Problem, cells: usize, barrier: f64, sign: DriftSign) -> Result<Setup> {
    // A noise model the backward equations do not run is refused here,
    // for every caller (scans, default t-max estimates), by name.
    crate::capability::check_noise(crate::capability::Solver::Backward, problem.params())?;
    BackwardOptions::with_cells(cells).validate()?;
    engine::setup(problem, cells, barrier, sign)
}

/// The mean's nodal solution (source 1), refused where negative beyond
/// rounding (the mesh does not resolve the solution, e.g. at a velocity
/// scale far beyond the drag's, where the band's entries lose their digits).
fn mean_nodes(set: &Setup) -> Result<Vec<f64>> {
    let x = set
        .solve(set.p.params().rate(), true, &|_, _| 1.0)?
        .ok_or_else(overflow)?;
    set.non_negative(&x)?;
    Ok(x)
}

/// The levels in the user's frame and, per user state, its canonical state.
fn user_states(problem: &Problem, set: &Setup) -> Result<(Vec<f64>, Vec<usize>)> {
    let levels = problem.params().chain()?.levels;
    let map = (0..set.states())
        .map(|u| set.space.user_state(u, set.swapped))
        .collect();
    Ok((levels, map))
}

/// tau±(v) on the whole mesh, in the user's frame (a point or a random
/// reset target; any noise: tau_plus / tau_minus the states of highest /
/// lowest level, tau the mean over π).
pub fn profile(problem: &Problem, opts: &BackwardOptions) -> Result<Profile> {
    let set = setup_checked(problem, opts.cells, BARRIER, opts.drift)?;
    let x = mean_nodes(&set)?;
    let (levels, map) = user_states(problem, &set)?;
    let (hi, lo) = extreme_states(&levels);
    let n = set.mesh.v.len();
    let ns = set.states();
    let tau: Vec<f64> = (0..n).map(|k| set.mean(&x[ns * k..ns * (k + 1)])).collect();
    let mut out = Profile {
        v: set.mesh.v.clone(),
        tau,
        tau_plus: set.column(&x, map[hi]),
        tau_minus: set.column(&x, map[lo]),
        start: set.mesh.start,
    };
    if set.swapped {
        out.v = out.v.iter().rev().map(|x| -x).collect();
        out.tau.reverse();
        out.tau_plus.reverse();
        out.tau_minus.reverse();
        out.start = n - 1 - out.start;
    }
    Ok(out)
}

/// The [`Error::Overflow`] of the backward solve: tau exceeds the f64 range.
fn overflow() -> Error {
    Error::Overflow {
        method: engine::METHOD,
        quantity: "the mean first-passage time",
        meaning: "the target is practically never reached",
    }
}

/// Like [`profile`] at v_0, but `Ok(None)` when tau overflows f64.
pub fn at_start_or_overflow(
    problem: &Problem,
    opts: &BackwardOptions,
) -> Result<Option<BackwardSolution>> {
    match solve_signed(problem, opts.cells, BARRIER, opts.drift).map(|s| s.summary()) {
        Ok(s) => Ok(Some(s)),
        Err(Error::Overflow { .. }) => Ok(None),
        Err(e) => Err(e),
    }
}

/// A rigorous lower bound on tau (Eq. (N36)). No state drives faster than
/// the highest level (+Sigma for the paper's noise), so reaching v_t takes
/// a reset-free stretch (since the start, or since the last reset) at
/// least as long as that level's flow (canonical frame) from v_0, or from
/// the highest reset velocity, to v_t; with T* the shorter of the two flow
/// times, the first time the time since the last reset reaches T* has mean
/// (e^{r T*} - 1)/r (T* at r = 0). +∞ when that exceeds the f64 range; 0
/// with thermal noise (diffusion has no speed limit).
pub fn lower_bound(problem: &Problem) -> f64 {
    let (cp, _) = problem.canonical();
    let Ok(space) = engine::space_of(&cp) else {
        return 0.0;
    };
    let chain = space.chain();
    if chain.temperature > 0.0 {
        return 0.0;
    }
    let amax = chain
        .levels
        .iter()
        .cloned()
        .fold(f64::NEG_INFINITY, f64::max);
    let p = cp.params();
    let flow = |from: f64| p.drag().flow_time(amax, from, cp.vt());
    let r = p.rate();
    // The highest velocity a reset can land on (a random target's top; at
    // or beyond v_t the reset is the passage: flow time 0).
    let top = p.reset().target().support().1;
    if r > 0.0 {
        let t = flow(cp.v0()).min(flow(top.min(cp.vt())));
        (r * t).exp_m1() / r
    } else {
        flow(cp.v0())
    }
}

/// `tau`, if it respects [`lower_bound`]: an overflowing bound is
/// [`Error::Overflow`] (the target is practically never reached), a violated
/// one a numerical failure (the mesh does not resolve the solution).
fn verified(problem: &Problem, tau: f64) -> Result<()> {
    let bound = lower_bound(problem);
    if !bound.is_finite() {
        return Err(overflow());
    }
    if !(tau >= bound * (1.0 - 1e-9)) {
        return Err(Error::Numerical {
            method: engine::METHOD,
            reason: format!(
                "tau = {tau:e} is below its lower bound {bound:e} (r = {}): the mesh does not \
                 resolve the solution at this reset rate; refused (more --cells, or a smaller rate)",
                problem.params().rate()
            ),
        });
    }
    Ok(())
}

/// T_s(v_0) per state on the mesh of `cells` cells, the truncation barrier
/// `barrier` (thermal only): the solve behind [`solve_states`], verified
/// (finite, ≥ 0, τ ≥ [`lower_bound`]).
pub fn solve_on(problem: &Problem, cells: usize, barrier: f64) -> Result<NoiseSolution> {
    solve_signed(problem, cells, barrier, DriftSign::Simulated)
}

/// [`solve_on`] with the drift convention `sign`.
fn solve_signed(
    problem: &Problem,
    cells: usize,
    barrier: f64,
    sign: DriftSign,
) -> Result<NoiseSolution> {
    let set = setup_checked(problem, cells, barrier, sign)?;
    let x = mean_nodes(&set)?;
    let (tau, per) = set.at_start(&x);
    verified(problem, tau)?;
    let (levels, map) = user_states(problem, &set)?;
    let thermal = set.chain().temperature > 0.0;
    Ok(NoiseSolution {
        tau,
        per_state: map.iter().map(|&c| per[c]).collect(),
        levels,
        pi: set.chain().pi.clone(),
        cells: set.mesh.v.len() - 1,
        error_estimate: f64::NAN,
        truncation: match (thermal, set.swapped) {
            (false, _) => f64::NAN,
            (true, true) => -set.lower,
            (true, false) => set.lower,
        },
    })
}

/// MFPT at v_0 with a Richardson error estimate (solves on N and N/2 cells).
/// Errors with [`Error::Overflow`] if tau overflows f64.
pub fn solve(problem: &Problem, opts: &BackwardOptions) -> Result<BackwardSolution> {
    solve_states(problem, opts).map(|s| s.summary())
}

/// The mean first-passage time per noise state at v_0, with the error
/// estimate of a second solve on half the cells (see
/// [`NoiseSolution::error_estimate`]).
pub fn solve_states(problem: &Problem, opts: &BackwardOptions) -> Result<NoiseSolution> {
    let fine = solve_signed(problem, opts.cells, BARRIER, opts.drift)?;
    crate::parallel::check_stop()?;
    let coarse = solve_signed(problem, (opts.cells / 2).max(8), BARRIER, opts.drift)?;
    let diff = (fine.tau - coarse.tau).abs();
    // Two meshes that disagree by more than 10 % resolve nothing (e.g. a
    // target beyond g⁻¹(max a) at a tiny temperature, τ ~ e^{ΔU/T}).
    if !(diff <= 0.1 * fine.tau) {
        return Err(Error::Numerical {
            method: engine::METHOD,
            reason: format!(
                "tau = {:e} on {} cells but {:e} on {}: not resolved; refused (more --cells)",
                fine.tau, fine.cells, coarse.tau, coarse.cells
            ),
        });
    }
    // On the smallest meshes the halved mesh can be the same mesh: no estimate.
    let error_estimate = if coarse.cells >= fine.cells {
        f64::NAN
    } else if problem.params().chain()?.temperature > 0.0 {
        diff
    } else {
        diff / 3.0
    };
    Ok(NoiseSolution {
        error_estimate,
        ..fine
    })
}

/// The first two moments of the first-passage time at v_0: T1± = tau±
/// from L T1 = -1, T2± = E(T²) from L T2 = -2 T1 (the same operator, mesh
/// and boundary conditions, a new right-hand side), and what follows for a
/// uniformly random initial noise state (the mixture, as tau): variance
/// E(T²) - tau² and coefficient of variation sqrt(variance)/tau.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Moments {
    /// tau = (tau+ + tau-)/2 (paper Eq. (28)).
    pub tau: f64,
    /// Mean starting in +Sigma.
    pub tau_plus: f64,
    /// Mean starting in -Sigma.
    pub tau_minus: f64,
    /// E(T²) = (T2+ + T2-)/2.
    pub second: f64,
    /// E(T²) starting in +Sigma.
    pub second_plus: f64,
    /// E(T²) starting in -Sigma.
    pub second_minus: f64,
    /// E(T²) - tau².
    pub variance: f64,
    /// T2+ - tau+².
    pub variance_plus: f64,
    /// T2- - tau-².
    pub variance_minus: f64,
    /// sqrt(variance) / tau.
    pub cv: f64,
    /// sqrt(variance_plus) / tau_plus.
    pub cv_plus: f64,
    /// sqrt(variance_minus) / tau_minus.
    pub cv_minus: f64,
    /// Cells used.
    pub cells: usize,
}

impl Moments {
    fn new(t1: (f64, f64), t2: (f64, f64), cells: usize) -> Self {
        let tau = 0.5 * (t1.0 + t1.1);
        let second = 0.5 * (t2.0 + t2.1);
        let var = |m2: f64, m: f64| m2 - m * m;
        let (variance, variance_plus, variance_minus) =
            (var(second, tau), var(t2.0, t1.0), var(t2.1, t1.1));
        Moments {
            tau,
            tau_plus: t1.0,
            tau_minus: t1.1,
            second,
            second_plus: t2.0,
            second_minus: t2.1,
            variance,
            variance_plus,
            variance_minus,
            cv: variance.sqrt() / tau,
            cv_plus: variance_plus.sqrt() / t1.0,
            cv_minus: variance_minus.sqrt() / t1.1,
            cells,
        }
    }
}

/// The first two moments of the first-passage time at v_0 (see
/// [`Moments`]); [`Error::Overflow`] when E(T²) exceeds the f64 range.
pub fn moments(problem: &Problem, opts: &BackwardOptions) -> Result<Moments> {
    opts.validate()?;
    two_state_only(problem, "the first-passage moments")?;
    let set = setup_checked(problem, opts.cells, BARRIER, opts.drift)?;
    let [(t1, _), (t2, _)] = moment_nodes(&set)?;
    let (_, map) = user_states(problem, &set)?;
    let at = |x: &[f64]| (x[map[0]], x[map[1]]);
    let out = Moments::new(at(&t1), at(&t2), set.mesh.v.len() - 1);
    verified(problem, out.tau)?;
    Ok(out)
}

/// T1_s and T2_s at v_0 per canonical state, and at the nodes, from
/// L T1 = -1 and L T2 = -2 T1 (the same operator, a new source).
fn moment_nodes(set: &Setup) -> Result<[(Vec<f64>, Vec<f64>); 2]> {
    let rate = set.p.params().rate();
    let x = set.solve(rate, true, &|_, _| 1.0)?.ok_or_else(overflow)?;
    let ns = set.states();
    let y = set
        .solve(rate, false, &|k, s| 2.0 * x[ns * k + s])?
        .ok_or_else(overflow)?;
    Ok([(set.at_start(&x).1, x), (set.at_start(&y).1, y)])
}

/// The first two moments of the first-passage time per state at v_0 on
/// `cells` cells (states in the noise's order), verified non-negative, and
/// the cells used: an independent discretisation (the box scheme) for the
/// distribution of `mfpt::distribution` with a noise model to agree with.
pub(super) fn moments_at_start(
    problem: &Problem,
    cells: usize,
) -> Result<(Vec<f64>, Vec<f64>, usize)> {
    let set = setup_checked(problem, cells, BARRIER, DriftSign::Simulated)?;
    let [(t1, x), (t2, y)] = moment_nodes(&set)?;
    set.non_negative(&x)?;
    set.non_negative(&y)?;
    let (_, map) = user_states(problem, &set)?;
    let user = |t: &[f64]| map.iter().map(|&c| t[c]).collect();
    Ok((user(&t1), user(&t2), set.mesh.v.len() - 1))
}

/// tau(v_0) at r = 0 and its derivative d tau / d r at r = 0 (the rate in
/// `problem` is ignored). Differentiating the backward equations in r
/// (Eq. (N30)) gives the r = 0 operator acting on sigma_s = d T_s / dr with
/// source T_mix,s - T_s(v) (the reset value state s returns to, evaluated
/// with the r = 0 solution; with an exponential refractory period the held
/// value T_R,s of Eq. (R13)). Negative derivative: a little resetting
/// shortens the search.
pub fn rate_derivative_at_zero(problem: &Problem, opts: &BackwardOptions) -> Result<(f64, f64)> {
    opts.validate()?;
    let set = setup_checked(problem, opts.cells, BARRIER, opts.drift)?;
    let ns = set.states();
    let x = set.solve(0.0, true, &|_, _| 1.0)?.ok_or_else(overflow)?;
    let mix = set.held_returns(&x)?;
    let d = set
        .solve(0.0, false, &|k, s| mix[s] - x[ns * k + s])?
        .ok_or_else(overflow)?;
    Ok((set.at_start(&x).0, set.at_start(&d).0))
}

/// T_s(v) of every state on the mesh of the canonical (upward) problem of
/// `problem` ([`Problem::canonical`], its states in the noise's order):
/// (nodes, T_s at the nodes per state), verified non-negative.
pub(super) fn canonical_states(
    problem: &Problem,
    cells: usize,
) -> Result<(Vec<f64>, Vec<Vec<f64>>)> {
    let set = setup_checked(problem, cells, BARRIER, DriftSign::Simulated)?;
    let x = mean_nodes(&set)?;
    let per_state = (0..set.states()).map(|s| set.column(&x, s)).collect();
    Ok((set.mesh.v.clone(), per_state))
}

/// What the backward equations refuse for `problem` (canonical frame): the
/// capability table's ([`crate::capability::check`]).
pub(super) fn admissible(problem: &Problem) -> Result<()> {
    crate::capability::check(crate::capability::Solver::Backward, problem.params())
}

/// The thermal generator on one mesh, for the survival equations of
/// `mfpt::distribution` with a noise model (Eq. (N49)): the band and border of the fitted operator
/// of Eqs. (N32)-(N34) (source 0), and per unknown whether it is absorbed
/// (S_s(v_t) = 0, an algebraic row whose band entry is 1).
pub(super) struct Generator {
    pub(super) band: Band,
    pub(super) border: Vec<Vec<f64>>,
    pub(super) absorbed: Vec<bool>,
}

/// The mesh of a thermal problem on `cells` cells, truncated at the
/// barrier [`BARRIER`] (Eq. (N33)), in the canonical frame, as the mean
/// solver builds it.
pub(super) fn thermal_mesh(problem: &Problem, cells: usize) -> Result<Mesh> {
    let set = setup_checked(problem, cells, BARRIER, DriftSign::Simulated)?;
    if !(set.chain().temperature > 0.0) {
        return Err(Error::invalid(
            "temperature",
            set.chain().temperature,
            "temperature > 0 for the thermal backward operator",
        ));
    }
    Ok(set.mesh)
}

/// The thermal generator (Eqs. (N32)-(N34)) of the canonical problem `cp`
/// with its chain on `mesh` (node 0 the truncation, the last v_t; from
/// [`thermal_mesh`] or its refinement).
pub(super) fn thermal_generator(cp: &Problem, chain: &Chain, mesh: &Mesh) -> Generator {
    let set = Setup::on_mesh(cp, chain, mesh);
    let op = set.operator(cp.params().rate(), &|_, _| 0.0);
    Generator {
        band: op.band,
        border: op.border,
        absorbed: op.absorbed,
    }
}

/// The paper's method (Sec. 3): first-order upwind differences iterated to a
/// fixed point (Gauss-Seidel sweeps: tau+ downwards from v_t, tau- upwards
/// from v_l, then the reset values) until the largest change is below `tol`.
/// Slow (many sweeps) and first order; kept as an independent check of
/// [`solve`]. Returns the solution and the number of sweeps, or
/// [`Error::NotConverged`] after `max_sweeps`.
pub fn fixed_point_upwind(
    problem: &Problem,
    cells: usize,
    tol: f64,
    max_sweeps: usize,
) -> Result<(BackwardSolution, usize)> {
    BackwardOptions::with_cells(cells).validate()?;
    two_state_only(problem, "the fixed-point iteration")?;
    let (cp, swapped) = problem.canonical();
    let m = mesh(&cp, cells)?;
    let par = &cp.params();
    let (g, sigma, lam, r) = (par.drag(), par.sigma(), par.lambda(), par.rate());
    let n = m.v.len();
    let a: Vec<(f64, f64)> =
        m.v.iter()
            .map(|&v| drifts(g.clone(), sigma, v, DriftSign::Simulated))
            .collect();
    let (mut tp, mut tm) = (vec![0.0; n], vec![0.0; n]);
    let mut change = f64::INFINITY;
    for sweep in 1..=max_sweeps {
        change = 0.0;
        let noise = par.reset().noise();
        let rp = noise
            .mix(m.reset_value(|j| tp[j]), m.reset_value(|j| tm[j]))
            .0;
        for i in (0..n - 1).rev() {
            let c = a[i].0 / (m.v[i + 1] - m.v[i]);
            let new = (c * tp[i + 1] + lam * tm[i] + r * rp + 1.0) / (c + lam + r);
            change = change.max((new - tp[i]).abs());
            tp[i] = new;
        }
        let rm = noise
            .mix(m.reset_value(|j| tp[j]), m.reset_value(|j| tm[j]))
            .1;
        for i in 0..n {
            let c = if i == 0 {
                0.0
            } else {
                -a[i].1 / (m.v[i] - m.v[i - 1])
            };
            let prev = if i == 0 { 0.0 } else { tm[i - 1] };
            let new = (c * prev + lam * tp[i] + r * rm + 1.0) / (c + lam + r);
            change = change.max((new - tm[i]).abs());
            tm[i] = new;
        }
        if change < tol {
            let prof = to_user_frame(m, tp, tm, swapped);
            return Ok((prof.at_start(), sweep));
        }
    }
    Err(Error::NotConverged {
        method: "mfpt fixed-point iteration",
        iterations: max_sweeps,
        residual: change,
        tolerance: tol,
    })
}

/// Refuse a noise model in a two-state-only routine `what` (the engine
/// runs any noise for the mean, its profile and dτ/dr at 0).
fn two_state_only(problem: &Problem, what: &str) -> Result<()> {
    match problem.params().noise() {
        Some(m) => crate::model::noise::support::refuse(what, m),
        None => Ok(()),
    }
}

/// (tau+, tau-) on the canonical mesh as a [`Profile`] in the user's frame.
fn to_user_frame(m: Mesh, tp: Vec<f64>, tm: Vec<f64>, swapped: bool) -> Profile {
    let tau = tp.iter().zip(&tm).map(|(p, m)| 0.5 * (p + m)).collect();
    if !swapped {
        return Profile {
            v: m.v,
            tau,
            tau_plus: tp,
            tau_minus: tm,
            start: m.start,
        };
    }
    let n = m.v.len();
    Profile {
        v: m.v.iter().rev().map(|x| -x).collect(),
        tau: tau.into_iter().rev().collect(),
        tau_plus: tm.into_iter().rev().collect(),
        tau_minus: tp.into_iter().rev().collect(),
        start: n - 1 - m.start,
    }
}
