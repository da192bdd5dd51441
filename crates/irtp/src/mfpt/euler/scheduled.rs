//! The Euler first passage with [`super`]'s lanes in flight, written once over the
//! noise's steps of the Euler sampler ([`NoiseSteps`]: the paper's
//! [`Telegraph`], or any finite-state noise and thermal noise in
//! [`NoiseKernel`], docs/equations.md Eqs. (N15)-(N19)) and its schedule
//! ([`Clock`]: periodic and renewal clocks, refractory holds), in the step
//! order of the sampler's scheduled loop: the Poisson decision, then a
//! held step, a reset (passage if the reset velocity is at or above v_t,
//! else the refractory period and the next scheduled time) or the
//! velocity step and its arrival check, then the noise's step 4. Step n
//! (from n·dt to (n+1)·dt) that arrives gives the time (n+1)·dt.
//!
//! The paper's noise starts particle i in +Σ for even i (labels swapped
//! in the reflected frame) with its first flip gap drawn before its first
//! reset gap: the stream of the lane kernel of [`super`]. A noise model
//! starts in a state drawn from π, so tau is the π-averaged MFPT
//! Σ_s π_s tau_s(v_0); the even and odd particles (strata 0 and 1 of
//! [`FptStats`], the `plus` and `minus` halves of its summary) are two
//! independent halves of the same law.
//!
//! At T > 0 a passage between two monitored steps is detected by the
//! Brownian-bridge crossing probability: a step v_n → v_{n+1} < v_t
//! crossed v_t with probability exp(-(v_t - v_n)(v_t - v_{n+1}) / (T dt))
//! (the bridge of sqrt(2T) W over dt with the drift frozen, Eq. (N19)),
//! drawn with one uniform where it exceeds e^-40. Without it the discretely
//! monitored passage time carries an O(sqrt(dt)) bias; with it the bias is
//! O(dt) and the dt-extrapolation of [`super::extrapolate`] applies.

use super::{EulerFpt, FptSample, FptStats};
use crate::model::reset::Reset;
use crate::model::{Drag, Params};
use crate::parallel::{self, Progress};
use crate::rng::{self, Rng};
use crate::sim::euler::noise::{temperature, NoiseKernel, State};
use crate::sim::euler::{Clock, EulerPlan, Events, Frame, Geometric, NoiseSteps, Step3, Telegraph};
use rand::Rng as _;
use std::ops::Range;

/// How a first-passage particle starts: its noise state and event sampler.
trait Begin: NoiseSteps {
    /// The start of a particle labelled with noise state `s0` (the paper's
    /// +Σ: 0, -Σ: 1; a noise model draws its own).
    fn begin(&self, s0: usize, rng: &mut Rng, plan: &EulerPlan) -> (Self::State, Geometric);
}

impl<D: Drag> Begin for Telegraph<'_, D> {
    fn begin(&self, s0: usize, rng: &mut Rng, plan: &EulerPlan) -> (f64, Geometric) {
        let eta = if s0 == 0 { self.sigma } else { -self.sigma };
        (eta, Geometric::flip_first(rng, plan))
    }
}

impl<D: Drag> Begin for NoiseKernel<'_, D> {
    fn begin(&self, _s0: usize, rng: &mut Rng, plan: &EulerPlan) -> (State, Geometric) {
        self.start(rng, plan)
    }
}

/// [`EulerFpt::units`] in the scheduled loop: the run's plan (no records,
/// max_steps steps) in the canonical (upward) frame, the noise's steps
/// matched once.
pub(super) fn units(
    e: &EulerFpt,
    n: u64,
    units: Range<u64>,
    seed: u64,
    progress: &dyn Progress,
) -> Vec<FptStats> {
    let (p, swapped) = e.problem.canonical();
    let par = p.params();
    let plan = plan(par, e.dt, e.t_max);
    // The run without its noise's steps (matched per drag below).
    let run = || Passage {
        noise: (),
        frame: Frame::unbinned(&plan, seed, par),
        swapped,
        v0: p.v0(),
        vt: p.vt(),
        t_dt: if e.bridge {
            temperature(par) * e.dt
        } else {
            0.0
        },
        t_max: e.t_max,
    };
    crate::with_drag!(par.drag(), |d| {
        if par.noise().is_none() {
            let noise = Telegraph {
                f: d,
                sigma: par.sigma(),
                dt: e.dt,
                reset: *par.reset(),
            };
            return run().with(noise).reduce(n, units, progress);
        }
        // Validated when the EulerFpt was built (the same chain and dt).
        let kernel = NoiseKernel::with_frame(d, par, Frame::unbinned(&plan, seed, par), true)
            .expect("noise chain validated by EulerFpt::new");
        run().with(kernel).reduce(n, units, progress)
    })
}

/// The plan of a first passage: max_steps = floor(t_max/dt) steps, the
/// reset and flip probabilities of the step, nothing recorded.
fn plan(par: &Params, dt: f64, t_max: f64) -> EulerPlan {
    EulerPlan {
        dt,
        p_reset: par.rate() * dt,
        q_flip: 0.5 * (-(-2.0 * par.lambda() * dt).exp_m1()),
        record_steps: Vec::new(),
        burn_in_step: 0,
        steps: (t_max / dt).floor() as u64,
    }
}

/// The constants of one run in the canonical (upward) frame.
struct Passage<'a, N> {
    noise: N,
    frame: Frame<'a>,
    /// The ± labels swapped by the reflection to the upward frame.
    swapped: bool,
    v0: f64,
    vt: f64,
    /// T dt of the bridge (0: no bridge).
    t_dt: f64,
    t_max: f64,
}

impl<'a> Passage<'a, ()> {
    /// The run with the noise's steps `noise`.
    fn with<N>(self, noise: N) -> Passage<'a, N> {
        Passage {
            noise,
            frame: self.frame,
            swapped: self.swapped,
            v0: self.v0,
            vt: self.vt,
            t_dt: self.t_dt,
            t_max: self.t_max,
        }
    }
}

/// One particle in flight: its index, stream, velocity, noise state,
/// event sampler, schedule clock and steps done.
struct Lane<S> {
    i: u64,
    rng: Rng,
    v: f64,
    st: S,
    ev: Geometric,
    clock: Clock,
    n: u64,
}

impl<N: Begin + Sync> Passage<'_, N> {
    /// The unit totals of units `units` of a run of `n` particles, each
    /// chunk's particles run in lanes ([`super::in_lanes`]).
    fn reduce(&self, n: u64, units: Range<u64>, progress: &dyn Progress) -> Vec<FptStats> {
        parallel::reduce_units(
            n,
            units,
            || FptStats::new(self.t_max),
            |lo, hi, acc| {
                super::in_lanes(lo, hi, acc, |i| self.start(i), |l| self.advance(l), |l| l.i)
            },
            |a, b| a.merge(&b),
            progress,
        )
    }

    /// Particle i at t = 0 (module docs): its stream gives the noise's
    /// start, then the first scheduled reset time.
    fn start(&self, i: u64) -> Lane<N::State> {
        let fr = &self.frame;
        let mut rng = rng::stream(fr.seed, i);
        // +Σ (state 0) for even i, the labels swapped in the reflected frame.
        let s0 = usize::from((i % 2 == 0) == self.swapped);
        let (st, ev) = self.noise.begin(s0, &mut rng, fr.plan);
        let clock = Clock::start(&fr.schedule, fr.plan.dt, &mut rng);
        Lane {
            i,
            rng,
            v: self.v0,
            st,
            ev,
            clock,
            n: 0,
        }
    }

    /// Step n of a lane: the Poisson decision, a reset's draws (velocity,
    /// noise state, refractory period, next scheduled time) or the
    /// velocity step's and the bridge uniform, then step 4's draws; the
    /// sample once the particle has arrived or reached t_max.
    #[inline(always)]
    fn advance(&self, l: &mut Lane<N::State>) -> Option<FptSample> {
        let fr = &self.frame;
        let plan = fr.plan;
        let n = l.n;
        let sample = |steps: u64, arrived: bool| FptSample {
            time: arrived.then_some(steps as f64 * plan.dt),
            work: steps,
        };
        if n >= plan.steps {
            return Some(sample(n, false));
        }
        l.n += 1;
        let rng = &mut l.rng;
        let poisson = l.ev.reset(n, rng);
        match l.clock.step3(n, poisson) {
            Step3::Hold => {}
            Step3::Reset => {
                l.v = fr.reset.draw_velocity(rng);
                self.noise.reset(&mut l.st, n, rng);
                if l.v >= self.vt {
                    return Some(sample(n + 1, true));
                }
                l.clock.rearm(&fr.schedule, rng);
            }
            Step3::Drift => {
                let w = self.noise.drift(l.v, &l.st, rng);
                if w >= self.vt || self.crossed(l.v, w, rng) {
                    return Some(sample(n + 1, true));
                }
                l.v = w;
            }
        }
        self.noise.jump(&mut l.st, &mut l.ev, n, rng);
        None
    }

    /// Whether the thermal path crossed v_t between v and w (both below):
    /// with probability exp(-(v_t - v)(v_t - w) / (T dt)) (Eq. (N19)).
    #[inline]
    fn crossed(&self, v: f64, w: f64, rng: &mut Rng) -> bool {
        if !(self.t_dt > 0.0) {
            return false;
        }
        let e = (self.vt - v) * (self.vt - w) / self.t_dt;
        e < 40.0 && rng.gen::<f64>() < (-e).exp()
    }
}
