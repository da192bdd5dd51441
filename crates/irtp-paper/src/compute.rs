//! The computations behind the figures, each a thin call into the library's
//! solvers, gathered here so every figure uses the same methods and sizes.

use irtp::analytic::r0::R0Density;
use irtp::error::{Error, Result};
use irtp::fp::{self, Mesh, StationaryOptions};
use irtp::mfpt::{self, BackwardOptions, OptimizeOptions, Problem};
use irtp::model::Params;
use irtp::parallel::{NoProgress, Progress};
use irtp::sim::control::{self, ControlledRun};
use irtp::sim::{exact, Observables, SimSpec};
use serde::Serialize;

/// Particle simulation with the exact event-driven sampler (no time step,
/// no discretisation bias; `irtp::sim::exact`).
pub fn simulate(params: &Params, spec: &SimSpec, progress: &dyn Progress) -> Result<Observables> {
    exact::simulate(params, spec, progress)
}

/// Exact-sampler run with each particle paired with its linear proxy as
/// control variate ([`irtp::sim::control`]); the proxy's exact moments come
/// from the closed-form moment equations (docs/equations.md, (D1)).
pub fn controlled(
    params: &Params,
    spec: &SimSpec,
    progress: &dyn Progress,
) -> Result<ControlledRun> {
    let proxy = irtp::analytic::linear_moments::moments(&params.linear_proxy(), spec.grid.times())?;
    control::run(params, spec, &proxy.x2, progress)
}

/// Seed index offset of the sizing pilots: a figure's pilot for the curve
/// or point of seed index k draws from index `PILOT_SEED_OFFSET + k`,
/// disjoint from the indices of the runs themselves.
pub const PILOT_SEED_OFFSET: u64 = 1 << 32;

/// How a sizing pilot turns into a run size: a pilot of `pilot` particles
/// (own seed, discarded) measures the equivalent independent samples one
/// particle is worth; the run then gets enough for `margin` × `target`
/// (the margin covers the pilot's own sampling error), between `min` and `max`.
#[derive(Clone, Copy, Debug, Serialize)]
pub struct Sizing {
    /// Particles of the pilot.
    pub pilot: u64,
    /// Equivalent independent samples aimed at.
    pub target: f64,
    /// Factor on the target (>= 1).
    pub margin: f64,
    /// Fewest particles.
    pub min: u64,
    /// Most particles.
    pub max: u64,
}

impl Sizing {
    /// Particles for a run whose pilot measured `equivalent` samples in all.
    pub fn particles(&self, equivalent: f64) -> u64 {
        let per = equivalent / self.pilot as f64;
        let want = self.margin * self.target / per;
        // NaN or a zero gain: the pilot says nothing, take the most.
        let n = if want.is_finite() {
            want.ceil() as u64
        } else {
            self.max
        };
        n.clamp(self.min, self.max.max(self.min))
    }
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

/// Exact D_eff with an error estimate, for comparisons at standard errors
/// far below the mesh error of [`d_eff`]: the meshes `D_EFF_CELLS` / 2,
/// `D_EFF_CELLS` and 2 `D_EFF_CELLS` in a two-stage Richardson table (the
/// solver's own extrapolation removes the O(1/N) error of each pair; the
/// second stage the O(1/N²) of the two extrapolants). The error estimate is
/// the second stage's correction, the error of the better extrapolant:
/// conservative for the combined value where the expansion holds.
pub fn d_eff_with_error(params: &Params) -> Result<(f64, f64)> {
    let a = fp_stationary(params, D_EFF_CELLS)?.d_eff;
    let b = fp_stationary(params, 2 * D_EFF_CELLS)?.d_eff;
    let correction = (b - a) / 3.0;
    Ok((b + correction, correction.abs()))
}

/// Relative bias of the Eq. (36) fit window for the linear proxy of a
/// controlled run, exact: (its window fit of the exact <x_lin²>(t_k)) /
/// (its exact D_eff) - 1. The proxy shares the target's flip rate, reset
/// rule and velocity interval, so the transients the window leaves in the
/// fit decay at the same rates; `None` without a fit window.
pub fn proxy_window_bias(run: &ControlledRun) -> Result<Option<f64>> {
    let w = &run.sums.target.msd_weights;
    if w.iter().all(|&x| x == 0.0) {
        return Ok(None);
    }
    let window: f64 = w.iter().zip(&run.proxy_x2).map(|(w, m)| w * m).sum();
    Ok(Some(
        window / irtp::analytic::linear::d_eff(&run.proxy)? - 1.0,
    ))
}

/// Cells of the backward MFPT solves.
pub const MFPT_CELLS: usize = 20_000;

/// MFPT from the backward equations of the simulated process; +∞ where
/// tau overflows f64.
pub fn mfpt(params: &Params, v0: f64, vt: f64) -> Result<f64> {
    let pr = Problem::new(params.clone(), v0, vt)?;
    let s = mfpt::backward::at_start_or_overflow(&pr, &BackwardOptions::with_cells(MFPT_CELLS))?;
    Ok(s.map_or(f64::INFINITY, |s| s.tau))
}

/// MFPT from the backward equations and its discretisation error estimate
/// (Richardson, [`MFPT_CELLS`] vs half as many cells).
pub fn mfpt_with_error(params: &Params, v0: f64, vt: f64) -> Result<(f64, f64)> {
    let pr = Problem::new(params.clone(), v0, vt)?;
    let s = mfpt::backward::solve(&pr, &BackwardOptions::with_cells(MFPT_CELLS))?;
    Ok((s.tau, s.error_estimate))
}

/// Exact first passages from v0 to vt under the martingale control variate
/// ([`irtp::mfpt::control`], u from the backward equations on
/// [`MFPT_CELLS`] cells, piecewise constant on `cells`): `particles`
/// walks, half started in each noise state; an error if any is censored
/// at `t_cap`.
pub fn mfpt_sim_controlled(
    params: &Params,
    (v0, vt): (f64, f64),
    (particles, seed, t_cap): (u64, u64, f64),
    cells: usize,
    progress: &dyn Progress,
) -> Result<mfpt::control::ControlledPassage> {
    let pr = Problem::new(params.clone(), v0, vt)?;
    mfpt::control::run(&pr, (particles, seed, t_cap), cells, MFPT_CELLS, progress)?.summary()
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
