//! The one entry point: [`solve`] a [`Problem`] by a [`Method`] (backward
//! equations, exact particles or Euler particles) into an [`MfptResult`].
//! To add a method: a [`Method`] variant and its arms in [`Method::check`]
//! and [`solve`].

use super::backward::{self, BackwardOptions, BackwardSolution};
use super::estimator::{merge_units, FptStats, FptSummary};
use super::euler::EulerFpt;
use super::{exact, Problem};
use crate::error::{Error, Result};
use crate::model::reset::Solver;
use crate::parallel::Progress;
use serde::{Deserialize, Serialize};
use std::ops::Range;

/// A particle estimate: how many particles, the time cap, the seed.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ParticleOptions {
    /// Particles (even indices start in +Sigma, odd in -Sigma); at least 2.
    pub particles: u64,
    /// Particles not arrived by `t_max` are counted as censored: tau is
    /// then not estimated, the restricted mean E[min(T, t_max)] bounds it
    /// from below ([`super::FptSummary`]).
    pub t_max: f64,
    /// Seed: particle i uses the random stream (seed, i).
    pub seed: u64,
}

/// How the mean first-passage time is computed.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "method", rename_all = "lowercase")]
pub enum Method {
    /// The backward equations solved directly (second order, with a
    /// Richardson error estimate; see [`super::backward`]).
    Backward(BackwardOptions),
    /// Exact event-driven particles: no time step, no overshoot
    /// (see [`super::exact`]); t_max may be +∞.
    Exact(ParticleOptions),
    /// The paper's Euler scheme (Eqs. (30)-(32)) with time step `dt`: O(dt)
    /// bias, including an overshoot of at most dt (see [`super::euler`]).
    Euler {
        /// Time step.
        dt: f64,
        /// Particles, time cap and seed.
        #[serde(flatten)]
        run: ParticleOptions,
    },
}

impl Method {
    /// Short name (`backward`, `exact`, `euler`).
    pub fn name(&self) -> &'static str {
        match self {
            Method::Backward(_) => "backward",
            Method::Exact(_) => "exact",
            Method::Euler { .. } => "euler",
        }
    }

    /// The particle options of a particle method (`None` for the backward
    /// equations).
    pub fn particles(&self) -> Option<&ParticleOptions> {
        match self {
            Method::Backward(_) => None,
            Method::Exact(run) | Method::Euler { run, .. } => Some(run),
        }
    }

    /// Validate the method for `problem` before anything runs: the backward
    /// mesh; for particles `particles >= 4` (two per starting state), then the method's own limits
    /// (Euler: step and time cap; exact: time cap, and with a noise model
    /// its protocol and levels).
    pub fn check(&self, problem: &Problem) -> Result<()> {
        if let Some(run) = self.particles() {
            // Two per starting state (±Sigma), for a standard error.
            if run.particles < 4 {
                return Err(Error::invalid("particles", run.particles, "particles >= 4"));
            }
        }
        match *self {
            Method::Backward(opts) => opts.validate(),
            Method::Exact(run) => {
                exact::check_t_max(run.t_max)?;
                exact::check_problem(problem)
            }
            Method::Euler { dt, run } => EulerFpt::new(problem.clone(), dt, run.t_max).map(|_| ()),
        }
    }
}

/// The mean first-passage time of a problem by one method.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "method", content = "result", rename_all = "lowercase")]
pub enum MfptResult {
    /// From the backward equations.
    Backward(BackwardSolution),
    /// From particles (exact or Euler): mergeable statistics.
    Particles(FptStats),
}

impl MfptResult {
    /// tau = (tau+ + tau-)/2: the MFPT for a uniformly random initial state
    /// (NaN for particles when any is censored; see [`FptSummary`]).
    pub fn tau(&self) -> f64 {
        match self {
            MfptResult::Backward(s) => s.tau,
            MfptResult::Particles(s) => s.summary().tau,
        }
    }
    /// The MFPT starting in +Sigma.
    pub fn tau_plus(&self) -> f64 {
        match self {
            MfptResult::Backward(s) => s.tau_plus,
            MfptResult::Particles(s) => s.summary().tau_plus,
        }
    }
    /// The MFPT starting in -Sigma.
    pub fn tau_minus(&self) -> f64 {
        match self {
            MfptResult::Backward(s) => s.tau_minus,
            MfptResult::Particles(s) => s.summary().tau_minus,
        }
    }
    /// The backward solution (`None` for particles).
    pub fn backward(&self) -> Option<&BackwardSolution> {
        match self {
            MfptResult::Backward(s) => Some(s),
            MfptResult::Particles(_) => None,
        }
    }
    /// The particle statistics (`None` for the backward equations).
    pub fn stats(&self) -> Option<&FptStats> {
        match self {
            MfptResult::Backward(_) => None,
            MfptResult::Particles(s) => Some(s),
        }
    }
    /// Means, standard errors and censoring of a particle estimate.
    pub fn summary(&self) -> Option<FptSummary> {
        self.stats().map(FptStats::summary)
    }
}

/// The mean first-passage time of `problem` by `method`, validated first
/// ([`Method::check`]). Particle estimates are bit-identical for any thread
/// count; `progress` counts particles (the backward solve reports none).
/// Errors with [`Error::Overflow`] where the backward tau overflows f64.
pub fn solve(problem: &Problem, method: &Method, progress: &dyn Progress) -> Result<MfptResult> {
    problem.params().require(match method {
        Method::Backward(_) => Solver::Backward,
        Method::Exact(_) => Solver::MfptExact,
        Method::Euler { .. } => Solver::MfptEuler,
    })?;
    method.check(problem)?;
    match (method, method.unit_count()) {
        (Method::Backward(opts), _) => Ok(MfptResult::Backward(backward::solve(problem, opts)?)),
        (_, Some(all)) => assemble(
            problem,
            method,
            &particle_units(problem, method, 0..all, progress)?,
        ),
        (_, None) => unreachable!("a particle method has units"),
    }
}

impl Method {
    /// The units of particles ([`crate::parallel::UNIT`] each) of a
    /// particle method's run: the grain of cutting it into parts
    /// ([`particle_units`]); None for the backward equations.
    pub fn unit_count(&self) -> Option<u64> {
        self.particles()
            .map(|r| crate::parallel::unit_count(r.particles))
    }
}

/// The unit totals of units `units` of a particle method's run (validated
/// first): computed anywhere, [`assemble`]d from all units (in unit
/// order, however split) they give [`solve`]'s result bit for bit.
pub fn particle_units(
    problem: &Problem,
    method: &Method,
    units: Range<u64>,
    progress: &dyn Progress,
) -> Result<Vec<FptStats>> {
    problem.params().require(match method {
        Method::Backward(_) => Solver::Backward,
        Method::Exact(_) => Solver::MfptExact,
        Method::Euler { .. } => Solver::MfptEuler,
    })?;
    method.check(problem)?;
    check_units(method.unit_count(), &units)?;
    Ok(match *method {
        Method::Backward(_) => unreachable!("checked: a particle method"),
        Method::Exact(run) => {
            exact::units(problem, run.t_max, run.particles, run.seed, units, progress)
        }
        Method::Euler { dt, run } => EulerFpt::new(problem.clone(), dt, run.t_max)?.units(
            run.particles,
            units,
            run.seed,
            progress,
        ),
    })
}

/// Refuse a unit range outside `0..count` (or a method without units).
pub(crate) fn check_units(count: Option<u64>, units: &Range<u64>) -> Result<()> {
    match count {
        Some(n) if units.start <= units.end && units.end <= n => Ok(()),
        Some(n) => Err(Error::invalid(
            "units",
            format!("{units:?}"),
            format!("a range inside 0..{n} (the run's units of particles)"),
        )),
        None => Err(Error::invalid(
            "method",
            "backward",
            "a particle method (only particles are cut into units)",
        )),
    }
}

/// The result of a particle method's run from the totals of all its units
/// ([`particle_units`], in unit order), verified.
pub fn assemble(problem: &Problem, method: &Method, units: &[FptStats]) -> Result<MfptResult> {
    let (Some(run), Some(all)) = (method.particles(), method.unit_count()) else {
        return Err(check_units(None, &(0..0)).expect_err("no units"));
    };
    if units.len() as u64 != all {
        return Err(Error::invalid(
            "units",
            units.len(),
            format!("all {all} units of the run, in order"),
        ));
    }
    let stats = merge_units(run.t_max, units);
    verify_particles(problem, &stats.summary())?;
    Ok(MfptResult::Particles(stats))
}

/// The largest speed |dv/dt| on (v_l, v_u): 2 Sigma for the paper's
/// noise, a_max - a_min for another noise without thermal noise (g(v) lies
/// between the extreme levels there), unbounded with thermal noise.
fn max_speed(p: &crate::model::Params) -> f64 {
    match p.noise() {
        None => 2.0 * p.sigma(),
        Some(m) if m.temperature() > 0.0 => f64::INFINITY,
        Some(m) => {
            let levels = m.levels();
            let hi = levels.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            let lo = levels.iter().copied().fold(f64::INFINITY, f64::min);
            hi - lo
        }
    }
}

/// Every passage takes at least the shortest distance to the target (from
/// v0, or from v_r after a reset) over the largest speed |dv/dt| <= 2 Sigma
/// on (v_l, v_u): the restricted means of both starting states must respect
/// it, or the sampler lost precision (tan at Sigma ~ 1e250) and the answer
/// is refused.
fn verify_particles(problem: &Problem, s: &super::FptSummary) -> Result<()> {
    let p = problem.params();
    let mut distance = (problem.vt() - problem.v0()).abs();
    if p.rate() > 0.0 {
        distance = distance.min((problem.vt() - p.reset_velocity()).abs());
    }
    let bound = distance / max_speed(p) * (1.0 - 1e-12);
    for (name, m) in [("rmst_plus", s.rmst_plus), ("rmst_minus", s.rmst_minus)] {
        if !(m >= bound) {
            return Err(crate::Error::Numerical {
                method: "first-passage sampler",
                reason: format!(
                    "{name} = {m:e} is below the least passage time {bound:e} (distance / \
                     (2 Sigma)): the sampler lost precision for these parameters; refused"
                ),
            });
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::{DragLaw, Params};
    use crate::parallel::NoProgress;

    fn problem() -> Problem {
        let p = Params::new(DragLaw::Tanh, 0.6, 0.5, 0.2, 0.0).unwrap();
        Problem::new(p, -0.249, 0.1).unwrap()
    }

    fn run(particles: u64, t_max: f64) -> ParticleOptions {
        ParticleOptions {
            particles,
            t_max,
            seed: 7,
        }
    }

    fn name(e: Error) -> &'static str {
        match e {
            Error::InvalidParameter { name, .. } => name,
            e => panic!("{e}"),
        }
    }

    #[test]
    fn check_particles_first_then_method() {
        let pr = problem();
        let euler = |dt, run| Method::Euler { dt, run };
        assert!(euler(1e-3, run(10, 1e4)).check(&pr).is_ok());
        assert!(Method::Exact(run(10, f64::INFINITY)).check(&pr).is_ok());
        let bad = Method::Exact(run(1, -1.0)).check(&pr).unwrap_err();
        assert_eq!(name(bad), "particles");
        let bad = Method::Exact(run(10, 0.0)).check(&pr).unwrap_err();
        assert_eq!(name(bad), "t_max");
        let bad = euler(-1.0, run(10, 1e4)).check(&pr).unwrap_err();
        assert_eq!(name(bad), "dt");
        let bad = Method::Backward(BackwardOptions::with_cells(2));
        assert_eq!(name(bad.check(&pr).unwrap_err()), "cells");
    }

    #[test]
    fn solve_dispatches_to_the_samplers() {
        let pr = problem();
        let a = solve(&pr, &Method::Exact(run(20, 1e4)), &NoProgress).unwrap();
        let b = merge_units(1e4, &exact::units(&pr, 1e4, 20, 7, 0..1, &NoProgress));
        assert_eq!(a.stats(), Some(&b));
        let e = Method::Euler {
            dt: 1e-2,
            run: run(20, 1e4),
        };
        let a = solve(&pr, &e, &NoProgress).unwrap();
        let b = EulerFpt::new(pr.clone(), 1e-2, 1e4)
            .unwrap()
            .stats(20, 7, &NoProgress);
        assert_eq!(a.stats(), Some(&b));
        assert_eq!(a.tau(), b.summary().tau);
        let opts = BackwardOptions::with_cells(400);
        let a = solve(&pr, &Method::Backward(opts), &NoProgress).unwrap();
        assert_eq!(a.backward(), Some(&backward::solve(&pr, &opts).unwrap()));
    }

    #[test]
    fn method_round_trips_through_json() {
        for m in [
            Method::Backward(BackwardOptions::default()),
            Method::Exact(run(10, 5.0)),
            Method::Euler {
                dt: 1e-3,
                run: run(10, 5.0),
            },
        ] {
            let j = serde_json::to_string(&m).unwrap();
            assert_eq!(serde_json::from_str::<Method>(&j).unwrap(), m, "{j}");
        }
    }
}
