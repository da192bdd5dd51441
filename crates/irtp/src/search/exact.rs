//! Exact first passage in position: the event-driven sampler of
//! [`crate::sim::exact`] run until x leaves the search region, over the
//! paper's ±Sigma telegraph noise or any finite-state noise at T = 0
//! ([`ExactNoise`]: one walk, generic over the noise states).
//!
//! Between events (those of the walk kernel below) the velocity follows the exact flow dv/dt = a_s - g(v) (a_s = ±Sigma for the paper's
//! noise), and x along a flow segment is the flow's displacement
//! v*_s t - ∫ (v*_s - v) dt (the flow potential tables of the simulation
//! sampler; for a level whose fixed point v*_s = g⁻¹(a_s) is inside the
//! velocity interval, such as the pause a_s = 0 of run-pause-tumble, the
//! tables on each side of v*_s, [`ExactNoise::segments`]). Along a segment v
//! moves monotonically towards v*_s, so it changes sign at most once (at
//! the flow time to v = 0; never where v*_s = 0: v keeps its sign and
//! tends to 0): x(t) is monotone on at most two pieces. On a
//! piece that moves towards a boundary and ends beyond it, the crossing is
//! the root of x(t) = boundary, found by safeguarded Halley steps with
//! dx/dt = v and d²x/dt² = a_s - g(v) inside the piece's bracket
//! ([`crate::numerics::root::solve_increasing`], bisection where it does
//! not converge): exact to rounding, no time step, no overshoot.
//!
//! The walk is the kernel `sim::exact::passage` with the position-target
//! observer: with position resetting x → x_r at a reset (on the start side
//! of the target, so a reset is never a passage); during a hold x moves
//! linearly (its crossing is closed-form).
//!
//! Start: the paper's noise starts at +Sigma for even particles and -Sigma
//! for odd ones (stratified); a chain starts in a state drawn from π with
//! the stream's first uniform, so τ is the π-averaged mean search time and
//! the even and odd particles (strata 0 and 1 of [`FptStats`], the `plus`
//! and `minus` halves of its summary) are two independent halves of the
//! same law (as in
//! [`crate::mfpt::exact`]'s N-state sampler).

use super::SearchProblem;
use crate::error::Result;
use crate::mfpt::estimator::{first_passage_units, merge_units, FptSample, FptStats, HALVES};
use crate::model::drag::{FlowMap, FlowPoint};
use crate::model::noise::chain::Chain;

use crate::model::Drag;
use crate::numerics::root::solve_increasing;
use crate::parallel::Progress;
use crate::rng::Rng;
use crate::sim::exact::passage::{Clocks, Flow, Mode, Observer};
use crate::sim::exact::{ExactNoise, Segments, Telegraph};
use std::ops::Range;

/// Prepared exact sampler of one search problem (flow tables built once),
/// over the noise states `N`.
#[derive(Clone)]
pub struct SearchSampler<D: Drag, N: ExactNoise = Telegraph> {
    drag: D,
    /// Flow segments of each noise state (the paper's: +Sigma, -Sigma).
    segs: Vec<Segments<D::Flow>>,
    /// The same flows, for flow times (the turning point v = 0).
    flows: Vec<D::Flow>,
    /// Fixed points v*_s, per state.
    vs: Vec<f64>,
    /// The noise, its event rates, the resetting rule and the schedule.
    clocks: Clocks<N>,
    x_reset: Option<f64>,
    /// The search region lo < x < hi (an open side is ∓∞).
    lo: f64,
    hi: f64,
}

/// The position-target observer of the walk kernel: x and the flow
/// point along the walk, the passage the first time x leaves the search
/// region (module docs).
struct PositionTarget<'a, D: Drag, N: ExactNoise> {
    sampler: &'a SearchSampler<D, N>,
    x: f64,
    /// The start of the current flow segment (its end after a Moved).
    a: FlowPoint,
}

/// The end of one flow segment.
enum Segment {
    /// x reached a boundary after this time into the segment.
    Hit(f64),
    /// No crossing: the segment's end point and x there.
    Moved(FlowPoint, f64),
}

impl<D: Drag> SearchSampler<D, Telegraph> {
    /// Prepare for `problem` (the paper's noise; a noise model is run by
    /// [`SearchSampler::with_chain`]) with the law `drag` (its own type:
    /// the walk is monomorphised). Errors where the flow tables cannot
    /// resolve the law (as the simulation sampler).
    pub fn new(drag: &D, problem: &SearchProblem) -> Result<Self> {
        super::noise_gate(problem, super::PAPER_NOISE_ONLY)?;
        Self::assemble(drag, problem)
    }
}

impl<D: Drag> SearchSampler<D, Chain> {
    /// Prepare for `problem` with its noise model at T = 0 (the paper's
    /// noise as a two-state chain where it has none): per level the
    /// segments and flows of [`ExactNoise`]; refused naming `noise` where
    /// a level's flow is not exact (a kink of the drag at v*, an interior
    /// fixed point of a law without closed-form flows), naming
    /// `temperature` at T > 0 (`super::noise_gate`).
    pub fn with_chain(drag: &D, problem: &SearchProblem) -> Result<Self> {
        super::noise_gate(problem, super::EXACT)?;
        Self::assemble(drag, problem)
    }
}

impl<D: Drag, N: ExactNoise> SearchSampler<D, N> {
    /// The sampler of `problem` with its noise `N`: per state the
    /// segments and flows of [`ExactNoise`].
    fn assemble(drag: &D, problem: &SearchProblem) -> Result<Self> {
        let params = problem.params();
        let noise = N::of(params)?;
        let segs = noise.segments(drag, params)?;
        let flows = noise.flows(drag, params, "the exact sampler")?;
        let (lo, hi) = problem.target().bounds(problem.x0());
        Ok(SearchSampler {
            drag: drag.clone(),
            vs: flows.iter().map(|f| f.fixed_point()).collect(),
            clocks: Clocks::new(noise, params),
            segs,
            flows,
            x_reset: params.schedule().position.map(|p| p.x),
            lo,
            hi,
        })
    }

    /// One search from (x0, v0), the noise state by [`ExactNoise::start`]
    /// (the paper's: state `start`, 0: +Sigma, 1: -Sigma; a chain's drawn
    /// from π, `start` unused): (the first time x leaves the search
    /// region, or None if not by `t_max`; the number of events).
    pub fn run(
        &self,
        x0: f64,
        v0: f64,
        start: usize,
        t_max: f64,
        rng: &mut Rng,
    ) -> (Option<f64>, u64) {
        let si = self.clocks.noise.start(Some(start), rng);
        let a = self.segs[si].at(v0);
        let mut obs = PositionTarget {
            sampler: self,
            x: x0,
            a,
        };
        self.clocks.walk(si, t_max, rng, &mut obs)
    }

    /// x after flowing for `dt` from `a` (state `si`, position `x`), and the
    /// end point: x + v* dt - ∫ (v* - v) dt from the deficit antiderivatives.
    #[inline]
    fn advance(&self, si: usize, a: &FlowPoint, x: f64, dt: f64) -> (FlowPoint, f64) {
        let b = self.segs[si].advance(a, dt);
        (b, x + self.vs[si] * dt - (a.q[0] - b.q[0]))
    }

    /// Flow for `span` from `a` at position `x` in state `si`: the first
    /// crossing of a boundary inside, else the end point. x(t) is monotone
    /// on [0, t0] and [t0, span] with t0 the flow time to v = 0 (only when
    /// v starts on the other side of 0 from v*).
    fn segment(&self, si: usize, a: &FlowPoint, x: f64, span: f64) -> Segment {
        let vs = self.vs[si];
        let turn = if a.v * vs < 0.0 {
            self.flows[si].time(a.v, 0.0)
        } else {
            f64::INFINITY
        };
        // The direction of x before the turn (from v* where v starts at 0).
        let first_up = if a.v != 0.0 { a.v > 0.0 } else { vs > 0.0 };
        let (mut t1, mut x1, mut up) = (0.0, x, first_up);
        if turn < span {
            let (_, xb) = self.advance(si, a, x, turn);
            if let Some(tau) = self.piece(si, a, x, (0.0, x), (turn, xb), first_up) {
                return Segment::Hit(tau);
            }
            (t1, x1, up) = (turn, xb, vs > 0.0);
        }
        let end = if span.is_finite() {
            span
        } else if (up && self.hi.is_infinite()) || (!up && self.lo.is_infinite()) {
            // Endless and moving away from the only boundary: never a hit.
            return Segment::Moved(*a, x);
        } else {
            // An endless segment (no clock, no t_max): the flow towards
            // v* ≠ 0 crosses eventually; find a time beyond the crossing.
            self.beyond(si, a, x, t1, up)
        };
        let (b, xb) = self.advance(si, a, x, end);
        match self.piece(si, a, x, (t1, x1), (end, xb), up) {
            Some(tau) => Segment::Hit(tau),
            None => Segment::Moved(b, xb),
        }
    }

    /// A time after `from` at which the monotone piece moving `up` from
    /// `a` (position x) is past its boundary (doubling; the last doubling
    /// tried if the boundary is never passed within the f64 range).
    fn beyond(&self, si: usize, a: &FlowPoint, x: f64, from: f64, up: bool) -> f64 {
        let mut t = from.max(1.0) * 2.0;
        for _ in 0..2000 {
            let (_, xt) = self.advance(si, a, x, t);
            if (up && xt >= self.hi) || (!up && xt <= self.lo) || !(t * 2.0).is_finite() {
                return t;
            }
            t *= 2.0;
        }
        t
    }

    /// The crossing inside the monotone piece [t1, t2] of the segment from
    /// `a` (position x at its start), x(t1) = x1, x(t2) = x2, moving `up`
    /// (x increasing) or down: None unless x2 is at or past the boundary
    /// in that direction.
    fn piece(
        &self,
        si: usize,
        a: &FlowPoint,
        x: f64,
        (t1, x1): (f64, f64),
        (t2, x2): (f64, f64),
        up: bool,
    ) -> Option<f64> {
        let (bound, dir) = if up { (self.hi, 1.0) } else { (self.lo, -1.0) };
        if !(dir * (x2 - bound) >= 0.0) {
            return None;
        }
        let s = self.clocks.noise.levels()[si];
        // H(t) = ±(x(t) - bound), increasing on [t1, t2]: H(t1) < 0 <= H(t2).
        let h = |t: f64| {
            let (b, xt) = self.advance(si, a, x, t);
            let accel = self.drag.drift(s, b.v);
            (dir * (xt - bound), dir * b.v, dir * accel)
        };
        let frac = (bound - x1) / (x2 - x1);
        let frac = if frac.is_finite() {
            frac.clamp(0.0, 1.0)
        } else {
            0.5
        };
        let guess = t1 + (t2 - t1) * frac;
        Some(monotone_root(&h, t1, t2, guess))
    }
}

impl<D: Drag, N: ExactNoise> Observer for PositionTarget<'_, D, N> {
    const MODE: Mode = Mode::Passage;
    #[inline(always)]
    fn flow(&mut self, s: usize, t: f64, step: f64, _: f64, t_max: f64) -> Flow {
        let span = step.min(t_max - t);
        match self.sampler.segment(s, &self.a, self.x, span) {
            // At most t_max (t + (t_max - t) may round above it).
            Segment::Hit(tau) => Flow::Done(Some((t + tau).min(t_max))),
            _ if span < step || t + step >= t_max => Flow::Done(None),
            Segment::Moved(b, x) => {
                (self.a, self.x) = (b, x);
                Flow::Moved
            }
        }
    }
    #[inline(always)]
    fn jump(&mut self, _: usize, j: usize) {
        self.a = self.sampler.segs[j].at(self.a.v);
    }
    #[inline(always)]
    fn reset(&mut self, _: f64, _: f64, _: usize, _: usize) -> Option<f64> {
        if let Some(xr) = self.sampler.x_reset {
            self.x = xr;
        }
        None
    }
    /// The crossing of x + v t (held velocity) within the hold, if any.
    #[inline(always)]
    fn hold(&mut self, t: f64, v: f64, d: f64, t_max: f64) -> Option<f64> {
        let (lo, hi) = (self.sampler.lo, self.sampler.hi);
        if v == 0.0 || v.is_nan() {
            return None;
        }
        let bound = if v > 0.0 { hi } else { lo };
        let tau = (bound - self.x) / v;
        (tau <= d.min(t_max - t)).then_some((t + tau).min(t_max))
    }
    #[inline(always)]
    fn resume(&mut self, v: f64, s: usize, held: Option<f64>) {
        if let Some(d) = held {
            self.x += v * d;
        }
        self.a = self.sampler.segs[s].at(v);
    }
}

/// Root of the increasing H on [lo, hi] (H(lo) < 0 <= H(hi)): safeguarded
/// Halley steps ([`solve_increasing`], to ~1e-18 relative), falling back to
/// bisection to adjacent doubles where those do not converge (a crossing
/// at a turning point, where H' = v → 0).
fn monotone_root(h: &dyn Fn(f64) -> (f64, f64, f64), lo: f64, hi: f64, guess: f64) -> f64 {
    if let Ok(t) = solve_increasing(h, lo, hi, guess, 1e-6, 0.0) {
        return t;
    }
    let (mut a, mut b) = (lo, hi);
    loop {
        let m = 0.5 * (a + b);
        if !(m > a && m < b) {
            return b;
        }
        if h(m).0 >= 0.0 {
            b = m;
        } else {
            a = m;
        }
    }
}

/// The sampler of `problem` for the law `d`, over its noise states: the
/// paper's telegraph, or the chain of its noise model; `$f` runs with it.
macro_rules! with_sampler {
    ($problem:expr, |$d:ident, $s:ident| $body:expr) => {
        crate::with_drag!($problem.params().drag(), |$d| {
            if $problem.params().noise().is_some() {
                let $s = SearchSampler::with_chain($d, $problem)?;
                $body
            } else {
                let $s = SearchSampler::new($d, $problem)?;
                $body
            }
        })
    };
}

/// The unit totals of units `units` of the search run of `particles`
/// particles of `problem` by the exact sampler, through the method-agnostic
/// driver [`first_passage_units`] (particle i: stream (seed, i), stratum
/// i mod 2 of [`HALVES`], the start state: +Sigma for even i with the
/// paper's noise; drawn from π with a
/// noise model; censored at `t_max`), monomorphised for the law's type and
/// the noise states. Merged in unit order ([`stats`]) they are
/// bit-identical for any thread count and any split into parts.
pub fn units(
    problem: &SearchProblem,
    t_max: f64,
    particles: u64,
    seed: u64,
    units: Range<u64>,
    progress: &dyn Progress,
) -> Result<Vec<FptStats>> {
    let (x0, v0) = (problem.x0(), problem.v0());
    with_sampler!(problem, |d, sampler| Ok(first_passage_units(
        particles,
        units.clone(),
        seed,
        (t_max, &HALVES[..]),
        progress,
        |_, rng, k| {
            let (time, work) = sampler.run(x0, v0, k, t_max, rng);
            FptSample { time, work }
        },
    )))
}

/// Search statistics of `problem` by the exact sampler: all [`units`]
/// merged. Bit-identical for any thread count.
pub fn stats(
    problem: &SearchProblem,
    t_max: f64,
    particles: u64,
    seed: u64,
    progress: &dyn Progress,
) -> Result<FptStats> {
    let all = crate::parallel::unit_count(particles);
    let u = units(problem, t_max, particles, seed, 0..all, progress)?;
    Ok(merge_units(t_max, &u))
}

/// One search of `problem` (any law and noise, dispatched per call; for
/// many particles build a [`SearchSampler`] once, as [`stats`] does): the
/// passage time (None if not by `t_max`) and the number of events, from
/// noise state `start` (0: +Sigma, 1: -Sigma; a chain's drawn from π).
pub fn search_once(
    problem: &SearchProblem,
    start: usize,
    t_max: f64,
    rng: &mut Rng,
) -> Result<(Option<f64>, u64)> {
    with_sampler!(problem, |d, sampler| Ok(sampler.run(
        problem.x0(),
        problem.v0(),
        start,
        t_max,
        rng
    )))
}
