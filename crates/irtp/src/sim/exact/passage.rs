//! The event-to-event kernel of the exact samplers: one loop
//! ([`Clocks::walk`]) advances the time, the noise state, the reset clock
//! and the refractory hold from event to event, and an observer
//! ([`Observer`]) carries what moves along a flow segment and decides what
//! a segment, a reset or a hold means. `simulate --method exact`, `mfpt
//! --method exact` and the exact search all run this loop.
//!
//! Events: in state s a Poisson clock of rate q_s + r (its uniform picks a
//! noise jump or a reset, [`ExactNoise::event`]); with a periodic clock
//! (resets at T, 2T, ... from t = 0) or a renewal clock (the next reset a
//! drawn waiting time after the last one, or after the end of its
//! refractory period) also the scheduled reset times, where a segment
//! ends. A reset draws the velocity from the rule's target, then the noise
//! state after it; with a refractory period of duration D (drawn next) the
//! velocity is held, Poisson resets are off, the periodic times inside it
//! or at its end are skipped, and the noise runs on. An event at t acts
//! just after t: a segment ending at t sees the state before it.
//!
//! The observer's [`Mode`] fixes the kernel's arithmetic and its hold, so
//! that each sampler keeps its random stream bit for bit:
//! - [`Mode::Passage`] (first passage): gaps Exp1 / (q_s + r), a periodic
//!   reset when T_next - t <= gap; a hold is one event, its noise drawn
//!   whole after the hold's duration ([`ExactNoise::after_hold`]: the
//!   paper's flip with the probability ½(1 - e^{-2 lambda D}) of an odd
//!   number of flips, a chain's jumps one by one), the renewal clock's
//!   next time drawn after it;
//! - [`Mode::Record`] (simulation): gaps Exp1 × 1/(q_s + r), a periodic
//!   reset when T_next <= t + gap; the renewal clock's next time is drawn
//!   at the reset, then the hold is walked jump by jump (gaps Exp1 × 1/q_s,
//!   each jump and the release an event), its pieces observed
//!   ([`Observer::held`]).
//!
//! The random stream is consumed in this order by every observer of a
//! mode, so a passage time depends on the observer only through where it
//! stops the walk.
//!
//! Observers:
//! - the velocity target of `mfpt::exact` (first time v reaches v_t from
//!   below; a reset to v_r ≥ v_t is the passage), which also reports its
//!   segments and jumps to a `Tally` (the control variate of
//!   `mfpt::control`);
//! - the position target of `search::exact` (first exit of x from the
//!   search region; x → x_r at a reset with position resetting; x moves
//!   linearly during a hold);
//! - the recorder of `sim::exact` (moments on the time grid, time
//!   averages, the velocity occupation histogram and atom, x).
//!
//! A new observable is one [`Observer`] impl in one file: its state
//! between events and its answers (a flow segment, a jump, a reset, a
//! hold, the flow's restart after a reset); [`Clocks::walk`] runs it
//! unchanged. The shortest real one is `PositionTarget` in
//! crates/irtp/src/search/exact.rs (its flow segment's root search aside,
//! five short methods); docs/extending.md walks through one.

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

/// The kernel's arithmetic and hold for an observer (module docs): the
/// first-passage samplers' or the simulation's random stream.
#[derive(Clone, Copy, PartialEq, Eq)]
pub(crate) enum Mode {
    Passage,
    Record,
}

/// What a walk means: the observer keeps the quantities that move along
/// a flow segment and says where the walk stops. States are noise-state
/// indices of [`ExactNoise`].
pub(crate) trait Observer {
    /// The kernel's arithmetic and hold for this observer.
    const MODE: Mode;
    /// Flow in state `s` from time `t` to the next event at `end`, `step`
    /// after t (each as the mode's arithmetic has it; `end` may lie past
    /// `t_max`): Done with the passage time within it (None where the walk
    /// reaches `t_max` first), else Moved.
    fn flow(&mut self, s: usize, t: f64, step: f64, end: f64, t_max: f64) -> Flow;
    /// A noise jump from state `s` to `j` at the current point.
    fn jump(&mut self, s: usize, j: usize);
    /// A reset at time `t` to velocity `v`, the noise from `s` to
    /// `after`: the passage time where the reset is the passage.
    fn reset(&mut self, t: f64, v: f64, s: usize, after: usize) -> Option<f64>;
    /// [`Mode::Passage`]: a refractory hold of duration `d` from time `t`
    /// at velocity `v`: the passage time inside it (capped at `t_max`),
    /// if any (none by default: the velocity is constant).
    #[inline(always)]
    fn hold(&mut self, _t: f64, _v: f64, _d: f64, _t_max: f64) -> Option<f64> {
        None
    }
    /// [`Mode::Record`]: a piece of a hold from `t` to `end` (a jump of
    /// the noise or the release; `end` may lie past `t_max`): Done where
    /// the walk ends in it (by default at `t_max`), else Moved.
    #[inline(always)]
    fn held(&mut self, _t: f64, end: f64, t_max: f64) -> Flow {
        if end >= t_max {
            Flow::Done(None)
        } else {
            Flow::Moved
        }
    }
    /// The walk flows on from velocity `v` in state `s` after a reset,
    /// `held` the hold's duration (None without a refractory period).
    fn resume(&mut self, v: f64, s: usize, held: Option<f64>);
}

/// The event clocks of a walk: the noise, its per-state event rates
/// q_s + r and their inverses, the inverse exit rates 1/q_s (0 where
/// q_s = 0), the resetting rule and the schedule.
#[derive(Clone, Debug)]
pub(crate) struct Clocks<N> {
    pub noise: N,
    /// Per state: q_s + r.
    pub total: Vec<f64>,
    inv_total: Vec<f64>,
    inv_exit: Vec<f64>,
    pub reset: ResetRule,
    pub schedule: Schedule,
}

impl<N: ExactNoise> Clocks<N> {
    /// The clocks of `params` with its noise `noise`.
    pub fn new(noise: N, params: &Params) -> Self {
        let total = noise.clocks(params.reset().rate());
        let exit = (0..total.len()).map(|s| noise.exit(s));
        Clocks {
            inv_total: total.iter().map(|t| 1.0 / t).collect(),
            inv_exit: exit.map(|q| if q > 0.0 { 1.0 / q } else { 0.0 }).collect(),
            total,
            noise,
            reset: *params.reset(),
            schedule: params.schedule().clone(),
        }
    }

    /// The walk from state `s` at t = 0 (the observer at its start point)
    /// until `obs` reports the passage or t_max: (passage time, or None if
    /// not by `t_max`; number of events: in [`Mode::Passage`] a hold
    /// counts as one, in [`Mode::Record`] each jump in it and its release).
    #[inline(always)]
    pub fn walk<O: Observer>(
        &self,
        mut s: usize,
        t_max: f64,
        rng: &mut Rng,
        obs: &mut O,
    ) -> (Option<f64>, u64) {
        let (schedule, refractory) = (&self.schedule, self.schedule.refractory);
        let record = O::MODE == Mode::Record;
        let mut t = 0.0f64;
        let mut next_periodic = schedule.first_reset(rng);
        let mut events = 0u64;
        loop {
            let total = self.total[s];
            let (gap, periodic) = if record {
                // Exp(rate) by a product with 1/rate (the division sits
                // on the simulation's dependency chain).
                let gap = gap_times(rng, total, self.inv_total[s]);
                (gap, next_periodic <= t + gap)
            } else {
                let gap = exp_gap(rng, total);
                (gap, next_periodic - t <= gap)
            };
            let (step, end) = if periodic {
                (next_periodic - t, next_periodic)
            } else {
                (gap, t + gap)
            };
            if let Flow::Done(hit) = obs.flow(s, t, step, end, t_max) {
                return (hit, events);
            }
            t = end;
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
                if record {
                    let until = t + d;
                    if schedule.scheduled_clock() {
                        next_periodic = schedule.next_reset(until, rng);
                    }
                    match self.hold_pieces(s, t, until, t_max, rng, obs) {
                        Ok((after, n)) => (s, t, events) = (after, until, events + n),
                        Err(n) => return (None, events + n),
                    }
                    obs.resume(v, s, Some(d));
                    continue;
                }
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

    /// [`Mode::Record`]'s hold from `t` to `until` in state `s`: the
    /// noise's jumps one by one (gaps Exp1 × 1/q_s), each piece observed:
    /// Ok(state at the release, events) or Err(events) where the walk
    /// ends at t_max inside it.
    #[inline(always)]
    fn hold_pieces<O: Observer>(
        &self,
        mut s: usize,
        mut t: f64,
        until: f64,
        t_max: f64,
        rng: &mut Rng,
        obs: &mut O,
    ) -> Result<(usize, u64), u64> {
        let mut events = 0;
        loop {
            let end = t + gap_times(rng, self.noise.exit(s), self.inv_exit[s]);
            let release = until <= end;
            let end = if release { until } else { end };
            if let Flow::Done(_) = obs.held(t, end, t_max) {
                return Err(events);
            }
            t = end;
            events += 1;
            if release {
                return Ok((s, events));
            }
            s = self.noise.draw_jump(s, rng);
        }
    }
}

/// Exp(rate) waiting time as Exp1 × `inv` (inv = 1/rate; ∞ for rate 0).
#[inline(always)]
fn gap_times(rng: &mut Rng, rate: f64, inv: f64) -> f64 {
    if rate > 0.0 {
        rng.sample::<f64, _>(rand_distr::Exp1) * inv
    } else {
        f64::INFINITY
    }
}
