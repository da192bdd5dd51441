//! Scans of tau against v_t or r (paper Fig. 7) and the optimal resetting rate.

use super::backward::{
    at_start_or_overflow, profile, rate_derivative_at_zero, BackwardOptions, BackwardSolution,
};
use super::Problem;
use crate::error::{finite, Error, Result};
use crate::model::reset::Solver;
use crate::numerics::grid;
use crate::parallel::{self, Progress};
use serde::{Deserialize, Serialize};

/// What a scan varies.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ScanAxis {
    /// The target velocity v_t.
    Vt,
    /// The reset rate r.
    Rate,
}

/// One point of a scan.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ScanPoint {
    /// The scanned value (v_t or r).
    pub x: f64,
    /// The problem solved at this point.
    pub problem: Problem,
    /// Backward-equation solution.
    pub solution: BackwardSolution,
}

/// The problem at one scan value (validated).
pub fn scan_problem(base: &Problem, axis: ScanAxis, x: f64) -> Result<Problem> {
    match axis {
        ScanAxis::Vt => base.with_target(x),
        ScanAxis::Rate => base.with_rate(x),
    }
}

/// tau against v_t or r: every value is validated first (nothing is solved
/// if one is inadmissible), then solved in parallel (with error estimates).
/// Points where tau overflows f64 get tau = tau± = +∞.
pub fn scan(
    base: &Problem,
    axis: ScanAxis,
    values: &[f64],
    opts: &BackwardOptions,
    progress: &dyn Progress,
) -> Result<Vec<ScanPoint>> {
    let problems: Vec<Problem> = values
        .iter()
        .map(|&x| scan_problem(base, axis, x))
        .collect::<Result<_>>()?;
    let sols = parallel::map(
        problems.len() as u64,
        |i| super::backward::solve(&problems[i as usize], opts),
        progress,
    );
    problems
        .iter()
        .zip(values)
        .zip(sols)
        .map(|((p, &x), s)| {
            let solution = match s {
                Ok(s) => s,
                Err(Error::Overflow { .. }) => BackwardSolution {
                    tau: f64::INFINITY,
                    tau_plus: f64::INFINITY,
                    tau_minus: f64::INFINITY,
                    cells: opts.cells,
                    error_estimate: f64::NAN,
                },
                Err(e) => return Err(e),
            };
            Ok(ScanPoint {
                x,
                problem: p.clone(),
                solution,
            })
        })
        .collect()
}

/// Search range for [`optimize_rate`].
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct OptimizeOptions {
    /// Smallest positive r of the coarse log grid (r = 0 is always checked).
    pub r_min: f64,
    /// Largest r.
    pub r_max: f64,
    /// Points of the coarse log grid.
    pub grid_points: usize,
    /// Backward solver options.
    pub backward: BackwardOptions,
}

impl Default for OptimizeOptions {
    fn default() -> Self {
        let range = RateRange::default();
        OptimizeOptions {
            r_min: range.r_min,
            r_max: range.r_max,
            grid_points: range.grid_points,
            backward: BackwardOptions::default(),
        }
    }
}

/// The rates [`minimize_rate`] searches: r = 0 and a coarse log grid of
/// `grid_points` rates over [r_min, r_max].
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct RateRange {
    /// Smallest positive r of the coarse log grid.
    pub r_min: f64,
    /// Largest r.
    pub r_max: f64,
    /// Points of the coarse log grid.
    pub grid_points: usize,
    /// Relative tolerance of the golden-section refinement of r*
    /// (1e-9: far below any solver's error; a coarse solver may stop
    /// earlier, where its error estimate dominates anyway).
    pub rtol: f64,
}

impl Default for RateRange {
    fn default() -> Self {
        RateRange {
            r_min: 1e-3,
            r_max: 1e3,
            grid_points: 61,
            rtol: 1e-9,
        }
    }
}

/// Result of [`minimize_rate`] (and so of [`optimize_rate`] and the
/// search's `search::optimize::optimize_rate`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Optimum {
    /// Minimising reset rate (0 when resetting never helps).
    pub r_opt: f64,
    /// tau at r_opt.
    pub tau_opt: f64,
    /// tau+ at r_opt.
    pub tau_plus_opt: f64,
    /// tau- at r_opt.
    pub tau_minus_opt: f64,
    /// The solver's error estimate of tau at r_opt (NaN where it has none).
    pub tau_opt_err: f64,
    /// The rates r* may lie between given the error estimates: the grid
    /// rates next to r_opt where tau exceeds tau_opt by more than the two
    /// error estimates (0 below the grid where r = 0 cannot be told apart,
    /// +∞ above it). A bound, conservative: mesh errors are smooth in r and
    /// largely cancel between neighbouring rates.
    pub r_opt_range: (f64, f64),
    /// tau without resetting (+∞ where that mean is infinite).
    pub tau_r0: f64,
    /// d tau / d r at r = 0 (negative: a little resetting helps; NaN where
    /// the solver does not compute it).
    pub dtau_dr_r0: f64,
    /// True when the minimum is at some r > 0 with tau_opt < tau_r0.
    pub interior: bool,
    /// True when the minimum sits at the top of the search range r_max
    /// (widen the range: the true optimum may be larger).
    pub at_upper_bound: bool,
    /// The coarse grid (r, tau) the minimum was bracketed on (a rate the
    /// objective's screen ruled out carries the screen's value:
    /// [`RateObjective::screen`]).
    pub grid: Vec<(f64, f64)>,
}

/// tau at r = 0, as a [`RateObjective`] knows it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AtZero {
    /// tau without resetting (+∞ where that mean is infinite).
    pub tau: f64,
    /// d tau / d r at r = 0 (NaN where not computed).
    pub slope: f64,
}

/// tau± at the optimum and the error estimate of tau there.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AtOptimum {
    /// tau+.
    pub tau_plus: f64,
    /// tau-.
    pub tau_minus: f64,
    /// Error estimate of tau (NaN where the solver has none).
    pub tau_err: f64,
}

/// The mean first-passage time as a function of the reset rate, from a
/// deterministic solver: what [`minimize_rate`] minimises. The velocity
/// target ([`VelocityTarget`]) and the search
/// (`search::optimize::SearchTarget`) implement it.
pub trait RateObjective: Sync {
    /// tau at rate r > 0 and its error estimate (NaN where the solver
    /// gives none on the grid); tau = +∞ where it exceeds the f64 range.
    fn tau(&self, r: f64) -> Result<(f64, f64)>;
    /// tau at r = 0 and its slope there.
    fn at_zero(&self) -> Result<AtZero>;
    /// tau± and the error estimate of tau at rate r (r = 0 included).
    fn at_optimum(&self, r: f64) -> Result<AtOptimum>;
    /// A cheaper tau at rate r > 0 and an error bound that holds for it
    /// and for [`RateObjective::tau`] alike (the same solver on coarser
    /// meshes of the same sequence), used only to leave grid rates out of
    /// the full solves ([`minimize_rate`]); None (the default) where there
    /// is none: every grid rate is solved in full.
    fn screen(&self, _r: f64) -> Option<(f64, f64)> {
        None
    }
    /// How r* is located inside the grid's bracket of an interior minimum:
    /// None (the default), golden-section search in ln r to
    /// [`RateRange::rtol`]; Some(t), Brent's method in ln r (parabolic steps,
    /// golden-section ones where a parabola is not trusted) until r* is
    /// known to within 2 t in ln r.
    fn ln_rate_tolerance(&self) -> Option<f64> {
        None
    }
}

/// The velocity target's tau(r): the 1-D backward equations.
pub struct VelocityTarget<'a> {
    /// The problem (its own rate is replaced).
    pub base: &'a Problem,
    /// Backward solver options.
    pub backward: &'a BackwardOptions,
}

impl RateObjective for VelocityTarget<'_> {
    /// tau at the start from the profile (no error estimate on the grid).
    fn tau(&self, r: f64) -> Result<(f64, f64)> {
        Ok((tau_at(self.base, r, self.backward)?, f64::NAN))
    }

    /// tau(0) and d tau/dr(0) from one solve of Eqs. (26)-(28) and its
    /// adjoint, the r = 0 profile checked against its lower bound.
    fn at_zero(&self) -> Result<AtZero> {
        let (tau, slope) = rate_derivative_at_zero(self.base, self.backward)?;
        // The r = 0 solve checked against its lower bound (a mesh too coarse fails).
        tau_at(self.base, 0.0, self.backward)?;
        Ok(AtZero { tau, slope })
    }

    /// tau± from the profile, the error from the Richardson solve.
    fn at_optimum(&self, r: f64) -> Result<AtOptimum> {
        let p = self.base.with_rate(r)?;
        let at = profile(&p, self.backward)?.at_start();
        let tau_err =
            super::backward::solve(&p, self.backward).map_or(f64::NAN, |s| s.error_estimate);
        Ok(AtOptimum {
            tau_plus: at.tau_plus,
            tau_minus: at.tau_minus,
            tau_err,
        })
    }
}

/// tau at rate r; +∞ where it overflows f64 (never the minimum).
fn tau_at(base: &Problem, r: f64, opts: &BackwardOptions) -> Result<f64> {
    Ok(at_start_or_overflow(&base.with_rate(r)?, opts)?.map_or(f64::INFINITY, |s| s.tau))
}

/// Golden-section minimisation of f on [a, b] until the bracket is below
/// `tol` (1 + |c|); returns (x, f(x)). Each step shrinks the bracket by
/// 0.618, so 200 steps reach any tolerance above 1e-40 of the initial width;
/// a bracket that stops shrinking (a tolerance below the rounding of the end
/// points) is reported as [`Error::NotConverged`].
fn golden<F: FnMut(f64) -> Result<f64>>(
    mut f: F,
    mut a: f64,
    mut b: f64,
    tol: f64,
) -> Result<(f64, f64)> {
    const STEPS: usize = 200;
    let g = 0.5 * (5f64.sqrt() - 1.0);
    let mut c = b - g * (b - a);
    let mut d = a + g * (b - a);
    let (mut fc, mut fd) = (f(c)?, f(d)?);
    let mut steps = 0;
    while (b - a).abs() > tol * (1.0 + c.abs()) {
        crate::parallel::check_stop()?;
        if steps == STEPS {
            return Err(Error::NotConverged {
                method: "golden-section search for the optimal reset rate",
                iterations: STEPS,
                residual: (b - a).abs(),
                tolerance: tol * (1.0 + c.abs()),
            });
        }
        steps += 1;
        if fc <= fd {
            b = d;
            d = c;
            fd = fc;
            c = b - g * (b - a);
            fc = f(c)?;
        } else {
            a = c;
            c = d;
            fc = fd;
            d = a + g * (b - a);
            fd = f(d)?;
        }
    }
    Ok(if fc <= fd { (c, fc) } else { (d, fd) })
}

/// Brent's minimisation of f on [a, b] (parabolic steps through the three
/// best points, golden-section steps where a parabola is not trusted; no
/// two evaluations closer than `tol`), stopping when the best point x is
/// within 2 `tol` of the minimum's bracket on both sides (the bracket at
/// most 4 `tol` wide); returns (x, f(x)). A bracket not closed in
/// [`BRENT_STEPS`] steps is [`Error::NotConverged`].
fn brent<F: FnMut(f64) -> Result<f64>>(
    mut f: F,
    mut a: f64,
    mut b: f64,
    tol: f64,
) -> Result<(f64, f64)> {
    const CGOLD: f64 = 0.381_966_011_250_105_1;
    let (mut x, mut d, mut e) = (a + CGOLD * (b - a), 0.0f64, 0.0f64);
    let (mut w, mut v) = (x, x);
    let mut fx = f(x)?;
    let (mut fw, mut fv) = (fx, fx);
    for _ in 0..BRENT_STEPS {
        crate::parallel::check_stop()?;
        let xm = 0.5 * (a + b);
        if (x - xm).abs() <= 2.0 * tol - 0.5 * (b - a) {
            return Ok((x, fx));
        }
        let golden_step = |x: f64| if x >= xm { a - x } else { b - x };
        if e.abs() > tol {
            let r = (x - w) * (fx - fv);
            let q = (x - v) * (fx - fw);
            let mut p = (x - v) * q - (x - w) * r;
            let mut q = 2.0 * (q - r);
            if q > 0.0 {
                p = -p;
            }
            q = q.abs();
            let last = e;
            e = d;
            if p.abs() >= (0.5 * q * last).abs() || p <= q * (a - x) || p >= q * (b - x) {
                e = golden_step(x);
                d = CGOLD * e;
            } else {
                d = p / q;
                let u = x + d;
                if u - a < 2.0 * tol || b - u < 2.0 * tol {
                    d = tol.copysign(xm - x);
                }
            }
        } else {
            e = golden_step(x);
            d = CGOLD * e;
        }
        let u = if d.abs() >= tol {
            x + d
        } else {
            x + tol.copysign(d)
        };
        let fu = f(u)?;
        if fu <= fx {
            if u >= x {
                a = x;
            } else {
                b = x;
            }
            (v, fv, w, fw, x, fx) = (w, fw, x, fx, u, fu);
        } else {
            if u < x {
                a = u;
            } else {
                b = u;
            }
            if fu <= fw || w == x {
                (v, fv, w, fw) = (w, fw, u, fu);
            } else if fu <= fv || v == x || v == w {
                (v, fv) = (u, fu);
            }
        }
    }
    Err(Error::NotConverged {
        method: "Brent's search for the optimal reset rate",
        iterations: BRENT_STEPS,
        residual: (b - a).abs(),
        tolerance: 4.0 * tol,
    })
}

/// Steps of [`brent`] before it gives up: its golden-section steps alone
/// shrink the bracket by 0.618 at least every other step, so 200 steps
/// close any bracket 10^20 times its tolerance.
const BRENT_STEPS: usize = 200;

/// The reset rate minimising tau(v_0) of the velocity target over
/// r ∈ {0} ∪ [r_min, r_max] ([`minimize_rate`] on [`VelocityTarget`]).
pub fn optimize_rate(
    base: &Problem,
    opts: &OptimizeOptions,
    progress: &dyn Progress,
) -> Result<Optimum> {
    base.params().require(Solver::MfptOptimize)?;
    opts.validate()?;
    base.with_rate(opts.r_max)?;
    let f = VelocityTarget {
        base,
        backward: &opts.backward,
    };
    minimize_rate(&f, &opts.range(), progress)
}

/// The reset rate minimising `f` over r ∈ {0} ∪ [r_min, r_max]: a coarse
/// log grid brackets the minimum, golden-section search in log r refines it
/// (to `range.rtol`; Brent's method to the objective's tolerance where it
/// gives one: [`RateObjective::ln_rate_tolerance`]); r = 0 is compared directly and, where the objective
/// gives it, through the sign of d tau/dr at r = 0, which decides robustly
/// whether resetting helps at all near r = 0. A minimum at r = 0 is reported
/// as r_opt = 0 (resetting does not help), one at r_max as `at_upper_bound`.
pub fn minimize_rate(
    f: &dyn RateObjective,
    range: &RateRange,
    progress: &dyn Progress,
) -> Result<Optimum> {
    range.validate()?;
    let zero = f.at_zero()?;
    let rs = range.grid();
    let k = rs.len();
    let evals = grid_evals(f, &rs, progress)?;
    let taus: Vec<f64> = evals.iter().map(|e| e.0).collect();
    let kmin = (0..k)
        .min_by(|&i, &j| taus[i].total_cmp(&taus[j]))
        .expect("non-empty grid");
    let at_upper_bound = kmin == k - 1;
    // The golden section's solves continue the grid's progress, out of at
    // most 2 + ln(width / rtol) / ln(1/0.618) (the bracket of the branch
    // taken below).
    let width = if kmin == 0 {
        rs[1]
    } else {
        (rs[(kmin + 1).min(k - 1)] / rs[kmin - 1]).ln()
    };
    let tol = f.ln_rate_tolerance().unwrap_or(range.rtol);
    let golden_max = 2 + ((width / tol).ln() / 1.618_f64.ln()).ceil().max(0.0) as u64;
    let total = k as u64 + golden_max;
    let calls = std::sync::atomic::AtomicU64::new(k as u64);
    let tau = |r: f64| {
        let n = calls.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
        progress.update(n.min(total), total);
        f.tau(r).map(|e| e.0)
    };
    let (r_opt, tau_opt) = if at_upper_bound {
        (rs[k - 1], taus[k - 1])
    } else if kmin == 0 {
        // A little resetting does not help where d tau/dr(0) >= 0 (or is
        // not known) and tau(0) is the lowest.
        if !(zero.slope < 0.0) && zero.tau <= taus[0] {
            (0.0, zero.tau)
        } else {
            // Minimum in (0, r_1]: refine in linear r.
            golden(tau, 0.0, rs[1], range.rtol)?
        }
    } else {
        let lr = |x: f64| tau(x.exp());
        let (a, b) = (rs[kmin - 1].ln(), rs[kmin + 1].ln());
        let (x, v) = match f.ln_rate_tolerance() {
            Some(tol) => brent(lr, a, b, tol)?,
            None => golden(lr, a, b, range.rtol)?,
        };
        (x.exp(), v)
    };
    let (r_opt, tau_opt) = if zero.tau <= tau_opt {
        (0.0, zero.tau)
    } else {
        (r_opt, tau_opt)
    };
    let at = f.at_optimum(r_opt)?;
    Ok(Optimum {
        r_opt,
        tau_opt,
        tau_plus_opt: at.tau_plus,
        tau_minus_opt: at.tau_minus,
        tau_opt_err: at.tau_err,
        r_opt_range: bracket(&rs, &evals, (r_opt, tau_opt, at.tau_err)),
        tau_r0: zero.tau,
        dtau_dr_r0: zero.slope,
        interior: r_opt > 0.0 && tau_opt < zero.tau,
        at_upper_bound: at_upper_bound && r_opt > 0.0,
        grid: rs.into_iter().zip(taus).collect(),
    })
}

/// tau and its error at each grid rate `rs`: first the objective's screen
/// ([`RateObjective::screen`]) at every rate, then [`RateObjective::tau`]
/// at the rates the screen cannot rule out, in parallel, in grid order.
/// With the screens' values t_i and bounds e_i (each bounding the full
/// solve's error too), a rate j is left out where t_j - 2 e_j exceeds
/// t_b + 2 e_b for some screened rate b: its full value is then above
/// b's, so it is not the grid's minimum and cannot move the bracket; it
/// keeps its screen's value and bound (the wider error: [`bracket`] stays
/// conservative). A rate whose screen failed or has no finite bound is
/// solved in full.
fn grid_evals(
    f: &dyn RateObjective,
    rs: &[f64],
    progress: &dyn Progress,
) -> Result<Vec<(f64, f64)>> {
    let k = rs.len() as u64;
    let screened: Vec<Option<(f64, f64)>> =
        parallel::map(k, |i| Ok(f.screen(rs[i as usize])), &parallel::NoProgress)
            .into_iter()
            .map(|s| {
                s.ok()
                    .flatten()
                    .filter(|(t, e)| t.is_finite() && e.is_finite())
            })
            .collect();
    let best = screened
        .iter()
        .flatten()
        .map(|(t, e)| t + 2.0 * e)
        .fold(f64::INFINITY, f64::min);
    let full: Vec<usize> = (0..rs.len())
        .filter(|&i| screened[i].map_or(true, |(t, e)| t - 2.0 * e <= best))
        .collect();
    let solved = parallel::map(full.len() as u64, |i| f.tau(rs[full[i as usize]]), progress)
        .into_iter()
        .collect::<Result<Vec<(f64, f64)>>>()?;
    let mut evals: Vec<(f64, f64)> = screened
        .iter()
        .map(|s| s.unwrap_or((f64::NAN, f64::NAN)))
        .collect();
    for (&i, e) in full.iter().zip(solved) {
        evals[i] = e;
    }
    Ok(evals)
}

/// The rates r* may lie between ([`Optimum::r_opt_range`]): walking out
/// from r_opt along the grid, the first rate on each side whose tau exceeds
/// tau_opt by more than the sum of the error estimates (a grid point
/// without one takes the optimum's); 0 off the bottom of the grid, +∞ off
/// the top. Without an error estimate at the optimum: (NaN, NaN).
fn bracket(rs: &[f64], evals: &[(f64, f64)], (r, tau, err): (f64, f64, f64)) -> (f64, f64) {
    if !err.is_finite() {
        return (f64::NAN, f64::NAN);
    }
    let apart = |&i: &usize| {
        let (t, e) = evals[i];
        t - tau > err + if e.is_finite() { e } else { err }
    };
    let hi = rs
        .iter()
        .position(|&x| x > r)
        .and_then(|u| (u..rs.len()).find(apart))
        .map_or(f64::INFINITY, |i| rs[i]);
    let lo = rs
        .iter()
        .rposition(|&x| x < r)
        .and_then(|d| (0..=d).rev().find(apart))
        .map_or(0.0, |i| rs[i]);
    (lo, hi)
}

impl OptimizeOptions {
    /// The rates searched.
    pub fn range(&self) -> RateRange {
        RateRange {
            r_min: self.r_min,
            r_max: self.r_max,
            grid_points: self.grid_points,
            rtol: RateRange::default().rtol,
        }
    }

    /// Check the search range (see [`RateRange::validate`]; the backward
    /// options are checked where they are used).
    pub fn validate(&self) -> Result<()> {
        self.range().validate()
    }
}

impl RateRange {
    /// The coarse log grid: `grid_points` rates from r_min to r_max.
    pub fn grid(&self) -> Vec<f64> {
        let k = self.grid_points;
        let (la, lb) = (self.r_min.ln(), self.r_max.ln());
        (0..k)
            .map(|i| (la + (lb - la) * i as f64 / (k - 1) as f64).exp())
            .collect()
    }

    /// Check the search range: finite 0 < r_min < r_max and at least 3 grid
    /// points.
    pub fn validate(&self) -> Result<()> {
        let r_min = finite("r_min", self.r_min)?;
        let r_max = finite("r_max", self.r_max)?;
        if !(r_min > 0.0) {
            return Err(Error::invalid("r_min", r_min, "r_min > 0"));
        }
        if !(r_max > r_min) {
            return Err(Error::invalid(
                "r_max",
                r_max,
                format!("r_max > r_min = {r_min}"),
            ));
        }
        if !(self.rtol > 0.0 && self.rtol < 1.0) {
            return Err(Error::invalid("rtol", self.rtol, "0 < rtol < 1"));
        }
        if self.grid_points < 3 {
            return Err(Error::invalid(
                "grid_points",
                self.grid_points,
                "at least 3",
            ));
        }
        Ok(())
    }
}

/// The values of a [`scan`]: `points` (>= 2) values from `from` to `to`, both
/// exact, equally spaced, or log-spaced with `log` (then from, to > 0).
pub fn scan_values(from: f64, to: f64, points: usize, log: bool) -> Result<Vec<f64>> {
    let from = finite("from", from)?;
    let to = finite("to", to)?;
    if points < 2 {
        return Err(Error::invalid("points", points, "points >= 2"));
    }
    if log && !(from > 0.0 && to > 0.0) {
        return Err(Error::invalid(
            "from",
            from,
            "from > 0 and to > 0 with --log",
        ));
    }
    Ok(if log {
        grid::logspace(from, to, points)
    } else {
        grid::linspace(from, to, points)
    })
}

#[cfg(test)]
mod range_tests {
    use super::*;

    fn name(e: Error) -> &'static str {
        match e {
            Error::InvalidParameter { name, .. } => name,
            e => panic!("{e}"),
        }
    }

    #[test]
    fn scan_values_grids_and_checks() {
        assert_eq!(
            scan_values(0.1, 0.5, 5, false).unwrap(),
            [0.1, 0.2, 0.3, 0.4, 0.5]
        );
        assert_eq!(scan_values(0.5, -0.5, 3, false).unwrap(), [0.5, 0.0, -0.5]);
        assert_eq!(
            scan_values(0.01, 100.0, 5, true).unwrap(),
            [0.01, 0.1, 1.0, 10.0, 100.0]
        );
        let bad = |f, t, n, l| name(scan_values(f, t, n, l).unwrap_err());
        assert_eq!(bad(f64::NAN, 1.0, 3, false), "from");
        assert_eq!(bad(0.0, f64::INFINITY, 3, false), "to");
        assert_eq!(bad(0.0, 1.0, 1, false), "points");
        assert_eq!(bad(0.0, 1.0, 3, true), "from");
        assert_eq!(bad(1.0, -1.0, 3, true), "from");
    }

    #[test]
    fn optimize_options_validate() {
        assert!(OptimizeOptions::default().validate().is_ok());
        let with = |r_min, r_max, grid_points| OptimizeOptions {
            r_min,
            r_max,
            grid_points,
            ..OptimizeOptions::default()
        };
        let bad = |o: OptimizeOptions| name(o.validate().unwrap_err());
        assert_eq!(bad(with(f64::NAN, 1.0, 5)), "r_min");
        assert_eq!(bad(with(0.0, 1.0, 5)), "r_min");
        assert_eq!(bad(with(1.0, f64::INFINITY, 5)), "r_max");
        assert_eq!(bad(with(1.0, 1.0, 5)), "r_max");
        assert_eq!(bad(with(0.1, 1.0, 2)), "grid_points");
    }
}

#[cfg(test)]
mod minimize_tests {
    use super::*;
    use crate::parallel::NoProgress;

    /// tau(r) in closed form, with a fixed error estimate.
    struct Closed<F: Fn(f64) -> f64 + Sync> {
        tau: F,
        err: f64,
    }

    impl<F: Fn(f64) -> f64 + Sync> RateObjective for Closed<F> {
        fn tau(&self, r: f64) -> Result<(f64, f64)> {
            Ok(((self.tau)(r), self.err))
        }
        fn at_zero(&self) -> Result<AtZero> {
            Ok(AtZero {
                tau: (self.tau)(0.0),
                slope: f64::NAN,
            })
        }
        fn at_optimum(&self, r: f64) -> Result<AtOptimum> {
            let t = (self.tau)(r);
            Ok(AtOptimum {
                tau_plus: t,
                tau_minus: t,
                tau_err: self.err,
            })
        }
    }

    fn range() -> RateRange {
        RateRange {
            r_min: 1e-2,
            r_max: 1e2,
            grid_points: 21,
            rtol: 1e-9,
        }
    }

    /// An interior minimum (tau = 2 + (ln r/2)², r* = 2, infinite at r = 0)
    /// is found to the golden tolerance and bracketed by the error range.
    #[test]
    fn interior_minimum() {
        let f = Closed {
            tau: |r: f64| 2.0 + (r / 2.0).ln().powi(2),
            err: 0.01,
        };
        let o = minimize_rate(&f, &range(), &NoProgress).unwrap();
        assert!((o.r_opt - 2.0).abs() < 1e-6, "{o:?}");
        assert!(o.interior && !o.at_upper_bound);
        assert_eq!(o.tau_r0, f64::INFINITY);
        // tau - 2 > 0.02 where |ln(r/2)| > 0.141: the first grid rates
        // beyond (grid step ln 10 / 5 = 0.46) on each side.
        let (lo, hi) = o.r_opt_range;
        assert!(lo < 2.0 && lo > 2.0 * (-0.141f64 - 0.47).exp(), "{lo}");
        assert!(hi > 2.0 && hi < 2.0 * (0.141f64 + 0.47).exp(), "{hi}");
    }

    /// Brent's method on a skewed minimum (ln r* = ln 2) closes its
    /// bracket around it to its tolerance, in fewer evaluations than the
    /// golden section needs to the same width.
    #[test]
    fn brent_locates_a_minimum_in_few_evaluations() {
        let at = 2f64.ln();
        let tau = |x: f64| 2.0 + (x - at).powi(2) + 0.4 * (x - at).powi(3);
        let (a, b) = (at - 0.3, at + 0.16);
        for tol in [1e-3, 1e-4, 1e-6] {
            let mut brent_calls = 0;
            let (x, v) = brent(
                |x| {
                    brent_calls += 1;
                    Ok(tau(x))
                },
                a,
                b,
                tol,
            )
            .unwrap();
            assert!((x - at).abs() <= 2.0 * tol && v == tau(x), "{x} {tol}");
            let mut golden_calls = 0;
            golden(
                |x| {
                    golden_calls += 1;
                    Ok(tau(x))
                },
                a,
                b,
                4.0 * tol / (1.0 + at),
            )
            .unwrap();
            println!("tol {tol}: brent {brent_calls}, golden {golden_calls} evaluations");
            assert!(brent_calls < golden_calls, "{brent_calls} {golden_calls}");
        }
    }

    /// tau increasing in r: r* = 0 ("resetting does not help"); tau
    /// decreasing: the top of the range, flagged.
    #[test]
    fn minimum_at_the_ends() {
        let up = Closed {
            tau: |r: f64| 1.0 + r,
            err: 1e-3,
        };
        let o = minimize_rate(&up, &range(), &NoProgress).unwrap();
        assert_eq!((o.r_opt, o.tau_opt, o.interior), (0.0, 1.0, false));
        assert_eq!(o.r_opt_range.0, 0.0);
        assert!(o.r_opt_range.1 > 1e-3 && o.r_opt_range.1 < 1e-1);
        let down = Closed {
            tau: |r: f64| 1.0 + 1.0 / (1.0 + r),
            err: 0.0,
        };
        let o = minimize_rate(&down, &range(), &NoProgress).unwrap();
        assert!(o.at_upper_bound && (o.r_opt - 100.0).abs() < 1e-9, "{o:?}");
        assert_eq!(o.r_opt_range.1, f64::INFINITY);
    }
}
