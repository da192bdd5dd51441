//! The exact sampler with a finite-state Markov noise (levels a_s,
//! generator Q, Eqs. (N10)-(N12) of docs/equations.md) at temperature 0.
//!
//! Between events the velocity follows the flow dv/dt = a_s - g(v) of the
//! current state toward its fixed point v*_s = g⁻¹(a_s), which may lie
//! inside the velocity interval (the pause of run-pause-tumble: v* = 0) and
//! is then approached from either side: such a level's segments are table
//! lookups on each side of v* ([`PotentialTable::side`], the paper's
//! tables generalised: one exponential and one series sum per segment, no
//! iteration), so a third state costs no more per event than the paper's
//! two. Events come at rate q_s + r in
//! state s (Eq. (N10)); one uniform u on [0, q_s + r) picks a jump of the
//! noise (u < q_s, its target by [`Chain::jump`] from the same u) or a
//! reset (velocity by the rule, noise kept or re-drawn from π). A particle
//! starts at v = 0 with its noise state drawn from π.
//!
//! These are the N-state noise states ([`ChainStates`]) of the exact
//! sampler's one event loop (`Sampler`, monomorphised over the paper's
//! two-state noise and this chain), so every schedule modifier runs here
//! as for the paper's noise; inside a refractory period the chain jumps
//! at its exit rate q_s.

use super::{crossing_times, segments, DeficitTable, NoiseStates, Segments, MIN_RELAXATION_RATE};
use crate::error::{Error, Result};
use crate::model::drag::{FlowMap, FlowPoint, PotentialTable};
use crate::model::noise::chain::Chain;
use crate::model::reset::{Reset, ResetRule};
use crate::model::{Drag, DragLaw, Params};
use crate::rng::Rng;
use crate::sim::SimSpec;
use rand::Rng as _;

/// What the levels and the number of bins fix (no rate enters): per state
/// the segments, fixed point, 1/g'(v*), bin crossing times and edge
/// potentials; memoised per (law, levels, bins) like the two-state setup.
#[derive(Clone)]
struct StatesSetup<F> {
    segs: Vec<Segments<F>>,
    vs: Vec<f64>,
    inv_rate: Vec<f64>,
    tau: Vec<Vec<f64>>,
    phi_edges: Vec<Vec<f64>>,
}

/// Where a level's fixed point v* = g⁻¹(a) sits in the velocity interval.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum LevelKind {
    /// The interval's edge, the farther from 0 (the paper's ±Sigma).
    Edge,
    /// Inside it, or the nearer edge (a law with closed-form flows).
    Interior,
}

/// The kind of level `a` on [lo, hi] for an exact event-driven method
/// (`method`, for the messages), refused naming `noise` where its fixed
/// point is at a kink of the drag (g'(v*) not finite, or below
/// [`MIN_RELAXATION_RATE`]) or, for a law without closed-form flows, not
/// an edge.
pub(crate) fn level_kind<D: Drag>(
    drag: &D,
    (law, spec): (DragLaw, &str),
    a: f64,
    (lo, hi): (f64, f64),
    method: &str,
) -> Result<LevelKind> {
    let rate = drag.flow(a).rate();
    if !(rate >= MIN_RELAXATION_RATE && rate.is_finite()) {
        return Err(Error::invalid(
            "noise",
            spec,
            format!(
                "levels whose fixed point v* = g⁻¹(a) has a finite relaxation rate g'(v*) >= \
                 {MIN_RELAXATION_RATE:e} for {method} (here level {a} has g'(v*) = {rate:e}: a \
                 kink of the drag at v*)"
            ),
        ));
    }
    let vs = drag.inverse(a);
    if (a > 0.0 && vs == hi && lo >= -vs) || (a < 0.0 && vs == lo && hi <= -vs) {
        return Ok(LevelKind::Edge);
    }
    if law.two_sided_flow() {
        return Ok(LevelKind::Interior);
    }
    Err(Error::invalid(
        "noise",
        spec,
        format!(
            "levels whose fixed points g⁻¹(a) are the edges of the velocity interval, the \
             farther from 0 for each, for {method} with drag {law} (here level {a} has g⁻¹(a) \
             = {vs:e} in [{lo:e}, {hi:e}]; interior or nearer fixed points are run for tan, tanh \
             and linear drag)"
        ),
    ))
}

/// The segments of level `a` on [lo, hi] ([`level_kind`]): the paper's
/// tables at an edge; else a potential table on each side of v*
/// (distances up to the interval's ends), or where a side does not fit in
/// its tables the iterative closed-form flow with the deficit table on
/// [lo, hi].
pub(crate) fn level_segments<D: Drag>(
    drag: &D,
    (law, spec): (DragLaw, &str),
    a: f64,
    lo: f64,
    hi: f64,
) -> Result<Segments<D::Flow>> {
    if level_kind(drag, (law, spec), a, (lo, hi), "the exact sampler")? == LevelKind::Edge {
        return segments(drag, a, lo, hi);
    }
    let vs = drag.inverse(a);
    if let Some(sides) = side_tables(drag, a, vs, lo, hi) {
        return Ok(Segments::Sides(Box::new(sides), vs));
    }
    // No acceleration: its guide covers only the paper's side of v*.
    Ok(Segments::Solve(
        drag.flow(a),
        DeficitTable::new(drag, a, lo, hi)?,
    ))
}

/// The potential tables of level `a` below and above its fixed point vs on
/// [lo, hi] (a side of zero length, v* at an edge, gets the other side's
/// table: no flow reaches it). None if a side does not fit in its tables.
fn side_tables<D: Drag>(
    drag: &D,
    a: f64,
    vs: f64,
    lo: f64,
    hi: f64,
) -> Option<[PotentialTable<D::Flow>; 2]> {
    let (wb, wa) = (vs - lo, hi - vs);
    let below = (wb > 0.0).then(|| PotentialTable::side(drag, a, true, wb));
    let above = (wa > 0.0).then(|| PotentialTable::side(drag, a, false, wa));
    match (below.flatten(), above.flatten()) {
        (Some(b), Some(a)) => Some([b, a]),
        (Some(b), None) if wa <= 0.0 => Some([b.clone(), b]),
        (None, Some(a)) if wb <= 0.0 => Some([a.clone(), a]),
        _ => None,
    }
}

impl<F: FlowMap> StatesSetup<F> {
    fn new<D: Drag<Flow = F>>(
        drag: &D,
        (law, spec): (DragLaw, &str),
        levels: &[f64],
        b: usize,
        bounds: (f64, f64),
    ) -> Result<Self> {
        let (lo, hi) = bounds;
        let mut edges: Vec<f64> = (0..=b)
            .map(|k| lo + (hi - lo) * k as f64 / b as f64)
            .collect();
        edges[b] = hi;
        let n = levels.len();
        let mut out = StatesSetup {
            segs: Vec::with_capacity(n),
            vs: Vec::with_capacity(n),
            inv_rate: Vec::with_capacity(n),
            tau: Vec::with_capacity(n),
            phi_edges: Vec::with_capacity(n),
        };
        for &a in levels {
            let flow = drag.flow(a);
            let rate = flow.rate();
            out.segs.push(level_segments(drag, (law, spec), a, lo, hi)?);
            out.vs.push(flow.fixed_point());
            out.inv_rate.push(1.0 / rate);
            out.tau.push(crossing_times(drag, a, &edges)?);
            out.phi_edges
                .push(edges.iter().map(|&e| flow.potential(e)).collect());
        }
        Ok(out)
    }
}

/// A finite-state chain's noise states for the one event loop
/// ([`NoiseStates`]): per state the tables of [`StatesSetup`], events at
/// rate q_s + r (Eq. (N10)), jumps only (rate q_s) inside a refractory
/// period.
pub(super) struct ChainStates<F> {
    setup: StatesSetup<F>,
    chain: Chain,
    /// Per state: q_s + r and its inverse.
    total: Vec<f64>,
    inv_total: Vec<f64>,
    /// Per state: 1/q_s (0 where q_s = 0).
    inv_exit: Vec<f64>,
    /// The segment start at the point target v_r, per noise state.
    at_vr: Option<Vec<FlowPoint>>,
}

impl<F: FlowMap> NoiseStates for ChainStates<F> {
    type Flow = F;
    type Cross = Vec<Vec<i64>>;

    /// The chain of `params` (a noise model at T = 0), refused naming
    /// `noise` where the velocity interval does not hold v = 0 or a level
    /// is not run ([`level_kind`]).
    fn build<D: Drag<Flow = F>>(drag: &D, params: &Params, spec: &SimSpec) -> Result<Self> {
        let chain = params.chain()?;
        let (lo, hi) = params.bounds();
        if !(lo < hi && lo <= 0.0 && 0.0 <= hi) {
            return Err(Error::invalid(
                "noise",
                params.noise_model()?.spec(),
                format!(
                    "levels of both signs (or zero) and at least two distinct levels for the \
                     exact sampler: the particle starts at v = 0 (here the velocity interval is \
                     [{lo}, {hi}])"
                ),
            ));
        }
        let bits: Vec<String> = chain
            .levels
            .iter()
            .map(|a| format!("{:x}", a.to_bits()))
            .collect();
        let key = format!(
            "exact sampler states {drag:?} {} {}",
            bits.join(","),
            spec.bins
        );
        let (law, noise) = (params.drag(), params.noise_model()?.spec());
        let setup = crate::memo::shared(key, || {
            StatesSetup::new(drag, (law, &noise), &chain.levels, spec.bins, (lo, hi))
        })?;
        let setup = (*setup).clone();
        let reset = params.reset();
        let r = reset.rate();
        let total: Vec<f64> = chain.exit.iter().map(|q| q + r).collect();
        let at_vr = reset
            .point()
            .map(|vr| setup.segs.iter().map(|s| s.at(vr)).collect());
        Ok(ChainStates {
            inv_total: total.iter().map(|t| 1.0 / t).collect(),
            inv_exit: chain
                .exit
                .iter()
                .map(|&q| if q > 0.0 { 1.0 / q } else { 0.0 })
                .collect(),
            total,
            setup,
            chain,
            at_vr,
        })
    }
    #[inline(always)]
    fn seg(&self, si: usize) -> &Segments<F> {
        &self.setup.segs[si]
    }
    #[inline(always)]
    fn fixed_point(&self, si: usize) -> f64 {
        self.setup.vs[si]
    }
    #[inline(always)]
    fn inv_rate(&self, si: usize) -> f64 {
        self.setup.inv_rate[si]
    }
    #[inline(always)]
    fn phi_edges(&self, si: usize) -> &[f64] {
        &self.setup.phi_edges[si]
    }
    #[inline(always)]
    fn tau(&self, si: usize) -> &[f64] {
        &self.setup.tau[si]
    }
    fn cross(&self, bins: usize) -> Vec<Vec<i64>> {
        vec![vec![0; bins]; self.chain.states()]
    }
    /// Drawn from π (one uniform).
    #[inline]
    fn start(&self, rng: &mut Rng) -> usize {
        self.chain.draw_stationary(rng.gen::<f64>())
    }
    #[inline(always)]
    fn clock(&self, si: usize) -> (f64, f64) {
        (self.total[si], self.inv_total[si])
    }
    #[inline(always)]
    fn jump_clock(&self, si: usize) -> (f64, f64) {
        (self.chain.exit[si], self.inv_exit[si])
    }
    /// One uniform on [0, q_s + r): a jump (u < q_s, its target by
    /// [`Chain::jump`] from the same u) or a reset.
    #[inline]
    fn event(&self, si: usize, u: f64) -> Option<usize> {
        let u = u * self.total[si];
        (u < self.chain.exit[si]).then(|| self.chain.jump(si, u))
    }
    /// The target of a jump by one uniform on [0, q_s).
    #[inline]
    fn jump_held(&self, si: usize, rng: &mut Rng) -> usize {
        self.chain.jump(si, rng.gen::<f64>() * self.chain.exit[si])
    }
    #[inline]
    fn after_reset(&self, si: usize, rule: &ResetRule, rng: &mut Rng) -> usize {
        rule.draw_noise_state(si, &self.chain, rng)
    }
    #[inline]
    fn reset_point(&self, si: usize, v: f64) -> FlowPoint {
        match &self.at_vr {
            Some(at) => at[si],
            None => self.setup.segs[si].at(v),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A level whose fixed point is not an interval edge (the pause at 0,
    /// the weaker level of an asymmetric noise, an interior level) runs on
    /// the side tables; they agree with the iterative closed-form flow and
    /// its deficit table to rounding on either side of v* (tolerances as
    /// the paper's tables against the solve, velocity in units of
    /// 1 + v_u).
    #[test]
    fn side_tables_and_solve_agree() {
        let q = std::f64::consts::FRAC_PI_4;
        for (d, a, lo, hi) in [
            (DragLaw::Tan, 0.0, -q, q),
            (DragLaw::Tan, -0.5, -0.5f64.atan(), 1.5f64.atan()),
            (DragLaw::Tan, 0.5, -q, 2f64.atan()),
            (DragLaw::Tanh, 0.0, -0.6f64.atanh(), 0.6f64.atanh()),
            (DragLaw::Tanh, 0.2, -0.3f64.atanh(), 0.8f64.atanh()),
            (DragLaw::Linear, 0.0, -1.0, 1.0),
        ] {
            let seg = level_segments(&d, (d, "test"), a, lo, hi).unwrap();
            assert!(matches!(seg, Segments::Sides(..)), "{d} {a}: not tabulated");
            let solve = Segments::Solve(d.flow(a), DeficitTable::new(&d, a, lo, hi).unwrap());
            for i in 0..=16 {
                let v = lo + (hi - lo) * i as f64 / 16.0;
                let (p, r) = (seg.at(v), solve.at(v));
                for dt in [0.0, 1e-6, 0.1, 1.0, 10.0, 50.0] {
                    let (ta, sa) = (seg.advance(&p, dt), solve.advance(&r, dt));
                    assert!(
                        (ta.v - sa.v).abs() < 1e-14 * (1.0 + hi - lo),
                        "{d} {a} {v} {dt}: {} {}",
                        ta.v,
                        sa.v
                    );
                    for k in 0..2 {
                        let (ja, jb) = (p.q[k] - ta.q[k], r.q[k] - sa.q[k]);
                        let scale = 1.0 + p.q[k].abs() + r.q[k].abs();
                        assert!(
                            (ja - jb).abs() < 1e-13 * scale,
                            "{d} {a} {v} {dt} {k}: {ja} {jb}"
                        );
                    }
                }
            }
        }
    }
}
