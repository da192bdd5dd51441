//! The renewal clock's best mean waiting time for a search under full
//! resetting (docs/equations.md (S10)): tau as a function of the reset
//! frequency f = 1/m, m the mean waiting time of the clock's law rescaled
//! at fixed shape ([`Clock::with_mean`]), minimised by the one minimiser of
//! the optimal reset rate ([`minimize_rate`]: a log grid brackets the
//! minimum, golden section refines it, f = 0 (no resets) compared
//! directly). Each point is the renewal route ([`super::renewal`]); f = 0
//! is the reset-free search: infinite for a one-sided level, the 2-D
//! backward equation for an interval.
//!
//! With the exponential law f is the Poisson rate and the optimum is the
//! rate optimum of the same problem (by another route); with a fixed clock
//! it is the best reset period's inverse.

use super::backward::{self, BackwardOptions};
use super::renewal::{self, RenewalOptions, RenewalSolution, WaitingTime};
use super::{PositionTarget, SearchProblem};
use crate::error::{Error, Result};
use crate::mfpt::optimize::{minimize_rate, AtOptimum, AtZero, Optimum, RateObjective, RateRange};
use crate::model::reset::Clock;
use crate::parallel::Progress;
use serde::{Deserialize, Serialize};

/// The optimum of [`optimize_clock`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ClockOptimum {
    /// The minimiser's answer in the reset frequency f = 1/m (its r_opt is
    /// f*, 0 where resetting does not help; its grid is (f, tau)).
    pub optimum: Optimum,
    /// The optimal mean waiting time m* = 1/f* (+∞: no resets).
    pub mean: f64,
    /// The range m* may lie in, from the frequency range of the optimum.
    pub mean_range: (f64, f64),
    /// The clock at the optimum (None where resetting does not help).
    pub clock: Option<Clock>,
}

/// tau(f) of a search whose clock is rescaled to mean 1/f.
struct ClockTarget<'a> {
    base: &'a SearchProblem,
    clock: Clock,
    renewal: &'a RenewalOptions,
    /// For the reset-free interval search at f = 0.
    backward: BackwardOptions,
    /// tau(0) of the checked reset-free solve, set by `at_zero`.
    checked_zero: std::sync::OnceLock<f64>,
}

impl ClockTarget<'_> {
    fn solve(&self, f: f64) -> Result<RenewalSolution> {
        self.solve_with(f, self.renewal)
    }

    /// The renewal route at frequency f with `opts`.
    fn solve_with(&self, f: f64, opts: &RenewalOptions) -> Result<RenewalSolution> {
        let clock = self.clock.with_mean(1.0 / f)?;
        renewal::solve(self.base, &WaitingTime::Renewal { clock }, opts)
    }

    /// The search without resets (the clock removed, rate 0) with `opts`.
    fn reset_free(&self, opts: &BackwardOptions) -> Result<backward::SearchSolution> {
        let p = self.base.params();
        let mut schedule = p.schedule().clone();
        schedule.clock = None;
        let params = p.with_schedule(schedule)?;
        let problem =
            SearchProblem::new(params, self.base.x0(), self.base.v0(), self.base.target())?;
        backward::solve(&problem, opts)
    }
}

/// The route's error estimate, or its known parts where the mesh step has
/// none (unrefined; or, not asymptotic, the last mesh difference).
fn error_of(s: &RenewalSolution) -> f64 {
    if s.error_estimate.is_finite() {
        s.error_estimate
    } else if !s.asymptotic {
        s.mesh_error + s.time_error + s.tail_bound + s.truncation_error
    } else {
        s.time_error + s.tail_bound + s.truncation_error
    }
}

impl RateObjective for ClockTarget<'_> {
    /// Located without climbing the mesh ladder (as the Poisson rate's
    /// [`super::optimize::SearchTarget`]); the optimum is checked.
    fn tau(&self, f: f64) -> Result<(f64, f64)> {
        let locate = RenewalOptions {
            climb: false,
            ..*self.renewal
        };
        let s = self.solve_with(f, &locate)?;
        Ok((s.tau, error_of(&s)))
    }

    /// An interval: the reset-free search on the grid's meshes (the
    /// route's own reset-free survival), after its checked solve, whose
    /// value is kept in `checked_zero`.
    fn at_zero(&self) -> Result<AtZero> {
        let tau = match self.base.target() {
            PositionTarget::Level(_) => f64::INFINITY,
            PositionTarget::Interval(..) => {
                let _ = self.checked_zero.set(self.reset_free(&self.backward)?.tau);
                let locate = BackwardOptions {
                    climb: false,
                    ..self.backward
                };
                self.reset_free(&locate)?.tau
            }
        };
        Ok(AtZero {
            tau,
            slope: f64::NAN,
        })
    }

    fn at_optimum(&self, f: f64) -> Result<AtOptimum> {
        if f == 0.0 {
            let s = self.reset_free(&self.backward)?;
            return Ok(AtOptimum {
                tau_plus: s.tau_plus,
                tau_minus: s.tau_minus,
                tau_err: s.error_estimate,
            });
        }
        let s = self.solve(f)?;
        Ok(AtOptimum {
            tau_plus: s.tau_plus,
            tau_minus: s.tau_minus,
            tau_err: error_of(&s),
        })
    }
}

/// Minimise the search's mean time over the reset frequency f = 1/m of
/// the problem's renewal clock (shape fixed) in {0} ∪ [range.r_min,
/// range.r_max]. Errors: a problem without a renewal clock or without
/// full resetting (named), a law without a finite mean (`reset_clock`),
/// the range's and the renewal route's own refusals.
pub fn optimize_clock(
    problem: &SearchProblem,
    range: &RateRange,
    renewal: &RenewalOptions,
    progress: &dyn Progress,
) -> Result<ClockOptimum> {
    let clock = problem.params().schedule().clock.clone().ok_or_else(|| {
        Error::invalid(
            "reset_clock",
            "none",
            "a renewal clock (--reset-clock SPEC) to optimise",
        )
    })?;
    range.validate()?;
    clock.with_mean(1.0)?;
    let target = ClockTarget {
        base: problem,
        clock: clock.clone(),
        renewal,
        backward: BackwardOptions {
            refine: renewal.refine,
            max_work: renewal.max_work,
            max_memory: renewal.max_memory,
            ..BackwardOptions::with_cells(renewal.cells_x, renewal.cells_v)
        },
        checked_zero: std::sync::OnceLock::new(),
    };
    // The route's refusals (velocity-only resetting, an infinite-mean law)
    // before the grid.
    target.tau(range.r_max)?;
    let mut optimum = minimize_rate(&target, range, progress)?;
    // tau at the optimum from its checked solve (as the Poisson rate's).
    optimum.tau_opt = 0.5 * (optimum.tau_plus_opt + optimum.tau_minus_opt);
    if let Some(&t0) = target.checked_zero.get() {
        optimum.tau_r0 = t0;
    }
    let inv = |f: f64| if f > 0.0 { 1.0 / f } else { f64::INFINITY };
    let (lo, hi) = optimum.r_opt_range;
    let clock = if optimum.r_opt > 0.0 {
        Some(clock.with_mean(1.0 / optimum.r_opt)?)
    } else {
        None
    };
    Ok(ClockOptimum {
        mean: inv(optimum.r_opt),
        mean_range: (inv(hi), inv(lo)),
        clock,
        optimum,
    })
}
