//! Exact first passage with a finite-state Markov noise (levels a_s,
//! generator Q) at temperature 0: docs/equations.md, "Exact first passage
//! with a finite-state noise", Eqs. (N46)-(N48).
//!
//! Events come at rate q_s + r in state s; one uniform u on [0, q_s + r)
//! picks a jump of the noise (u < q_s, its target by [`Chain::jump`] from
//! the same u) or a reset (velocity by the rule, noise kept or re-drawn
//! from π), as in the N-state simulation loop of [`crate::sim::exact`]
//! (Eq. (N10)). Between events the velocity follows the exact flow
//! dv/dt = a_s - g(v) toward v*_s = g⁻¹(a_s) (Eq. (N11)), which may be
//! interior (the pause of run-pause-tumble) and approached from either
//! side. In the canonical (upward) frame the walk stays below v_t, so a
//! segment crosses v_t iff v*_s > v_t, at the exact flow time
//! [`FlowMap::time`] from the segment's start, compared with the gap: no
//! time step, no overshoot (Eq. (N46)). A reset to v_r ≥ v_t is the
//! passage at the reset instant.
//!
//! A particle starts at v_0 in a state drawn from π (one uniform, the first
//! of its stream), so τ is the π-averaged mean passage time
//! Σ_s π_s T_s(v_0) of the backward equations (Eq. (N47)); the even and
//! odd particles (the `plus` and `minus` halves of
//! [`super::super::FptStats`]) are two independent halves of the same law,
//! as for the Euler particles with a noise model.
//!
//! The chain is a [`super::NoiseSpace`] of the one kernel
//! ([`super::walk`]) that also runs the paper's two-state
//! [`super::FirstPassage`] (with its stratified ±Sigma start); the
//! flows are those of the simulation (closed-form flows of tan, tanh and
//! linear drag on either side of a fixed point; for the other laws only
//! levels whose fixed point is the interval's edge farther from 0, where
//! their tabulated flows are exact), and the estimator and driver
//! ([`super::super::estimator`]) are shared.

use super::{NoiseSpace, Tally};
use crate::error::{Error, Result};
use crate::model::drag::FlowMap;
use crate::model::noise::chain::Chain;
use crate::model::reset::{Refractory, Reset, ResetRule, Schedule};
use crate::model::{Drag, DragLaw, Params};
use crate::rng::Rng;
use crate::sim::exact::{exp_gap, level_kind, LevelKind};
use rand::Rng as _;

/// The exact first-passage sampler of one upward (canonical) problem with
/// a noise model at T = 0.
#[derive(Clone, Debug)]
pub(crate) struct StatesPassage<F> {
    /// The flow of each level.
    flows: Vec<F>,
    /// Per state: its fixed point v*_s = g⁻¹(a_s).
    stars: Vec<f64>,
    /// Per state: its fixed point lies beyond v_t (its flow crosses v_t).
    crosses: Vec<bool>,
    chain: Chain,
    /// Per state: q_s + r.
    total: Vec<f64>,
    reset: ResetRule,
    /// The periodic or renewal clock and the refractory period.
    schedule: Schedule,
    vt: f64,
}

/// The flows of `levels` on the velocity interval `(lo, hi)`: accelerated
/// where the level's fixed point is the interval's edge farther from 0
/// (the paper's case), plain closed forms for the other levels of tan,
/// tanh and linear drag; refused naming `noise` otherwise, or at a kink of
/// the drag ([`level_kind`]).
fn level_flows<D: Drag>(
    drag: &D,
    (law, spec): (DragLaw, &str),
    levels: &[f64],
    bounds: (f64, f64),
) -> Result<Vec<D::Flow>> {
    levels
        .iter()
        .map(|&a| {
            let flow = drag.flow(a);
            Ok(
                match level_kind(drag, (law, spec), a, bounds, "mfpt --method exact")? {
                    LevelKind::Edge => flow.accelerated(),
                    LevelKind::Interior => flow,
                },
            )
        })
        .collect()
}

impl<F: FlowMap> StatesPassage<F> {
    /// The sampler of the upward problem to `vt` under `params` (a noise
    /// model at T = 0, its support checked by the caller; any schedule
    /// modifier, run by [`super::walk_scheduled`]): the flows as
    /// [`level_flows`] (memoised per law, levels and interval).
    pub(crate) fn new<D: Drag<Flow = F>>(drag: &D, params: &Params, vt: f64) -> Result<Self> {
        let model = params.noise_model()?;
        let chain = params.chain()?;
        if chain.temperature > 0.0 {
            return Err(Error::invalid(
                "temperature",
                chain.temperature,
                "temperature 0 for mfpt --method exact (no exact flow with thermal noise; \
                 mfpt --method euler runs it)",
            ));
        }
        let bounds = params.bounds();
        let bits: Vec<String> = chain
            .levels
            .iter()
            .chain([&bounds.0, &bounds.1])
            .map(|a| format!("{:x}", a.to_bits()))
            .collect();
        let key = format!("first passage states {drag:?} {}", bits.join(","));
        let spec = model.spec();
        let flows = crate::memo::shared(key, || {
            level_flows(drag, (params.drag(), &spec), &chain.levels, bounds)
        })?;
        let flows = (*flows).clone();
        let stars: Vec<f64> = chain.levels.iter().map(|&a| drag.inverse(a)).collect();
        let crosses = stars.iter().map(|&star| star > vt).collect();
        let reset = *params.reset();
        let total = chain.exit.iter().map(|q| q + reset.rate()).collect();
        Ok(StatesPassage {
            flows,
            stars,
            crosses,
            chain,
            total,
            reset,
            schedule: *params.schedule(),
            vt,
        })
    }

    /// The flow and fixed point of each state, the chain and the resetting
    /// rule (for the control variate of [`super::super::control`]).
    pub(crate) fn parts(&self) -> (&[F], &[f64], &Chain, &ResetRule) {
        (&self.flows, &self.stars, &self.chain, &self.reset)
    }

    /// One upward first passage from `v0` < v_t, the start state drawn
    /// from π with the stream's first uniform: (passage time, or None if
    /// not reached by `t_max`; number of events).
    pub(crate) fn run(&self, v0: f64, t_max: f64, rng: &mut Rng) -> (Option<f64>, u64) {
        self.walk(v0, t_max, rng, &mut ())
    }

    /// [`StatesPassage::run`] reporting the start, every flow segment and
    /// jump to `tally` (the random stream consumed exactly as by `run`).
    #[inline(always)]
    pub(crate) fn walk<T: Tally>(
        &self,
        v0: f64,
        t_max: f64,
        rng: &mut Rng,
        tally: &mut T,
    ) -> (Option<f64>, u64) {
        let s = self.chain.draw_stationary(rng.gen::<f64>());
        if v0 >= self.vt {
            return (Some(0.0), 0);
        }
        if self.schedule.scheduled_clock() || self.schedule.refractory.is_some() {
            return super::walk_scheduled(self, s, v0, self.vt, t_max, rng);
        }
        tally.start(v0, s);
        super::walk(self, s, v0, self.vt, t_max, rng, tally)
    }
}

impl<F: FlowMap> NoiseSpace for StatesPassage<F> {
    type Flow = F;
    #[inline(always)]
    fn flow(&self, s: usize) -> &F {
        &self.flows[s]
    }
    #[inline(always)]
    fn crosses(&self, s: usize) -> bool {
        self.crosses[s]
    }
    #[inline(always)]
    fn total(&self, s: usize) -> f64 {
        self.total[s]
    }
    #[inline(always)]
    fn event(&self, s: usize, u: f64) -> Option<usize> {
        (u < self.chain.exit[s]).then(|| self.chain.jump(s, u))
    }
    #[inline(always)]
    fn reset(&self, s: usize, rng: &mut Rng) -> (f64, usize) {
        let w = self.reset.draw_velocity(rng);
        (w, self.reset.draw_noise_state(s, &self.chain, rng))
    }
    /// The chain run alone for `d` (exact: its exponential holding times
    /// and jumps, Eq. (N10)).
    fn hold(&self, mut s: usize, mut d: f64, rng: &mut Rng) -> usize {
        loop {
            let exit = self.chain.exit[s];
            let gap = exp_gap(rng, exit);
            if gap >= d {
                return s;
            }
            d -= gap;
            s = self.chain.jump(s, rng.gen::<f64>() * exit);
        }
    }
    fn schedule(&self) -> (&Schedule, Option<Refractory>) {
        (&self.schedule, self.schedule.refractory)
    }
}
