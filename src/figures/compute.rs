//! The computations behind the figures, each a thin call into the library's
//! solvers, gathered here so every figure uses the same methods and sizes.

use crate::analytic::r0::R0Density;
use crate::error::{Error, Result};
use crate::fp::{self, Mesh, StationaryOptions};
use crate::mfpt::{self, BackwardOptions, OptimizeOptions, ParticleOptions, Problem};
use crate::model::Params;
use crate::parallel::{NoProgress, Progress};
use crate::sim::{exact, Observables, SimSpec};
use serde::Serialize;

/// Particle simulation with the exact event-driven sampler (no time step,
/// no discretisation bias; `crate::sim::exact`).
pub fn simulate(params: &Params, spec: &SimSpec, progress: &dyn Progress) -> Result<Observables> {
    exact::simulate(params, spec, progress)
}

/// The moments the figures use at one recording time (named columns of
/// [`Observables::moment_rows`]).
#[derive(Clone, Copy, Debug, Serialize)]
pub struct Moments {
    /// Time.
    pub t: f64,
    /// <v²> and its standard error.
    pub v2: f64,
    /// Standard error of `v2`.
    pub v2_err: f64,
    /// `<x>`.
    pub x_mean: f64,
    /// <x²>.
    pub x2: f64,
    /// Standard error of `x2`.
    pub x2_err: f64,
}

/// Moments at every recording time of a simulation.
pub fn moments(obs: &Observables) -> Vec<Moments> {
    obs.moment_rows()
        .into_iter()
        .map(|r| Moments {
            t: r[0],
            v2: r[3],
            v2_err: r[4],
            x_mean: r[5],
            x2: r[7],
            x2_err: r[8],
        })
        .collect()
}

/// One histogram bin of a simulation's time-averaged stationary density
/// (named columns of [`Observables::density_rows`]).
#[derive(Clone, Copy, Debug, Serialize)]
pub struct DensityBin {
    /// Bin centre.
    pub v: f64,
    /// Density.
    pub p: f64,
    /// Standard error of `p`.
    pub p_err: f64,
}

/// The time-averaged density of a simulation, bin by bin.
pub fn density_bins(obs: &Observables) -> Vec<DensityBin> {
    obs.density_rows()
        .into_iter()
        .map(|d| DensityBin {
            v: d[0],
            p: d[1],
            p_err: d[2],
        })
        .collect()
}

/// A stationary density on a velocity mesh.
#[derive(Clone, Debug, Serialize)]
pub struct Density {
    /// Cell centres.
    pub v: Vec<f64>,
    /// Cell widths.
    pub widths: Vec<f64>,
    /// Cell edges (one more than cells).
    pub edges: Vec<f64>,
    /// Density values.
    pub p: Vec<f64>,
    /// Stationary <v²> (paper Eq. (33)), Richardson-extrapolated.
    pub v2: f64,
    /// Exact D_eff (discrete Green-Kubo), Richardson-extrapolated.
    pub d_eff: f64,
}

/// Stationary Fokker-Planck solution (graded finite-volume mesh, `cells` even).
pub fn fp_stationary(params: &Params, cells: usize) -> Result<Density> {
    let s = fp::stationary(
        params,
        &StationaryOptions {
            cells: cells + cells % 2,
            mesh: Mesh::Graded,
            extrapolate: true,
        },
    )?;
    Ok(Density {
        v: s.v,
        widths: s.widths,
        edges: s.edges,
        p: s.p,
        v2: s.v2,
        d_eff: s.d_eff,
    })
}

/// Analytic r = 0 density (paper Eqs. (34)-(35)) at the given velocities.
pub fn r0_density(params: &Params, v: &[f64]) -> Result<Vec<f64>> {
    let d = R0Density::new(params.drag(), params.sigma(), params.lambda())?;
    Ok(v.iter().map(|&x| d.pdf(x)).collect())
}

/// Cells of the FP solves for scalar results (D_eff).
pub const D_EFF_CELLS: usize = 20_000;

/// Exact effective diffusion coefficient from the stationary FP solver.
pub fn d_eff(params: &Params) -> Result<f64> {
    Ok(fp_stationary(params, D_EFF_CELLS)?.d_eff)
}

/// Cells of the backward MFPT solves.
pub const MFPT_CELLS: usize = 20_000;

/// MFPT from the backward equations of the simulated process; +∞ where
/// tau overflows f64.
pub fn mfpt(params: &Params, v0: f64, vt: f64) -> Result<f64> {
    let pr = Problem::new(*params, v0, vt)?;
    let s = mfpt::backward::at_start_or_overflow(&pr, &BackwardOptions::with_cells(MFPT_CELLS))?;
    Ok(s.map_or(f64::INFINITY, |s| s.tau))
}

/// Simulated first passage with the exact sampler (half the particles start
/// in +Sigma, half in -Sigma): (tau, standard error, particles, censored).
/// Particles not arrived by `t_cap` are censored (reported, excluded).
pub fn mfpt_sim(
    params: &Params,
    v0: f64,
    vt: f64,
    samples: u64,
    seed: u64,
    t_cap: f64,
    progress: &dyn Progress,
) -> Result<(f64, f64, u64, u64)> {
    let pr = Problem::new(*params, v0, vt)?;
    let method = mfpt::Method::Exact(ParticleOptions {
        particles: samples,
        t_max: t_cap,
        seed,
    });
    let s = mfpt::solve(&pr, &method, progress)?
        .summary()
        .expect("a particle method");
    Ok((s.tau, s.tau_err, s.particles, s.censored))
}

/// Result of the optimal-rate search.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct RateOptimum {
    /// Minimising rate (0 when resetting never helps).
    pub r_opt: f64,
    /// tau at r_opt.
    pub tau_opt: f64,
    /// tau without resetting.
    pub tau_r0: f64,
    /// d tau / d r at r = 0 (negative: a little resetting helps).
    pub dtau_dr_r0: f64,
    /// Minimum at some r > 0 with tau_opt < tau_r0.
    pub interior: bool,
}

/// Optimal resetting rate over r ∈ {0} ∪ [1e-3, 1e3] (`mfpt::optimize_rate`).
pub fn optimal_rate(params: &Params, v0: f64, vt: f64) -> Result<RateOptimum> {
    let pr = Problem::new(params.with_rate(0.0)?, v0, vt)?;
    let o = mfpt::optimize_rate(&pr, &OptimizeOptions::default(), &NoProgress)?;
    if o.at_upper_bound {
        return Err(Error::Numerical {
            method: "mfpt optimiser",
            reason: "minimum at the upper end of the r range".into(),
        });
    }
    Ok(RateOptimum {
        r_opt: o.r_opt,
        tau_opt: o.tau_opt,
        tau_r0: o.tau_r0,
        dtau_dr_r0: o.dtau_dr_r0,
        interior: o.interior,
    })
}

/// <v²>(t) from the time-dependent FP equations, the paper's method
/// (uniform mesh, explicit upwind, P±(v, 0) = ½ δ(v)), at `times`.
pub fn fp_transient_v2(params: &Params, cells: usize, times: &[f64]) -> Result<Vec<f64>> {
    let t_max = times.iter().copied().fold(0.0, f64::max);
    let tr = fp::transient(
        params,
        &fp::TransientOptions {
            cells,
            t_max,
            times: times.to_vec(),
            scheme: fp::Scheme::Paper,
            ..Default::default()
        },
    )?;
    // Recorded times come back sorted and deduplicated; map them to `times`.
    Ok(times
        .iter()
        .map(|t| {
            tr.times
                .iter()
                .position(|x| x == t)
                .map_or(f64::NAN, |i| tr.v2[i])
        })
        .collect())
}
