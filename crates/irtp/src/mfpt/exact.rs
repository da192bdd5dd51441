//! Exact first passage: the event-driven sampler of [`crate::sim::exact`]
//! run until the velocity reaches the target. Between events (noise flips,
//! resets; a Poisson clock of rate lambda + r) the velocity follows the exact
//! flow dv/dt = s - g(v) (Eq. (5)), and a flow segment is tested with the
//! exact flow time to v_t: no time step, no overshoot. Estimates are gathered
//! by [`super::first_passage_stats`]'s driver; the entry point is [`super::solve`] with
//! [`super::Method::Exact`].
//!
//! Clocks, resets and refractory holds are those of the walk kernel
//! (`sim::exact::passage`); a hold keeps v at the reset velocity (below
//! v_t, or the reset itself is the passage), so it cannot cross v_t.
//!
//! The walk is that kernel with the velocity-target observer, generic
//! over the noise state space ([`ExactNoise`]): the paper's noise
//! ([`FirstPassage`], two states, started stratified: +Sigma for even
//! particles) and any finite-state noise at T = 0 (docs/equations.md Eqs.
//! (N46)-(N48): events at rate q_s + r, a fixed point v*_s = g⁻¹(a_s)
//! possibly interior and approached from either side). In the canonical
//! (upward) frame a segment crosses v_t iff v*_s > v_t. A chain's particle
//! starts in a state drawn from π (the stream's first uniform), so τ is
//! the π-averaged Σ_s π_s T_s(v_0) of the backward equations (Eq. (N47))
//! and the even and odd particles (strata 0 and 1 of [`FptStats`], the
//! `plus` and `minus` halves of its summary) are two independent halves
//! of the same law. The noise
//! is dispatched once, at the entry (`units`).

use super::estimator::{first_passage_units, FptSample, FptStats, HALVES};
use super::Problem;
use crate::error::{Error, Result};
use crate::model::drag::{AnyFlow, FlowMap};
use crate::model::noise::chain::Chain;
use crate::model::reset::{Reset, ResetRule, Schedule};
use crate::model::{Drag, Params};
use crate::parallel::Progress;
use crate::rng::Rng;
use crate::sim::exact::passage::{Clocks, Flow, Mode, Observer};
use crate::sim::exact::{ExactNoise, Telegraph};

/// Exact first passage of v to `vt` from below: the first time v(t) ≥ vt,
/// starting at v(0) = v0 in noise state `start` (0: +Sigma, 1: -Sigma).
/// A flow segment is tested with the exact flow time to vt (no overshoot);
/// a reset to v_r ≥ vt counts as passage at the reset instant. Returns
/// (passage time, or None if not reached by `t_max`; number of events).
/// For many particles build a [`FirstPassage`] once instead (faster).
pub fn first_passage(
    params: &Params,
    v0: f64,
    vt: f64,
    start: usize,
    t_max: f64,
    rng: &mut Rng,
) -> (Option<f64>, u64) {
    FirstPassage::new(params).run(v0, vt, start, t_max, rng)
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
    /// The noise, its event rates, the resetting rule and the schedule.
    clocks: Clocks<N>,
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
        let c = &self.clocks;
        (c.noise.exit(0), c.reset.rate(), &c.reset)
    }
}

impl<F: FlowMap, N: ExactNoise> Passage<F, N> {
    /// The sampler of the upward problem under `params` (any schedule
    /// modifier): the flows of [`ExactNoise`],
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
        Ok(Passage {
            flows: (*flows).clone(),
            stars: noise.levels().iter().map(|&a| drag.inverse(a)).collect(),
            clocks: Clocks::new(noise, params),
        })
    }

    /// The flow and fixed point of each state, the noise and the resetting
    /// rule (for the control variate of [`super::control`]).
    pub(crate) fn parts(&self) -> (&[F], &[f64], &N, &ResetRule) {
        let c = &self.clocks;
        (&self.flows, &self.stars, &c.noise, &c.reset)
    }

    /// The periodic or renewal clock and the refractory period.
    pub(crate) fn schedule(&self) -> &Schedule {
        &self.clocks.schedule
    }

    /// One upward first passage, as [`first_passage`] (the start state by
    /// [`ExactNoise::start`]: the paper's state `start` (0: +Sigma, 1:
    /// -Sigma), a chain's drawn from π with the stream's first uniform,
    /// `start` unused).
    pub fn run(
        &self,
        v0: f64,
        vt: f64,
        start: usize,
        t_max: f64,
        rng: &mut Rng,
    ) -> (Option<f64>, u64) {
        self.walk(v0, vt, start, t_max, rng, &mut ())
    }

    /// [`Passage::run`] reporting the start, every flow segment and jump
    /// of the walk to `tally` (the random stream is consumed exactly as by
    /// `run`, so the passage time is the same bits; the control variate
    /// of [`super::control`] refuses the walks of a scheduled clock or a
    /// refractory period).
    #[inline(always)]
    pub fn walk<T: Tally>(
        &self,
        v0: f64,
        vt: f64,
        start: usize,
        t_max: f64,
        rng: &mut Rng,
        tally: &mut T,
    ) -> (Option<f64>, u64) {
        let s = self.clocks.noise.start(Some(start), rng);
        if v0 >= vt {
            return (Some(0.0), 0);
        }
        tally.start(v0, s);
        let mut obs = VelocityTarget {
            flows: &self.flows,
            stars: &self.stars,
            v: v0,
            vt,
            tally,
        };
        self.clocks.walk(s, t_max, rng, &mut obs)
    }
}

/// An observer of a first-passage walk ([`FirstPassage::walk`], and the
/// N-state walk of a noise model): the passage-time control variate of
/// [`super::control`] integrates along it. Noise states are indices (the
/// paper's: 0 for +Sigma, 1 for -Sigma). `()` observes nothing and compiles away.
pub trait Tally {
    /// The walk's start in state `s` at `v` (a chain's start state is
    /// drawn from π).
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

/// The velocity-target observer of the walk kernel: v along the walk,
/// the passage the first time v reaches v_t from below (a flow segment
/// tested with the exact flow time to v_t, which it crosses iff
/// v*_s > v_t; a reset to v_r ≥ v_t is the passage at the reset
/// instant), every segment and jump reported to `tally`.
struct VelocityTarget<'a, F, T> {
    flows: &'a [F],
    stars: &'a [f64],
    v: f64,
    vt: f64,
    tally: &'a mut T,
}

impl<F: FlowMap, T: Tally> Observer for VelocityTarget<'_, F, T> {
    const MODE: Mode = Mode::Passage;
    #[inline(always)]
    fn flow(&mut self, s: usize, t: f64, step: f64, _: f64, t_max: f64) -> Flow {
        let flow = &self.flows[s];
        if self.stars[s] > self.vt {
            let tau = flow.time(self.v, self.vt);
            if tau <= step {
                let hit = t + tau;
                if hit > t_max {
                    return Flow::Done(None);
                }
                self.tally.flow(s, self.v, self.vt, hit - t);
                return Flow::Done(Some(hit));
            }
        }
        if t + step >= t_max {
            return Flow::Done(None);
        }
        let w = flow.velocity(self.v, step);
        self.tally.flow(s, self.v, w, step);
        self.v = w;
        Flow::Moved
    }
    #[inline(always)]
    fn jump(&mut self, s: usize, j: usize) {
        self.tally.jump(self.v, s, Some((self.v, j)));
    }
    #[inline(always)]
    fn reset(&mut self, t: f64, v: f64, s: usize, after: usize) -> Option<f64> {
        if v >= self.vt {
            self.tally.jump(self.v, s, None);
            return Some(t);
        }
        self.tally.jump(self.v, s, Some((v, after)));
        None
    }
    #[inline(always)]
    fn resume(&mut self, v: f64, _: usize, _: Option<f64>) {
        self.v = v;
    }
}

/// [`first_passage`] in either direction: the first time v(t) reaches `vt`
/// from `v0` (from below or from above). A downward problem is the upward
/// one under v → -v (all drag laws are odd): v0, vt and v_r change sign and
/// the noise states swap (`start` 0: +Sigma, 1: -Sigma becomes 1 - `start`),
/// so both directions share one code path.
pub fn first_passage_to(
    params: &Params,
    v0: f64,
    vt: f64,
    start: usize,
    t_max: f64,
    rng: &mut Rng,
) -> Result<(Option<f64>, u64)> {
    if v0 <= vt {
        return Ok(first_passage(params, v0, vt, start, t_max, rng));
    }
    let mirrored = params.mirrored_reset();
    Ok(first_passage(&mirrored, -v0, -vt, 1 - start, t_max, rng))
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
/// (seed, i), stratum i mod 2 of [`HALVES`]: the paper's start state
/// +Sigma for even i; with a noise model other than the paper's a state
/// drawn from π, the even and odd particles two halves of one law). Downward problems run in the mirrored upward frame
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
/// stratum of particle i is its parity, the paper's start state that
/// stratum's, swapped in a mirrored frame (`swapped`).
fn noise_units<D: Drag, N: ExactNoise>(
    d: &D,
    cp: &Problem,
    swapped: bool,
    (t_max, particles, seed, units): (f64, u64, u64, std::ops::Range<u64>),
    progress: &dyn Progress,
) -> Vec<FptStats> {
    let fpt = Passage::<D::Flow, N>::build(d, cp.params()).expect("checked by Method::check");
    let run = (t_max, &HALVES[..]);
    first_passage_units(particles, units, seed, run, progress, |_, rng, k| {
        let start = if swapped { 1 - k } else { k };
        let (time, work) = fpt.run(cp.v0(), cp.vt(), start, t_max, rng);
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
            let s = (i % 2) as usize;
            let down = first_passage_to(&p, 0.2, -0.3, s, 1e3, &mut a).unwrap();
            let up = first_passage(&q, -0.2, 0.3, 1 - s, 1e3, &mut b);
            assert_eq!(down, up);
            assert!(down.0.is_some());
        }
    }
}
