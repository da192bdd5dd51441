//! Position moments `<x>(t)`, `<x v>(t)`, `<x²>(t)` without sampling.
//!
//! x enters the dynamics linearly (dx/dt = v, a reset keeps x), so the
//! x-weighted densities M_k(v, s, t) = ∫ x^k p(x, v, s, t) dx obey the forward
//! operator A of the density itself plus a source from the transport in x:
//!
//! ```text
//! ∂_t M_k = A M_k + k v M_{k-1},   M_k(0) = δ_{k0} p(v, s, 0)     (k = 0, 1, 2)
//! ```
//!
//! (∂_t ∫ x^k p = ∫ x^k (-v ∂_x p + A p) = k v M_{k-1} + A M_k after one
//! integration by parts in x). When a reset keeps x the reset term of A is
//! the whole story (docs/equations.md, entry (D1)). With position
//! resetting (`--reset-position x_r`) the reset influx of M_k (k ≥ 1) is
//! x_r^k times that of M_0 instead of its own, and with an exponential
//! refractory period the held pairs of [`ForwardOperator`] are unknowns of
//! every block, x moving at the held velocity there (entry (R8)). On the
//! mesh this is the chain operator
//! C = [[A, 0, 0], [V, A, 0], [0, 2V, A]] with V = diag(cell-centre v): block
//! lower triangular, so (I - cC) x = b is three shifted solves of A by
//! forward substitution. TR-BDF2 ([`crate::numerics::trbdf2`]) integrates
//! it from the paper's start (x = 0, v = 0, η = ±Σ equally likely), and
//!
//! ```text
//! <x^k v^j>(t) = Σ_cells v^j M_k,   d⟨x²⟩/dt = 2 ⟨x v⟩,
//! ```
//!
//! so the effective exponent α(t) = d ln⟨x²⟩/d ln t = 2 t ⟨x v⟩ / ⟨x²⟩ is
//! exact (no finite difference). Long times: 2 (⟨x v⟩ - ⟨x⟩⟨v⟩) → 2 D_eff, the
//! Green-Kubo D_eff of the same discrete chain ([`super::stationary`]);
//! with position resetting ⟨x⟩ and ⟨x²⟩ tend to the stationary ones of the
//! same chain instead (no D_eff).
//!
//! The mesh error is removed by Richardson extrapolation over `levels` nested
//! meshes (cells, 2 cells, ...), assuming an expansion in powers of 1/N (the
//! first-order upwind scheme).

use super::grid::Mesh;
use super::nstate::{observe as observe_blocks, operator, Blocks, HeldBlocks};
use super::operator::ForwardOperator;
use super::stationary::MIN_CELLS;
use crate::error::{finite, Error, Result};
use crate::model::reset::Solver;
use crate::model::reset::{NoiseAtReset, Reset};
use crate::model::Params;
use crate::numerics::trbdf2::{integrate, ShiftedLinear, Tolerances};
use crate::numerics::Failure;
use crate::parallel::Progress;
use serde::{Deserialize, Serialize};

/// Largest number of cells of the finest mesh.
pub const MAX_MSD_CELLS: usize = 2_000_000;
/// Most Richardson levels.
pub const MAX_LEVELS: usize = 5;

/// Options of [`moments`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct MsdOptions {
    /// Cells of the coarsest mesh.
    pub cells: usize,
    /// Cell placement.
    pub mesh: Mesh,
    /// Nested meshes (cells, 2 cells, ..., 2^(levels-1) cells) combined by
    /// Richardson extrapolation in 1/N (1: the coarsest mesh only).
    pub levels: usize,
    /// Output times (sorted, >= 0).
    pub times: Vec<f64>,
    /// Relative tolerance of TR-BDF2's local error.
    pub rtol: f64,
}

impl Default for MsdOptions {
    fn default() -> Self {
        MsdOptions {
            cells: 400,
            mesh: Mesh::Graded,
            levels: 3,
            times: vec![1.0],
            rtol: 1e-10,
        }
    }
}

/// Moments at the output times.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct MomentSeries {
    /// Times.
    pub t: Vec<f64>,
    /// Total mass (1 up to rounding).
    pub mass: Vec<f64>,
    /// `<v>(t)`.
    pub v_mean: Vec<f64>,
    /// `<v²>(t)`.
    pub v2: Vec<f64>,
    /// `<x>(t)`.
    pub x_mean: Vec<f64>,
    /// `<x v>(t)`.
    pub xv: Vec<f64>,
    /// `<x²>(t)`.
    pub x2: Vec<f64>,
    /// Error estimate of `x2`: its change when the finest mesh is left out of
    /// the Richardson table (conservative for the full table; +∞ with one
    /// level, 0 at t = 0).
    pub x2_err: Vec<f64>,
    /// Effective exponent d ln⟨x²⟩/d ln t = 2 t ⟨x v⟩ / ⟨x²⟩ (4 at t = 0,
    /// the limit from v(0) = 0).
    pub alpha: Vec<f64>,
    /// Cells of the finest mesh.
    pub cells_finest: usize,
    /// Accepted TR-BDF2 steps, all meshes.
    pub steps: usize,
}

/// The moment chain k = 0, 1, 2 on one mesh.
struct Chain {
    op: ForwardOperator,
    /// The velocity of every unknown (the held ones at their held velocity).
    v: Vec<f64>,
    /// Position resetting to x_r: the reset influx of block k ≥ 1 is x_r^k
    /// times that of M_0 (docs/equations.md, (R8)).
    x_r: Option<f64>,
    /// Absolute tolerance of each block.
    atol: [f64; 3],
    tmp: Vec<f64>,
}

impl ShiftedLinear for Chain {
    fn dim(&self) -> usize {
        3 * self.v.len()
    }

    fn apply(&self, u: &[f64], out: &mut [f64]) {
        let n = self.v.len();
        for k in 0..3 {
            let block = &mut out[k * n..(k + 1) * n];
            match self.x_r {
                Some(x) if k > 0 => {
                    self.op.apply_with(&u[k * n..(k + 1) * n], block, false);
                    self.op.add_injection(&u[..n], block, x.powi(k as i32));
                }
                _ => self.op.apply(&u[k * n..(k + 1) * n], block),
            }
            if k > 0 {
                let kf = k as f64;
                for i in 0..n {
                    block[i] += kf * self.v[i] * u[(k - 1) * n + i];
                }
            }
        }
    }

    fn solve_shifted(
        &mut self,
        c: f64,
        b: &[f64],
        x: &mut [f64],
    ) -> std::result::Result<(), Failure> {
        let n = self.v.len();
        for k in 0..3 {
            self.tmp.copy_from_slice(&b[k * n..(k + 1) * n]);
            if k > 0 {
                let ck = c * k as f64;
                for i in 0..n {
                    self.tmp[i] += ck * self.v[i] * x[(k - 1) * n + i];
                }
            }
            let (lower, rest) = x.split_at_mut(k * n);
            let block = &mut rest[..n];
            match self.x_r {
                Some(xr) if k > 0 => {
                    self.op
                        .add_injection(&lower[..n], &mut self.tmp, c * xr.powi(k as i32));
                    self.op.solve_shifted_with(c, &self.tmp, block, false)?;
                }
                _ => self.op.solve_shifted_into(c, &self.tmp, block)?,
            }
        }
        Ok(())
    }

    fn atol(&self, i: usize, _atol: f64) -> f64 {
        self.atol[i / self.v.len()]
    }
}

/// Moments [mass, ⟨v⟩, ⟨v²⟩, ⟨x⟩, ⟨xv⟩, ⟨x²⟩] of a chain state.
fn observe(v: &[f64], u: &[f64]) -> [f64; 6] {
    let n = v.len();
    let mut s = [0.0; 6];
    for i in 0..n {
        let (m0, m1, m2) = (u[i], u[n + i], u[2 * n + i]);
        s[0] += m0;
        s[1] += v[i] * m0;
        s[2] += v[i] * v[i] * m0;
        s[3] += m1;
        s[4] += v[i] * m1;
        s[5] += m2;
    }
    s
}

fn check(params: &Params, o: &MsdOptions) -> Result<Vec<f64>> {
    // Either noise rule: A re-injects the M_k like the density (x kept), or
    // x_r^k times M_0's influx (position resetting).
    match params.reset().noise() {
        NoiseAtReset::Kept | NoiseAtReset::Redrawn => {}
    }
    if !(1..=MAX_LEVELS).contains(&o.levels) {
        return Err(Error::invalid(
            "levels",
            o.levels,
            format!("1 <= levels <= {MAX_LEVELS}"),
        ));
    }
    let finest = o
        .cells
        .checked_shl(o.levels as u32 - 1)
        .unwrap_or(usize::MAX);
    if !(o.cells >= MIN_CELLS && finest <= MAX_MSD_CELLS) {
        return Err(Error::invalid(
            "cells",
            o.cells,
            format!("{MIN_CELLS} <= cells and cells * 2^(levels - 1) <= {MAX_MSD_CELLS}"),
        ));
    }
    let rtol = finite("rtol", o.rtol)?;
    if !(1e-14..=1e-3).contains(&rtol) {
        return Err(Error::invalid("rtol", rtol, "1e-14 <= rtol <= 1e-3"));
    }
    if params.noise().is_none() && !(params.lambda() > 0.0) && !(params.rate() > 0.0) {
        return Err(Error::invalid(
            "lambda",
            params.lambda(),
            "lambda > 0 when rate = 0 (otherwise each state sits at its edge forever)",
        ));
    }
    let mut t = Vec::with_capacity(o.times.len());
    for &x in &o.times {
        let x = finite("times", x)?;
        if !(0.0..=1e9).contains(&x) {
            return Err(Error::invalid("times", x, "0 <= t <= 1e9"));
        }
        t.push(x);
    }
    if t.is_empty() || !t.windows(2).all(|w| w[0] < w[1]) {
        return Err(Error::invalid(
            "times",
            t.len(),
            "at least one time, strictly increasing",
        ));
    }
    Ok(t)
}

/// Moments on one mesh: rows [mass, ⟨v⟩, ⟨v²⟩, ⟨x⟩, ⟨xv⟩, ⟨x²⟩] per time.
/// Integrates interval by interval, resetting the absolute tolerance of the
/// x-weighted blocks to the current length scale of x.
fn one_mesh(
    params: &Params,
    o: &MsdOptions,
    times: &[f64],
    refine: usize,
    progress: &dyn Progress,
    done: &mut u64,
    total: u64,
) -> Result<(Vec<[f64; 6]>, usize)> {
    let op = ForwardOperator::refined(params, o.mesh, o.cells, refine)?;
    let m0 = op.point_mass(0.0);
    let n = m0.len();
    let mut u = vec![0.0; 3 * n];
    u[..n].copy_from_slice(&m0);
    let v = op.velocities().to_vec();
    let vmax = {
        let (lo, hi) = params.bounds();
        lo.abs().max(hi.abs())
    };
    let mut chain = Chain {
        op,
        v,
        x_r: params.schedule().position.map(|x| x.x),
        atol: [0.0; 3],
        tmp: vec![0.0; n],
    };
    let mut rows = Vec::with_capacity(times.len());
    let mut steps = 0;
    let (mut t0, mut x2) = (0.0, 0.0f64);
    let base = o.rtol;
    for &t1 in times {
        if t1 > t0 {
            // Length scale of x: the ballistic start from v = 0 at first,
            // then the current root-mean-square x.
            let ell = if t0 == 0.0 {
                (0.5 * params.sigma() * t1 * t1).min(vmax * t1)
            } else {
                x2.sqrt()
            };
            // An error δ in M_0 moves <x²> by about δ (v t)², one in M_1 by
            // δ v t: scale each block so that all move <x²> alike.
            let w = (ell / (vmax * t1)).min(1.0);
            chain.atol = [base * w * w, base * ell * w, base * ell * ell];
            let tol = Tolerances {
                rtol: o.rtol,
                atol: base,
                ..Tolerances::default()
            };
            let stats = integrate(&mut chain, &mut u, &[t1 - t0], &tol, |_, _, _| Ok(()))?;
            steps += stats.steps;
        }
        let s = observe(&chain.v, &u);
        x2 = s[5];
        rows.push(s);
        t0 = t1;
        *done += 1;
        progress.update(*done, total);
        if progress.cancelled() {
            return Err(Error::Interrupted);
        }
    }
    Ok((rows, steps))
}

/// Richardson extrapolation in 1/N over meshes N, 2N, 4N, ... (values
/// coarsest first): the Neville table with ratios 2^p, p = 1, 2, ...
pub(crate) fn richardson(values: &[f64]) -> f64 {
    let mut t = values.to_vec();
    for p in 1..t.len() {
        let f = (1u64 << p) as f64;
        for j in (p..t.len()).rev() {
            t[j] = t[j] + (t[j] - t[j - 1]) / (f - 1.0);
        }
    }
    *t.last().expect("at least one level")
}

/// `<x>`, `<x v>`, `<x²>` (and mass, `<v>`, `<v²>`, α) at `opts.times` from the
/// paper's initial condition, by the moment chain (module docs).
/// Fails on a numerical failure of the time stepping or when the
/// extrapolated moments violate mass 1, 0 <= `<v²>` <= v_max²,
/// `<x²>` >= `<x>`², α finite.
pub fn moments(
    params: &Params,
    opts: &MsdOptions,
    progress: &dyn Progress,
) -> Result<MomentSeries> {
    params.require(Solver::FpMsd)?;
    let times = check(params, opts)?;
    let total = (opts.levels * times.len()) as u64;
    let mut done = 0;
    // One mesh of the chain over the noise's state space: the paper's two
    // states ([`ForwardOperator`]) or a finite-state chain
    // ([`super::nstate`]); the extrapolation below serves both.
    let chain = params.noise().is_some();
    let mut level = |refine: usize| {
        if chain {
            chain_level(params, opts, &times, refine)
        } else {
            one_mesh(params, opts, &times, refine, progress, &mut done, total)
        }
    };
    let mut levels = Vec::with_capacity(opts.levels);
    let mut steps = 0;
    for refine in 0..opts.levels {
        let (rows, s) = level(refine)?;
        levels.push(rows);
        steps += s;
    }
    let col = |k: usize, j: usize| -> f64 {
        richardson(&levels.iter().map(|rows| rows[k][j]).collect::<Vec<_>>())
    };
    let mut out = MomentSeries {
        t: times.clone(),
        mass: Vec::new(),
        v_mean: Vec::new(),
        v2: Vec::new(),
        x_mean: Vec::new(),
        xv: Vec::new(),
        x2: Vec::new(),
        x2_err: Vec::new(),
        alpha: Vec::new(),
        cells_finest: opts.cells << (opts.levels - 1),
        steps,
    };
    for (k, &t) in times.iter().enumerate() {
        if t == 0.0 {
            // The start itself (x = v = 0, mass 1), not its cell-centre
            // quadrature (<v²> = h²/4 on each mesh); α's limit from v(0) = 0.
            for (c, x) in [
                (&mut out.mass, 1.0),
                (&mut out.v_mean, 0.0),
                (&mut out.v2, 0.0),
            ] {
                c.push(x);
            }
            for c in [&mut out.x_mean, &mut out.xv, &mut out.x2, &mut out.x2_err] {
                c.push(0.0);
            }
            out.alpha.push(4.0);
            continue;
        }
        out.mass.push(col(k, 0));
        out.v_mean.push(col(k, 1));
        out.v2.push(col(k, 2));
        out.x_mean.push(col(k, 3));
        out.xv.push(col(k, 4));
        out.x2.push(col(k, 5));
        out.x2_err.push(match levels.len() {
            1 => f64::INFINITY,
            n => {
                let coarser: Vec<f64> = levels[..n - 1].iter().map(|rows| rows[k][5]).collect();
                (col(k, 5) - richardson(&coarser)).abs()
            }
        });
        out.alpha.push(if t == 0.0 {
            4.0
        } else {
            2.0 * t * out.xv[k] / out.x2[k]
        });
    }
    verify(params, &out)?;
    Ok(out)
}

/// The invariants of the answer, or a refusal.
fn verify(params: &Params, s: &MomentSeries) -> Result<()> {
    let (lo, hi) = params.bounds();
    let v2_max = lo.powi(2).max(hi.powi(2));
    for k in 0..s.t.len() {
        let (t, x2, xm) = (s.t[k], s.x2[k], s.x_mean[k]);
        let why = if !((s.mass[k] - 1.0).abs() <= 1e-9) {
            Some(format!("mass {:e} != 1", s.mass[k]))
        } else if !(s.v2[k] >= 0.0 && s.v2[k] <= v2_max) {
            Some(format!("<v^2> = {:e} outside [0, {v2_max:e}]", s.v2[k]))
        } else if !(x2 >= xm * xm * (1.0 - 1e-9) && (t == 0.0 || x2 > 0.0)) {
            Some(format!("<x^2> = {x2:e} < <x>^2 = {:e}", xm * xm))
        } else if !s.alpha[k].is_finite() {
            Some(format!("effective exponent {}", s.alpha[k]))
        } else {
            None
        };
        if let Some(why) = why {
            return Err(Error::Numerical {
                method: "fp msd",
                reason: format!("{why} at t = {t}: the mesh or the time tolerance does not resolve the moments; refused"),
            });
        }
    }
    Ok(())
}

/// One level of [`moments`] for a noise model: the moment chain on the
/// N-state mesh refined `refine` times ([`Blocks`] of 3 blocks; with an
/// exponential refractory period [`HeldBlocks`], entry (R14)), the rows
/// of [`observe_blocks`] at `times` and the number of accepted steps.
fn chain_level(
    p: &Params,
    o: &MsdOptions,
    times: &[f64],
    refine: usize,
) -> Result<(Vec<[f64; 6]>, usize)> {
    let tol = Tolerances {
        rtol: o.rtol,
        atol: o.rtol,
        ..Tolerances::default()
    };
    let op = operator(p, o.cells, refine, true)?;
    if let Some(mut h) = HeldBlocks::of(p, op.clone()) {
        let (mut u, obs) = (h.initial()?, h.observer());
        let mut rows = vec![[0.0; 6]; times.len()];
        let stats = integrate(&mut h, &mut u, times, &tol, |k, _, u| {
            rows[k] = obs.observe(u);
            Ok(())
        })?;
        return Ok((rows, stats.steps));
    }
    let mut b = Blocks::new(op, 3);
    let mut u = b.initial()?;
    let v = b.v.clone();
    let mut rows = vec![[0.0; 6]; times.len()];
    let stats = integrate(&mut b, &mut u, times, &tol, |k, _, u| {
        rows[k] = observe_blocks(&v, 3, u);
        Ok(())
    })?;
    Ok((rows, stats.steps))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn richardson_removes_powers_of_one_over_n() {
        // X(N) = 1 + 3/N - 2/N² + 5/N³ on N = 10, 20, 40, 80.
        let x = |n: f64| 1.0 + 3.0 / n - 2.0 / (n * n) + 5.0 / n.powi(3);
        let v: Vec<f64> = [10.0, 20.0, 40.0, 80.0].iter().map(|&n| x(n)).collect();
        assert!((richardson(&v) - 1.0).abs() < 1e-14);
        assert!((richardson(&v[..3]) - 1.0).abs() > 1e-6);
    }
}
