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
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
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
                problem: *p,
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
        OptimizeOptions {
            r_min: 1e-3,
            r_max: 1e3,
            grid_points: 61,
            backward: BackwardOptions::default(),
        }
    }
}

/// Result of [`optimize_rate`].
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
    /// tau without resetting.
    pub tau_r0: f64,
    /// d tau / d r at r = 0 (negative: a little resetting helps).
    pub dtau_dr_r0: f64,
    /// True when the minimum is at some r > 0 with tau_opt < tau_r0.
    pub interior: bool,
    /// True when the minimum sits at the top of the search range r_max
    /// (widen the range: the true optimum may be larger).
    pub at_upper_bound: bool,
    /// The coarse grid (r, tau) the minimum was bracketed on.
    pub grid: Vec<(f64, f64)>,
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

/// The reset rate minimising tau(v_0) over r ∈ {0} ∪ [r_min, r_max]: a coarse
/// log grid brackets the minimum, golden-section search in log r refines it;
/// r = 0 is compared directly and through the sign of d tau/dr at r = 0,
/// which decides robustly whether resetting helps at all near r = 0.
pub fn optimize_rate(
    base: &Problem,
    opts: &OptimizeOptions,
    progress: &dyn Progress,
) -> Result<Optimum> {
    base.params().require(Solver::MfptOptimize)?;
    opts.validate()?;
    let (r_min, r_max) = (opts.r_min, opts.r_max);
    base.with_rate(r_max)?;
    let bo = &opts.backward;
    let (tau0, d0) = rate_derivative_at_zero(base, bo)?;
    // The r = 0 solve checked against its lower bound (a mesh too coarse fails).
    tau_at(base, 0.0, bo)?;
    let k = opts.grid_points;
    let (la, lb) = (r_min.ln(), r_max.ln());
    let rs: Vec<f64> = (0..k)
        .map(|i| (la + (lb - la) * i as f64 / (k - 1) as f64).exp())
        .collect();
    let taus = parallel::map(k as u64, |i| tau_at(base, rs[i as usize], bo), progress)
        .into_iter()
        .collect::<Result<Vec<f64>>>()?;
    let grid: Vec<(f64, f64)> = rs.iter().copied().zip(taus.iter().copied()).collect();
    let kmin = (0..k)
        .min_by(|&i, &j| taus[i].total_cmp(&taus[j]))
        .expect("non-empty grid");
    let mut at_upper_bound = false;
    let (r_opt, tau_opt) = if kmin == k - 1 {
        at_upper_bound = true;
        (rs[k - 1], taus[k - 1])
    } else if kmin == 0 {
        if d0 >= 0.0 && tau0 <= taus[0] {
            (0.0, tau0)
        } else {
            // Minimum in (0, r_1]: refine in linear r.
            golden(|r| tau_at(base, r, bo), 0.0, rs[1], 1e-9)?
        }
    } else {
        let (x, f) = golden(
            |lr| tau_at(base, lr.exp(), bo),
            rs[kmin - 1].ln(),
            rs[kmin + 1].ln(),
            1e-9,
        )?;
        (x.exp(), f)
    };
    let (r_opt, tau_opt) = if tau0 <= tau_opt {
        (0.0, tau0)
    } else {
        (r_opt, tau_opt)
    };
    let at = profile(&base.with_rate(r_opt)?, bo)?.at_start();
    Ok(Optimum {
        r_opt,
        tau_opt,
        tau_plus_opt: at.tau_plus,
        tau_minus_opt: at.tau_minus,
        tau_r0: tau0,
        dtau_dr_r0: d0,
        interior: r_opt > 0.0 && tau_opt < tau0,
        at_upper_bound: at_upper_bound && r_opt > 0.0,
        grid,
    })
}

impl OptimizeOptions {
    /// Check the search range: finite 0 < r_min < r_max and at least 3 grid
    /// points (the backward options are checked where they are used).
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
