//! A flow segment as two table lookups: the inverse of the flow potential
//! and the deficit integrals, both tabulated as functions of the potential.
//!
//! Along the flow dv/dt = s - g(v) (Eq. (5)) the potential Φ of
//! [`FlowMap::potential`] falls at the constant rate k = g'(v*):
//! Φ(t) = Φ(0) - k t. In the canonical frame (u = |v* - v| ∈ (0, 2|v*|],
//! the whole admissible interval of Eqs. (8)-(10)) this table holds, on
//! pieces in Φ (uniform cells, each halved as often as it needs), Chebyshev series of
//! - L(Φ) = ln u, smooth (Φ = ln u + R(u) with R smooth; ln u itself, not
//!   ln u - Φ, so that u keeps its relative accuracy where Φ is large),
//! - the antiderivatives Q_k(Φ) = (1/k) ∫_{-∞}^{Φ} u^k dΦ', k = 1, 2,
//!
//! so the velocity after time t is u = exp(L(Φ - k t)) (one
//! table sum and one exponential, no iteration), and the deficit integrals
//! of [`Drag::flow_deficits`] are I_k = Q_k(Φ_a) - Q_k(Φ_b), since
//! dt = -dΦ/k. Below the first piece (u < ulp(v*)/4, where v* - u rounds
//! to v*) the approach to v* is the exponential u ∝ e^Φ, handled in
//! closed form. Where g'(0) = ∞ (g ~ |v|^n, n < 1) Φ has a |v|^(1+n)
//! kink at v = 0 (u = v*), a cell boundary: the two cells next to it are
//! tabulated in t with Φ = Φ_0 ∓ h (1 - t)^8 or Φ_0 + h t^8 (three square
//! roots per lookup there), in which the kink's powers |Φ - Φ_0|^(1+jn)
//! become t^(8(1+jn)): smooth for n = 1/2, and of high order (resolved by a
//! few halvings) for any n. The nodes are solved once from the law's own potential
//! ([`FlowMap::potential_at_distance`]) to rounding, and the pieces are
//! halved until every series is resolved to the rounding noise of its
//! values: the lookups agree with the iterative flow to rounding (relative
//! error about ε |Φ| in u, a time error of ε |Φ| / k).
//!
//! The same tables serve a fixed point inside the velocity interval (a
//! noise level other than the paper's ±Sigma, the pause's v* = 0):
//! [`PotentialTable::side`] tabulates the distance on either side of v*,
//! up to any length (the far side, v beyond v*, with the law's potential
//! and drift at a negative distance).

use super::{Drag, FlowMap};
use crate::numerics::chebyshev::{self, power_sum, to_power, Adaptive, Piece, Refine};
use crate::numerics::root;
use std::sync::Arc;

/// Coefficients kept per series: pieces are refined until every series is
/// resolved at degree 11 (summed in powers of the unit variable by
/// Estrin's scheme: short dependency chains).
const M: usize = 12;

/// Most pieces a table may have (a law or parameter that needs more uses
/// the iterative solve): uniform cells of width ≤ 1 in Φ, each split into
/// 2^d equal pieces as its resolution needs.
const MAX_PIECES: usize = 4096;

/// The most pieces for `drag`: [`MAX_PIECES`] over the law's
/// [`Drag::evaluation_weight`], so the attempt costs at most what 4096
/// pieces of a shipped law cost (every piece solves its nodes with g): an
/// expression 10 times dearer to evaluate gets 409 pieces before the
/// iterative solve takes over (measured: a failing attempt on
/// `cosh(asinh(v)^5)` at Sigma = 5e206 took 18 s at 4096 pieces).
fn max_pieces<D: Drag>(drag: &D) -> usize {
    let w = drag.evaluation_weight();
    if w > 1.0 {
        ((MAX_PIECES as f64 / w) as usize).max(64)
    } else {
        MAX_PIECES
    }
}

/// One point of a flow segment: the velocity, its potential Φ and the
/// deficit antiderivatives (real frame: I_k(a → b) = q_k(a) - q_k(b)).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FlowPoint {
    /// Velocity.
    pub v: f64,
    /// Flow potential Φ(v).
    pub phi: f64,
    /// Antiderivatives of the deficit integrals (v* - v)^k dt, k = 1, 2.
    pub q: [f64; 2],
}

/// The canonical tables (see the module docs).
#[derive(Debug)]
struct Inner<F> {
    /// Canonical flow (s = |s| > 0).
    flow: F,
    /// Canonical fixed point v* > 0 and k = g'(v*).
    vs: f64,
    k: f64,
    /// Φ at the first piece's left end, and u there.
    phi_lo: f64,
    u_lo: f64,
    /// Inverse width in Φ of the uniform cells.
    inv_h: f64,
    /// The cell above a kink of Φ where g'(0) = ∞: it and the cell below
    /// are tabulated in t ([`Var`]); usize::MAX for none.
    kink: usize,
    /// Per cell: its first piece and its number of (equal) pieces.
    cells: Vec<(u32, f64)>,
    /// Per piece: series of L and of Q_1, Q_2 (relative to the piece's left
    /// end), interleaved for one Clenshaw pass.
    coef: Vec<[[f64; 3]; M]>,
    /// Q_1, Q_2 at each piece's left end.
    offset: Vec<[f64; 2]>,
}

/// The tabulated flow of one noise value s (module docs); cheap to clone.
#[derive(Clone, Debug)]
pub struct PotentialTable<F> {
    /// +1, or -1 for s < 0 (the canonical tables mirrored).
    refl: f64,
    /// +1: the side of v* toward -v* (canonical u = v* - v > 0, the
    /// paper's); -1: the far side (canonical v > v*, u = v - v*).
    dir: f64,
    inner: Arc<Inner<F>>,
}

impl<F: FlowMap> PotentialTable<F> {
    /// Tabulate the flow of `drag` with noise value `s` ≠ 0 on the
    /// admissible interval [-|v*|, |v*|]. None when the flow does not fit in
    /// 4096 pieces (or a node fails): use the iterative solve.
    pub fn new<D: Drag<Flow = F>>(drag: &D, s: f64) -> Option<Self> {
        let vs = drag.flow(s.abs()).fixed_point();
        if !(vs > 0.0) {
            return None;
        }
        Self::build(drag, s, 1.0, 2.0 * vs, 0.25 * f64::EPSILON * vs)
    }

    /// Tabulate the flow of `drag` with noise value `s` (any sign, 0
    /// included: the pause's v* = 0) on one side of its fixed point v*:
    /// velocities in [v* - w_max, v*] (`below`) or [v*, v* + w_max]. The
    /// far side (away from -v*) and distances past 2 |v*| need the law's
    /// potential and drift at signed distance ([`FlowMap::potential_at_distance`]
    /// and [`Drag::drift_at_distance`] of a negative u), which the
    /// closed-form laws give; the caller asks only those. None as
    /// [`PotentialTable::new`].
    pub fn side<D: Drag<Flow = F>>(drag: &D, s: f64, below: bool, w_max: f64) -> Option<Self> {
        if drag.static_friction() > 0.0 || !drag.derivative(0.0).is_finite() {
            // A kink of the potential at v = 0 is laid out for the paper's
            // side only.
            return None;
        }
        let refl = if s < 0.0 { -1.0 } else { 1.0 };
        let dir = if below { refl } else { -refl };
        let vs = drag.flow(s.abs()).fixed_point();
        // Below u_lo, v* ± u rounds to v* (v* = 0: the exponential approach
        // is exact to O(u_lo²) relative there).
        let u_lo = 0.25 * f64::EPSILON * if vs > 0.0 { vs } else { w_max };
        Self::build(drag, s, dir, w_max, u_lo)
    }

    /// The tables of noise value s on the side `dir` of v*, distances
    /// (u_lo, w_max] (module docs).
    fn build<D: Drag<Flow = F>>(drag: &D, s: f64, dir: f64, w_max: f64, u_lo: f64) -> Option<Self> {
        let a = s.abs();
        let flow = drag.flow(a);
        let (vs, k) = (flow.fixed_point(), flow.rate());
        if !(vs >= 0.0 && vs.is_finite() && k > 0.0 && k.is_finite()) {
            return None;
        }
        if !(u_lo > 0.0 && w_max > u_lo && w_max.is_finite()) {
            return None;
        }
        let phi_lo = flow.potential_at_distance(dir * u_lo);
        let phi_top = flow.potential_at_distance(dir * w_max);
        let (n, range, phi_top, u_top, kink) = layout(drag, &flow, (vs, w_max), phi_lo, phi_top)?;
        let most = max_pieces(drag);
        if n > most {
            return None;
        }
        let mut bld = Builder {
            drag,
            flow: &flow,
            s: a,
            dir,
            bracket: (u_lo.ln() - 2.0, u_top.ln()),
            guess: u_lo.ln(),
            acc: [u_lo / k, 0.5 * u_lo * u_lo / k],
            var: Var::Phi,
            coef: Vec::new(),
            offset: Vec::new(),
            most,
        };
        let mut cells = Vec::with_capacity(n);
        for i in 0..n {
            let ca = phi_lo + range * i as f64 / n as f64;
            let cb = if i + 1 == n {
                phi_top
            } else {
                phi_lo + range * (i + 1) as f64 / n as f64
            };
            let first = bld.coef.len() as u32;
            bld.var = if i + 1 == kink {
                Var::Below(cb, cb - ca)
            } else if i == kink {
                Var::Above(ca, cb - ca)
            } else {
                Var::Phi
            };
            let d = match bld.var {
                Var::Phi => bld.cell(ca, cb)?,
                _ => bld.cell(0.0, 1.0)?,
            };
            cells.push((first, (1u32 << d) as f64));
        }
        let (coef, offset) = (bld.coef, bld.offset);
        let inner = Inner {
            flow,
            vs,
            k,
            phi_lo,
            u_lo,
            inv_h: n as f64 / range,
            kink,
            cells,
            coef,
            offset,
        };
        Some(PotentialTable {
            refl: if s < 0.0 { -1.0 } else { 1.0 },
            dir,
            inner: Arc::new(inner),
        })
    }

    /// The same tables for the noise value -s.
    pub fn mirrored(&self) -> Self {
        PotentialTable {
            refl: -self.refl,
            dir: self.dir,
            inner: Arc::clone(&self.inner),
        }
    }

    /// Number of pieces.
    pub fn pieces(&self) -> usize {
        self.inner.coef.len()
    }

    /// The fixed point v* (real frame).
    pub fn fixed_point(&self) -> f64 {
        self.refl * self.inner.vs
    }

    /// g'(v*).
    pub fn rate(&self) -> f64 {
        self.inner.k
    }

    /// The point at velocity v (on the table's side of v*, within its
    /// range): its potential from the law's closed form (or table), the
    /// antiderivatives from the table.
    #[inline]
    pub fn at(&self, v: f64) -> FlowPoint {
        let t = &*self.inner;
        let phi = t.flow.potential_at_distance(t.vs - self.refl * v);
        let (_, q) = t.series(phi);
        FlowPoint {
            v,
            phi,
            q: [self.refl * self.dir * q[0], q[1]],
        }
    }

    /// The point reached from `p` after flowing for time dt ≥ 0 (`p` itself
    /// for dt = 0).
    #[inline]
    pub fn advance(&self, p: &FlowPoint, dt: f64) -> FlowPoint {
        if !(dt > 0.0) {
            return *p;
        }
        let t = &*self.inner;
        let phi = p.phi - t.k * dt;
        let (lnu, q) = t.series(phi);
        let u = if phi >= t.phi_lo { lnu.exp() } else { lnu };
        FlowPoint {
            v: self.refl * (t.vs - self.dir * u),
            phi,
            q: [self.refl * self.dir * q[0], q[1]],
        }
    }
}

/// The uniform cells of the table: (number n, range in Φ, Φ and u at the
/// top, the cell above a kink tabulated in t or usize::MAX). Normally
/// n = ⌈range⌉ (at least 8) cells up to u = w_max. Where the force jumps at
/// v = 0 ([`Drag::static_friction`], Coulomb friction) or g'(0) = ∞ the
/// potential has a kink at u = v*: it is made a cell boundary (at least 8
/// cells of equal width h <= 1 below it), and the table extends upwards to
/// a whole number of cells (past u = 2 v*, where the flow continues), so
/// every piece is smooth (a jump of g leaves Φ smooth on either side; an
/// infinite slope needs the cells next to it in t, [`Var`]). None if the
/// range is empty or not finite.
fn layout<D: Drag, F: FlowMap>(
    drag: &D,
    flow: &F,
    (vs, w_max): (f64, f64),
    phi_lo: f64,
    phi_top: f64,
) -> Option<(usize, f64, f64, f64, usize)> {
    let range = phi_top - phi_lo;
    if !(range > 0.0 && range.is_finite()) {
        return None;
    }
    let jump = drag.static_friction() > 0.0;
    if !jump && drag.derivative(0.0).is_finite() {
        let n = (range.ceil() as usize).max(8);
        return Some((n, range, phi_top, w_max, usize::MAX));
    }
    let below = flow.potential_at_distance(vs) - phi_lo;
    if !(below > 0.0 && below < range) {
        return None;
    }
    let kc = below.ceil().max(8.0);
    let h = below / kc;
    let n = ((range / h).ceil() as usize).max(kc as usize + 1);
    let top = phi_lo + h * n as f64;
    let mut u = w_max;
    while !(flow.potential_at_distance(u) >= top) {
        u *= 2.0;
        if !u.is_finite() {
            return None;
        }
    }
    let kink = if jump { usize::MAX } else { kc as usize };
    Some((n, top - phi_lo, top, u, kink))
}

/// The variable of a cell's pieces: Φ itself, or t ∈ [0, 1] in the cell
/// (Φ_0 - h, Φ_0) below a kink at Φ_0 (Φ = Φ_0 - h (1 - t)^8) or the cell
/// (Φ_0, Φ_0 + h) above it (Φ = Φ_0 + h t^8).
#[derive(Clone, Copy, Debug)]
enum Var {
    Phi,
    Below(f64, f64),
    Above(f64, f64),
}

impl Var {
    /// (Φ, dΦ/dt) at t.
    #[inline]
    fn map(self, t: f64) -> (f64, f64) {
        match self {
            Var::Phi => (t, 1.0),
            Var::Below(p0, h) => {
                let w = 1.0 - t;
                let w7 = w.powi(7);
                (p0 - h * w7 * w, 8.0 * h * w7)
            }
            Var::Above(p0, h) => {
                let w7 = t.powi(7);
                (p0 + h * w7 * t, 8.0 * h * w7)
            }
        }
    }
}

impl<F> Inner<F> {
    /// (L(Φ) = ln u, (Q_1(Φ), Q_2(Φ))) on the table; below it, (u, (Q_1, Q_2)) of
    /// the exponential approach u = u_lo e^{Φ - Φ_lo} (NaN stays NaN).
    #[inline(always)]
    fn series(&self, phi: f64) -> (f64, [f64; 2]) {
        if !(phi >= self.phi_lo) {
            let u = self.u_lo * (phi - self.phi_lo).exp();
            return (u, [u / self.k, 0.5 * u * u / self.k]);
        }
        let x = (phi - self.phi_lo) * self.inv_h;
        let i = (x as usize).min(self.cells.len() - 1);
        let (first, m) = self.cells[i];
        let mut f = x - i as f64;
        // The cells next to a kink are tabulated in t (see `Var`).
        if (i + 1).wrapping_sub(self.kink) < 2 {
            f = if i < self.kink {
                1.0 - (1.0 - f.min(1.0)).sqrt().sqrt().sqrt()
            } else {
                f.min(1.0).sqrt().sqrt().sqrt()
            };
        }
        let y = (f * m).min(m);
        let j = (y as usize).min(m as usize - 1);
        let z = (2.0 * (y - j as f64) - 1.0).min(1.0);
        let i = first as usize + j;
        let [lnu, a1, a2] = power_sum(&self.coef[i], z);
        let o = self.offset[i];
        (lnu, [o[0] + a1, o[1] + a2])
    }
}

/// ln u at potential `target` (canonical, distance u on the side `dir`),
/// by safeguarded Newton in w = ln u from `guess` inside [lo, hi].
fn solve_node<D: Drag, F: FlowMap>(
    drag: &D,
    flow: &F,
    (s, dir): (f64, f64),
    target: f64,
    (lo, hi): (f64, f64),
    guess: f64,
) -> Option<f64> {
    let k = flow.rate();
    let g = |w: f64| {
        let u = w.exp();
        let slope = u * k / (dir * drag.drift_at_distance(s, dir * u));
        (flow.potential_at_distance(dir * u) - target, slope, 0.0)
    };
    root::solve_increasing(&g, lo, hi, guess, 0.0, 1e-10).ok()
}

/// The pieces' series and offsets under construction.
struct Builder<'a, D, F> {
    drag: &'a D,
    flow: &'a F,
    s: f64,
    /// The table's side of v* (`PotentialTable::dir`).
    dir: f64,
    /// Bracket of ln u for the node solves.
    bracket: (f64, f64),
    /// Newton start: ln u at the last piece's right end.
    guess: f64,
    /// Q_1, Q_2 at the next piece's left end.
    acc: [f64; 2],
    /// The variable of the current cell's pieces.
    var: Var,
    coef: Vec<[[f64; 3]; M]>,
    offset: Vec<[f64; 2]>,
    /// The most pieces of this table ([`max_pieces`]).
    most: usize,
}

impl<D: Drag, F: FlowMap> Builder<'_, D, F> {
    /// The integrands of one piece at t (in the cell's [`Var`]): L = ln u
    /// and u^k dΦ/dt / k, k = 1, 2 (their antiderivatives are Q_k in Φ);
    /// NaN where the node solve fails, so that the piece is not resolved.
    fn integrands(&self, t: f64) -> [f64; 3] {
        let k = self.flow.rate();
        let (phi, dphi) = self.var.map(t);
        match solve_node(
            self.drag,
            self.flow,
            (self.s, self.dir),
            phi,
            self.bracket,
            self.guess,
        ) {
            Some(lnu) => {
                let u = lnu.exp();
                [lnu, u / k * dphi, u * u / k * dphi]
            }
            None => [f64::NAN; 3],
        }
    }

    /// Whether the fit of one piece [a, b] is resolved to the noise of its
    /// values at degree M - 1.
    fn resolved(&self, fit: &chebyshev::Fit<3>, a: f64, b: f64) -> bool {
        if !fit.finite {
            return false;
        }
        // Noise of the node values: the potential rounds at ε |Φ|, which moves
        // ln u by ε P |dL/dΦ| (bounded by the series, Markov), and ln u
        // rounds at ε |ln u|; u and u² carry that relative error.
        let slope = match self.var {
            Var::Phi => {
                (fit.series[0].iter().enumerate())
                    .map(|(j, c)| (j * j) as f64 * c.abs())
                    .sum::<f64>()
                    / fit.half_width
            }
            _ => self.kink_slope(&fit.series[0]),
        };
        let (pa, pb) = (self.var.map(a).0, self.var.map(b).0);
        let p_local = pa.abs().max(pb.abs()).max(1.0);
        let rel = 16.0 * f64::EPSILON * (1.0 + slope * (p_local + fit.scale[0]));
        // Resolved at degree M - 1: the dropped coefficients of L, and of the
        // integrands (whose antiderivatives gain a degree), below the noise.
        let dropped = |c: &[f64]| c[M - 1..].iter().map(|x| x.abs()).sum::<f64>();
        dropped(&fit.series[0][1..]) <= rel * fit.scale[0].max(1.0)
            && dropped(&fit.series[1]) <= rel * fit.scale[1]
            && dropped(&fit.series[2]) <= rel * fit.scale[2]
    }

    /// |dL/dΦ| = |s - g(v)| / (k u) on a piece next to the kink (where
    /// dΦ/dt vanishes, so the series' slope in t does not bound it), from
    /// its series of L = ln u at both ends and the middle, with a margin
    /// of 2 (the piece is short and the slope smooth in u).
    fn kink_slope(&self, lnu: &[f64; chebyshev::NC]) -> f64 {
        let k = self.flow.rate();
        [-1.0, 0.0, 1.0]
            .iter()
            .map(|&z| {
                let u = chebyshev::clenshaw(lnu, z).exp();
                (self.drag.drift_at_distance(self.s, self.dir * u) / (k * u)).abs()
            })
            .fold(0.0, f64::max)
            * 2.0
    }

    /// Cover [a, b] with 2^d equal pieces, the smallest d ≤ 16 that
    /// resolves them all ([`Refine::Uniform`]); None past `MAX_PIECES` in
    /// all.
    fn cell(&mut self, a: f64, b: f64) -> Option<u32> {
        let this = &*self;
        let opts = Adaptive {
            resolved: &|fit, pa, pb| this.resolved(fit, pa, pb),
            refine: Refine::Uniform { max_depth: 16 },
            max_pieces: self.most - self.coef.len(),
        };
        let pieces = chebyshev::fit_adaptive(&|t| this.integrands(t), &[(a, b)], &opts).ok()?;
        let depth = pieces.len().trailing_zeros();
        for Piece { fit, .. } in pieces {
            // The series of L and the antiderivatives, in powers of the unit
            // variable.
            let power = [
                to_power::<M>(&fit.series[0]),
                to_power::<M>(&fit.anti[1]),
                to_power::<M>(&fit.anti[2]),
            ];
            let c: [[f64; 3]; M] = std::array::from_fn(|j| [power[0][j], power[1][j], power[2][j]]);
            self.offset.push(self.acc);
            let end = power_sum(&c, 1.0);
            self.acc = [self.acc[0] + end[1], self.acc[1] + end[2]];
            self.guess = end[0];
            self.coef.push(c);
        }
        Some(depth)
    }
}
#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::DragLaw;

    /// Lookups against the iterative flow and the deficit quadrature.
    #[test]
    fn table_matches_iterative_flow() {
        let coulomb = crate::model::drag::Coulomb::new(0.5, 1.3).unwrap();
        let power = |n: f64| DragLaw::Power(crate::model::drag::Power::new(n, 1.0).unwrap());
        // Tolerance on v in units of 1 + |v*|: a potential rounds at ε |Φ|,
        // a time error of ε |Φ| / g'(v*) (tanh at 0.99: g'(v*) = 0.02 and
        // Φ = ln sinh u - s u cancels from |Φ| ~ 5 near -v*: measured time
        // error 2e-13 against the closed-form flow time). Power law (n < 1:
        // g'(0) = ∞, the cells next to v = 0 in t): largest error far from
        // v = 0, near -v*, where |dv/dΦ| = (Sigma + g)/g'(v*) is 36
        // (n = 0.5) and 260 (n = 0.3): measured 3.4e-14 and 5.4e-14.
        for (d, sg, tol) in [
            (DragLaw::Tan, 3.0, 1e-14),
            (DragLaw::Tan, 30.0, 1e-14),
            (DragLaw::Tanh, 0.6, 1e-14),
            (DragLaw::Tanh, 0.99, 1e-12),
            (DragLaw::Linear, 1.0, 1e-14),
            (DragLaw::Cubic, 3.0, 1e-14),
            (DragLaw::Coulomb(coulomb), 2.0, 3e-14),
            (DragLaw::Coulomb(coulomb), 30.0, 3e-14),
            (power(0.5), 3.0, 1e-13),
            (power(0.3), 3.0, 1e-13),
            (power(0.8), 0.5, 1e-13),
        ] {
            for s in [sg, -sg] {
                let tab =
                    PotentialTable::new(&d, s).unwrap_or_else(|| panic!("{d} {s} not tabulated"));
                let flow = d.flow(s);
                let vs = flow.fixed_point();
                for i in 0..=20 {
                    let v0 = -vs + 2.0 * vs * i as f64 / 20.0 * 0.999;
                    let p = tab.at(v0);
                    for t in [1e-9, 1e-4, 0.01, 0.3, 1.0, 5.0, 40.0] {
                        let b = tab.advance(&p, t);
                        let vb = flow.velocity(v0, t);
                        assert!(
                            (b.v - vb).abs() <= tol * (1.0 + vs.abs()),
                            "{d} s={s} v0={v0} t={t}: {} vs {vb} ({} pieces)",
                            b.v,
                            tab.pieces()
                        );
                        let (i1, i2) = d.flow_deficits(s, v0, b.v);
                        let (j1, j2) = (p.q[0] - b.q[0], p.q[1] - b.q[1]);
                        let scale = 1e-13 * (1.0 + p.q[0].abs() + p.q[1].abs());
                        assert!(
                            (i1 - j1).abs() <= scale && (i2 - j2).abs() <= scale,
                            "{d} s={s} v0={v0} t={t}: {j1} {i1} / {j2} {i2}"
                        );
                    }
                }
            }
        }
    }

    /// Tables on either side of v*, v* = 0 (the pause) and interior fixed
    /// points, against the closed-form flow and the deficit quadrature.
    /// Tolerance as above, on v in units of 1 + w_max (measured below).
    #[test]
    fn side_tables_match_closed_flow() {
        let mut worst = 0.0f64;
        for (d, s, lo, hi) in [
            (DragLaw::Tan, 0.0, -1.2, 1.2),
            (DragLaw::Tan, -1.5, -1.25, 1.4),
            (DragLaw::Tan, 0.5, -1.2, 1.5),
            (DragLaw::Tanh, 0.0, -2.0, 2.0),
            (DragLaw::Tanh, 0.3, -1.0, 2.5),
            (DragLaw::Linear, 0.0, -1.0, 1.0),
            (DragLaw::Linear, -0.5, -3.0, 1.0),
        ] {
            let flow = d.flow(s);
            let vs = flow.fixed_point();
            for below in [true, false] {
                let w = if below { vs - lo } else { hi - vs };
                let tab = PotentialTable::side(&d, s, below, w)
                    .unwrap_or_else(|| panic!("{d} {s} {below} not tabulated"));
                for i in 0..=20 {
                    let off = w * i as f64 / 20.0;
                    let v0 = if below { vs - off } else { vs + off };
                    let p = tab.at(v0);
                    for t in [1e-9, 1e-4, 0.01, 0.3, 1.0, 5.0, 40.0] {
                        let b = tab.advance(&p, t);
                        let vb = flow.velocity(v0, t);
                        // A potential rounds at ε |Φ|: v moves by that times
                        // |dv/dΦ| = |s - g(v)| / g'(v*) (up to 8 near tan's
                        // pole at 1.5).
                        let slope = d.drift(s, vb).abs() / tab.rate();
                        let err = (b.v - vb).abs() / ((1.0 + w) * (1.0 + slope));
                        worst = worst.max(err);
                        assert!(
                            err <= 1e-14,
                            "{d} s={s} below={below} v0={v0} t={t}: {} vs {vb}",
                            b.v
                        );
                        let (i1, i2) = d.flow_deficits(s, v0, b.v);
                        let (j1, j2) = (p.q[0] - b.q[0], p.q[1] - b.q[1]);
                        let scale = 1e-13 * (1.0 + p.q[0].abs() + p.q[1].abs());
                        assert!(
                            (i1 - j1).abs() <= scale && (i2 - j2).abs() <= scale,
                            "{d} s={s} below={below} v0={v0} t={t}: {j1} {i1} / {j2} {i2}"
                        );
                    }
                }
            }
        }
        eprintln!("worst scaled velocity error {worst:e}");
    }
}
