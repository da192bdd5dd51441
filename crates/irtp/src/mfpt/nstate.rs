//! The backward equations of first passage in velocity for a noise model
//! (docs/equations.md, "Backward equations for a noise model", Eqs.
//! (N30)-(N36)): N coupled equations for the conditional mean passage times
//! T_s(v), one per noise state s, first order at temperature 0 and second
//! order with thermal noise.
//!
//! At T = 0 (Eq. (N30)) state s has the drift b_s(v) = a_s - g(v), which
//! decreases in v and vanishes at its fixed point v*_s = g⁻¹(a_s). Each
//! state takes exactly one condition (Eq. (N31)): T_s(v_t) = 0 where
//! b_s(v_t) > 0 (its characteristics enter the target), else regularity at
//! its fixed point v*_s ∈ [v_l, v_t] (v_l = g⁻¹(min a), the lowest state's
//! fixed point; an interior one is a turning point of the characteristics,
//! the pause of run-pause-tumble), where the equation reduces to the
//! algebraic relation Σ_s' Q_ss' T_s' - r T_s + r T_mix,s = -1. Every fixed
//! point is a mesh node, and the box scheme of [`super::backward`] is used
//! cell by cell: on either side of v*_s it integrates outwards from v*_s, the
//! direction in which information travels along the characteristics (the
//! upwind direction for each state on each side), so the scheme stays
//! second order and needs no artificial boundary condition.
//!
//! With T > 0 (Eq. (N32)) every state is absorbed at v_t (T_s(v_t) = 0) and
//! the unbounded (or diverging-drag) side is truncated at v_lo where the
//! lowest state's potential barrier ∫(a_min - g) reaches [`BARRIER`]·T
//! (Eq. (N33)), with a reflecting condition ∂_v T_s = 0 there. The
//! discretisation is exponentially fitted (Eq. (N34)): on each node's
//! three-point stencil the operator T ∂² + b ∂ is exact for 1, v and
//! e^{-b v/T} (b frozen at the node), so it is stable for any cell Péclet
//! number and reduces to upwinding as T → 0.
//!
//! The reset term couples every row to the N reset values R_s = T_s(v_r)
//! (or Σ_j w_j T_s(v_j) for a random target): kept out of the band and
//! added back by an N×N capacitance system (bordering, Eq. (N35)).
//!
//! This is a separate path from the two-state solver of
//! [`super::backward`]: the paper's default noise keeps its bit-identical,
//! faster path there (two interleaved states, 2×2 bordering with its
//! cancellation-free determinant); both share the mesh (`backward::mesh_on`), the
//! band solver and the verification of the answer.

use super::backward::{beyond, mesh_on, BackwardOptions, BackwardSolution, Mesh, Profile};
use super::Problem;
use crate::error::{Error, Result};
use crate::model::noise::chain::Chain;
use crate::model::reset::{NoiseAtReset, Reset};
use crate::model::Drag;
use crate::numerics::band::Band;
use serde::{Deserialize, Serialize};

/// The barrier (in units of T) of the lowest state's potential at the
/// truncation point of a thermal problem (e^{-40} ≈ 4·10⁻¹⁸).
pub const BARRIER: f64 = 40.0;

const METHOD: &str = "mfpt backward solve (noise model)";

/// The mean first-passage time of a noise model's problem at v_0.
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
    /// As the two-state [`BackwardSolution`]: tau_plus starts in the state
    /// of highest level, tau_minus in the state of lowest level.
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

/// The problem as the solver runs it: canonical (upward) frame, its chain,
/// the domain's lower end (v_l at T = 0, the truncation with T > 0) and the
/// mesh.
struct Setup {
    p: Problem,
    swapped: bool,
    chain: Chain,
    lower: f64,
    mesh: Mesh,
    /// Per state: the node of its condition ([`Cond`]).
    cond: Vec<Cond>,
}

/// The condition each state takes (T = 0: Eq. (N31)).
#[derive(Clone, Copy, Debug, PartialEq)]
enum Cond {
    /// T_s(v_t) = 0.
    Absorbed,
    /// Regularity (the algebraic relation) at this node, its fixed point.
    Regular(usize),
}

/// Refuse what the N-state solver does not run, as
/// [`crate::capability::check`] says for the backward equations: schedule
/// modifiers with a noise model, and with T > 0 a drag without
/// [`crate::model::Drag::thermal_backward`] up to T.
/// (`_chain` is the problem's: its temperature is the noise model's.)
pub(super) fn admissible(p: &Problem, _chain: &Chain) -> Result<()> {
    crate::capability::check(crate::capability::Solver::Backward, p.params())
}

/// The truncation point of a thermal problem (canonical frame, Eq. (N33)):
/// below `from` = min(v*_min, v_0, v_r), the first v where the barrier
/// ∫_v^{v*_min} (a_min - g) du of the lowest state reaches `barrier`·T,
/// marched by the midpoint rule with steps of 1 % of the thermal width
/// sqrt(T / g'), halved towards a finite drag bound.
fn truncation(p: &Problem, chain: &Chain, barrier: f64) -> Result<f64> {
    let par = p.params();
    let g = par.drag();
    let t = chain.temperature;
    let amin = chain.levels.iter().cloned().fold(f64::INFINITY, f64::min);
    let bound = par.bounds().0;
    let star = g.inverse(amin);
    let from = star.min(p.v0()).min(par.reset_velocity());
    let (mut v, mut acc) = (star, 0.0);
    let target = barrier * t;
    for _ in 0..1_000_000 {
        let slope = g.derivative(v).max(1e-3);
        let mut h = 0.01 * (t / slope).sqrt();
        if bound.is_finite() {
            h = h.min(0.5 * (v - bound));
        }
        let mid = v - 0.5 * h;
        acc += h * (amin - g.force(mid));
        v -= h;
        if acc >= target && v <= from - 0.01 * (t / slope).sqrt() {
            return Ok(v);
        }
        if bound.is_finite() && v - bound <= 1e-12 * (1.0 + bound.abs()) {
            return Ok(v);
        }
    }
    Err(Error::Numerical {
        method: METHOD,
        reason: format!("no truncation point found below v = {from} (barrier {barrier} T)"),
    })
}

/// The band matrix's bytes: N (cells + 1) rows of 3(2N - 1) + 1 entries.
fn band_bytes(states: usize, cells: usize) -> f64 {
    let n = states as f64;
    8.0 * n * (cells as f64 + 1.0) * (3.0 * (2.0 * n - 1.0) + 1.0)
}

/// The memory budget of the band: that of the two-state solver at its
/// largest mesh ([`BackwardOptions::validate`]: 2·10⁶ cells).
const MAX_BAND_BYTES: f64 = 2e6 * 2.0 * 8.0 * 8.0;

fn setup(problem: &Problem, cells: usize, barrier: f64) -> Result<Setup> {
    let (p, swapped) = problem.canonical();
    let chain = p.params().chain()?;
    admissible(&p, &chain)?;
    if band_bytes(chain.states(), cells) > MAX_BAND_BYTES {
        return Err(Error::invalid(
            "cells",
            cells,
            format!(
                "cells small enough for the band matrix of {} noise states to fit in {:.0} MB \
                 (bytes ≈ 8 N (cells + 1) (6N - 2))",
                chain.states(),
                MAX_BAND_BYTES / 1e6
            ),
        ));
    }
    let g = p.params().drag();
    let thermal = chain.temperature > 0.0;
    let (vl, vu) = p.params().bounds();
    let lower = if thermal {
        truncation(&p, &chain, barrier)?
    } else {
        vl
    };
    // Fixed points inside the domain are nodes (Eq. (N31)).
    let stars: Vec<f64> = chain.levels.iter().map(|&a| g.inverse(a)).collect();
    let mesh = mesh_on(&p, lower, vu, &stars, cells)?;
    let n = mesh.v.len();
    let vt = p.vt();
    let cond = chain
        .levels
        .iter()
        .zip(&stars)
        .map(|(&a, &star)| {
            if thermal || a - g.force(vt) > 0.0 {
                return Cond::Absorbed;
            }
            // The lowest state's fixed point is v_l = node 0.
            let k = if star <= lower {
                0
            } else {
                mesh.v.iter().position(|&x| x == star).unwrap_or(n - 1)
            };
            Cond::Regular(k)
        })
        .collect();
    Ok(Setup {
        p,
        swapped,
        chain,
        lower,
        mesh,
        cond,
    })
}

/// The assembled operator: band A, border columns U_j (the coefficient of
/// the reset value R_j in each row) and right-hand side b of
/// A x + Σ_j U_j R_j = b.
struct Operator {
    band: Band,
    border: Vec<Vec<f64>>,
    rhs: Vec<f64>,
}

impl Setup {
    fn states(&self) -> usize {
        self.chain.states()
    }

    /// Whether unknown `row` (node row / N, state row % N) is absorbed:
    /// T_s(v_t) = 0.
    fn absorbed_row(&self, row: usize) -> bool {
        let ns = self.states();
        let last = row / ns + 1 == self.mesh.v.len();
        last && (self.chain.temperature > 0.0 || self.cond[row % ns] == Cond::Absorbed)
    }

    /// Add `coef`·r·(the reset value state s returns to) to row `row`:
    /// kept: R_s, re-drawn: Σ_j π_j R_j (Eq. (N30)).
    fn reset_term(&self, border: &mut [Vec<f64>], row: usize, s: usize, coef: f64, rate: f64) {
        match self.p.params().reset().noise() {
            NoiseAtReset::Kept => border[s][row] += coef * rate,
            NoiseAtReset::Redrawn => {
                for (j, col) in border.iter_mut().enumerate() {
                    col[row] += coef * rate * self.chain.pi[j];
                }
            }
        }
    }

    /// The coupling Σ_s' Q_ss' x_s'(node) - r x_s(node), times `coef`.
    fn coupling(&self, a: &mut Band, row: usize, s: usize, node: usize, coef: f64, rate: f64) {
        let ns = self.states();
        for (j, &q) in self.chain.q[s].iter().enumerate() {
            let d = if j == s { q - rate } else { q };
            if d != 0.0 {
                let col = ns * node + j;
                a.set(row, col, a.get(row, col) + coef * d);
            }
        }
    }

    /// The box-scheme operator at T = 0 (Eqs. (N30)-(N31)); `src` gives the
    /// source at each (node, state) of "L x = -src".
    fn athermal(&self, rate: f64, src: &dyn Fn(usize, usize) -> f64) -> Operator {
        let ns = self.states();
        let v = &self.mesh.v;
        let n = v.len();
        let g = self.p.params().drag();
        let mut band = Band::new(ns * n, 2 * ns - 1, 2 * ns - 1);
        let mut border = vec![vec![0.0; ns * n]; ns];
        let mut rhs = vec![0.0; ns * n];
        for s in 0..ns {
            let k = match self.cond[s] {
                Cond::Absorbed => n - 1,
                Cond::Regular(k) => k,
            };
            for i in 0..n {
                let row = ns * i + s;
                if i == k {
                    if self.cond[s] == Cond::Absorbed {
                        band.set(row, row, 1.0);
                    } else {
                        self.coupling(&mut band, row, s, i, 1.0, rate);
                        self.reset_term(&mut border, row, s, 1.0, rate);
                        rhs[row] = -src(i, s);
                    }
                    continue;
                }
                // The cell on the side away from the condition node.
                let c = if i < k { i } else { i - 1 };
                let h = v[c + 1] - v[c];
                let b = self.chain.levels[s] - g.force(0.5 * (v[c] + v[c + 1]));
                let (l, u) = (ns * c + s, ns * (c + 1) + s);
                band.set(row, l, -b);
                band.set(row, u, b);
                self.coupling(&mut band, row, s, c, 0.5 * h, rate);
                self.coupling(&mut band, row, s, c + 1, 0.5 * h, rate);
                self.reset_term(&mut border, row, s, h, rate);
                rhs[row] = -0.5 * h * (src(c, s) + src(c + 1, s));
            }
        }
        Operator { band, border, rhs }
    }

    /// The exponentially fitted operator with T > 0 (Eqs. (N32)-(N34)).
    fn thermal(&self, rate: f64, src: &dyn Fn(usize, usize) -> f64) -> Operator {
        let ns = self.states();
        let v = &self.mesh.v;
        let n = v.len();
        let g = self.p.params().drag();
        let t = self.chain.temperature;
        let mut band = Band::new(ns * n, 2 * ns - 1, 2 * ns - 1);
        let mut border = vec![vec![0.0; ns * n]; ns];
        let mut rhs = vec![0.0; ns * n];
        for i in 0..n {
            for s in 0..ns {
                let row = ns * i + s;
                if i == n - 1 {
                    band.set(row, row, 1.0);
                    continue;
                }
                let b = self.chain.levels[s] - g.force(v[i]);
                // Reflecting at the truncation: the ghost node mirrors node 1.
                let (hm, hp) = if i == 0 {
                    (v[1] - v[0], v[1] - v[0])
                } else {
                    (v[i] - v[i - 1], v[i + 1] - v[i])
                };
                let (am, ap) = fitted(t, b, hm, hp);
                let (lo, up) = (ns * i.saturating_sub(1) + s, ns * (i + 1) + s);
                if i == 0 {
                    band.set(row, up, am + ap);
                } else {
                    band.set(row, lo, am);
                    band.set(row, up, ap);
                }
                band.set(row, row, -(am + ap));
                self.coupling(&mut band, row, s, i, 1.0, rate);
                self.reset_term(&mut border, row, s, 1.0, rate);
                rhs[row] = -src(i, s);
            }
        }
        Operator { band, border, rhs }
    }
}

/// The thermal generator on one mesh, for the survival equations of
/// `mfpt::ndist` (Eq. (N49)): the band and border of the fitted operator
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
    let set = setup(problem, cells, BARRIER)?;
    if !(set.chain.temperature > 0.0) {
        return Err(Error::invalid(
            "temperature",
            set.chain.temperature,
            "temperature > 0 for the thermal backward operator",
        ));
    }
    Ok(set.mesh)
}

/// The thermal generator (Eqs. (N32)-(N34)) of the canonical problem `cp`
/// with its chain on `mesh` (node 0 the truncation, the last v_t; from
/// [`thermal_mesh`] or its refinement).
pub(super) fn thermal_generator(cp: &Problem, chain: &Chain, mesh: &Mesh) -> Generator {
    let set = Setup {
        p: *cp,
        swapped: false,
        chain: chain.clone(),
        lower: mesh.v[0],
        mesh: mesh.clone(),
        cond: vec![Cond::Absorbed; chain.states()],
    };
    let op = set.thermal(cp.params().rate(), &|_, _| 0.0);
    let absorbed = (0..op.band.dim()).map(|r| set.absorbed_row(r)).collect();
    Generator {
        band: op.band,
        border: op.border,
        absorbed,
    }
}

/// The weights (α-, α+) of x_{i-1}, x_{i+1} (α_0 = -(α- + α+)) of the
/// fitted stencil of T x'' + b x' at a node with spacings h- and h+
/// (Eq. (N34)): exact for 1, v and e^{-b v / T}, i.e.
/// α+ = b E- / D, α- = -b E+ / D with E- = e^{ρ-} - 1, E+ = e^{-ρ+} - 1,
/// ρ± = b h± / T and D = h+ E- + h- E+. For |ρ±| ≤ 1 the first-order terms
/// of D cancel exactly (h+ ρ- = h- ρ+), so D = h+ φ(ρ-) + h- φ(-ρ+) with
/// φ(x) = e^x - 1 - x from its series; beyond, ratios of expm1's that never
/// overflow. Upwind differences as T → 0, the central ones as b h / T → 0.
fn fitted(t: f64, b: f64, hm: f64, hp: f64) -> (f64, f64) {
    let (rm, rp) = (b * hm / t, b * hp / t);
    if b == 0.0 || (rm.abs() <= 1.0 && rp.abs() <= 1.0) {
        if b == 0.0 {
            let w = 2.0 * t / (hm + hp);
            return (w / hm, w / hp);
        }
        let d = hp * phi(rm) + hm * phi(-rp);
        return (-b * (-rp).exp_m1() / d, b * rm.exp_m1() / d);
    }
    let em = rm.exp_m1(); // e^{ρ-} - 1
    let ep = (-rp).exp_m1(); // e^{-ρ+} - 1
    if b > 0.0 {
        let ap = b / (hp + hm * (ep / em));
        (-ap * (ep / em), ap)
    } else {
        let am = -b / (hm + hp * (em / ep));
        (am, -am * (em / ep))
    }
}

/// φ(x) = e^x - 1 - x for |x| ≤ 1, by its series (no cancellation).
fn phi(x: f64) -> f64 {
    let (mut term, mut sum) = (x, 0.0);
    for k in 2..=20 {
        term *= x / k as f64;
        sum += term;
    }
    sum
}

/// Solve A x + Σ_j U_j R_j = b with R_j = ℓ_j(x) (the reset values): N + 2
/// band solves with one factorisation and an N×N capacitance system
/// (I + E) R = ℓ(A⁻¹ b), E_ij = ℓ_i(A⁻¹ U_j) (Eq. (N35)). As in the
/// two-state solver, the system is formed without cancellation: the whole
/// operator maps the constant 1 to the indicator e of the absorbed rows, so
/// Σ_j A⁻¹U_j = q - 1 with q = A⁻¹ e and the row sums of I + E are
/// ℓ_i(q) + b (b: a random target's mass beyond v_t), sums of non-negative
/// terms where τ is astronomically large ([`m_matrix_solve`]). None when τ
/// exceeds the f64 range.
fn solve_operator(set: &Setup, op: Operator, rate: f64) -> Result<Option<Vec<f64>>> {
    let Operator {
        mut band,
        border,
        rhs,
    } = op;
    band.factor().map_err(|e| Error::Numerical {
        method: METHOD,
        reason: e.to_string(),
    })?;
    let mut x = rhs;
    band.solve(&mut x);
    if rate > 0.0 {
        let ns = set.states();
        let ell = |y: &[f64], j: usize| set.mesh.reset_value(|k| y[ns * k + j]);
        let mut q = vec![0.0; x.len()];
        for (i, qi) in q.iter_mut().enumerate() {
            if set.absorbed_row(i) {
                *qi = 1.0;
            }
        }
        band.solve(&mut q);
        let z: Vec<Vec<f64>> = border
            .into_iter()
            .map(|mut col| {
                band.solve(&mut col);
                col
            })
            .collect();
        let off: Vec<Vec<f64>> = (0..ns)
            .map(|i| (0..ns).map(|j| ell(&z[j], i)).collect())
            .collect();
        let beyond = set.mesh.weights.as_ref().map_or(0.0, |_| beyond(&set.p));
        let sums: Vec<f64> = (0..ns).map(|i| beyond + ell(&q, i)).collect();
        let f: Vec<f64> = (0..ns).map(|i| ell(&x, i)).collect();
        let Some(r) = m_matrix_solve(off, sums, f) else {
            return Ok(None);
        };
        for (zj, rj) in z.iter().zip(&r) {
            x.iter_mut().zip(zj).for_each(|(xi, zi)| *xi -= rj * zi);
        }
    }
    if x.iter().any(|t| !t.is_finite()) {
        return Ok(None);
    }
    Ok(Some(x))
}

/// Solve M R = f for the capacitance matrix M of [`solve_operator`], given
/// its off-diagonal part E_ij ≤ 0 (i ≠ j; the diagonal of `off` is
/// ignored) and its row sums s_i ≥ 0: Gaussian elimination in the order of
/// the states, each pivot formed as (remaining row sum) - Σ(off-diagonal)
/// and each new row sum as s_i + |l| s_k (Grassmann-Taksar-Heyman): every
/// step adds non-negative terms. Where a sign is violated by rounding (a
/// coarse mesh), the plain dense solve of the same system
/// ([`dense_fallback`]). None where a pivot is not positive and finite (τ
/// beyond f64).
#[allow(clippy::needless_range_loop)] // index form mirrors the elimination
fn m_matrix_solve(mut m: Vec<Vec<f64>>, mut s: Vec<f64>, mut f: Vec<f64>) -> Option<Vec<f64>> {
    let n = s.len();
    let off_ok = (0..n).all(|i| (0..n).all(|j| i == j || m[i][j] <= 0.0));
    if !off_ok || s.iter().any(|x| !(*x >= 0.0)) {
        return dense_fallback(m, s, f);
    }
    for k in 0..n {
        m[k][k] = s[k] - (k + 1..n).map(|j| m[k][j]).sum::<f64>();
        if !(m[k][k] > 0.0 && m[k][k].is_finite()) {
            return None;
        }
        for i in k + 1..n {
            let l = m[i][k] / m[k][k];
            for j in k + 1..n {
                if j != i {
                    m[i][j] -= l * m[k][j];
                }
            }
            s[i] -= l * s[k];
            f[i] -= l * f[k];
        }
    }
    let mut r = vec![0.0; n];
    for k in (0..n).rev() {
        let rest: f64 = (k + 1..n).map(|j| m[k][j] * r[j]).sum();
        r[k] = (f[k] - rest) / m[k][k];
    }
    r.iter().all(|x| x.is_finite()).then_some(r)
}

/// M R = f by LU with partial pivoting, M's diagonal formed from the row
/// sums s (the system of [`m_matrix_solve`] without its sign structure).
fn dense_fallback(mut m: Vec<Vec<f64>>, s: Vec<f64>, f: Vec<f64>) -> Option<Vec<f64>> {
    for (i, row) in m.iter_mut().enumerate() {
        let others: f64 = row
            .iter()
            .enumerate()
            .filter(|&(j, _)| j != i)
            .map(|(_, x)| x)
            .sum();
        row[i] = s[i] - others;
    }
    crate::model::noise::chain::solve(&m, &f, METHOD).ok()
}

impl Setup {
    fn solve_source(&self, rate: f64, src: &dyn Fn(usize, usize) -> f64) -> Result<Vec<f64>> {
        let op = if self.chain.temperature > 0.0 {
            self.thermal(rate, src)
        } else {
            self.athermal(rate, src)
        };
        solve_operator(self, op, rate)?.ok_or_else(overflow)
    }

    /// T_s(v_0) and τ from the nodal solution x.
    fn at_start(&self, x: &[f64]) -> (f64, Vec<f64>) {
        let ns = self.states();
        let per: Vec<f64> = (0..ns).map(|s| x[ns * self.mesh.start + s]).collect();
        let tau = per.iter().zip(&self.chain.pi).map(|(t, p)| t * p).sum();
        (tau, per)
    }
}

fn overflow() -> Error {
    Error::Overflow {
        method: METHOD,
        quantity: "the mean first-passage time",
        meaning: "the target is practically never reached",
    }
}

/// Refuse a nodal solution with a negative value beyond rounding (1e-9 of
/// the largest): the mesh did not resolve it.
fn non_negative(x: &[f64]) -> Result<()> {
    let scale = x.iter().fold(0.0f64, |m, t| m.max(t.abs()));
    match x.iter().position(|&t| !(t >= -1e-9 * scale)) {
        None => Ok(()),
        Some(i) => Err(Error::Numerical {
            method: METHOD,
            reason: format!(
                "T = {:e} at unknown {i} is not >= 0: the mesh does not resolve the solution; \
                 refused (more --cells)",
                x[i]
            ),
        }),
    }
}

/// A rigorous lower bound on τ at T = 0 (Eq. (N36)): no state drives faster
/// than the highest level, so reaching v_t takes a reset-free stretch of at
/// least the flow time T* of the highest level from min(v_0, v_r) upwards
/// (canonical frame); with resetting its first occurrence has mean
/// (e^{r T*} - 1)/r. 0 with thermal noise (diffusion has no speed limit).
pub fn lower_bound(problem: &Problem) -> Result<f64> {
    let (p, _) = problem.canonical();
    let chain = p.params().chain()?;
    if chain.temperature > 0.0 {
        return Ok(0.0);
    }
    let amax = chain
        .levels
        .iter()
        .cloned()
        .fold(f64::NEG_INFINITY, f64::max);
    let g = p.params().drag();
    let r = p.params().rate();
    let from = if r > 0.0 {
        let top = p.params().reset().target().support().1.min(p.vt());
        p.v0().max(top)
    } else {
        p.v0()
    };
    let t = g.flow_time(amax, from, p.vt());
    Ok(if r > 0.0 { (r * t).exp_m1() / r } else { t })
}

/// T_s(v) on the mesh of `cells` cells, the truncation barrier `barrier`
/// (thermal only): the solve behind [`solve`], verified (finite, ≥ 0,
/// τ ≥ [`lower_bound`]).
pub fn solve_on(problem: &Problem, cells: usize, barrier: f64) -> Result<NoiseSolution> {
    BackwardOptions::with_cells(cells).validate()?;
    let set = setup(problem, cells, barrier)?;
    let rate = set.p.params().rate();
    let x = set.solve_source(rate, &|_, _| 1.0)?;
    non_negative(&x)?;
    let (tau, per_state) = set.at_start(&x);
    let bound = lower_bound(problem)?;
    if !bound.is_finite() {
        return Err(overflow());
    }
    if !(tau >= bound * (1.0 - 1e-9)) {
        return Err(Error::Numerical {
            method: METHOD,
            reason: format!(
                "tau = {tau:e} is below its lower bound {bound:e}: the mesh does not resolve the \
                 solution; refused (more --cells, or a smaller rate)"
            ),
        });
    }
    Ok(NoiseSolution {
        tau,
        per_state,
        levels: problem.params().chain()?.levels,
        pi: set.chain.pi.clone(),
        cells: set.mesh.v.len() - 1,
        error_estimate: f64::NAN,
        truncation: if set.chain.temperature > 0.0 {
            if set.swapped {
                -set.lower
            } else {
                set.lower
            }
        } else {
            f64::NAN
        },
    })
}

/// The mean first-passage time of a problem with a noise model (its
/// `Params::noise()` is Some) at v_0, with the error estimate of a second
/// solve on half the cells (see [`NoiseSolution::error_estimate`]). The
/// library entry point of `mfpt --method backward` for a noise model.
pub fn solve(problem: &Problem, opts: &BackwardOptions) -> Result<NoiseSolution> {
    let fine = solve_on(problem, opts.cells, BARRIER)?;
    let coarse = solve_on(problem, (opts.cells / 2).max(8), BARRIER)?;
    let diff = (fine.tau - coarse.tau).abs();
    // Two meshes that disagree by more than 10 % resolve nothing (e.g. a
    // target beyond g⁻¹(max a) at a tiny temperature, τ ~ e^{ΔU/T}).
    if !(diff <= 0.1 * fine.tau) {
        return Err(Error::Numerical {
            method: METHOD,
            reason: format!(
                "tau = {:e} on {} cells but {:e} on {}: not resolved; refused (more --cells)",
                fine.tau, fine.cells, coarse.tau, coarse.cells
            ),
        });
    }
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

/// τ(v_0) at r = 0 and dτ/dr at r = 0 for a noise model (the rate in
/// `problem` is ignored): differentiating Eq. (N30) in r gives the r = 0
/// operator on σ_s = ∂_r T_s with source T_mix,s - T_s(v) (Eq. (N30) at
/// r = 0 evaluated with the r = 0 solution).
pub fn rate_derivative_at_zero(problem: &Problem, opts: &BackwardOptions) -> Result<(f64, f64)> {
    opts.validate()?;
    let set = setup(problem, opts.cells, BARRIER)?;
    let ns = set.states();
    let x = set.solve_source(0.0, &|_, _| 1.0)?;
    let ret: Vec<f64> = (0..ns)
        .map(|j| set.mesh.reset_value(|k| x[ns * k + j]))
        .collect();
    let mix: Vec<f64> = match set.p.params().reset().noise() {
        NoiseAtReset::Kept => ret,
        NoiseAtReset::Redrawn => {
            let m: f64 = ret.iter().zip(&set.chain.pi).map(|(a, b)| a * b).sum();
            vec![m; ns]
        }
    };
    let d = set.solve_source(0.0, &|k, s| mix[s] - x[ns * k + s])?;
    Ok((set.at_start(&x).0, set.at_start(&d).0))
}

/// The first two moments of the first-passage time per state at v_0 on
/// `cells` cells: T1_s from Eq. (N30) and T2_s from the same operator with
/// the source 2 T1_s (L T2 = -2 T1), and the cells used. An independent
/// discretisation (the box scheme) for the distribution of
/// `mfpt::distribution` with a noise model to agree with.
pub(super) fn moments_at_start(
    problem: &Problem,
    cells: usize,
) -> Result<(Vec<f64>, Vec<f64>, usize)> {
    BackwardOptions::with_cells(cells).validate()?;
    let set = setup(problem, cells, BARRIER)?;
    let rate = set.p.params().rate();
    let ns = set.states();
    let x = set.solve_source(rate, &|_, _| 1.0)?;
    non_negative(&x)?;
    let y = set.solve_source(rate, &|k, s| 2.0 * x[ns * k + s])?;
    non_negative(&y)?;
    Ok((set.at_start(&x).1, set.at_start(&y).1, set.mesh.v.len() - 1))
}

/// T_s(v) of every state on the mesh of the canonical (upward) problem of
/// `problem` ([`Problem::canonical`], its states in the noise's order):
/// (nodes, T_s at the nodes per state), verified as [`solve_on`].
pub(super) fn canonical_states(
    problem: &Problem,
    cells: usize,
) -> Result<(Vec<f64>, Vec<Vec<f64>>)> {
    BackwardOptions::with_cells(cells).validate()?;
    let set = setup(problem, cells, BARRIER)?;
    let x = set.solve_source(set.p.params().rate(), &|_, _| 1.0)?;
    non_negative(&x)?;
    let ns = set.states();
    let n = set.mesh.v.len();
    let per_state = (0..ns)
        .map(|s| (0..n).map(|k| x[ns * k + s]).collect())
        .collect();
    Ok((set.mesh.v.clone(), per_state))
}

/// T_s(v) on the whole mesh in the user's frame, as a [`Profile`]: tau the
/// mean over π, tau_plus / tau_minus the states of highest / lowest level
/// (verified as [`solve_on`]).
pub fn profile(problem: &Problem, cells: usize, barrier: f64) -> Result<Profile> {
    BackwardOptions::with_cells(cells).validate()?;
    let set = setup(problem, cells, barrier)?;
    let x = set.solve_source(set.p.params().rate(), &|_, _| 1.0)?;
    non_negative(&x)?;
    let ns = set.states();
    let (hi, lo) = extreme_states(&problem.params().chain()?.levels);
    let n = set.mesh.v.len();
    let column = |s: usize| -> Vec<f64> { (0..n).map(|k| x[ns * k + s]).collect() };
    let tau: Vec<f64> = (0..n)
        .map(|k| (0..ns).map(|s| set.chain.pi[s] * x[ns * k + s]).sum())
        .collect();
    let mut out = Profile {
        v: set.mesh.v.clone(),
        tau,
        tau_plus: column(hi),
        tau_minus: column(lo),
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
