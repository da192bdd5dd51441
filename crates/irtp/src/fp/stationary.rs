//! Direct stationary solve, `<v>`, `<v²>` (paper Eq. (33)) and the exact D_eff.

use super::grid::{Grid, Mesh};
use super::position::stationary_x;
use super::refractory::Held;
use super::solve::{solve_free, solve_reset};
use crate::error::{Error, Result};
use crate::model::reset::NoiseAtReset;
use crate::model::reset::{Reset, Solver};
use crate::model::{Params, VelocityAtom};
use serde::{Deserialize, Serialize};

/// Smallest number of cells accepted.
pub const MIN_CELLS: usize = 16;
/// Largest number of cells accepted (memory: ~100 bytes per cell).
pub const MAX_CELLS: usize = 50_000_000;

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
    /// Its + and - parts.
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
    pub noise: Option<super::nstate::NoiseSummary>,
}

fn check_options(p: &Params, o: &StationaryOptions) -> Result<()> {
    if !(MIN_CELLS..=MAX_CELLS).contains(&o.cells) {
        return Err(Error::invalid(
            "cells",
            o.cells,
            format!("{MIN_CELLS} <= cells <= {MAX_CELLS}"),
        ));
    }
    if o.extrapolate && o.cells % 2 != 0 {
        return Err(Error::invalid(
            "cells",
            o.cells,
            "an even number (extrapolation uses cells/2 as the coarse mesh)",
        ));
    }
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

/// Mesh with `n` cells, `halves` times refined (each refinement splits every
/// cell in two in the mesh parameter): the graded mesh splits its cells at v_r
/// (and at v = 0 where g'(0) = ∞) in proportion to length, so nested meshes
/// share the same split.
pub(crate) fn make_grid(p: &Params, mesh: Mesh, n: usize, refine: usize) -> Result<Grid> {
    match mesh {
        Mesh::Uniform => Ok(Grid::uniform(p, n << refine)),
        Mesh::Graded => super::grid::graded_mesh(p, n, refine),
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

/// The observables on the (unrefined) mesh of `cells` cells.
fn coarse_moments(p: &Params, mesh: Mesh, cells: usize) -> Result<Moments> {
    crate::parallel::check_stop()?;
    let g = make_grid(p, mesh, cells, 0)?;
    let h = Held::new(&g, p);
    let (m, q) = stationary_masses(&g, p, h.as_ref())?;
    Ok(moments(&g, p, h.as_ref(), &m, q))
}

/// Error estimate of the first-order extrapolation E₁ = 2 x₂ - x₁ from
/// the values x₀, x₁, x₂ on the meshes N/4, N/2, N. With x_h = x + a h +
/// b h², E₁ - x = -2 b h² and E₀ = 2 x₁ - x₀ has 4 times that error, so
/// |E₁ - E₀| is 3 times E₁'s error. Where the changes d₀ = x₁ - x₀,
/// d₁ = x₂ - x₁ shrink like h^p with 1/2 <= p <= 3 (1.4 <= d₀/d₁ <= 8,
/// the N-state solver's check, Eq. (N27)) the estimate is 2 |E₁ - E₀|
/// (6 times the model's error: E₀'s error may pass near 0 where the
/// density has a kink between nodes, at v_r); otherwise (not yet
/// asymptotic) 2 |d₁| + 2 |E₁ - E₀|. Never below 1e-14 |x₂|.
fn extrapolation_error(x0: f64, x1: f64, x2: f64) -> f64 {
    let (d0, d1) = (x1 - x0, x2 - x1);
    let gap = ((2.0 * x2 - x1) - (2.0 * x1 - x0)).abs();
    let floor = 1e-14 * x2.abs();
    let rho = d0 / d1;
    let est = if (1.4..=8.0).contains(&rho) {
        2.0 * gap
    } else {
        2.0 * (d1.abs() + gap)
    };
    est.max(floor)
}

/// Solve the stationary forward equations directly (no time stepping), in O(N).
///
/// With a noise model (`params.noise()` is Some) the N-state solver runs
/// (docs/equations.md (N20)-(N27)): N coupled densities, thermal noise,
/// `noise` filled in and `p_plus`, `p_minus` empty.
pub fn stationary(params: &Params, opts: &StationaryOptions) -> Result<Stationary> {
    params.require(Solver::FpStationary)?;
    if params.noise().is_some() {
        return super::nstate::stationary(params, opts);
    }
    check_options(params, opts)?;
    let g = if opts.extrapolate {
        make_grid(params, opts.mesh, opts.cells / 2, 1)?
    } else {
        make_grid(params, opts.mesh, opts.cells, 0)?
    };
    let held = Held::new(&g, params);
    crate::parallel::check_stop()?;
    let (m, q) = stationary_masses(&g, params, held.as_ref())?;
    crate::parallel::check_stop()?;
    let fine = moments(&g, params, held.as_ref(), &m, q);
    crate::parallel::check_stop()?;
    let coarse = opts
        .extrapolate
        .then(|| coarse_moments(params, opts.mesh, opts.cells / 2))
        .transpose()?;
    let coarsest = (opts.extrapolate && opts.cells >= 32)
        .then(|| coarse_moments(params, opts.mesh, opts.cells / 4))
        .transpose()?;
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
    for (name, x) in [
        ("<v>", v_mean),
        ("<v^2>", v2),
        ("<x>", x_mean.unwrap_or(0.0)),
        ("<x^2>", x2.unwrap_or(0.0)),
    ] {
        if !x.is_finite() {
            return Err(Error::Numerical {
                method: "fp stationary",
                reason: format!("{name} = {x}"),
            });
        }
    }
    check_invariants(params, v2, d_eff)?;
    let p_plus: Vec<f64> = m.iter().zip(&g.widths).map(|(c, h)| c[0] / h).collect();
    let p_minus: Vec<f64> = m.iter().zip(&g.widths).map(|(c, h)| c[1] / h).collect();
    let p = p_plus.iter().zip(&p_minus).map(|(a, b)| a + b).collect();
    Ok(Stationary {
        params: *params,
        mesh: opts.mesh,
        cells: opts.cells,
        grading: g.grading,
        edge_exponent: params.edge_exponent(),
        v: g.centres.clone(),
        edges: g.edges.clone(),
        widths: g.widths.clone(),
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
