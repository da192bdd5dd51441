//! The power-law tail of a survival curve: S(t) ~ t^(-theta), fitted where
//! the mean search time is infinite (velocity-only resetting and a
//! one-sided level: theta = 1/2 when the stationary mean velocity is zero).

use crate::mfpt::estimator::FptStats;
use crate::mfpt::survival::edges;
use serde::{Deserialize, Serialize};

/// Survivors each starting state must still have at a time for the curve
/// to count as resolved there (relative error of S± about 1/sqrt(50) = 14 %).
pub const MIN_SURVIVORS: u64 = 50;

/// Decades of time below the last resolved time that the fit spans.
pub const FIT_DECADES: f64 = 2.0;

/// Fewest grid times a fit uses (fewer: no fit).
pub const MIN_POINTS: usize = 5;

/// A fitted power-law tail S(t) ≈ A t^(-theta) ([`fit_tail`]).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct TailFit {
    /// The exponent theta (minus the slope of ln S against ln t).
    pub theta: f64,
    /// Its standard error (binomial covariance of the Kaplan-Meier points).
    pub theta_err: f64,
    /// The fitted window [t_from, t_to].
    pub t_from: f64,
    /// Its end: the last time where the curve is resolved.
    pub t_to: f64,
    /// The number of grid times fitted.
    pub points: usize,
}

/// Fit the tail exponent of the Kaplan-Meier survival of `stats`.
///
/// What it fits, exactly: the ordinary least-squares slope b of
/// y = ln S(t) against u = ln t over the survival grid's times t
/// (24 per decade, [`crate::mfpt::survival`], and t_max) in the window
/// [t_to / 10^FIT_DECADES, t_to], where t_to is the last grid time at which
/// both starting states still have at least [`MIN_SURVIVORS`] particles in
/// flight; S = (S+ + S-)/2 is the stratified estimate; theta = -b. Its
/// standard error is sqrt(c^T C c) with the OLS weights
/// c_i = (u_i - ū) / Σ (u_k - ū)² and C the covariance of the ln S_i from
/// the binomial (administrative-censoring Kaplan-Meier) covariance
/// Cov(S±_i, S±_j) = S±_j (1 - S±_i) / N± for t_i <= t_j, combined over the
/// two halves and carried to ln S by the delta method (the points of one
/// curve are strongly correlated: treating them as independent would
/// understate the error). `None` with fewer than [`MIN_POINTS`] times in
/// the window.
pub fn fit_tail(stats: &FptStats) -> Option<TailFit> {
    let (np, nm) = (stats.particles_in(0), stats.particles_in(1));
    let mut times: Vec<f64> = edges(stats.t_max).to_vec();
    if stats.t_max.is_finite() {
        times.push(stats.t_max);
    }
    // Survival of each half at every grid time.
    let (mut cp, mut cm) = (0u64, 0u64);
    let mut rows = Vec::with_capacity(times.len());
    for (j, &t) in times.iter().enumerate() {
        cp += stats.arrivals.counts[0][j];
        cm += stats.arrivals.counts[1][j];
        rows.push((t, np - cp, nm - cm));
    }
    let last = rows
        .iter()
        .rposition(|&(_, sp, sm)| sp >= MIN_SURVIVORS && sm >= MIN_SURVIVORS)?;
    let t_to = rows[last].0;
    let t_from = t_to / 10f64.powf(FIT_DECADES);
    let window: Vec<(f64, f64, f64)> = rows[..=last]
        .iter()
        .filter(|r| r.0 >= t_from)
        .map(|&(t, sp, sm)| (t, sp as f64 / np as f64, sm as f64 / nm as f64))
        .collect();
    if window.len() < MIN_POINTS {
        return None;
    }
    let (theta, theta_err) = ols_slope(&window, np as f64, nm as f64);
    Some(TailFit {
        theta,
        theta_err,
        t_from: window[0].0,
        t_to,
        points: window.len(),
    })
}

/// (theta, standard error) from rows (t, S+, S-) with N+ = `np`,
/// N- = `nm` (see [`fit_tail`]).
fn ols_slope(rows: &[(f64, f64, f64)], np: f64, nm: f64) -> (f64, f64) {
    let u: Vec<f64> = rows.iter().map(|r| r.0.ln()).collect();
    let s: Vec<f64> = rows.iter().map(|r| 0.5 * (r.1 + r.2)).collect();
    let y: Vec<f64> = s.iter().map(|v| v.ln()).collect();
    let n = u.len() as f64;
    let (ub, yb) = (u.iter().sum::<f64>() / n, y.iter().sum::<f64>() / n);
    let sxx: f64 = u.iter().map(|v| (v - ub) * (v - ub)).sum();
    let sxy: f64 = u.iter().zip(&y).map(|(a, b)| (a - ub) * (b - yb)).sum();
    let c: Vec<f64> = u.iter().map(|v| (v - ub) / sxx).collect();
    let mut var = 0.0;
    for i in 0..rows.len() {
        for j in 0..rows.len() {
            // Times increase with the index: the earlier one is min(i, j).
            let (e, l) = (&rows[i.min(j)], &rows[i.max(j)]);
            let cov = 0.25 * (l.1 * (1.0 - e.1) / np + l.2 * (1.0 - e.2) / nm);
            var += c[i] * c[j] * cov / (s[i] * s[j]);
        }
    }
    (-sxy / sxx, var.max(0.0).sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mfpt::estimator::FptSample;

    /// Exact power-law quantiles: M = N/2 particles per starting state with
    /// S(t) = t^(-1/2) for t >= 1 (arrival k at (M / (M - k))^2) fit
    /// theta = 1/2.
    #[test]
    fn recovers_the_exponent_of_a_deterministic_power_law() {
        let n = 20_000u64;
        let t_max = 1e6;
        let mut st = FptStats::new(t_max);
        for i in 0..n {
            let m = n / 2;
            let t = (m as f64 / (m - i / 2) as f64).powi(2);
            let time = (t <= t_max).then_some(t);
            st.push((i % 2) as usize, FptSample { time, work: 1 });
        }
        let fit = fit_tail(&st).unwrap();
        assert!((fit.theta - 0.5).abs() < 0.01, "{fit:?}");
        assert!(fit.theta_err > 0.0 && fit.theta_err < 0.05, "{fit:?}");
        assert!(fit.points >= MIN_POINTS && fit.t_to <= t_max);
    }
}
