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

use super::Problem;
use crate::error::{Error, Result};
use crate::model::reset::{Refractory, Reset};
use crate::model::Drag;
use crate::numerics::band::Band;
use crate::numerics::bordered::{responses, Capacitance, LowRank};
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
/// velocities inside (v_l, v_t) as nodes too (the N-state solver's fixed
/// points, [`super::nstate`]).
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

/// Source terms s± of the equations "... = -s±": 1 for the MFPT itself,
/// node values for derivatives and higher moments.
enum Source<'a> {
    One,
    Nodes(&'a [f64], &'a [f64]),
}

/// The box-scheme operator on a mesh, before any right-hand side: the band
/// part (unknowns interleaved tau+_0, tau-_0, tau+_1, ...) and the two
/// border columns multiplying the reset values x±(v_r). Row 0 is the
/// regularity relation at v_l (minus the generator of the - state), rows
/// 1..n-2 are h·(generator) at the cell midpoints, the last row x+(v_t) = 0.
pub(super) struct Assembly {
    /// The band part (unfactored).
    pub(super) band: Band,
    /// Border column of x+(v_r).
    pub(super) cp: Vec<f64>,
    /// Border column of x-(v_r).
    pub(super) cm: Vec<f64>,
}

/// Assemble the operator of the simulated (or printed) drifts at `rate`.
pub(super) fn assemble(p: &Problem, m: &Mesh, rate: f64, sign: DriftSign) -> Assembly {
    let par = &p.params();
    let (g, sigma, lam) = (par.drag(), par.sigma(), par.lambda());
    // The reset term of state s weighs x±(v_r) by the noise rule's shares
    // (kept: x_s(v_r) alone; re-drawn: ½ each).
    let noise = par.reset().noise();
    let nodes = m.v.len();
    let n = 2 * nodes;
    let mut a = Band::new(n, 2, 2);
    let mut cp = vec![0.0; n];
    let mut cm = vec![0.0; n];
    // Row 0: regularity of tau- at v_l.
    a.set(0, 0, -lam);
    a.set(0, 1, lam + rate);
    (cp[0], cm[0]) = noise.mix(0.0, -rate);
    for i in 0..nodes - 1 {
        let h = m.v[i + 1] - m.v[i];
        let mid = 0.5 * (m.v[i] + m.v[i + 1]);
        let (ap, am) = drifts(g, sigma, mid, sign);
        let hl = 0.5 * h * lam;
        let hd = 0.5 * h * (lam + rate);
        let (rp, rm) = (2 * i + 1, 2 * i + 2);
        let (pi, mi, pj, mj) = (2 * i, 2 * i + 1, 2 * i + 2, 2 * i + 3);
        a.set(rp, pi, -ap - hd);
        a.set(rp, pj, ap - hd);
        a.set(rp, mi, hl);
        a.set(rp, mj, hl);
        (cp[rp], cm[rp]) = noise.mix(h * rate, 0.0);
        a.set(rm, mi, -am - hd);
        a.set(rm, mj, am - hd);
        a.set(rm, pi, hl);
        a.set(rm, pj, hl);
        (cp[rm], cm[rm]) = noise.mix(0.0, h * rate);
    }
    // Last row: tau+(v_t) = 0.
    a.set(n - 1, n - 2, 1.0);
    Assembly { band: a, cp, cm }
}

/// The right-hand side of "operator · x = -M s" for sources s±: -h times
/// the cell averages of s on the cell rows, s-(v_l) on row 0, 0 on the
/// last (M: the mass matrix of the time-dependent equations,
/// [`super::distribution`]).
fn rhs(m: &Mesh, src: &Source) -> Vec<f64> {
    let nodes = m.v.len();
    let s_at = |i: usize| -> (f64, f64) {
        match *src {
            Source::One => (1.0, 1.0),
            Source::Nodes(sp, sm) => (sp[i], sm[i]),
        }
    };
    let mut b = vec![0.0; 2 * nodes];
    b[0] = s_at(0).1;
    for i in 0..nodes - 1 {
        let h = m.v[i + 1] - m.v[i];
        let (s0, s1) = (s_at(i), s_at(i + 1));
        b[2 * i + 1] = -h * 0.5 * (s0.0 + s1.0);
        b[2 * i + 2] = -h * 0.5 * (s0.1 + s1.1);
    }
    b
}

/// Solve on the canonical (upward) mesh; returns (tau+, tau-) at the nodes,
/// or `None` when tau exceeds the f64 range (resetting so frequent that the
/// target is practically never reached).
fn solve_mesh(
    p: &Problem,
    m: &Mesh,
    rate: f64,
    sign: DriftSign,
    src: Source,
) -> Result<Option<(Vec<f64>, Vec<f64>)>> {
    let nodes = m.v.len();
    let Assembly {
        band: mut a,
        mut cp,
        mut cm,
    } = assemble(p, m, rate, sign);
    crate::parallel::check_stop()?;
    let mut b = rhs(m, &src);
    if rate > 0.0 {
        refractory(p, m, &src, &mut cp, &mut cm, &mut b)?;
    }
    a.factor().map_err(|e| Error::Numerical {
        method: "mfpt backward solve",
        reason: e.to_string(),
    })?;
    crate::parallel::check_stop()?;
    a.solve(&mut b);
    crate::parallel::check_stop()?;
    let mut x = b;
    if rate > 0.0 {
        let corrected = match &m.weights {
            None => reset_correction(&a, &mut x, cp, cm, m.reset),
            Some(w) => spread_correction(&a, &mut x, cp, cm, w, beyond(p)),
        };
        if !corrected {
            return Ok(None);
        }
    }
    let tp: Vec<f64> = (0..nodes).map(|i| x[2 * i]).collect();
    let tm: Vec<f64> = (0..nodes).map(|i| x[2 * i + 1]).collect();
    if tp.iter().chain(&tm).any(|t| !t.is_finite()) {
        return Ok(None);
    }
    Ok(Some((tp, tm)))
}

/// An exponential refractory period (docs/equations.md, entry (R6)): the
/// held phase's values T_R(s) solve
/// λ (T_R(-s) - T_R(s)) + κ (T(u, s) - T_R(s)) = -1 (u < v_t: no passage
/// while held), i.e. T_R = P T(u) + 1/κ with P = κ K⁻¹,
/// K = [[κ + λ, -λ], [-λ, κ + λ]], and the reset term of the flowing
/// equations takes T_R where it took T(v_r). The reset values R± enter
/// the rows through the border columns c±, so they become
/// (c+, c-) P, and the constant moves to the right-hand side:
/// b -= (c+ + c-) W/κ, W = Σ w_j (1 for a point target; a random
/// target's mass beyond v_t is a passage at the reset itself). P's rows sum
/// to 1, so c+ + c- is unchanged (the identity [`reset_correction`] relies
/// on). Only the mean (source 1): the moments and distributions refuse it.
fn refractory(
    p: &Problem,
    m: &Mesh,
    src: &Source,
    cp: &mut [f64],
    cm: &mut [f64],
    b: &mut [f64],
) -> Result<()> {
    let mean = match p.params().schedule().refractory {
        None => return Ok(()),
        Some(Refractory::Exp { mean }) => mean,
        Some(r @ Refractory::Fixed { .. }) => {
            return Err(Error::invalid(
                "refractory",
                r.spec(),
                "exp:mean=M for the backward equations",
            ))
        }
    };
    if !matches!(src, Source::One) {
        return Err(Error::invalid(
            "refractory",
            format!("exp:mean={mean}"),
            "none for the first-passage moments and distributions (the mean, mfpt --method backward and mfpt scan, runs it)",
        ));
    }
    let (k, l) = (1.0 / mean, p.params().lambda());
    let det = k + 2.0 * l;
    let (d, o) = ((k + l) / det, l / det);
    let wsum: f64 = m.weights.as_ref().map_or(1.0, |w| w.iter().sum());
    for i in 0..b.len() {
        let (a, c) = (cp[i], cm[i]);
        b[i] -= (a + c) * wsum * mean;
        cp[i] = d * a + o * c;
        cm[i] = o * a + d * c;
    }
    Ok(())
}

/// The reset terms of the backward equations by two extra solves with the
/// factored matrix ([`LowRank`]): x = y0 - R+ y1 - R- y2 with y1 = A⁻¹c+,
/// y2 = A⁻¹c-, and R± = x±(v_r) at the reset node. Returns false when the
/// 2×2 system is singular or overflows (tau beyond the f64 range).
fn reset_correction(a: &Band, x: &mut [f64], cp: Vec<f64>, cm: Vec<f64>, reset: usize) -> bool {
    // With q = A⁻¹e_last (tau+(v_t) = 1, no source) one has exactly
    // 1 + y1 + y2 = q (A applied to the constant 1 gives -(c+ + c-) + e_last),
    // so the 2×2 system is rewritten in sums of non-negative terms only:
    // no cancellation even when tau ~ e^{r T} is astronomically large.
    let q = unit_response(a, x.len());
    let z = responses(|y| a.solve(y), [cp, cm]);
    let (kp, km) = (2 * reset, 2 * reset + 1);
    let (y1m, y2p) = (z[0][km], z[1][kp]);
    let (qp, qm) = (q[kp], q[km]);
    // m11 = 1 + y1p = qp - y2p, m22 = 1 + y2m = qm - y1m, m12 = y2p, m21 = y1m.
    let (m11, m22) = (qp - y2p, qm - y1m);
    let det = qp * qm - qp * y1m - qm * y2p;
    if !(det > 0.0) || !det.is_finite() {
        return false;
    }
    let s = Capacitance::with_det([[m11, y2p], [y1m, m22]], det);
    let f = [x[kp], x[km]];
    LowRank::new(z, s).correct(x, f);
    true
}

/// q = A⁻¹ e_last: the response to tau+(v_t) = 1 with no source.
fn unit_response(a: &Band, n: usize) -> Vec<f64> {
    let mut q = vec![0.0; n];
    q[n - 1] = 1.0;
    a.solve(&mut q);
    q
}

/// The probability that a reset of `p` (canonical frame) lands at or
/// beyond v_t, where it is the passage: 1 - Σ_j w_j in exact arithmetic.
pub(super) fn beyond(p: &Problem) -> f64 {
    let target = p.params().reset().target();
    let vu = p.params().v_upper();
    target.mass(p.vt(), vu) / target.mass(-vu, vu)
}

/// The reset terms for a random target: as [`reset_correction`], with the
/// reset values R± = ℓ±(x) = Σ_j w_j x±(v_j) (the dense rank-one term
/// r (∫ x± q - x±) in bordered form), R from the 2×2 system
/// R = ℓ(y0) - R+ ℓ(y1) - R- ℓ(y2). As there, 1 + y1 + y2 = q gives
/// 1 + ℓ+(y1) = b + ℓ+(q) - ℓ+(y2) with b = 1 - Σ_j w_j (`beyond`, the mass
/// past v_t) and y1, y2 <= 0, so the system is solved in sums of
/// non-negative terms (no cancellation when tau is astronomically large).
/// Returns false when it is singular or overflows.
fn spread_correction(
    a: &Band,
    x: &mut [f64],
    cp: Vec<f64>,
    cm: Vec<f64>,
    w: &[f64],
    beyond: f64,
) -> bool {
    let q = unit_response(a, x.len());
    let z = responses(|y| a.solve(y), [cp, cm]);
    let ell = |y: &[f64], s: usize| -> f64 {
        w.iter().enumerate().map(|(j, wj)| wj * y[2 * j + s]).sum()
    };
    // -ℓ+(y2), -ℓ-(y1) >= 0; m11 = 1 + ℓ+(y1), m22 = 1 + ℓ-(y2).
    let (y2p, y1m) = (-ell(&z[1], 0), -ell(&z[0], 1));
    let (m11, m22) = (beyond + ell(&q, 0) + y2p, beyond + ell(&q, 1) + y1m);
    let det = (beyond + ell(&q, 0)) * (beyond + ell(&q, 1))
        + (beyond + ell(&q, 0)) * y1m
        + (beyond + ell(&q, 1)) * y2p;
    if !(det > 0.0) || !det.is_finite() {
        return false;
    }
    let s = Capacitance::with_det([[m11, -y2p], [-y1m, m22]], det);
    let f = [ell(x, 0), ell(x, 1)];
    LowRank::new(z, s).correct(x, f);
    true
}

/// tau±(v) on the whole mesh, in the user's frame (a point or a random
/// reset target).
pub fn profile(problem: &Problem, opts: &BackwardOptions) -> Result<Profile> {
    // A noise model the backward equations do not run is refused here,
    // for every caller (scans, default t-max estimates), by name.
    crate::capability::check_noise(crate::capability::Solver::Backward, problem.params())?;
    opts.validate()?;
    if problem.params().noise().is_some() {
        return super::nstate::profile(problem, opts.cells, super::nstate::BARRIER);
    }
    let (cp, swapped) = problem.canonical();
    crate::parallel::check_stop()?;
    let m = mesh(&cp, opts.cells)?;
    crate::parallel::check_stop()?;
    let (tp, tm) =
        solve_mesh(&cp, &m, cp.params().rate(), opts.drift, Source::One)?.ok_or_else(overflow)?;
    non_negative(&m.v, &tp, &tm)?;
    Ok(to_user_frame(m, tp, tm, swapped))
}

/// Refuse a profile with a negative (or NaN) mean first-passage time
/// beyond rounding (1e-12 of the largest value; tau+ at v_t is 0 up to
/// it): the mesh did not resolve the solution (e.g. at a velocity scale
/// far beyond the drag's, where the band's entries lose all their digits).
fn non_negative(v: &[f64], tp: &[f64], tm: &[f64]) -> Result<()> {
    let scale = tp.iter().chain(tm).fold(0.0f64, |m, t| m.max(t.abs()));
    let floor = -1e-12 * scale;
    let bad = (0..v.len()).find(|&i| !(tp[i] >= floor && tm[i] >= floor));
    match bad {
        None => Ok(()),
        Some(i) => Err(Error::Numerical {
            method: "mfpt backward solve",
            reason: format!(
                "tau(v) = ({:e}, {:e}) at v = {:e} is not >= 0: the mesh does not resolve \
                 the solution; refused",
                tp[i], tm[i], v[i]
            ),
        }),
    }
}

/// The [`Error::Overflow`] of the backward solve: tau exceeds the f64 range.
fn overflow() -> Error {
    Error::Overflow {
        method: "mfpt backward solve",
        quantity: "the mean first-passage time",
        meaning: "the target is practically never reached",
    }
}

/// Like [`profile`] at v_0, but `Ok(None)` when tau overflows f64.
pub fn at_start_or_overflow(
    problem: &Problem,
    opts: &BackwardOptions,
) -> Result<Option<BackwardSolution>> {
    let solved = if problem.params().noise().is_some() {
        super::nstate::solve_on(problem, opts.cells, super::nstate::BARRIER).map(|s| s.summary())
    } else {
        profile(problem, opts).and_then(|p| verified(problem, p.at_start()))
    };
    match solved {
        Ok(s) => Ok(Some(s)),
        Err(Error::Overflow { .. }) => Ok(None),
        Err(e) => Err(e),
    }
}

/// A rigorous lower bound on tau. Reaching v_t takes a reset-free stretch
/// (since the start, or since the last reset) at least as long as the
/// fastest flow (noise +Sigma throughout, in the upward frame) from v_0, or
/// from v_r, to v_t; with T* the shorter of the two flow times, the first
/// time the time since the last reset reaches T* has mean (e^{r T*} - 1)/r
/// (T* at r = 0). +∞ when that exceeds the f64 range.
pub fn lower_bound(problem: &Problem) -> f64 {
    if problem.params().noise().is_some() {
        return super::nstate::lower_bound(problem).unwrap_or(0.0);
    }
    let (cp, _) = problem.canonical();
    let p = cp.params();
    let flow = |from: f64| p.drag().flow_time(p.sigma(), from, cp.vt());
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

/// The solution, if tau respects [`lower_bound`]: an overflowing bound is
/// [`Error::Overflow`] (the target is practically never reached), a violated
/// one a numerical failure (the mesh does not resolve the solution).
fn verified(problem: &Problem, s: BackwardSolution) -> Result<BackwardSolution> {
    let bound = lower_bound(problem);
    if !bound.is_finite() {
        return Err(overflow());
    }
    if !(s.tau >= bound * (1.0 - 1e-9)) {
        return Err(Error::Numerical {
            method: "mfpt backward solve",
            reason: format!(
                "tau = {:e} is below its lower bound {bound:e} (r = {}): the mesh does not resolve \
                 the solution at this reset rate; refused (more --cells, or a smaller rate)",
                s.tau,
                problem.params().rate()
            ),
        });
    }
    Ok(s)
}

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

/// MFPT at v_0 with a Richardson error estimate (solves on N and N/2 cells).
/// Errors with [`Error::Overflow`] if tau overflows f64.
pub fn solve(problem: &Problem, opts: &BackwardOptions) -> Result<BackwardSolution> {
    if problem.params().noise().is_some() {
        return super::nstate::solve(problem, opts).map(|s| s.summary());
    }
    let fine = verified(problem, profile(problem, opts)?.at_start())?;
    crate::parallel::check_stop()?;
    let half = BackwardOptions {
        cells: (opts.cells / 2).max(8),
        ..*opts
    };
    let coarse = profile(problem, &half)?.at_start();
    // On the smallest meshes the halved mesh can be the same mesh: no estimate.
    let error_estimate = if coarse.cells < fine.cells {
        (fine.tau - coarse.tau).abs() / 3.0
    } else {
        f64::NAN
    };
    Ok(BackwardSolution {
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

/// T1± and T2± on the canonical mesh `m` (see [`Moments`]).
pub(super) fn moment_nodes(
    cp: &Problem,
    m: &Mesh,
    sign: DriftSign,
) -> Result<[(Vec<f64>, Vec<f64>); 2]> {
    let rate = cp.params().rate();
    let (tp, tm) = solve_mesh(cp, m, rate, sign, Source::One)?.ok_or_else(overflow)?;
    let (sp, sm): (Vec<f64>, Vec<f64>) = (
        tp.iter().map(|t| 2.0 * t).collect(),
        tm.iter().map(|t| 2.0 * t).collect(),
    );
    let second = solve_mesh(cp, m, rate, sign, Source::Nodes(&sp, &sm))?.ok_or_else(overflow)?;
    Ok([(tp, tm), second])
}

/// The first two moments of the first-passage time at v_0 (see
/// [`Moments`]); [`Error::Overflow`] when E(T²) exceeds the f64 range.
pub fn moments(problem: &Problem, opts: &BackwardOptions) -> Result<Moments> {
    opts.validate()?;
    two_state_only(problem, "the first-passage moments")?;
    let (cp, swapped) = problem.canonical();
    let m = mesh(&cp, opts.cells)?;
    let [(tp, tm), (qp, qm)] = moment_nodes(&cp, &m, opts.drift)?;
    let i = m.start;
    let (t1, t2) = if swapped {
        ((tm[i], tp[i]), (qm[i], qp[i]))
    } else {
        ((tp[i], tm[i]), (qp[i], qm[i]))
    };
    let out = Moments::new(t1, t2, m.v.len() - 1);
    verified(problem, out.at_start())?;
    Ok(out)
}

impl Moments {
    fn at_start(&self) -> BackwardSolution {
        BackwardSolution {
            tau: self.tau,
            tau_plus: self.tau_plus,
            tau_minus: self.tau_minus,
            cells: self.cells,
            error_estimate: f64::NAN,
        }
    }
}

/// tau(v_0) at r = 0 and its derivative d tau / d r at r = 0 (the rate in
/// `problem` is ignored). Differentiating the backward equations in r gives
/// the r = 0 operator acting on sigma± = d tau± / dr with source
/// tau±(v_r) - tau±(v) (evaluated with the r = 0 solution). Negative
/// derivative: a little resetting shortens the search.
pub fn rate_derivative_at_zero(problem: &Problem, opts: &BackwardOptions) -> Result<(f64, f64)> {
    opts.validate()?;
    if problem.params().noise().is_some() {
        return super::nstate::rate_derivative_at_zero(problem, opts);
    }
    let (cp, _) = problem.canonical();
    let m = mesh(&cp, opts.cells)?;
    let (tp, tm) = solve_mesh(&cp, &m, 0.0, opts.drift, Source::One)?.ok_or_else(overflow)?;
    // The reset values each state returns to (kept: its own, re-drawn: the mean).
    let (rp, rm) = cp
        .params()
        .reset()
        .noise()
        .mix(m.reset_value(|j| tp[j]), m.reset_value(|j| tm[j]));
    let sp: Vec<f64> = tp.iter().map(|t| rp - t).collect();
    let sm: Vec<f64> = tm.iter().map(|t| rm - t).collect();
    let (dp, dm) =
        solve_mesh(&cp, &m, 0.0, opts.drift, Source::Nodes(&sp, &sm))?.ok_or_else(overflow)?;
    let i = m.start;
    Ok((0.5 * (tp[i] + tm[i]), 0.5 * (dp[i] + dm[i])))
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
            .map(|&v| drifts(g, sigma, v, DriftSign::Simulated))
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

/// Refuse a noise model in a two-state-only routine `what` (the N-state
/// solver, [`super::nstate`], runs the mean, its profile and dτ/dr at 0).
fn two_state_only(problem: &Problem, what: &str) -> Result<()> {
    match problem.params().noise() {
        Some(m) => crate::model::noise::support::refuse(what, m),
        None => Ok(()),
    }
}
