//! The distribution of the search time by the time-dependent backward
//! equation (docs/equations.md, search section, (S9)).
//!
//! The survival S(x, v, eta, t) = P(T > t | start) solves
//! `∂t S = L S` with the generator (S1) of the process WITH its resets,
//! `S(0) = 1` off the target and `S = 0` on it (backward Kolmogorov
//! equation of the killed process). With full resetting the reset term is
//! `r [Σ_s'' mix(s, s'') Σ_j w_j S(x_r, v_j, s'', t) - S]`: N scalars per
//! time (N noise states), the reset point's survival in each, weighed by the
//! target's node weights (a point target: one node). Velocity-only resetting
//! (an interval target) is a jump in v at fixed x, inside the band (as the
//! stationary solver). The density is f = -dS/dt = -(L S)(start), exact for
//! the semi-discrete system.
//!
//! Discretisation: the upwind mesh and generator of [`super::backward`];
//! in time TR-BDF2 with a fixed step (this module's stepper, shared with
//! the renewal route), each implicit stage `(I - d dt B) y = b` solved by one banded LU
//! of `(1 + d dt r) I - d dt A` and a rank-N correction for the N reset
//! values (the paper's noise: [`crate::numerics::bordered::LowRank`];
//! more states: `RankN`). The start's noise state is drawn from the
//! stationary law π (the paper's noise: ±Sigma with 1/2 each). Runs on the steps dt and
//! dt/2 (second order: `(4 S_{dt/2} - S_dt)/3`, error `|S_{dt/2} - S_dt|/3`)
//! and on the meshes h and h/2 (first order: `2 S_{h/2} - S_h`, error
//! `|S_{h/2} - S_h|`), and a truncated level again at 1.5 X. Invariants
//! checked on every run: 0 ≤ S ≤ 1 and S non-increasing (to 1e-9), and on
//! the extrapolated curve within its error estimate.
//!
//! An exponential refractory period is Markov: the held survival
//! H(x, s, t) joins S on the mesh ((S14), the held unknowns of (S13)), a
//! reset leads to it and it releases to S(x, v_r, s, t) at rate 1/M.
//!
//! Refused by name: periodic clocks and a fixed refractory period (the
//! equation is not autonomous there; the exact sampler runs them), a
//! random reset target with an exponential refractory period, a one-sided level
//! with velocity-only resetting or none: x is unbounded on the far side and
//! S(t) there needs the whole half-line (the mesh of the stationary solver
//! truncates it only because resets to x_r bound the distance travelled;
//! the exact sampler gives S(t) and its tail).

use super::backward::{
    build, check_budget, cost_of, factor_held, mesh_drivers, mesh_info, meshes, reset_weights,
    BackwardOptions,
};
use super::backward::{truncation_factor, Cost, MeshInfo, Resetting, Setup};
use super::mesh::{Generator, LocalReset, Mesh};
use super::SearchProblem;
use crate::error::{Error, Result};
use crate::numerics::band::Band;
use crate::numerics::bordered::{responses, LowRank};
use serde::{Deserialize, Serialize};

/// Fixed-step TR-BDF2 for u' = B u: the trapezoidal stage to t + γ dt and
/// the BDF2 stage to t + dt (γ = 2 - √2), both solving `(I - d B) y = b`
/// with d = γ dt / 2. Hand-written: the stages are the caller's band
/// solves (with a rank-2 correction), which no ODE crate takes; the
/// adaptive integrator of [`crate::numerics::trbdf2`] steps to its own
/// times, and these runs need a fixed step for the dt/2 extrapolation.
pub(crate) struct Stepper {
    d: f64,
    c1: f64,
    c0: f64,
}

impl Stepper {
    /// The step dt.
    pub fn new(dt: f64) -> Self {
        let gamma = 2.0 - std::f64::consts::SQRT_2;
        Stepper {
            d: 0.5 * gamma * dt,
            c1: 1.0 / (gamma * (2.0 - gamma)),
            c0: (1.0 - gamma).powi(2) / (gamma * (2.0 - gamma)),
        }
    }

    /// The shift d of the stages' `I - d B`.
    pub fn d(&self) -> f64 {
        self.d
    }

    /// One step of `u`: `apply(u, out)` writes B u, `solve(y)` replaces y
    /// by `(I - d B)⁻¹ y`; `au`, `star` are work vectors of u's length.
    pub fn step(
        &self,
        u: &mut [f64],
        (au, star): (&mut [f64], &mut [f64]),
        apply: impl Fn(&[f64], &mut [f64]),
        solve: impl Fn(&mut [f64]),
    ) {
        apply(u, au);
        for k in 0..u.len() {
            star[k] = u[k] + self.d * au[k];
        }
        solve(star);
        for k in 0..u.len() {
            u[k] = self.c1 * star[k] - self.c0 * u[k];
        }
        solve(u);
    }
}

/// Options of [`solve`].
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct DistributionOptions {
    /// The mesh (cells, refinement, truncation of a level, budgets) as for
    /// the mean ([`BackwardOptions`]).
    pub mesh: BackwardOptions,
    /// The last time.
    pub t_max: f64,
    /// Time steps to t_max (also run with twice as many).
    pub steps: usize,
}

impl DistributionOptions {
    /// The mesh's checks, 0 < t_max < ∞, 4 ≤ steps ≤ 10⁶.
    pub fn validate(&self) -> Result<()> {
        self.mesh.validate()?;
        if !(self.t_max > 0.0 && self.t_max.is_finite()) {
            return Err(Error::invalid("t_max", self.t_max, "0 < t_max < inf"));
        }
        if !(4..=1_000_000).contains(&self.steps) {
            return Err(Error::invalid("steps", self.steps, "4 <= steps <= 1000000"));
        }
        Ok(())
    }
}

/// S(t) and f(t) of the search from (x0, v0), the noise state random.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SearchDistribution {
    /// Times t_n = n t_max / steps, n = 0..=steps.
    pub t: Vec<f64>,
    /// S(t_n), extrapolated in the step and the mesh.
    pub survival: Vec<f64>,
    /// f(t_n) = -dS/dt, extrapolated likewise.
    pub density: Vec<f64>,
    /// Error estimate of S(t_n): mesh + step + truncation.
    pub survival_err: Vec<f64>,
    /// The largest |S_{h/2} - S_h| over the times (NaN without refinement).
    pub mesh_error: f64,
    /// The largest |S_{dt/2} - S_dt| / 3 over the times.
    pub time_error: f64,
    /// The largest truncation error (0 without truncation).
    pub truncation_error: f64,
    /// ∫_0^t_max S dt (trapezoid on the extrapolated curve: E[min(T, t_max)]).
    pub restricted_mean: f64,
    /// The finest mesh.
    pub mesh: MeshInfo,
}

/// Work of [`solve`]: per mesh two factorisations, 2 stages per step on
/// dt and dt/2 (6 band solves per step of `steps`) and N reset responses
/// on each.
pub fn estimate(problem: &SearchProblem, opts: &DistributionOptions) -> Result<Cost> {
    opts.validate()?;
    let setup = Setup::new(problem, super::DISTRIBUTION, false)?;
    let responses = 2.0 * setup.noise.states() as f64;
    let c = cost_of(
        &meshes(&setup, &opts.mesh),
        6.0 * opts.steps as f64 + responses,
    );
    // The curves kept: S, f and their errors, on the steps and half steps.
    let curves = 8.0 * 12.0 * (2.0 * opts.steps as f64 + 1.0);
    Ok(Cost {
        work: c.work,
        memory: c.memory + curves,
    })
}

/// The survival and density of the search (module docs), refused (typed)
/// where the equation does not run or above the budgets of `opts.mesh`.
pub fn solve(problem: &SearchProblem, opts: &DistributionOptions) -> Result<SearchDistribution> {
    let cost = estimate(problem, opts)?;
    check_budget(
        &cost,
        (opts.mesh.max_work, opts.mesh.max_memory),
        mesh_drivers(problem, &["steps"]),
    )?;
    let setup = Setup::new(problem, super::DISTRIBUTION, false)?;
    let plans = meshes(&setup, &opts.mesh);
    let meshes = build(&plans);
    let n = opts.steps;
    let in_time = |m: &Mesh| -> Result<(Curve, Vec<f64>, Curve)> {
        let (c1, c2) = (
            run(&setup, m, opts.t_max, n)?,
            run(&setup, m, opts.t_max, 2 * n)?,
        );
        let c2 = c2.every_other();
        let err = (0..=n).map(|i| (c2.s[i] - c1.s[i]).abs() / 3.0).collect();
        Ok((c2.combine(4.0 / 3.0, &c1, -1.0 / 3.0), err, c1))
    };
    let (coarse, coarse_time, coarse_raw) = in_time(&meshes[0])?;
    // Two meshes, not the ladder of the mean's solvers: S(t) near the
    // earliest arrival is a front, whose pointwise mesh differences shrink
    // slower than first order, so an order check would refuse nearly
    // every curve.
    let (best, mesh_err, time_err, finest) = if opts.mesh.refine {
        let (fine, fine_time, _) = in_time(&meshes[1])?;
        let e: Vec<f64> = (0..=n).map(|i| (fine.s[i] - coarse.s[i]).abs()).collect();
        (
            fine.combine(2.0, &coarse, -1.0),
            e,
            fine_time,
            meshes[1].clone(),
        )
    } else {
        (
            coarse,
            vec![f64::NAN; n + 1],
            coarse_time,
            meshes[0].clone(),
        )
    };
    let trunc: Vec<f64> = if setup.truncated() {
        let wide = run(&setup, &meshes[meshes.len() - 1], opts.t_max, n)?;
        let k = truncation_factor(opts.mesh.truncation);
        (0..=n)
            .map(|i| (wide.s[i] - coarse_raw.s[i]).abs() * k)
            .collect()
    } else {
        vec![0.0; n + 1]
    };
    let err: Vec<f64> = (0..=n)
        .map(|i| mesh_err[i] + time_err[i] + trunc[i])
        .collect();
    check_curve(&best.s, &err, "mfpt distribution --xt (extrapolated)")?;
    let dt = opts.t_max / n as f64;
    let restricted_mean = best.integral(dt);
    let max = |v: &[f64]| v.iter().copied().fold(0.0f64, f64::max);
    Ok(SearchDistribution {
        t: (0..=n).map(|i| dt * i as f64).collect(),
        survival: best.s,
        density: best.f,
        survival_err: err,
        mesh_error: if opts.mesh.refine {
            max(&mesh_err)
        } else {
            f64::NAN
        },
        time_error: max(&time_err),
        truncation_error: max(&trunc),
        restricted_mean,
        mesh: mesh_info(&finest),
    })
}

/// S and f at the start (random noise state) at t_n, n = 0..=steps.
#[derive(Clone, Debug, PartialEq)]
struct Curve {
    s: Vec<f64>,
    f: Vec<f64>,
}

impl Curve {
    /// ∫ S dt by the trapezoid rule on steps `dt`.
    fn integral(&self, dt: f64) -> f64 {
        let n = self.s.len() - 1;
        dt * (self.s.iter().sum::<f64>() - 0.5 * (self.s[0] + self.s[n]))
    }

    /// The values at the even steps (the run at dt/2 on the times of dt).
    fn every_other(&self) -> Curve {
        Curve {
            s: self.s.iter().step_by(2).copied().collect(),
            f: self.f.iter().step_by(2).copied().collect(),
        }
    }
    /// c0 self + c1 other, pointwise.
    fn combine(&self, c0: f64, other: &Curve, c1: f64) -> Curve {
        let mix = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| c0 * x + c1 * y).collect();
        Curve {
            s: mix(&self.s, &other.s),
            f: mix(&self.f, &other.f),
        }
    }
}

/// Verified or refused: S in [-tol, 1 + tol] and non-increasing to `tol`
/// (per time: the error estimate, at least 1e-9).
fn check_curve(s: &[f64], tol: &[f64], method: &'static str) -> Result<()> {
    for i in 0..s.len() {
        let t = tol[i].max(1e-9);
        let t = if t.is_finite() { t } else { 1e-9 };
        let rising = i > 0 && s[i] > s[i - 1] + t + tol[i - 1].max(0.0);
        if !(s[i] >= -t && s[i] <= 1.0 + t) || rising {
            return Err(Error::Numerical {
                method,
                reason: format!(
                    "survival {} at step {i} (previous {}) is not a non-increasing \
                     probability within its error {t:e}",
                    s[i],
                    if i > 0 { s[i - 1] } else { f64::NAN }
                ),
            });
        }
    }
    Ok(())
}

/// The operator B of the survival equation on one mesh: the generator A
/// (with velocity-only resetting inside it) and, with full resetting, the
/// reset term `r [Σ_s'' mix(s, s'') R_s''(S) - S]`, R_s'' the weighed reset
/// point values (N noise states); with an exponential refractory period
/// R_s'' is the held survival at x_r and the held rows carry no reset
/// term ((S14)).
struct Operator<'a> {
    g: &'a Generator,
    /// Full-resetting rate (0 otherwise).
    r: f64,
    /// (unknown, weight) of R_s for each state s (empty without full
    /// resetting).
    reset: Vec<Vec<(usize, f64)>>,
    /// mix[s][s'']: the noise rule at a reset (N × N).
    mix: Vec<Vec<f64>>,
}

impl Operator<'_> {
    /// R_s(u) for each state s.
    fn reset_values(&self, u: &[f64]) -> Vec<f64> {
        self.reset
            .iter()
            .map(|r| r.iter().map(|&(k, w)| w * u[k]).sum())
            .collect()
    }
    /// R_+(u), R_-(u) of the paper's noise (two states).
    fn reset_pair(&self, u: &[f64]) -> [f64; 2] {
        let rv = self.reset_values(u);
        [rv[0], rv[1]]
    }
    /// out = B u (0 on the target).
    fn apply(&self, u: &[f64], out: &mut [f64]) {
        self.g.apply(u, out);
        if self.r > 0.0 {
            let rv = self.reset_values(u);
            let ns = self.mix.len();
            for (k, o) in out.iter_mut().enumerate() {
                if !self.g.absorbing[k] && !self.g.held[k] {
                    let m = &self.mix[k % ns];
                    let back = (1..ns).fold(m[0] * rv[0], |a, s| a + m[s] * rv[s]);
                    *o += self.r * (back - u[k]);
                }
            }
        }
    }
    /// The column U_s'' of the reset coupling, scaled by `c`.
    fn column(&self, s2: usize, c: f64) -> Vec<f64> {
        let ns = self.mix.len();
        (0..self.g.dim())
            .map(|k| {
                if self.g.absorbing[k] || self.g.held[k] {
                    0.0
                } else {
                    c * self.mix[k % ns][s2]
                }
            })
            .collect()
    }
}

/// The rank-N correction of a base solve w = A⁻¹ b into the solve of
/// (A + U Vᵀ) x = b (Sherman-Morrison-Woodbury, as
/// [`crate::numerics::bordered::LowRank`] for N = 2): Z = A⁻¹ U, the
/// capacitance S = I + Vᵀ Z factorised once (LU with partial pivoting),
/// x ← x - Z S⁻¹ Vᵀ x.
struct RankN {
    z: Vec<Vec<f64>>,
    s: Band,
}

impl RankN {
    /// From the responses Z = A⁻¹ U and `v` mapping y to Vᵀ y; a singular
    /// capacitance is refused (typed) naming `method`.
    fn new(z: Vec<Vec<f64>>, v: impl Fn(&[f64]) -> Vec<f64>, method: &'static str) -> Result<Self> {
        let n = z.len();
        let k = n.saturating_sub(1);
        let mut s = Band::new(n, k, k);
        for (j, zj) in z.iter().enumerate() {
            for (i, x) in v(zj).into_iter().enumerate() {
                s.set(i, j, x + f64::from(u8::from(i == j)));
            }
        }
        s.factor().map_err(|e| {
            e.into_error(method, format!("singular {n}×{n} reset capacitance ({e})"))
        })?;
        Ok(RankN { z, s })
    }

    /// x ← (A + U Vᵀ)⁻¹ x, with `base` the solve by A (in place).
    fn solve(&self, base: impl Fn(&mut [f64]), x: &mut [f64], v: impl Fn(&[f64]) -> Vec<f64>) {
        base(x);
        let mut a = v(x);
        self.s.solve(&mut a);
        for (zs, a) in self.z.iter().zip(&a) {
            for (xi, y) in x.iter_mut().zip(zs) {
                *xi -= a * y;
            }
        }
    }
}

/// The reset coupling's correction of the base solve: none (no full
/// resetting), rank 2 (the paper's noise), rank N.
enum Coupling {
    None,
    Two(LowRank),
    Many(RankN),
}

/// One run on `mesh` with `steps` steps to `t_max`.
fn run(setup: &Setup, mesh: &Mesh, t_max: f64, steps: usize) -> Result<Curve> {
    const METHOD: &str = "mfpt distribution --xt";
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
    let (r, reset) = match setup.resetting {
        Resetting::Full { x, v } => {
            let ir = mesh.node(x, v)?.0;
            let w = reset_weights(mesh, p, ir)?;
            let at = |s| w.iter().map(|&(k, wj)| (k + s, wj)).collect();
            (p.rate(), (0..mesh.states).map(at).collect())
        }
        _ => (0.0, vec![]),
    };
    let op = Operator {
        g: &g,
        r,
        reset,
        mix: setup.mix.clone(),
    };
    let stepper = Stepper::new(t_max / steps as f64);
    let d = stepper.d();
    // (1 + d r) I - d A (I - d A on the held rows: no reset acts during a
    // hold), and the rank-N term -d r U Rᵀ of the reset values.
    let band: Band = factor_held(&g, (1.0 + d * r, 1.0), d, METHOD)?;
    let base = |y: &mut [f64]| band.solve(y);
    let coupling = match (r > 0.0, mesh.states) {
        (false, _) => Coupling::None,
        (true, 2) => {
            let z = responses(base, [op.column(0, -d * r), op.column(1, -d * r)]);
            Coupling::Two(LowRank::standard(z, |y| op.reset_pair(y)))
        }
        (true, ns) => {
            let z = (0..ns)
                .map(|s2| {
                    let mut col = op.column(s2, -d * r);
                    base(&mut col);
                    col
                })
                .collect();
            Coupling::Many(RankN::new(z, |y| op.reset_values(y), METHOD)?)
        }
    };
    let solve = |y: &mut [f64]| match &coupling {
        Coupling::Two(l) => l.solve(base, y, |y| op.reset_pair(y)),
        Coupling::Many(l) => l.solve(base, y, |y| op.reset_values(y)),
        Coupling::None => base(y),
    };
    record_run(setup, mesh, &op, &stepper, steps, solve)
}

/// Step S from 1 off the target, recording S and f at the start; each run
/// checked (module docs).
fn record_run(
    setup: &Setup,
    mesh: &Mesh,
    op: &Operator,
    stepper: &Stepper,
    steps: usize,
    solve: impl Fn(&mut [f64]),
) -> Result<Curve> {
    const METHOD: &str = "mfpt distribution --xt";
    let n = op.g.dim();
    let (i0, j0) = mesh.node(setup.x0, setup.v0)?;
    let start: Vec<usize> = (0..mesh.states).map(|s| mesh.idx(i0, j0, s)).collect();
    let pi = &setup.noise.pi;
    // Σ_s π_s x(start, s), summed in state order (the paper's noise:
    // 0.5 x+ + 0.5 x-, which is (x+ + x-)/2 to the bit: halving is exact).
    let at_start = |x: &[f64]| {
        let mut terms = start.iter().zip(pi).map(|(&k, p)| p * x[k]);
        let first = terms.next().unwrap_or(0.0);
        terms.fold(first, |a, b| a + b)
    };
    let mut u: Vec<f64> = (0..n)
        .map(|k| if op.g.absorbing[k] { 0.0 } else { 1.0 })
        .collect();
    let (mut au, mut star) = (vec![0.0; n], vec![0.0; n]);
    let mut curve = Curve {
        s: Vec::with_capacity(steps + 1),
        f: Vec::with_capacity(steps + 1),
    };
    for step in 0..=steps {
        crate::parallel::check_stop()?;
        if step > 0 {
            stepper.step(&mut u, (&mut au, &mut star), |x, y| op.apply(x, y), &solve);
        }
        op.apply(&u, &mut au);
        curve.s.push(at_start(&u));
        curve.f.push(-at_start(&au));
        if u.iter().any(|x| !x.is_finite()) {
            return Err(Error::NonFinite {
                method: METHOD,
                at: step as f64,
            });
        }
    }
    check_curve(&curve.s, &vec![0.0; steps + 1], METHOD)?;
    Ok(curve)
}
