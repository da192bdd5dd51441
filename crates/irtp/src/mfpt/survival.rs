//! Kaplan-Meier survival of first-passage times under administrative
//! censoring.
//!
//! Every particle starts at t = 0 and is censored at the same t_max, so the
//! Kaplan-Meier estimator is the empirical survival S(t) = 1 - (arrivals by
//! t)/N for t <= t_max, and its integral is the restricted mean
//! E[min(T, t_max)] (Eq. (24) with the integral cut at t_max: a lower bound
//! of tau). Arrival times are counted on a fixed grid of [0, t_max] (the
//! E24 series, 24 values per decade from 1e-6 to 1e12, below t_max, then
//! t_max itself), so the histogram merges by addition, bit for bit, for any
//! thread count or shard split, and S at each grid time is exact (not
//! binned): the fraction of particles whose passage time exceeds it.
//! The grid is logarithmic because t_max is a cap far beyond the typical
//! passage time (default 1e4): a uniform grid would put every arrival in
//! its first bin.

use serde::{Deserialize, Serialize};
use std::sync::OnceLock;

/// The E24 mantissas (times 10).
const E24: [u32; 24] = [
    10, 11, 12, 13, 15, 16, 18, 20, 22, 24, 27, 30, 33, 36, 39, 43, 47, 51, 56, 62, 68, 75, 82, 91,
];

/// The grid's decades: 10^FIRST_DECADE .. 10^LAST_DECADE.
const FIRST_DECADE: i32 = -6;
const LAST_DECADE: i32 = 12;

/// Every edge of the grid, increasing (each the double nearest its decimal
/// value, e.g. 1.1e-3, so the CSV shows round numbers).
fn all_edges() -> &'static [f64] {
    static EDGES: OnceLock<Vec<f64>> = OnceLock::new();
    EDGES.get_or_init(|| {
        let mut e = Vec::new();
        for d in FIRST_DECADE..LAST_DECADE {
            for m in E24 {
                // m * 10^(d-1): one correctly rounded operation on exact
                // integers (10^k is exact in f64 for k <= 22).
                let p = 10f64.powi((d - 1).abs());
                e.push(if d >= 1 { m as f64 * p } else { m as f64 / p });
            }
        }
        e.push(10f64.powi(LAST_DECADE));
        e
    })
}

/// The grid edges below `t_max` (the last bin ends at t_max, or at +∞ when
/// t_max is infinite).
pub fn edges(t_max: f64) -> &'static [f64] {
    let all = all_edges();
    &all[..all.partition_point(|&e| e < t_max)]
}

/// Arrival counts per bin of the grid of `t_max`, by stratum (starting
/// noise state): bin `j < edges.len()` holds the arrivals in
/// `(edges[j-1], edges[j]]` (bin 0 from t = 0), the last bin those in
/// `(edges[last], t_max]`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Arrivals {
    /// The counts of each stratum (for the paper's noise: +Sigma, -Sigma).
    pub counts: Vec<Vec<u64>>,
}

impl Arrivals {
    /// Empty counts of `strata` strata for the grid of `t_max`.
    pub fn new(t_max: f64, strata: usize) -> Self {
        let bins = edges(t_max).len() + 1;
        Arrivals {
            counts: vec![vec![0; bins]; strata],
        }
    }

    /// Count one arrival at time `t` (t <= t_max) of stratum `k` on the
    /// grid of `t_max`.
    pub fn push(&mut self, t_max: f64, k: usize, t: f64) {
        let j = edges(t_max).partition_point(|&e| e < t);
        self.counts[k][j] += 1;
    }

    /// The arrivals of every stratum in bin `j`.
    pub fn in_bin(&self, j: usize) -> u64 {
        self.counts.iter().map(|c| c[j]).sum()
    }

    /// Add another shard's counts (same grid and strata).
    pub fn merge(&mut self, o: &Arrivals) {
        let shape = |a: &Arrivals| (a.counts.len(), a.counts.first().map(Vec::len));
        assert_eq!(
            shape(self),
            shape(o),
            "merging first-passage histograms of different grids (t_max) or strata"
        );
        for (mine, theirs) in self.counts.iter_mut().zip(&o.counts) {
            for (a, b) in mine.iter_mut().zip(theirs) {
                *a += b;
            }
        }
    }
}

/// The Kaplan-Meier survival curve S(t) = Σ_k w_k S_k(t) of a start
/// state drawn with the strata's weights (the stratified estimate, like
/// tau; the paper's noise: (S+(t) + S-(t))/2), at t = 0 and the grid
/// times (t_max the last, when finite), with the binomial (Greenwood)
/// standard error sqrt(S_k(1 - S_k)/N_k) of each stratum combined.
/// Leading grid times where no particle has arrived are left out (one is
/// kept), and the curve stops at the first time S = 0.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SurvivalCurve {
    /// Times.
    pub t: Vec<f64>,
    /// S(t): the fraction of particles not arrived by t.
    pub survival: Vec<f64>,
    /// Its standard error.
    pub survival_err: Vec<f64>,
    /// Particles not arrived by t (still in flight; at t_max: the censored).
    pub at_risk: Vec<u64>,
}

impl SurvivalCurve {
    /// The curve of `arrivals` on the grid of `t_max`, with `n[k]`
    /// particles started in stratum k (arrived or not) of weight
    /// `weights[k]`.
    pub fn new(arrivals: &Arrivals, t_max: f64, n: &[u64], weights: &[f64]) -> Self {
        let mut times: Vec<f64> = edges(t_max).to_vec();
        if t_max.is_finite() {
            times.push(t_max);
        }
        let total: u64 = n.iter().sum();
        let mut curve = SurvivalCurve {
            t: vec![0.0],
            survival: vec![1.0],
            survival_err: vec![0.0],
            at_risk: vec![total],
        };
        let mut arrived = vec![0u64; n.len()];
        for (j, &t) in times.iter().enumerate() {
            for (c, counts) in arrived.iter_mut().zip(&arrivals.counts) {
                *c += counts[j];
            }
            let all: u64 = arrived.iter().sum();
            let (s, e) = stratified(n, &arrived, weights);
            let none_yet = all == 0;
            if none_yet && curve.t.len() > 1 {
                curve.pop();
            }
            curve.push((t, s, e, total - all));
            if all == total {
                break;
            }
        }
        curve
    }

    fn push(&mut self, (t, s, e, r): (f64, f64, f64, u64)) {
        self.t.push(t);
        self.survival.push(s);
        self.survival_err.push(e);
        self.at_risk.push(r);
    }

    fn pop(&mut self) {
        self.t.pop();
        self.survival.pop();
        self.survival_err.pop();
        self.at_risk.pop();
    }
}

/// S = Σ_k w_k S_k and its standard error sqrt(Σ_k w_k² S_k(1 - S_k)/N_k)
/// with `c[k]` of `n[k]` particles of stratum k arrived; for two equal
/// halves exactly (S_0 + S_1)/2 and sqrt(v_0 + v_1)/2.
fn stratified(n: &[u64], c: &[u64], w: &[f64]) -> (f64, f64) {
    let half = |k: usize| {
        let s = 1.0 - c[k] as f64 / n[k] as f64;
        (s, s * (1.0 - s) / n[k] as f64)
    };
    if w == super::estimator::HALVES {
        let ((sp, vp), (sm, vm)) = (half(0), half(1));
        return (0.5 * (sp + sm), 0.5 * (vp + vm).sqrt());
    }
    let (mut s, mut v) = (0.0, 0.0);
    for (k, &wk) in w.iter().enumerate() {
        let (sk, vk) = half(k);
        s += wk * sk;
        v += wk * wk * vk;
    }
    (s, v.sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mfpt::estimator::HALVES;

    #[test]
    fn grid_is_increasing_round_and_cut_at_t_max() {
        let all = all_edges();
        assert!(all.windows(2).all(|w| w[0] < w[1]));
        assert_eq!(all[0], 1e-6);
        assert_eq!(*all.last().unwrap(), 1e12);
        assert!(all.contains(&1.1e-3) && all.contains(&9.1e11) && all.contains(&1.0));
        assert_eq!(all.len(), 18 * 24 + 1);
        assert_eq!(*edges(1.0).last().unwrap(), 0.91);
        assert_eq!(edges(f64::INFINITY).len(), all.len());
    }

    #[test]
    fn arrivals_fall_in_the_bin_of_their_upper_edge() {
        let mut a = Arrivals::new(2.0, 2);
        for t in [0.0, 1e-9, 1.0, 1.0000001, 2.0] {
            a.push(2.0, 0, t);
        }
        let e = edges(2.0);
        let one = e.iter().position(|&x| x == 1.0).unwrap();
        assert_eq!(a.counts[0][0], 2);
        assert_eq!(a.counts[0][one], 1);
        assert_eq!(a.counts[0][one + 1], 1);
        assert_eq!(a.counts[0][e.len()], 1);
        assert_eq!(a.counts[0].iter().sum::<u64>(), 5);
        assert!(a.counts[1].iter().all(|&c| c == 0));
    }

    #[test]
    fn curve_starts_at_one_trims_and_stops_at_zero() {
        let mut a = Arrivals::new(10.0, 2);
        for (k, t) in [(0, 0.5), (1, 0.5), (0, 2.0), (1, 3.0)] {
            a.push(10.0, k, t);
        }
        let c = SurvivalCurve::new(&a, 10.0, &[2, 2], &HALVES);
        assert_eq!((c.t[0], c.survival[0], c.at_risk[0]), (0.0, 1.0, 4));
        // One leading time with no arrival kept (0.47), then 0.51 > 0.5.
        assert_eq!(&c.t[1..3], &[0.47, 0.51]);
        assert_eq!(c.survival[1], 1.0);
        assert_eq!((c.survival[2], c.at_risk[2]), (0.5, 2));
        assert_eq!(c.survival_err[2], 0.5 * (2.0 * 0.25 / 2.0f64).sqrt());
        assert_eq!(*c.t.last().unwrap(), 3.0);
        assert_eq!(
            (*c.survival.last().unwrap(), *c.at_risk.last().unwrap()),
            (0.0, 0)
        );
        // A censored particle: the curve ends at t_max with S > 0.
        let c = SurvivalCurve::new(&a, 10.0, &[3, 2], &HALVES);
        assert_eq!(*c.t.last().unwrap(), 10.0);
        assert_eq!(*c.at_risk.last().unwrap(), 1);
        assert_eq!(*c.survival.last().unwrap(), 0.5 * (1.0 - 2.0 / 3.0));
    }
}
