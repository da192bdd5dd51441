//! The noise's state space as the exact samplers read it: the simulation
//! ([`super`]), first passage in velocity ([`crate::mfpt::exact`]) and the
//! search in position ([`crate::search::exact`]) are written once over
//! [`ExactNoise`], which the paper's telegraph ([`Telegraph`]) and a
//! finite-state chain ([`Chain`], docs/equations.md Eqs. (N10)-(N12))
//! implement. It lives with the simulation sampler because its flow
//! segments ([`Segments`]) are that sampler's tables; the samplers keep
//! what only they need (bin crossing times, crossing tests, roots in x).
//!
//! Per state s: the level a_s, the exit rate q_s (the paper's: lambda), so
//! the event clock q_s + r with Poisson resets at rate r (Eq. (N10)); one
//! uniform u on [0, q_s + r) picks a jump (u < q_s, its target by
//! [`Chain::jump`] from the same u; the paper's: the other state) or a
//! reset. The flows between events are exact (Eq. (N11)): the paper's
//! tables at an interval edge, tables on each side of an interior fixed
//! point (the pause of run-pause-tumble: v* = 0), which a third state
//! costs no more per event than the paper's two.

use super::{check_relaxation, exp_gap, segments, DeficitTable, Segments, MIN_RELAXATION_RATE};
use crate::error::{Error, Result};
use crate::model::drag::{FlowMap, PotentialTable};
use crate::model::noise::chain::Chain;
use crate::model::reset::{Reset, ResetRule};
use crate::model::{Drag, DragLaw, Params};
use crate::rng::Rng;
use rand::Rng as _;

/// The noise's state space of the exact samplers (module docs): levels,
/// jump law, start law, the noise at a reset and during a refractory
/// hold, and the per-state flows. States are indices (the paper's: 0 =
/// +Sigma, 1 = -Sigma).
pub trait ExactNoise: Clone + Send + Sync + std::fmt::Debug + 'static {
    /// The noise of `params` (a noise model's chain at T = 0, or the
    /// paper's telegraph where it has none).
    fn of(params: &Params) -> Result<Self>;
    /// The levels a_s, one per state.
    fn levels(&self) -> &[f64];
    /// The exit rate q_s of state s.
    fn exit(&self, s: usize) -> f64;
    /// The state a jump from s goes to, given u uniform on [0, q_s).
    fn jump(&self, s: usize, u: f64) -> usize;
    /// A jump from s drawn from `rng` (one uniform on [0, q_s)).
    #[inline]
    fn draw_jump(&self, s: usize, rng: &mut Rng) -> usize {
        self.jump(s, rng.gen::<f64>() * self.exit(s))
    }
    /// The event of u uniform on [0, q_s + r) in state s: Some(j) a jump
    /// to j (u < q_s), None a reset.
    #[inline(always)]
    fn event(&self, s: usize, u: f64) -> Option<usize> {
        (u < self.exit(s)).then(|| self.jump(s, u))
    }
    /// The event clock q_s + r of each state (Poisson resets at rate r).
    fn clocks(&self, r: f64) -> Vec<f64> {
        (0..self.levels().len()).map(|s| self.exit(s) + r).collect()
    }
    /// A particle's start state: `half` is its stratum in a first-passage
    /// run (Some(state): even particles 0, odd 1, swapped in a mirrored
    /// frame), None in a simulation.
    fn start(&self, half: Option<usize>, rng: &mut Rng) -> usize;
    /// The state after a reset from s, by the rule's noise option.
    fn after_reset(&self, s: usize, rule: &ResetRule, rng: &mut Rng) -> usize;
    /// The state after holding the velocity for `d` from s (a refractory
    /// period: the noise runs on, no resets).
    fn after_hold(&self, s: usize, d: f64, rng: &mut Rng) -> usize;
    /// The flow segments of each state on the velocity interval of
    /// `params`.
    fn segments<D: Drag>(&self, drag: &D, params: &Params) -> Result<Vec<Segments<D::Flow>>>;
    /// The flow of each state, accelerated where its fixed point is an
    /// interval edge; `method` names the sampler in a refusal.
    fn flows<D: Drag>(&self, drag: &D, params: &Params, method: &str) -> Result<Vec<D::Flow>>;
}

/// The paper's noise: ±Sigma flipping at rate lambda (state 0: +Sigma).
#[derive(Clone, Copy, Debug)]
pub struct Telegraph {
    lambda: f64,
    levels: [f64; 2],
}

impl ExactNoise for Telegraph {
    fn of(params: &Params) -> Result<Self> {
        let sigma = params.sigma();
        Ok(Telegraph {
            lambda: params.lambda(),
            levels: [sigma, -sigma],
        })
    }
    #[inline(always)]
    fn levels(&self) -> &[f64] {
        &self.levels
    }
    #[inline(always)]
    fn exit(&self, _: usize) -> f64 {
        self.lambda
    }
    #[inline(always)]
    fn jump(&self, s: usize, _: f64) -> usize {
        1 - s
    }
    /// The flip (no draw).
    #[inline(always)]
    fn draw_jump(&self, s: usize, _: &mut Rng) -> usize {
        1 - s
    }
    /// The stratum's state; in a simulation ±Sigma with probability ½
    /// each (one boolean).
    #[inline(always)]
    fn start(&self, half: Option<usize>, rng: &mut Rng) -> usize {
        half.unwrap_or_else(|| usize::from(!rng.gen::<bool>()))
    }
    #[inline(always)]
    fn after_reset(&self, s: usize, rule: &ResetRule, rng: &mut Rng) -> usize {
        rule.draw_telegraph(s, rng)
    }
    /// A flip with the probability ½(1 - e^{-2 lambda d}) of an odd number
    /// of flips (one uniform).
    fn after_hold(&self, s: usize, d: f64, rng: &mut Rng) -> usize {
        if rng.gen::<f64>() < -0.5 * (-2.0 * self.lambda * d).exp_m1() {
            1 - s
        } else {
            s
        }
    }
    /// The paper's tables (the -Sigma table the +Sigma one mirrored),
    /// refused where g'(v_u) is too small (`check_relaxation`).
    fn segments<D: Drag>(&self, drag: &D, params: &Params) -> Result<Vec<Segments<D::Flow>>> {
        let (sigma, (lo, hi)) = (self.levels[0], params.bounds());
        check_relaxation(drag, sigma, hi)?;
        let plus = segments(drag, sigma, lo, hi)?;
        let minus = match &plus {
            Segments::Table(t) => Segments::Table(t.mirrored()),
            _ => segments(drag, -sigma, lo, hi)?,
        };
        Ok(vec![plus, minus])
    }
    fn flows<D: Drag>(&self, drag: &D, _: &Params, _: &str) -> Result<Vec<D::Flow>> {
        Ok(self
            .levels
            .iter()
            .map(|&a| drag.flow(a).accelerated())
            .collect())
    }
}

impl ExactNoise for Chain {
    fn of(params: &Params) -> Result<Self> {
        params.chain()
    }
    #[inline(always)]
    fn levels(&self) -> &[f64] {
        &self.levels
    }
    #[inline(always)]
    fn exit(&self, s: usize) -> f64 {
        self.exit[s]
    }
    #[inline(always)]
    fn jump(&self, s: usize, u: f64) -> usize {
        Chain::jump(self, s, u)
    }
    /// Drawn from π with one uniform (the stream's first draw), whatever
    /// the stratum.
    #[inline]
    fn start(&self, _: Option<usize>, rng: &mut Rng) -> usize {
        self.draw_stationary(rng.gen::<f64>())
    }
    #[inline]
    fn after_reset(&self, s: usize, rule: &ResetRule, rng: &mut Rng) -> usize {
        rule.draw_noise_state(s, self, rng)
    }
    /// The chain's jumps over d, one exponential gap each (Eq. (N10)).
    fn after_hold(&self, mut s: usize, d: f64, rng: &mut Rng) -> usize {
        let mut t = exp_gap(rng, self.exit[s]);
        while t < d {
            s = Chain::jump(self, s, rng.gen::<f64>() * self.exit[s]);
            t += exp_gap(rng, self.exit[s]);
        }
        s
    }
    /// Per level the segments of `level_segments`.
    fn segments<D: Drag>(&self, drag: &D, params: &Params) -> Result<Vec<Segments<D::Flow>>> {
        let (lo, hi) = params.bounds();
        let spec = params.noise_model()?.spec();
        let law = (params.drag(), spec.as_str());
        self.levels
            .iter()
            .map(|&a| level_segments(drag, law.clone(), a, lo, hi))
            .collect()
    }
    /// Accelerated at an interval edge, the plain closed form at an
    /// interior fixed point (`level_kind`).
    fn flows<D: Drag>(&self, drag: &D, params: &Params, method: &str) -> Result<Vec<D::Flow>> {
        let spec = params.noise_model()?.spec();
        let law = (params.drag(), spec.as_str());
        self.levels
            .iter()
            .map(|&a| {
                Ok(
                    match level_kind(drag, law.clone(), a, params.bounds(), method)? {
                        LevelKind::Edge => drag.flow(a).accelerated(),
                        LevelKind::Interior => drag.flow(a),
                    },
                )
            })
            .collect()
    }
}

/// Where a level's fixed point v* = g⁻¹(a) sits in the velocity interval.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum LevelKind {
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
fn level_kind<D: Drag>(
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
fn level_segments<D: Drag>(
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
            let seg = level_segments(&d, (d.clone(), "test"), a, lo, hi).unwrap();
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
