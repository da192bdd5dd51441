//! First-passage estimators shared by every particle method.
//!
//! [`first_passage_stats`] is method-agnostic: it hands particle `i` its own
//! stream `rng::stream(seed, i)` and its stratum `i mod K` (the starting
//! noise state; for the paper's noise even `i`: +Sigma, odd `i`: -Sigma —
//! stratified, so tau = (tau+ + tau-)/2 is estimated with exactly balanced
//! halves), calls the per-particle sampler and reduces the
//! results deterministically into mergeable sums and counts ([`FptStats`],
//! with the arrival-time histogram of [`super::survival`]), summarised as
//! [`FptSummary`]: the mean passage times when every particle arrived by
//! t_max, otherwise the restricted mean E[min(T, t_max)], a lower bound. A particle method is any
//! `Fn(index, &mut Rng, stratum) -> FptSample`
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

/// The strata of the paper's noise: start states +Sigma (index 0) and
/// -Sigma (index 1), weight 1/2 each. A noise model's run has the same
/// two equal halves (even and odd particles), each particle's start state
/// drawn from the stationary law π (the halves are two samples of the
/// π-mixture).
pub const HALVES: [f64; 2] = [0.5, 0.5];

/// Σ_k w_k x_k over the strata of weights `w`; for [`HALVES`] exactly
/// (x_0 + x_1)/2.
fn mix(w: &[f64], x: impl Fn(usize) -> f64) -> f64 {
    if w == HALVES {
        return 0.5 * (x(0) + x(1));
    }
    (0..w.len()).map(|k| w[k] * x(k)).sum()
}

/// The standard error sqrt(Σ_k w_k² e_k²) of [`mix`] from the strata's
/// standard errors `e`; for [`HALVES`] exactly sqrt(e_0² + e_1²)/2.
fn mix_err(w: &[f64], e: impl Fn(usize) -> f64) -> f64 {
    if w == HALVES {
        let (a, b) = (e(0), e(1));
        return 0.5 * (a * a + b * b).sqrt();
    }
    let var: f64 = (0..w.len()).map(|k| (w[k] * e(k)).powi(2)).sum();
    var.sqrt()
}

/// Mergeable first-passage statistics, split by stratum (the starting
/// noise state; particle i is in stratum i mod the number of strata):
/// sums and counts only (merged by addition), so a run gives the same bits
/// for any thread count and shard split.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FptStats {
    /// The censoring time: every particle not arrived by t_max is censored.
    pub t_max: f64,
    /// The weight of each stratum in the estimates (its probability as a
    /// start state; they sum to 1).
    pub weights: Vec<f64>,
    /// Arrival times of the particles of each stratum.
    pub arrived: Vec<MeanAcc>,
    /// Particles of each stratum that had not arrived by t_max.
    pub censored_in: Vec<u64>,
    /// Arrival-time histogram on the fixed grid of t_max (the survival curve).
    pub arrivals: Arrivals,
    /// Total work (sum of [`FptSample::work`]).
    pub work: u64,
}

impl FptStats {
    /// No particle yet, censoring at `t_max`, in the strata [`HALVES`].
    pub fn new(t_max: f64) -> Self {
        Self::stratified(t_max, &HALVES)
    }
    /// No particle yet, censoring at `t_max`, one stratum per weight.
    pub fn stratified(t_max: f64, weights: &[f64]) -> Self {
        let k = weights.len();
        assert!(k > 0, "first-passage statistics need a stratum");
        FptStats {
            t_max,
            weights: weights.to_vec(),
            arrived: vec![MeanAcc::new(); k],
            censored_in: vec![0; k],
            arrivals: Arrivals::new(t_max, k),
            work: 0,
        }
    }
    /// The number of strata.
    pub fn strata(&self) -> usize {
        self.weights.len()
    }
    /// Add one particle of stratum `k`.
    pub fn push(&mut self, k: usize, s: FptSample) {
        self.work += s.work;
        match s.time {
            Some(t) => {
                self.arrivals.push(self.t_max, k, t);
                self.arrived[k].push(t);
            }
            None => self.censored_in[k] += 1,
        }
    }
    /// Merge another shard (same t_max and strata).
    pub fn merge(&mut self, o: &FptStats) {
        assert_eq!(
            self.t_max.to_bits(),
            o.t_max.to_bits(),
            "merging first-passage statistics of different t_max"
        );
        assert_eq!(
            self.weights, o.weights,
            "merging first-passage statistics of different strata"
        );
        for (a, b) in self.arrived.iter_mut().zip(&o.arrived) {
            a.merge(b);
        }
        for (a, b) in self.censored_in.iter_mut().zip(&o.censored_in) {
            *a += b;
        }
        self.arrivals.merge(&o.arrivals);
        self.work += o.work;
    }
    /// Particles of stratum `k` (arrived or not).
    pub fn particles_in(&self, k: usize) -> u64 {
        self.arrived[k].n + self.censored_in[k]
    }
    /// Particles in total.
    pub fn particles(&self) -> u64 {
        self.arrived.iter().map(|a| a.n).sum::<u64>() + self.censored()
    }
    /// Particles that had not arrived by t_max.
    pub fn censored(&self) -> u64 {
        self.censored_in.iter().sum()
    }
    /// The Kaplan-Meier survival curve of the passage times (see
    /// [`SurvivalCurve`]).
    pub fn survival(&self) -> SurvivalCurve {
        let n: Vec<u64> = (0..self.strata()).map(|k| self.particles_in(k)).collect();
        SurvivalCurve::new(&self.arrivals, self.t_max, &n, &self.weights)
    }
    /// Means (NaN where censored), restricted means, standard errors and
    /// the censoring; `tau_plus`/`tau_minus` are strata 0 and 1 (the
    /// paper's ±Sigma; NaN where there is no such stratum).
    pub fn summary(&self) -> FptSummary {
        let w = &self.weights;
        let k = w.len();
        let at = |x: &[f64], j: usize| x.get(j).copied().unwrap_or(f64::NAN);
        let t: Vec<f64> = self.arrived.iter().map(MeanAcc::mean).collect();
        let e: Vec<f64> = self.arrived.iter().map(MeanAcc::sem).collect();
        let (r, er): (Vec<f64>, Vec<f64>) = (0..k)
            .map(|j| restricted(&self.arrived[j], self.censored_in[j], self.t_max))
            .unzip();
        let rmst = mix(w, |j| r[j]);
        let censored = self.censored();
        // A mean over the arrived particles alone is no estimate of tau.
        let unless = |c: u64, x: f64| if c == 0 { x } else { f64::NAN };
        let c = |j: usize| self.censored_in.get(j).copied().unwrap_or(0);
        FptSummary {
            tau: unless(censored, mix(w, |j| t[j])),
            tau_err: unless(censored, mix_err(w, |j| e[j])),
            tau_plus: unless(c(0), at(&t, 0)),
            tau_plus_err: unless(c(0), at(&e, 0)),
            tau_minus: unless(c(1), at(&t, 1)),
            tau_minus_err: unless(c(1), at(&e, 1)),
            rmst,
            rmst_err: mix_err(w, |j| er[j]),
            rmst_plus: at(&r, 0),
            rmst_plus_err: at(&er, 0),
            rmst_minus: at(&r, 1),
            rmst_minus_err: at(&er, 1),
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

/// Run `n` particles in the strata of `weights`: particle `i` gets
/// `rng::stream(seed, i)` and stratum `i % weights.len()` (for the
/// paper's noise, [`HALVES`]: +Sigma for even `i`, -Sigma for odd `i`),
/// handed to the sampler; a sample time must be <= `t_max` (`None`:
/// censored). Bit-identical for any thread count.
pub fn first_passage_stats<S>(
    n: u64,
    seed: u64,
    (t_max, weights): (f64, &[f64]),
    progress: &dyn Progress,
    sample: S,
) -> FptStats
where
    S: Fn(u64, &mut Rng, usize) -> FptSample + Sync,
{
    let k = weights.len() as u64;
    parallel::reduce(
        n,
        || FptStats::stratified(t_max, weights),
        |i, acc| {
            let mut rng = rng::stream(seed, i);
            let s = (i % k) as usize;
            acc.push(s, sample(i, &mut rng, s));
        },
        |a, b| a.merge(&b),
        progress,
    )
}

/// The unit totals of units `units` of the run of [`first_passage_stats`]
/// over `n` particles ([`parallel::reduce_units`]: unit u holds particles
/// u·UNIT..(u+1)·UNIT, each with its own stream (seed, i) and stratum).
/// [`merge_units`] of all units' totals, in unit order and however they were
/// split into calls, is [`first_passage_stats`]'s result bit for bit.
pub fn first_passage_units<S>(
    n: u64,
    units: Range<u64>,
    seed: u64,
    (t_max, weights): (f64, &[f64]),
    progress: &dyn Progress,
    sample: S,
) -> Vec<FptStats>
where
    S: Fn(u64, &mut Rng, usize) -> FptSample + Sync,
{
    let k = weights.len() as u64;
    parallel::reduce_units(
        n,
        units,
        || FptStats::stratified(t_max, weights),
        |lo, hi, acc| {
            for i in lo..hi {
                // A cancelled chunk is discarded: stop within one particle.
                if progress.cancelled() {
                    return;
                }
                let mut rng = rng::stream(seed, i);
                let s = (i % k) as usize;
                acc.push(s, sample(i, &mut rng, s));
            }
        },
        |a, b| a.merge(&b),
        progress,
    )
}

/// Unit totals merged in unit order into empty statistics at `t_max`
/// (in the strata of the units, [`HALVES`] when there is none): the same
/// additions as the reduction that made them, so the same bits.
pub fn merge_units(t_max: f64, units: &[FptStats]) -> FptStats {
    let weights = units.first().map_or(&HALVES[..], |u| &u.weights);
    let mut total = FptStats::stratified(t_max, weights);
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
            st.push(i % 2, sample(t));
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
        assert_eq!(a.censored_in, [2, 2]);
        assert_eq!(a.particles(), whole.particles());
        let json = serde_json::to_string(&a).unwrap();
        assert_eq!(serde_json::from_str::<FptStats>(&json).unwrap(), a);
    }

    #[test]
    fn three_strata_mix_with_their_weights() {
        let w = [0.25, 0.25, 0.5];
        let mut st = FptStats::stratified(10.0, &w);
        // Stratum k holds the times k+1 and k+3: means 2, 3, 4.
        for (i, t) in [1.0, 2.0, 3.0, 3.0, 4.0, 5.0].into_iter().enumerate() {
            st.push(i % 3, sample(Some(t)));
        }
        let s = st.summary();
        assert_eq!(s.tau, 0.25 * 2.0 + 0.25 * 3.0 + 0.5 * 4.0);
        assert_eq!((s.tau_plus, s.tau_minus, s.particles), (2.0, 3.0, 6));
        // Each stratum's standard error is 1 (sd sqrt(2) over sqrt(2)).
        assert!((s.tau_err - (2.0 * 0.0625 + 0.25f64).sqrt()).abs() < 1e-15);
        // S(t) at t = 2.2 (past the arrivals 1, 2): strata 1/2, 1/2, 1.
        let c = st.survival();
        let j = c.t.iter().position(|&t| t == 2.2).unwrap();
        assert_eq!(c.survival[j], 0.25 * 0.5 + 0.25 * 0.5 + 0.5 * 1.0);
        assert_eq!(c.at_risk[j], 4);
    }
}
