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

use super::exact::{Sampler, Scratch, Telegraph};
use super::{Observables, Part, SimSpec};
use crate::error::{Error, Result};
use crate::model::reset::Solver;
use crate::model::Drag;
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
    let sums = simulate_coupled(params, &proxy, spec, progress)?;
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

/// [`run`]'s sampler: every particle of the run twice, with
/// `params` and with the linear proxy `proxy` ([`Params::linear_proxy`]),
/// from the same stream (seed, i), so both see the same events; the pairs
/// (x(t_k)², x_proxy(t_k)²) and the pair of Eq. (36) slopes are summed.
fn simulate_coupled(
    params: &Params,
    proxy: &Params,
    spec: &SimSpec,
    progress: &dyn Progress,
) -> Result<Coupled> {
    crate::with_drag!(params.drag(), |d| coupled_drag(
        d, params, proxy, spec, progress
    ))
}

/// Per-chunk state of a coupled run: the totals, a one-particle accumulator
/// per sampler and the scratch.
struct CoupledChunk {
    totals: Coupled,
    one: [Observables; 2],
    sc: Scratch,
}

fn coupled_drag<D: Drag>(
    drag: &D,
    params: &Params,
    proxy: &Params,
    spec: &SimSpec,
    progress: &dyn Progress,
) -> Result<Coupled> {
    let target = Sampler::<D::Flow, Telegraph>::new(drag, params, spec)?;
    let linear = Sampler::<_, Telegraph>::new(&crate::model::drag::Linear, proxy, spec)?;
    let empty = [
        Observables::new(spec, params),
        Observables::new(spec, proxy),
    ];
    let b = spec.bins;
    let first = spec.first_particle;
    let init = || CoupledChunk {
        totals: Coupled::empty(empty[0].clone()),
        one: empty.clone(),
        sc: target.scratch(b),
    };
    let chunk = |lo: u64, hi: u64, c: &mut CoupledChunk| {
        for i in first + lo..first + hi {
            target.particles(i..i + 1, &mut c.one[0], &mut c.sc);
            linear.particles(i..i + 1, &mut c.one[1], &mut c.sc);
            c.totals.push(&c.one[0], &c.one[1]);
            c.one[0].clone_from(&empty[0]);
            c.one[1].clone_from(&empty[1]);
        }
    };
    let mut totals = Part::Whole.reduce(
        spec.particles,
        init,
        chunk,
        |a, b| a.totals.merge(&b.totals),
        progress,
    );
    Ok(totals.remove(0).totals)
}
