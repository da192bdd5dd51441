//! Control variates for the exact sampler's position moments.
//!
//! Each particle is paired with a Newtonian particle on the same velocity
//! interval ([`Params::linear_proxy`]: g(v) = v, Sigma' = v_u, the same flip
//! rate and resetting rule) driven by the same random stream (seed, i). The
//! exact sampler draws an event's time and kind from the stream alone, never
//! from the law, so the two particles flip and reset at the same instants
//! and differ only in their flows between events: their displacements are
//! strongly correlated (measured at lambda = 1/2, t ∈ [0.01, 100], r ≤ 10:
//! a pair is worth at least 6.6 plain particles for tan at Sigma = 3 and 359
//! for tanh at Sigma = 0.6, see `tests/control_variate.rs`). The
//! proxy's moments are exact (docs/equations.md (D1),
//! [`crate::analytic::linear_moments`]), so
//!
//! ```text
//! <x²>(t) ≈ mean(x²) - β (mean(x_lin²) - <x_lin²>_exact),   β = Cov / Var(x_lin²),
//! ```
//!
//! is unbiased up to O(1/n) (β estimated from the same pairs) with variance
//! (1 - ρ²) Var(x²)/n: a run of n particles is worth n/(1 - ρ²) plain ones
//! ([`Controlled::equivalent_samples`]). The same holds for any statistic
//! linear in the x(t_k)², such as the per-particle Eq. (36) slope whose mean
//! is the MSD-fit D_eff. The pairs cost two particles' events each (the
//! linear flow is the cheaper one).

use super::exact;
use super::{Observables, SimSpec};
use crate::error::{Error, Result};
use crate::model::reset::Solver;
use crate::model::Params;
use crate::parallel::Progress;
use crate::stats::{Controlled, PairAcc};

/// Sums of a coupled run: the target's observables and the pairs.
#[derive(Clone, Debug, PartialEq)]
pub struct Coupled {
    /// The target law's observables (as [`crate::sim::simulate`] gives them).
    pub target: Observables,
    /// Pairs (x(t_k)², x_lin(t_k)²) per recording time.
    pub x2: Vec<PairAcc>,
    /// Pairs of per-particle Eq. (36) slopes (empty without a fit window).
    pub msd_d: PairAcc,
}

impl Coupled {
    /// No particles yet.
    pub(crate) fn empty(target: Observables) -> Self {
        let k = target.times.len();
        Coupled {
            target,
            x2: vec![PairAcc::new(); k],
            msd_d: PairAcc::new(),
        }
    }

    /// Add one particle: `one` and `lin` hold that particle alone, of the
    /// target law and of the proxy.
    pub(crate) fn push(&mut self, one: &Observables, lin: &Observables) {
        self.target.merge(one);
        for ((p, a), b) in self.x2.iter_mut().zip(&one.x2).zip(&lin.x2) {
            p.push(a.sum, b.sum);
        }
        if one.msd_fit_d.n == 1 {
            self.msd_d.push(one.msd_fit_d.sum, lin.msd_fit_d.sum);
        }
    }

    /// Merge the sums of another chunk.
    pub(crate) fn merge(&mut self, o: &Coupled) {
        self.target.merge(&o.target);
        for (a, b) in self.x2.iter_mut().zip(&o.x2) {
            a.merge(b);
        }
        self.msd_d.merge(&o.msd_d);
    }
}

/// A run with its control-variate estimates.
#[derive(Clone, Debug)]
pub struct ControlledRun {
    /// The sums.
    pub sums: Coupled,
    /// The proxy model.
    pub proxy: Params,
    /// Exact <x_lin²>(t_k) of the proxy.
    pub proxy_x2: Vec<f64>,
    /// Controlled <x²>(t_k).
    pub x2: Vec<Controlled>,
    /// Controlled MSD-fit D (Eq. (36)) over the fit window, if there is one.
    pub msd_d: Option<Controlled>,
}

/// Simulate `spec.particles` particles of `params` with the exact sampler,
/// each paired with its linear proxy, and estimate <x²>(t_k) and the
/// MSD-fit D with the proxy as control variate. `proxy_x2` are the proxy's
/// exact <x²>(t_k) at the recording times:
/// `crate::analytic::linear_moments::moments(&params.linear_proxy(), times)`
/// (the analytic layer sits beside this one, so the caller passes them).
/// Bit-identical for any thread count. Refused where the proxy's moments are
/// not known exactly (a fixed refractory period).
pub fn run(
    params: &Params,
    spec: &SimSpec,
    proxy_x2: &[f64],
    progress: &dyn Progress,
) -> Result<ControlledRun> {
    params.require(Solver::Exact)?;
    if let Some(m) = params.noise() {
        // The proxy's exact moments are those of the paper's noise.
        return Err(Error::invalid(
            "noise",
            m.spec(),
            "the paper's symmetric telegraph noise for the linear-proxy control variate (the \
             plain exact sampler runs this noise)",
        ));
    }
    let proxy = params.linear_proxy();
    proxy.require(Solver::ClosedForm)?;
    if proxy_x2.len() != spec.grid.len() || !proxy_x2.iter().all(|m| m.is_finite()) {
        return Err(Error::invalid(
            "proxy_x2",
            proxy_x2.len(),
            format!(
                "{} finite exact moments, one per recording time",
                spec.grid.len()
            ),
        ));
    }
    let sums = exact::simulate_coupled(params, &proxy, spec, progress)?;
    let x2 = sums
        .x2
        .iter()
        .zip(proxy_x2)
        .map(|(p, &mu)| p.controlled(mu))
        .collect();
    let weights = &sums.target.msd_weights;
    let msd_d = (sums.msd_d.n > 0).then(|| {
        let mu: f64 = weights.iter().zip(proxy_x2).map(|(w, m)| w * m).sum();
        sums.msd_d.controlled(mu)
    });
    Ok(ControlledRun {
        sums,
        proxy,
        proxy_x2: proxy_x2.to_vec(),
        x2,
        msd_d,
    })
}
