//! Stationary N-state densities, `<v>`, `<v²>`, the per-state means and
//! the exact D_eff of the discrete generator (Eqs. (N23)-(N25)).

use super::mesh::mesh;
use super::operator::NoiseOperator;
use crate::error::{Error, Result};
use crate::model::noise::chain;
use crate::model::reset::NoiseAtReset;
use crate::model::reset::Reset;
use crate::model::Drag;
use crate::model::Params;
use serde::{Deserialize, Serialize};

const METHOD: &str = "fp stationary";

/// Observables of the N-state solve on one mesh.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct NoiseMoments {
    /// Number of cells.
    pub cells: usize,
    /// `<v>` (the drift velocity U of x, Eq. (N5)).
    pub v_mean: f64,
    /// `<v²>`.
    pub v2: f64,
    /// D_eff = Σ f y with A y = -(m∘f), f = v - `<v>` (Eq. (N24)).
    pub d_eff: f64,
    /// Per-state means m_s = E[v 1{η = s}].
    pub state_means: Vec<f64>,
    /// Per-state masses (π to rounding, checked).
    pub state_masses: Vec<f64>,
    /// Estimated stationary mass beyond a truncated domain's ends
    /// (Eq. (N26)); 0 on a bounded domain.
    pub tail_mass: f64,
}

/// The N-state solution on one mesh: the operator, cell masses (m_{i,s}
/// interleaved by cell), and observables.
pub(crate) struct MeshSolution {
    pub op: NoiseOperator,
    pub masses: Vec<f64>,
    pub moments: NoiseMoments,
}

/// The operator of `p` on the mesh of `n << refine` cells.
/// `graded`: cells graded towards the singular fixed points (else only
/// the breakpoints are nodes).
pub(crate) fn operator(p: &Params, n: usize, refine: usize, graded: bool) -> Result<NoiseOperator> {
    let c = p.chain()?;
    let m = mesh(p, &c, n, refine, graded)?;
    Ok(NoiseOperator::new(
        m,
        c,
        p.drag(),
        p.rate(),
        p.reset().noise(),
    ))
}

/// Solve and check the stationary state on the mesh of `n << refine` cells.
pub(crate) fn solve_mesh(
    p: &Params,
    n: usize,
    refine: usize,
    graded: bool,
) -> Result<MeshSolution> {
    let op = operator(p, n, refine, graded)?;
    let masses = stationary_masses(&op)?;
    let moments = moments(&op, &masses)?;
    check(p, &op, &masses, &moments)?;
    Ok(MeshSolution {
        op,
        masses,
        moments,
    })
}

/// The mass of state `s` in the cells receiving its resets at v_r (its
/// atom there, if it has one, plus the density's share of those cells).
pub(crate) fn target_mass(sol: &MeshSolution, s: usize) -> f64 {
    let ns = sol.op.mesh.states;
    sol.op.mesh.target[s]
        .iter()
        .map(|&(i, _)| sol.masses[i * ns + s])
        .sum()
}

/// A row where the null vector of A is far from 0 (middle cell, the state
/// of largest π): pinned when r = 0.
fn pinned_row(op: &NoiseOperator) -> usize {
    let pi = &op.chain.pi;
    let s = (0..pi.len())
        .max_by(|&a, &b| pi[a].total_cmp(&pi[b]))
        .unwrap_or(0);
    (op.mesh.widths.len() / 2) * op.mesh.states + s
}

/// Solve B x = b (r > 0) or, at r = 0, the singular B x = b with row
/// `pinned_row` replaced by x_k = b_k.
fn solve_b(op: &NoiseOperator, b: &mut [f64]) -> Result<()> {
    let mut a = op.band(None);
    if !(op.rate > 0.0) {
        let k = pinned_row(op);
        for j in a.row_range(k) {
            a.set(k, j, 0.0);
        }
        a.set(k, k, 1.0);
    }
    a.factor().map_err(|e| Error::Numerical {
        method: METHOD,
        reason: format!("{e}"),
    })?;
    a.solve(b);
    Ok(())
}

/// The stationary cell masses, total 1: B m = -R m with R m known, since
/// the state masses are π (the noise is autonomous and both reset rules
/// map π to π); at r = 0 the pinned singular system.
fn stationary_masses(op: &NoiseOperator) -> Result<Vec<f64>> {
    let mut b = vec![0.0; op.dim()];
    if op.rate > 0.0 {
        let inf: Vec<f64> = op.influx(&op.chain.pi).iter().map(|x| -x).collect();
        op.add_target(&inf, &mut b);
    } else {
        b[pinned_row(op)] = 1.0;
    }
    solve_b(op, &mut b)?;
    let total: f64 = b.iter().sum();
    if !(total.is_finite() && total > 0.0) {
        return Err(Error::Numerical {
            method: METHOD,
            reason: format!("stationary solve gave total mass {total}"),
        });
    }
    b.iter_mut().for_each(|x| *x /= total);
    Ok(b)
}

/// The state sums Y of A y = -(m∘f) (Eq. (N24)): Qᵀ Y = -F, Σ Y = 0 when a
/// reset keeps the state; (Qᵀ - r) Y = -F when it re-draws it.
fn dual_state_sums(op: &NoiseOperator, f: &[f64]) -> Result<Vec<f64>> {
    let c = &op.chain;
    let ns = c.states();
    let mut a: Vec<Vec<f64>> = (0..ns)
        .map(|i| (0..ns).map(|j| c.q[j][i]).collect())
        .collect();
    let mut b: Vec<f64> = f.iter().map(|x| -x).collect();
    match op.noise {
        NoiseAtReset::Kept => {
            a[ns - 1] = vec![1.0; ns];
            b[ns - 1] = 0.0;
        }
        NoiseAtReset::Redrawn => (0..ns).for_each(|i| a[i][i] -= op.rate),
    }
    chain::solve(&a, &b, METHOD)
}

/// `<v>`, `<v²>`, per-state masses and means, D_eff, tail mass.
fn moments(op: &NoiseOperator, m: &[f64]) -> Result<NoiseMoments> {
    let ns = op.mesh.states;
    let v = &op.mesh.centres;
    let mut state_means = vec![0.0; ns];
    let (mut v1, mut v2) = (0.0, 0.0);
    for (c, &vi) in m.chunks_exact(ns).zip(v) {
        for (s, &x) in c.iter().enumerate() {
            state_means[s] += x * vi;
            v1 += x * vi;
            v2 += x * vi * vi;
        }
    }
    let f: Vec<f64> = v.iter().map(|&vi| vi - v1).collect();
    let mut b: Vec<f64> = m.iter().enumerate().map(|(k, x)| -x * f[k / ns]).collect();
    if op.rate > 0.0 {
        let big_f: Vec<f64> = op.state_sums(&b).iter().map(|x| -x).collect();
        let y = dual_state_sums(op, &big_f)?;
        let inf: Vec<f64> = op.influx(&y).iter().map(|x| -x).collect();
        op.add_target(&inf, &mut b);
    } else {
        b[pinned_row(op)] = 0.0;
    }
    solve_b(op, &mut b)?;
    let d_eff = b.iter().enumerate().map(|(k, y)| f[k / ns] * y).sum();
    Ok(NoiseMoments {
        cells: op.mesh.widths.len(),
        v_mean: v1,
        v2,
        d_eff,
        state_means,
        state_masses: op.state_sums(m),
        tail_mass: tail_mass(op, m),
    })
}

/// Eq. (N26): on a truncated domain, the mass beyond each end estimated
/// as the end cell's density times the decay length T/|a_s - g(v_end)| of
/// the tail, summed over states.
fn tail_mass(op: &NoiseOperator, m: &[f64]) -> f64 {
    let mesh = &op.mesh;
    if !mesh.truncated {
        return 0.0;
    }
    let (ns, n, t) = (mesh.states, mesh.widths.len(), op.chain.temperature);
    let ends = [(0, mesh.edges[0]), (n - 1, mesh.edges[n])];
    let mut tail = 0.0;
    for (i, v) in ends {
        for s in 0..ns {
            let drift = (op.chain.levels[s] - op.drag.force(v)).abs();
            tail += m[i * ns + s] / mesh.widths[i] * t / drift;
        }
    }
    tail
}

/// Mass 1, masses ≥ 0 to rounding, state masses π, 0 ≤ `<v²>` ≤ the
/// domain's bound, D_eff ≥ 0, tail mass below 1e-10; else refused.
fn check(p: &Params, op: &NoiseOperator, m: &[f64], mo: &NoiseMoments) -> Result<()> {
    let refuse = |what: String| {
        Err(Error::Numerical {
            method: METHOD,
            reason: format!("{what}: the mesh does not resolve the density; refused"),
        })
    };
    let top = m.iter().fold(0.0f64, |a, &x| a.max(x));
    let low = m.iter().fold(0.0f64, |a, &x| a.min(x));
    if !(low >= -1e-12 * top) {
        return refuse(format!("a negative cell mass {low:e}"));
    }
    for (s, (&ms, &pi)) in mo.state_masses.iter().zip(&op.chain.pi).enumerate() {
        if !((ms - pi).abs() <= 1e-9) {
            return refuse(format!("state {s} has mass {ms}, not pi = {pi}"));
        }
    }
    let (lo, hi) = (op.mesh.edges[0], op.mesh.edges[op.mesh.widths.len()]);
    let bound = lo.powi(2).max(hi.powi(2));
    if !(mo.v2 >= 0.0 && mo.v2 <= bound) {
        return refuse(format!("<v^2> = {:e} outside [0, {bound:e}]", mo.v2));
    }
    if !(mo.d_eff >= 0.0 && mo.d_eff.is_finite()) {
        return refuse(format!("D_eff = {:e}", mo.d_eff));
    }
    if !(mo.tail_mass <= 1e-10) {
        return Err(Error::Numerical {
            method: METHOD,
            reason: format!(
                "the truncated domain [{lo}, {hi}] leaves a tail mass {:e} > 1e-10 at T = {}",
                mo.tail_mass,
                p.chain()?.temperature
            ),
        });
    }
    Ok(())
}

/// Richardson extrapolation of a value on meshes N/4, N/2, N with the
/// observed order (Eq. (N27)): (value, error estimate, order). Where the
/// differences do not shrink like h^p with 1/2 ≤ p ≤ 3 the fine value is
/// returned with twice its last change as the estimate (order NaN).
pub(crate) fn richardson(x0: f64, x1: f64, x2: f64) -> (f64, f64, f64) {
    let (d0, d1) = (x1 - x0, x2 - x1);
    let floor = 1e-14 * x2.abs();
    if d1.abs() <= floor {
        return (x2, d1.abs().max(d0.abs()).max(floor), f64::NAN);
    }
    let rho = d0 / d1;
    if (1.4..=8.0).contains(&rho) {
        let corr = d1 / (rho - 1.0);
        (x2 + corr, corr.abs().max(floor), rho.log2())
    } else {
        (x2, 2.0 * d1.abs(), f64::NAN)
    }
}
