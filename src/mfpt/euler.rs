//! Euler first passage: the paper's Euler scheme (Eqs. (30)-(32)) run until the
//! velocity reaches the target, one particle at a time, with flip and reset
//! steps drawn as geometric waiting times. The step and the gaps are those
//! of the particle simulation ([`euler_step`] with the law's fast g,
//! [`geometric_gap`]). Estimates are gathered by
//! [`super::estimator::first_passage_stats`]; the entry point is
//! [`super::solve`] with [`super::Method::Euler`].

use super::estimator::{first_passage_stats, FptSample, FptStats};
use super::Problem;
use crate::error::{finite, Error, Result};
use crate::model::Drag;
use crate::model::Reset;
use crate::parallel::Progress;
use crate::rng::Rng;
use crate::sim::euler::{euler_step, geometric_gap};
use serde::{Deserialize, Serialize};

/// Euler first-passage sampler (paper Eqs. (30)-(32)), step order as in
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
        crate::with_drag!(self.problem.params().drag(), |d| self
            .run(d, rng, start_plus))
    }

    #[inline(always)]
    fn run<D: Drag>(&self, drag: &D, rng: &mut Rng, start_plus: bool) -> FptSample {
        let (p, swapped) = self.problem.canonical();
        let par = &p.params();
        let dt = self.dt;
        // ln(1 - q) and ln(1 - r dt): the geometric gaps of flips and resets.
        let ln_flip = (-(0.5 * (-(-2.0 * par.lambda() * dt).exp_m1()))).ln_1p();
        let ln_reset = (-(par.rate() * dt)).ln_1p();
        let (vt, reset) = (p.vt(), par.reset());
        let max_steps = (self.t_max / dt).floor() as u64;
        let mut s = if start_plus != swapped {
            par.sigma()
        } else {
            -par.sigma()
        };
        let mut v = p.v0();
        let mut next_flip = geometric_gap(rng, ln_flip);
        let mut next_reset = geometric_gap(rng, ln_reset);
        let mut step = 0u64;
        while step < max_steps {
            step += 1;
            if step == next_reset {
                v = reset.draw_velocity(rng);
                let plus = reset.draw_noise(s > 0.0, rng);
                s = if plus { par.sigma() } else { -par.sigma() };
                next_reset = step.saturating_add(geometric_gap(rng, ln_reset));
            } else {
                v = euler_step(drag, v, s, dt);
                if v >= vt {
                    return FptSample {
                        time: Some(step as f64 * dt),
                        work: step,
                    };
                }
            }
            if step == next_flip {
                s = -s;
                next_flip = step.saturating_add(geometric_gap(rng, ln_flip));
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::{DragLaw, Params};
    use crate::rng;

    /// Without flips and resets the passage is the deterministic chain of
    /// the shared [`euler_step`]: same step count, for every law.
    #[test]
    fn steps_are_the_shared_euler_step() {
        for (d, sigma) in [
            (DragLaw::Tan, 3.0),
            (DragLaw::Tanh, 0.6),
            (DragLaw::Linear, 1.0),
        ] {
            let p = Params::new(d, sigma, 1e-300, 0.0, 0.0).unwrap();
            let (v0, vt, dt) = (-0.2, 0.5 * p.v_upper(), 1e-3);
            let pr = Problem::new(p, v0, vt).unwrap();
            let (mut v, mut n) = (v0, 0u64);
            while v < vt {
                v = euler_step(&d, v, sigma, dt);
                n += 1;
            }
            let fpt = EulerFpt::new(pr, dt, 1e3).unwrap();
            let s = fpt.sample(&mut rng::stream(1, 0), true);
            assert_eq!(s.work, n, "{d}");
            assert_eq!(s.time, Some(n as f64 * dt), "{d}");
        }
    }
}
