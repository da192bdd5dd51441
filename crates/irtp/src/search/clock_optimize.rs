//! The renewal clock's best mean waiting time for a search under full
//! resetting: tau(m) of the renewal route ([`super::renewal`]) for the
//! clock law rescaled to mean m at fixed shape ([`Clock::with_mean`]),
//! minimised over ln m by golden-section search on a bracket [lo, hi].
//!
//! The minimum must be interior: tau at the best point is below tau at
//! both ends of the bracket (else refused, naming `mean`: the minimum
//! is at or beyond an edge, widen the bracket). The reported error of the
//! optimal mean combines the final bracket and the flatness of tau near
//! the minimum: where tau is within its error estimate of the minimum,
//! m cannot be told apart (from the parabola through the last three
//! points, δu = sqrt(2 δτ / τ''), u = ln m).

use super::renewal::{self, RenewalOptions, WaitingTime};
use super::SearchProblem;
use crate::error::{Error, Result};
use crate::model::reset::Clock;
use serde::{Deserialize, Serialize};

/// The optimum of [`optimize_mean`].
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct ClockOptimum {
    /// The clock at the optimal mean.
    pub clock: Clock,
    /// The optimal mean waiting time m*.
    pub mean: f64,
    /// Error estimate of m* (bracket and flatness, module docs).
    pub mean_error: f64,
    /// tau(m*) by the renewal route.
    pub tau: f64,
    /// The renewal route's error estimate of tau(m*).
    pub tau_error: f64,
    /// Renewal solves spent.
    pub evaluations: usize,
}

/// tau and its error estimate at mean `m`.
fn tau_at(
    problem: &SearchProblem,
    clock: &Clock,
    m: f64,
    opts: &RenewalOptions,
) -> Result<(f64, f64)> {
    let c = clock.with_mean(m)?;
    let s = renewal::solve(problem, &WaitingTime::Renewal { clock: c }, opts)?;
    let err = if s.error_estimate.is_finite() {
        s.error_estimate
    } else {
        s.time_error + s.tail_bound + s.truncation_error
    };
    Ok((s.tau, err))
}

/// Minimise the search's mean time over the mean waiting time of
/// `clock`'s shape in [lo, hi] (module docs) until the bracket in ln m is
/// below `rel_tol`. Errors: a bad bracket or tolerance (named), a law
/// without a finite mean (`reset_clock`), a minimum at an edge (`mean`),
/// and the renewal route's own refusals.
pub fn optimize_mean(
    problem: &SearchProblem,
    clock: &Clock,
    (lo, hi): (f64, f64),
    rel_tol: f64,
    opts: &RenewalOptions,
) -> Result<ClockOptimum> {
    if !(lo > 0.0 && hi > lo && hi.is_finite()) {
        return Err(Error::invalid(
            "mean",
            format!("[{lo}, {hi}]"),
            "a bracket 0 < lo < hi, finite",
        ));
    }
    if !(rel_tol > 1e-12 && rel_tol < 1.0) {
        return Err(Error::invalid("rel_tol", rel_tol, "1e-12 < rel_tol < 1"));
    }
    let f = |u: f64| tau_at(problem, clock, u.exp(), opts);
    let g = 0.5 * (5f64.sqrt() - 1.0);
    let (mut a, mut b) = (lo.ln(), hi.ln());
    let (fa, fb) = (f(a)?.0, f(b)?.0);
    let (mut c, mut d) = (b - g * (b - a), a + g * (b - a));
    let (mut fc, mut fd) = (f(c)?, f(d)?);
    let mut evaluations = 4;
    while b - a > rel_tol {
        if fc.0 < fd.0 {
            (b, d, fd) = (d, c, fc);
            c = b - g * (b - a);
            fc = f(c)?;
        } else {
            (a, c, fc) = (c, d, fd);
            d = a + g * (b - a);
            fd = f(d)?;
        }
        evaluations += 1;
    }
    let (u, (tau, tau_error)) = if fc.0 < fd.0 { (c, fc) } else { (d, fd) };
    if !(tau < fa && tau < fb) {
        let edge = if fa <= fb { lo } else { hi };
        return Err(Error::invalid(
            "mean",
            format!("[{lo}, {hi}]"),
            format!(
                "a bracket with an interior minimum of tau (tau is lowest at the edge m = \
                 {edge}: widen the bracket past it)"
            ),
        ));
    }
    // Curvature from the parabola through c, d and their midpoint.
    let (lo_u, hi_u) = (c.min(d), c.max(d));
    let mid = 0.5 * (lo_u + hi_u);
    let fm = f(mid)?.0;
    evaluations += 1;
    let h = 0.5 * (hi_u - lo_u);
    let (f_lo, f_hi) = if c < d { (fc.0, fd.0) } else { (fd.0, fc.0) };
    let curvature = (f_lo - 2.0 * fm + f_hi) / (h * h);
    let flat = if curvature > 0.0 {
        (2.0 * tau_error / curvature).sqrt()
    } else {
        f64::INFINITY
    };
    let du = (b - a).max(flat);
    let mean = u.exp();
    Ok(ClockOptimum {
        clock: clock.with_mean(mean)?,
        mean,
        mean_error: mean * du.exp_m1(),
        tau,
        tau_error,
        evaluations,
    })
}
