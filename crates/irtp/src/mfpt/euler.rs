//! Euler first passage: the paper's Euler scheme (Eqs. (30)-(32)) run until the
//! velocity reaches the target, with flip and reset steps drawn as
//! geometric waiting times and several particles in flight per thread. The
//! step and the gaps are those of the particle simulation ([`euler_step`]
//! with the law's fast g, [`geometric_gap`]). The entry point is
//! [`super::solve`] with [`super::Method::Euler`].
//!
//! The paper's noise under Poisson resetting runs the lane kernel below.
//! A clock or a refractory period, and any noise model (finite-state
//! noise, thermal noise with the Brownian-bridge crossing check, Eq.
//! (N19)) with or without them, run the one loop of the `scheduled`
//! submodule over the Euler sampler's noise steps and schedule
//! ([`crate::sim::euler`]): the periodic reset at kT in the step from n·dt
//! to (n+1)·dt with n = round(kT/dt) (O(dt) timing; a renewal clock's
//! drawn times likewise), a refractory period as round(D/dt) held steps
//! (no drift, Poisson resets discarded, the noise moving on, periodic
//! times up to its end skipped). A reset at or above v_t is the passage at
//! that step. A position reset does not touch the velocity process.

use super::estimator::{merge_units, FptSample, FptStats, FptSummary};
use super::Problem;
use crate::error::{finite, Error, Result};
use crate::model::reset::{Reset, ResetRule};
use crate::model::Drag;
use crate::parallel::{self, Progress};
use crate::rng::{self, Rng};
use crate::sim::euler::{euler_step, geometric_gap};
use serde::{Deserialize, Serialize};
use std::ops::Range;

mod scheduled;

/// Euler first-passage sampler (paper Eqs. (30)-(32)), step order as in
/// [`crate::sim::euler`]: with probability r dt, v ← v_r (noise kept),
/// otherwise v ← v + dt (eta - g(v)) and arrival if v ≥ v_t (time = steps·dt,
/// an overshoot bias of at most dt); then eta flips with probability
/// q = ½(1 - e^{-2 lambda dt}).
/// Flip and reset steps are drawn as geometric waiting times — the same
/// Markov chain as a Bernoulli trial every step, with one random number per
/// event instead of two per step. Targets below v_0 run in the reflected frame.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct EulerFpt {
    problem: Problem,
    dt: f64,
    t_max: f64,
    /// The Brownian-bridge crossing check between steps at T > 0 (on;
    /// off only in tests that show the O(sqrt(dt)) bias it removes).
    #[serde(skip, default = "bridge_on")]
    bridge: bool,
}

fn bridge_on() -> bool {
    true
}

impl EulerFpt {
    /// Validate dt (Euler stability limit and r dt < 1) and t_max > 0.
    pub fn new(problem: Problem, dt: f64, t_max: f64) -> Result<Self> {
        let par = problem.params();
        let dt = match par.noise() {
            None => par.check_dt(dt)?,
            Some(_) => {
                par.require(crate::model::reset::Solver::MfptEuler)?;
                crate::sim::euler::noise::check_noise_dt(par, dt)?
            }
        };
        if !(problem.params().rate() * dt < 1.0) {
            return Err(Error::invalid(
                "dt",
                dt,
                format!(
                    "rate * dt < 1 (the reset probability per step is r dt), i.e. dt < {}",
                    1.0 / problem.params().rate()
                ),
            ));
        }
        let t_max = finite("t_max", t_max)?;
        if !(t_max >= dt) {
            return Err(Error::invalid(
                "t_max",
                t_max,
                format!("t_max >= dt = {dt}"),
            ));
        }
        Ok(EulerFpt {
            problem,
            dt,
            t_max,
            bridge: true,
        })
    }

    /// Time step.
    pub fn dt(&self) -> f64 {
        self.dt
    }

    /// The same sampler without the Brownian-bridge crossing check at
    /// T > 0 (passages detected at the steps only: an O(sqrt(dt)) bias);
    /// for tests that measure what the check removes.
    #[doc(hidden)]
    pub fn without_bridge(mut self) -> Self {
        self.bridge = false;
        self
    }

    /// Run `n` particles: particle i uses the stream (seed, i) and starts
    /// in +Sigma for even i. Four particles advance side by side per
    /// thread (the step is a serial chain v → g(v) → v, so interleaving
    /// independent particles lets the CPU overlap them); a lane that
    /// finishes takes the chunk's next particle, and results are added in
    /// particle order, so the statistics are bit-identical to one particle
    /// at a time, for any thread count.
    pub fn stats(&self, n: u64, seed: u64, progress: &dyn Progress) -> FptStats {
        let all = self.units(n, 0..parallel::unit_count(n), seed, progress);
        merge_units(self.t_max, &all)
    }

    /// The unit totals of units `units` of [`EulerFpt::stats`]'s run of
    /// `n` particles ([`crate::mfpt::estimator::first_passage_units`]'s
    /// contract: merged in unit order, the whole run's bits).
    pub fn units(
        &self,
        n: u64,
        units: Range<u64>,
        seed: u64,
        progress: &dyn Progress,
    ) -> Vec<FptStats> {
        let par = self.problem.params();
        let schedule = par.schedule();
        if par.noise().is_some() || schedule.scheduled_clock() || schedule.refractory.is_some() {
            return scheduled::units(self, n, units, seed, progress);
        }
        let c = Chain::new(self, seed);
        crate::with_drag!(par.drag(), |d| {
            parallel::reduce_units(
                n,
                units.clone(),
                || FptStats::new(self.t_max),
                |lo, hi, acc| c.chunk(d, lo, hi, acc),
                |a, b| a.merge(&b),
                progress,
            )
        })
    }
}

/// A first-passage estimate Richardson-extrapolated in the time step:
/// from runs at dt and dt/2 whose means carry a bias c·dt + O(dt²)
/// (the Euler weak error and the crossing detected on the step, an
/// overshoot of at most one step), 2 T(dt/2) - T(dt) removes the term in
/// dt. The two runs share the seed, so their errors may be correlated: the
/// standard error is bounded for any correlation by 2 se(dt/2) + se(dt).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Extrapolated {
    /// 2 tau(dt/2) - tau(dt) (NaN where either run is censored).
    pub tau: f64,
    /// Its standard-error bound.
    pub tau_err: f64,
    /// The same for the particles started in +Sigma.
    pub tau_plus: f64,
    /// Its standard-error bound.
    pub tau_plus_err: f64,
    /// The same for the particles started in -Sigma.
    pub tau_minus: f64,
    /// Its standard-error bound.
    pub tau_minus_err: f64,
    /// tau(dt/2) - tau(dt): the step's leading bias, measured (as large
    /// as the remaining bias of tau(dt/2)).
    pub step_bias: f64,
}

/// [`Extrapolated`] from the summaries of the runs at dt (`coarse`) and
/// dt/2 (`fine`).
pub fn extrapolate(coarse: &FptSummary, fine: &FptSummary) -> Extrapolated {
    let ex = |c: f64, f: f64| 2.0 * f - c;
    let err = |c: f64, f: f64| 2.0 * f + c;
    Extrapolated {
        tau: ex(coarse.tau, fine.tau),
        tau_err: err(coarse.tau_err, fine.tau_err),
        tau_plus: ex(coarse.tau_plus, fine.tau_plus),
        tau_plus_err: err(coarse.tau_plus_err, fine.tau_plus_err),
        tau_minus: ex(coarse.tau_minus, fine.tau_minus),
        tau_minus_err: err(coarse.tau_minus_err, fine.tau_minus_err),
        step_bias: fine.tau - coarse.tau,
    }
}

/// A correction 2 T(dt/2) - T(dt) - T(dt/2) larger than this fraction of
/// the extrapolated value (beyond 4 standard errors of the two runs) means
/// dt is not small against the passage time: the expansion c·dt + O(dt²)
/// behind [`extrapolate`] does not hold there.
pub const MAX_STEP_CORRECTION: f64 = 0.5;

/// Verify an extrapolation from `coarse` (dt) and `fine` (dt/2) for tau and
/// both starting states (censored runs, NaN, are skipped): each
/// 2 T(dt/2) - T(dt) must be at least `least` (a lower bound of the mean
/// passage time, 0 or more) and its correction |T(dt/2) - T(dt)| within
/// [`MAX_STEP_CORRECTION`] of it, or the answer is refused
/// ([`Error::Numerical`], naming `--dt`): a target within a few steps gave
/// a negative mean time.
pub fn verify_extrapolation(coarse: &FptSummary, fine: &FptSummary, least: f64) -> Result<()> {
    let rows = [
        ("tau", coarse.tau, coarse.tau_err, fine.tau, fine.tau_err),
        (
            "tau_plus",
            coarse.tau_plus,
            coarse.tau_plus_err,
            fine.tau_plus,
            fine.tau_plus_err,
        ),
        (
            "tau_minus",
            coarse.tau_minus,
            coarse.tau_minus_err,
            fine.tau_minus,
            fine.tau_minus_err,
        ),
    ];
    let refuse = |reason: String| Error::Numerical {
        method: "Euler extrapolation to dt -> 0",
        reason: format!("{reason}; reduce --dt or use --method exact"),
    };
    for (name, c, c_err, f, f_err) in rows {
        if !(c.is_finite() && f.is_finite()) {
            continue;
        }
        let ex = 2.0 * f - c;
        if !(ex >= least.max(0.0)) {
            return Err(refuse(format!(
                "{name} = 2 T(dt/2) - T(dt) = {ex:.3e} is below the least time {:.3e}",
                least.max(0.0)
            )));
        }
        let change = (f - c).abs() - 4.0 * (c_err + f_err);
        if change > MAX_STEP_CORRECTION * ex {
            return Err(refuse(format!(
                "{name} changes by {:.2e} from dt to dt/2, over half of its extrapolated {ex:.2e}",
                (f - c).abs()
            )));
        }
    }
    Ok(())
}

/// Particles in flight per thread.
const LANES: usize = 4;

/// The constants of one run of the lane kernel (the paper's noise, Poisson
/// resetting), in the canonical (upward) frame.
struct Chain {
    dt: f64,
    /// ln(1 - q) and ln(1 - r dt): the geometric gaps of flips and resets.
    ln_flip: f64,
    ln_reset: f64,
    v0: f64,
    vt: f64,
    sigma: f64,
    /// The ± labels swapped by the reflection to the upward frame.
    swapped: bool,
    max_steps: u64,
    reset: ResetRule,
    seed: u64,
}

/// One particle in flight.
struct Lane {
    /// Particle index.
    i: u64,
    rng: Rng,
    v: f64,
    /// The noise value ±Sigma.
    s: f64,
    next_flip: u64,
    next_reset: u64,
    step: u64,
}

impl Chain {
    fn new(e: &EulerFpt, seed: u64) -> Self {
        let (p, swapped) = e.problem.canonical();
        let par = p.params();
        let dt = e.dt;
        Chain {
            dt,
            ln_flip: (-(0.5 * (-(-2.0 * par.lambda() * dt).exp_m1()))).ln_1p(),
            ln_reset: (-(par.rate() * dt)).ln_1p(),
            v0: p.v0(),
            vt: p.vt(),
            sigma: par.sigma(),
            swapped,
            max_steps: (e.t_max / dt).floor() as u64,
            reset: *par.reset(),
            seed,
        }
    }

    /// Particle i at t = 0: its stream, start state, first event steps.
    fn start(&self, i: u64) -> Lane {
        let mut rng = rng::stream(self.seed, i);
        let plus = (i % 2 == 0) != self.swapped;
        let next_flip = geometric_gap(&mut rng, self.ln_flip);
        let next_reset = geometric_gap(&mut rng, self.ln_reset);
        Lane {
            i,
            rng,
            v: self.v0,
            s: if plus { self.sigma } else { -self.sigma },
            next_flip,
            next_reset,
            step: 0,
        }
    }

    /// One Euler step of a lane (reset or drift, arrival check, then flip);
    /// the sample once the particle has arrived or reached t_max.
    #[inline(always)]
    fn advance<D: Drag>(&self, drag: &D, l: &mut Lane) -> Option<FptSample> {
        if l.step >= self.max_steps {
            return Some(FptSample {
                time: None,
                work: l.step,
            });
        }
        l.step += 1;
        if l.step == l.next_reset {
            l.v = self.reset.draw_velocity(&mut l.rng);
            let s = self
                .reset
                .draw_telegraph(usize::from(!(l.s > 0.0)), &mut l.rng);
            l.s = if s == 0 { self.sigma } else { -self.sigma };
            l.next_reset = l
                .step
                .saturating_add(geometric_gap(&mut l.rng, self.ln_reset));
        } else {
            l.v = euler_step(drag, l.v, l.s, self.dt);
            if l.v >= self.vt {
                return Some(FptSample {
                    time: Some(l.step as f64 * self.dt),
                    work: l.step,
                });
            }
        }
        self.flip(l);
        None
    }

    /// Step 4: the flip of the noise state, at the lane's next flip step.
    #[inline(always)]
    fn flip(&self, l: &mut Lane) {
        if l.step == l.next_flip {
            l.s = -l.s;
            l.next_flip = l
                .step
                .saturating_add(geometric_gap(&mut l.rng, self.ln_flip));
        }
    }

    /// Particles lo..hi, `LANES` in flight ([`in_lanes`]).
    fn chunk<D: Drag>(&self, drag: &D, lo: u64, hi: u64, acc: &mut FptStats) {
        in_lanes(
            lo,
            hi,
            acc,
            |i| self.start(i),
            |l| self.advance(drag, l),
            |l| l.i,
        );
    }
}

/// Particles lo..hi, `LANES` in flight: `start(i)` is particle i's lane,
/// `advance` one step of a lane (its sample once the particle has arrived
/// or reached t_max), `index` a lane's particle; a lane that finishes
/// takes the chunk's next particle, and the samples are added to `acc` in
/// index order (the same statistics as one particle at a time).
#[inline(always)]
fn in_lanes<L>(
    lo: u64,
    hi: u64,
    acc: &mut FptStats,
    start: impl Fn(u64) -> L,
    mut advance: impl FnMut(&mut L) -> Option<FptSample>,
    index: impl Fn(&L) -> u64,
) {
    let mut out: Vec<Option<FptSample>> = vec![None; (hi - lo) as usize];
    let mut next = lo;
    let mut lanes: Vec<L> = Vec::with_capacity(LANES);
    while lanes.len() < LANES && next < hi {
        lanes.push(start(next));
        next += 1;
    }
    let mut rounds = 0u64;
    while !lanes.is_empty() {
        rounds += 1;
        // A stopped chunk is discarded by the cancelled reduction.
        if parallel::stop_due(rounds) {
            return;
        }
        let mut k = 0;
        while k < lanes.len() {
            if let Some(sample) = advance(&mut lanes[k]) {
                out[(index(&lanes[k]) - lo) as usize] = Some(sample);
                if next < hi {
                    lanes[k] = start(next);
                    next += 1;
                } else {
                    lanes.swap_remove(k);
                    continue;
                }
            }
            k += 1;
        }
    }
    for (k, sample) in out.into_iter().enumerate() {
        let stratum = ((lo + k as u64) % 2) as usize;
        acc.push(stratum, sample.expect("every particle ran"));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::{DragLaw, Params};
    use crate::parallel::NoProgress;

    /// A summary with the same mean and standard error for both states.
    fn summary(tau: f64, err: f64) -> FptSummary {
        let mut s = EulerFpt::new(
            Problem::new(
                Params::new(DragLaw::Tan, 3.0, 0.5, 1.0, 0.0).unwrap(),
                0.0,
                0.5,
            )
            .unwrap(),
            0.01,
            10.0,
        )
        .unwrap()
        .stats(2, 1, &NoProgress)
        .summary();
        (s.tau, s.tau_plus, s.tau_minus) = (tau, tau, tau);
        (s.tau_err, s.tau_plus_err, s.tau_minus_err) = (err, err, err);
        s
    }

    /// The extrapolation is refused below its bound (a negative mean: a
    /// target within a step) and where its correction is over half the
    /// value beyond the noise; accepted in the asymptotic regime and where
    /// the change is within the noise.
    #[test]
    fn extrapolation_is_verified() {
        let ok = |c: f64, f: f64, err: f64, least: f64| {
            verify_extrapolation(&summary(c, err), &summary(f, err), least)
        };
        let refused = |r: Result<()>| match r {
            Err(Error::Numerical { reason, .. }) => assert!(reason.contains("--dt"), "{reason}"),
            r => panic!("{r:?}"),
        };
        // T(dt) = 2 dt, T(dt/2) = dt: 0, then below 0.
        refused(ok(0.02, 0.01, 0.0, 1e-12));
        refused(ok(0.02, 0.0099, 1e-5, 0.0));
        // Above the bound, but the correction 0.5 is over half of 0.6.
        refused(ok(1.6, 1.1, 0.01, 0.1));
        // Asymptotic: bias 0.01 on 3.
        ok(3.02, 3.01, 0.01, 0.4).unwrap();
        // A change of 0.5 within 4 standard errors of noise (0.1 each).
        ok(1.6, 1.1, 0.1, 0.1).unwrap();
        // Censored runs (NaN) are not verified.
        ok(f64::NAN, 1.0, 0.0, 0.5).unwrap();
    }

    /// Without flips and resets the passage is the deterministic chain of
    /// the shared [`euler_step`]: same step count, for every law.
    #[test]
    fn steps_are_the_shared_euler_step() {
        for (d, sigma) in [
            (DragLaw::Tan, 3.0),
            (DragLaw::Tanh, 0.6),
            (DragLaw::Linear, 1.0),
        ] {
            let p = Params::new(d.clone(), sigma, 1e-300, 0.0, 0.0).unwrap();
            let (v0, vt, dt) = (-0.2, 0.5 * p.v_upper(), 1e-3);
            let pr = Problem::new(p, v0, vt).unwrap();
            let (mut v, mut n) = (v0, 0u64);
            while v < vt {
                v = euler_step(&d, v, sigma, dt);
                n += 1;
            }
            let fpt = EulerFpt::new(pr, dt, 1e3).unwrap();
            let st = fpt.stats(1, 1, &NoProgress);
            assert_eq!(st.work, n, "{d}");
            assert_eq!(st.summary().tau_plus, n as f64 * dt, "{d}");
        }
    }

    /// Lanes in flight change nothing: the statistics equal those of the
    /// particles run one at a time in index order, bit for bit (both
    /// directions, with resets and censoring at a short t_max).
    #[test]
    fn lanes_equal_one_particle_at_a_time() {
        for (v0, vt, t_max) in [(-0.249, 0.5, 1e4), (0.3, -0.4, 0.7)] {
            let p = Params::new(DragLaw::Tan, 3.0, 0.5, 2.0, 0.1).unwrap();
            let fpt = EulerFpt::new(Problem::new(p, v0, vt).unwrap(), 1e-3, t_max).unwrap();
            let n = 600; // two full chunks and a partial one
            let c = Chain::new(&fpt, 7);
            let mut one = FptStats::new(t_max);
            let mut parts = Vec::new();
            for lo in (0..n).step_by(parallel::CHUNK as usize) {
                let mut acc = FptStats::new(t_max);
                for i in lo..(lo + parallel::CHUNK).min(n) {
                    let mut lane = c.start(i);
                    let sample = loop {
                        if let Some(s) = c.advance(&crate::model::drag::Tan, &mut lane) {
                            break s;
                        }
                    };
                    acc.push((i % 2) as usize, sample);
                }
                parts.push(acc);
            }
            for part in &parts {
                one.merge(part);
            }
            let many = fpt.stats(n, 7, &NoProgress);
            assert_eq!(many, one);
            assert!(t_max > 1.0 || many.censored() > 0);
        }
    }
}
