//! Euler first passage: the paper's Euler scheme (Eqs. 14-16) run until the
//! velocity reaches the target, one particle at a time, with flip and reset
//! steps drawn as geometric waiting times. Estimates are gathered by
//! [`super::estimator::first_passage_stats`]; the entry point is
//! [`super::solve`] with [`super::Method::Euler`].

use super::estimator::{first_passage_stats, FptSample, FptStats};
use super::Problem;
use crate::error::{finite, Error, Result};
use crate::model::Drag;
use crate::parallel::Progress;
use crate::rng::Rng;
use rand::Rng as _;
use serde::{Deserialize, Serialize};

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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng;
    use crate::stats::MeanAcc;

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
