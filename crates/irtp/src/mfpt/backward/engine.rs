//! The one engine of the velocity backward equations, written once over
//! the noise's state space (docs/equations.md, "Backward equations for a
//! noise model", Eqs. (N30)-(N36); the paper's noise is its two-state
//! case): N coupled equations for the conditional mean passage times
//! T_s(v), one per noise state s, first order at temperature 0 and second
//! order with thermal noise.
//!
//! The state space is a [`Chain`] (levels a_s, generator Q, stationary law
//! π, temperature) behind a [`Space`]: [`Telegraph`] is the paper's
//! (+Sigma, -Sigma) flipping at rate lambda, [`Finite`] any noise model's
//! chain. Both feed the same assembly; the paper's noise differs only in
//! the trait methods where its bits are kept: where its rows sit in the
//! band (two sub- and super-diagonals instead of 2N - 1), its 2×2 reset
//! correction with the cancellation-free determinant, its refractory
//! period, and the user frame's state order after a reflection.
//!
//! At T = 0 (Eq. (N30)) state s has the drift b_s(v) = a_s - g(v), which
//! decreases in v and vanishes at its fixed point v*_s = g⁻¹(a_s). Each
//! state takes exactly one condition (Eq. (N31)): T_s(v_t) = 0 where
//! b_s(v_t) > 0 (its characteristics enter the target), else regularity at
//! its fixed point v*_s ∈ [v_l, v_t] (v_l = g⁻¹(min a), the lowest state's
//! fixed point; an interior one is a turning point of the characteristics,
//! the pause of run-pause-tumble), where the equation reduces to the
//! algebraic relation Σ_s' Q_ss' T_s' - r T_s + r T_mix,s = -1 (its row
//! is written negated, as the paper's regularity relation at v_l). Every
//! fixed point is a mesh node, and the box scheme integrates each state's
//! equation cell by cell outwards from its condition node (the upwind
//! direction of its characteristics), with both first-order terms imposed
//! at the cell midpoint and the coupling averaged over the two nodes:
//! second order, no artificial boundary condition.
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

use super::{beyond, mesh_on, DriftSign, Mesh};
use crate::error::{Error, Result};
use crate::mfpt::Problem;
use crate::model::noise::chain::Chain;
use crate::model::reset::{NoiseAtReset, Refractory, Reset};
use crate::model::Drag;
use crate::numerics::band::Band;
use crate::numerics::bordered::{responses, Capacitance, LowRank};

/// The barrier (in units of T) of the lowest state's potential at the
/// truncation point of a thermal problem (e^{-40} ≈ 4·10⁻¹⁸).
pub const BARRIER: f64 = 40.0;

/// The noise's state space as the backward equations run it: its chain
/// (canonical, upward frame) and the steps a space may specialise.
pub(crate) trait Space {
    /// Levels, generator, stationary law and temperature.
    fn chain(&self) -> &Chain;
    /// The velocities that must be nodes besides v_0, v_r: the fixed
    /// points of the levels inside the domain.
    fn fixed_points(&self, g: &dyn Fn(f64) -> f64) -> Vec<f64>;
    /// The slot of state s's equations among a node's N rows of the box
    /// scheme.
    fn slot(&self, s: usize) -> usize;
    /// The sub- and super-diagonals of the box scheme's band.
    fn bandwidth(&self) -> usize;
    /// The state of the user's frame that canonical state s is.
    fn user_state(&self, s: usize, swapped: bool) -> usize;
    /// The relative size of a negative T that rounding explains.
    fn rounding(&self) -> f64;
    /// Fold an exponential refractory period into the border columns and
    /// the right-hand side (mean only: `mean_only` is false for another
    /// source).
    fn refractory(&self, p: &Problem, m: &Mesh, mean_only: bool, op: &mut Operator) -> Result<()>;
    /// Add the reset values back: x = y0 - Σ_j R_j A⁻¹U_j with R from the
    /// capacitance system; `q` = A⁻¹ e (e: the absorbed rows), `beyond` a
    /// random target's mass past v_t. False when it is singular or
    /// overflows.
    fn correct(
        &self,
        a: &Band,
        x: &mut [f64],
        border: Vec<Vec<f64>>,
        q: &[f64],
        m: &Mesh,
        beyond: f64,
    ) -> bool;
}

/// The paper's noise: states 0 = +Sigma, 1 = -Sigma, flips at rate lambda.
pub(crate) struct Telegraph(Chain);

impl Telegraph {
    /// The paper's noise of `p` (canonical frame).
    pub(crate) fn of(p: &Problem) -> Self {
        let (s, l) = (p.params().sigma(), p.params().lambda());
        Telegraph(Chain {
            levels: vec![s, -s],
            q: vec![vec![-l, l], vec![l, -l]],
            exit: vec![l, l],
            pi: vec![0.5, 0.5],
            temperature: 0.0,
        })
    }
}

impl Space for Telegraph {
    fn chain(&self) -> &Chain {
        &self.0
    }
    /// ±Sigma's fixed points are the edges v_l, v_u.
    fn fixed_points(&self, _: &dyn Fn(f64) -> f64) -> Vec<f64> {
        vec![]
    }
    /// The + equation of cell i in the row of node i's - unknown, the -
    /// equation in that of node i + 1's + unknown: two sub- and
    /// super-diagonals.
    fn slot(&self, s: usize) -> usize {
        1 - s
    }
    fn bandwidth(&self) -> usize {
        2
    }
    /// A reflection swaps ±Sigma.
    fn user_state(&self, s: usize, swapped: bool) -> usize {
        if swapped {
            1 - s
        } else {
            s
        }
    }
    fn rounding(&self) -> f64 {
        1e-12
    }
    fn refractory(&self, p: &Problem, m: &Mesh, mean_only: bool, op: &mut Operator) -> Result<()> {
        refractory(p, m, mean_only, op)
    }
    fn correct(
        &self,
        a: &Band,
        x: &mut [f64],
        border: Vec<Vec<f64>>,
        q: &[f64],
        m: &Mesh,
        beyond: f64,
    ) -> bool {
        let [cp, cm]: [Vec<f64>; 2] = border.try_into().expect("two border columns");
        match &m.weights {
            None => reset_correction(a, x, cp, cm, q, m.reset),
            Some(w) => spread_correction(a, x, cp, cm, q, w, beyond),
        }
    }
}

/// A noise model's finite-state chain.
pub(crate) struct Finite(pub(crate) Chain);

impl Space for Finite {
    fn chain(&self) -> &Chain {
        &self.0
    }
    fn fixed_points(&self, inverse: &dyn Fn(f64) -> f64) -> Vec<f64> {
        self.0.levels.iter().map(|&a| inverse(a)).collect()
    }
    fn slot(&self, s: usize) -> usize {
        s
    }
    fn bandwidth(&self) -> usize {
        2 * self.0.states() - 1
    }
    fn user_state(&self, s: usize, _: bool) -> usize {
        s
    }
    fn rounding(&self) -> f64 {
        1e-9
    }
    fn refractory(&self, p: &Problem, m: &Mesh, mean_only: bool, op: &mut Operator) -> Result<()> {
        let Some(mean) = refractory_mean(p, mean_only)? else {
            return Ok(());
        };
        chain_refractory(&self.0, mean, m, op)
    }
    fn correct(
        &self,
        a: &Band,
        x: &mut [f64],
        border: Vec<Vec<f64>>,
        q: &[f64],
        m: &Mesh,
        beyond: f64,
    ) -> bool {
        chain_correction(self.0.states(), a, x, border, q, m, beyond)
    }
}

/// The space of `p` (canonical frame): the paper's noise or its model's chain.
pub(crate) fn space_of(p: &Problem) -> Result<Box<dyn Space>> {
    Ok(match p.params().noise() {
        None => Box::new(Telegraph::of(p)),
        Some(_) => Box::new(Finite(p.params().chain()?)),
    })
}

/// The condition each state takes (T = 0: Eq. (N31)).
#[derive(Clone, Copy, Debug, PartialEq)]
enum Cond {
    /// T_s(v_t) = 0.
    Absorbed,
    /// Regularity (the algebraic relation) at this node, its fixed point.
    Regular(usize),
}

/// The problem as the engine runs it: canonical (upward) frame, its state
/// space, the domain's lower end (v_l at T = 0, the truncation with T > 0),
/// the mesh and each state's condition.
pub(crate) struct Setup {
    pub(crate) p: Problem,
    pub(crate) swapped: bool,
    pub(crate) space: Box<dyn Space>,
    pub(crate) lower: f64,
    pub(crate) mesh: Mesh,
    cond: Vec<Cond>,
    sign: DriftSign,
}

/// The assembled operator: band A, border columns U_j (the coefficient of
/// the reset value R_j in each row), right-hand side b of
/// A x + Σ_j U_j R_j = b, and the rows of the absorbed conditions.
pub(crate) struct Operator {
    pub(crate) band: Band,
    pub(crate) border: Vec<Vec<f64>>,
    pub(crate) rhs: Vec<f64>,
    pub(crate) absorbed: Vec<bool>,
}

/// The band matrix's bytes: N (cells + 1) rows of 3 k + 1 entries (k the
/// half bandwidth: 2N - 1 for a chain, 2 for the paper's noise).
fn band_bytes(states: usize, bandwidth: usize, cells: usize) -> f64 {
    let n = states as f64;
    8.0 * n * (cells as f64 + 1.0) * (3.0 * bandwidth as f64 + 1.0)
}

/// Nodes of an operator's assembly between two polls of the stop request.
const STOP_POLL_NODES: usize = 1 << 14;

/// Whether the assembly at node `i` must stop (see [`Setup::operator`]).
fn stop_due(i: usize) -> bool {
    i % STOP_POLL_NODES == 0 && crate::stop::stop_requested()
}

/// The memory budget of the band (256 MB), which the paper's noise at its
/// largest mesh fits ([`super::BackwardOptions::validate`]: 2·10⁶ cells).
const MAX_BAND_BYTES: f64 = 2e6 * 2.0 * 8.0 * 8.0;

/// The setup of `problem` on `cells` cells (thermal: truncated at
/// `barrier`), after what [`crate::capability::check`] refuses.
pub(crate) fn setup(
    problem: &Problem,
    cells: usize,
    barrier: f64,
    sign: DriftSign,
) -> Result<Setup> {
    // The protocol with a noise model (the paper's noise: its callers'
    // checks, e.g. a default t-max estimate of a scheduled clock).
    if problem.params().noise().is_some() {
        crate::capability::check(crate::capability::Solver::Backward, problem.params())?;
    }
    let (p, swapped) = problem.canonical();
    let space = space_of(&p)?;
    let chain = space.chain();
    if band_bytes(chain.states(), space.bandwidth(), cells) > MAX_BAND_BYTES {
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
        truncation(&p, chain, barrier)?
    } else {
        vl
    };
    crate::parallel::check_stop()?;
    // Fixed points inside the domain are nodes (Eq. (N31)).
    let stars = space.fixed_points(&|a| g.inverse(a));
    let mesh = mesh_on(&p, lower, vu, &stars, cells)?;
    crate::parallel::check_stop()?;
    let cond = conditions(&p, chain, &mesh, lower);
    Ok(Setup {
        p,
        swapped,
        space,
        lower,
        mesh,
        cond,
        sign,
    })
}

/// Each state's condition (Eq. (N31)): absorbed where its drift at v_t is
/// positive (every state with T > 0), else regular at its fixed point (the
/// lowest state's is v_l = node 0).
fn conditions(p: &Problem, chain: &Chain, mesh: &Mesh, lower: f64) -> Vec<Cond> {
    let g = p.params().drag();
    let n = mesh.v.len();
    chain
        .levels
        .iter()
        .map(|&a| {
            if chain.temperature > 0.0 || a - g.force(p.vt()) > 0.0 {
                return Cond::Absorbed;
            }
            let star = g.inverse(a);
            let k = if star <= lower {
                0
            } else {
                mesh.v.iter().position(|&x| x == star).unwrap_or(n - 1)
            };
            Cond::Regular(k)
        })
        .collect()
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

pub(crate) const METHOD: &str = "mfpt backward solve";

impl Setup {
    /// The canonical setup of `cp` with the chain `chain` on `mesh` (the
    /// thermal generator of the distribution, every state absorbed).
    pub(crate) fn on_mesh(cp: &Problem, chain: &Chain, mesh: &Mesh) -> Setup {
        Setup {
            p: cp.clone(),
            swapped: false,
            space: Box::new(Finite(chain.clone())),
            lower: mesh.v[0],
            mesh: mesh.clone(),
            cond: vec![Cond::Absorbed; chain.states()],
            sign: DriftSign::Simulated,
        }
    }

    pub(crate) fn states(&self) -> usize {
        self.space.chain().states()
    }

    pub(crate) fn chain(&self) -> &Chain {
        self.space.chain()
    }

    /// Add `coef`·r·(the reset value state s returns to) to row `row`:
    /// kept: R_s, re-drawn: Σ_j π_j R_j (Eq. (N30)).
    fn reset_term(&self, border: &mut [Vec<f64>], row: usize, s: usize, coef: f64, rate: f64) {
        match self.p.params().reset().noise() {
            NoiseAtReset::Kept => border[s][row] += coef * rate,
            NoiseAtReset::Redrawn => {
                for (j, col) in border.iter_mut().enumerate() {
                    col[row] += coef * rate * self.chain().pi[j];
                }
            }
        }
    }

    /// The coupling Σ_s' Q_ss' x_s'(node) - r x_s(node), times `coef`.
    fn coupling(&self, a: &mut Band, row: usize, s: usize, node: usize, coef: f64, rate: f64) {
        let ns = self.states();
        for (j, &q) in self.chain().q[s].iter().enumerate() {
            let d = if j == s { q - rate } else { q };
            if d != 0.0 {
                let col = ns * node + j;
                a.set(row, col, a.get(row, col) + coef * d);
            }
        }
    }

    fn empty(&self, kl: usize) -> Operator {
        let (ns, n) = (self.states(), self.mesh.v.len());
        Operator {
            band: Band::new(ns * n, kl, kl),
            border: vec![vec![0.0; ns * n]; ns],
            rhs: vec![0.0; ns * n],
            absorbed: vec![false; ns * n],
        }
    }

    /// The box-scheme operator at T = 0 (Eqs. (N30)-(N31)); `src` gives the
    /// source at each (node, state) of "L x = -src". Every entry is written
    /// once: on the row of state s at cell c, ∓b + (h/2)(Q_ss - r) on its
    /// own unknowns at c and c + 1, (h/2) Q_ss' on state s' there.
    fn athermal(&self, rate: f64, src: &dyn Fn(usize, usize) -> f64) -> Operator {
        let ns = self.states();
        let v = &self.mesh.v;
        let n = v.len();
        let mut op = self.empty(self.space.bandwidth());
        let chain = self.chain();
        // The drag at each cell's midpoint (shared by the states).
        let g = self.p.params().drag();
        let force: Vec<f64> = v.windows(2).map(|c| g.force(0.5 * (c[0] + c[1]))).collect();
        let slots: Vec<usize> = (0..ns).map(|s| self.space.slot(s)).collect();
        let reset = self.reset_weights();
        for i in 0..n {
            if stop_due(i) {
                break;
            }
            for s in 0..ns {
                let row = ns * i + slots[s];
                let (k, absorbed) = match self.cond[s] {
                    Cond::Absorbed => (n - 1, true),
                    Cond::Regular(k) => (k, false),
                };
                if i == k && absorbed {
                    op.band.set(row, ns * i + s, 1.0);
                    op.absorbed[row] = true;
                    continue;
                }
                if i == k {
                    // Minus the generator, as the regularity relation.
                    for (j, &q) in chain.q[s].iter().enumerate() {
                        let d = if j == s { q - rate } else { q };
                        if d != 0.0 {
                            op.band.set(row, ns * i + j, -d);
                        }
                    }
                    for (j, &w) in reset[s].iter().enumerate().filter(|e| *e.1 != 0.0) {
                        op.border[j][row] = -rate * w;
                    }
                    op.rhs[row] = src(i, s);
                    continue;
                }
                // The cell on the side away from the condition node.
                let c = if i < k { i } else { i - 1 };
                let h = v[c + 1] - v[c];
                let b = match self.sign {
                    DriftSign::Simulated => chain.levels[s] - force[c],
                    DriftSign::PaperPrinted => force[c] + chain.levels[s],
                };
                let hh = 0.5 * h;
                for (j, &q) in chain.q[s].iter().enumerate() {
                    let (l, u) = (ns * c + j, ns * (c + 1) + j);
                    if j == s {
                        let d = hh * (q - rate);
                        op.band.set(row, l, -b + d);
                        op.band.set(row, u, b + d);
                    } else if q != 0.0 {
                        op.band.set(row, l, hh * q);
                        op.band.set(row, u, hh * q);
                    }
                }
                for (j, &w) in reset[s].iter().enumerate().filter(|e| *e.1 != 0.0) {
                    op.border[j][row] = h * rate * w;
                }
                op.rhs[row] = -0.5 * h * (src(c, s) + src(c + 1, s));
            }
        }
        op
    }

    /// Per state s, the weight of each R_j in the reset value s returns to
    /// (kept: R_s alone, re-drawn: Σ_j π_j R_j; Eq. (N30)); a border entry
    /// is (coefficient · r) · weight, the weight 1 dropped.
    fn reset_weights(&self) -> Vec<Vec<f64>> {
        let ns = self.states();
        match self.p.params().reset().noise() {
            NoiseAtReset::Kept => (0..ns)
                .map(|s| (0..ns).map(|j| if j == s { 1.0 } else { 0.0 }).collect())
                .collect(),
            NoiseAtReset::Redrawn => vec![self.chain().pi.clone(); ns],
        }
    }

    /// The exponentially fitted operator with T > 0 (Eqs. (N32)-(N34)):
    /// each unknown's equation in its own row.
    fn thermal(&self, rate: f64, src: &dyn Fn(usize, usize) -> f64) -> Operator {
        let ns = self.states();
        let v = &self.mesh.v;
        let n = v.len();
        let g = self.p.params().drag();
        let t = self.chain().temperature;
        let mut op = self.empty(2 * ns - 1);
        for i in 0..n {
            if stop_due(i) {
                break;
            }
            for s in 0..ns {
                let row = ns * i + s;
                if i == n - 1 {
                    op.band.set(row, row, 1.0);
                    op.absorbed[row] = true;
                    continue;
                }
                let b = self.chain().levels[s] - g.force(v[i]);
                // Reflecting at the truncation: the ghost node mirrors node 1.
                let (hm, hp) = if i == 0 {
                    (v[1] - v[0], v[1] - v[0])
                } else {
                    (v[i] - v[i - 1], v[i + 1] - v[i])
                };
                let (am, ap) = fitted(t, b, hm, hp);
                let (lo, up) = (ns * i.saturating_sub(1) + s, ns * (i + 1) + s);
                if i == 0 {
                    op.band.set(row, up, am + ap);
                } else {
                    op.band.set(row, lo, am);
                    op.band.set(row, up, ap);
                }
                op.band.set(row, row, -(am + ap));
                self.coupling(&mut op.band, row, s, i, 1.0, rate);
                self.reset_term(&mut op.border, row, s, 1.0, rate);
                op.rhs[row] = -src(i, s);
            }
        }
        op
    }

    /// The operator of this setup at `rate` with source `src`. A stop
    /// request (polled every `STOP_POLL_NODES` nodes: millions of nodes
    /// take a second) ends the assembly early: the operator is then
    /// unfinished, for the caller's next poll (or the factorisation's,
    /// [`Band::factor_for`]) to discard.
    pub(crate) fn operator(&self, rate: f64, src: &dyn Fn(usize, usize) -> f64) -> Operator {
        if self.chain().temperature > 0.0 {
            self.thermal(rate, src)
        } else {
            self.athermal(rate, src)
        }
    }

    /// The nodal solution x (unknown N k + s: state s at node k) of
    /// "L x = -src" at `rate` (`mean_only`: the source is 1, where a
    /// refractory period runs); None when it exceeds the f64 range.
    pub(crate) fn solve(
        &self,
        rate: f64,
        mean_only: bool,
        src: &dyn Fn(usize, usize) -> f64,
    ) -> Result<Option<Vec<f64>>> {
        let mut op = self.operator(rate, src);
        crate::parallel::check_stop()?;
        if rate > 0.0 {
            self.space
                .refractory(&self.p, &self.mesh, mean_only, &mut op)?;
        }
        let Operator {
            mut band,
            border,
            rhs,
            absorbed,
        } = op;
        band.factor_for(METHOD)?;
        crate::parallel::check_stop()?;
        let mut x = rhs;
        band.solve(&mut x);
        crate::parallel::check_stop()?;
        if rate > 0.0 {
            let mut q: Vec<f64> = absorbed
                .iter()
                .map(|&a| if a { 1.0 } else { 0.0 })
                .collect();
            band.solve(&mut q);
            let beyond = self.mesh.weights.as_ref().map_or(0.0, |_| beyond(&self.p));
            if !self
                .space
                .correct(&band, &mut x, border, &q, &self.mesh, beyond)
            {
                return Ok(None);
            }
        }
        if x.iter().any(|t| !t.is_finite()) {
            return Ok(None);
        }
        Ok(Some(x))
    }

    /// State s's column of a nodal solution.
    pub(crate) fn column(&self, x: &[f64], s: usize) -> Vec<f64> {
        let ns = self.states();
        (0..self.mesh.v.len()).map(|k| x[ns * k + s]).collect()
    }

    /// T_s(v_0) per canonical state and their mean over π.
    pub(crate) fn at_start(&self, x: &[f64]) -> (f64, Vec<f64>) {
        let ns = self.states();
        let per: Vec<f64> = (0..ns).map(|s| x[ns * self.mesh.start + s]).collect();
        (self.mean(&per), per)
    }

    /// Σ_s π_s y_s.
    pub(crate) fn mean(&self, y: &[f64]) -> f64 {
        y.iter().zip(&self.chain().pi).map(|(t, p)| t * p).sum()
    }

    /// The reset value each state returns to (kept: its own, re-drawn:
    /// the mean over π) of a nodal solution x.
    pub(crate) fn returns(&self, x: &[f64]) -> Vec<f64> {
        let ns = self.states();
        let ret: Vec<f64> = (0..ns)
            .map(|j| self.mesh.reset_value(|k| x[ns * k + j]))
            .collect();
        match self.p.params().reset().noise() {
            NoiseAtReset::Kept => ret,
            NoiseAtReset::Redrawn => vec![self.mean(&ret); ns],
        }
    }

    /// The value each state's reset leads to, of a nodal solution x of the
    /// mean: [`Self::returns`], and with an exponential refractory period
    /// of mean M the held values T_R = P R + W M (docs/equations.md,
    /// (R11); W the reset's mass below v_t, the rest a passage at the
    /// reset itself). Refused for a fixed refractory period.
    pub(crate) fn held_returns(&self, x: &[f64]) -> Result<Vec<f64>> {
        let ret = self.returns(x);
        let Some(mean) = refractory_mean(&self.p, true)? else {
            return Ok(ret);
        };
        let p = held_transfer(self.chain(), mean)?;
        let wsum: f64 = self.mesh.weights.as_ref().map_or(1.0, |w| w.iter().sum());
        Ok(p.iter()
            .map(|row| row.iter().zip(&ret).map(|(a, b)| a * b).sum::<f64>() + wsum * mean)
            .collect())
    }

    /// Refuse a nodal solution with a negative value beyond rounding
    /// ([`Space::rounding`] of the largest): the mesh did not resolve it.
    pub(crate) fn non_negative(&self, x: &[f64]) -> Result<()> {
        let scale = x.iter().fold(0.0f64, |m, t| m.max(t.abs()));
        let floor = -self.space.rounding() * scale;
        let ns = self.states();
        match x.iter().position(|&t| !(t >= floor)) {
            None => Ok(()),
            Some(i) => Err(Error::Numerical {
                method: METHOD,
                reason: format!(
                    "T = {:e} (state {}) at v = {:e} is not >= 0: the mesh does not resolve the \
                     solution; refused (more --cells)",
                    x[i],
                    i % ns,
                    self.mesh.v[i / ns]
                ),
            }),
        }
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

/// An exponential refractory period with the paper's noise
/// (docs/equations.md, entry (R6)): the held phase's values T_R(s) solve
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
fn refractory(p: &Problem, m: &Mesh, mean_only: bool, op: &mut Operator) -> Result<()> {
    let Some(mean) = refractory_mean(p, mean_only)? else {
        return Ok(());
    };
    let (k, l) = (1.0 / mean, p.params().lambda());
    let det = k + 2.0 * l;
    let (d, o) = ((k + l) / det, l / det);
    let wsum: f64 = m.weights.as_ref().map_or(1.0, |w| w.iter().sum());
    let (b, [cp, cm]) = (&mut op.rhs, &mut op.border[..]) else {
        unreachable!("the paper's noise has two border columns")
    };
    for i in 0..b.len() {
        let (a, c) = (cp[i], cm[i]);
        b[i] -= (a + c) * wsum * mean;
        cp[i] = d * a + o * c;
        cm[i] = o * a + d * c;
    }
    Ok(())
}

/// The mean M of an exponential refractory period of `p` (None without
/// one); refused for a fixed one and for another source than the mean's.
fn refractory_mean(p: &Problem, mean_only: bool) -> Result<Option<f64>> {
    let mean = match p.params().schedule().refractory {
        None => return Ok(None),
        Some(Refractory::Exp { mean }) => mean,
        Some(r @ Refractory::Fixed { .. }) => {
            return Err(Error::invalid(
                "refractory",
                r.spec(),
                "exp:mean=M for the backward equations",
            ))
        }
    };
    if !mean_only {
        return Err(Error::invalid(
            "refractory",
            format!("exp:mean={mean}"),
            "none for the first-passage moments and distributions (the mean, mfpt --method backward and mfpt scan, runs it)",
        ));
    }
    Ok(Some(mean))
}

/// An exponential refractory period with a noise model's chain
/// (docs/equations.md, entry (R11)): the held values T_R(s) solve
/// Σ_s' Q_ss' T_R(s') + κ (T(u, s) - T_R(s)) = -1, i.e.
/// T_R = P T(u) + 1/κ with P = κ (κ I - Q)⁻¹ (non-negative, rows summing
/// to 1 as Q 1 = 0). The border columns c_j (the coefficient of R_j)
/// become c'_k = Σ_j c_j P_jk, whose sum is unchanged (the identity
/// [`chain_correction`] relies on), and b -= (Σ_j c_j) W/κ as for the
/// paper's noise ([`refractory`]).
fn chain_refractory(chain: &Chain, mean: f64, m: &Mesh, op: &mut Operator) -> Result<()> {
    let p = held_transfer(chain, mean)?;
    let wsum: f64 = m.weights.as_ref().map_or(1.0, |w| w.iter().sum());
    let mut c = vec![0.0; chain.states()];
    for i in 0..op.rhs.len() {
        for (cj, col) in c.iter_mut().zip(&op.border) {
            *cj = col[i];
        }
        op.rhs[i] -= c.iter().sum::<f64>() * wsum * mean;
        for (kk, col) in op.border.iter_mut().enumerate() {
            col[i] = c.iter().zip(&p).map(|(cj, row)| cj * row[kk]).sum();
        }
    }
    Ok(())
}

/// The held phase's transfer matrix P = κ (κ I - Q)⁻¹ of `chain` for a
/// refractory period of mean M = 1/κ (docs/equations.md, (R11)): the held
/// values are T_R = P T(u) + M. Non-negative, rows summing to 1.
fn held_transfer(chain: &Chain, mean: f64) -> Result<Vec<Vec<f64>>> {
    let ns = chain.states();
    let k = 1.0 / mean;
    // Deflated, well posed as κ → 0: κ I - Q + 1 πᵀ is nonsingular for
    // every κ ≥ 0, and column c of P is π_c 1 + κ (κ I - Q + 1 πᵀ)⁻¹
    // (e_c - π_c 1) (P 1 = 1; the solve keeps πᵀ = 0 on πᵀ-free data).
    let pi = &chain.pi;
    let a: Vec<Vec<f64>> = (0..ns)
        .map(|i| {
            (0..ns)
                .map(|j| if i == j { k } else { 0.0 } - chain.q[i][j] + pi[j])
                .collect()
        })
        .collect();
    let mut p = vec![vec![0.0; ns]; ns];
    for c in 0..ns {
        let e: Vec<f64> = (0..ns)
            .map(|i| f64::from(u8::from(i == c)) - pi[c])
            .collect();
        let col = crate::model::noise::chain::solve(&a, &e, METHOD)?;
        for (row, x) in p.iter_mut().zip(col) {
            row[c] = pi[c] + k * x;
        }
    }
    Ok(p)
}

/// The reset terms of the paper's noise by two extra solves with the
/// factored matrix ([`LowRank`]): x = y0 - R+ y1 - R- y2 with y1 = A⁻¹c+,
/// y2 = A⁻¹c-, and R± = x±(v_r) at the reset node. With q = A⁻¹e_last
/// (tau+(v_t) = 1, no source) one has exactly 1 + y1 + y2 = q (A applied
/// to the constant 1 gives -(c+ + c-) + e_last), so the 2×2 system is
/// written in sums of non-negative terms only: no cancellation even when
/// tau ~ e^{r T} is astronomically large. Returns false when the 2×2
/// system is singular or overflows (tau beyond the f64 range).
fn reset_correction(
    a: &Band,
    x: &mut [f64],
    cp: Vec<f64>,
    cm: Vec<f64>,
    q: &[f64],
    reset: usize,
) -> bool {
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
    q: &[f64],
    w: &[f64],
    beyond: f64,
) -> bool {
    let z = responses(|y| a.solve(y), [cp, cm]);
    let ell = |y: &[f64], s: usize| -> f64 {
        w.iter().enumerate().map(|(j, wj)| wj * y[2 * j + s]).sum()
    };
    // -ℓ+(y2), -ℓ-(y1) >= 0; m11 = 1 + ℓ+(y1), m22 = 1 + ℓ-(y2).
    let (y2p, y1m) = (-ell(&z[1], 0), -ell(&z[0], 1));
    let (m11, m22) = (beyond + ell(q, 0) + y2p, beyond + ell(q, 1) + y1m);
    let det = (beyond + ell(q, 0)) * (beyond + ell(q, 1))
        + (beyond + ell(q, 0)) * y1m
        + (beyond + ell(q, 1)) * y2p;
    if !(det > 0.0) || !det.is_finite() {
        return false;
    }
    let s = Capacitance::with_det([[m11, -y2p], [-y1m, m22]], det);
    let f = [ell(x, 0), ell(x, 1)];
    LowRank::new(z, s).correct(x, f);
    true
}

/// The reset terms of an N-state chain: N band solves with the factored
/// matrix and an N×N capacitance system (I + E) R = ℓ(A⁻¹ b),
/// E_ij = ℓ_i(A⁻¹ U_j) (Eq. (N35)). As for the paper's noise, the system is
/// formed without cancellation: the whole operator maps the constant 1 to
/// the indicator e of the absorbed rows, so Σ_j A⁻¹U_j = q - 1 and the row
/// sums of I + E are ℓ_i(q) + b (b: a random target's mass beyond v_t),
/// sums of non-negative terms where τ is astronomically large
/// ([`m_matrix_solve`]). False when τ exceeds the f64 range.
fn chain_correction(
    ns: usize,
    a: &Band,
    x: &mut [f64],
    border: Vec<Vec<f64>>,
    q: &[f64],
    m: &Mesh,
    beyond: f64,
) -> bool {
    let ell = |y: &[f64], j: usize| m.reset_value(|k| y[ns * k + j]);
    let z: Vec<Vec<f64>> = border
        .into_iter()
        .map(|mut col| {
            a.solve(&mut col);
            col
        })
        .collect();
    let off: Vec<Vec<f64>> = (0..ns)
        .map(|i| (0..ns).map(|j| ell(&z[j], i)).collect())
        .collect();
    let sums: Vec<f64> = (0..ns).map(|i| beyond + ell(q, i)).collect();
    let f: Vec<f64> = (0..ns).map(|i| ell(x, i)).collect();
    let Some(r) = m_matrix_solve(off, sums, f) else {
        return false;
    };
    for (zj, rj) in z.iter().zip(&r) {
        x.iter_mut().zip(zj).for_each(|(xi, zi)| *xi -= rj * zi);
    }
    true
}

/// Solve M R = f for the capacitance matrix M of [`chain_correction`],
/// given its off-diagonal part E_ij ≤ 0 (i ≠ j; the diagonal of `off` is
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
