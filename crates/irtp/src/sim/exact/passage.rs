//! The event-to-event kernel of the exact first-passage samplers: one loop
//! ([`Clocks::walk`]) advances the time, the noise state, the reset clock
//! and the refractory hold from event to event, and an observer
//! ([`PassageObserver`]) carries what moves along a flow segment (v, or v
//! and x) and decides what a segment, a reset or a hold means.
//!
//! Events: in state s a Poisson clock of rate q_s + r (its uniform picks a
//! noise jump or a reset, [`ExactNoise::event`]); with a periodic clock
//! (resets at T, 2T, ... from t = 0) or a renewal clock (the next reset a
//! drawn waiting time after the last one, or after the end of its
//! refractory period) also the scheduled reset times, where a segment
//! ends. A reset draws the velocity from the rule's target, then the noise
//! state after it; with a refractory period of duration D (drawn next) the
//! velocity is held, Poisson resets are off, the periodic times inside it
//! or at its end are skipped, and the noise runs on
//! ([`ExactNoise::after_hold`]: the paper's flips with the probability
//! ½(1 - e^{-2 lambda D}) of an odd number of flips, a chain's jumps are
//! drawn one by one). The random stream is consumed in this order by
//! every observer, so a passage time depends on the observer only through
//! where it stops the walk.
//!
//! Observers:
//! - the velocity target of `mfpt::exact` (first time v reaches v_t from
//!   below; a reset to v_r ≥ v_t is the passage), which also reports its
//!   segments and jumps to a `Tally` (the control variate of
//!   `mfpt::control`);
//! - the position target of `search::exact` (first exit of x from the
//!   search region; x → x_r at a reset with position resetting; x moves
//!   linearly during a hold).
//!
//! A new observable is one [`PassageObserver`] impl: its state between
//! events and its answers (a flow segment, a jump, a reset, a hold, the
//! flow's restart after a reset); [`Clocks::walk`] runs it unchanged.

use super::ExactNoise;
use crate::model::reset::{Reset, ResetRule, Schedule};
use crate::model::Params;
use crate::rng::Rng;
use crate::sim::exact::exp_gap;
use rand::Rng as _;

/// The end of one flow segment: the walk is over (Done: the passage
/// time, or None where t_max comes first), or it Moved to the segment's
/// end without a passage (the observer holds the state there).
pub(crate) enum Flow {
    Done(Option<f64>),
    Moved,
}

/// What a first-passage walk means: the observer keeps the quantities
/// that move along a flow segment and says where the walk stops. States
/// are noise-state indices of [`ExactNoise`].
pub(crate) trait PassageObserver {
    /// Flow in state `s` for `step` from time `t` (the segment's end is
    /// the next event): Done with the passage time within it (None where
    /// the walk reaches `t_max` first), else Moved.
    fn flow(&mut self, s: usize, t: f64, step: f64, t_max: f64) -> Flow;
    /// A noise jump from state `s` to `j` at the current point.
    fn jump(&mut self, s: usize, j: usize);
    /// A reset at time `t` to velocity `v`, the noise from `s` to
    /// `after`: the passage time where the reset is the passage.
    fn reset(&mut self, t: f64, v: f64, s: usize, after: usize) -> Option<f64>;
    /// A refractory hold of duration `d` from time `t` at velocity `v`:
    /// the passage time inside it (capped at `t_max`), if any (none by
    /// default: the velocity is constant).
    #[inline(always)]
    fn hold(&mut self, _t: f64, _v: f64, _d: f64, _t_max: f64) -> Option<f64> {
        None
    }
    /// The walk flows on from velocity `v` in state `s` after a reset,
    /// `held` the hold's duration (None without a refractory period).
    fn resume(&mut self, v: f64, s: usize, held: Option<f64>);
}

/// The event clocks of a first-passage walk: the noise, its per-state
/// event rates q_s + r, the resetting rule and the schedule.
#[derive(Clone, Debug)]
pub(crate) struct Clocks<N> {
    pub noise: N,
    /// Per state: q_s + r.
    pub total: Vec<f64>,
    pub reset: ResetRule,
    pub schedule: Schedule,
}

impl<N: ExactNoise> Clocks<N> {
    /// The clocks of `params` with its noise `noise`.
    pub fn new(noise: N, params: &Params) -> Self {
        Clocks {
            total: noise.clocks(params.reset().rate()),
            noise,
            reset: *params.reset(),
            schedule: params.schedule().clone(),
        }
    }

    /// The walk from state `s` at t = 0 (the observer at its start point)
    /// until `obs` reports the passage or t_max: (passage time, or None if
    /// not by `t_max`; number of events, a hold counted as one).
    #[inline(always)]
    pub fn walk<O: PassageObserver>(
        &self,
        mut s: usize,
        t_max: f64,
        rng: &mut Rng,
        obs: &mut O,
    ) -> (Option<f64>, u64) {
        let (schedule, refractory) = (&self.schedule, self.schedule.refractory);
        let mut t = 0.0f64;
        let mut next_periodic = schedule.first_reset(rng);
        let mut events = 0u64;
        loop {
            let total = self.total[s];
            let gap = exp_gap(rng, total);
            let periodic = next_periodic - t <= gap;
            let step = if periodic { next_periodic - t } else { gap };
            if let Flow::Done(hit) = obs.flow(s, t, step, t_max) {
                return (hit, events);
            }
            t = if periodic { next_periodic } else { t + step };
            events += 1;
            if !periodic {
                if let Some(j) = self.noise.event(s, rng.gen::<f64>() * total) {
                    obs.jump(s, j);
                    s = j;
                    continue;
                }
            }
            let v = self.reset.draw_velocity(rng);
            let after = self.noise.after_reset(s, &self.reset, rng);
            if let Some(hit) = obs.reset(t, v, s, after) {
                return (Some(hit), events);
            }
            s = after;
            let mut held = None;
            if let Some(r) = refractory {
                let d = r.draw(rng);
                if let Some(hit) = obs.hold(t, v, d, t_max) {
                    return (Some(hit), events);
                }
                if t + d >= t_max {
                    return (None, events);
                }
                s = self.noise.after_hold(s, d, rng);
                t += d;
                events += 1;
                held = Some(d);
            }
            obs.resume(v, s, held);
            if schedule.scheduled_clock() {
                next_periodic = schedule.next_reset(t, rng);
            }
        }
    }
}
