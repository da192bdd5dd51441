//! First-passage times from particle simulation.
//!
//! [`first_passage_stats`] is method-agnostic: it hands particle `i` its own
//! stream `rng::stream(seed, i)` and its starting noise state (even `i`: +Sigma,
//! odd `i`: -Sigma — stratified, so tau = (tau+ + tau-)/2 is estimated with
//! exactly balanced halves), calls the per-particle sampler and reduces the
//! results deterministically into mergeable sums. To plug in another sampler
//! (e.g. an exact event-driven one) pass any
//! `Fn(index, &mut Rng, start_plus) -> FptSample`.

use super::Problem;
use crate::error::{finite, Error, Result};
use crate::model::Drag;
use crate::parallel::{self, Progress};
use crate::rng::{self, Rng};
use crate::stats::MeanAcc;
use rand::Rng as _;
use serde::{Deserialize, Serialize};

/// One particle's first passage.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct FptSample {
    /// First-passage time; `None` if the target was not reached by t_max.
    pub time: Option<f64>,
    /// Work done (time steps or events), for cost accounting.
    pub work: u64,
}

/// Mergeable first-passage statistics, split by starting noise state.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct FptStats {
    /// Arrival times of particles started in +Sigma.
    pub plus: MeanAcc,
    /// Arrival times of particles started in -Sigma.
    pub minus: MeanAcc,
    /// Particles started in +Sigma that had not arrived by t_max.
    pub censored_plus: u64,
    /// Particles started in -Sigma that had not arrived by t_max.
    pub censored_minus: u64,
    /// Total work (sum of [`FptSample::work`]).
    pub work: u64,
}

impl FptStats {
    /// Add one particle.
    pub fn push(&mut self, start_plus: bool, s: FptSample) {
        self.work += s.work;
        match (start_plus, s.time) {
            (true, Some(t)) => self.plus.push(t),
            (false, Some(t)) => self.minus.push(t),
            (true, None) => self.censored_plus += 1,
            (false, None) => self.censored_minus += 1,
        }
    }
    /// Merge another shard.
    pub fn merge(&mut self, o: &FptStats) {
        self.plus.merge(&o.plus);
        self.minus.merge(&o.minus);
        self.censored_plus += o.censored_plus;
        self.censored_minus += o.censored_minus;
        self.work += o.work;
    }
    /// Particles in total.
    pub fn particles(&self) -> u64 {
        self.plus.n + self.minus.n + self.censored()
    }
    /// Particles that had not arrived by t_max.
    pub fn censored(&self) -> u64 {
        self.censored_plus + self.censored_minus
    }
    /// Means, standard errors and the censoring flag.
    pub fn summary(&self) -> FptSummary {
        let (tp, tm) = (self.plus.mean(), self.minus.mean());
        let (ep, em) = (self.plus.sem(), self.minus.sem());
        FptSummary {
            tau: 0.5 * (tp + tm),
            tau_err: 0.5 * (ep * ep + em * em).sqrt(),
            tau_plus: tp,
            tau_plus_err: ep,
            tau_minus: tm,
            tau_minus_err: em,
            particles: self.particles(),
            censored: self.censored(),
            mean_is_lower_bound: self.censored() > 0,
            work_per_particle: self.work as f64 / self.particles() as f64,
        }
    }
}

/// Simulation estimate of the MFPT.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct FptSummary {
    /// (tau_plus + tau_minus)/2: the MFPT for a uniformly random initial state.
    /// Means are over arrived particles (NaN if none of a half arrived).
    pub tau: f64,
    /// Its standard error.
    pub tau_err: f64,
    /// Mean arrival time of particles started in +Sigma.
    pub tau_plus: f64,
    /// Its standard error.
    pub tau_plus_err: f64,
    /// Mean arrival time of particles started in -Sigma.
    pub tau_minus: f64,
    /// Its standard error.
    pub tau_minus_err: f64,
    /// Particles simulated.
    pub particles: u64,
    /// Particles that had not arrived by t_max (excluded from the means).
    pub censored: u64,
    /// True if any particle was censored: the means are then means of the
    /// arrived particles only, i.e. lower bounds of the true MFPT.
    pub mean_is_lower_bound: bool,
    /// Mean work (steps or events) per particle.
    pub work_per_particle: f64,
}

/// Run `n` particles: particle `i` gets `rng::stream(seed, i)` and starts in
/// +Sigma for even `i`, -Sigma for odd `i`. Bit-identical for any thread count.
pub fn first_passage_stats<S>(n: u64, seed: u64, progress: &dyn Progress, sample: S) -> FptStats
where
    S: Fn(u64, &mut Rng, bool) -> FptSample + Sync,
{
    parallel::reduce(
        n,
        FptStats::default,
        |i, acc| {
            let mut rng = rng::stream(seed, i);
            let plus = i % 2 == 0;
            acc.push(plus, sample(i, &mut rng, plus));
        },
        |a, b| a.merge(&b),
        progress,
    )
}

/// Euler first-passage sampler (paper Eqs. 14-16), step order as in
/// [`crate::sim::euler`]: with probability r dt, v ← v_r (noise kept),
/// otherwise v ← v + dt (eta - g(v)) and arrival if v ≥ v_t (time = steps·dt,
/// an overshoot bias of at most dt); then eta flips with probability
/// q = ½(1 - e^{-2 lambda dt}).
/// Flip and reset steps are drawn as geometric waiting times — the same
/// Markov chain as a Bernoulli trial every step, with one random number per
/// event instead of two per step. Targets below v_0 run in the reflected frame.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct EulerFpt {
    problem: Problem,
    dt: f64,
    t_max: f64,
}

impl EulerFpt {
    /// Validate dt (Euler stability limit and r dt < 1) and t_max > 0.
    pub fn new(problem: Problem, dt: f64, t_max: f64) -> Result<Self> {
        let dt = problem.params().check_dt(dt)?;
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
        Ok(EulerFpt { problem, dt, t_max })
    }

    /// Time step.
    pub fn dt(&self) -> f64 {
        self.dt
    }

    /// One particle's first passage.
    pub fn sample(&self, rng: &mut Rng, start_plus: bool) -> FptSample {
        crate::with_drag!(self.problem.params().drag(), |d| self.run(
            rng,
            start_plus,
            |v| d.force(v)
        ))
    }

    #[inline(always)]
    fn run<G: Fn(f64) -> f64>(&self, rng: &mut Rng, start_plus: bool, g: G) -> FptSample {
        let (p, swapped) = self.problem.canonical();
        let par = &p.params();
        let dt = self.dt;
        let q = 0.5 * (-(-2.0 * par.lambda() * dt).exp_m1());
        let pr = par.rate() * dt;
        let (vt, vr) = (p.vt(), par.reset_velocity());
        let max_steps = (self.t_max / dt).floor() as u64;
        let mut s = if start_plus != swapped {
            par.sigma()
        } else {
            -par.sigma()
        };
        let mut v = p.v0();
        let mut next_flip = geometric(rng, q);
        let mut next_reset = geometric(rng, pr);
        let mut step = 0u64;
        while step < max_steps {
            step += 1;
            if step == next_reset {
                v = vr;
                next_reset = step + geometric(rng, pr);
            } else {
                v += dt * (s - g(v));
                if v >= vt {
                    return FptSample {
                        time: Some(step as f64 * dt),
                        work: step,
                    };
                }
            }
            if step == next_flip {
                s = -s;
                next_flip = step + geometric(rng, q);
            }
        }
        FptSample {
            time: None,
            work: step,
        }
    }

    /// Run `n` particles.
    pub fn stats(&self, n: u64, seed: u64, progress: &dyn Progress) -> FptStats {
        first_passage_stats(n, seed, progress, |_, rng, plus| self.sample(rng, plus))
    }
}

/// Steps until the first success of independent Bernoulli(p) trials (≥ 1);
/// u64::MAX when p = 0.
#[inline]
fn geometric(rng: &mut Rng, p: f64) -> u64 {
    if !(p > 0.0) {
        return u64::MAX;
    }
    if p >= 1.0 {
        return 1;
    }
    // U in (0, 1].
    let u = 1.0 - rng.gen::<f64>();
    let k = (u.ln() / (-p).ln_1p()).floor();
    if k >= 1e18 {
        u64::MAX / 2
    } else {
        1 + k as u64
    }
}

/// Convenience: Euler first-passage statistics for a problem.
pub fn euler_first_passage(
    problem: &Problem,
    dt: f64,
    t_max: f64,
    particles: u64,
    seed: u64,
    progress: &dyn Progress,
) -> Result<FptStats> {
    if particles < 2 {
        return Err(Error::invalid("particles", particles, "particles >= 2"));
    }
    Ok(EulerFpt::new(*problem, dt, t_max)?.stats(particles, seed, progress))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn geometric_mean() {
        let mut rng = rng::stream(3, 0);
        let p = 0.01;
        let mut acc = MeanAcc::new();
        for _ in 0..200_000 {
            acc.push(geometric(&mut rng, p) as f64);
        }
        // Mean 1/p = 100, sd ≈ 99.5.
        assert!(
            (acc.mean() - 100.0).abs() < 4.0 * acc.sem(),
            "{}",
            acc.mean()
        );
        assert_eq!(geometric(&mut rng, 0.0), u64::MAX);
    }
}
