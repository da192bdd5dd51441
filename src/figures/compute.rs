//! The computations behind the figures, each a thin call into the library's
//! solvers, gathered here so every figure uses the same methods and sizes.

use crate::error::{Error, Result};
use crate::model::Params;
use crate::parallel::Progress;
use crate::sim::{Observables, SimSpec};
use serde::Serialize;

fn missing(what: &'static str) -> Error {
    Error::Numerical {
        method: what,
        reason: "solver not merged into this branch yet".into(),
    }
}

/// Particle simulation with the exact event-driven sampler.
pub fn simulate(params: &Params, spec: &SimSpec, progress: &dyn Progress) -> Result<Observables> {
    // Interim: Euler until the exact sampler is merged.
    crate::sim::simulate(
        params,
        spec,
        crate::sim::Method::Euler { dt: 1e-3 },
        progress,
    )
}

/// A stationary density on a velocity grid.
#[derive(Clone, Debug, Serialize)]
pub struct Density {
    /// Velocities (cell centres).
    pub v: Vec<f64>,
    /// Cell widths.
    pub widths: Vec<f64>,
    /// Density values.
    pub p: Vec<f64>,
    /// Stationary <v²> (paper Eq. 17).
    pub v2: f64,
}

/// Stationary Fokker-Planck density with `cells` cells.
pub fn fp_stationary(params: &Params, cells: usize) -> Result<Density> {
    let _ = (params, cells);
    Err(missing("fp stationary"))
}

/// Analytic r = 0 density (paper Eqs. Neqn17, apeqn18a) at the given velocities.
pub fn r0_density(params: &Params, v: &[f64]) -> Result<Vec<f64>> {
    let _ = (params, v);
    Err(missing("analytic r0"))
}

/// Exact effective diffusion coefficient.
pub fn d_eff(params: &Params) -> Result<f64> {
    let _ = params;
    Err(missing("fp d_eff"))
}

/// MFPT from the backward equations.
pub fn mfpt(params: &Params, v0: f64, vt: f64) -> Result<f64> {
    let _ = (params, v0, vt);
    Err(missing("mfpt backward"))
}

/// Simulated first-passage times: (mean, standard error, samples).
pub fn mfpt_sim(
    params: &Params,
    v0: f64,
    vt: f64,
    samples: u64,
    seed: u64,
    t_cap: f64,
    progress: &dyn Progress,
) -> Result<(f64, f64, u64, u64)> {
    let _ = (params, v0, vt, samples, seed, t_cap, progress);
    Err(missing("exact first passage"))
}

/// Optimal resetting rate: `Some((r*, tau(r*), tau(0)))` when interior, `None` when tau grows from r = 0.
pub fn optimal_rate(params: &Params, v0: f64, vt: f64) -> Result<Option<(f64, f64, f64)>> {
    let _ = (params, v0, vt);
    Err(missing("mfpt optimiser"))
}

/// <v²>(t) from the time-dependent FP equations at `times`.
pub fn fp_transient_v2(params: &Params, cells: usize, times: &[f64]) -> Result<Vec<f64>> {
    let _ = (params, cells, times);
    Err(missing("fp transient"))
}
