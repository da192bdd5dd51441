//! Euler first passage in position: the paper's Euler scheme (Eqs.
//! (30)-(32)) for (x, v) run until x leaves the search region, at the step
//! dt and at dt/2, Richardson-extrapolated to dt → 0
//! ([`crate::mfpt::euler::extrapolate`], shared with the velocity target).
//!
//! One step from n·dt to (n+1)·dt (the order of [`crate::mfpt::euler`]):
//! a reset with probability r dt (or the scheduled reset at time t_k, the
//! periodic kT or a renewal clock's, in the step n = round(t_k/dt); after
//! every reset the clock restarts at its time, or at the end of its
//! refractory period, by [`Schedule::next_reset`], as in the exact
//! sampler): v ← v_r drawn from the target, the noise state kept
//! or re-drawn, x ← x_r with full resetting (on the start side: a reset is
//! never a passage); otherwise x ← x + v dt, v ← v + dt (eta - g(v)), and
//! the passage is at (n+1)·dt if x is now outside (lo, hi); then eta flips
//! with probability q = ½(1 - e^{-2 lambda dt}). Flip and reset steps are
//! geometric gaps, as in the velocity target's Euler sampler.
//!
//! Bias: the crossing is detected on the step, so the passage time is late
//! by at most dt (on average about dt/2: x is C¹, its crossing falls
//! uniformly inside a step); an excursion across the target and back within
//! one step needs a crossing speed below O(dt), whose chance is O(dt²)
//! (the flux of crossings vanishes linearly in the speed); the scheme's
//! weak error is O(dt). The bias is c·dt + o(dt): the extrapolation
//! 2 T(dt/2) - T(dt) removes the leading term, and |T(dt/2) - T(dt)| is
//! reported as the measured step bias. Where the step is not small against
//! the passage time the expansion fails (a target within a few steps gave
//! a negative mean): the extrapolated means are verified
//! ([`crate::mfpt::euler::verify_extrapolation`]) and refused.
//!
//! A refractory period (`--refractory`, exp or fixed) follows a reset as in
//! the exact sampler ([`super::exact`]): its duration D drawn after the
//! reset's velocity and noise state, held for round(D/dt) steps (the
//! rounding of [`crate::sim::euler`]'s scheduled loop); in a held step v
//! stays at the reset velocity, x moves by v dt (a passage if it leaves),
//! Poisson resets are off (a Poisson reset drawn in a held step is
//! dropped: the gaps are memoryless), a periodic time inside the hold is
//! skipped, and the noise keeps jumping.
//!
//! With a noise model at T = 0 (docs/equations.md, "Euler schemes with a
//! noise model") the velocity step uses the level a_s of the current
//! state, the chain moves by P = exp(Q dt) ([`StepChain`], as
//! [`crate::mfpt::euler`]'s noise kernel: geometric stays, the jump's
//! target from one uniform), a reset keeps the state or re-draws it from
//! π, and a particle starts in a state drawn from π (the stream's first
//! uniform): tau is the π-averaged mean, the even and odd particles two
//! independent halves of the same law. The step is written once over the
//! noise states (`EulerNoise`).

use super::SearchProblem;
use crate::error::{finite, Error, Result};
use crate::mfpt::estimator::{first_passage_units, FptSample, FptStats, HALVES};
use crate::model::reset::{Reset, ResetRule, Schedule};
use crate::model::Drag;
use crate::parallel::Progress;
use crate::rng::Rng;
use crate::sim::euler::noise::StepChain;
use crate::sim::euler::{euler_step, geometric_gap, Clock, Step3};
use rand::Rng as _;
use std::ops::Range;

/// The noise states of an Euler search: the paper's telegraph or a chain
/// stepped by P = exp(Q dt). A state enters with the step of its next
/// jump (a geometric gap).
trait EulerNoise {
    /// The start state of a particle labelled with state `s0` (an even
    /// particle: 0) and the step of its first jump.
    fn start(&self, s0: usize, rng: &mut Rng) -> (usize, u64);
    /// The level a_s of state s.
    fn level(&self, s: usize) -> f64;
    /// The state and next jump step after a reset at `step` from s (whose
    /// next jump is at `next`), by the rule's noise option.
    fn reset(
        &self,
        s: usize,
        next: u64,
        step: u64,
        rule: &ResetRule,
        rng: &mut Rng,
    ) -> (usize, u64);
    /// The state and next jump step after the jump at `step` from s.
    fn jump(&self, s: usize, step: u64, rng: &mut Rng) -> (usize, u64);
}

/// The paper's noise: ±Sigma (state 0: +Sigma), a flip per step with
/// probability q = ½(1 - e^{-2 lambda dt}), ln(1 - q) = `ln_flip`.
struct Telegraph {
    sigma: f64,
    ln_flip: f64,
}

impl EulerNoise for Telegraph {
    fn start(&self, s0: usize, rng: &mut Rng) -> (usize, u64) {
        (s0, geometric_gap(rng, self.ln_flip))
    }
    #[inline]
    fn level(&self, s: usize) -> f64 {
        if s == 0 {
            self.sigma
        } else {
            -self.sigma
        }
    }
    fn reset(&self, s: usize, next: u64, _: u64, rule: &ResetRule, rng: &mut Rng) -> (usize, u64) {
        (rule.draw_telegraph(s, rng), next)
    }
    fn jump(&self, s: usize, step: u64, rng: &mut Rng) -> (usize, u64) {
        (1 - s, step.saturating_add(geometric_gap(rng, self.ln_flip)))
    }
}

impl EulerNoise for StepChain {
    /// Drawn from π (one uniform; the label ignored), then its first jump.
    fn start(&self, _: usize, rng: &mut Rng) -> (usize, u64) {
        let s = self.draw_stationary(rng);
        (s, geometric_gap(rng, self.ln_stay[s]))
    }
    #[inline]
    fn level(&self, s: usize) -> f64 {
        self.levels[s]
    }
    /// A re-drawn state enters at the step before (it may jump in this
    /// step, as [`crate::mfpt::euler`]'s noise kernel).
    fn reset(
        &self,
        s: usize,
        next: u64,
        step: u64,
        rule: &ResetRule,
        rng: &mut Rng,
    ) -> (usize, u64) {
        let s2 = rule.draw_noise_state(s, &self.chain, rng);
        if s2 == s {
            return (s, next);
        }
        (
            s2,
            (step - 1).saturating_add(geometric_gap(rng, self.ln_stay[s2])),
        )
    }
    fn jump(&self, s: usize, step: u64, rng: &mut Rng) -> (usize, u64) {
        let s2 = self.dest(s, rng.gen::<f64>() * self.leave[s]);
        (
            s2,
            step.saturating_add(geometric_gap(rng, self.ln_stay[s2])),
        )
    }
}

/// The Euler search sampler of one problem and step (build with
/// [`SearchEuler::new`]).
#[derive(Clone, Debug, PartialEq)]
pub struct SearchEuler {
    problem: SearchProblem,
    dt: f64,
    t_max: f64,
}

/// The constants of one run.
struct Chain {
    dt: f64,
    /// ln(1 - r dt): the geometric gaps of resets.
    ln_reset: f64,
    x0: f64,
    v0: f64,
    lo: f64,
    hi: f64,
    max_steps: u64,
    reset: ResetRule,
    /// The scheduled clock (periodic or renewal) and refractory period, if any.
    schedule: Schedule,
    x_reset: Option<f64>,
}

impl SearchEuler {
    /// Validate: a noise model at T = 0 (`super::noise_gate`) with its
    /// step chain exp(Q dt), dt inside the Euler stability limit with
    /// r dt < 1, a finite t_max ≥ dt; the protocol features of
    /// [`crate::capability`]'s SearchEuler row.
    pub fn new(problem: &SearchProblem, dt: f64, t_max: f64) -> Result<Self> {
        // The noise and the protocol it runs.
        crate::capability::check(crate::capability::Solver::SearchEuler, problem.params())?;
        let p = problem.params();
        let dt = p.check_dt(dt)?;
        if p.noise().is_some() {
            StepChain::new(&p.chain()?, dt)?;
        }
        if !(p.rate() * dt < 1.0) {
            return Err(Error::invalid(
                "dt",
                dt,
                format!(
                    "rate * dt < 1 (the reset probability per step), i.e. dt < {}",
                    1.0 / p.rate()
                ),
            ));
        }
        let t_max = finite("t_max", t_max)?;
        if !(t_max >= dt) {
            return Err(Error::invalid(
                "t_max",
                t_max,
                format!("a finite t_max >= dt = {dt}"),
            ));
        }
        Ok(SearchEuler {
            problem: problem.clone(),
            dt,
            t_max,
        })
    }

    /// Time step.
    pub fn dt(&self) -> f64 {
        self.dt
    }

    /// The unit totals of units `units` of the run of `n` particles
    /// (particle i: stream (seed, i), stratum i mod 2 of [`HALVES`]: the
    /// start state, +Sigma for even i; the contract of
    /// [`first_passage_units`]: merged in unit order, bit-identical for
    /// any thread count and split).
    pub fn units(
        &self,
        n: u64,
        units: Range<u64>,
        seed: u64,
        progress: &dyn Progress,
    ) -> Vec<FptStats> {
        let c = self.chain();
        let p = self.problem.params();
        let paper = Telegraph {
            sigma: p.sigma(),
            ln_flip: (-(0.5 * (-(-2.0 * p.lambda() * self.dt).exp_m1()))).ln_1p(),
        };
        // Validated when the SearchEuler was built (the same chain and dt).
        let chain = p.noise().map(|_| {
            p.chain()
                .and_then(|ch| StepChain::new(&ch, self.dt))
                .expect("noise chain validated by SearchEuler::new")
        });
        // Stratum k labelled with state k (0: +Sigma for an even particle).
        let run = |noise: &(dyn Fn(&mut Rng, usize) -> FptSample + Sync)| {
            first_passage_units(
                n,
                units.clone(),
                seed,
                (self.t_max, &HALVES[..]),
                progress,
                |_, rng, k| noise(rng, k),
            )
        };
        crate::with_drag!(p.drag(), |d| match &chain {
            None => run(&|rng, s0| c.run(d, &paper, s0, rng)),
            Some(ch) => run(&|rng, s0| c.run(d, ch, s0, rng)),
        })
    }

    fn chain(&self) -> Chain {
        let p = self.problem.params();
        let dt = self.dt;
        let (lo, hi) = self.problem.target().bounds(self.problem.x0());
        Chain {
            dt,
            ln_reset: (-(p.rate() * dt)).ln_1p(),
            x0: self.problem.x0(),
            v0: self.problem.v0(),
            lo,
            hi,
            max_steps: (self.t_max / dt).floor() as u64,
            reset: *p.reset(),
            schedule: p.schedule().clone(),
            x_reset: p.schedule().position.map(|r| r.x),
        }
    }
}

impl Chain {
    /// One particle (module docs) starting in noise state `s0` (the
    /// paper's noise; a chain draws its own): the passage time (None by
    /// t_max) and the number of steps.
    fn run<D: Drag, N: EulerNoise>(
        &self,
        drag: &D,
        noise: &N,
        s0: usize,
        rng: &mut Rng,
    ) -> FptSample {
        let (mut x, mut v) = (self.x0, self.v0);
        let (mut s, mut next_flip) = noise.start(s0, rng);
        let mut next_reset = geometric_gap(rng, self.ln_reset);
        // The scheduled resets and refractory holds (no draw without them).
        let mut clock = Clock::start(&self.schedule, self.dt, rng);
        let mut step = 0u64;
        while step < self.max_steps {
            step += 1;
            // Stopped: reported as censored, in a chunk the cancelled
            // reduction discards.
            if crate::parallel::stop_due(step) {
                break;
            }
            let poisson = step == next_reset;
            if poisson {
                next_reset = step.saturating_add(geometric_gap(rng, self.ln_reset));
            }
            // Step n = step - 1 holds, resets (on the start side: never a
            // passage) or drifts; a held step moves x at the held velocity.
            let moved = match clock.step3(step - 1, poisson) {
                Step3::Hold => {
                    x += self.dt * v;
                    true
                }
                Step3::Reset => {
                    v = self.reset.draw_velocity(rng);
                    (s, next_flip) = noise.reset(s, next_flip, step, &self.reset, rng);
                    x = self.x_reset.unwrap_or(x);
                    clock.rearm(&self.schedule, rng);
                    false
                }
                Step3::Drift => {
                    x += self.dt * v;
                    v = euler_step(drag, v, noise.level(s), self.dt);
                    true
                }
            };
            if moved && !(x > self.lo && x < self.hi) {
                return FptSample {
                    time: Some(step as f64 * self.dt),
                    work: step,
                };
            }
            if step == next_flip {
                (s, next_flip) = noise.jump(s, step, rng);
            }
        }
        FptSample {
            time: None,
            work: step,
        }
    }
}
