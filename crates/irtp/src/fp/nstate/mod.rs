//! Fokker-Planck solvers for any finite-state noise and thermal noise
//! (docs/equations.md, "Fokker-Planck with N states", Eqs. (N20)-(N29)).
//!
//! Forward equations of N coupled densities p_s(v, t) (Eq. (N20)):
//!   ∂_t p_s = -∂_v[(a_s - g) p_s] + T ∂_v² p_s + Σ_s' Q_s's p_s' - r p_s
//!             + r [W M(t)]_s δ(v - v_r),
//! M_s = ∫ p_s dv, W the reset's noise rule (kept: identity; re-drawn:
//! π 1ᵀ), no flux through the domain's ends.
//!
//! A separate path from the two-state solver ([`super::stationary()`],
//! whose subtraction-free block-Thomas elimination and graded meshes serve
//! the paper's noise bit for bit): the N-state operator is assembled as a
//! band matrix (N sub- and super-diagonals) and solved by the shared
//! [`crate::numerics::band`] LU, its mesh built from the two-state
//! solver's graded [`super::grid`] pieces, its time stepping the shared
//! TR-BDF2.

mod mesh;
mod operator;
mod stationary;
mod time;

pub use operator::NoiseOperator;
pub use stationary::NoiseMoments;
pub(crate) use time::{msd, transient};

use super::stationary::{Moments, Stationary, StationaryOptions, MAX_CELLS, MIN_CELLS};
use crate::error::{Error, Result};
use crate::model::atoms::reset_atom_states;
use crate::model::reset::Reset;
use crate::model::{Params, VelocityAtom};
use serde::{Deserialize, Serialize};
use stationary::{richardson, solve_mesh};

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
}

/// Options the N-state solver accepts: no schedule modifier, `cells` in range and a multiple of 4 when extrapolating (the
/// meshes N/4, N/2, N nest).
fn check(p: &Params, o: &StationaryOptions) -> Result<()> {
    if !(MIN_CELLS..=MAX_CELLS).contains(&o.cells) {
        return Err(Error::invalid(
            "cells",
            o.cells,
            format!("{MIN_CELLS} <= cells <= {MAX_CELLS}"),
        ));
    }
    if o.extrapolate && o.cells % 4 != 0 {
        return Err(Error::invalid(
            "cells",
            o.cells,
            "a multiple of 4 with a noise model (extrapolation uses cells/2 and cells/4)",
        ));
    }
    refuse_protocols(p, "fp")
}

/// A noise model runs with Poisson resetting (any target, noise kept or
/// re-drawn) only: the schedule modifiers are refused by flag.
pub(crate) fn refuse_protocols(p: &Params, method: &str) -> Result<()> {
    if let Some(f) = p.schedule().features().first() {
        return Err(Error::invalid(
            f.flag(),
            p.schedule().spec_of(*f),
            format!("no schedule modifier with a noise model in {method} (Poisson resetting only)"),
        ));
    }
    Ok(())
}

/// The stationary solve of [`super::stationary()`] for a noise model.
pub(crate) fn stationary(params: &Params, opts: &StationaryOptions) -> Result<Stationary> {
    check(params, opts)?;
    let graded = opts.mesh == super::Mesh::Graded;
    let sols = if opts.extrapolate {
        let base = opts.cells / 4;
        (0..3)
            .map(|k| solve_mesh(params, base, k, graded))
            .collect::<Result<Vec<_>>>()?
    } else {
        vec![solve_mesh(params, opts.cells, 0, graded)?]
    };
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
    let (atoms, densities) = split_atoms(params, &sols, densities)?;
    let p = (0..n)
        .map(|i| densities.iter().map(|d| d[i]).sum())
        .collect();
    let moments = |m: &NoiseMoments| Moments {
        cells: m.cells,
        mass: 1.0,
        v_mean: m.v_mean,
        v2: m.v2,
        d_eff: m.d_eff,
        refractory_mass: 0.0,
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
    };
    Ok(Stationary {
        params: *params,
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
        mass: fine.masses.iter().sum(),
        v_mean: v_mean.0,
        v2: v2.0,
        d_eff: d_eff.0,
        d_eff_err: extrapolated.then_some(d_eff.1),
        refractory_mass: 0.0,
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

/// The point mass at v_r of the states that hold one
/// ([`reset_atom_states`]) and the fine-mesh densities without it. A
/// state's atom sits in the two cells beside v_r that receive its resets
/// (no transport crosses its fixed point); their mass is the atom plus the
/// density's share of those cells, which vanishes with the mesh: the atom
/// is that mass Richardson-extrapolated over the meshes N/4, N/2, N (Eq.
/// (N27)), with its error estimate (NaN on one mesh). Each cell gives up
/// its share of the atom (at most its mass). Refused (exit 4) unless the
/// densities' mass and the atom's add up to 1 within the atom's error.
fn split_atoms(
    params: &Params,
    sols: &[stationary::MeshSolution],
    mut densities: Vec<Vec<f64>>,
) -> Result<(Vec<VelocityAtom>, Vec<Vec<f64>>)> {
    let states = reset_atom_states(params);
    let Some(vr) = params.reset().point().filter(|_| !states.is_empty()) else {
        return Ok((Vec::new(), densities));
    };
    let fine = sols.last().expect("one mesh at least");
    let (mut mass, mut err) = (0.0, 0.0);
    for &s in &states {
        let x: Vec<f64> = sols.iter().map(|m| stationary::target_mass(m, s)).collect();
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
