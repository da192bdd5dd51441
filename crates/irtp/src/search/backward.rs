//! Mean first-passage time to a position target from the 2-D backward
//! equation (docs/equations.md, "Search: the 2-D backward equation and the
//! renewal route").
//!
//! `L T = -1` for T(x, v, ±) with the generator
//! `L f = v ∂x f + (eta - g(v)) ∂v f + lambda [f(x, v, -eta) - f] + R f`,
//! R the reset term: `r [f(x_r, v_r, eta') - f]` for full resetting,
//! `r [f(x, v_r, eta') - f]` for velocity-only resetting (eta' = eta kept,
//! or averaged over ± when re-drawn; a random target's law replaces v_r by
//! an average over it, on the mesh by hat-function node weights). T = 0
//! where x leaves through the
//! target with v pointing out; no condition at the velocity edges (the
//! state whose drift vanishes there has no v-derivative term); a one-sided
//! level is truncated at distance X on the far side, zero gradient there.
//!
//! A finite-state noise model at temperature 0 (Eq. (S12)) runs the same
//! code with N states per node: levels a_s for ±Sigma, the jumps Q_ss' for
//! the flips, and tau = Σ_s π_s T(x0, v0, s) (the state at the start drawn
//! from the stationary law π; the paper's noise: (tau+ + tau-)/2). Its
//! per-state values are `tau_states` (`tau_plus`, `tau_minus` are NaN).
//!
//! An exponential refractory period of mean M with a point reset velocity
//! (docs/equations.md, (S13)) adds a held value T_h(x, s) per x node and
//! noise state:
//! `v_r ∂x T_h + Σ_s' Q_ss' (T_h(s') - T_h(s)) + (T(x, v_r, s) - T_h(s)) / M = -1`
//! (x moves at v_r while held, resets are off, the noise jumps on),
//! upwinded at v_r (algebraic for v_r = 0); a reset leads to T_h at x_r
//! (full resetting) or at x, not to (x, v_r).
//!
//! Discretisation: first-order upwind in x and v on the mesh of
//! `search::mesh` (a Markov generator: the matrix `r I - A` is an M-matrix,
//! so T ≥ 0 and the mean speed bound T ≥ distance / v_u hold exactly on
//! the mesh), one banded LU ([`crate::numerics::band`], 2 n_v sub- and
//! super-diagonals). Full resetting couples every row to the two values
//! T(x_r, v_r, ±) (weighted means over a random target): superposition `T = U + T_r(+) W+ + T_r(-) W-` (three
//! solves with one factorisation) and a 2×2 self-consistency. Velocity-only
//! resetting stays inside the band (same x-column). Answers on the meshes h
//! and h/2 are extrapolated (first order: `2 T_{h/2} - T_h`), and a
//! truncated domain is solved again at 1.5 X; both differences are reported
//! (the second as a bound, see `truncation_factor`). The mesh error
//! estimate |T_{h/2} - T_h| is that of T_{h/2}: for the extrapolated value
//! it is conservative (measured 5-15× in the tests, whose extrapolated
//! values converge at about second order).
//!
//! Use (a front end checks [`estimate`] against its budget first; `solve`
//! refuses above the budgets of its options in any case):
//!
//! ```
//! use irtp::model::reset::Schedule;
//! use irtp::search::backward::{self, BackwardOptions};
//! use irtp::search::renewal::{self, RenewalOptions, WaitingTime};
//! use irtp::search::{PositionTarget, SearchProblem};
//! use irtp::{DragLaw, Params};
//!
//! // Full resetting to (x_r, v_r) = (0, 0) at rate 0.3, noise state kept.
//! let schedule = Schedule::parse(None, Some(0.0), None)?;
//! let p = Params::new(DragLaw::Linear, 1.0, 0.5, 0.3, 0.0)?.with_schedule(schedule)?;
//! let problem = SearchProblem::new(p.clone(), 0.0, 0.0, PositionTarget::Level(1.0))?;
//! let opts = BackwardOptions::with_cells(16, 8);
//! let cost = backward::estimate(&problem, &opts)?;
//! assert!(cost.work < 1e9);
//! let direct = backward::solve(&problem, &opts)?;
//! let ropts = RenewalOptions { cells_x: 16, cells_v: 8, ..Default::default() };
//! let renewed = renewal::solve(&problem, &WaitingTime::of(&p)?, &ropts)?;
//! assert!((direct.tau - renewed.tau).abs() <= direct.error_estimate + renewed.error_estimate);
//! # Ok::<(), irtp::Error>(())
//! ```

use super::mesh::{Generator, Hold, Layout, LocalReset, Mesh, Noise, Side};
use super::{yes, PositionTarget, SearchProblem};
use crate::error::{Error, Result};
use crate::model::reset::{NoiseAtReset, Refractory, Reset};
use crate::model::Drag;
use crate::numerics::band::Band;
use crate::numerics::bordered::Capacitance;
use crate::parallel::{NoProgress, Progress};
use crate::Params;
use serde::{Deserialize, Serialize};
use std::cell::Cell;

/// Options of the direct (backward) search solver.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct BackwardOptions {
    /// Cells of the coarse mesh across the near part of x (from the lowest
    /// to the highest of start, reset position and target ends); the far
    /// stretch of a truncated side adds cells of the same size next to it,
    /// growing geometrically.
    pub cells_x: usize,
    /// Cells of the coarse mesh on (v_l, v_u).
    pub cells_v: usize,
    /// Solve on the mesh halved too and extrapolate (Richardson); without
    /// it the coarse answer is returned and the mesh error is NaN.
    pub refine: bool,
    /// With `refine`: a mesh sequence that is not asymptotic (the check
    /// of `asymptotic` on three meshes) is refined a level at a time
    /// within the budgets, else refused (exit 4, naming the mesh flags).
    /// Without it nothing is refined: such an answer comes back with
    /// `asymptotic` false and its error NaN (a scan's unresolved point,
    /// the optimiser's solves that locate r*).
    #[serde(default = "yes")]
    pub climb: bool,
    /// Truncation tolerance of a one-sided level: the far side is cut at
    /// X = v_u ln(1/tol) / r (the chance of travelling X before a reset is
    /// below tol); checked by a solve at 1.5 X.
    pub truncation: f64,
    /// Refuse a solve estimated above this many floating-point operations.
    pub max_work: f64,
    /// Refuse a solve estimated above this many bytes.
    pub max_memory: f64,
}

impl Default for BackwardOptions {
    fn default() -> Self {
        BackwardOptions {
            cells_x: 64,
            cells_v: 32,
            refine: true,
            climb: true,
            truncation: 1e-8,
            max_work: 1e11,
            max_memory: 4e9,
        }
    }
}

impl BackwardOptions {
    /// Options with the given coarse mesh.
    pub fn with_cells(cells_x: usize, cells_v: usize) -> Self {
        BackwardOptions {
            cells_x,
            cells_v,
            ..Default::default()
        }
    }

    /// 2 ≤ cells ≤ 10⁵ each, 0 < truncation < 1, positive budgets.
    pub fn validate(&self) -> Result<()> {
        for (name, c) in [("cells_x", self.cells_x), ("cells_v", self.cells_v)] {
            if !(2..=100_000).contains(&c) {
                return Err(Error::invalid(name, c, format!("2 <= {name} <= 100000")));
            }
        }
        if !(self.truncation > 0.0 && self.truncation < 1.0) {
            return Err(Error::invalid(
                "truncation",
                self.truncation,
                "0 < truncation < 1",
            ));
        }
        for (name, b) in [("max_work", self.max_work), ("max_memory", self.max_memory)] {
            if !(b > 0.0) {
                return Err(Error::invalid(name, b, "a positive budget"));
            }
        }
        Ok(())
    }
}

/// The mesh a search answer came from.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct MeshInfo {
    /// x nodes of the finest mesh solved.
    pub nodes_x: usize,
    /// v nodes of the finest mesh solved.
    pub nodes_v: usize,
    /// Unknowns of the finest mesh (N n_x n_v for N noise states; N n_x
    /// (n_v + 1) with an exponential refractory period).
    pub unknowns: usize,
    /// Sub- and super-diagonals of its band matrix.
    pub band: usize,
    /// The x-domain solved: [x_min, x_max] (a truncated side at distance X).
    pub x_min: f64,
    /// Upper end of the x-domain.
    pub x_max: f64,
}

/// Mean first-passage time to the position target.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SearchSolution {
    /// tau = Σ_s π_s T(x0, v0, s): the noise state at the start drawn from
    /// the stationary law π (the paper's noise: (tau+ + tau-)/2).
    pub tau: f64,
    /// Start in the +Sigma state (the paper's noise; NaN for another noise
    /// model: see `tau_states`).
    pub tau_plus: f64,
    /// Start in the -Sigma state (the paper's noise; NaN for another noise
    /// model: see `tau_states`).
    pub tau_minus: f64,
    /// T(x0, v0, s) for each state s of a noise model other than the
    /// paper's, in the model's state order (extrapolated like tau); absent
    /// for the paper's noise.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub tau_states: Option<Vec<f64>>,
    /// Error estimate of tau: mesh plus truncation (NaN without
    /// refinement).
    pub error_estimate: f64,
    /// |T_{h/2} - T_h| of tau (NaN without refinement).
    pub mesh_error: f64,
    /// |T_{1.5X} - T_X| / (1 - √truncation) of tau on the coarse mesh
    /// (0 without truncation): a bound on the truncation error of T_X
    /// (the far field decays at least like e^{-r X / v_u}).
    pub truncation_error: f64,
    /// T(x_r, v_r, ±) for full resetting (extrapolated like tau; with an
    /// exponential refractory period the held T_h(x_r, ±) at the start of
    /// a hold, (S13)); None for a noise model other than the paper's (see
    /// `reset_states`).
    pub reset_values: Option<[f64; 2]>,
    /// T(x_r, v_r, s) for each state s of a noise model other than the
    /// paper's with full resetting; absent otherwise.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reset_states: Option<Vec<f64>>,
    /// The finest mesh.
    pub mesh: MeshInfo,
    /// The mean search time is infinite
    /// ([`SearchProblem::infinite_mean_reason`]): tau = +∞, nothing solved.
    #[serde(default)]
    pub infinite_mean: bool,
    /// The last three meshes passed the check of `asymptotic` (false
    /// only without `climb`: then the error estimate is NaN).
    #[serde(default = "yes")]
    pub asymptotic: bool,
    /// Floating-point operations done (band factorisations and solves,
    /// counted by [`crate::numerics::band::work_done`]): the measure the
    /// cost estimate ([`estimate`]) predicts.
    #[serde(default)]
    pub work: f64,
}

impl MeshInfo {
    /// No mesh: nothing was solved (an infinite mean).
    pub fn none() -> Self {
        MeshInfo {
            nodes_x: 0,
            nodes_v: 0,
            unknowns: 0,
            band: 0,
            x_min: f64::NAN,
            x_max: f64::NAN,
        }
    }
}

impl SearchSolution {
    /// The answer of a problem whose mean is infinite: tau = +∞, errors NaN.
    fn infinite() -> Self {
        let inf = f64::INFINITY;
        SearchSolution {
            tau: inf,
            tau_plus: inf,
            tau_minus: inf,
            tau_states: None,
            error_estimate: f64::NAN,
            mesh_error: f64::NAN,
            truncation_error: f64::NAN,
            reset_values: Some([inf; 2]),
            reset_states: None,
            mesh: MeshInfo::none(),
            infinite_mean: true,
            asymptotic: true,
            work: 0.0,
        }
    }
}

/// The work and memory a solve is estimated to need.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Cost {
    /// Floating-point operations (band factorisations and solves, all meshes).
    pub work: f64,
    /// Bytes at the peak (the finest band matrix and its vectors).
    pub memory: f64,
}

impl Cost {
    /// Nothing to solve (an infinite mean is reported without a solve).
    pub const NOTHING: Cost = Cost {
        work: 0.0,
        memory: 0.0,
    };
}

/// How resets act on the search, from the parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Resetting {
    /// No resets (r = 0 and no period).
    None,
    /// x → x_r and v → v_r.
    Full {
        /// Reset position.
        x: f64,
        /// Reset velocity.
        v: f64,
    },
    /// v → v_r, x kept.
    Velocity {
        /// Reset velocity.
        v: f64,
    },
}

/// A validated, solver-ready description of a search problem.
#[derive(Clone, Debug)]
pub(crate) struct Setup {
    pub params: Params,
    pub x0: f64,
    pub v0: f64,
    pub resetting: Resetting,
    /// The noise: levels, generator, stationary law (N states).
    pub noise: Noise,
    /// mix[s][s']: chance of state s' after a reset from state s (N × N:
    /// the identity when kept, every row π when re-drawn).
    pub mix: Vec<Vec<f64>>,
    pub sides: (Side, Side),
    /// x breakpoints of the near part.
    pub near: Vec<f64>,
    /// Distance from x0 to the nearest exit.
    pub distance: f64,
    /// An exponential refractory hold at the point target v_r ((S13)), or
    /// None.
    pub hold: Option<Hold>,
}

impl Setup {
    /// Check what the search solvers run: the noise and the protocol the
    /// method runs ([`crate::capability::check`]; an exponential refractory
    /// period with a point target only); a finite mean. `renewal`: full
    /// resetting required, any clock (the renewal route takes its
    /// waiting-time law separately); otherwise a Poisson clock only.
    pub fn new(problem: &SearchProblem, method: &str, renewal: bool) -> Result<Setup> {
        // The noise and the protocol the method runs (crate::capability).
        match super::solver_of(method) {
            Some(solver) => crate::capability::check(solver, problem.params())?,
            None => super::noise_gate(problem, method)?,
        }
        let p = problem.params().clone();
        let s = p.schedule();
        // A random target enters through its node weights; meshes put a
        // node at its centre.
        let vr = p.reset_velocity();
        if let (None, true) = (s.position, renewal) {
            return Err(Error::invalid(
                "reset_position",
                "none",
                format!("a reset position (full resetting) for {method}: only full resetting renews the search"),
            ));
        }
        let resets = renewal || p.rate() > 0.0 || s.scheduled_clock();
        let resetting = match (resets, s.position) {
            (false, _) => Resetting::None,
            (true, Some(x)) => Resetting::Full { x: x.x, v: vr },
            (true, None) => Resetting::Velocity { v: vr },
        };
        refuse_infinite(problem, resetting)?;
        let hold = match s.refractory {
            Some(Refractory::Exp { mean }) => Some(Hold {
                kappa: 1.0 / mean,
                v: p.point_target(&format!("an exponential refractory period in {method}"))?,
            }),
            _ => None,
        };
        let noise = Noise::of(&p, method)?;
        let n = noise.states();
        let mix = match p.reset().noise() {
            NoiseAtReset::Kept => (0..n)
                .map(|s| (0..n).map(|t| if s == t { 1.0 } else { 0.0 }).collect())
                .collect(),
            NoiseAtReset::Redrawn => vec![noise.pi.clone(); n],
        };
        let (x0, v0) = (problem.x0(), problem.v0());
        let mut near = vec![x0];
        if let Resetting::Full { x, .. } = resetting {
            near.push(x);
        }
        let (sides, distance) = match problem.target() {
            PositionTarget::Level(l) if l > x0 => ((Side::Truncated, Side::Target), l - x0),
            PositionTarget::Level(l) => ((Side::Target, Side::Truncated), x0 - l),
            PositionTarget::Interval(a, b) => ((Side::Target, Side::Target), (x0 - a).min(b - x0)),
        };
        match problem.target() {
            PositionTarget::Level(l) => near.push(l),
            PositionTarget::Interval(a, b) => near.extend([a, b]),
        }
        Ok(Setup {
            params: p,
            x0,
            v0,
            resetting,
            noise,
            mix,
            sides,
            near,
            distance,
            hold,
        })
    }

    /// The velocities that must be nodes: 0 (where v changes sign at the
    /// target), v_0, v_r, and with a noise model other than the paper's
    /// each level's fixed point v*_s = g⁻¹(a_s) inside (v_l, v_u) (where
    /// that state's drift changes sign; the paper's fixed points are the
    /// edges v_l, v_u).
    pub fn v_points(&self) -> Vec<f64> {
        let mut v = vec![0.0, self.v0];
        match self.resetting {
            Resetting::Full { v: vr, .. } | Resetting::Velocity { v: vr } => v.push(vr),
            Resetting::None => {}
        }
        if self.params.noise().is_some() {
            let (vl, vu) = self.params.bounds();
            let drag = self.params.drag();
            let fixed = self.noise.levels.iter().map(|&a| drag.inverse(a));
            v.extend(fixed.filter(|&w| w > vl && w < vu));
        }
        v
    }

    /// Whether the x-domain has a truncated side.
    pub fn truncated(&self) -> bool {
        self.sides.0 == Side::Truncated || self.sides.1 == Side::Truncated
    }

    /// The mesh layout with a far stretch of length `extent` on the scale
    /// of the far field's decay, v_u / √(r_e (2 lambda + r_e)) (r_e: the
    /// reset rate, or 1/T for a period; lambda: the noise's mean jump rate
    /// [`Noise::rate`], the paper's flip rate).
    pub fn layout(&self, cells: (usize, usize), extent: f64) -> Layout {
        let p = &self.params;
        let re = match p.schedule().periodic {
            Some(t) => 1.0 / t.period,
            None => p.rate(),
        };
        let scale = (p.v_upper() / (re * (2.0 * self.noise.rate + re)).sqrt()).min(extent);
        let mut layout = Layout::new(
            p,
            self.near.clone(),
            self.sides,
            extent,
            scale,
            cells,
            &self.v_points(),
            self.noise.states(),
        );
        layout.hold = self.hold;
        layout
    }
}

/// Refuse a problem whose mean first-passage time is infinite, naming
/// what would make it finite.
fn refuse_infinite(problem: &SearchProblem, resetting: Resetting) -> Result<()> {
    if let PositionTarget::Level(l) = problem.target() {
        match resetting {
            Resetting::Full { .. } => {}
            Resetting::Velocity { .. } => {
                return Err(Error::invalid(
                    "reset_position",
                    "none",
                    format!(
                        "a reset position for the level {}: with velocity-only resetting \
                         the mean is infinite or x unbounded (--method exact samples it)",
                        crate::error::short(l)
                    ),
                ))
            }
            Resetting::None => {
                return Err(Error::invalid(
                    "rate",
                    problem.params().rate(),
                    format!(
                        "rate > 0 with a reset position for the level {}: without resets \
                         the mean first-passage time to a one-sided level is infinite",
                        crate::error::short(l)
                    ),
                ))
            }
        }
    }
    Ok(())
}

/// The truncation distance X = v_u ln(1/tol) / r (Poisson clock); with
/// an exponential refractory period of mean M, v_u ln(1/tol) (1/r + M):
/// x also moves during the hold that follows a reset.
fn extent(p: &Params, tol: f64) -> f64 {
    match p.schedule().refractory {
        Some(Refractory::Exp { mean }) => p.v_upper() * (1.0 / tol).ln() * (1.0 / p.rate() + mean),
        _ => p.v_upper() * (1.0 / tol).ln() / p.rate(),
    }
}

/// Estimated cost of [`solve`]: the band LU of each mesh (n kl (2 kl + ku)
/// operations, kl = ku = 2 n_v) and its solves (three with full resetting),
/// memory of the finest band matrix (n (3 kl + 1) values) and six vectors.
pub fn estimate(problem: &SearchProblem, opts: &BackwardOptions) -> Result<Cost> {
    opts.validate()?;
    let setup = Setup::new(problem, super::BACKWARD, false)?;
    if !problem.mean_is_finite() {
        return Ok(Cost::NOTHING);
    }
    Ok(cost_of(
        &with_check(&setup, meshes(&setup, opts), opts.refine),
        solves(&setup),
    ))
}

/// Solves per mesh in the cost estimate: N + 1 for N noise states (T and
/// a response per reset state; 3 for the paper's noise).
fn solves(setup: &Setup) -> f64 {
    setup.noise.states() as f64 + 1.0
}

/// `plans` and, when refining, the check mesh ([`check_plan`]) last.
pub(crate) fn with_check(setup: &Setup, mut plans: Vec<Plan>, refine: bool) -> Vec<Plan> {
    if refine {
        let check = check_plan(setup, &plans[0].0);
        plans.push(check);
    }
    plans
}

/// A mesh before it is built: its layout and refinement level. Costs are
/// estimated from plans ([`cost_of`]), so a mesh too large for the budget
/// (or for memory) is refused before anything is allocated.
pub(crate) type Plan = (Layout, u32);

/// Build the meshes of `plans` (after [`check_budget`] passed on their cost).
pub(crate) fn build(plans: &[Plan]) -> Vec<Mesh> {
    plans.iter().map(|(l, k)| Mesh::build(l, *k)).collect()
}

/// Cost of factorising each mesh of `plans` and `solves` solves with each,
/// in f64 from the node counts ([`Layout::nodes`]): N n_x n_v unknowns,
/// N n_v = kl sub- and super-diagonals (N noise states; n_v + 1 slots
/// per column with a hold). A solve is 2 (3 kl + 1) operations
/// a row; the factorisation does 2 (kl + ku) = 4 kl a row for each nonzero
/// multiplier, and about 0.4 kl of a row's kl multipliers are nonzero
/// (upwind rows reach back a column only where v < 0; counted by
/// [`crate::numerics::band::work_done`]: 0.35-0.45 kl on the tests'
/// meshes), so 1.6 kl² a row.
pub(crate) fn cost_of(plans: &[Plan], solves: f64) -> Cost {
    let mut c = Cost {
        work: 0.0,
        memory: 0.0,
    };
    for (layout, k) in plans {
        let (nx, nv) = layout.nodes(*k);
        let nv = nv + f64::from(u8::from(layout.hold.is_some()));
        let ns = layout.states as f64;
        let (n, kl) = (ns * nx * nv, ns * nv);
        c.work += 1.6 * n * kl * kl + solves * n * 2.0 * (3.0 * kl + 1.0);
        c.memory = c.memory.max(8.0 * n * (3.0 * kl + 7.0));
    }
    c
}

/// What the size of a search mesh grows with, by the library's names: the
/// mesh options, the target (its distance sets the cell size), the reset
/// rate and the clock (the length of the far stretch), an exponential
/// refractory period (its mean lengthens the far stretch; its held
/// unknowns add a slot per column), then `extra`.
pub fn mesh_drivers(problem: &SearchProblem, extra: &[&'static str]) -> Vec<&'static str> {
    let mut d = vec!["cells_x", "cells_v"];
    d.push(match problem.target() {
        PositionTarget::Level(_) => "xt",
        PositionTarget::Interval(..) => "interval",
    });
    d.push("rate");
    d.extend(problem.params().schedule().cost_drivers());
    if let Some(Refractory::Exp { .. }) = problem.params().schedule().refractory {
        d.push("refractory");
    }
    d.extend_from_slice(extra);
    d
}

/// Refuse `cost` above the budgets (`max_work`, `max_memory`), naming
/// what it grows with (`drivers`).
pub(crate) fn check_budget(
    cost: &Cost,
    (max_work, max_memory): (f64, f64),
    drivers: Vec<&'static str>,
) -> Result<()> {
    if !(cost.work <= max_work) {
        return Err(Error::TooCostly {
            unit: "floating-point operations",
            estimate: cost.work,
            drivers,
            limit_name: "max_work",
            limit: max_work,
        });
    }
    if !(cost.memory <= max_memory) {
        return Err(Error::TooCostly {
            unit: "bytes of memory",
            estimate: cost.memory,
            drivers,
            limit_name: "max_memory",
            limit: max_memory,
        });
    }
    Ok(())
}

/// The meshes [`solve`] uses: coarse, halved (if refining), and the coarse
/// one widened to 1.5 X (if truncated).
pub(crate) fn meshes(setup: &Setup, opts: &BackwardOptions) -> Vec<Plan> {
    let x = if setup.truncated() {
        extent(&setup.params, opts.truncation)
    } else {
        0.0
    };
    let layout = setup.layout((opts.cells_x, opts.cells_v), x);
    let mut out = vec![(layout.clone(), 0)];
    if opts.refine {
        out.push((layout.clone(), 1));
    }
    if setup.truncated() {
        out.push((layout.widened(1.5), 0));
    }
    out
}

/// Solve for the mean first-passage time at (x0, v0), tau for each
/// starting noise state and their mean, with the mesh and truncation
/// error estimates (module docs). Refuses (typed) periodic clocks (see
/// [`super::renewal::solve`]), a fixed refractory period, an
/// infinite mean (one-sided level without full resetting), and a solve
/// above the budgets of `opts` ([`estimate`]).
pub fn solve(problem: &SearchProblem, opts: &BackwardOptions) -> Result<SearchSolution> {
    solve_watched(problem, opts, &NoProgress)
}

/// [`solve`], its progress reported to `progress` in millions of
/// operations of the estimate (`Watch`).
pub fn solve_watched(
    problem: &SearchProblem,
    opts: &BackwardOptions,
    progress: &dyn Progress,
) -> Result<SearchSolution> {
    opts.validate()?;
    let setup = Setup::new(problem, super::BACKWARD, false)?;
    if !problem.mean_is_finite() {
        return Ok(SearchSolution::infinite());
    }
    let plans = with_check(&setup, meshes(&setup, opts), opts.refine);
    let cost = cost_of(&plans, solves(&setup));
    let budget = (opts.max_work, opts.max_memory);
    check_budget(&cost, budget, mesh_drivers(problem, &["truncation"]))?;
    let watch = Watch::new(progress, cost.work);
    let meshes = build(&plans);
    let on = |m: &Mesh| {
        let a = solve_on(&setup, m);
        watch.tick();
        a
    };
    let answers = meshes.iter().map(on).collect::<Result<Vec<_>>>()?;
    let coarse = &answers[0];
    let (best, mesh_error, finest, asymptotic) = if opts.refine {
        let rungs = vec![
            answers[answers.len() - 1].clone(),
            coarse.clone(),
            answers[1].clone(),
        ];
        let ladder = Ladder {
            layout: &plans[0].0,
            cells: (opts.cells_x, opts.cells_v),
            budget,
            spent: cost.work,
            climb: opts.climb,
            method: METHOD,
            watch: &watch,
        };
        let top = ladder.climb(
            rungs,
            meshes[1].clone(),
            on,
            |a| (a.mean(), 0.0),
            |p| cost_of(std::slice::from_ref(p), solves(&setup)),
        )?;
        let (c, f) = top.last_two();
        let best = c.extrapolated(f);
        let error = top.factor.unwrap_or(1.0) * (f.mean() - c.mean()).abs();
        (best, error, top.finest, top.factor.is_some())
    } else {
        (coarse.clone(), f64::NAN, meshes[0].clone(), true)
    };
    // The extrapolated values pass the same checks as each mesh's.
    verify(
        &best.tau,
        &best.tau,
        &setup,
        "the backward solver (--method backward, extrapolated)",
    )?;
    let truncation_error = if setup.truncated() {
        // The coarse mesh widened to 1.5 X follows the coarse and fine ones.
        let diff = (answers[1 + opts.refine as usize].mean() - coarse.mean()).abs();
        diff * truncation_factor(opts.truncation)
    } else {
        0.0
    };
    let error_estimate = if opts.refine && asymptotic {
        mesh_error + truncation_error
    } else {
        f64::NAN
    };
    let paper = problem.params().noise().is_none();
    let (tau_plus, tau_minus) = if paper {
        (best.tau[0], best.tau[1])
    } else {
        (f64::NAN, f64::NAN)
    };
    Ok(SearchSolution {
        tau: best.mean(),
        tau_plus,
        tau_minus,
        tau_states: (!paper).then(|| best.tau.clone()),
        error_estimate,
        mesh_error,
        truncation_error,
        reset_values: best.reset.as_ref().filter(|_| paper).map(|r| [r[0], r[1]]),
        reset_states: best.reset.clone().filter(|_| !paper),
        mesh: mesh_info(&finest),
        infinite_mean: false,
        asymptotic,
        work: watch.done(),
    })
}

/// The progress of a mesh solver: the operations counted on this thread
/// ([`crate::numerics::band::work_done`]) since it started, of the
/// estimated total (raised as the ladder climbs), reported to `progress`
/// in millions.
pub(crate) struct Watch<'a> {
    progress: &'a dyn Progress,
    start: f64,
    total: Cell<f64>,
}

impl<'a> Watch<'a> {
    /// Watching from now, `total` operations expected.
    pub fn new(progress: &'a dyn Progress, total: f64) -> Self {
        Watch {
            progress,
            start: crate::numerics::band::work_done(),
            total: Cell::new(total),
        }
    }

    /// Operations done since [`Watch::new`].
    pub fn done(&self) -> f64 {
        crate::numerics::band::work_done() - self.start
    }

    /// `more` operations expected.
    pub fn expect(&self, more: f64) {
        self.total.set(self.total.get() + more);
    }

    /// Report the work done so far.
    pub fn tick(&self) {
        let done = self.done();
        let total = self.total.get().max(done);
        self.progress
            .update((done / 1e6) as u64, (total / 1e6).ceil() as u64);
    }
}

/// The backward solver's name in its refusals.
const METHOD: &str = "the backward solver (--method backward)";

/// The least observed ratio ρ = (T_h - T_2h) / (T_h/2 - T_h) of successive
/// mesh differences taken as converging (first-order upwind: ρ ≈ 2). In
/// the model T_h = T + c h^p (ρ = 2^p) the error of 2 T_h/2 - T_h is
/// d (2 - ρ) / (ρ - 1), d = T_h/2 - T_h: at most |d| from ρ = 1.5 up, and
/// [`error_factor`] times |d| below (at most 4 at ρ = 1.2).
pub(crate) const LEAST_RATIO: f64 = 1.2;

/// The bound on the error of 2 T_h/2 - T_h in units of |T_h/2 - T_h| at
/// the observed ratio `ratio` ≥ [`LEAST_RATIO`] (see there): at least 1.
pub(crate) fn error_factor(ratio: f64) -> f64 {
    ((2.0 - ratio) / (ratio - 1.0)).max(1.0)
}

/// The mesh that checks the observed order: the layout of half the cells
/// (at least 2 each way), so that h runs 2h, h, h/2 with the two meshes
/// solved already.
pub(crate) fn check_plan(setup: &Setup, layout: &Layout) -> Plan {
    let cells = |c: &[usize]| (c.iter().sum::<usize>() / 2).max(2);
    let x = layout.far.map_or(0.0, |f| f.length);
    (setup.layout((cells(&layout.xc), cells(&layout.vc)), x), 0)
}

/// The error factor ([`error_factor`]) of the last three means (coarsest
/// first) where they converge (ratio ≥ [`LEAST_RATIO`], the differences
/// of one sign), 1 where the last difference is below what the mesh can
/// resolve (`floor`: the time error of the renewal route; √ε |T| for
/// round-off); else the two differences and their ratio.
pub(crate) fn asymptotic(m: [f64; 3], floor: f64) -> std::result::Result<f64, (f64, f64, f64)> {
    let (d1, d2) = (m[1] - m[0], m[2] - m[1]);
    let ratio = d1 / d2;
    let floor = floor.max(f64::EPSILON.sqrt() * m[2].abs());
    if d2.abs() <= floor {
        Ok(1.0)
    } else if ratio >= LEAST_RATIO {
        Ok(error_factor(ratio))
    } else {
        Err((d1, d2, ratio))
    }
}

/// The finest level a ladder climbs to: 2^5 times the coarse mesh's cells
/// each way (a level costs about 16 times the one before).
pub(crate) const TOP_LEVEL: u32 = 5;

/// The Richardson ladder of a mesh method: meshes of `layout` (the coarse
/// mesh of `cells`) refined one level at a time while the last three
/// answers are not asymptotic and the next one fits the budget (work
/// `spent` so far); without `climb`, not refined at all.
pub(crate) struct Ladder<'a> {
    pub layout: &'a Layout,
    pub cells: (usize, usize),
    pub budget: (f64, f64),
    pub spent: f64,
    pub climb: bool,
    pub method: &'static str,
    pub watch: &'a Watch<'a>,
}

/// Where a ladder stopped: the answers (coarsest first), the finest mesh
/// and the error factor of the last difference ([`error_factor`]; None
/// where the sequence is not asymptotic and the ladder did not climb).
pub(crate) struct Top<A> {
    pub rungs: Vec<A>,
    pub finest: Mesh,
    pub factor: Option<f64>,
}

impl<A> Top<A> {
    /// The answers on the last two meshes (h, h/2).
    pub fn last_two(&self) -> (&A, &A) {
        let n = self.rungs.len();
        (&self.rungs[n - 2], &self.rungs[n - 1])
    }
}

impl Ladder<'_> {
    /// From `rungs` (answers on the check mesh, levels 0 and 1 of the
    /// layout) and the finest mesh so far: more levels until
    /// [`asymptotic`] (`mean` gives an answer's mean and its floor), each
    /// one's `cost` checked before it is built; refused (exit 4, naming
    /// the mesh flags and the mesh needed) when the next level is beyond
    /// the budget or [`TOP_LEVEL`].
    pub fn climb<A>(
        mut self,
        mut rungs: Vec<A>,
        mut finest: Mesh,
        solve: impl Fn(&Mesh) -> Result<A>,
        mean: impl Fn(&A) -> (f64, f64),
        cost: impl Fn(&Plan) -> Cost,
    ) -> Result<Top<A>> {
        let mut level = 1;
        loop {
            let n = rungs.len();
            let (m, floor) = (
                [0, 1, 2].map(|k| mean(&rungs[n - 3 + k]).0),
                mean(&rungs[n - 1]).1,
            );
            let (d1, d2, ratio) = match asymptotic(m, floor) {
                Ok(factor) => {
                    let factor = Some(factor);
                    return Ok(Top {
                        rungs,
                        finest,
                        factor,
                    });
                }
                Err(_) if !self.climb => {
                    let factor = None;
                    return Ok(Top {
                        rungs,
                        finest,
                        factor,
                    });
                }
                Err(e) => e,
            };
            level += 1;
            let plan = (self.layout.clone(), level);
            let c = cost(&plan);
            self.spent += c.work;
            let fits = self.spent <= self.budget.0 && c.memory <= self.budget.1;
            if !fits || level > TOP_LEVEL {
                let k = 1usize << (level - 1);
                let over = if fits {
                    ", past the top"
                } else {
                    " > --max-work"
                };
                return Err(Error::Numerical {
                    method: self.method,
                    reason: format!(
                        "meshes not asymptotic (steps {d1:.1e}, {d2:.1e}: ratio {ratio:.2} < \
                         {LEAST_RATIO}); needs --cells-x {} --cells-v {} ({:.0e} ops{over})",
                        k * self.cells.0,
                        k * self.cells.1,
                        self.spent,
                    ),
                });
            }
            self.watch.expect(c.work);
            finest = Mesh::build(&plan.0, level);
            rungs.push(solve(&finest)?);
        }
    }
}

/// From |T_{1.5X} - T_X| to a bound on the error of T_X when
/// X = v_u ln(1/tol) / r: the far field's influence decays at least like
/// e^{-r X / v_u} (the chance of travelling X before a reset), so the
/// step X → 1.5 X removes at least a share 1 - √tol of the error.
pub(crate) fn truncation_factor(tol: f64) -> f64 {
    1.0 / (1.0 - tol.sqrt())
}

/// The size of `m`.
pub(crate) fn mesh_info(m: &Mesh) -> MeshInfo {
    MeshInfo {
        nodes_x: m.x.len(),
        nodes_v: m.v.len(),
        unknowns: m.unknowns(),
        band: m.band(),
        x_min: m.x[0],
        x_max: m.x[m.x.len() - 1],
    }
}

/// T(x0, v0, s) and T(x_r, v_r, s) on one mesh, for each noise state s,
/// and the stationary law π of the states.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct NodeAnswer {
    pub tau: Vec<f64>,
    pub reset: Option<Vec<f64>>,
    pub pi: Vec<f64>,
}

impl NodeAnswer {
    /// Σ_s π_s T(x0, v0, s) (the paper's noise: 0.5 tau+ + 0.5 tau-, which
    /// is (tau+ + tau-)/2 to the bit: halving is exact).
    pub fn mean(&self) -> f64 {
        let mut terms = self.tau.iter().zip(&self.pi).map(|(t, p)| p * t);
        let first = terms.next().unwrap_or(0.0);
        terms.fold(first, |a, b| a + b)
    }

    /// 2 `fine` - `self` for each value (first-order Richardson).
    pub fn extrapolated(&self, fine: &NodeAnswer) -> NodeAnswer {
        let ex = |c: &[f64], f: &[f64]| -> Vec<f64> {
            c.iter().zip(f).map(|(c, f)| 2.0 * f - c).collect()
        };
        NodeAnswer {
            tau: ex(&self.tau, &fine.tau),
            reset: self
                .reset
                .as_ref()
                .zip(fine.reset.as_ref())
                .map(|(c, f)| ex(c, f)),
            pi: self.pi.clone(),
        }
    }
}

/// Factorise `r I - A` (identity rows on the target).
pub(crate) fn factor(g: &Generator, alpha: f64, beta: f64, method: &'static str) -> Result<Band> {
    factor_held(g, (alpha, alpha), beta, method)
}

/// [`factor`] with `alpha.1` in place of `alpha.0` on the held rows
/// ([`Generator::shifted_held`]).
pub(crate) fn factor_held(
    g: &Generator,
    alpha: (f64, f64),
    beta: f64,
    method: &'static str,
) -> Result<Band> {
    let mut band = g.shifted_held(alpha.0, alpha.1, beta);
    band.factor().map_err(|e| {
        let why = "the upwind matrix should be a non-singular M-matrix";
        e.into_error(method, format!("{e} ({why})"))
    })?;
    Ok(band)
}

/// Solve `L T = -1` on `mesh` (module docs): superposition for full
/// resetting, the reset inside the band for velocity-only resetting.
/// With the target's node weights w_j the reset values are
/// R_s = Σ_j w_j T(x_r, v_j, s) (T(x_r, v_r, s) for a point target):
/// `R = M R + U_r`, M[s][s'] = Σ_j w_j W_s'(x_r, v_j, s) (the chance that a
/// reset comes first, into state s'), its escape chances
/// e_s = Σ_j w_j h(x_r, v_j, s) from the hitting chance h solved for
/// directly (no cancellation when it is small); one response W_s' per
/// noise state s'. With an exponential refractory period ((S13)) a reset
/// starts a hold: R_s is the held unknown T_h(x_r, s), the held rows carry
/// no reset (neither the loss r nor a response's source).
fn solve_on(setup: &Setup, mesh: &Mesh) -> Result<NodeAnswer> {
    const METHOD: &str = "the backward solver (--method backward)";
    let p = &setup.params;
    let local = match setup.resetting {
        Resetting::Velocity { .. } => Some(LocalReset {
            rate: p.rate(),
            target: mesh.target_weights(p)?,
            mix: setup.mix.clone(),
        }),
        _ => None,
    };
    let g = Generator::assemble(mesh, p, &setup.noise, local.as_ref());
    let full = matches!(setup.resetting, Resetting::Full { .. });
    let r = if full { p.rate() } else { 0.0 };
    let band = factor_held(&g, (r, 0.0), 1.0, METHOD)?;
    let fill = |f: &dyn Fn(usize) -> f64| -> Vec<f64> {
        (0..g.dim())
            .map(|k| if g.absorbing[k] { 0.0 } else { f(k) })
            .collect()
    };
    let mut t = fill(&|_| 1.0);
    band.solve(&mut t);
    let ns = mesh.states;
    let reset = match setup.resetting {
        Resetting::Full { x, v } => {
            let ir = mesh.node(x, v)?.0;
            let weights = reset_weights(mesh, p, ir)?;
            let at_reset =
                |f: &[f64], s: usize| -> f64 { weights.iter().map(|&(k, w)| w * f[k + s]).sum() };
            let w: Vec<Vec<f64>> = (0..ns)
                .map(|s2| {
                    let source = |k: usize| match g.held[k] {
                        true => 0.0,
                        false => r * setup.mix[k % ns][s2],
                    };
                    let mut w = fill(&source);
                    band.solve(&mut w);
                    w
                })
                .collect();
            let mut hit: Vec<f64> = (0..g.dim())
                .map(|k| if g.absorbing[k] { 1.0 } else { 0.0 })
                .collect();
            band.solve(&mut hit);
            let m: Vec<Vec<f64>> = (0..ns)
                .map(|s| w.iter().map(|ws| at_reset(ws, s)).collect())
                .collect();
            let escape: Vec<f64> = (0..ns).map(|s| at_reset(&hit, s)).collect();
            let u: Vec<f64> = (0..ns).map(|s| at_reset(&t, s)).collect();
            let tr = renew(&m, &escape, &u, METHOD)?;
            for (k, tk) in t.iter_mut().enumerate() {
                *tk += (1..ns).fold(tr[0] * w[0][k], |a, s| a + tr[s] * w[s][k]);
            }
            Some(tr)
        }
        _ => None,
    };
    let (i0, j0) = mesh.node(setup.x0, setup.v0)?;
    let tau: Vec<f64> = (0..ns).map(|s| t[mesh.idx(i0, j0, s)]).collect();
    verify(&t, &tau, setup, METHOD)?;
    let pi = setup.noise.pi.clone();
    Ok(NodeAnswer { tau, reset, pi })
}

/// Where a full reset lands, as (unknown of state 0, weight) pairs (the
/// unknown of state s is that plus s): the held unknown at x_r with a hold
/// ((S13)), else the target's node weights at (x_r, v_j).
pub(crate) fn reset_weights(mesh: &Mesh, p: &Params, ir: usize) -> Result<Vec<(usize, f64)>> {
    if mesh.hold.is_some() {
        return Ok(vec![(mesh.held(ir, 0), 1.0)]);
    }
    let weights = mesh.target_weights(p)?;
    Ok(weights
        .iter()
        .map(|&(j, w)| (mesh.idx(ir, j, 0), w))
        .collect())
}

/// The reset values R solving R = M R + u (the renewal at the reset point,
/// M[s][s'] the chance that a reset into s' comes first from s, e_s the
/// chance of the target first): two states by [`capacitance`], N states
/// by elimination on `I - M` in the manner of Grassmann-Taksar-Heyman:
/// each pivot is its row's escape chance plus its off-diagonal chances,
/// the escape chances updated as e_i + l e_k with l ≥ 0 (sums of
/// non-negative terms, no cancellation when the target is rarely reached
/// first, so R ≥ 0); refused alike unless every e_s > 0.
pub(crate) fn renew(
    m: &[Vec<f64>],
    e: &[f64],
    u: &[f64],
    method: &'static str,
) -> Result<Vec<f64>> {
    if m.len() == 2 {
        let m2 = [[m[0][0], m[0][1]], [m[1][0], m[1][1]]];
        let tr = capacitance(m2, [e[0], e[1]], method)?.solve([u[0], u[1]]);
        return Ok(tr.to_vec());
    }
    refuse_unreached(m, e, method)?;
    let n = m.len();
    // Off-diagonal chances c[i][j] = M_ij (the system's entries are -c).
    let (mut c, mut e, mut b) = (m.to_vec(), e.to_vec(), u.to_vec());
    let pivot = |c: &[Vec<f64>], e: &[f64], k: usize| -> f64 {
        e[k] + (k + 1..n).map(|j| c[k][j]).sum::<f64>()
    };
    for k in 0..n {
        let p = pivot(&c, &e, k);
        for i in k + 1..n {
            let l = c[i][k] / p;
            let row_k = c[k].clone();
            for (j, cij) in c[i].iter_mut().enumerate().skip(k + 1) {
                if j != i {
                    *cij += l * row_k[j];
                }
            }
            e[i] += l * e[k];
            b[i] += l * b[k];
        }
    }
    let mut x = vec![0.0; n];
    for k in (0..n).rev() {
        let known: f64 = (k + 1..n).map(|j| c[k][j] * x[j]).sum();
        x[k] = (b[k] + known) / pivot(&c, &e, k);
    }
    Ok(x)
}

/// Refused (typed) unless every escape chance e_s > 0 and M ≥ 0: the
/// target must be reachable between resets from every state at x_r.
fn refuse_unreached(m: &[Vec<f64>], e: &[f64], method: &'static str) -> Result<()> {
    if e.iter().all(|x| *x > 0.0) && m.iter().flatten().all(|x| *x >= 0.0) {
        return Ok(());
    }
    let chances: Vec<String> = e.iter().map(|x| format!("{x:e}")).collect();
    Err(Error::Numerical {
        method,
        reason: format!(
            "the target is not reached between resets (chance of reaching it first \
             from x_r: {})",
            chances.join(", ")
        ),
    })
}

/// The system I - M of a renewal at the reset point, with the rows' escape
/// chances e_s = 1 - Σ_s' M[s][s'] known: diagonal e_s + M[s][s̄],
/// det = e0 e1 + e0 M10 + M01 e1 (non-negative terms). Refused (typed)
/// unless both escape chances are positive.
pub(crate) fn capacitance(
    m: [[f64; 2]; 2],
    e: [f64; 2],
    method: &'static str,
) -> Result<Capacitance> {
    if !(e[0] > 0.0 && e[1] > 0.0 && m.iter().flatten().all(|x| *x >= 0.0)) {
        return Err(Error::Numerical {
            method,
            reason: format!(
                "the target is not reached between resets (chance of reaching it first \
                 from x_r: {:e}, {:e})",
                e[0], e[1]
            ),
        });
    }
    let s = [[e[0] + m[0][1], -m[0][1]], [-m[1][0], e[1] + m[1][0]]];
    let det = e[0] * e[1] + e[0] * m[1][0] + m[0][1] * e[1];
    Ok(Capacitance::inverted(s, det))
}

/// Verified or refused: T finite and ≥ 0 everywhere up to the round-off
/// of the solve, T at the start at least distance / v_u (the mean speed
/// bound, exact on the mesh). The round-off allowed is n ε max |T| for n
/// values: the forward error of an elimination (and of the superposition
/// that adds the reset responses, values of size max |T|) grows at most
/// linearly with the unknowns (Wilkinson's bound, no pivot growth in an
/// M-matrix), so a value of T ≈ 0 next to the target may come out
/// slightly negative.
pub(crate) fn verify(t: &[f64], tau: &[f64], setup: &Setup, method: &'static str) -> Result<()> {
    let max = t.iter().fold(0.0f64, |m, &x| m.max(x.abs()));
    if !max.is_finite() {
        return Err(Error::NonFinite {
            method,
            at: setup.x0,
        });
    }
    let round_off = t.len().max(16) as f64 * f64::EPSILON * max;
    if let Some(bad) = t.iter().find(|&&x| x < -round_off) {
        return Err(Error::Numerical {
            method,
            reason: format!(
                "negative mean first-passage time {bad:e} on the mesh (beyond the \
                 round-off {round_off:.1e})"
            ),
        });
    }
    let bound = setup.distance / setup.params.v_upper();
    for &x in tau {
        if !(x >= bound * (1.0 - 1e-12)) {
            return Err(Error::Numerical {
                method,
                reason: format!(
                    "tau = {x} below distance / v_u = {bound} (the particle cannot be faster)"
                ),
            });
        }
    }
    Ok(())
}
