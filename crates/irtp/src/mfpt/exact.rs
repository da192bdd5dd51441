//! Exact first passage: the event-driven sampler of [`crate::sim::exact`]
//! run until the velocity reaches the target. Between events (noise flips,
//! resets; a Poisson clock of rate lambda + r) the velocity follows the exact
//! flow dv/dt = s - g(v) (Eq. (5)), and a flow segment is tested with the
//! exact flow time to v_t: no time step, no overshoot. Estimates are gathered
//! by [`super::first_passage_stats`]'s driver; the entry point is [`super::solve`] with
//! [`super::Method::Exact`].
//!
//! With a periodic reset clock (resets at T, 2T, ... from t = 0) or a
//! renewal clock (the next reset a drawn waiting time after the last one,
//! or after the end of its refractory period) a flow segment also ends at
//! the next scheduled time; after a reset with a
//! refractory period of duration D the velocity is held at the reset
//! velocity (below v_t, or the reset itself is the passage), so the period
//! cannot cross v_t: it advances the time by D and flips the noise state
//! with the probability of an odd number of flips, ½(1 - e^{-2 lambda D});
//! Poisson resets are off during it and the periodic times inside it or at
//! its end are skipped. With a finite-state noise the chain runs on alone
//! during the period (its own holding times and jumps).
//!
//! One kernel runs every noise ([`Passage`]: `walk`, `walk_scheduled`),
//! generic over the noise state space ([`ExactNoise`]): the paper's noise
//! ([`FirstPassage`], two states, started stratified: +Sigma for even
//! particles) and any finite-state noise at T = 0 (docs/equations.md Eqs.
//! (N46)-(N48): events at rate q_s + r, a fixed point v*_s = g⁻¹(a_s)
//! possibly interior and approached from either side). In the canonical
//! (upward) frame a segment crosses v_t iff v*_s > v_t. A chain's particle
//! starts in a state drawn from π (the stream's first uniform), so τ is
//! the π-averaged Σ_s π_s T_s(v_0) of the backward equations (Eq. (N47))
//! and the even and odd particles (the `plus` and `minus` halves of
//! [`FptStats`]) are two independent halves of the same law. The noise
//! is dispatched once, at the entry (`units`).

use super::estimator::{first_passage_units, FptSample, FptStats};
use super::Problem;
use crate::error::{Error, Result};
use crate::model::drag::{AnyFlow, FlowMap};
use crate::model::noise::chain::Chain;
use crate::model::reset::{Reset, ResetRule, Schedule};
use crate::model::{Drag, Params};
use crate::parallel::Progress;
use crate::rng::Rng;
use crate::sim::exact::{exp_gap, ExactNoise, Telegraph};
use rand::Rng as _;

/// Exact first passage of v to `vt` from below: the first time v(t) ≥ vt,
/// starting at v(0) = v0 in noise state +Sigma (`start_plus`) or -Sigma.
/// A flow segment is tested with the exact flow time to vt (no overshoot);
/// a reset to v_r ≥ vt counts as passage at the reset instant. Returns
/// (passage time, or None if not reached by `t_max`; number of events).
/// For many particles build a [`FirstPassage`] once instead (faster).
pub fn first_passage(
    params: &Params,
    v0: f64,
    vt: f64,
    start_plus: bool,
    t_max: f64,
    rng: &mut Rng,
) -> (Option<f64>, u64) {
    FirstPassage::new(params).run(v0, vt, start_plus, t_max, rng)
}

/// The prepared exact first-passage sampler of the paper's noise.
pub type FirstPassage<F = AnyFlow> = Passage<F, Telegraph>;

/// Prepared exact first-passage sampler for one parameter set and its
/// noise `N` (flows and their acceleration tables built once, shared
/// through [`crate::memo`]); see [`first_passage`].
#[derive(Clone, Debug)]
pub struct Passage<F, N> {
    /// The flow of each state.
    flows: Vec<F>,
    /// Per state: its fixed point v*_s = g⁻¹(a_s); its flow crosses v_t
    /// iff v*_s > v_t.
    stars: Vec<f64>,
    noise: N,
    /// Per state: q_s + r.
    total: Vec<f64>,
    /// The resetting rule (target and noise state at a reset).
    reset: ResetRule,
    /// The periodic or renewal clock and the refractory period.
    schedule: Schedule,
}

impl FirstPassage {
    /// Prepare for `params` (any law, dispatched per call; engines use
    /// [`FirstPassage::for_drag`] with the law's own type).
    pub fn new(params: &Params) -> Self {
        Self::for_drag(&params.drag(), params)
    }
}

impl<F: FlowMap> FirstPassage<F> {
    /// Prepare for `params` with the (accelerated) flows of `drag`.
    pub fn for_drag<D: Drag<Flow = F>>(drag: &D, params: &Params) -> Self {
        Self::build(drag, params).expect("the paper's flows are built at every Sigma")
    }

    /// (lambda, r, the resetting rule).
    pub(super) fn rates(&self) -> (f64, f64, &ResetRule) {
        (self.noise.exit(0), self.reset.rate(), &self.reset)
    }
}

impl<F: FlowMap, N: ExactNoise> Passage<F, N> {
    /// The sampler of the upward problem under `params` (any schedule
    /// modifier, run by [`walk_scheduled`]): the flows of [`ExactNoise`],
    /// memoised per noise kind, law, levels and interval; refused naming
    /// `temperature` at T > 0 or `noise` where a level's flow is not exact.
    pub(crate) fn build<D: Drag<Flow = F>>(drag: &D, params: &Params) -> Result<Self> {
        if let Some(t) = params.noise().map(|m| m.temperature()).filter(|&t| t > 0.0) {
            return Err(Error::invalid(
                "temperature",
                t,
                "temperature 0 for mfpt --method exact (no exact flow with thermal noise; \
                 mfpt --method euler runs it)",
            ));
        }
        let noise = N::of(params)?;
        let bounds = params.bounds();
        let bits: Vec<String> = noise
            .levels()
            .iter()
            .chain([&bounds.0, &bounds.1])
            .map(|a| format!("{:x}", a.to_bits()))
            .collect();
        let kind = std::any::type_name::<N>();
        let key = format!("first passage {kind} {drag:?} {}", bits.join(","));
        let flows = crate::memo::shared(key, || noise.flows(drag, params, "mfpt --method exact"))?;
        let reset = *params.reset();
        Ok(Passage {
            flows: (*flows).clone(),
            stars: noise.levels().iter().map(|&a| drag.inverse(a)).collect(),
            total: noise.clocks(reset.rate()),
            noise,
            reset,
            schedule: params.schedule().clone(),
        })
    }

    /// The flow and fixed point of each state, the noise and the resetting
    /// rule (for the control variate of [`super::control`]).
    pub(crate) fn parts(&self) -> (&[F], &[f64], &N, &ResetRule) {
        (&self.flows, &self.stars, &self.noise, &self.reset)
    }

    /// The periodic or renewal clock and the refractory period.
    pub(crate) fn schedule(&self) -> &Schedule {
        &self.schedule
    }

    /// One upward first passage, as [`first_passage`] (the start state by
    /// [`ExactNoise::start`]: the paper's +Sigma where `start_plus`, a
    /// chain's drawn from π with the stream's first uniform).
    pub fn run(
        &self,
        v0: f64,
        vt: f64,
        start_plus: bool,
        t_max: f64,
        rng: &mut Rng,
    ) -> (Option<f64>, u64) {
        self.walk(v0, vt, start_plus, t_max, rng, &mut ())
    }

    /// [`Passage::run`] reporting the start, every flow segment and jump
    /// of the walk to `tally` (the random stream is consumed exactly as by
    /// `run`, so the passage time is the same bits). Periodic and
    /// refractory schedules report nothing: their clock is not a Poisson
    /// one.
    #[inline(always)]
    pub fn walk<T: Tally>(
        &self,
        v0: f64,
        vt: f64,
        start_plus: bool,
        t_max: f64,
        rng: &mut Rng,
        tally: &mut T,
    ) -> (Option<f64>, u64) {
        let s = self.noise.start(Some(state(start_plus)), rng);
        if v0 >= vt {
            return (Some(0.0), 0);
        }
        if self.schedule.scheduled_clock() || self.schedule.refractory.is_some() {
            return walk_scheduled(self, s, v0, vt, t_max, rng);
        }
        tally.start(v0, s);
        walk(self, s, v0, vt, t_max, rng, tally)
    }

    /// The reset's velocity and the noise state after it (in this order
    /// from `rng`).
    #[inline(always)]
    fn reset(&self, s: usize, rng: &mut Rng) -> (f64, usize) {
        let w = self.reset.draw_velocity(rng);
        (w, self.noise.after_reset(s, &self.reset, rng))
    }
}

/// The exact first passage of `space` from (v0 < v_t, state s) under
/// Poisson events (module docs), reporting to `tally`: (passage time, or
/// None if not reached by `t_max`; number of events).
#[inline(always)]
pub(crate) fn walk<F: FlowMap, N: ExactNoise, T: Tally>(
    space: &Passage<F, N>,
    mut s: usize,
    v0: f64,
    vt: f64,
    t_max: f64,
    rng: &mut Rng,
    tally: &mut T,
) -> (Option<f64>, u64) {
    let (mut t, mut v) = (0.0f64, v0);
    let mut events = 0u64;
    loop {
        let total = space.total[s];
        let gap = exp_gap(rng, total);
        v = match segment(space, s, v, vt, t, gap, t_max) {
            Segment::Done(hit) => {
                if let Some(hit) = hit {
                    tally.flow(s, v, vt, hit - t);
                }
                return (hit, events);
            }
            Segment::Moved(w) => {
                tally.flow(s, v, w, gap);
                w
            }
        };
        t += gap;
        events += 1;
        if let Some(j) = space.noise.event(s, rng.gen::<f64>() * total) {
            tally.jump(v, s, Some((v, j)));
            s = j;
        } else {
            let (w, after) = space.reset(s, rng);
            if w >= vt {
                tally.jump(v, s, None);
                return (Some(t), events);
            }
            tally.jump(v, s, Some((w, after)));
            (v, s) = (w, after);
        }
    }
}

/// The index of the paper's noise state in a [`Tally`]: 0 for +Sigma, 1
/// for -Sigma (the order of [`FirstPassage`]'s flows).
#[inline(always)]
pub fn state(plus: bool) -> usize {
    usize::from(!plus)
}

/// An observer of a first-passage walk ([`FirstPassage::walk`], and the
/// N-state walk of a noise model): the passage-time control variate of
/// [`super::control`] integrates along it. Noise states are indices (the
/// paper's: [`state`]). `()` observes nothing and compiles away.
pub trait Tally {
    /// The walk's start in state `s` at `v` (called by the N-state walk,
    /// whose start state is drawn from π).
    #[inline(always)]
    fn start(&mut self, _v: f64, _s: usize) {}
    /// A flow segment in noise state `s` from `va` to `vb` lasting `dt`
    /// (the last one ends at v_t).
    fn flow(&mut self, s: usize, va: f64, vb: f64, dt: f64);
    /// A flip or reset from (v, s) to `after`; `None` when the jump is
    /// the passage (a reset at or beyond v_t).
    fn jump(&mut self, v: f64, s: usize, after: Option<(f64, usize)>);
}

impl Tally for () {
    #[inline(always)]
    fn flow(&mut self, _: usize, _: f64, _: f64, _: f64) {}
    #[inline(always)]
    fn jump(&mut self, _: f64, _: usize, _: Option<(f64, usize)>) {}
}

/// The end of one flow segment of [`FirstPassage`].
enum Segment {
    /// The walk is over: the passage time, or None past t_max.
    Done(Option<f64>),
    /// The velocity at the segment's end (no passage, t_max not reached).
    Moved(f64),
}

/// Flow for `step` from (t, v) in state `s`: the passage if the flow
/// crosses v_t within the step (None when that is past t_max), a stop when
/// the step reaches t_max, else the velocity at its end.
#[inline(always)]
fn segment<F: FlowMap, N>(
    space: &Passage<F, N>,
    s: usize,
    v: f64,
    vt: f64,
    t: f64,
    step: f64,
    t_max: f64,
) -> Segment {
    let flow = &space.flows[s];
    if space.stars[s] > vt {
        let tau = flow.time(v, vt);
        if tau <= step {
            let hit = t + tau;
            return Segment::Done(if hit <= t_max { Some(hit) } else { None });
        }
    }
    if t + step >= t_max {
        return Segment::Done(None);
    }
    Segment::Moved(flow.velocity(v, step))
}

/// [`walk`] with a periodic or renewal clock and/or a refractory period
/// (module docs); nothing is reported (the clock is not a Poisson one).
pub(crate) fn walk_scheduled<F: FlowMap, N: ExactNoise>(
    space: &Passage<F, N>,
    mut s: usize,
    v0: f64,
    vt: f64,
    t_max: f64,
    rng: &mut Rng,
) -> (Option<f64>, u64) {
    let (schedule, refractory) = (&space.schedule, space.schedule.refractory);
    let (mut t, mut v) = (0.0f64, v0);
    let mut next_periodic = schedule.first_reset(rng);
    let mut events = 0u64;
    loop {
        let total = space.total[s];
        let gap = exp_gap(rng, total);
        let periodic = next_periodic - t <= gap;
        let step = if periodic { next_periodic - t } else { gap };
        v = match segment(space, s, v, vt, t, step, t_max) {
            Segment::Done(hit) => return (hit, events),
            Segment::Moved(v) => v,
        };
        t = if periodic { next_periodic } else { t + step };
        events += 1;
        if !periodic {
            if let Some(j) = space.noise.event(s, rng.gen::<f64>() * total) {
                s = j;
                continue;
            }
        }
        (v, s) = space.reset(s, rng);
        if v >= vt {
            return (Some(t), events);
        }
        if let Some(r) = refractory {
            let d = r.draw(rng);
            if t + d >= t_max {
                return (None, events);
            }
            s = space.noise.after_hold(s, d, rng);
            t += d;
            events += 1;
        }
        if schedule.scheduled_clock() {
            next_periodic = schedule.next_reset(t, rng);
        }
    }
}

/// [`first_passage`] in either direction: the first time v(t) reaches `vt`
/// from `v0` (from below or from above). A downward problem is the upward
/// one under v → -v (all drag laws are odd): v0, vt and v_r change sign and
/// the noise states swap, so both directions share one code path.
pub fn first_passage_to(
    params: &Params,
    v0: f64,
    vt: f64,
    start_plus: bool,
    t_max: f64,
    rng: &mut Rng,
) -> Result<(Option<f64>, u64)> {
    if v0 <= vt {
        return Ok(first_passage(params, v0, vt, start_plus, t_max, rng));
    }
    let mirrored = params.mirrored_reset();
    Ok(first_passage(&mirrored, -v0, -vt, !start_plus, t_max, rng))
}

/// Validate a first-passage time cap (`t_max`): t_max > 0 (+∞ allowed:
/// with lambda > 0 every particle arrives almost surely).
pub fn check_t_max(t_max: f64) -> Result<f64> {
    if !(t_max > 0.0) {
        return Err(Error::invalid("t_max", t_max, "t_max > 0 (inf allowed)"));
    }
    Ok(t_max)
}

/// Refuse what the exact first-passage sampler does not run for `problem`,
/// beyond [`check_t_max`] and the support table: with a noise model other
/// than the paper's, thermal noise (`temperature`) and the levels a law's
/// flows do not run (`noise`); every schedule modifier runs.
pub(super) fn check_problem(problem: &Problem) -> Result<()> {
    if problem.params().noise().is_none() {
        return Ok(());
    }
    problem
        .params()
        .require(crate::model::reset::Solver::MfptExact)?;
    let (cp, _) = problem.canonical();
    crate::with_drag!(cp.params().drag(), |d| {
        Passage::<_, Chain>::build(d, cp.params()).map(|_| ())
    })
}

/// The unit totals of units `units` of the first-passage run of `problem`
/// (either direction) by the exact sampler over `particles` particles,
/// through the method-agnostic driver
/// ([`super::estimator::first_passage_units`]: particle i has the stream
/// (seed, i), start state +Sigma for even i; with a noise model other than
/// the paper's a state drawn from π, the even and odd particles two halves
/// of one law). Downward problems run in the mirrored upward frame
/// ([`Problem::canonical`]), where the noise states swap (a noise model's
/// levels are negated state for state). Inputs are checked by
/// [`super::Method::check`].
pub(super) fn units(
    problem: &Problem,
    t_max: f64,
    particles: u64,
    seed: u64,
    units: std::ops::Range<u64>,
    progress: &dyn Progress,
) -> Vec<FptStats> {
    let (cp, swapped) = problem.canonical();
    crate::with_drag!(cp.params().drag(), |d| {
        let run = (t_max, particles, seed, units.clone());
        if cp.params().noise().is_some() {
            noise_units::<_, Chain>(d, &cp, swapped, run, progress)
        } else {
            noise_units::<_, Telegraph>(d, &cp, swapped, run, progress)
        }
    })
}

/// [`units`] of the canonical problem `cp` with the noise `N`; the
/// stratum of particle i is its parity, its state swapped in a mirrored
/// frame (`swapped`).
fn noise_units<D: Drag, N: ExactNoise>(
    d: &D,
    cp: &Problem,
    swapped: bool,
    (t_max, particles, seed, units): (f64, u64, u64, std::ops::Range<u64>),
    progress: &dyn Progress,
) -> Vec<FptStats> {
    let fpt = Passage::<D::Flow, N>::build(d, cp.params()).expect("checked by Method::check");
    first_passage_units(particles, units, seed, t_max, progress, |_, rng, plus| {
        let (time, work) = fpt.run(cp.v0(), cp.vt(), plus != swapped, t_max, rng);
        FptSample { time, work }
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng;

    #[test]
    fn downward_passage_is_mirrored_upward() {
        use crate::model::DragLaw;
        let p = Params::new(DragLaw::Tanh, 0.6, 1.2, 0.5, 0.1).unwrap();
        let q = p.with_reset_velocity(-0.1).unwrap();
        for i in 0..50 {
            let (mut a, mut b) = (rng::stream(9, i), rng::stream(9, i));
            let down = first_passage_to(&p, 0.2, -0.3, i % 2 == 0, 1e3, &mut a).unwrap();
            let up = first_passage(&q, -0.2, 0.3, i % 2 == 1, 1e3, &mut b);
            assert_eq!(down, up);
            assert!(down.0.is_some());
        }
    }
}
