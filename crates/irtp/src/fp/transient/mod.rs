//! Time-dependent forward equations from the paper's initial condition
//! P±(v, 0) = ½ δ(v) on upwind finite volumes (no-flux edges): one
//! TR-BDF2 engine ([`integrate_levels`]) over the noise's state space
//! ([`TransientSpace`]), dispatched once at the entry, and the paper's
//! explicit scheme for the paper's noise:
//!
//! - [`Scheme::TrBdf2`] (default): the singularity-graded mesh of the
//!   stationary solver and adaptive TR-BDF2 time stepping (Bank et al., IEEE
//!   Trans. Electron Devices 32, 1985; as the ESDIRK of Hosea & Shampine,
//!   Appl. Numer. Math. 20, 1996; see [`crate::numerics::trbdf2`]) of the
//!   discrete generator of the space: the paper's two states
//!   ([`two_state`], [`crate::fp::ForwardOperator`]) or a finite-state chain
//!   with thermal noise ([`chain`], [`crate::fp::NoiseOperator`]). The
//!   method is L-stable, so the step is set by the requested accuracy
//!   (`rtol`, `atol` on the cell masses), not by the smallest cell; every
//!   stage is an exact O(N) solve. `<v>` and `<v²>` are
//!   Richardson-extrapolated over the nested meshes of N, N/2 and N/4
//!   cells (two states: twice, removing the 1/N and 1/N² terms of the
//!   first-order fluxes, with the change made by the second extrapolation
//!   plus the three-mesh bound on the first, Eq. (N27), reported as the
//!   error estimate; a chain: with the observed order,
//!   Eq. (N27)); the density is the fine mesh's.
//! - [`Scheme::Paper`]: the paper's way (Sec. 3): explicit upwind on a
//!   uniform mesh, the step set by the CFL limit (the paper's noise only).
//!
//! An exponential refractory period (docs/equations.md, (R7)) runs in
//! [`Scheme::TrBdf2`]: with the paper's noise the held pairs of
//! [`crate::fp::ForwardOperator`] are unknowns next to the cell masses,
//! with a noise model one held mass per noise state ([`chain`], (R10));
//! [`Transient::refractory_mass`] reports their mass; the paper scheme
//! refuses it.

mod chain;
mod two_state;

use super::grid::{Grid, Mesh};
use super::stationary::{MAX_CELLS, MIN_CELLS};
use crate::error::{finite, Error, Result};
use crate::model::reset::Solver;
use crate::model::{Drag, Params, VelocityAtom};
use crate::numerics::trbdf2::{self, ShiftedLinear, Stats, Tolerances};
use crate::parallel::{NoProgress, Progress};
use serde::{Deserialize, Serialize};

/// Time-stepping scheme of [`transient`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum Scheme {
    /// Graded mesh, adaptive TR-BDF2, Richardson-extrapolated moments.
    #[default]
    TrBdf2,
    /// The paper's explicit upwind scheme on a uniform mesh (Sec. 3).
    Paper,
}

impl Scheme {
    /// Name as typed on the command line.
    pub fn name(&self) -> &'static str {
        match self {
            Scheme::TrBdf2 => "trbdf2",
            Scheme::Paper => "paper",
        }
    }

    /// Mesh the scheme uses.
    pub fn mesh(&self) -> Mesh {
        match self {
            Scheme::TrBdf2 => Mesh::Graded,
            Scheme::Paper => Mesh::Uniform,
        }
    }
}

/// Options of [`transient`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TransientOptions {
    /// Time-stepping scheme (and with it the mesh).
    #[serde(default)]
    pub scheme: Scheme,
    /// Number of cells on (v_l, v_u): graded for [`Scheme::TrBdf2`] (a
    /// multiple of 4: the extrapolation uses the nested meshes of cells/2
    /// and cells/4), uniform for
    /// [`Scheme::Paper`] (paper: 2000 for tan, 1000 for tanh).
    pub cells: usize,
    /// Final time.
    pub t_max: f64,
    /// Times in [0, t_max] at which `<v>`, `<v²>` and the mass are recorded
    /// (empty: t_max only).
    pub times: Vec<f64>,
    /// Times in [0, t_max] at which the density P(v, t) is stored.
    pub snapshot_times: Vec<f64>,
    /// [`Scheme::Paper`]: Courant number in (0, 1]: dt = cfl / max_i (the
    /// outflow, flip and reset rates of cell i) ≤ cfl Δv / max|drift|.
    /// cfl ≤ 1 keeps every cell mass ≥ 0.
    pub cfl: f64,
    /// [`Scheme::TrBdf2`]: relative tolerance of the local error of the cell
    /// masses per step (global error ∝ rtol^(2/3)).
    #[serde(default = "default_rtol")]
    pub rtol: f64,
    /// [`Scheme::TrBdf2`]: absolute tolerance of the local error of the cell
    /// masses per step (the masses sum to 1).
    #[serde(default = "default_atol")]
    pub atol: f64,
}

/// Default [`TransientOptions::rtol`].
pub const DEFAULT_RTOL: f64 = 1e-6;
/// Default [`TransientOptions::atol`].
pub const DEFAULT_ATOL: f64 = 1e-10;

fn default_rtol() -> f64 {
    DEFAULT_RTOL
}

fn default_atol() -> f64 {
    DEFAULT_ATOL
}

impl Default for TransientOptions {
    fn default() -> Self {
        TransientOptions {
            scheme: Scheme::TrBdf2,
            cells: 2000,
            t_max: 10.0,
            times: Vec::new(),
            snapshot_times: Vec::new(),
            cfl: 0.5,
            rtol: DEFAULT_RTOL,
            atol: DEFAULT_ATOL,
        }
    }
}

impl TransientOptions {
    /// Options recording `<v²>` at `samples` equally spaced times in
    /// [0, t_max] and the density at `snapshots` equally spaced times in
    /// (0, t_max] (both grids end exactly at t_max), the other options from
    /// `base`. Validates `t_max` and `samples` here; [`transient`] validates
    /// the rest.
    pub fn sampled(t_max: f64, samples: usize, snapshots: usize, base: Self) -> Result<Self> {
        let times = crate::numerics::time_grid::TimeGrid::linear(t_max, samples)?
            .times()
            .to_vec();
        let snapshot_times =
            crate::numerics::grid::linspace(0.0, t_max, snapshots.saturating_add(1)).split_off(1);
        Ok(TransientOptions {
            t_max,
            times,
            snapshot_times,
            ..base
        })
    }
}

/// Density at one time.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Snapshot {
    /// Time.
    pub t: f64,
    /// Total density P(v, t) at the cell centres.
    pub p: Vec<f64>,
    /// + state density.
    pub p_plus: Vec<f64>,
    /// - state density.
    pub p_minus: Vec<f64>,
    /// With a noise model: the density of every state (then `p_plus`,
    /// `p_minus` are empty); empty for the paper's noise.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub states: Vec<Vec<f64>>,
    /// The point masses at this time ([`Transient::atoms`]); the densities
    /// above are without them.
    pub atoms: Vec<VelocityAtom>,
}

/// Result of [`transient`].
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Transient {
    /// Parameters.
    pub params: Params,
    /// Scheme used.
    pub scheme: Scheme,
    /// Mesh kind (graded for TR-BDF2, uniform for the paper's scheme).
    pub mesh: Mesh,
    /// Number of cells (of the fine mesh).
    pub cells: usize,
    /// Paper scheme: the time step (steps landing on a requested time are
    /// shortened). TR-BDF2: None (adaptive).
    pub dt: Option<f64>,
    /// Number of (accepted) steps taken, over the three meshes for TR-BDF2.
    pub steps: u64,
    /// TR-BDF2: rejected steps, over the three meshes (0 for the paper scheme).
    pub rejected: u64,
    /// Whether `v_mean` and `v2` are Richardson-extrapolated over the meshes
    /// of `cells`, `cells/2` and `cells/4` cells (TR-BDF2).
    pub extrapolated: bool,
    /// Cell centres.
    pub v: Vec<f64>,
    /// Recording times.
    pub times: Vec<f64>,
    /// `<v>(t)`.
    pub v_mean: Vec<f64>,
    /// `<v²>(t)` (paper Fig. 1).
    pub v2: Vec<f64>,
    /// TR-BDF2: estimated mesh error of `v2` at each time (the change made by
    /// the second Richardson extrapolation, see [`Transient::extrapolated`]);
    /// empty for the paper scheme.
    pub v2_mesh_error: Vec<f64>,
    /// Σ P Δv at the recording times (fine mesh), with the refractory mass.
    pub mass: Vec<f64>,
    /// The refractory (held) point mass q+ + q- at the recording times
    /// (fine mesh; docs/equations.md, (R1), (R7)), 0 without an exponential
    /// refractory period. `mass`, `v_mean` and `v2` include it, at the held
    /// velocities; the snapshots are the continuous part.
    pub refractory_mass: Vec<f64>,
    /// The point masses of the velocity law at each recording time (one
    /// list per time, the same velocities at every time, masses possibly
    /// 0): the refractory hold at a point target v_r (the fine mesh's held
    /// mass, error the change from the mesh of cells/2), and with a noise
    /// model at T = 0 the mass held at a state's fixed point (Eq. (N52):
    /// the reset target, or the start v = 0), extrapolated over the three
    /// meshes; masses at one velocity are one atom (their masses and
    /// errors added: the hold at v_r and a state's reset atom there). The
    /// snapshots' densities are without them, and the density
    /// mass plus the atoms is checked to be 1 at every time (refused
    /// otherwise). Empty lists where nothing holds the velocity. At t = 0
    /// the start's share in the states that move is in the cells of v = 0,
    /// not an atom.
    pub atoms: Vec<Vec<VelocityAtom>>,
    /// |Σ P Δv - 1|, maximum over every step (paper scheme) or over every
    /// recording and snapshot time of the three meshes (TR-BDF2).
    pub mass_error_max: f64,
    /// Density snapshots (fine mesh).
    pub snapshots: Vec<Snapshot>,
}

fn check_times(name: &'static str, ts: &[f64], t_max: f64) -> Result<Vec<f64>> {
    let mut out = Vec::with_capacity(ts.len());
    for &t in ts {
        let t = finite(name, t)?;
        if !(t >= 0.0 && t <= t_max) {
            return Err(Error::invalid(
                name,
                t,
                format!("0 <= t <= t_max = {t_max}"),
            ));
        }
        out.push(t);
    }
    out.sort_by(|a, b| a.total_cmp(b));
    out.dedup();
    Ok(out)
}

/// The time step and the number of steps of a run.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Plan {
    /// Paper scheme: the Courant number over the largest total outflow rate.
    /// TR-BDF2: None (adaptive).
    pub dt: Option<f64>,
    /// Paper scheme: steps to t_max. TR-BDF2: the estimated steps on the fine
    /// mesh, see [`trbdf2_step_bound`].
    pub steps: u64,
    /// Cell updates: cells × steps for the paper scheme;
    /// [`TRBDF2_UPDATES_PER_STEP`] × cells × steps × 1.75 (`mesh_work_factor`, the three meshes) for
    /// TR-BDF2.
    pub work: f64,
}

/// Cell updates per TR-BDF2 step and cell, counted as in the paper scheme's
/// explicit step (one update ~ 10 flops): a factorisation and 2 unit solves
/// for the shift, 3 solves, 3 operator applications and the vector updates.
pub const TRBDF2_UPDATES_PER_STEP: f64 = 12.0;

/// The step and step count [`transient`] will use (O(cells), no
/// integration): for estimating the cost before a run.
pub fn plan(params: &Params, opts: &TransientOptions) -> Result<Plan> {
    params.require(Solver::FpTransient)?;
    two_state::require_held(params, opts.scheme)?;
    let (times, snaps) = validate(opts)?;
    match opts.scheme {
        Scheme::Paper => two_state::plan_on(params, opts, &Grid::uniform(params, opts.cells)),
        Scheme::TrBdf2 => {
            let steps = trbdf2_step_bound(params, opts, merged(&times, &snaps).len());
            Ok(Plan {
                dt: None,
                steps,
                work: TRBDF2_UPDATES_PER_STEP
                    * mesh_work_factor()
                    * opts.cells as f64
                    * steps as f64,
            })
        }
    }
}

/// Estimated steps (accepted + rejected) of TR-BDF2 on the fine mesh: an
/// upper estimate from measurements, for the cost check before a run.
///
/// Each output time costs at most 4 steps (the step clipped to land on it
/// and the controller's recovery). In between, the step follows the moving
/// front of the initial delta through the cells (cell masses change on the
/// time scale Δv/Σ until flips and resets have smeared the front), so the
/// count grows with the mesh (measured ∝ cells^(1/2)), with the tolerances
/// (local error ∝ h³; measured ∝ (rtol atol)^(-1/6)) and, slowly, with the
/// number of relaxation times t_max (λ + r + g'(v_r) + 1). The estimate
///   4 outputs + 10 (rtol atol)^(-1/6) (cells/100)^(1/2) (1 + log10(1 + t_max rate))
/// exceeded the measured counts by a factor of 7 to 20 (tan Σ = 3 and
/// tanh Σ = 0.6 at λ = 0.5, r = 0 and 2, 200 to 1600 cells,
/// 1e-7 <= rtol <= 1e-4, 1e-14 <= atol <= 1e-8). The integrator is stopped
/// (numerical failure) at [`TRBDF2_STEP_CAP`] times the estimate.
///
/// With periodic resetting every reset time up to t_max is a further stop,
/// and each reset puts the mass back on a front at the target, started
/// afresh: each reset counts as one more output and one more front.
pub fn trbdf2_step_bound(params: &Params, opts: &TransientOptions, outputs: usize) -> u64 {
    let rate = 1.0 + params.lambda() + params.rate() + relaxation_rate(params);
    let decades = 1.0 + (opts.t_max * rate).ln_1p() / std::f64::consts::LN_10;
    let tol = (opts.rtol * opts.atol).powf(-1.0 / 6.0);
    let mesh = (opts.cells as f64 / 100.0).sqrt();
    let resets = params
        .schedule()
        .periodic
        .map_or(0.0, |p| (opts.t_max / p.period).floor().min(1e12));
    (4.0 * (outputs as f64 + resets) + 10.0 * tol * mesh * decades * (1.0 + resets))
        .ceil()
        .min(1e15) as u64
}

/// |g'(v_r)|, the rate at which the flow leaves the reset velocity; where
/// g' is infinite there (the power law with n < 1 at v_r = 0) the steepest
/// secant slope to the edge ([`Drag::euler_slope`], finite), the rate of
/// the flow across the cells around v_r.
fn relaxation_rate(params: &Params) -> f64 {
    let g1 = params.drag().derivative(params.reset_velocity()).abs();
    if g1.is_finite() {
        g1
    } else {
        params.drag().euler_slope(params.sigma())
    }
}

/// The TR-BDF2 integrator gives up after this many times the estimated
/// steps ([`trbdf2_step_bound`]) on one mesh.
pub const TRBDF2_STEP_CAP: u64 = 10;

/// Sorted union of the recording and snapshot times.
pub(crate) fn merged(times: &[f64], snaps: &[f64]) -> Vec<f64> {
    let mut all: Vec<f64> = times.iter().chain(snaps).copied().collect();
    all.sort_by(|a, b| a.total_cmp(b));
    all.dedup();
    all
}

/// Periodic resetting: the reset times kT (k = 1, 2, ..., counted as k T so
/// as not to drift, as in [`crate::analytic::linear_moments::moments`]) up
/// to the last recording or snapshot time; empty without
/// `--reset-period`. Steps land on them and the state is reset there,
/// before recording: a recording time at kT shows the state just after
/// the reset.
fn reset_times(params: &Params, times: &[f64], snaps: &[f64]) -> Vec<f64> {
    let last = times.iter().chain(snaps).copied().fold(0.0, f64::max);
    let Some(p) = params.schedule().periodic else {
        return Vec::new();
    };
    (1..)
        .map(|k| k as f64 * p.period)
        .take_while(|&t| t <= last)
        .collect()
}

/// Integrate the forward equations from the paper's initial condition.
pub fn transient(params: &Params, opts: &TransientOptions) -> Result<Transient> {
    transient_with_progress(params, opts, &NoProgress)
}

/// [`transient`] reporting steps done to `progress`: dispatched once, by
/// the noise's state space, to the paper's two states or a finite-state
/// chain with thermal noise.
pub fn transient_with_progress(
    params: &Params,
    opts: &TransientOptions,
    progress: &dyn Progress,
) -> Result<Transient> {
    let (times, snaps) = validate(opts)?;
    params.require(Solver::FpTransient)?;
    if params.noise().is_some() {
        let out = chain::transient(params, opts, &times, &snaps, progress)?;
        check_mass(&out)?;
        return Ok(out);
    }
    two_state::require_held(params, opts.scheme)?;
    let out = match opts.scheme {
        Scheme::Paper => two_state::paper(params, opts, &times, &snaps, progress),
        Scheme::TrBdf2 => two_state::trbdf2(params, opts, &times, &snaps, progress),
    }?;
    check_mass(&out)?;
    two_state::nonnegative(out)
}

/// The noise's state space as the time-stepping engine [`integrate_levels`]
/// sees it: the discrete generator of each nested mesh and what is
/// recorded of its state.
pub(super) trait TransientSpace {
    /// The discrete generator of one mesh.
    type Op: ShiftedLinear;
    /// The generator on mesh `level` (0: cells/4, [`MESH_LEVELS`] - 1:
    /// cells) and its initial state.
    fn mesh(&mut self, level: usize) -> Result<(Self::Op, Vec<f64>)>;
    /// A periodic reset of the state `u` of the current mesh.
    fn reset(&self, u: &mut [f64]);
    /// Record the state `u` of mesh `level` at the `k`-th output time.
    fn observe(&mut self, level: usize, k: usize, u: &[f64]) -> Result<()>;
}

/// TR-BDF2 on the [`MESH_LEVELS`] nested meshes of `space`, each from its
/// initial state to every time of `all` (sorted), recorded there by
/// [`TransientSpace::observe`]. With periodic resetting each mesh's run
/// is split at `resets` (hidden stops, see [`reset_times`]): each piece
/// is integrated from its start to the next reset, where the state is
/// reset and then recorded if asked. `progress` counts the outputs done
/// over the meshes. Returns the steps taken over the meshes.
pub(super) fn integrate_levels<S: TransientSpace>(
    space: &mut S,
    tol: &Tolerances,
    all: &[f64],
    resets: &[f64],
    progress: &dyn Progress,
) -> Result<Stats> {
    let total = (MESH_LEVELS * all.len()) as u64;
    let mut effort = Stats::default();
    for level in 0..MESH_LEVELS {
        let done = (level * all.len()) as u64;
        let mesh = integrate_mesh(space, level, tol, all, resets, |k| {
            report(progress, done + k, total)
        })?;
        effort.steps += mesh.steps;
        effort.rejected += mesh.rejected;
    }
    progress.update(total, total);
    Ok(effort)
}

/// One mesh of [`integrate_levels`]; `report(k)` after k outputs.
fn integrate_mesh<S: TransientSpace>(
    space: &mut S,
    level: usize,
    tol: &Tolerances,
    all: &[f64],
    resets: &[f64],
    mut report: impl FnMut(u64) -> Result<()>,
) -> Result<Stats> {
    let (mut op, mut u) = space.mesh(level)?;
    let mut effort = Stats::default();
    let mut done = 0u64;
    let mut observe = |space: &mut S, t: f64, u: &[f64]| -> Result<()> {
        let Ok(k) = all.binary_search_by(|x| x.total_cmp(&t)) else {
            return Ok(());
        };
        space.observe(level, k, u)?;
        done += 1;
        report(done)
    };
    // Pieces [t0, end): from 0 or a reset time to the next reset time (the
    // last piece to the last output); outputs at t0 are recorded at its
    // start, after the reset.
    let mut t0 = 0.0;
    let ends = resets.iter().map(|&e| Some(e)).chain([None]);
    for end in ends {
        observe(space, t0, &u)?;
        let mut stops: Vec<f64> = all
            .iter()
            .copied()
            .filter(|&s| s > t0 && end.map_or(true, |e| s < e))
            .collect();
        stops.extend(end);
        if !stops.is_empty() {
            let rel: Vec<f64> = stops.iter().map(|&s| s - t0).collect();
            let piece = Tolerances {
                max_steps: tol.max_steps.saturating_sub(effort.steps + effort.rejected),
                ..*tol
            };
            let stats = trbdf2::integrate(&mut op, &mut u, &rel, &piece, |k, _, u| {
                // The piece's end (a reset time) is recorded after the reset.
                match end {
                    Some(_) if k + 1 == stops.len() => Ok(()),
                    _ => observe(space, stops[k], u),
                }
            })?;
            effort.steps += stats.steps;
            effort.rejected += stats.rejected;
        }
        if let Some(e) = end {
            space.reset(&mut u);
            t0 = e;
        }
    }
    Ok(effort)
}

/// The total probability (cells and the held refractory mass) at every
/// recording time within [`MASS_TOLERANCE`] of 1: both schemes conserve it
/// to rounding, so a loss means the integration broke down (e.g. a
/// refractory period so short that its exit rate overwhelms the step), and
/// the answer is refused rather than returned.
fn check_mass(out: &Transient) -> Result<()> {
    for (t, m) in out.times.iter().zip(&out.mass) {
        if !((m - 1.0).abs() <= MASS_TOLERANCE) {
            return Err(Error::Numerical {
                method: "fp transient",
                reason: format!(
                    "the total probability at t = {t} is {m:e}, not 1 (tolerance {MASS_TOLERANCE:e}); \
                     the time integration lost mass"
                ),
            });
        }
    }
    Ok(())
}

/// How far the recorded total probability may be from 1.
pub const MASS_TOLERANCE: f64 = 1e-8;

/// Nested meshes of the TR-BDF2 scheme: cells/4, cells/2 and cells.
pub const MESH_LEVELS: usize = 3;

/// Cells of the [`MESH_LEVELS`] nested meshes N, N/2, N/4, ... in units of
/// N: 1 + 1/2 + 1/4 = 1.75.
fn mesh_work_factor() -> f64 {
    (0..MESH_LEVELS).map(|l| 0.5f64.powi(l as i32)).sum()
}

/// Report `steps` of `total` done; [`Error::Interrupted`] when the caller
/// asked to stop.
fn report(progress: &dyn Progress, steps: u64, total: u64) -> Result<()> {
    progress.update(steps.min(total), total);
    if progress.cancelled() {
        return Err(Error::Interrupted);
    }
    Ok(())
}

/// Check the options; returns the recording times (t_max when none) and
/// the snapshot times.
fn validate(opts: &TransientOptions) -> Result<(Vec<f64>, Vec<f64>)> {
    let n = opts.cells;
    if !(MIN_CELLS..=MAX_CELLS).contains(&n) {
        return Err(Error::invalid(
            "cells",
            n,
            format!("{MIN_CELLS} <= cells <= {MAX_CELLS}"),
        ));
    }
    let t_max = finite("t_max", opts.t_max)?;
    if !(t_max > 0.0) {
        return Err(Error::invalid("t_max", t_max, "t_max > 0"));
    }
    match opts.scheme {
        Scheme::Paper => {
            let cfl = finite("cfl", opts.cfl)?;
            if !(cfl > 0.0 && cfl <= 1.0) {
                return Err(Error::invalid("cfl", cfl, "0 < cfl <= 1"));
            }
        }
        Scheme::TrBdf2 => {
            if !(n % 4 == 0 && n / 4 >= MIN_CELLS) {
                return Err(Error::invalid(
                    "cells",
                    n,
                    format!(
                        "a multiple of 4, at least {} (TR-BDF2 extrapolates from the meshes of \
                         cells/2 and cells/4)",
                        4 * MIN_CELLS
                    ),
                ));
            }
            let rtol = finite("rtol", opts.rtol)?;
            if !(1e-13..=0.1).contains(&rtol) {
                return Err(Error::invalid("rtol", rtol, "1e-13 <= rtol <= 0.1"));
            }
            let atol = finite("atol", opts.atol)?;
            if !(1e-20..=0.1).contains(&atol) {
                return Err(Error::invalid("atol", atol, "1e-20 <= atol <= 0.1"));
            }
        }
    }
    let mut times = check_times("times", &opts.times, t_max)?;
    if times.is_empty() {
        times.push(t_max);
    }
    let snaps = check_times("snapshot_times", &opts.snapshot_times, t_max)?;
    Ok((times, snaps))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sampled_grids() {
        let o = TransientOptions::sampled(2.0, 5, 4, TransientOptions::default()).unwrap();
        assert_eq!(o.times, vec![0.0, 0.5, 1.0, 1.5, 2.0]);
        assert_eq!(o.snapshot_times, vec![0.5, 1.0, 1.5, 2.0]);
        // Both grids end exactly at t_max, also where t·n/n would round.
        let t = 0.1 + 0.2;
        let o = TransientOptions::sampled(t, 7, 3, TransientOptions::default()).unwrap();
        assert_eq!((o.times[6], o.snapshot_times[2]), (t, t));
        let o = TransientOptions::sampled(1.0, 2, 0, TransientOptions::default()).unwrap();
        assert!(o.snapshot_times.is_empty());
    }

    #[test]
    fn sampled_validates_t_max_then_samples() {
        let name = |r: Result<TransientOptions>| match r.unwrap_err() {
            Error::InvalidParameter { name, .. } => name,
            e => panic!("{e}"),
        };
        assert_eq!(
            name(TransientOptions::sampled(
                f64::NAN,
                1,
                1,
                TransientOptions::default()
            )),
            "t_max"
        );
        assert_eq!(
            name(TransientOptions::sampled(
                0.0,
                5,
                1,
                TransientOptions::default()
            )),
            "t_max"
        );
        assert_eq!(
            name(TransientOptions::sampled(
                1.0,
                1,
                1,
                TransientOptions::default()
            )),
            "samples"
        );
    }
}
