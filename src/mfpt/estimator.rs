//! First-passage estimators shared by every particle method.
//!
//! [`first_passage_stats`] is method-agnostic: it hands particle `i` its own
//! stream `rng::stream(seed, i)` and its starting noise state (even `i`: +Sigma,
//! odd `i`: -Sigma — stratified, so tau = (tau+ + tau-)/2 is estimated with
//! exactly balanced halves), calls the per-particle sampler and reduces the
//! results deterministically into mergeable sums ([`FptStats`], summarised
//! as [`FptSummary`]). A particle method is any
//! `Fn(index, &mut Rng, start_plus) -> FptSample`
//! ([`super::euler`], [`super::exact`]).

use crate::parallel::{self, Progress};
use crate::rng::{self, Rng};
use crate::stats::MeanAcc;
use serde::{Deserialize, Serialize};

/// One particle's first passage.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct FptSample {
    /// First-passage time; `None` if the target was not reached by t_max.
    pub time: Option<f64>,
    /// Work done (time steps or events), for cost accounting.
    pub work: u64,
}

/// Mergeable first-passage statistics, split by starting noise state.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct FptStats {
    /// Arrival times of particles started in +Sigma.
    pub plus: MeanAcc,
    /// Arrival times of particles started in -Sigma.
    pub minus: MeanAcc,
    /// Particles started in +Sigma that had not arrived by t_max.
    pub censored_plus: u64,
    /// Particles started in -Sigma that had not arrived by t_max.
    pub censored_minus: u64,
    /// Total work (sum of [`FptSample::work`]).
    pub work: u64,
}

impl FptStats {
    /// Add one particle.
    pub fn push(&mut self, start_plus: bool, s: FptSample) {
        self.work += s.work;
        match (start_plus, s.time) {
            (true, Some(t)) => self.plus.push(t),
            (false, Some(t)) => self.minus.push(t),
            (true, None) => self.censored_plus += 1,
            (false, None) => self.censored_minus += 1,
        }
    }
    /// Merge another shard.
    pub fn merge(&mut self, o: &FptStats) {
        self.plus.merge(&o.plus);
        self.minus.merge(&o.minus);
        self.censored_plus += o.censored_plus;
        self.censored_minus += o.censored_minus;
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
    /// Means, standard errors and the censoring flag.
    pub fn summary(&self) -> FptSummary {
        let (tp, tm) = (self.plus.mean(), self.minus.mean());
        let (ep, em) = (self.plus.sem(), self.minus.sem());
        FptSummary {
            tau: 0.5 * (tp + tm),
            tau_err: 0.5 * (ep * ep + em * em).sqrt(),
            tau_plus: tp,
            tau_plus_err: ep,
            tau_minus: tm,
            tau_minus_err: em,
            particles: self.particles(),
            censored: self.censored(),
            mean_is_lower_bound: self.censored() > 0,
            work_per_particle: self.work as f64 / self.particles() as f64,
        }
    }
}

/// Simulation estimate of the MFPT.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct FptSummary {
    /// (tau_plus + tau_minus)/2: the MFPT for a uniformly random initial state.
    /// Means are over arrived particles (NaN if none of a half arrived).
    pub tau: f64,
    /// Its standard error.
    pub tau_err: f64,
    /// Mean arrival time of particles started in +Sigma.
    pub tau_plus: f64,
    /// Its standard error.
    pub tau_plus_err: f64,
    /// Mean arrival time of particles started in -Sigma.
    pub tau_minus: f64,
    /// Its standard error.
    pub tau_minus_err: f64,
    /// Particles simulated.
    pub particles: u64,
    /// Particles that had not arrived by t_max (excluded from the means).
    pub censored: u64,
    /// True if any particle was censored: the means are then means of the
    /// arrived particles only, i.e. lower bounds of the true MFPT.
    pub mean_is_lower_bound: bool,
    /// Mean work (steps or events) per particle.
    pub work_per_particle: f64,
}

/// Run `n` particles: particle `i` gets `rng::stream(seed, i)` and starts in
/// +Sigma for even `i`, -Sigma for odd `i`. Bit-identical for any thread count.
pub fn first_passage_stats<S>(n: u64, seed: u64, progress: &dyn Progress, sample: S) -> FptStats
where
    S: Fn(u64, &mut Rng, bool) -> FptSample + Sync,
{
    parallel::reduce(
        n,
        FptStats::default,
        |i, acc| {
            let mut rng = rng::stream(seed, i);
            let plus = i % 2 == 0;
            acc.push(plus, sample(i, &mut rng, plus));
        },
        |a, b| a.merge(&b),
        progress,
    )
}
