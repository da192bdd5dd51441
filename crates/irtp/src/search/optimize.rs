//! Scans of the mean search time against the reset rate, the start or the
//! level, and the reset rate r* minimising it, all from the 2-D backward
//! equation ([`super::backward`], with its error estimate).
//!
//! The minimiser is the velocity target's: [`crate::mfpt::optimize::minimize_rate`]
//! over the [`RateObjective`] [`SearchTarget`]. Where a rate is optimised:
//! - full resetting (a reset position x_r): tau(r) is finite for r > 0; with
//!   a one-sided level tau(0) is infinite (S(t) ~ t^(-1/2) without resets),
//!   so r* > 0 always, with an interval tau(0) is finite and r* = 0 is
//!   reported where resetting does not help;
//! - velocity-only resetting with an interval: finite for every r;
//! - velocity-only resetting with a one-sided level: tau is infinite for
//!   every r ([`SearchProblem::mean_is_finite`]); refused
//!   ([`check_optimizable`]), nothing to minimise.

use super::backward::{self, BackwardOptions, SearchSolution};
use super::{PositionTarget, SearchProblem};
use crate::error::{Error, Result};
use crate::mfpt::optimize::{minimize_rate, AtOptimum, AtZero, Optimum, RateObjective, RateRange};
use crate::parallel::{self, Progress};
use serde::{Deserialize, Serialize};

/// What a search scan varies.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum SearchAxis {
    /// The reset rate r.
    Rate,
    /// The start position x_0.
    X0,
    /// The level L of a one-sided target.
    Xt,
}

impl SearchAxis {
    /// The parameter's name, as a validation error names it.
    pub fn name(&self) -> &'static str {
        match self {
            SearchAxis::Rate => "rate",
            SearchAxis::X0 => "x0",
            SearchAxis::Xt => "xt",
        }
    }
}

/// One point of a search scan.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SearchScanPoint {
    /// The scanned value (r, x_0 or L).
    pub x: f64,
    /// The problem solved at this point.
    pub problem: SearchProblem,
    /// Its backward-equation solution.
    pub solution: SearchSolution,
}

/// The problem at one scan value (validated): another rate, start or
/// level (the level axis needs a one-sided base).
pub fn scan_problem(base: &SearchProblem, axis: SearchAxis, x: f64) -> Result<SearchProblem> {
    match (axis, base.target()) {
        (SearchAxis::Rate, _) => base.with_rate(x),
        (SearchAxis::X0, _) => base.with_start(x),
        (SearchAxis::Xt, PositionTarget::Level(_)) => base.with_target(PositionTarget::Level(x)),
        (SearchAxis::Xt, PositionTarget::Interval(a, b)) => Err(Error::invalid(
            "over",
            "xt",
            format!("rate or x0 with the interval ({a}, {b}): xt scans the level of --xt L"),
        )),
    }
}

/// tau against r, x_0 or L: every value is validated and checked by the
/// solver ([`backward::estimate`]: its refusals, e.g. an infinite mean, and
/// its budgets) before anything is solved, then solved in parallel. The
/// meshes are not refined beyond `opts` (no `climb`): a point whose mesh
/// sequence is not asymptotic is unresolved, reported with
/// `asymptotic` false and a NaN error, the rest of the scan kept.
pub fn scan(
    base: &SearchProblem,
    axis: SearchAxis,
    values: &[f64],
    opts: &BackwardOptions,
    progress: &dyn Progress,
) -> Result<Vec<SearchScanPoint>> {
    let problems: Vec<SearchProblem> = values
        .iter()
        .map(|&x| scan_problem(base, axis, x))
        .collect::<Result<_>>()?;
    for p in &problems {
        backward::estimate(p, opts)?;
    }
    let opts = &BackwardOptions {
        climb: false,
        ..*opts
    };
    let sols = parallel::map(
        problems.len() as u64,
        |i| backward::solve(&problems[i as usize], opts),
        progress,
    );
    problems
        .iter()
        .zip(values)
        .zip(sols)
        .map(|((problem, &x), s)| {
            Ok(SearchScanPoint {
                x,
                problem: problem.clone(),
                solution: s?,
            })
        })
        .collect()
}

/// The search's tau(r): the 2-D backward equation at each rate, the rest
/// of the problem kept (reset position and velocity, noise rule). The
/// rates that locate r* are solved on the meshes of `backward` without
/// climbing (one mesh sequence for every rate, so that tau(r) is one
/// smooth function to minimise); the reported values (r = 0, the
/// optimum) with the checked ladder (`climb`), whose refusal ends the
/// optimisation (exit 4, naming the mesh flags). r = 0 is compared with
/// the grid on the grid's meshes (the checked value differs from them by
/// the mesh error, which would otherwise decide r* = 0 against a tiny r).
pub struct SearchTarget<'a> {
    /// The problem (its own rate is replaced).
    pub base: &'a SearchProblem,
    /// Backward solver options.
    pub backward: &'a BackwardOptions,
    /// tau(0) of the checked solve, set by `at_zero` (an interval).
    pub checked_zero: std::sync::OnceLock<f64>,
    /// tau of the checked solve at the optimum, set by `at_optimum` (a
    /// noise model's tau = Σ_s π_s T_s: its tau± are NaN).
    pub checked_opt: std::sync::OnceLock<f64>,
}

impl SearchTarget<'_> {
    /// The checked solve at rate r (the options' `climb` as given).
    fn verified(&self, r: f64) -> Result<SearchSolution> {
        backward::solve(&self.base.with_rate(r)?, self.backward)
    }
}

impl RateObjective for SearchTarget<'_> {
    /// tau and its error estimate (mesh plus truncation; where the meshes
    /// are not asymptotic, the last mesh difference plus truncation).
    fn tau(&self, r: f64) -> Result<(f64, f64)> {
        let locate = BackwardOptions {
            climb: false,
            ..*self.backward
        };
        let s = backward::solve(&self.base.with_rate(r)?, &locate)?;
        let err = if s.asymptotic {
            s.error_estimate
        } else {
            s.mesh_error + s.truncation_error
        };
        Ok((s.tau, err))
    }

    /// A one-sided level without resets: tau = +∞; an interval: solved at
    /// r = 0 on the grid's meshes, after the checked solve there (its
    /// refusal ends the optimisation; its value is kept in
    /// `checked_zero`). The slope is not computed (NaN).
    fn at_zero(&self) -> Result<AtZero> {
        let tau = match self.base.target() {
            PositionTarget::Level(_) => f64::INFINITY,
            PositionTarget::Interval(..) => {
                let checked = self.verified(0.0)?.tau;
                let _ = self.checked_zero.set(checked);
                self.tau(0.0)?.0
            }
        };
        Ok(AtZero {
            tau,
            slope: f64::NAN,
        })
    }

    fn at_optimum(&self, r: f64) -> Result<AtOptimum> {
        let s = self.verified(r)?;
        let _ = self.checked_opt.set(s.tau);
        Ok(AtOptimum {
            tau_plus: s.tau_plus,
            tau_minus: s.tau_minus,
            tau_err: s.error_estimate,
        })
    }
}

/// Refuse a search whose rate cannot be optimised: velocity-only resetting
/// with a one-sided level (tau infinite at every r), named by the flag
/// that makes it finite; then the backward solver's own refusals at the
/// rates of `range` (a periodic clock, a refractory period).
pub fn check_optimizable(base: &SearchProblem, range: &RateRange) -> Result<()> {
    range.validate()?;
    let full = base.params().schedule().position.is_some();
    if let (PositionTarget::Level(l), false) = (base.target(), full) {
        return Err(Error::invalid(
            "reset_position",
            "none",
            format!(
                "a reset position (full resetting) to optimise the rate of a search for the \
                 level {l}: with velocity-only resetting x is unbounded and the mean search \
                 time is infinite at every r (S(t) ~ t^-1/2), so no rate minimises it; an \
                 interval target (--interval A,B) has a finite mean for every r"
            ),
        ));
    }
    Ok(())
}

/// The reset rate minimising the mean search time over
/// r ∈ {0} ∪ [r_min, r_max] ([`minimize_rate`] on [`SearchTarget`]),
/// refused where it is infinite for every r ([`check_optimizable`]). tau
/// at the optimum and at r = 0 are the checked solves' (at the optimum the
/// mean of tau±, with its error; with a noise model the solve's
/// Σ_s π_s T_s), not the values that located r*.
pub fn optimize_rate(
    base: &SearchProblem,
    range: &RateRange,
    opts: &BackwardOptions,
    progress: &dyn Progress,
) -> Result<Optimum> {
    check_optimizable(base, range)?;
    for r in [range.r_min, range.r_max] {
        backward::estimate(&base.with_rate(r)?, opts)?;
    }
    let f = SearchTarget {
        base,
        backward: opts,
        checked_zero: std::sync::OnceLock::new(),
        checked_opt: std::sync::OnceLock::new(),
    };
    let mut best = minimize_rate(&f, range, progress)?;
    best.tau_opt = match f.checked_opt.get() {
        Some(&t) if base.params().noise().is_some() => t,
        _ => 0.5 * (best.tau_plus_opt + best.tau_minus_opt),
    };
    if let Some(&t0) = f.checked_zero.get() {
        best.tau_r0 = t0;
    }
    Ok(best)
}
