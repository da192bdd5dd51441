//! Time-dependent forward equations from the paper's initial condition
//! P±(v, 0) = ½ δ(v), two schemes on the same upwind finite volumes
//! (no-flux edges):
//!
//! - [`Scheme::TrBdf2`] (default): the singularity-graded mesh of the
//!   stationary solver and adaptive TR-BDF2 time stepping (Bank et al., IEEE
//!   Trans. Electron Devices 32, 1985; as the ESDIRK of Hosea & Shampine,
//!   Appl. Numer. Math. 20, 1996; see [`crate::numerics::trbdf2`]) of the
//!   discrete generator [`ForwardOperator`]. The method is L-stable, so the
//!   step is set by the requested accuracy (`rtol`, `atol` on the cell
//!   masses), not by the smallest cell; every stage is an exact O(N) solve.
//!   `<v>` and `<v²>` are Richardson-extrapolated twice over the nested
//!   meshes of N, N/2 and N/4 cells (removing the 1/N and 1/N² terms of the
//!   first-order fluxes), with the change made by the second extrapolation
//!   reported as the error estimate; the density is the fine mesh's.
//! - [`Scheme::Paper`]: the paper's way (Sec. 3): explicit upwind on a
//!   uniform mesh, the step set by the CFL limit.
//!
//! An exponential refractory period (docs/equations.md, (R7)) runs in
//! [`Scheme::TrBdf2`]: the held pairs of [`ForwardOperator`] are unknowns
//! next to the cell masses, and [`Transient::refractory_mass`] reports
//! their mass; the paper scheme refuses it.

use super::grid::{uniform_target, Grid, Mesh};
use super::operator::ForwardOperator;
use super::stationary::{MAX_CELLS, MIN_CELLS};
use crate::error::{finite, Error, Result};
use crate::model::reset::Reset;
use crate::model::reset::Solver;
use crate::model::{Drag, Params, VelocityAtom};
use crate::numerics::trbdf2::{self, Tolerances};
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
    /// meshes. The snapshots' densities are without them, and the density
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
    require_held(params, opts.scheme)?;
    let (times, snaps) = validate(opts)?;
    match opts.scheme {
        Scheme::Paper => plan_on(params, opts, &Grid::uniform(params, opts.cells)),
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

fn plan_on(params: &Params, opts: &TransientOptions, g: &Grid) -> Result<Plan> {
    let (lambda, r) = (params.lambda(), params.rate());
    let max_rate = (0..opts.cells)
        .map(|i| g.out_plus[i].max(g.out_minus[i]) + lambda + r)
        .fold(0.0, f64::max);
    let dt = opts.cfl / max_rate;
    let steps = (opts.t_max / dt).ceil();
    if !(steps <= 1e12) {
        return Err(Error::invalid(
            "t_max",
            opts.t_max,
            format!("t_max / dt <= 1e12 steps (dt = {dt:.3e})"),
        ));
    }
    Ok(Plan {
        dt: Some(dt),
        steps: steps as u64,
        work: opts.cells as f64 * steps,
    })
}

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

/// A periodic reset of the flat interleaved cell masses (m+_0, m-_0, ...):
/// all the mass of each noise state moves to the target (the reset cells of
/// a point target, spread by the target's cell masses for a random one),
/// the noise state kept or re-drawn by [`Grid::reinject`].
fn periodic_reset(g: &Grid, u: &mut [f64]) {
    let (mut a, mut b) = (0.0, 0.0);
    for c in u.chunks_exact_mut(2) {
        a += c[0];
        b += c[1];
        c.fill(0.0);
    }
    let (ip, im) = g.reinject(a, b);
    g.add_reset_flat(u, ip, im);
}

/// The exponential refractory period runs in [`Scheme::TrBdf2`] only (the
/// held pairs of [`ForwardOperator`]; with periodic resetting it is refused
/// before, by `capability::combination_runs`).
fn require_held(params: &Params, scheme: Scheme) -> Result<()> {
    let Some(r) = params.schedule().refractory else {
        return Ok(());
    };
    if scheme == Scheme::Paper {
        return Err(Error::invalid(
            "refractory",
            r.spec(),
            "none with --scheme paper (the refractory period runs in --scheme trbdf2)",
        ));
    }
    Ok(())
}

/// Integrate the forward equations from the paper's initial condition.
pub fn transient(params: &Params, opts: &TransientOptions) -> Result<Transient> {
    transient_with_progress(params, opts, &NoProgress)
}

/// [`transient`] reporting steps done to `progress`.
pub fn transient_with_progress(
    params: &Params,
    opts: &TransientOptions,
    progress: &dyn Progress,
) -> Result<Transient> {
    let (times, snaps) = validate(opts)?;
    params.require(Solver::FpTransient)?;
    if params.noise().is_some() {
        let out = super::nstate::transient(params, opts)?;
        check_mass(&out)?;
        return Ok(out);
    }
    require_held(params, opts.scheme)?;
    let out = match opts.scheme {
        Scheme::Paper => paper(params, opts, &times, &snaps, progress),
        Scheme::TrBdf2 => run_trbdf2(params, opts, &times, &snaps, progress),
    }?;
    check_mass(&out)?;
    nonnegative(out)
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

/// The snapshots' densities with the round-off negatives of the solves (at
/// most [`NEGATIVE_TOLERANCE`] of the snapshot's largest density in
/// magnitude) set to 0; a larger negative density means the integration
/// lost positivity (TR-BDF2's second stage has a right-hand side of mixed
/// sign), and the answer is refused.
fn nonnegative(mut out: Transient) -> Result<Transient> {
    for snap in &mut out.snapshots {
        let scale = snap.p.iter().fold(0.0f64, |a, &b| a.max(b.abs()));
        let floor = -NEGATIVE_TOLERANCE * scale;
        for col in [&mut snap.p_plus, &mut snap.p_minus] {
            if let Some(x) = col.iter().find(|&&x| !(x >= floor)) {
                return Err(Error::Numerical {
                    method: "fp transient",
                    reason: format!(
                        "a density of {x:e} at t = {} (largest {scale:e}): the time \
                         integration lost positivity; raise --cells or lower --rtol",
                        snap.t
                    ),
                });
            }
            col.iter_mut().filter(|x| **x < 0.0).for_each(|x| *x = 0.0);
        }
        for ((p, a), b) in snap.p.iter_mut().zip(&snap.p_plus).zip(&snap.p_minus) {
            *p = a + b;
        }
    }
    Ok(out)
}

/// How negative a snapshot's density may come out (relative to its largest
/// value) and still count as round-off, reported as 0.
pub const NEGATIVE_TOLERANCE: f64 = 1e-12;

/// How far the recorded total probability may be from 1.
pub const MASS_TOLERANCE: f64 = 1e-8;

/// The paper's explicit upwind scheme on a uniform mesh.
fn paper(
    params: &Params,
    opts: &TransientOptions,
    times: &[f64],
    snaps: &[f64],
    progress: &dyn Progress,
) -> Result<Transient> {
    let n = opts.cells;
    let g = Grid::uniform(params, n);
    let plan = plan_on(params, opts, &g)?;
    let (dt, total_steps) = (plan.dt.expect("explicit step"), plan.steps);
    let (lambda, r) = (params.lambda(), params.rate());

    let (vl, vu) = params.bounds();
    let (i0p, i0m) = uniform_target(n, vl, vu, 0.0);
    let mut m = vec![[0.0f64; 2]; n];
    m[i0p][0] += 0.5;
    m[i0m][1] += 0.5;
    let mut next = vec![[0.0f64; 2]; n];

    let mut out = Transient {
        params: *params,
        scheme: Scheme::Paper,
        mesh: Mesh::Uniform,
        cells: n,
        dt: Some(dt),
        steps: 0,
        rejected: 0,
        extrapolated: false,
        v: g.centres.clone(),
        times: Vec::with_capacity(times.len()),
        v_mean: Vec::with_capacity(times.len()),
        v2: Vec::with_capacity(times.len()),
        v2_mesh_error: Vec::new(),
        mass: Vec::with_capacity(times.len()),
        refractory_mass: Vec::with_capacity(times.len()),
        atoms: Vec::with_capacity(times.len()),
        mass_error_max: 0.0,
        snapshots: Vec::with_capacity(snaps.len()),
    };
    let resets = reset_times(params, times, snaps);
    let (mut ti, mut si) = (0usize, 0usize);
    let mut t = 0.0f64;
    let report_every = (total_steps / 200).max(1);
    for target in merged(&merged(times, snaps), &resets) {
        // Step to `target`, the last step shortened to land on it exactly.
        while t < target {
            let h = if t + dt >= target - 1e-9 * dt {
                target - t
            } else {
                dt
            };
            let err = step(&g, lambda, r, h, &m, &mut next);
            std::mem::swap(&mut m, &mut next);
            out.mass_error_max = out.mass_error_max.max(err);
            out.steps += 1;
            t = if h == dt { t + dt } else { target };
            if out.steps % report_every == 0 {
                report(progress, out.steps, total_steps)?;
            }
        }
        if resets.binary_search_by(|x| x.total_cmp(&t)).is_ok() {
            periodic_reset(&g, m.as_flattened_mut());
        }
        while ti < times.len() && times[ti] <= t {
            out.record_moments(times[ti], &m, &g.centres, n);
            ti += 1;
        }
        while si < snaps.len() && snaps[si] <= t {
            out.record_snapshot(snaps[si], &m, &g);
            si += 1;
        }
    }
    progress.update(total_steps, total_steps);
    Ok(out)
}

/// TR-BDF2 on the nested graded meshes of `cells/4`, `cells/2` and `cells`
/// cells; moments Richardson-extrapolated twice at t > 0 (see
/// [`extrapolate`]).
fn run_trbdf2(
    params: &Params,
    opts: &TransientOptions,
    times: &[f64],
    snaps: &[f64],
    progress: &dyn Progress,
) -> Result<Transient> {
    let all = merged(times, snaps);
    let bound = trbdf2_step_bound(params, opts, all.len());
    let tol = Tolerances {
        rtol: opts.rtol,
        atol: opts.atol,
        h0: None,
        h_max: f64::INFINITY,
        max_steps: usize::try_from(bound.saturating_mul(TRBDF2_STEP_CAP)).unwrap_or(usize::MAX),
    };
    let base = opts.cells / 4;
    // Progress: outputs done on the coarsest mesh, then on the finer ones.
    let total = (MESH_LEVELS * all.len()) as u64;
    let mut runs = Vec::with_capacity(MESH_LEVELS);
    for level in 0..MESH_LEVELS {
        let op = ForwardOperator::refined(params, Mesh::Graded, base, level)?;
        let done = level * all.len();
        runs.push(integrate_mesh(params, op, &tol, times, snaps, &all, |k| {
            report(progress, (done + k) as u64, total)
        })?);
    }
    progress.update(total, total);
    let fine = runs.pop().expect("three meshes").t;
    let (half, quarter) = (&runs[1].t, &runs[0].t);
    let (v2, v2_mesh_error) = extrapolate(times, &fine.v2, &half.v2, &quarter.v2);
    check_resolved(params, times, &v2)?;
    Ok(Transient {
        params: *params,
        scheme: Scheme::TrBdf2,
        mesh: Mesh::Graded,
        cells: opts.cells,
        dt: None,
        steps: fine.steps + half.steps + quarter.steps,
        rejected: fine.rejected + half.rejected + quarter.rejected,
        extrapolated: true,
        v: fine.v,
        times: times.to_vec(),
        v_mean: extrapolate(times, &fine.v_mean, &half.v_mean, &quarter.v_mean).0,
        v2,
        v2_mesh_error,
        mass: fine.mass,
        refractory_mass: fine.refractory_mass,
        atoms: held_errors(fine.atoms, &half.atoms),
        mass_error_max: fine
            .mass_error_max
            .max(half.mass_error_max)
            .max(quarter.mass_error_max),
        snapshots: fine
            .snapshots
            .into_iter()
            .zip(&half.snapshots)
            .map(|(s, h)| Snapshot {
                atoms: held_errors(vec![s.atoms], std::slice::from_ref(&h.atoms)).remove(0),
                ..s
            })
            .collect(),
    })
}

/// The refractory atoms of the fine mesh with their error estimates: the
/// change from the mesh of cells/2 (as the stationary solver's), at least
/// 1e-14 of the mass.
fn held_errors(fine: Vec<Vec<VelocityAtom>>, half: &[Vec<VelocityAtom>]) -> Vec<Vec<VelocityAtom>> {
    fine.into_iter()
        .zip(half)
        .map(|(f, h)| {
            f.into_iter()
                .zip(h)
                .map(|(a, b)| VelocityAtom {
                    err: (a.mass - b.mass).abs().max(1e-14 * a.mass),
                    ..a
                })
                .collect()
        })
        .collect()
}

/// Nested meshes of the TR-BDF2 scheme: cells/4, cells/2 and cells.
pub const MESH_LEVELS: usize = 3;

/// Cells of the [`MESH_LEVELS`] nested meshes N, N/2, N/4, ... in units of
/// N: 1 + 1/2 + 1/4 = 1.75.
fn mesh_work_factor() -> f64 {
    (0..MESH_LEVELS).map(|l| 0.5f64.powi(l as i32)).sum()
}

/// Moments on the nested meshes of N, N/2 and N/4 cells, extrapolated twice:
/// the upwind fluxes are first order, X_N = X + a/N + b/N² + ..., so
/// X₂ = 2 X_N - X_{N/2} removes the 1/N term and
/// X₃ = (4 X₂(N) - X₂(N/2)) / 3 = (8 X_N - 6 X_{N/2} + X_{N/4}) / 3 the 1/N²
/// term. Returns X₃ and the estimate of its error |X₃ - X₂(N)| (the change
/// made by the second extrapolation, an upper estimate where the expansion
/// holds).
///
/// At t = 0 the moments are those of the initial delta placed in a cell
/// (O(Δv²), not a first-order mesh error): reported from the fine mesh, not
/// extrapolated (2 X_N - X_{N/2} would give <v²> = -Δv²/2 < 0 there). The
/// same holds while the front of the delta has crossed few cells; an
/// extrapolated <v²> outside its range there is refused by
/// [`check_resolved`].
fn extrapolate(times: &[f64], n: &[f64], half: &[f64], quarter: &[f64]) -> (Vec<f64>, Vec<f64>) {
    times
        .iter()
        .enumerate()
        .map(|(k, &t)| {
            if t > 0.0 {
                let x2 = 2.0 * n[k] - half[k];
                let x3 = (8.0 * n[k] - 6.0 * half[k] + quarter[k]) / 3.0;
                (x3, (x3 - x2).abs())
            } else {
                (n[k], 0.0)
            }
        })
        .unzip()
}

/// 0 <= <v²>(t) <= max(v_l², v_u²) for the extrapolated values, or the
/// answer is refused (as the stationary solver does): a violation means the
/// meshes do not resolve the density (e.g. a peak narrower than a cell at
/// fast flips), where Richardson extrapolation is not valid.
fn check_resolved(params: &Params, times: &[f64], v2: &[f64]) -> Result<()> {
    let (lo, hi) = params.bounds();
    let v2_max = lo.powi(2).max(hi.powi(2));
    match v2.iter().position(|&x| !(x >= 0.0 && x <= v2_max)) {
        None => Ok(()),
        Some(k) => Err(Error::Numerical {
            method: "fp transient (TR-BDF2)",
            reason: format!(
                "extrapolated <v^2>(t = {}) = {:e} outside [0, {v2_max:e}]: the mesh does not \
                 resolve the density at lambda = {}, rate = {} (at early times: the initial \
                 delta has crossed few cells); refused (use more --cells or later times)",
                times[k],
                v2[k],
                params.lambda(),
                params.rate()
            ),
        }),
    }
}

/// One mesh's run.
struct MeshRun {
    t: Transient,
}

/// One mesh's TR-BDF2 run from the paper's initial condition: moments at
/// `times`, densities at `snaps` (`all`: their sorted union). With periodic
/// resetting the run is split at the reset times (hidden stops, see
/// [`reset_times`]): each piece is integrated from its start to the next
/// reset, where the state is reset and then recorded if asked.
fn integrate_mesh(
    params: &Params,
    mut op: ForwardOperator,
    tol: &Tolerances,
    times: &[f64],
    snaps: &[f64],
    all: &[f64],
    mut report: impl FnMut(usize) -> Result<()>,
) -> Result<MeshRun> {
    let mut u = op.point_mass(0.0);
    let mut out = Transient {
        params: *params,
        scheme: Scheme::TrBdf2,
        mesh: Mesh::Graded,
        cells: op.cells(),
        dt: None,
        steps: 0,
        rejected: 0,
        extrapolated: false,
        v: op.centres().to_vec(),
        times: Vec::with_capacity(times.len()),
        v_mean: Vec::with_capacity(times.len()),
        v2: Vec::with_capacity(times.len()),
        v2_mesh_error: Vec::new(),
        mass: Vec::with_capacity(times.len()),
        refractory_mass: Vec::with_capacity(times.len()),
        atoms: Vec::with_capacity(times.len()),
        mass_error_max: 0.0,
        snapshots: Vec::with_capacity(snaps.len()),
    };
    let g = op.grid().clone();
    // The velocity of each (cell or held) pair of unknowns.
    let pair_v: Vec<f64> = op.velocities().iter().step_by(2).copied().collect();
    let resets = reset_times(params, times, snaps);
    let mut done = 0usize;
    let mut observe = |t: f64, u: &[f64], out: &mut Transient| -> Result<()> {
        if all.binary_search_by(|x| x.total_cmp(&t)).is_err() {
            return Ok(());
        }
        let m: Vec<[f64; 2]> = u.chunks_exact(2).map(|c| [c[0], c[1]]).collect();
        let mass: f64 = u.iter().sum();
        out.mass_error_max = out.mass_error_max.max((mass - 1.0).abs());
        if times.binary_search_by(|x| x.total_cmp(&t)).is_ok() {
            out.record_moments(t, &m, &pair_v, g.cells());
        }
        if snaps.binary_search_by(|x| x.total_cmp(&t)).is_ok() {
            out.record_snapshot(t, &m, &g);
        }
        done += 1;
        report(done)
    };
    // Pieces [t0, end): from 0 or a reset time to the next reset time (the
    // last piece to the last output); outputs at t0 are recorded at its
    // start, after the reset.
    let mut t0 = 0.0;
    let ends = resets.iter().map(|&e| Some(e)).chain([None]);
    for end in ends {
        observe(t0, &u, &mut out)?;
        let mut stops: Vec<f64> = all
            .iter()
            .copied()
            .filter(|&s| s > t0 && end.map_or(true, |e| s < e))
            .collect();
        stops.extend(end);
        if !stops.is_empty() {
            let rel: Vec<f64> = stops.iter().map(|&s| s - t0).collect();
            let piece = Tolerances {
                max_steps: tol
                    .max_steps
                    .saturating_sub((out.steps + out.rejected) as usize),
                ..*tol
            };
            let stats = trbdf2::integrate(&mut op, &mut u, &rel, &piece, |k, _, u| {
                // The piece's end (a reset time) is recorded after the reset.
                match end {
                    Some(_) if k + 1 == stops.len() => Ok(()),
                    _ => observe(stops[k], u, &mut out),
                }
            })?;
            out.steps += stats.steps as u64;
            out.rejected += stats.rejected as u64;
        }
        if let Some(e) = end {
            periodic_reset(&g, &mut u);
            t0 = e;
        }
    }
    Ok(MeshRun { t: out })
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

impl Transient {
    /// Record mass, `<v>` and `<v²>` of the pairs `m` (the cell masses,
    /// then from index `cells` on the held pairs) at velocities `v` at time
    /// t, and the held mass.
    fn record_moments(&mut self, t: f64, m: &[[f64; 2]], v: &[f64], cells: usize) {
        let (mut s0, mut s1, mut s2) = (0.0, 0.0, 0.0);
        for (c, &v) in m.iter().zip(v) {
            let w = c[0] + c[1];
            s0 += w;
            s1 += w * v;
            s2 += w * v * v;
        }
        self.times.push(t);
        self.mass.push(s0);
        let held: f64 = m[cells..].iter().map(|c| c[0] + c[1]).sum();
        self.refractory_mass.push(held);
        self.atoms.push(self.held_atoms(held));
        self.v_mean.push(s1);
        self.v2.push(s2);
    }

    /// Record the densities P, P+ and P- of the cell masses `m` at time t.
    fn record_snapshot(&mut self, t: f64, m: &[[f64; 2]], g: &Grid) {
        let pp: Vec<f64> = m.iter().zip(&g.widths).map(|(c, h)| c[0] / h).collect();
        let pm: Vec<f64> = m.iter().zip(&g.widths).map(|(c, h)| c[1] / h).collect();
        self.snapshots.push(Snapshot {
            t,
            p: pp.iter().zip(&pm).map(|(a, b)| a + b).collect(),
            p_plus: pp,
            p_minus: pm,
            states: Vec::new(),
            atoms: self.held_atoms(m[g.cells()..].iter().map(|c| c[0] + c[1]).sum()),
        });
    }

    /// The refractory hold at a point target v_r as an atom of mass `held`
    /// (error set by [`held_errors`]); none without an exponential
    /// refractory period or with a random target (its held mass is spread
    /// over the target's cells' velocities).
    fn held_atoms(&self, held: f64) -> Vec<VelocityAtom> {
        match (
            self.params.schedule().refractory,
            self.params.reset().point(),
        ) {
            (Some(_), Some(v)) => vec![VelocityAtom {
                v,
                mass: held,
                err: 0.0,
            }],
            _ => Vec::new(),
        }
    }
}

/// One explicit step in conservative form: every transfer (flux through an
/// edge, flip, reset) is subtracted from one cell and added to another, so the
/// total mass changes by rounding only. Returns |Σ m - 1| after the step.
fn step(g: &Grid, lambda: f64, r: f64, h: f64, m: &[[f64; 2]], next: &mut [[f64; 2]]) -> f64 {
    let n = m.len();
    let (al, be) = (&g.out_plus, &g.out_minus);
    let (mut reset_p, mut reset_m) = (0.0, 0.0);
    let mut in_p = 0.0; // + flux entering cell i from i-1
    let mut out_m_next = h * be[0] * m[0][1]; // - flux leaving cell i leftwards
    for i in 0..n {
        let [mp, mm] = m[i];
        let op = h * al[i] * mp;
        let om = out_m_next;
        let in_m = if i + 1 < n {
            out_m_next = h * be[i + 1] * m[i + 1][1];
            out_m_next
        } else {
            0.0
        };
        let fl = h * lambda * (mm - mp);
        let (rp, rm) = (h * r * mp, h * r * mm);
        reset_p += rp;
        reset_m += rm;
        next[i] = [mp - op - rp + fl + in_p, mm - om - rm - fl + in_m];
        in_p = op;
    }
    let (ip, im) = g.reinject(reset_p, reset_m);
    g.add_reset(next, ip, im);
    let total: f64 = next.iter().map(|c| c[0] + c[1]).sum();
    (total - 1.0).abs()
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
