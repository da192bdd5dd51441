//! The paper's Euler particle simulation (Eqs. (30)-(32) with the reset rule Eq. (3)).
//!
//! One step n → n+1 (time n·dt → (n+1)·dt), in this exact order:
//! 1. observe the state (v_n, x_n): record it if n is a grid step, and, if
//!    n_b ≤ n < N, add dt to the time averages of v, v² and to the occupation
//!    time of the histogram bin of v_n (left-point rule, like Eq. (31));
//! 2. x ← x + v·dt with the OLD velocity (Eq. (31));
//! 3. with probability p = r·dt: v ← v_r (Eq. (3)); otherwise
//!    v ← v + dt·(η - g(v)) (Eq. (30));
//! 4. with probability q = ½(1 - e^{-2λ dt}) (Eq. (32)): η ← -η.
//!
//! The reset and flip decisions are independent of each other and of the
//! state; a reset keeps x and η. Particles start at x = 0, v = 0 (as in the
//! paper, not at v_r) with η = ±Σ with probability ½ each.
//!
//! Two samplers of the reset/flip decisions are provided ([`EventSampling`]):
//! the paper's per-step Bernoulli draws, and geometric waiting times. The
//! decisions of step 3 (and of step 4) form an i.i.d. Bernoulli(p) (resp.
//! Bernoulli(q)) sequence; the gaps between successes of such a sequence are
//! i.i.d. Geometric(p) on {1, 2, ...}, so drawing the gaps directly gives the
//! same process in distribution with two random numbers per event instead of
//! two per step (tested in `tests/sim_euler.rs` and below).
//!
//! Implementation: the drag law and sampler are matched once per run and the
//! kernel is monomorphised; [`LANES`] particles are integrated side by side
//! (bit-identical to one at a time); g(v) is [`Drag::fast_force`] (for tan
//! and tanh the kernels of [`crate::numerics::fastmath`], within 3 ulp of
//! libm and platform-independent).
//!
//! The modifiers of the resetting rule ([`crate::model::reset::Schedule`])
//! run in a one-particle-at-a-time kernel chosen once per run (the paper's
//! protocol keeps the kernel above, bit for bit), same step order:
//! - periodic resetting: the reset at t = kT is the reset of step 3 in step
//!   n = round(kT/dt) (from n·dt to (n+1)·dt), so the state recorded at kT
//!   is the one before the reset, as in the exact sampler (a reset at t
//!   acts just after t); it acts within dt of kT, an O(dt) timing error;
//!   a renewal clock likewise, at the step nearest each drawn reset time;
//! - a refractory period of duration D (drawn at the reset) holds v at the
//!   reset velocity for round(D/dt) steps (duration error ≤ dt/2): step 3
//!   neither drifts nor resets there (the Poisson decisions are drawn and
//!   discarded, the periodic times up to its end skipped); the flips of
//!   step 4 go on;
//! - position resetting: x ← x_r at the reset of step 3.
//!
//! A noise model other than the paper's (any finite-state noise, thermal
//! noise) runs the steps of [`noise`] (docs/equations.md, "Euler schemes
//! with a noise model", Eqs. (N15)-(N19)) in the same one-particle loop,
//! generic over the noise's steps, with every modifier above (during a
//! hold its chain jumps on and no thermal kick is drawn); the paper's
//! noise keeps the kernel above bit for bit.
//!
//! Time grid: grid time t_k is recorded at step n_k = round(t_k/dt) and
//! reported as n_k·dt (the exact time of the recorded state); grid times that
//! round to the same step (closer than dt, e.g. the short end of a log grid)
//! are recorded once, so the output may have fewer rows than grid times. The
//! run has N = n_{K-1} steps and the averaging window is steps
//! n_b = round(burn_in/dt) .. N-1.

use super::{Observables, Part, SimSpec};
use crate::error::{Error, Result};
use crate::model::reset::{Reset, ResetRule, Schedule, Solver};
use crate::model::{Drag, Params};
use crate::parallel::Progress;
use crate::rng::{self, Rng};
use rand::Rng as _;
use serde::{Deserialize, Serialize};
use std::ops::Range;

pub mod noise;

/// How the per-step reset and flip decisions are drawn (same law, see module docs).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum EventSampling {
    /// Geometric waiting times between events (fast; default).
    #[default]
    Geometric,
    /// Two uniform draws per step, exactly as written in the paper.
    Bernoulli,
}

impl EventSampling {
    /// Whether this is the default, [`EventSampling::Geometric`].
    pub fn is_geometric(&self) -> bool {
        *self == EventSampling::Geometric
    }
}

impl std::str::FromStr for EventSampling {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        match s {
            "geometric" => Ok(EventSampling::Geometric),
            "bernoulli" => Ok(EventSampling::Bernoulli),
            _ => Err(Error::invalid("events", s, "one of geometric, bernoulli")),
        }
    }
}

/// Validated step plan of an Euler run (step indices derived from the grid).
#[derive(Clone, Debug, PartialEq)]
pub struct EulerPlan {
    /// Time step.
    pub dt: f64,
    /// Reset probability per step, p = r·dt.
    pub p_reset: f64,
    /// Flip probability per step, q = ½(1 - e^{-2λ dt}) (Eq. (32)).
    pub q_flip: f64,
    /// Distinct step indices n_k = round(t_k/dt) of the grid times, increasing.
    pub record_steps: Vec<u64>,
    /// First step of the averaging window, n_b.
    pub burn_in_step: u64,
    /// Total number of steps N.
    pub steps: u64,
}

impl EulerPlan {
    /// Validate dt against the parameters (dt < 1/max g', r·dt < 1) and map
    /// the grid and burn-in onto steps.
    pub fn new(params: &Params, spec: &SimSpec, dt: f64) -> Result<Self> {
        params.require(Solver::Euler)?;
        super::check_period_window(params, spec)?;
        let dt = match params.noise() {
            None => params.check_dt(dt)?,
            Some(_) => noise::check_noise_dt(params, dt)?,
        };
        let p_reset = params.rate() * dt;
        if !(p_reset < 1.0) {
            return Err(Error::invalid(
                "dt",
                dt,
                format!(
                    "dt < 1/rate = {} (the reset probability per step is rate·dt)",
                    1.0 / params.rate()
                ),
            ));
        }
        let q_flip = 0.5 * (-(-2.0 * params.lambda() * dt).exp_m1());
        let max_steps = 1e15;
        let mut record_steps = Vec::with_capacity(spec.grid.len());
        for &t in spec.grid.times() {
            let n = (t / dt).round();
            if !(n <= max_steps) {
                return Err(Error::invalid(
                    "t_max",
                    t,
                    format!("t_max/dt <= {max_steps:e} steps (dt = {dt})"),
                ));
            }
            let n = n as u64;
            // Grid times closer than dt (e.g. the short end of a log grid)
            // fall on one step, which is recorded once.
            if record_steps.last() == Some(&n) {
                continue;
            }
            record_steps.push(n);
        }
        let steps = *record_steps.last().expect("non-empty grid");
        if steps == 0 {
            return Err(Error::invalid(
                "t_max",
                spec.grid.t_max(),
                format!("t_max >= dt = {dt}"),
            ));
        }
        let burn_in_step = (spec.burn_in / dt).round() as u64;
        if burn_in_step >= steps {
            return Err(Error::invalid(
                "burn_in",
                spec.burn_in,
                format!("burn_in <= t_max - dt = {}", steps as f64 * dt - dt),
            ));
        }
        Ok(EulerPlan {
            dt,
            p_reset,
            q_flip,
            record_steps,
            burn_in_step,
            steps,
        })
    }

    /// The recorded times n_k·dt.
    pub fn record_times(&self) -> Vec<f64> {
        self.record_steps
            .iter()
            .map(|&n| n as f64 * self.dt)
            .collect()
    }
}

/// Simulate `spec.particles` particles with the Euler scheme and geometric
/// waiting times. Bit-identical for any thread count.
pub fn simulate(
    params: &Params,
    spec: &SimSpec,
    dt: f64,
    progress: &dyn Progress,
) -> Result<Observables> {
    simulate_with(params, spec, dt, EventSampling::Geometric, progress)
}

/// [`simulate`] with an explicit event sampler.
pub fn simulate_with(
    params: &Params,
    spec: &SimSpec,
    dt: f64,
    sampling: EventSampling,
    progress: &dyn Progress,
) -> Result<Observables> {
    simulate_with_lanes(params, spec, dt, sampling, LANES, progress)
}

/// Particles integrated side by side in one loop. The Euler step is
/// latency-bound (v → g(v) → v is a serial chain), so interleaving
/// independent particles lets the CPU overlap their chains. Every particle
/// keeps its own stream and pushes its samples in particle order, so each
/// particle's trajectory is the same as with one lane.
pub const LANES: usize = 8;

/// [`simulate_with`] with an explicit lane count (1 or [`LANES`]; anything
/// else means 1); exposed so tests can check that lanes change nothing.
#[doc(hidden)]
pub fn simulate_with_lanes(
    params: &Params,
    spec: &SimSpec,
    dt: f64,
    sampling: EventSampling,
    lanes: usize,
    progress: &dyn Progress,
) -> Result<Observables> {
    let whole = simulate_part(params, spec, dt, sampling, lanes, Part::Whole, progress)?;
    Ok(whole.into_iter().next().expect("one total"))
}

/// The unit totals of units `units` of [`simulate_with`]'s run (see
/// [`crate::sim::simulate_units`]).
pub fn simulate_units(
    params: &Params,
    spec: &SimSpec,
    dt: f64,
    sampling: EventSampling,
    units: Range<u64>,
    progress: &dyn Progress,
) -> Result<Vec<Observables>> {
    let part = Part::Units(units);
    simulate_part(params, spec, dt, sampling, LANES, part, progress)
}

fn simulate_part(
    params: &Params,
    spec: &SimSpec,
    dt: f64,
    sampling: EventSampling,
    lanes: usize,
    part: Part,
    progress: &dyn Progress,
) -> Result<Vec<Observables>> {
    let plan = EulerPlan::new(params, spec, dt)?;
    let p = &part;
    if params.noise().is_some() {
        return crate::with_drag!(params.drag(), |d| run_noise(
            d, params, spec, &plan, sampling, p, progress
        ));
    }
    // Match the drag law and sampler once, outside the hot loop: the kernel
    // is monomorphised per (law, sampler) and has no dispatch per step.
    Ok(crate::with_drag!(params.drag(), |d| match sampling {
        EventSampling::Geometric => run::<_, Geometric>(d, params, spec, &plan, lanes, p, progress),
        EventSampling::Bernoulli => run::<_, Bernoulli>(d, params, spec, &plan, lanes, p, progress),
    }))
}

/// The N-state / thermal kernel ([`noise`]) over the particles of `part`,
/// reduced like [`run`]; a non-finite result (a failed implicit step) is
/// an error.
fn run_noise<D: Drag>(
    f: &D,
    params: &Params,
    spec: &SimSpec,
    plan: &EulerPlan,
    sampling: EventSampling,
    part: &Part,
    progress: &dyn Progress,
) -> Result<Vec<Observables>> {
    let template = template(params, spec, plan);
    let geometric = sampling.is_geometric();
    let kernel = noise::NoiseKernel::new(f, params, spec, plan, &template, geometric)?;
    let first = spec.first_particle;
    let out = part.reduce(
        spec.particles,
        || template.clone(),
        |lo, hi, obs| {
            let mut occ = vec![0.0; spec.bins];
            let fr = &kernel.frame;
            for i in lo..hi {
                match sampling {
                    EventSampling::Geometric => {
                        scheduled::<_, Geometric>(&kernel, fr, first + i, obs, &mut occ)
                    }
                    EventSampling::Bernoulli => {
                        scheduled::<_, Bernoulli>(&kernel, fr, first + i, obs, &mut occ)
                    }
                }
            }
        },
        |total, part| total.merge(&part),
        progress,
    );
    if out
        .iter()
        .any(|o| !(o.v2_time_avg.sum.is_finite() && o.v_time_avg.sum.is_finite()))
    {
        return Err(Error::Numerical {
            method: "Euler scheme with a noise model",
            reason: "a non-finite velocity (a drift-implicit step failed to converge)".into(),
        });
    }
    Ok(out)
}

/// The empty observables of an Euler run: recorded at the plan's steps.
pub(crate) fn template(params: &Params, spec: &SimSpec, plan: &EulerPlan) -> Observables {
    let mut template = Observables::new(spec, params);
    let k = plan.record_steps.len();
    // Recording happens at whole steps: the fit uses the times actually recorded.
    template.times = plan.record_times();
    template.msd_weights = super::msd_fit_weights(&template.times, spec.burn_in, params);
    for a in [
        &mut template.v,
        &mut template.v2,
        &mut template.x,
        &mut template.x2,
    ] {
        a.truncate(k);
    }
    template
}

/// Reset / flip decisions of one particle (steps 3 and 4 of the module docs).
pub(crate) trait Events: Sized {
    fn new(rng: &mut Rng, plan: &EulerPlan) -> Self;
    /// Does a reset happen in step n?
    fn reset(&mut self, n: u64, rng: &mut Rng) -> bool;
    /// Does η flip in step n?
    fn flip(&mut self, n: u64, rng: &mut Rng) -> bool;
    /// The first step from which [`Events::reset`] or [`Events::flip`] may
    /// say yes (or draw): the steps before it are quiet. 0 when every step
    /// draws (the Bernoulli sampler).
    fn quiet_until(&self) -> u64;
}

/// Geometric waiting times: step indices of the next reset and flip.
pub(crate) struct Geometric {
    next_reset: u64,
    next_flip: u64,
    ln_reset: f64,
    ln_flip: f64,
}

impl Geometric {
    /// [`Events::new`] with the first flip gap drawn before the first
    /// reset gap (the first passage's stream).
    pub(crate) fn flip_first(rng: &mut Rng, plan: &EulerPlan) -> Self {
        let ln_reset = (-plan.p_reset).ln_1p();
        let ln_flip = (-plan.q_flip).ln_1p();
        let next_flip = geometric_gap(rng, ln_flip) - 1;
        let next_reset = geometric_gap(rng, ln_reset) - 1;
        Geometric {
            next_reset,
            next_flip,
            ln_reset,
            ln_flip,
        }
    }
}

impl Events for Geometric {
    #[inline(always)]
    fn new(rng: &mut Rng, plan: &EulerPlan) -> Self {
        let ln_reset = (-plan.p_reset).ln_1p();
        let ln_flip = (-plan.q_flip).ln_1p();
        // The first event happens in step G - 1 (steps count from 0).
        let next_reset = geometric_gap(rng, ln_reset) - 1;
        let next_flip = geometric_gap(rng, ln_flip) - 1;
        Geometric {
            next_reset,
            next_flip,
            ln_reset,
            ln_flip,
        }
    }
    #[inline(always)]
    fn reset(&mut self, n: u64, rng: &mut Rng) -> bool {
        if n == self.next_reset {
            self.next_reset = n.saturating_add(geometric_gap(rng, self.ln_reset));
            true
        } else {
            false
        }
    }
    #[inline(always)]
    fn quiet_until(&self) -> u64 {
        self.next_reset.min(self.next_flip)
    }
    #[inline(always)]
    fn flip(&mut self, n: u64, rng: &mut Rng) -> bool {
        if n == self.next_flip {
            self.next_flip = n.saturating_add(geometric_gap(rng, self.ln_flip));
            true
        } else {
            false
        }
    }
}

/// The paper's two uniform draws per step: reset if u < r·dt, flip if u < q.
struct Bernoulli {
    p: f64,
    q: f64,
}

impl Events for Bernoulli {
    #[inline(always)]
    fn new(_rng: &mut Rng, plan: &EulerPlan) -> Self {
        Bernoulli {
            p: plan.p_reset,
            q: plan.q_flip,
        }
    }
    #[inline(always)]
    fn reset(&mut self, _n: u64, rng: &mut Rng) -> bool {
        rng.gen::<f64>() < self.p
    }
    #[inline(always)]
    fn flip(&mut self, _n: u64, rng: &mut Rng) -> bool {
        rng.gen::<f64>() < self.q
    }
    #[inline(always)]
    fn quiet_until(&self) -> u64 {
        0
    }
}

fn run<D: Drag, E: Events>(
    f: &D,
    params: &Params,
    spec: &SimSpec,
    plan: &EulerPlan,
    lanes: usize,
    part: &Part,
    progress: &dyn Progress,
) -> Vec<Observables> {
    let (lo, hi) = params.bounds();
    let template = template(params, spec, plan);
    let kernel = Kernel {
        f,
        sigma: params.sigma(),
        reset: *params.reset(),
        lo,
        scale: spec.bins as f64 / (hi - lo),
        bins: spec.bins,
        seed: spec.seed,
        plan,
        schedule: params.schedule().clone(),
    };
    let frame = Frame {
        plan,
        seed: spec.seed,
        reset: *params.reset(),
        schedule: params.schedule().clone(),
        lo,
        scale: kernel.scale,
        bins: spec.bins,
    };
    // Chunks of parallel::CHUNK consecutive particles, reduced exactly like
    // parallel::reduce (each chunk from an empty accumulator in particle
    // order, chunks merged in index order into their unit, units in order):
    // bit-identical for any thread count and for any lane count. Inside a chunk, groups of LANES
    // particles run side by side; the remainder runs one at a time.
    let (n, first) = (spec.particles, spec.first_particle);
    part.reduce(
        n,
        || template.clone(),
        |lo, hi, obs| {
            let mut occ = vec![0.0; LANES * spec.bins];
            let mut i = lo;
            if !kernel.schedule.is_plain() {
                let telegraph = Telegraph {
                    f,
                    sigma: kernel.sigma,
                    dt: plan.dt,
                    reset: kernel.reset,
                };
                for i in lo..hi {
                    scheduled::<_, E>(&telegraph, &frame, first + i, obs, &mut occ[..spec.bins]);
                }
                return;
            }
            if lanes == LANES {
                let wide = wide_vectors();
                while i + LANES as u64 <= hi {
                    if wide {
                        // SAFETY: the CPU has AVX2 (checked at run time).
                        #[cfg(target_arch = "x86_64")]
                        unsafe {
                            kernel.group_avx2::<E>(first + i, obs, &mut occ)
                        };
                    } else {
                        kernel.group::<LANES, E>(first + i, obs, &mut occ);
                    }
                    i += LANES as u64;
                }
            }
            for i in i..hi {
                kernel.group::<1, E>(first + i, obs, &mut occ);
            }
        },
        |total, part| total.merge(&part),
        progress,
    )
}

struct Kernel<'a, D> {
    f: &'a D,
    sigma: f64,
    /// The resetting rule (target and noise state at a reset).
    reset: ResetRule,
    lo: f64,
    scale: f64,
    bins: usize,
    seed: u64,
    plan: &'a EulerPlan,
    /// The modifiers of the resetting rule (see the module docs).
    schedule: Schedule,
}

/// The paper's noise state of the level `eta` (0: +Sigma, 1: -Sigma).
#[inline]
fn sign_state(eta: f64) -> usize {
    usize::from(!(eta > 0.0))
}

/// The level of the paper's noise state `s` (0: +Sigma, 1: -Sigma).
#[inline]
fn state_level(s: usize, sigma: f64) -> f64 {
    if s == 0 {
        sigma
    } else {
        -sigma
    }
}

/// Number of Bernoulli(p) trials up to and including the first success,
/// G ~ Geometric(p) on {1, 2, ...}: G = 1 + floor(ln U / ln(1-p)), U ∈ (0, 1],
/// since P(G > k) = P(U ≤ (1-p)^k) = (1-p)^k. `ln_1mp` = ln(1-p) < 0;
/// p = 0 (ln_1mp = 0) never succeeds.
#[inline]
pub fn geometric_gap(rng: &mut Rng, ln_1mp: f64) -> u64 {
    if ln_1mp == 0.0 {
        return u64::MAX;
    }
    let u = 1.0 - rng.gen::<f64>(); // (0, 1]
                                    // `as` saturates, so an astronomically long gap becomes u64::MAX.
    1u64.saturating_add((u.ln() / ln_1mp) as u64)
}

/// One Euler step of the velocity, v + dt (s - g(v)) (Eq. (30)), with g the
/// law's [`Drag::fast_force`]: the one step of every Euler engine (this
/// kernel and the Euler first passage).
#[inline(always)]
pub fn euler_step<D: Drag>(drag: &D, v: f64, s: f64, dt: f64) -> f64 {
    v + dt * (s - drag.fast_force(v))
}

/// Whether the lanes may run on 256-bit vectors (AVX2, detected at run
/// time; the binary itself targets the x86-64 baseline).
fn wide_vectors() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::arch::is_x86_feature_detected!("avx2")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

impl<D: Drag> Kernel<'_, D> {
    /// [`Kernel::group`] of [`LANES`] particles compiled for AVX2: the same
    /// IEEE operations in the same order on wider vectors (Rust never fuses
    /// a multiply and an add), so bit-identical to the baseline build.
    ///
    /// # Safety
    /// Only for a CPU with AVX2.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn group_avx2<E: Events>(&self, first: u64, obs: &mut Observables, occ: &mut [f64]) {
        self.group::<LANES, E>(first, obs, occ)
    }

    #[inline(always)]
    fn bin(&self, v: f64) -> usize {
        let i = ((v - self.lo) * self.scale) as isize;
        i.clamp(0, self.bins as isize - 1) as usize
    }

    /// `count` quiet steps of L particles: steps 1 (window sums, if
    /// `window`), 2 and 3 (drift) of the module docs, with no record and no
    /// event.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn quiet<const L: usize>(
        &self,
        count: u64,
        window: bool,
        v: &mut [f64; L],
        x: &mut [f64; L],
        eta: &[f64; L],
        sv: &mut [f64; L],
        sv2: &mut [f64; L],
        occ: &mut [f64],
    ) {
        let dt = self.plan.dt;
        for _ in 0..count {
            if window {
                for l in 0..L {
                    sv[l] += v[l];
                    sv2[l] += v[l] * v[l];
                    occ[l * self.bins + self.bin(v[l])] += 1.0;
                }
            }
            for l in 0..L {
                x[l] += v[l] * dt;
                v[l] = euler_step(self.f, v[l], eta[l], dt);
            }
        }
    }

    /// Particles `first .. first + L`, side by side, following the step order
    /// of the module docs. Per particle, the random stream is consumed as:
    /// η_0 (one uniform), the event sampler's initial draws, then per step the
    /// reset draw(s) before the flip draw(s).
    #[inline(always)]
    fn group<const L: usize, E: Events>(&self, first: u64, obs: &mut Observables, occ: &mut [f64]) {
        let plan = self.plan;
        let dt = plan.dt;
        let mut rng: [Rng; L] = std::array::from_fn(|l| rng::stream(self.seed, first + l as u64));
        let mut eta = [0.0f64; L];
        let mut ev: [Option<E>; L] = std::array::from_fn(|_| None);
        for l in 0..L {
            eta[l] = if rng[l].gen::<f64>() < 0.5 {
                self.sigma
            } else {
                -self.sigma
            };
            ev[l] = Some(E::new(&mut rng[l], plan));
        }
        let mut ev: [E; L] = ev.map(|e| e.expect("initialised"));
        let (mut v, mut x) = ([0.0f64; L], [0.0f64; L]);
        let (mut sv, mut sv2, mut msd) = ([0.0f64; L], [0.0f64; L], [0.0f64; L]);
        let mut k = 0usize;
        let mut next_rec = plan.record_steps[0];
        let mut n = 0;
        while n < plan.steps {
            // Stopped: the cancelled reduction discards this chunk.
            if crate::parallel::stop_requested() {
                return;
            }
            // Quiet steps (no record, no event in any lane, the same side of
            // the window start) run branch-free; the same operations in the
            // same order as the full step below, so bit-identical.
            let window = n >= plan.burn_in_step;
            let mut end = plan.steps.min(next_rec);
            if !window {
                end = end.min(plan.burn_in_step);
            }
            for e in &ev {
                end = end.min(e.quiet_until());
            }
            if end > n {
                self.quiet::<L>(
                    end - n,
                    window,
                    &mut v,
                    &mut x,
                    &eta,
                    &mut sv,
                    &mut sv2,
                    occ,
                );
                n = end;
                continue;
            }
            // 1. observe
            if n == next_rec {
                for l in 0..L {
                    obs.record(k, v[l], x[l]);
                    msd[l] += obs.msd_term(k, x[l]);
                }
                k += 1;
                next_rec = plan.record_steps.get(k).copied().unwrap_or(u64::MAX);
            }
            if n >= plan.burn_in_step {
                for l in 0..L {
                    sv[l] += v[l];
                    sv2[l] += v[l] * v[l];
                    // Occupation in units of steps; the window is passed in steps too.
                    occ[l * self.bins + self.bin(v[l])] += 1.0;
                }
            }
            for l in 0..L {
                // 2. position with the old velocity
                x[l] += v[l] * dt;
                // 3. reset or Euler drift
                if ev[l].reset(n, &mut rng[l]) {
                    v[l] = self.reset.draw_velocity(&mut rng[l]);
                    let s = self.reset.draw_telegraph(sign_state(eta[l]), &mut rng[l]);
                    eta[l] = state_level(s, self.sigma);
                } else {
                    v[l] = euler_step(self.f, v[l], eta[l], dt);
                }
                // 4. flip
                if ev[l].flip(n, &mut rng[l]) {
                    eta[l] = -eta[l];
                }
            }
            n += 1;
        }
        if k < plan.record_steps.len() {
            for l in 0..L {
                obs.record(k, v[l], x[l]);
                msd[l] += obs.msd_term(k, x[l]);
            }
        }
        let w = (plan.steps - plan.burn_in_step) as f64;
        for l in 0..L {
            let o = &mut occ[l * self.bins..(l + 1) * self.bins];
            obs.finish_particle(sv[l] / w, sv2[l] / w, o, w, v[l], msd[l]);
        }
        obs.steps += L as u64 * plan.steps;
    }
}

/// What the scheduled loop ([`scheduled`]) reads of a run besides the
/// noise: the plan, seed, resetting rule and its modifiers, the bins.
pub(crate) struct Frame<'a> {
    pub(crate) plan: &'a EulerPlan,
    pub(crate) seed: u64,
    pub(crate) reset: ResetRule,
    pub(crate) schedule: Schedule,
    /// The histogram's lower edge, bins per unit velocity, bin count.
    lo: f64,
    scale: f64,
    bins: usize,
}

impl<'a> Frame<'a> {
    /// The frame of a run of `params` that keeps no histogram (one bin):
    /// the first passage's loop.
    pub(crate) fn unbinned(plan: &'a EulerPlan, seed: u64, params: &Params) -> Self {
        Frame {
            plan,
            seed,
            reset: *params.reset(),
            schedule: params.schedule().clone(),
            lo: 0.0,
            scale: 0.0,
            bins: 1,
        }
    }

    #[inline]
    fn bin(&self, v: f64) -> usize {
        let i = ((v - self.lo) * self.scale) as isize;
        i.clamp(0, self.bins as isize - 1) as usize
    }
}

/// What step 3 does in one step of a scheduled loop ([`Clock::step3`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Step3 {
    /// A held step of a refractory period: v stays put.
    Hold,
    /// A reset (Poisson, periodic or renewal).
    Reset,
    /// The velocity step.
    Drift,
}

/// The schedule's modifiers of one particle (module docs): the next
/// periodic or renewal reset time, its step, and the held steps left of a
/// refractory period. Shared by the scheduled loops of the simulation, the
/// velocity first passage ([`crate::mfpt::euler`]) and the search
/// ([`crate::search::euler`]); each relies on a scheduled clock having
/// no Poisson rate ([`crate::Params::with_schedule`]).
pub(crate) struct Clock {
    next: f64,
    /// round(next/dt): the step of the next scheduled reset (∞ without one).
    step: f64,
    hold: u64,
    dt: f64,
}

impl Clock {
    /// The clock of `schedule` at step `dt` at t = 0: the first scheduled
    /// reset time drawn from `rng` (no draw without a clock).
    #[inline]
    pub(crate) fn start(schedule: &Schedule, dt: f64, rng: &mut Rng) -> Self {
        let next = schedule.first_reset(rng);
        Clock {
            next,
            step: (next / dt).round(),
            hold: 0,
            dt,
        }
    }

    /// Whether the particle is held (a refractory period).
    #[inline]
    pub(crate) fn holding(&self) -> bool {
        self.hold > 0
    }

    /// Step 3 in step n with the Poisson decision `poisson`: a held step
    /// (counted), a reset (Poisson, or the scheduled one of step n), or the
    /// drift.
    #[inline]
    pub(crate) fn step3(&mut self, n: u64, poisson: bool) -> Step3 {
        if self.hold > 0 {
            self.hold -= 1;
            Step3::Hold
        } else if poisson || n as f64 >= self.step {
            Step3::Reset
        } else {
            Step3::Drift
        }
    }

    /// After a reset: the refractory period's held steps round(D/dt), then
    /// the next scheduled reset time, the clock restarted at the hold's end
    /// (`schedule` the one it started with).
    #[inline]
    pub(crate) fn rearm(&mut self, schedule: &Schedule, rng: &mut Rng) {
        let dt = self.dt;
        if let Some(r) = schedule.refractory {
            self.hold = (r.draw(rng) / dt).round() as u64;
        }
        if schedule.scheduled_clock() {
            let free = self.next + self.hold as f64 * dt;
            self.next = schedule.next_reset(free, rng);
            self.step = (self.next / dt).round();
        }
    }
}

/// The noise's part of one Euler step in the scheduled loop: the paper's
/// η = ±Σ flipped by the event sampler ([`Telegraph`]) or a finite-state
/// chain with its thermal kick ([`noise::NoiseKernel`]).
pub(crate) trait NoiseSteps {
    /// The noise state of one particle.
    type State;
    /// The start state and the event sampler, drawn from `rng`.
    fn start<E: Events>(&self, rng: &mut Rng, plan: &EulerPlan) -> (Self::State, E);
    /// Step 3 without a reset: the velocity after one step from v.
    fn drift(&self, v: f64, st: &Self::State, rng: &mut Rng) -> f64;
    /// Step 3 with a reset in step n: the noise state at the reset.
    fn reset(&self, st: &mut Self::State, n: u64, rng: &mut Rng);
    /// Step 4 in step n: the noise state moves on.
    fn jump<E: Events>(&self, st: &mut Self::State, ev: &mut E, n: u64, rng: &mut Rng);
    /// Whether v rests at the law's atom outside a hold (a state whose
    /// fixed point it is).
    fn rests(&self, v: f64, st: &Self::State, obs: &Observables) -> bool;
}

/// The paper's noise η = ±Σ in the scheduled loop: the step of
/// [`euler_step`], a reset keeping or re-drawing η, the flips of the event
/// sampler.
pub(crate) struct Telegraph<'a, D> {
    pub(crate) f: &'a D,
    pub(crate) sigma: f64,
    pub(crate) dt: f64,
    pub(crate) reset: ResetRule,
}

impl<D: Drag> NoiseSteps for Telegraph<'_, D> {
    type State = f64;
    fn start<E: Events>(&self, rng: &mut Rng, plan: &EulerPlan) -> (f64, E) {
        let eta = if rng.gen::<f64>() < 0.5 {
            self.sigma
        } else {
            -self.sigma
        };
        (eta, E::new(rng, plan))
    }
    #[inline]
    fn drift(&self, v: f64, eta: &f64, _rng: &mut Rng) -> f64 {
        euler_step(self.f, v, *eta, self.dt)
    }
    #[inline]
    fn reset(&self, eta: &mut f64, _n: u64, rng: &mut Rng) {
        let s = self.reset.draw_telegraph(sign_state(*eta), rng);
        *eta = state_level(s, self.sigma);
    }
    #[inline]
    fn jump<E: Events>(&self, eta: &mut f64, ev: &mut E, n: u64, rng: &mut Rng) {
        if ev.flip(n, rng) {
            *eta = -*eta;
        }
    }
    fn rests(&self, _v: f64, _eta: &f64, _obs: &Observables) -> bool {
        false
    }
}

/// Particle `i` with the schedule's modifiers (module docs) and the noise
/// steps `noise`, one step at a time in the step order of
/// [`Kernel::group`]. The stream: the noise's start draws, the first
/// scheduled reset time; per step the Poisson reset draws, then a reset's
/// velocity, noise state, refractory duration and next scheduled time (or
/// the drift's draws), then step 4's draws. During a hold v stays put and
/// the noise moves on.
fn scheduled<N: NoiseSteps, E: Events>(
    noise: &N,
    fr: &Frame,
    i: u64,
    obs: &mut Observables,
    occ: &mut [f64],
) {
    let plan = fr.plan;
    let dt = plan.dt;
    let mut rng = rng::stream(fr.seed, i);
    let (mut st, mut ev) = noise.start::<E>(&mut rng, plan);
    let mut clock = Clock::start(&fr.schedule, dt, &mut rng);
    let (mut v, mut x) = (0.0f64, 0.0f64);
    let (mut sv, mut sv2, mut msd, mut k) = (0.0f64, 0.0f64, 0.0f64, 0usize);
    // Steps at the law's atom (held at the reset velocity, or resting at
    // a state's fixed point), in no bin.
    let mut at_atom = 0.0f64;
    for n in 0..plan.steps {
        // Stopped: the cancelled reduction discards this chunk.
        if crate::parallel::stop_due(n) {
            return;
        }
        if plan.record_steps.get(k) == Some(&n) {
            obs.record(k, v, x);
            msd += obs.msd_term(k, x);
            k += 1;
        }
        if n >= plan.burn_in_step {
            sv += v;
            sv2 += v * v;
            if (clock.holding() && obs.is_atom(v)) || noise.rests(v, &st, obs) {
                at_atom += 1.0;
            } else {
                occ[fr.bin(v)] += 1.0;
            }
        }
        x += v * dt;
        let poisson = ev.reset(n, &mut rng);
        match clock.step3(n, poisson) {
            Step3::Hold => {}
            Step3::Reset => {
                v = fr.reset.draw_velocity(&mut rng);
                noise.reset(&mut st, n, &mut rng);
                if let Some(p) = fr.schedule.position {
                    x = p.x;
                }
                clock.rearm(&fr.schedule, &mut rng);
            }
            Step3::Drift => v = noise.drift(v, &st, &mut rng),
        }
        noise.jump(&mut st, &mut ev, n, &mut rng);
    }
    if k < plan.record_steps.len() {
        obs.record(k, v, x);
        msd += obs.msd_term(k, x);
    }
    let w = (plan.steps - plan.burn_in_step) as f64;
    obs.finish_particle(sv / w, sv2 / w, occ, w, v, msd);
    obs.finish_atom(at_atom, w, v);
    obs.record_final_position(x);
    obs.steps += plan.steps;
}

/// Exact expected moments of the Euler chain (not of the continuum process)
/// for linear drag g(v) = v, started like the simulation (x = v = 0, η = ±Σ).
///
/// With a = 1 - dt, p = r·dt, ρ = 1 - 2q = e^{-2λ dt} and the step order of
/// the module docs, the moments m = E v, c = E vη, s = E v², X = E x,
/// XV = E xv, XE = E xη, X2 = E x² obey a closed linear recursion
/// (E η_n = 0, E η² = Σ², E[η_{n+1} | η_n] = ρ η_n, events independent):
/// m' = p v_r + (1-p) a m, c' = ρ(1-p)(a c + dt Σ²),
/// s' = p v_r² + (1-p)(a² s + 2 a dt c + dt² Σ²), X' = X + dt m,
/// X2' = X2 + 2 dt XV + dt² s, XV' = p v_r X' + (1-p)(a (XV + dt s) + dt (XE + dt c)),
/// XE' = ρ (XE + dt c). This separates the O(dt) discretisation bias from
/// statistical error in tests.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct LinearChainMoments {
    /// E v_n.
    pub v: f64,
    /// E v_n η_n.
    pub v_eta: f64,
    /// E v_n².
    pub v2: f64,
    /// E x_n.
    pub x: f64,
    /// E x_n v_n.
    pub x_v: f64,
    /// E x_n η_n.
    pub x_eta: f64,
    /// E x_n².
    pub x2: f64,
}

/// Iterator-style stepper for [`LinearChainMoments`].
#[derive(Clone, Debug)]
pub struct LinearChain {
    dt: f64,
    p: f64,
    rho: f64,
    /// <v_r> and <v_r²> of the reset target.
    vr1: f64,
    vr2: f64,
    s2: f64,
    /// Moments at the current step.
    pub m: LinearChainMoments,
}

impl LinearChain {
    /// Start at step 0 (all moments zero). Requires linear drag and a valid dt.
    pub fn new(params: &Params, dt: f64) -> Result<Self> {
        // The chain is the paper's protocol only: no modifier of the
        // resetting rule (the closed forms' support does not carry over).
        if let Some(&f) = params.schedule().features().first() {
            return Err(Error::invalid(
                f.flag(),
                params.schedule().spec_of(f),
                format!("no {} in the exactly solvable Euler chain", f.describe()),
            ));
        }
        if !params.drag().newtonian() {
            return Err(Error::invalid(
                "drag",
                params.drag(),
                "linear (the Euler chain is exactly solvable only for Newtonian drag)",
            ));
        }
        let dt = params.check_dt(dt)?;
        let (vr1, vr2) = params.reset().target().moments();
        Ok(LinearChain {
            dt,
            p: params.rate() * dt,
            rho: (-2.0 * params.lambda() * dt).exp(),
            vr1,
            vr2,
            s2: params.sigma() * params.sigma(),
            m: LinearChainMoments::default(),
        })
    }

    /// Advance one Euler step.
    pub fn step(&mut self) {
        let (dt, p, rho, s2) = (self.dt, self.p, self.rho, self.s2);
        let (vr, vr2) = (self.vr1, self.vr2);
        let a = 1.0 - dt;
        let o = self.m;
        let x = o.x + dt * o.v;
        let x_eta_pre = o.x_eta + dt * o.v_eta;
        self.m = LinearChainMoments {
            v: p * vr + (1.0 - p) * a * o.v,
            v_eta: rho * (1.0 - p) * (a * o.v_eta + dt * s2),
            v2: p * vr2 + (1.0 - p) * (a * a * o.v2 + 2.0 * a * dt * o.v_eta + dt * dt * s2),
            x,
            x_v: p * vr * x + (1.0 - p) * (a * (o.x_v + dt * o.v2) + dt * x_eta_pre),
            x_eta: rho * x_eta_pre,
            x2: o.x2 + 2.0 * dt * o.x_v + dt * dt * o.v2,
        };
    }

    /// Stationary E v², E v, E vη of the chain (fixed point of the recursion).
    pub fn stationary(params: &Params, dt: f64) -> Result<LinearChainMoments> {
        let c = LinearChain::new(params, dt)?;
        let (p, rho, vr, vr2, s2) = (c.p, c.rho, c.vr1, c.vr2, c.s2);
        let a = 1.0 - dt;
        let v = p * vr / (1.0 - (1.0 - p) * a);
        let v_eta = rho * (1.0 - p) * dt * s2 / (1.0 - rho * (1.0 - p) * a);
        let v2 = (p * vr2 + (1.0 - p) * (2.0 * a * dt * v_eta + dt * dt * s2))
            / (1.0 - (1.0 - p) * a * a);
        Ok(LinearChainMoments {
            v,
            v_eta,
            v2,
            ..Default::default()
        })
    }
}

/// Exact expectation of what an Euler run with linear drag reports: the
/// window average of v² (the `v2` of the summary) and E v², E x² at the
/// plan's record steps.
pub fn linear_chain_expectations(
    params: &Params,
    plan: &EulerPlan,
) -> Result<(f64, Vec<LinearChainMoments>)> {
    let mut chain = LinearChain::new(params, plan.dt)?;
    let mut at = Vec::with_capacity(plan.record_steps.len());
    let mut k = 0;
    let mut sum = 0.0;
    for n in 0..=plan.steps {
        if plan.record_steps.get(k) == Some(&n) {
            at.push(chain.m);
            k += 1;
        }
        if n >= plan.burn_in_step && n < plan.steps {
            sum += chain.m.v2;
        }
        chain.step();
    }
    Ok((sum / (plan.steps - plan.burn_in_step) as f64, at))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::DragLaw;
    use crate::rng::stream;
    use crate::stats::MeanAcc;

    /// The law of event step indices: the number of events among the first
    /// `n` steps is Binomial(n, p) for both samplers. Compare mean and
    /// variance of the count (4 standard errors).
    #[test]
    fn geometric_gaps_give_binomial_counts() {
        let (n, p) = (200u64, 0.03f64);
        let ln = (-p).ln_1p();
        let reps = 40_000;
        let (mut geo, mut ber) = (MeanAcc::new(), MeanAcc::new());
        for i in 0..reps {
            let mut rng = stream(5, i);
            let mut count = 0u64;
            let mut next = geometric_gap(&mut rng, ln) - 1;
            while next < n {
                count += 1;
                next += geometric_gap(&mut rng, ln);
            }
            geo.push(count as f64);
            let mut rng = stream(6, i);
            ber.push((0..n).filter(|_| rng.gen::<f64>() < p).count() as f64);
        }
        let mean = n as f64 * p;
        let var = mean * (1.0 - p);
        for acc in [geo, ber] {
            let se = (var / reps as f64).sqrt();
            assert!((acc.mean() - mean).abs() < 4.0 * se, "{acc:?}");
            // Var of the sample variance ≈ (μ4 - σ⁴)/n; μ4 of a binomial ≈ 3σ⁴ + σ²(1-6p(1-p)).
            let mu4 = 3.0 * var * var + var * (1.0 - 6.0 * p * (1.0 - p));
            let se_var = ((mu4 - var * var) / reps as f64).sqrt();
            assert!((acc.variance() - var).abs() < 4.0 * se_var, "{acc:?}");
        }
    }

    #[test]
    fn geometric_gap_extremes() {
        let mut rng = stream(1, 1);
        assert_eq!(geometric_gap(&mut rng, 0.0), u64::MAX);
        // p → 1: every trial succeeds.
        let ln = (-(1.0 - 1e-300f64)).ln_1p();
        assert!((0..100).all(|_| geometric_gap(&mut rng, ln) == 1));
    }

    #[test]
    fn chain_fixed_point_matches_iteration() {
        let p = Params::new(DragLaw::Linear, 1.3, 0.7, 2.0, 0.4).unwrap();
        let mut c = LinearChain::new(&p, 0.01).unwrap();
        for _ in 0..20_000 {
            c.step();
        }
        let s = LinearChain::stationary(&p, 0.01).unwrap();
        assert!((c.m.v2 - s.v2).abs() < 1e-12);
        assert!((c.m.v - s.v).abs() < 1e-12);
        assert!((c.m.v_eta - s.v_eta).abs() < 1e-12);
    }
}
