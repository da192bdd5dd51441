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
/// optimisation (exit 4, naming the mesh flags). Each grid rate is first
/// screened on half the cells ([`screening`]): a rate whose screened value
/// is above another's by more than twice both error estimates is not
/// solved in full ([`crate::mfpt::optimize::minimize_rate`]); the checked
/// solve at the optimum reuses the locating one where that was asymptotic
/// (the same solve). r = 0 is compared with
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
    /// The work counted by every solve made so far (screening, locating
    /// and checked: the sum of their [`SearchSolution::work`]).
    pub work: std::sync::Mutex<f64>,
    /// The locating solves by rate (its bits): the checked solve at the
    /// optimum is the same solve where the locating one was asymptotic
    /// (nothing to climb), and is taken from here.
    located: std::sync::Mutex<std::collections::BTreeMap<u64, SearchSolution>>,
}

impl<'a> SearchTarget<'a> {
    /// The objective of `base` under `backward`, nothing solved yet.
    pub fn new(base: &'a SearchProblem, backward: &'a BackwardOptions) -> Self {
        SearchTarget {
            base,
            backward,
            checked_zero: std::sync::OnceLock::new(),
            checked_opt: std::sync::OnceLock::new(),
            work: std::sync::Mutex::new(0.0),
            located: std::sync::Mutex::new(std::collections::BTreeMap::new()),
        }
    }

    fn screening(&self) -> Option<BackwardOptions> {
        screening(self.backward)
    }

    /// The backward solve at rate r under `opts`, its work added to `work`.
    fn solve(&self, r: f64, opts: &BackwardOptions) -> Result<SearchSolution> {
        let s = backward::solve(&self.base.with_rate(r)?, opts)?;
        *self.work.lock().unwrap_or_else(|e| e.into_inner()) += s.work;
        Ok(s)
    }

    /// The checked solve at rate r (the options' `climb` as given).
    fn verified(&self, r: f64) -> Result<SearchSolution> {
        self.solve(r, self.backward)
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
        let s = self.solve(r, &locate)?;
        self.located
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .insert(r.to_bits(), s.clone());
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

    /// The solve on half the cells each way (its ladder's meshes are the
    /// check, coarse and widened meshes of the full solve's, its error
    /// estimate conservative for its extrapolated value, 5-15× in the
    /// solver's tests): where asymptotic, its value and error estimate
    /// (the full solve's meshes, finer in the same sequence, have the
    /// smaller mesh difference); else None, as where it fails.
    fn screen(&self, r: f64) -> Option<(f64, f64)> {
        let s = self.solve(r, &self.screening()?).ok()?;
        s.asymptotic.then_some((s.tau, s.error_estimate))
    }

    /// [`LN_RATE_TOL`]: Brent's method locates r* to it.
    fn ln_rate_tolerance(&self) -> Option<f64> {
        Some(LN_RATE_TOL)
    }

    /// The checked solve at r: the locating solve there where it was
    /// asymptotic (the checked one would climb no further and repeat it
    /// to the bit), else solved with the options' `climb`.
    fn at_optimum(&self, r: f64) -> Result<AtOptimum> {
        let located = self
            .located
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .get(&r.to_bits())
            .filter(|s| s.asymptotic && self.backward.refine)
            .cloned();
        let s = match located {
            Some(s) => s,
            None => self.verified(r)?,
        };
        let _ = self.checked_opt.set(s.tau);
        Ok(AtOptimum {
            tau_plus: s.tau_plus,
            tau_minus: s.tau_minus,
            tau_err: s.error_estimate,
        })
    }
}

/// How closely the search's r* is located in ln r (Brent's method inside
/// the grid's bracket, [`minimize_rate`], stops with r* within twice this
/// of its r): tau(r) carries its mesh error (about 1 % at the command
/// line's defaults), which leaves r* uncertain over the reported
/// `r_opt_range`, at least a grid step each way (0.23 in ln r at the
/// defaults); at 2e-4 in ln r from the minimum, tau exceeds it by about
/// 2e-8 tau'' (tau'' = d²tau/d(ln r)²), far below that error.
pub const LN_RATE_TOL: f64 = 1e-4;

/// Refuse a search whose rate cannot be optimised: velocity-only resetting
/// with a one-sided level (tau infinite at every r), named by the flag
/// that makes it finite; then the backward solver's own refusals at the
/// rates of `range` (a periodic clock, a fixed refractory period).
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

/// [`optimize_rate`]'s answer and the work its solves counted.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SearchRateOptimum {
    /// The optimum.
    pub optimum: Optimum,
    /// Floating-point operations counted by every backward solve made
    /// (the grid's, the golden section's, the checked ones at r = 0 and at
    /// the optimum: the sum of their [`SearchSolution::work`]), to compare
    /// with [`estimate_work`].
    pub work: f64,
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
) -> Result<SearchRateOptimum> {
    check_optimizable(base, range)?;
    for r in [range.r_min, range.r_max] {
        backward::estimate(&base.with_rate(r)?, opts)?;
    }
    let f = SearchTarget::new(base, opts);
    let mut best = minimize_rate(&f, range, progress)?;
    best.tau_opt = match f.checked_opt.get() {
        Some(&t) if base.params().noise().is_some() => t,
        _ => 0.5 * (best.tau_plus_opt + best.tau_minus_opt),
    };
    if let Some(&t0) = f.checked_zero.get() {
        best.tau_r0 = t0;
    }
    let work = f.work.into_inner().unwrap_or_else(|e| e.into_inner());
    Ok(SearchRateOptimum {
        optimum: best,
        work,
    })
}

/// The options of the screening solves ([`RateObjective::screen`] of
/// [`SearchTarget`]): half the cells each way (the check mesh of the full
/// solve's ladder is the screen's coarse mesh), not climbing; None where
/// that mesh is below the solver's least (2 cells) or nothing is refined
/// (no error bound).
pub fn screening(opts: &BackwardOptions) -> Option<BackwardOptions> {
    let o = BackwardOptions {
        cells_x: opts.cells_x / 2,
        cells_v: opts.cells_v / 2,
        climb: false,
        ..*opts
    };
    (opts.refine && o.validate().is_ok()).then_some(o)
}

/// The estimated work of the screening solves, one at each grid rate
/// ([`backward::estimate`] under [`screening`]; 0 without screening).
pub fn screen_work(base: &SearchProblem, range: &RateRange, opts: &BackwardOptions) -> Result<f64> {
    let Some(o) = screening(opts) else {
        return Ok(0.0);
    };
    range
        .grid()
        .into_iter()
        .map(|r| Ok(backward::estimate(&base.with_rate(r)?, &o)?.work))
        .sum()
}

/// Solves of the golden-section refinement of r* ([`minimize_rate`]): the
/// bracket of two grid steps in ln r shrunk by 0.618 a step to `rtol`, two
/// to start.
pub fn golden_solves(range: &RateRange) -> f64 {
    let step = (range.r_max / range.r_min).ln() / (range.grid_points - 1) as f64;
    let width = (2.0 * step).max(range.r_min * step.exp());
    let shrink = 2.0 / (5f64.sqrt() - 1.0);
    ((width / range.rtol).ln() / shrink.ln()).ceil().max(0.0) + 2.0
}

/// The estimated work of a rate optimisation from one solve's at each grid
/// rate (`grid`, in any order) and at r = 0 (`at_zero`: 0 where r = 0 is
/// not solved): the grid's solves; the golden-section solves
/// ([`golden_solves`]) and the checked solve at the optimum, each at the
/// upper quartile of the grid's costs (r* is not known before the grid is
/// solved; the small rates, with the longest truncated domains, are the
/// dearest, and the levels' r* lay among them in the cost tests, where
/// the median put the total 1.6 to 3 times low); and `at_zero` twice (the checked solve at r = 0 and the one on
/// the grid's meshes). A climbing checked solve is priced as one solve: its
/// finer levels are checked against the budget as they are reached. Where
/// the optimum is at r = 0 or r_max the golden section is skipped and the
/// estimate is above the work done.
pub fn total_work(range: &RateRange, grid: &[f64], at_zero: f64) -> f64 {
    let mut works = grid.to_vec();
    works.sort_by(f64::total_cmp);
    let upper = works.get(3 * works.len() / 4).copied().unwrap_or(0.0);
    works.iter().sum::<f64>() + (golden_solves(range) + 1.0) * upper + 2.0 * at_zero
}

/// Solves of the refinement of the search's r* ([`minimize_rate`]:
/// Brent's method in ln r to [`LN_RATE_TOL`] from the bracket of two grid
/// steps, one to start): priced at the golden section's count to the
/// bracket Brent's stopping rule leaves (4 [`LN_RATE_TOL`] wide), its
/// bound where parabolic steps are not trusted; on a smooth minimum the
/// parabolic steps take it there in fewer.
pub fn locate_solves(range: &RateRange) -> f64 {
    let step = (range.r_max / range.r_min).ln() / (range.grid_points - 1) as f64;
    let shrink = 2.0 / (5f64.sqrt() - 1.0);
    ((2.0 * step / (4.0 * LN_RATE_TOL)).ln() / shrink.ln())
        .ceil()
        .max(0.0)
        + 1.0
}

/// The estimated work of a rate optimisation whose grid rates are
/// screened first ([`SearchTarget`]): `screens` (the screening solves',
/// [`screen_work`]); the solves locating r* ([`locate_solves`]) and the
/// checked solve at the optimum, each at the mean of the median and the
/// upper quartile of the grid's costs (r* is not known before the grid is
/// solved); the grid's full solves at half the sum of `grid`, each rate's
/// cost capped at that per-solve cost (the screen leaves out the rates far
/// from r*, where it can tell them apart, and none where its meshes are
/// not asymptotic; the dearest rates, the smallest with the longest
/// truncated domains, were far from r* at the defaults of `mfpt optimize
/// --xt 2`, whose grid sums to 4.2e10 operations and whose whole run
/// counted 8.1e9); `at_zero` twice (as [`total_work`]). Calibrated on the
/// cost tests (a 9-rate grid, r* among the dear rates, little screened)
/// and those defaults: within 3× of the work counted both ways.
pub fn screened_total_work(range: &RateRange, grid: &[f64], at_zero: f64, screens: f64) -> f64 {
    let mut works = grid.to_vec();
    works.sort_by(f64::total_cmp);
    let at = |q: usize| works.get(q * works.len() / 4).copied().unwrap_or(0.0);
    let per_solve = 0.5 * (at(2) + at(3));
    let full: f64 = works.iter().map(|w| w.min(per_solve)).sum();
    screens + 0.5 * full + (locate_solves(range) + 1.0) * per_solve + 2.0 * at_zero
}

/// The estimated work of [`optimize_rate`]: [`screened_total_work`] of
/// [`backward::estimate`] at each grid rate and, for an interval, at r = 0,
/// and of the screening solves ([`screen_work`]).
pub fn estimate_work(
    base: &SearchProblem,
    range: &RateRange,
    opts: &BackwardOptions,
) -> Result<f64> {
    range.validate()?;
    let locate = BackwardOptions {
        climb: false,
        ..*opts
    };
    let grid = range
        .grid()
        .into_iter()
        .map(|r| Ok(backward::estimate(&base.with_rate(r)?, &locate)?.work))
        .collect::<Result<Vec<f64>>>()?;
    let at_zero = match base.target() {
        PositionTarget::Interval(..) => backward::estimate(&base.with_rate(0.0)?, &locate)?.work,
        PositionTarget::Level(_) => 0.0,
    };
    let screens = screen_work(base, range, opts)?;
    Ok(screened_total_work(range, &grid, at_zero, screens))
}
