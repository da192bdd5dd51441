//! First-passage estimators shared by every particle method.
//!
//! [`first_passage_stats`] is method-agnostic: it hands particle `i` its own
//! stream `rng::stream(seed, i)` and its starting noise state (even `i`: +Sigma,
//! odd `i`: -Sigma — stratified, so tau = (tau+ + tau-)/2 is estimated with
//! exactly balanced halves), calls the per-particle sampler and reduces the
//! results deterministically into mergeable sums and counts ([`FptStats`],
//! with the arrival-time histogram of [`super::survival`]), summarised as
//! [`FptSummary`]: the mean passage times when every particle arrived by
//! t_max, otherwise the restricted mean E[min(T, t_max)], a lower bound. A particle method is any
//! `Fn(index, &mut Rng, start_plus) -> FptSample`
//! ([`super::euler`], [`super::exact`]).

use super::survival::{Arrivals, SurvivalCurve};
use crate::parallel::{self, Progress};
use crate::rng::{self, Rng};
use crate::stats::MeanAcc;
use serde::{Deserialize, Serialize};
use std::ops::Range;

/// One particle's first passage.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct FptSample {
    /// First-passage time; `None` if the target was not reached by t_max.
    pub time: Option<f64>,
    /// Work done (time steps or events), for cost accounting.
    pub work: u64,
}

/// Mergeable first-passage statistics, split by starting noise state:
/// sums and counts only (merged by addition), so a run gives the same bits
/// for any thread count and shard split.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FptStats {
    /// The censoring time: every particle not arrived by t_max is censored.
    pub t_max: f64,
    /// Arrival times of particles started in +Sigma.
    pub plus: MeanAcc,
    /// Arrival times of particles started in -Sigma.
    pub minus: MeanAcc,
    /// Particles started in +Sigma that had not arrived by t_max.
    pub censored_plus: u64,
    /// Particles started in -Sigma that had not arrived by t_max.
    pub censored_minus: u64,
    /// Arrival-time histogram on the fixed grid of t_max (the survival curve).
    pub arrivals: Arrivals,
    /// Total work (sum of [`FptSample::work`]).
    pub work: u64,
}

impl FptStats {
    /// No particle yet, censoring at `t_max`.
    pub fn new(t_max: f64) -> Self {
        FptStats {
            t_max,
            plus: MeanAcc::new(),
            minus: MeanAcc::new(),
            censored_plus: 0,
            censored_minus: 0,
            arrivals: Arrivals::new(t_max),
            work: 0,
        }
    }
    /// Add one particle.
    pub fn push(&mut self, start_plus: bool, s: FptSample) {
        self.work += s.work;
        if let Some(t) = s.time {
            self.arrivals.push(self.t_max, start_plus, t);
        }
        match (start_plus, s.time) {
            (true, Some(t)) => self.plus.push(t),
            (false, Some(t)) => self.minus.push(t),
            (true, None) => self.censored_plus += 1,
            (false, None) => self.censored_minus += 1,
        }
    }
    /// Merge another shard (same t_max).
    pub fn merge(&mut self, o: &FptStats) {
        assert_eq!(
            self.t_max.to_bits(),
            o.t_max.to_bits(),
            "merging first-passage statistics of different t_max"
        );
        self.plus.merge(&o.plus);
        self.minus.merge(&o.minus);
        self.censored_plus += o.censored_plus;
        self.censored_minus += o.censored_minus;
        self.arrivals.merge(&o.arrivals);
        self.work += o.work;
    }
    /// Particles in total.
    pub fn particles(&self) -> u64 {
        self.plus.n + self.minus.n + self.censored()
    }
    /// Particles that had not arrived by t_max.
    pub fn censored(&self) -> u64 {
        self.censored_plus + self.censored_minus
    }
    /// The Kaplan-Meier survival curve of the passage times (see
    /// [`SurvivalCurve`]).
    pub fn survival(&self) -> SurvivalCurve {
        SurvivalCurve::new(
            &self.arrivals,
            self.t_max,
            self.plus.n + self.censored_plus,
            self.minus.n + self.censored_minus,
        )
    }
    /// Means (NaN where censored), restricted means, standard errors and
    /// the censoring.
    pub fn summary(&self) -> FptSummary {
        let (tp, tm) = (self.plus.mean(), self.minus.mean());
        let (ep, em) = (self.plus.sem(), self.minus.sem());
        let rp = restricted(&self.plus, self.censored_plus, self.t_max);
        let rm = restricted(&self.minus, self.censored_minus, self.t_max);
        let (rp, rm, erp, erm) = (rp.0, rm.0, rp.1, rm.1);
        let rmst = 0.5 * (rp + rm);
        let censored = self.censored();
        // A mean over the arrived particles alone is no estimate of tau.
        let unless = |c: u64, x: f64| if c == 0 { x } else { f64::NAN };
        let (cp, cm) = (self.censored_plus, self.censored_minus);
        FptSummary {
            tau: unless(censored, 0.5 * (tp + tm)),
            tau_err: unless(censored, 0.5 * (ep * ep + em * em).sqrt()),
            tau_plus: unless(cp, tp),
            tau_plus_err: unless(cp, ep),
            tau_minus: unless(cm, tm),
            tau_minus_err: unless(cm, em),
            rmst,
            rmst_err: 0.5 * (erp * erp + erm * erm).sqrt(),
            rmst_plus: rp,
            rmst_plus_err: erp,
            rmst_minus: rm,
            rmst_minus_err: erm,
            t_max: self.t_max,
            particles: self.particles(),
            censored,
            censored_fraction: censored as f64 / self.particles() as f64,
            tau_lower_bound: (censored > 0).then_some(rmst),
            work_per_particle: self.work as f64 / self.particles() as f64,
        }
    }
}

/// Mean and standard error of min(T, t_max) over the arrived (`acc`) and
/// `censored` particles of one starting state; without censoring exactly
/// the mean and standard error of the arrival times.
fn restricted(acc: &MeanAcc, censored: u64, t_max: f64) -> (f64, f64) {
    if censored == 0 {
        return (acc.mean(), acc.sem());
    }
    let c = censored as f64;
    let all = MeanAcc {
        n: acc.n + censored,
        sum: acc.sum + c * t_max,
        sum_sq: acc.sum_sq + c * t_max * t_max,
    };
    // A mean of numbers <= t_max, kept there against rounding.
    (all.mean().min(t_max), all.sem())
}

/// Simulation estimate of the MFPT.
///
/// Without censoring, tau± are the mean passage times. When any particle
/// has not arrived by t_max, the mean of the arrived ones is no estimate of
/// tau (it is biased low, arbitrarily): tau (and tau± of a censored half)
/// are then NaN, and the answer is the restricted mean
/// RMST = E[min(T, t_max)] = ∫_0^t_max S(t) dt, a lower bound: tau > RMST.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct FptSummary {
    /// (tau_plus + tau_minus)/2: the MFPT for a uniformly random initial
    /// state. NaN when any particle is censored.
    pub tau: f64,
    /// Its standard error (NaN when censored).
    pub tau_err: f64,
    /// Mean arrival time of particles started in +Sigma (NaN when one of
    /// them is censored).
    pub tau_plus: f64,
    /// Its standard error.
    pub tau_plus_err: f64,
    /// Mean arrival time of particles started in -Sigma (NaN when one of
    /// them is censored).
    pub tau_minus: f64,
    /// Its standard error.
    pub tau_minus_err: f64,
    /// Restricted mean (rmst_plus + rmst_minus)/2 of min(T, t_max); equal
    /// to tau, bit for bit, when nothing is censored.
    pub rmst: f64,
    /// Its standard error (from the sums of squares of min(T, t_max)).
    pub rmst_err: f64,
    /// Restricted mean of the particles started in +Sigma.
    pub rmst_plus: f64,
    /// Its standard error.
    pub rmst_plus_err: f64,
    /// Restricted mean of the particles started in -Sigma.
    pub rmst_minus: f64,
    /// Its standard error.
    pub rmst_minus_err: f64,
    /// The censoring time.
    pub t_max: f64,
    /// Particles simulated.
    pub particles: u64,
    /// Particles that had not arrived by t_max.
    pub censored: u64,
    /// censored / particles.
    pub censored_fraction: f64,
    /// `Some(rmst)` when any particle is censored: tau > rmst.
    pub tau_lower_bound: Option<f64>,
    /// Mean work (steps or events) per particle.
    pub work_per_particle: f64,
}

/// Run `n` particles: particle `i` gets `rng::stream(seed, i)` and starts in
/// +Sigma for even `i`, -Sigma for odd `i`; a sample time must be <= `t_max`
/// (`None`: censored). Bit-identical for any thread count.
pub fn first_passage_stats<S>(
    n: u64,
    seed: u64,
    t_max: f64,
    progress: &dyn Progress,
    sample: S,
) -> FptStats
where
    S: Fn(u64, &mut Rng, bool) -> FptSample + Sync,
{
    parallel::reduce(
        n,
        || FptStats::new(t_max),
        |i, acc| {
            let mut rng = rng::stream(seed, i);
            let plus = i % 2 == 0;
            acc.push(plus, sample(i, &mut rng, plus));
        },
        |a, b| a.merge(&b),
        progress,
    )
}

/// The unit totals of units `units` of the run of [`first_passage_stats`]
/// over `n` particles ([`parallel::reduce_units`]: unit u holds particles
/// u·UNIT..(u+1)·UNIT, each with its own stream (seed, i) and start state).
/// [`merge_units`] of all units' totals, in unit order and however they were
/// split into calls, is [`first_passage_stats`]'s result bit for bit.
pub fn first_passage_units<S>(
    n: u64,
    units: Range<u64>,
    seed: u64,
    t_max: f64,
    progress: &dyn Progress,
    sample: S,
) -> Vec<FptStats>
where
    S: Fn(u64, &mut Rng, bool) -> FptSample + Sync,
{
    parallel::reduce_units(
        n,
        units,
        || FptStats::new(t_max),
        |lo, hi, acc| {
            for i in lo..hi {
                // A cancelled chunk is discarded: stop within one particle.
                if progress.cancelled() {
                    return;
                }
                let mut rng = rng::stream(seed, i);
                let plus = i % 2 == 0;
                acc.push(plus, sample(i, &mut rng, plus));
            }
        },
        |a, b| a.merge(&b),
        progress,
    )
}

/// Unit totals merged in unit order into empty statistics at `t_max`: the
/// same additions as the reduction that made them, so the same bits.
pub fn merge_units(t_max: f64, units: &[FptStats]) -> FptStats {
    let mut total = FptStats::new(t_max);
    for u in units {
        total.merge(u);
    }
    total
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample(time: Option<f64>) -> FptSample {
        FptSample { time, work: 1 }
    }

    fn stats(t_max: f64, times: &[Option<f64>]) -> FptStats {
        let mut st = FptStats::new(t_max);
        for (i, &t) in times.iter().enumerate() {
            st.push(i % 2 == 0, sample(t));
        }
        st
    }

    #[test]
    fn uncensored_rmst_is_tau_bit_for_bit() {
        let times: Vec<_> = (1..40)
            .map(|i| Some((i as f64 * 0.37).sin().abs()))
            .collect();
        let s = stats(5.0, &times).summary();
        assert_eq!(s.censored, 0);
        assert_eq!(s.rmst.to_bits(), s.tau.to_bits());
        assert_eq!(s.rmst_err.to_bits(), s.tau_err.to_bits());
        assert_eq!(s.tau_lower_bound, None);
    }

    #[test]
    fn censored_tau_is_not_a_number_and_rmst_counts_t_max() {
        // + half: 1, 3 and one censored; - half: 2, 4 (none censored).
        let s = stats(5.0, &[Some(1.0), Some(2.0), Some(3.0), Some(4.0), None]).summary();
        assert!(s.tau.is_nan() && s.tau_err.is_nan() && s.tau_plus.is_nan());
        assert_eq!((s.tau_minus, s.rmst_minus), (3.0, 3.0));
        assert_eq!(s.rmst_plus, (1.0 + 3.0 + 5.0) / 3.0);
        assert_eq!(s.rmst, 0.5 * (3.0 + 3.0));
        assert_eq!(s.tau_lower_bound, Some(s.rmst));
        assert_eq!((s.censored, s.censored_fraction), (1, 0.2));
        // sd of {1, 3, 5} is 2: standard error 2/sqrt(3).
        assert!((s.rmst_plus_err - 2.0 / 3f64.sqrt()).abs() < 1e-15);
    }

    #[test]
    fn merge_adds_sums_counts_and_histograms() {
        let times: Vec<_> = (0..30)
            .map(|i| (i % 7 != 3).then_some(i as f64 * 0.1))
            .collect();
        let whole = stats(2.5, &times);
        let (mut a, b) = (stats(2.5, &times[..10]), stats(2.5, &times[10..]));
        assert_eq!(whole.censored(), 4);
        // The second part starts at an even index: same start states.
        a.merge(&b);
        assert_eq!(a.arrivals, whole.arrivals);
        assert_eq!((a.censored_plus, a.censored_minus), (2, 2));
        assert_eq!(a.plus.n + a.minus.n, whole.plus.n + whole.minus.n);
        let json = serde_json::to_string(&a).unwrap();
        assert_eq!(serde_json::from_str::<FptStats>(&json).unwrap(), a);
    }
}
