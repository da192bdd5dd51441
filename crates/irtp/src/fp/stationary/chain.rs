//! A finite-state noise chain with thermal noise as the stationary
//! engine's space (docs/equations.md, "Fokker-Planck with N states", Eqs.
//! (N20)-(N27)): N coupled densities p_s(v) on the chain's mesh, the band
//! operator ([`NoiseOperator`]) solved by the shared band LU; `<v>`,
//! `<v²>`, the per-state means and the exact D_eff of the discrete
//! generator (Eqs. (N23)-(N25)), extrapolated over cells/4, cells/2, cells
//! with their observed order.

use super::{Moments, Stationary, StationaryOptions, StationarySpace};
use crate::error::{Error, Result};
use crate::fp::extrapolate::richardson;
use crate::fp::grid::Mesh;
use crate::fp::nstate::{operator, Hold, NoiseOperator};
use crate::model::atoms::reset_atom_states;
use crate::model::noise::chain;
use crate::model::reset::NoiseAtReset;
use crate::model::reset::Reset;
use crate::model::Drag;
use crate::model::{Params, VelocityAtom};
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
    /// The held block of an exponential refractory period (Eq. (R10)).
    pub hold: Option<Hold>,
    pub masses: Vec<f64>,
    pub moments: NoiseMoments,
}

/// Solve and check the stationary state on the mesh of `n << refine` cells.
pub(crate) fn solve_mesh(
    p: &Params,
    n: usize,
    refine: usize,
    graded: bool,
) -> Result<MeshSolution> {
    let op = operator(p, n, refine, graded)?;
    let hold = Hold::of(p, &op);
    let masses = stationary_masses(&op, hold.as_ref())?;
    let moments = moments(&op, hold.as_ref(), &masses)?;
    check(p, &op, &masses, &moments)?;
    Ok(MeshSolution {
        op,
        hold,
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
    a.factor_for(METHOD)?;
    a.solve(b);
    Ok(())
}

/// The stationary cell masses, total 1 less the held mass: B m = -R m
/// with R m known, since the state masses are π (the noise is autonomous
/// and both reset rules map π to π); with a refractory period R m is the
/// re-entry κ q of the held masses (Eq. (R10)); at r = 0 the pinned
/// singular system.
fn stationary_masses(op: &NoiseOperator, hold: Option<&Hold>) -> Result<Vec<f64>> {
    let mut b = vec![0.0; op.dim()];
    if let Some(h) = hold {
        h.stationary_source(op, &mut b);
    } else if op.rate > 0.0 {
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
    let continuous = hold.map_or(1.0, |h| 1.0 - h.mass());
    b.iter_mut().for_each(|x| *x = *x / total * continuous);
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

/// `<v>`, `<v²>`, per-state masses and means, D_eff, tail mass; the
/// held masses of a refractory period `hold` count at their held
/// velocities (Eq. (R10)).
fn moments(op: &NoiseOperator, hold: Option<&Hold>, m: &[f64]) -> Result<NoiseMoments> {
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
    let mut state_masses = op.state_sums(m);
    if let Some(h) = hold {
        let (u1, u2) = h.velocity_moments();
        for (s, &q) in h.q.iter().enumerate() {
            state_means[s] += q * u1;
            state_masses[s] += q;
            v1 += q * u1;
            v2 += q * u2;
        }
    }
    let f: Vec<f64> = v.iter().map(|&vi| vi - v1).collect();
    let mut b: Vec<f64> = m.iter().enumerate().map(|(k, x)| -x * f[k / ns]).collect();
    let big_f: Vec<f64> = op.state_sums(&b).iter().map(|x| -x).collect();
    let mut held = 0.0;
    if let Some(h) = hold {
        let y = h.dual_state_sums(op, &big_f, h.velocity_moments().0 - v1)?;
        h.dual_source(op, &y, v1, &mut b)?;
        held = h.d_eff_share(op, &y, v1);
    } else if op.rate > 0.0 {
        let y = dual_state_sums(op, &big_f)?;
        let inf: Vec<f64> = op.influx(&y).iter().map(|x| -x).collect();
        op.add_target(&inf, &mut b);
    } else {
        b[pinned_row(op)] = 0.0;
    }
    solve_b(op, &mut b)?;
    let d_eff = b
        .iter()
        .enumerate()
        .map(|(k, y)| f[k / ns] * y)
        .sum::<f64>()
        + held;
    Ok(NoiseMoments {
        cells: op.mesh.widths.len(),
        v_mean: v1,
        v2,
        d_eff,
        state_means,
        state_masses,
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

/// What the N-state stationary solver adds to [`Stationary`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct NoiseSummary {
    /// The noise levels a_s.
    pub levels: Vec<f64>,
    /// The stationary law π of the noise.
    pub pi: Vec<f64>,
    /// Temperature T.
    pub temperature: f64,
    /// The computational domain (truncated where unbounded, Eq. (N26)).
    pub domain: (f64, f64),
    /// Per-state densities p_s (cell averages, fine mesh), state-major.
    pub densities: Vec<Vec<f64>>,
    /// Per-state means E[v 1{η = s}] (extrapolated if extrapolating).
    pub state_means: Vec<f64>,
    /// Error estimates of `<v>`, `<v²>`, D_eff (Eq. (N27); None without
    /// extrapolation).
    pub errors: Option<[f64; 3]>,
    /// Error estimates of the per-state means.
    pub state_mean_errors: Option<Vec<f64>>,
    /// Observed convergence orders of `<v>`, `<v²>`, D_eff (NaN where the
    /// differences were not in an asymptotic regime).
    pub orders: Option<[f64; 3]>,
    /// The estimated tail mass beyond a truncated domain (fine mesh).
    pub tail_mass: f64,
    /// Error estimate of the fine-mesh densities in L1 (summed over the
    /// states): Σ_k Σ_s |m_{2k,s} + m_{2k+1,s} - m'_{k,s}|, the change of
    /// the cell masses from the mesh N/2 (m') to N (nested), which
    /// estimates a first-order scheme's error (None without extrapolation).
    pub density_l1_error: Option<f64>,
    /// Observables on the meshes N/4, N/2, N (or N alone).
    pub meshes: Vec<NoiseMoments>,
    /// The held masses q_s per state of an exponential refractory period
    /// (Eq. (R10): r/(κ + r) π); empty without one.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub held: Vec<f64>,
}

impl StationarySpace for MeshSolution {
    const NEST: usize = 4;
    const NEST_RULE: &'static str =
        "a multiple of 4 with a noise model (extrapolation uses cells/2 and cells/4)";

    /// cells/4 refined 0, 1, 2 times (Eq. (N27)); or cells alone.
    fn meshes(o: &StationaryOptions) -> Vec<(usize, usize)> {
        if o.extrapolate {
            (0..3).map(|k| (o.cells / 4, k)).collect()
        } else {
            vec![(o.cells, 0)]
        }
    }

    fn solve(p: &Params, mesh: Mesh, n: usize, refine: usize) -> Result<Self> {
        solve_mesh(p, n, refine, mesh == Mesh::Graded)
    }

    fn assemble(params: &Params, opts: &StationaryOptions, sols: Vec<Self>) -> Result<Stationary> {
        let fine = sols.last().expect("one mesh at least");
        let mo: Vec<NoiseMoments> = sols.iter().map(|s| s.moments.clone()).collect();
        let pick = |f: &dyn Fn(&NoiseMoments) -> f64| match mo.as_slice() {
            [a, b, c] => richardson(f(a), f(b), f(c)),
            _ => (f(&mo[0]), f64::NAN, f64::NAN),
        };
        let (v_mean, v2, d_eff) = (pick(&|m| m.v_mean), pick(&|m| m.v2), pick(&|m| m.d_eff));
        let ns = fine.op.mesh.states;
        let means: Vec<(f64, f64, f64)> = (0..ns).map(|s| pick(&|m| m.state_means[s])).collect();
        let mesh = &fine.op.mesh;
        let n = mesh.widths.len();
        let densities: Vec<Vec<f64>> = (0..ns)
            .map(|s| {
                (0..n)
                    .map(|i| fine.masses[i * ns + s] / mesh.widths[i])
                    .collect()
            })
            .collect();
        let held = fine.hold.as_ref().map_or(0.0, Hold::mass);
        let (atoms, densities) = split_atoms(params, &sols, densities, held)?;
        let p = (0..n)
            .map(|i| densities.iter().map(|d| d[i]).sum())
            .collect();
        let moments = |m: &NoiseMoments| Moments {
            cells: m.cells,
            mass: 1.0,
            v_mean: m.v_mean,
            v2: m.v2,
            d_eff: m.d_eff,
            refractory_mass: held,
            x_moments: None,
        };
        let extrapolated = opts.extrapolate;
        let summary = NoiseSummary {
            levels: fine.op.chain.levels.clone(),
            pi: fine.op.chain.pi.clone(),
            temperature: fine.op.chain.temperature,
            domain: (mesh.edges[0], mesh.edges[n]),
            densities,
            state_means: means.iter().map(|m| m.0).collect(),
            errors: extrapolated.then_some([v_mean.1, v2.1, d_eff.1]),
            state_mean_errors: extrapolated.then(|| means.iter().map(|m| m.1).collect()),
            orders: extrapolated.then_some([v_mean.2, v2.2, d_eff.2]),
            tail_mass: fine.moments.tail_mass,
            density_l1_error: extrapolated.then(|| l1_change(&sols[1].masses, &fine.masses, ns)),
            meshes: mo.clone(),
            held: fine.hold.as_ref().map_or_else(Vec::new, |h| h.q.clone()),
        };
        Ok(Stationary {
            params: params.clone(),
            mesh: opts.mesh,
            cells: n,
            grading: mesh.grading,
            edge_exponent: f64::NAN,
            v: mesh.centres.clone(),
            edges: mesh.edges.clone(),
            widths: mesh.widths.clone(),
            p,
            p_plus: Vec::new(),
            p_minus: Vec::new(),
            mass: fine.masses.iter().sum::<f64>() + held,
            v_mean: v_mean.0,
            v2: v2.0,
            d_eff: d_eff.0,
            d_eff_err: extrapolated.then_some(d_eff.1),
            refractory_mass: held,
            refractory: [0.0; 2],
            atoms,
            x_mean: None,
            x2: None,
            extrapolated,
            fine: moments(&fine.moments),
            coarse: extrapolated.then(|| moments(&mo[1])),
            coarsest: extrapolated.then(|| moments(&mo[0])),
            noise: Some(summary),
        })
    }
}

/// The point mass at v_r of the states that hold one
/// ([`reset_atom_states`]) and of a refractory period (its `held` mass,
/// exact on every mesh: error rounding) and the fine-mesh densities
/// without it. A
/// state's atom sits in the two cells beside v_r that receive its resets
/// (no transport crosses its fixed point); their mass is the atom plus the
/// density's share of those cells, which vanishes with the mesh: the atom
/// is that mass Richardson-extrapolated over the meshes N/4, N/2, N (Eq.
/// (N27)), with its error estimate (NaN on one mesh). Each cell gives up
/// its share of the atom (at most its mass). Refused (exit 4) unless the
/// densities' mass and the atom's add up to 1 within the atom's error.
fn split_atoms(
    params: &Params,
    sols: &[MeshSolution],
    mut densities: Vec<Vec<f64>>,
    held: f64,
) -> Result<(Vec<VelocityAtom>, Vec<Vec<f64>>)> {
    let states = reset_atom_states(params);
    let atom = !states.is_empty() || held > 0.0;
    let Some(vr) = params.reset().point().filter(|_| atom) else {
        return Ok((Vec::new(), densities));
    };
    let fine = sols.last().expect("one mesh at least");
    let (mut mass, mut err) = (held, 1e-14 * held);
    for &s in &states {
        let x: Vec<f64> = sols.iter().map(|m| target_mass(m, s)).collect();
        let (value, e) = match x.as_slice() {
            [a, b, c] => {
                let (v, e, _) = richardson(*a, *b, *c);
                (v, e)
            }
            _ => (x[0], f64::NAN),
        };
        for &(i, f) in &fine.op.mesh.target[s] {
            let w = fine.op.mesh.widths[i];
            let cell = densities[s][i] * w;
            densities[s][i] = (cell - (value * f).min(cell)) / w;
        }
        mass += value;
        err += e;
    }
    let widths = &fine.op.mesh.widths;
    let total: f64 = densities
        .iter()
        .map(|d| d.iter().zip(widths).map(|(p, w)| p * w).sum::<f64>())
        .sum::<f64>()
        + mass;
    if !((total - 1.0).abs() <= err + 1e-12) {
        return Err(Error::Numerical {
            method: "fp stationary",
            reason: format!(
                "the density and the atom at v = {vr} add up to {total}, not 1 within the atom's error {err:e}"
            ),
        });
    }
    Ok((vec![VelocityAtom { v: vr, mass, err }], densities))
}

/// Σ_k Σ_s |fine_{2k,s} + fine_{2k+1,s} - coarse_{k,s}| over nested meshes.
fn l1_change(coarse: &[f64], fine: &[f64], ns: usize) -> f64 {
    coarse
        .chunks_exact(ns)
        .zip(fine.chunks_exact(2 * ns))
        .map(|(c, f)| {
            (0..ns)
                .map(|s| (f[s] + f[ns + s] - c[s]).abs())
                .sum::<f64>()
        })
        .sum()
}
