//! O(N) direct solvers for the discrete forward operator.
//!
//! The upwind discretisation is the generator of a Markov jump process on
//! (cell, state): + mass in cell i moves right at rate α_i, - mass moves left
//! at rate β_i, states flip at rate λ, and reset removes mass at rate r and
//! re-injects it into the target cell of its state. In the interleaved order
//! (m+_0, m-_0, m+_1, ...) the operator without reset re-injection is block
//! tridiagonal with 2×2 blocks:
//!   (B m)+_i = α_{i-1} m+_{i-1} - (α_i + λ + r) m+_i + λ m-_i,
//!   (B m)-_i = λ m+_i - (β_i + λ + r) m-_i + β_{i+1} m-_{i+1}.
//! Hand-written because no crate offers a block-tridiagonal solve, and because
//! the elimination below is free of subtractions (in the spirit of the
//! Grassmann-Taksar-Heyman algorithm): cells of width 1e-100 at a singular
//! edge give rates α ~ 1e100 next to λ ~ 1, where a generic LU would lose all
//! digits to cancellation.

use super::grid::Grid;

/// Solve B x = b for r > 0 (B is then a nonsingular, column diagonally
/// dominant M-matrix with column sums -r). See [`ResetFactor`].
pub(crate) fn solve_reset(g: &Grid, lambda: f64, r: f64, b: &[[f64; 2]]) -> Vec<[f64; 2]> {
    let flat: Vec<f64> = b.iter().flatten().copied().collect();
    let mut x = vec![0.0; flat.len()];
    ResetFactor::new(g, lambda, r).solve(g, &flat, &mut x);
    x.chunks_exact(2).map(|c| [c[0], c[1]]).collect()
}

/// The block-Thomas factorisation of B for r > 0, reusable for several
/// right-hand sides.
///
/// The pivot blocks are D'_i = [[-(α_i+λ+r), λ+e_i], [λ, -(β_i+λ+r)]]
/// with e_0 = 0, e_{i+1} = α_i β_{i+1} (λ + e_i) / det_i. Their determinants
/// are computed as det_i = (α_i + r)(β_i + λ + r) + λ δ_i with
/// δ_i = β_i + r - e_i ≥ r obeying δ_0 = r,
/// δ_{i+1} = r + β_{i+1} [(α_i + λ) δ_i + r (β_i + λ + r)] / det_i,
/// i.e. as sums of positive terms. D'^{-1} ≤ 0 entrywise, so for b ≤ 0 every
/// intermediate is a sum of like-signed terms and x ≥ 0.
#[derive(Clone, Debug)]
pub(crate) struct ResetFactor {
    lambda: f64,
    r: f64,
    e: Vec<f64>,
    det: Vec<f64>,
}

impl ResetFactor {
    /// Factorise B on `g` with flip rate `lambda` and loss rate `r` > 0.
    pub fn new(g: &Grid, lambda: f64, r: f64) -> Self {
        let n = g.cells();
        let (al, be) = (&g.out_plus, &g.out_minus);
        let mut e = vec![0.0; n];
        let mut det = vec![0.0; n];
        let mut delta = r;
        for i in 0..n {
            det[i] = (al[i] + r) * (be[i] + lambda + r) + lambda * delta;
            if i + 1 < n {
                e[i + 1] = al[i] * be[i + 1] * (lambda + e[i]) / det[i];
                delta =
                    r + be[i + 1] * ((al[i] + lambda) * delta + r * (be[i] + lambda + r)) / det[i];
            }
        }
        ResetFactor { lambda, r, e, det }
    }

    /// inv(D'_i) y = -(1/det) [[β+λ+r, λ+e], [λ, α+λ+r]] y.
    fn inv(&self, g: &Grid, i: usize, y0: f64, y1: f64) -> [f64; 2] {
        let (lambda, r, d) = (self.lambda, self.r, self.det[i]);
        [
            -((g.out_minus[i] + lambda + r) * y0 + (lambda + self.e[i]) * y1) / d,
            -(lambda * y0 + (g.out_plus[i] + lambda + r) * y1) / d,
        ]
    }

    /// Solve B x = b on flat interleaved cell values (m+_0, m-_0, m+_1, ...);
    /// `g` must be the grid the factor was made on.
    pub fn solve(&self, g: &Grid, b: &[f64], x: &mut [f64]) {
        let n = g.cells();
        let (al, be) = (&g.out_plus, &g.out_minus);
        // Forward sweep (in x): y_i = b_i - L_i D'^{-1}_{i-1} y_{i-1}, L_i = diag(α_{i-1}, 0).
        x.copy_from_slice(b);
        for i in 1..n {
            let z = self.inv(g, i - 1, x[2 * i - 2], x[2 * i - 1]);
            x[2 * i] -= al[i - 1] * z[0];
        }
        // Back substitution: x_i = D'^{-1}_i (y_i - U_i x_{i+1}), U_i = diag(0, β_{i+1}).
        let last = self.inv(g, n - 1, x[2 * n - 2], x[2 * n - 1]);
        x[2 * n - 2..].copy_from_slice(&last);
        for i in (0..n - 1).rev() {
            let y1 = x[2 * i + 1] - be[i + 1] * x[2 * i + 3];
            let xi = self.inv(g, i, x[2 * i], y1);
            x[2 * i..2 * i + 2].copy_from_slice(&xi);
        }
    }
}

/// Solve B x = b for r = 0, where B is singular (null vector: the stationary
/// state) and 1ᵀb must vanish; returns the solution with x-_0 = `start`.
///
/// Summing the equations of cells 0..j gives the current through the edge
/// between cells j-1 and j: α_{j-1} x+_{j-1} - β_j x-_j = -R_j with
/// R_j = Σ_{i<j} (b+_i + b-_i). With the - equation of cell j this is the
/// forward recursion
///   (α_j + λ) x+_j = b-_j + (β_j + λ) x-_j - R_{j+1},
///   β_{j+1} x-_{j+1} = α_j x+_j + R_{j+1},
/// which for b = 0 multiplies positive numbers only. Values are rescaled when
/// they approach overflow (the density can span hundreds of decades).
pub(crate) fn solve_free(g: &Grid, lambda: f64, b: &[[f64; 2]], start: f64) -> Vec<[f64; 2]> {
    let n = g.cells();
    let (al, be) = (&g.out_plus, &g.out_minus);
    let homogeneous = b.iter().all(|c| c[0] == 0.0 && c[1] == 0.0);
    let mut x = vec![[0.0; 2]; n];
    let mut xm = start;
    let mut cum = 0.0;
    for j in 0..n {
        x[j][1] = xm;
        cum += b[j][0] + b[j][1];
        let rj1 = if j + 1 == n { 0.0 } else { cum };
        let xp = (b[j][1] + (be[j] + lambda) * xm - rj1) / (al[j] + lambda);
        x[j][0] = xp;
        if j + 1 < n {
            xm = (al[j] * xp + rj1) / be[j + 1];
            if homogeneous && xm > 1e250 {
                for c in x.iter_mut().take(j + 1) {
                    c[0] *= 1e-250;
                    c[1] *= 1e-250;
                }
                xm *= 1e-250;
            }
        }
    }
    x
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::{DragLaw, Params};

    /// (B x) with reset loss -r on the diagonal, applied directly.
    fn apply(g: &Grid, lambda: f64, r: f64, x: &[[f64; 2]]) -> Vec<[f64; 2]> {
        let n = g.cells();
        let (al, be) = (&g.out_plus, &g.out_minus);
        (0..n)
            .map(|i| {
                let left = if i > 0 { al[i - 1] * x[i - 1][0] } else { 0.0 };
                let right = if i + 1 < n {
                    be[i + 1] * x[i + 1][1]
                } else {
                    0.0
                };
                [
                    left - (al[i] + lambda + r) * x[i][0] + lambda * x[i][1],
                    lambda * x[i][0] - (be[i] + lambda + r) * x[i][1] + right,
                ]
            })
            .collect()
    }

    fn rhs(n: usize) -> Vec<[f64; 2]> {
        // Mixed signs, zero sum (needed for r = 0).
        let mut b: Vec<[f64; 2]> = (0..n)
            .map(|i| [((i * 7) % 11) as f64 - 5.0, ((i * 3) % 5) as f64 - 2.0])
            .collect();
        let s: f64 = b.iter().map(|c| c[0] + c[1]).sum();
        b[n / 2][0] -= s;
        b
    }

    fn check(g: &Grid, lambda: f64, r: f64) {
        let b = rhs(g.cells());
        let x = if r > 0.0 {
            solve_reset(g, lambda, r, &b)
        } else {
            solve_free(g, lambda, &b, 0.3)
        };
        let y = apply(g, lambda, r, &x);
        let scale = b
            .iter()
            .map(|c| c[0].abs() + c[1].abs())
            .fold(0.0, f64::max);
        for (yi, bi) in y.iter().zip(&b) {
            for k in 0..2 {
                assert!((yi[k] - bi[k]).abs() < 1e-9 * scale, "{yi:?} vs {bi:?}");
            }
        }
    }

    #[test]
    fn solvers_satisfy_the_equations() {
        for (d, s, l) in [
            (DragLaw::Tan, 3.0, 0.9),
            (DragLaw::Tanh, 0.6, 3.0),
            (DragLaw::Linear, 1.0, 0.3),
        ] {
            for r in [0.0, 1e-3, 2.0] {
                let p = Params::new(d.clone(), s, l, r, 0.1).unwrap();
                check(&Grid::uniform(&p, 200), l, r);
                // Moderate grading so that the residual check is well scaled.
                check(&Grid::graded(&p, 90, 110).unwrap(), l, r);
            }
        }
    }

    #[test]
    fn stationary_solution_is_nonnegative_with_unit_mass() {
        let p = Params::new(DragLaw::Tan, 3.0, 0.5, 1e-6, 0.2).unwrap();
        let g = Grid::graded(&p, 400, 600).unwrap();
        let mut b = vec![[0.0; 2]; g.cells()];
        b[g.reset_plus][0] -= 0.5 * p.rate();
        b[g.reset_minus][1] -= 0.5 * p.rate();
        let x = solve_reset(&g, p.lambda(), p.rate(), &b);
        assert!(x.iter().all(|c| c[0] >= 0.0 && c[1] >= 0.0));
        let mass: f64 = x.iter().map(|c| c[0] + c[1]).sum();
        assert!((mass - 1.0).abs() < 1e-12, "{mass}");
    }
}
