//! Direct stationary solve, `<v>`, `<v²>` (paper Eq. (33)) and the exact
//! D_eff: one engine ([`stationary()`]) over the noise's state space
//! ([`StationarySpace`]), dispatched once at its entry: the paper's two
//! states ([`two_state`]: subtraction-free block-Thomas elimination on the
//! paper's graded mesh, refractory and position moments) or a finite-state
//! chain with thermal noise ([`chain`]: band LU, Eqs. (N20)-(N27)).

mod chain;
mod two_state;

pub use chain::{NoiseMoments, NoiseSummary};
pub(crate) use two_state::make_grid;

pub use super::grid::{MAX_CELLS, MIN_CELLS};

use super::grid::Mesh;
use crate::error::{Error, Result};
use crate::model::reset::Solver;
use crate::model::{Params, VelocityAtom};
use serde::{Deserialize, Serialize};

/// Options of [`stationary`].
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct StationaryOptions {
    /// Number of finite-volume cells of the reported (fine) mesh.
    pub cells: usize,
    /// Cell placement.
    pub mesh: Mesh,
    /// Richardson-extrapolate `<v>`, `<v²>`, D_eff from the meshes with `cells`
    /// and `cells/2` cells (first-order scheme: X = 2 X_N - X_{N/2}).
    /// Needs an even `cells`. The density is always the fine-mesh one.
    pub extrapolate: bool,
}

impl Default for StationaryOptions {
    fn default() -> Self {
        StationaryOptions {
            cells: 20_000,
            mesh: Mesh::Graded,
            extrapolate: true,
        }
    }
}

/// Scalar stationary observables on one mesh.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Moments {
    /// Number of cells.
    pub cells: usize,
    /// Σ P Δv (1 up to rounding).
    pub mass: f64,
    /// `<v>_ss`.
    pub v_mean: f64,
    /// `<v²>_ss` (paper Eq. (33)).
    pub v2: f64,
    /// D_eff = ∫_0^∞ <δv(0) δv(t)>_ss dt (∞ for λ = 0: ballistic).
    pub d_eff: f64,
    /// Refractory mass q+ + q- (the point mass at the held velocity; 0
    /// without a refractory period). Included in `mass`, `v_mean`, `v2`.
    pub refractory_mass: f64,
    /// Stationary (`<x>`, `<x²>`) under position resetting, else None.
    pub x_moments: Option<[f64; 2]>,
}

/// Stationary state of the discrete forward equations (paper Eqs. (11)-(12) with
/// state-preserving reset to v_r).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Stationary {
    /// Parameters.
    pub params: Params,
    /// Mesh kind.
    pub mesh: Mesh,
    /// Number of cells (fine mesh).
    pub cells: usize,
    /// Grading exponent q (1 = uniform near the edges).
    pub grading: f64,
    /// Edge exponent a = (λ + r)/g'(v_u) - 1 of P ~ (v_u - v)^a.
    pub edge_exponent: f64,
    /// Cell centres.
    pub v: Vec<f64>,
    /// Cell edges (cells + 1).
    pub edges: Vec<f64>,
    /// Cell widths (exact, also where edges round to the same float).
    pub widths: Vec<f64>,
    /// Total density P_s = P+ + P- (cell averages).
    pub p: Vec<f64>,
    /// Density of the + state.
    pub p_plus: Vec<f64>,
    /// Density of the - state.
    pub p_minus: Vec<f64>,
    /// Σ P Δv after normalisation.
    pub mass: f64,
    /// `<v>_ss` (extrapolated if `extrapolated`).
    pub v_mean: f64,
    /// `<v²>_ss` (extrapolated if `extrapolated`).
    pub v2: f64,
    /// D_eff (extrapolated if `extrapolated`). With position resetting
    /// the position does not diffuse: this is then only the integral of the
    /// velocity autocorrelation, and the CLI does not report it.
    pub d_eff: f64,
    /// Error estimate of `d_eff` from the meshes cells/4, cells/2, cells
    /// (twice the change of the first-order extrapolation from the meshes
    /// cells/4, cells/2, where it converges; the N-state solver's Eq. (N27));
    /// None without extrapolation, with fewer than 32 cells, or where
    /// D_eff is infinite (λ = 0).
    pub d_eff_err: Option<f64>,
    /// The refractory point mass q+ + q- at the held velocity (v_r, or
    /// spread as the random target), fine mesh; 0 without a refractory
    /// period. `p` is the continuous part only: Σ p Δv + this = 1.
    pub refractory_mass: f64,
    /// Its + and - parts (the paper's noise; 0 with a noise model, whose
    /// held masses per state are `noise.held`).
    pub refractory: [f64; 2],
    /// The point masses of the stationary law (docs/output-formats.md,
    /// "atoms"): the refractory mass at a point target v_r (exact on every
    /// mesh: its error is rounding), or the mass a noise state holds at
    /// v_r ([`crate::model::atoms`]); `p` is the density without them.
    pub atoms: Vec<VelocityAtom>,
    /// Stationary `<x>` under position resetting (extrapolated if
    /// `extrapolated`), else None.
    pub x_mean: Option<f64>,
    /// Stationary `<x²>` under position resetting, else None.
    pub x2: Option<f64>,
    /// Whether v_mean, v2, d_eff are Richardson-extrapolated.
    pub extrapolated: bool,
    /// Observables on the fine mesh.
    pub fine: Moments,
    /// Observables on the coarse mesh (when extrapolating).
    pub coarse: Option<Moments>,
    /// Observables on the mesh of cells/4 that checks the extrapolation
    /// (paper's noise, when extrapolating with cells >= 32; the N-state
    /// solver lists its meshes in `noise`).
    pub coarsest: Option<Moments>,
    /// With a noise model (the N-state solver, Eqs. (N20)-(N27)): the
    /// per-state densities, per-state means, error estimates and the
    /// domain; None for the paper's noise.
    pub noise: Option<NoiseSummary>,
}

/// The noise's state space as the stationary engine solves it: one mesh's
/// solution (`Self`) and the answer assembled from the nested meshes.
pub(crate) trait StationarySpace: Sized {
    /// With extrapolation `cells` is a multiple of this (the meshes nest)
    /// ...
    const NEST: usize;
    /// ... and the allowed range of `cells` says why.
    const NEST_RULE: &'static str;
    /// The space's numerical refusals (the capability module refuses the
    /// unsupported models at the entry).
    fn check(_: &Params) -> Result<()> {
        Ok(())
    }
    /// The meshes solved, as (cells, refinements), the fine mesh last.
    fn meshes(o: &StationaryOptions) -> Vec<(usize, usize)>;
    /// The stationary solution on the mesh of `n << refine` cells.
    fn solve(p: &Params, mesh: Mesh, n: usize, refine: usize) -> Result<Self>;
    /// The answer from the solutions on [`Self::meshes`] (in that order):
    /// extrapolation, error estimates, checks, densities.
    fn assemble(p: &Params, o: &StationaryOptions, sols: Vec<Self>) -> Result<Stationary>;
}

/// `cells` in range, a multiple of the space's nesting when extrapolating.
fn check_cells<S: StationarySpace>(o: &StationaryOptions) -> Result<()> {
    if !(MIN_CELLS..=MAX_CELLS).contains(&o.cells) {
        return Err(Error::invalid(
            "cells",
            o.cells,
            format!("{MIN_CELLS} <= cells <= {MAX_CELLS}"),
        ));
    }
    if o.extrapolate && o.cells % S::NEST != 0 {
        return Err(Error::invalid("cells", o.cells, S::NEST_RULE));
    }
    Ok(())
}

/// Solve the stationary forward equations directly (no time stepping).
///
/// The paper's noise runs the two-state space (`two_state`); a noise
/// model (`params.noise()` is Some) the chain (`chain`, Eqs.
/// (N20)-(N27)): N coupled densities, thermal noise, `noise` filled in and
/// `p_plus`, `p_minus` empty.
pub fn stationary(params: &Params, opts: &StationaryOptions) -> Result<Stationary> {
    params.require(Solver::FpStationary)?;
    match params.noise() {
        None => run::<two_state::TwoState>(params, opts),
        Some(_) => run::<chain::MeshSolution>(params, opts),
    }
}

/// The engine: options, the nested meshes' solutions, the answer.
fn run<S: StationarySpace>(params: &Params, opts: &StationaryOptions) -> Result<Stationary> {
    check_cells::<S>(opts)?;
    S::check(params)?;
    let sols = S::meshes(opts)
        .into_iter()
        .map(|(n, refine)| {
            crate::parallel::check_stop()?;
            S::solve(params, opts.mesh, n, refine)
        })
        .collect::<Result<Vec<_>>>()?;
    crate::parallel::check_stop()?;
    S::assemble(params, opts, sols)
}

impl Stationary {
    /// Cell masses P_i Δv_i (total over both states).
    pub fn cell_masses(&self) -> Vec<f64> {
        self.p
            .iter()
            .zip(&self.widths)
            .map(|(p, h)| p * h)
            .collect()
    }
}
