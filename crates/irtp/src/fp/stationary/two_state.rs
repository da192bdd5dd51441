//! The paper's two noise states ±Σ as the stationary engine's space:
//! block-Thomas elimination ([`super::super::solve`]) on the paper's
//! graded mesh, the refractory block ([`Held`]) and the position moments
//! under position resetting; extrapolation from the meshes cells/2,
//! cells (first order) with the error from cells/4.

use super::{Moments, Stationary, StationaryOptions, StationarySpace};
use crate::error::{Error, Result};
use crate::fp::extrapolate::extrapolation_error;
use crate::fp::grid::{Grid, Mesh};
use crate::fp::position::stationary_x;
use crate::fp::refractory::Held;
use crate::fp::solve::{solve_free, solve_reset};
use crate::model::reset::NoiseAtReset;
use crate::model::reset::Reset;
use crate::model::{Params, VelocityAtom};

/// The two-state solution on one mesh.
pub(crate) struct TwoState {
    g: Grid,
    /// Continuous cell masses [m+, m-].
    m: Vec<[f64; 2]>,
    /// Refractory masses (q+, q-).
    q: [f64; 2],
    mo: Moments,
}

impl StationarySpace for TwoState {
    const NEST: usize = 2;
    const NEST_RULE: &'static str =
        "an even number (extrapolation uses cells/2 as the coarse mesh)";

    fn check(p: &Params) -> Result<()> {
        if !(p.lambda() > 0.0) && !(p.rate() > 0.0) {
            return Err(Error::invalid(
                "lambda",
                p.lambda(),
                "lambda > 0 when rate = 0 (otherwise each state sits at its edge forever)",
            ));
        }
        if let (Some(x), false) = (p.schedule().position, p.rate() > 0.0) {
            return Err(Error::invalid(
                "reset_position",
                x.x,
                "a reset rate > 0 (without resets the position has no stationary law)",
            ));
        }
        Ok(())
    }

    /// cells/4 (the error check, with cells >= 32), cells/2 and cells as
    /// cells/2 refined once; or cells alone.
    fn meshes(o: &StationaryOptions) -> Vec<(usize, usize)> {
        match (o.extrapolate, o.cells >= 32) {
            (false, _) => vec![(o.cells, 0)],
            (true, false) => vec![(o.cells / 2, 0), (o.cells / 2, 1)],
            (true, true) => vec![(o.cells / 4, 0), (o.cells / 2, 0), (o.cells / 2, 1)],
        }
    }

    fn solve(p: &Params, mesh: Mesh, n: usize, refine: usize) -> Result<Self> {
        let g = make_grid(p, mesh, n, refine)?;
        crate::parallel::check_stop()?;
        let held = Held::new(&g, p);
        let (m, q) = stationary_masses(&g, p, held.as_ref())?;
        crate::parallel::check_stop()?;
        let mo = moments(&g, p, held.as_ref(), &m, q);
        Ok(TwoState { g, m, q, mo })
    }

    fn assemble(
        params: &Params,
        opts: &StationaryOptions,
        mut sols: Vec<Self>,
    ) -> Result<Stationary> {
        let TwoState { g, m, q, mo: fine } = sols.pop().expect("the fine mesh");
        let coarse = sols.pop().map(|s| s.mo);
        let coarsest = sols.pop().map(|s| s.mo);
        // ∞ (λ = 0) stays ∞.
        let ex = |f: f64, c: f64| if f.is_finite() { 2.0 * f - c } else { f };
        let (v_mean, v2, d_eff) = match &coarse {
            Some(c) => (
                ex(fine.v_mean, c.v_mean),
                ex(fine.v2, c.v2),
                ex(fine.d_eff, c.d_eff),
            ),
            None => (fine.v_mean, fine.v2, fine.d_eff),
        };
        let xm = |i: usize| match &coarse {
            Some(c) => fine.x_moments.zip(c.x_moments).map(|(f, c)| ex(f[i], c[i])),
            None => fine.x_moments.map(|f| f[i]),
        };
        let (x_mean, x2) = (xm(0), xm(1));
        let d_eff_err = match (&coarse, &coarsest) {
            (Some(c), Some(cc)) if d_eff.is_finite() => {
                Some(extrapolation_error(cc.d_eff, c.d_eff, fine.d_eff))
            }
            _ => None,
        };
        check_values(
            params,
            [v_mean, v2, x_mean.unwrap_or(0.0), x2.unwrap_or(0.0)],
            d_eff,
        )?;
        let p_plus: Vec<f64> = m.iter().zip(&g.widths).map(|(c, h)| c[0] / h).collect();
        let p_minus: Vec<f64> = m.iter().zip(&g.widths).map(|(c, h)| c[1] / h).collect();
        let p = p_plus.iter().zip(&p_minus).map(|(a, b)| a + b).collect();
        Ok(Stationary {
            params: params.clone(),
            mesh: opts.mesh,
            cells: opts.cells,
            grading: g.grading,
            edge_exponent: params.edge_exponent(),
            v: g.centres,
            edges: g.edges,
            widths: g.widths,
            p,
            p_plus,
            p_minus,
            mass: fine.mass,
            v_mean,
            v2,
            d_eff,
            d_eff_err,
            refractory_mass: q[0] + q[1],
            refractory: q,
            atoms: refractory_atoms(params, q[0] + q[1], coarse.map(|c| c.refractory_mass)),
            x_mean,
            x2,
            extrapolated: coarse.is_some(),
            fine,
            coarse,
            coarsest,
            noise: None,
        })
    }
}

/// `<v>`, `<v²>`, `<x>`, `<x²>` finite and the invariants of
/// [`check_invariants`], or refused.
fn check_values(params: &Params, x: [f64; 4], d_eff: f64) -> Result<()> {
    for (name, x) in ["<v>", "<v^2>", "<x>", "<x^2>"].into_iter().zip(x) {
        if !x.is_finite() {
            return Err(Error::Numerical {
                method: "fp stationary",
                reason: format!("{name} = {x}"),
            });
        }
    }
    check_invariants(params, x[1], d_eff)
}

/// Mesh with `n` cells, `halves` times refined (each refinement splits every
/// cell in two in the mesh parameter): the graded mesh splits its cells at v_r
/// (and at v = 0 where g'(0) = ∞) in proportion to length, so nested meshes
/// share the same split.
pub(crate) fn make_grid(p: &Params, mesh: Mesh, n: usize, refine: usize) -> Result<Grid> {
    match mesh {
        Mesh::Uniform => Ok(Grid::uniform(p, n << refine)),
        Mesh::Graded => crate::fp::grid::graded_mesh(p, n, refine),
    }
}

/// Stationary continuous cell masses [m+, m-] and refractory masses
/// (q+, q-) (total 1) of the discrete forward equations.
pub(crate) fn stationary_masses(
    g: &Grid,
    p: &Params,
    held: Option<&Held>,
) -> Result<(Vec<[f64; 2]>, [f64; 2])> {
    let (lambda, r) = (p.lambda(), p.rate());
    if let (Some(h), true) = (held, r > 0.0) {
        return h.stationary(g);
    }
    let n = g.cells();
    let mut m = if r > 0.0 {
        // Flips conserve the state masses' sum and equalise them: M± = 1/2
        // (for λ = 0 the symmetric choice), so the reset influx is r/2 per
        // state, the noise state kept or re-drawn.
        let mut b = vec![[0.0; 2]; n];
        let (ip, im) = g.reinject(0.5 * r, 0.5 * r);
        g.add_reset(&mut b, -ip, -im);
        solve_reset(g, lambda, r, &b)
    } else {
        solve_free(g, lambda, &vec![[0.0; 2]; n], 1.0)
    };
    let total: f64 = m.iter().map(|c| c[0] + c[1]).sum();
    if !(total.is_finite() && total > 0.0) {
        return Err(Error::Numerical {
            method: "fp stationary",
            reason: format!("stationary solve gave total mass {total}"),
        });
    }
    for c in m.iter_mut() {
        c[0] /= total;
        c[1] /= total;
    }
    Ok((m, [0.0; 2]))
}

/// `<v>`, `<v²>` and D_eff of the discrete chain with stationary masses `m`.
///
/// D_eff = Σ_s π(s) f(s) h(s) with f = v - `<v>` and -Q h = f (Q: the discrete
/// generator, Q = Bᵀ + reset re-injection), the exact Green-Kubo integral of
/// the discrete process. Computed through the dual problem Qᵀ y = -(π∘f),
/// D = Σ f y, which uses the forward solvers. Summing the + rows of
/// Qᵀ y = -(π∘f) with Y- = -Y+ gives κ Y+ = F+ := Σ π+ f, κ = 2λ when a
/// reset keeps the noise state (the re-injection r Y+ returns to the +
/// rows), κ = 2λ + r when it re-draws it (the re-injection r (Y+ + Y-)/2
/// vanishes); so Y± = ±F+/κ (the free null-space component cπ does not
/// change Σ f y since Σ π f = 0), and By = -(π∘f) - (re-injection of
/// r Y+, r Y- into e_{k+}, e_{k-}).
///
/// With a refractory block `held` the masses `q` sit at its held
/// velocities and D_eff comes from [`Held::d_eff`]; with position
/// resetting the stationary `<x>`, `<x²>` come from
/// [`stationary_x`].
pub(crate) fn moments(
    g: &Grid,
    p: &Params,
    held: Option<&Held>,
    m: &[[f64; 2]],
    q: [f64; 2],
) -> Moments {
    let (lambda, r) = (p.lambda(), p.rate());
    let n = g.cells();
    let mut mass = 0.0;
    let mut v1 = 0.0;
    let mut v2 = 0.0;
    for (c, &v) in m.iter().zip(&g.centres) {
        let w = c[0] + c[1];
        mass += w;
        v1 += w * v;
        v2 += w * v * v;
    }
    let qt = q[0] + q[1];
    if let Some(h) = held {
        let (u1, u2) = h.velocity_moments();
        mass += qt;
        v1 += qt * u1;
        v2 += qt * u2;
    }
    let x_moments = p
        .schedule()
        .position
        .map(|x| stationary_x(g, p, held, m, q, x.x));
    let d_eff = if let (true, Some(h)) = (lambda > 0.0 && r > 0.0, held) {
        h.d_eff(g, m, q, v1)
    } else if lambda > 0.0 {
        let f: Vec<f64> = g.centres.iter().map(|&v| v - v1).collect();
        let mut b: Vec<[f64; 2]> = m
            .iter()
            .zip(&f)
            .map(|(c, &fi)| [-c[0] * fi, -c[1] * fi])
            .collect();
        let y = if r > 0.0 {
            let fp: f64 = m.iter().zip(&f).map(|(c, &fi)| c[0] * fi).sum();
            let kappa = match g.noise {
                NoiseAtReset::Kept => 2.0 * lambda,
                NoiseAtReset::Redrawn => 2.0 * lambda + r,
            };
            let yp = fp / kappa;
            let (ip, im) = g.reinject(r * yp, -(r * yp));
            g.add_reset(&mut b, -ip, -im);
            solve_reset(g, lambda, r, &b)
        } else {
            solve_free(g, lambda, &b, 0.0)
        };
        (0..n).map(|i| f[i] * (y[i][0] + y[i][1])).sum()
    } else {
        f64::INFINITY
    };
    Moments {
        cells: n,
        mass,
        v_mean: v1,
        v2,
        d_eff,
        refractory_mass: qt,
        x_moments,
    }
}

/// 0 <= <v²> <= max(v_l², v_u²) and D_eff >= 0, or the answer is refused:
/// a violation means the mesh does not resolve the density.
fn check_invariants(params: &Params, v2: f64, d_eff: f64) -> Result<()> {
    let (lo, hi) = params.bounds();
    let v2_max = lo.powi(2).max(hi.powi(2));
    let refuse = |what: String| Error::Numerical {
        method: "fp stationary",
        reason: format!(
            "{what}: the mesh does not resolve the density at lambda = {}, rate = {}; refused",
            params.lambda(),
            params.rate()
        ),
    };
    if !(v2 >= 0.0 && v2 <= v2_max) {
        return Err(refuse(format!("<v^2> = {v2:e} outside [0, {v2_max:e}]")));
    }
    if !(d_eff >= 0.0) {
        return Err(refuse(format!("D_eff = {d_eff:e} < 0")));
    }
    Ok(())
}

/// The refractory point mass `q` at a point target v_r as an atom (none
/// for a random target, whose held phase is spread as its law). Summed
/// over the states, K q = W r M reads κ q = r (1 - q): no mesh quantity
/// enters, and the error estimate is the change from the coarse mesh's
/// `coarse` (rounding; at least 1e-14 q).
fn refractory_atoms(p: &Params, q: f64, coarse: Option<f64>) -> Vec<VelocityAtom> {
    match p.reset().point() {
        Some(v) if q > 0.0 => vec![VelocityAtom {
            v,
            mass: q,
            err: coarse.map_or(0.0, |c| (q - c).abs()).max(1e-14 * q),
        }],
        _ => Vec::new(),
    }
}
