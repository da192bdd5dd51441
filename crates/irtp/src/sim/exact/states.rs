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
//! This is a second event loop beside the paper's two-state one, on
//! purpose: the paper's loop keeps its fixed-size per-state arrays and its
//! random draws bit for bit (and its speed); both loops share the segment
//! building blocks ([`Segments`], `flow_segment` over the `StateTables`
//! of either loop, the bin crossing times and occupation).

use super::{
    add_crossings, close_particle, crossing_times, flow_segment, segments, DeficitTable, Lane,
    Occupation, Segments, StateTables, MIN_RELAXATION_RATE,
};
use crate::error::{Error, Result};
use crate::model::drag::{FlowMap, FlowPoint, PotentialTable};
use crate::model::noise::chain::Chain;
use crate::model::reset::{Reset, ResetRule};
use crate::model::{Drag, DragLaw, Params};
use crate::rng;
use crate::sim::{Observables, SimSpec};
use rand::Rng as _;
use std::ops::Range;

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

/// Whether the law's flow map is in closed form on the whole velocity line
/// (tan, tanh, linear: a fixed point approached from either side, at any
/// distance); the tabulated flows are exact only on the side of v* of the
/// paper's noise, within 2 |v*|.
fn two_sided(drag: DragLaw) -> bool {
    matches!(drag, DragLaw::Tan | DragLaw::Tanh | DragLaw::Linear)
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
    if two_sided(law) {
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

/// Everything fixed for an N-state run.
pub(super) struct StatesSampler<F> {
    setup: StatesSetup<F>,
    chain: Chain,
    /// Per state: q_s + r and its inverse.
    total: Vec<f64>,
    inv_total: Vec<f64>,
    reset: ResetRule,
    /// The segment start at the point target v_r, per noise state.
    at_vr: Option<Vec<FlowPoint>>,
    times: Vec<f64>,
    burn_in: f64,
    t_max: f64,
    seed: u64,
}

impl<F: FlowMap> StateTables<F> for StatesSampler<F> {
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
    fn window(&self) -> (&[f64], f64) {
        (&self.times, self.burn_in)
    }
}

impl Occupation for StatesScratch {
    #[inline(always)]
    fn occ(&mut self) -> &mut [f64] {
        &mut self.occ
    }
    #[inline(always)]
    fn cross(&mut self, si: usize) -> &mut [i64] {
        &mut self.cross[si]
    }
}

/// Per-chunk scratch: occupation times and one crossing difference array
/// per noise state.
pub(super) struct StatesScratch {
    occ: Vec<f64>,
    cross: Vec<Vec<i64>>,
}

impl<F: FlowMap> StatesSampler<F> {
    /// The sampler of `params` (a noise model at T = 0; the caller has
    /// checked the solver's support line). The schedule's modifiers are
    /// refused here, naming their flag.
    pub(super) fn new<D: Drag<Flow = F>>(
        drag: &D,
        params: &Params,
        spec: &SimSpec,
    ) -> Result<Self> {
        if let Some(f) = params.schedule().features().into_iter().next() {
            return Err(Error::invalid(
                f.flag(),
                params.schedule().spec_of(f),
                "the paper's Poisson protocol for the exact sampler with a noise model other than \
                 the paper's (a schedule modifier with such a noise is not run)",
            ));
        }
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
        let reset = *params.reset();
        let r = reset.rate();
        let total: Vec<f64> = chain.exit.iter().map(|q| q + r).collect();
        let at_vr = reset
            .point()
            .map(|vr| setup.segs.iter().map(|s| s.at(vr)).collect());
        Ok(StatesSampler {
            inv_total: total.iter().map(|t| 1.0 / t).collect(),
            total,
            setup,
            chain,
            reset,
            at_vr,
            times: spec.grid.times().to_vec(),
            burn_in: spec.burn_in,
            t_max: spec.grid.t_max(),
            seed: spec.seed,
        })
    }

    /// Empty scratch for `bins` bins.
    pub(super) fn scratch(&self, bins: usize) -> StatesScratch {
        StatesScratch {
            occ: vec![0.0; bins],
            cross: vec![vec![0; bins]; self.chain.states()],
        }
    }

    /// A particle at t = 0: v = 0, noise state drawn from π.
    fn start(&self, i: u64) -> Lane {
        let mut rng = rng::stream(self.seed, i);
        let si = self.chain.draw_stationary(rng.gen::<f64>());
        Lane {
            rng,
            si,
            a: self.setup.segs[si].at(0.0),
            t: 0.0,
            x: 0.0,
            k: 0,
            int_v: 0.0,
            int_v2: 0.0,
            msd: 0.0,
            at_atom: 0.0,
            events: 0,
            done: false,
            held: false,
            hold_until: f64::INFINITY,
            next_periodic: f64::INFINITY,
        }
    }

    /// One flow segment of a particle up to its next event (or t_max), then
    /// the event: a jump of the noise (Eq. (N10)) or a reset.
    #[inline]
    fn step(&self, p: &mut Lane, obs: &mut Observables, sc: &mut StatesScratch) {
        let s = p.si;
        let gap = if self.total[s] > 0.0 {
            p.rng.sample::<f64, _>(rand_distr::Exp1) * self.inv_total[s]
        } else {
            f64::INFINITY
        };
        let t_end = (p.t + gap).min(self.t_max);
        let b = flow_segment(self, p, obs, sc, t_end);
        if t_end >= self.t_max {
            p.done = true;
            return;
        }
        p.events += 1;
        let u = p.rng.gen::<f64>() * self.total[s];
        if u < self.chain.exit[s] {
            p.si = self.chain.jump(s, u);
            p.a = self.setup.segs[p.si].at(b.v);
        } else {
            let v = self.reset.draw_velocity(&mut p.rng);
            p.si = self.reset.draw_noise_state(s, &self.chain, &mut p.rng);
            p.a = match &self.at_vr {
                Some(at) => at[p.si],
                None => self.setup.segs[p.si].at(v),
            };
        }
    }

    /// Particles `ids` one after the other.
    pub(super) fn particles(&self, ids: Range<u64>, obs: &mut Observables, sc: &mut StatesScratch) {
        for i in ids {
            let mut p = self.start(i);
            while !p.done {
                self.step(&mut p, obs, sc);
            }
            for (cross, tau) in sc.cross.iter_mut().zip(&self.setup.tau) {
                add_crossings(cross, &mut sc.occ, tau);
            }
            close_particle(&p, obs, &mut sc.occ, self.t_max - self.burn_in);
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
