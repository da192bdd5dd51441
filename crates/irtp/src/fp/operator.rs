//! The discrete forward generator as a linear operator, for implicit time
//! stepping (TR-BDF2, see [`crate::numerics::trbdf2`]) and moment chains.
//!
//! Unknowns are the cell masses in the interleaved order
//! (m+_0, m-_0, m+_1, m-_1, ...). The operator is A = B + R, the generator of
//! the Markov jump process on (cell, state) that the stationary solver uses
//! (see [`super::solve`]): B moves mass between cells (upwind transport),
//! flips states at rate λ and removes mass at the reset rate r; R re-injects
//! the removed mass, r Σ_i m±_i, into the reset target cell of the same state.
//! Every column of A sums to zero (mass is conserved) and its off-diagonal
//! entries are ≥ 0 (positivity).
//!
//! Shifted solves (I - cA) x = b are done without subtractions where the
//! signs allow it: I - cA = -c (B' + R) with B' = B - I/c, which is B with the
//! loss rate r + 1/c, solved by the block-Thomas factorisation of
//! [`super::solve`]; R = E Fᵀ has rank ≤ 2 (E: unit mass in the target
//! cell of each state, or spread by a random target's cell masses,
//! Fᵀ = r W (1+, 1-)ᵀ: the state sums mixed by the noise rule, W = I when the
//! state is kept, all entries ½ when it is re-drawn; W's columns sum to 1)
//! and is added by the
//! Sherman-Morrison-Woodbury formula ([`crate::numerics::bordered`])
//!   (B' + E Fᵀ)^{-1} y = w - Z S^{-1} Fᵀ w,  w = B'^{-1} y, Z = B'^{-1} E,
//!   S = I + Fᵀ Z (2×2).
//! B'^{-1} ≤ 0 entrywise, so Z ≤ 0; the column sums of B' are -(r + 1/c), so
//! each column of S sums to s = 1/(1 + rc) exactly, and S's diagonal is formed
//! as s plus the magnitude of its off-diagonal entry: det S = s² + s(|S01| +
//! |S10|) and S^{-1} ≥ 0. For b ≥ 0 the solution is then a sum of
//! non-negative terms.
//!
//! With an exponential refractory period (docs/equations.md, entries (R1),
//! (R7)) the unknowns go on, after the cell masses, with one held pair
//! y_a = (q+, q-) per held velocity u_a (the [`Atom`]s): the reset outflux
//! enters the held pairs, y_a' = w_a W r (Σx+, Σx-) - K y_a, and the pairs
//! re-enter the cells at rate κ, x' = B x + κ Σ_a E_a y_a (E_a: the cells of
//! atom a). The shifted solve eliminates the 2×2 held blocks:
//! y_a = L (d_a + c w_a W r Σx), L = (I + cK)^{-1} ≥ 0, which leaves
//!   (B' + E G W r Σ) x = -(b + c κ Σ_a E_a L d_a)/c,  G = c κ L,
//! the same rank-2 structure with Fᵀ = G W r Σ, solved by the same
//! Sherman-Morrison-Woodbury formula with a general 2×2 S^{-1}.

use super::grid::{Grid, Mesh};
use super::refractory::{Atom, Held};
use super::solve::ResetFactor;
use super::stationary::{make_grid, MAX_CELLS, MIN_CELLS};
use crate::error::{Error, Result};
use crate::model::Params;
use crate::numerics::bordered::{Capacitance, LowRank};
use crate::numerics::trbdf2::ShiftedLinear;
use crate::numerics::Failure;

/// The factorisation of one shift c.
#[derive(Clone, Debug)]
struct Shifted {
    c: f64,
    factor: ResetFactor,
    /// The Sherman-Morrison-Woodbury correction: Z = B'^{-1} E, the
    /// responses to unit sources in the + and - target cells, and S^{-1}.
    low: LowRank,
    /// With a refractory period: L = (I + cK)^{-1} (row-major).
    l: [[f64; 2]; 2],
}

/// The discrete forward generator A (transport, flips, reset removal and
/// re-injection) on a finite-volume mesh, acting on flat interleaved cell
/// masses (m+_0, m-_0, m+_1, ...).
#[derive(Clone, Debug)]
pub struct ForwardOperator {
    grid: Grid,
    lambda: f64,
    rate: f64,
    /// Cell-centre velocity of every unknown (each centre twice).
    velocities: Vec<f64>,
    /// The exponential refractory period, if any: one held pair per atom
    /// after the cell masses.
    held: Option<Held>,
    shifted: Option<Shifted>,
}

impl ForwardOperator {
    /// The operator of `params` on a `mesh` of `cells` cells (the stationary
    /// solver's meshes: the graded one has v_r as a node).
    pub fn new(params: &Params, mesh: Mesh, cells: usize) -> Result<Self> {
        Self::refined(params, mesh, cells, 0)
    }

    /// The operator on the mesh of `cells` cells refined `refine` times (each
    /// refinement halves every cell in the mesh parameter, so the meshes are
    /// nested, as Richardson extrapolation needs).
    pub fn refined(params: &Params, mesh: Mesh, cells: usize, refine: usize) -> Result<Self> {
        if !(MIN_CELLS..=MAX_CELLS).contains(&cells) {
            return Err(Error::invalid(
                "cells",
                cells,
                format!("{MIN_CELLS} <= cells <= {MAX_CELLS}"),
            ));
        }
        if !(refine <= 20 && (cells << refine) <= MAX_CELLS) {
            return Err(Error::invalid(
                "cells",
                cells,
                format!("cells * 2^refine <= {MAX_CELLS} (refine = {refine})"),
            ));
        }
        Ok(Self::on_grid(
            params,
            make_grid(params, mesh, cells, refine)?,
        ))
    }

    pub(crate) fn on_grid(params: &Params, grid: Grid) -> Self {
        let held = Held::new(&grid, params);
        let atoms = held.as_ref().map_or(&[][..], |h| &h.atoms[..]);
        let velocities = grid
            .centres
            .iter()
            .chain(atoms.iter().map(|a| &a.v))
            .flat_map(|&v| [v, v])
            .collect();
        ForwardOperator {
            grid,
            lambda: params.lambda(),
            rate: params.rate(),
            velocities,
            held,
            shifted: None,
        }
    }

    pub(crate) fn grid(&self) -> &Grid {
        &self.grid
    }

    /// Number of cells (the number of unknowns is twice this).
    pub fn cells(&self) -> usize {
        self.grid.cells()
    }

    /// Number of unknowns: 2 × cells, and with an exponential refractory
    /// period 2 more per held velocity (the held pairs (q+, q-), after the
    /// cell masses).
    pub fn dim(&self) -> usize {
        2 * (self.grid.cells() + self.atoms().len())
    }

    /// The held velocities of a refractory period (empty without one).
    pub(crate) fn atoms(&self) -> &[Atom] {
        self.held.as_ref().map_or(&[], |h| &h.atoms)
    }

    /// The held (refractory) mass Σ_a (q+_a + q-_a) of `u` (0 without a
    /// refractory period).
    pub fn refractory_mass(&self, u: &[f64]) -> f64 {
        u[2 * self.grid.cells()..].iter().sum()
    }

    /// Cell centres (one per cell).
    pub fn centres(&self) -> &[f64] {
        &self.grid.centres
    }

    /// Cell widths (one per cell; exact also where edges round together).
    pub fn widths(&self) -> &[f64] {
        &self.grid.widths
    }

    /// Cell edges (cells + 1).
    pub fn edges(&self) -> &[f64] {
        &self.grid.edges
    }

    /// Cell-centre velocity of every unknown, in the interleaved order
    /// (length [`dim`](Self::dim): v_0, v_0, v_1, v_1, ..., then the held
    /// velocity u_a twice per held pair). This is the v of the source of the
    /// position-moment chain dM_k/dt = A M_k + k v M_{k-1} (elementwise
    /// product).
    pub fn velocities(&self) -> &[f64] {
        &self.velocities
    }

    /// Masses of ½ δ(v - w) in each noise state. If w is a node: ½ in the
    /// cell on the side each state moves to (right for +, left for -), as
    /// for the reset target; the paper's initial condition is w = 0, a node
    /// of the graded mesh where v_r = 0. Inside a cell (a mesh graded
    /// towards v_r ≠ 0): split between the two cells whose centres bracket
    /// w, with weights that put the mean at w exactly (linear
    /// interpolation), so that `<v>` starts exact. (The whole ½ in the
    /// cell that contains w would start `<v>` off by up to half a cell, an
    /// offset that differs between the nested meshes and so is not removed
    /// by the Richardson extrapolation: measured 1e-3 in `<v>` at t = 0.3
    /// before the first periodic reset, linear drag, v_r = 0.2, 2000 cells.)
    pub fn point_mass(&self, w: f64) -> Vec<f64> {
        let g = &self.grid;
        let (kp, km) = target(g, w);
        let mut u = vec![0.0; self.dim()];
        if kp != km || g.centres[kp] == w {
            u[2 * kp] = 0.5;
            u[2 * km + 1] = 0.5;
            return u;
        }
        let c = &g.centres;
        let other = if c[kp] > w {
            kp.checked_sub(1)
        } else {
            Some(kp + 1)
        };
        match other.filter(|&k| k < g.cells()) {
            Some(k) => {
                let wk = (w - c[kp]) / (c[k] - c[kp]);
                for (cell, weight) in [(kp, 1.0 - wk), (k, wk)] {
                    u[2 * cell] += 0.5 * weight;
                    u[2 * cell + 1] += 0.5 * weight;
                }
            }
            None => {
                u[2 * kp] = 0.5;
                u[2 * kp + 1] = 0.5;
            }
        }
        u
    }

    /// Mass, `<v>` and `<v²>` of the cell masses `u` (cell-centre quadrature;
    /// the held pairs at their held velocities).
    pub fn moments(&self, u: &[f64]) -> [f64; 3] {
        let (mut s0, mut s1, mut s2) = (0.0, 0.0, 0.0);
        for (c, &v) in u.chunks_exact(2).zip(self.velocities.iter().step_by(2)) {
            let w = c[0] + c[1];
            s0 += w;
            s1 += w * v;
            s2 += w * v * v;
        }
        [s0, s1, s2]
    }

    /// out = A u.
    pub fn apply(&self, u: &[f64], out: &mut [f64]) {
        self.apply_with(u, out, true)
    }

    /// out = A u, without the reset influx (the re-injection into the target
    /// cells, or the entry into the held pairs) unless `inject`: the operator
    /// of an x-weighted block with position resetting, whose influx is
    /// [`add_injection`](Self::add_injection) of M_0 instead.
    pub fn apply_with(&self, u: &[f64], out: &mut [f64], inject: bool) {
        let g = &self.grid;
        let n = g.cells();
        let (al, be, l, r) = (&g.out_plus, &g.out_minus, self.lambda, self.rate);
        let (mut up, mut um) = (0.0, 0.0);
        for i in 0..n {
            let (p, m) = (u[2 * i], u[2 * i + 1]);
            up += p;
            um += m;
            let left = if i > 0 { al[i - 1] * u[2 * i - 2] } else { 0.0 };
            let right = if i + 1 < n {
                be[i + 1] * u[2 * i + 3]
            } else {
                0.0
            };
            out[2 * i] = left - (al[i] + l + r) * p + l * m;
            out[2 * i + 1] = l * p - (be[i] + l + r) * m + right;
        }
        match &self.held {
            None if inject => {
                let (ip, im) = g.reinject(r * up, r * um);
                g.add_reset_flat(out, ip, im);
            }
            None => {}
            Some(h) => self.apply_held(h, u, out, if inject { [up, um] } else { [0.0; 2] }),
        }
    }

    /// The held pairs' rows of A u and their re-entry into the cells, with
    /// the reset outflux of the state sums `sums`.
    fn apply_held(&self, h: &Held, u: &[f64], out: &mut [f64], sums: [f64; 2]) {
        let base = 2 * self.grid.cells();
        let inf = h.influx(sums[0], sums[1]);
        let (k, l) = (h.kappa, self.lambda);
        for (i, a) in h.atoms.iter().enumerate() {
            let (p, m) = (u[base + 2 * i], u[base + 2 * i + 1]);
            out[base + 2 * i] = a.w * inf[0] - (k + l) * p + l * m;
            out[base + 2 * i + 1] = a.w * inf[1] + l * p - (k + l) * m;
            out[2 * a.plus] += k * p;
            out[2 * a.minus + 1] += k * m;
        }
    }

    /// out += `scale` × the reset influx of the state sums of `u0`'s cell
    /// masses: into the target cells, or into the held pairs with a
    /// refractory period. With position resetting the x-weighted block k
    /// receives this with scale x_r^k from M_0 (docs/equations.md, (R8)).
    pub fn add_injection(&self, u0: &[f64], out: &mut [f64], scale: f64) {
        let g = &self.grid;
        let n = g.cells();
        let (up, um) = state_sums(&u0[..2 * n]);
        match &self.held {
            None => {
                let (ip, im) = g.reinject(scale * self.rate * up, scale * self.rate * um);
                g.add_reset_flat(&mut out[..2 * n], ip, im);
            }
            Some(h) => {
                let inf = h.influx(scale * up, scale * um);
                for (i, a) in h.atoms.iter().enumerate() {
                    out[2 * n + 2 * i] += a.w * inf[0];
                    out[2 * n + 2 * i + 1] += a.w * inf[1];
                }
            }
        }
    }

    /// Solve (I - cA) x = b for c > 0, caching the factorisation of the last
    /// c (so several right-hand sides with one c cost one O(N) sweep each).
    /// A c that is not finite and positive, or a non-finite solution, is
    /// reported as [`Failure::NonFinite`] (`?` turns it into [`Error`]).
    pub fn solve_shifted_into(
        &mut self,
        c: f64,
        b: &[f64],
        x: &mut [f64],
    ) -> std::result::Result<(), Failure> {
        self.solve_shifted_with(c, b, x, true)
    }

    /// [`solve_shifted_into`](Self::solve_shifted_into) for the operator of
    /// [`apply_with`](Self::apply_with): without the reset influx unless
    /// `inject`.
    pub fn solve_shifted_with(
        &mut self,
        c: f64,
        b: &[f64],
        x: &mut [f64],
        inject: bool,
    ) -> std::result::Result<(), Failure> {
        let fail = Failure::shifted_solve("fp shifted solve (I - cA) x = b", c)?;
        if !matches!(&self.shifted, Some(s) if s.c == c) {
            self.shifted = Some(self.factorise(c));
        }
        let s = self.shifted.as_ref().expect("factorised above");
        let g = &self.grid;
        match &self.held {
            None => {
                // (B' + E Fᵀ) x = -b/c.
                let y: Vec<f64> = b.iter().map(|&bi| -bi / c).collect();
                s.factor.solve(g, &y, x);
                if inject {
                    let (fp, fm) = state_sums(x);
                    let (f0, f1) = g.reinject(self.rate * fp, self.rate * fm);
                    s.low.correct(x, [f0, f1]);
                }
            }
            Some(h) => solve_held(g, h, s, b, x, inject),
        }
        if x.iter().all(|v| v.is_finite()) {
            Ok(())
        } else {
            Err(fail)
        }
    }

    /// B' = B(r + 1/c), Z = B'^{-1} E and S^{-1} (see the module docs).
    fn factorise(&self, c: f64) -> Shifted {
        let g = &self.grid;
        let loss = self.rate + 1.0 / c;
        let factor = ResetFactor::new(g, self.lambda, loss);
        // E's columns: unit mass re-entering in the + and in the - state.
        let unit = |ip: f64, im: f64| {
            let mut e = vec![0.0; 2 * g.cells()];
            g.add_reset_flat(&mut e, ip, im);
            let mut z = vec![0.0; 2 * g.cells()];
            factor.solve(g, &e, &mut z);
            z
        };
        let z = [unit(1.0, 0.0), unit(0.0, 1.0)];
        if let Some(h) = &self.held {
            let (l, s_inv) = held_s_inv(h, self.rate, c, &z);
            return Shifted {
                c,
                factor,
                low: LowRank::new(z, s_inv),
                l,
            };
        }
        // Column k of S: s on the sum; the off-diagonal is the re-injection
        // into the other state of r Σ Z_k (≤ 0), the diagonal
        // s + |off-diagonal|.
        let s = 1.0 / (1.0 + self.rate * c);
        let inject = |z: &[f64]| {
            let (a, b) = state_sums(z);
            g.reinject(self.rate * a, self.rate * b)
        };
        let off = [inject(&z[0]).1, inject(&z[1]).0];
        let (s00, s11) = (s - off[0], s - off[1]);
        let det = s * s - s * (off[0] + off[1]);
        let s_inv = Capacitance::inverted([[s00, off[1]], [off[0], s11]], det);
        Shifted {
            c,
            factor,
            low: LowRank::new(z, s_inv),
            l: [[0.0; 2]; 2],
        }
    }
}

/// M y for a row-major 2×2 M.
fn mat2(m: &[[f64; 2]; 2], y: [f64; 2]) -> [f64; 2] {
    [
        m[0][0] * y[0] + m[0][1] * y[1],
        m[1][0] * y[0] + m[1][1] * y[1],
    ]
}

/// L = (I + cK)^{-1} (entries ≥ 0) and S^{-1}, S = I + G W r Σ Z with
/// G = c κ L (module docs). Free of cancellation as for the plain S: the
/// columns of L sum to 1/(1 + cκ), those of W to 1, and Σ Z_j sums to
/// -c/(1 + rc), so each column of S sums to
/// s = (1 + cκ + rc) / ((1 + cκ)(1 + rc)); the off-diagonal entries are ≤ 0
/// and the diagonal is s plus their magnitude.
fn held_s_inv(h: &Held, r: f64, c: f64, z: &[Vec<f64>; 2]) -> ([[f64; 2]; 2], Capacitance) {
    let (k, l) = (c * h.kappa, c * h.lambda());
    let det = (1.0 + k) * (1.0 + k + 2.0 * l);
    let (d, o) = ((1.0 + k + l) / det, l / det);
    let lm = [[d, o], [o, d]];
    let col = |z: &[f64]| {
        let (a, b) = state_sums(z);
        mat2(&lm, h.influx(a, b)).map(|x| k * x)
    };
    let off = [col(&z[0])[1], col(&z[1])[0]];
    let s = (1.0 + k + r * c) / ((1.0 + k) * (1.0 + r * c));
    let (s00, s11) = (s - off[0], s - off[1]);
    let det = s * s - s * (off[0] + off[1]);
    let s_inv = Capacitance::inverted([[s00, off[1]], [off[0], s11]], det);
    (lm, s_inv)
}

/// The shifted solve with the held pairs (module docs): x's cells from the
/// rank-2 corrected solve, then y_a = L (d_a + c w_a W r Σx).
fn solve_held(g: &Grid, h: &Held, s: &Shifted, b: &[f64], x: &mut [f64], inject: bool) {
    let n2 = 2 * g.cells();
    let c = s.c;
    let (bc, d) = b.split_at(n2);
    let ld: Vec<[f64; 2]> = d
        .chunks_exact(2)
        .map(|da| mat2(&s.l, [da[0], da[1]]))
        .collect();
    let mut y: Vec<f64> = bc.iter().map(|&bi| -bi / c).collect();
    for (a, l) in h.atoms.iter().zip(&ld) {
        y[2 * a.plus] -= h.kappa * l[0];
        y[2 * a.minus + 1] -= h.kappa * l[1];
    }
    let (xc, xh) = x.split_at_mut(n2);
    s.factor.solve(g, &y, xc);
    let mut inf = [0.0; 2];
    if inject {
        let (fp, fm) = state_sums(xc);
        let f = mat2(&s.l, h.influx(fp, fm)).map(|v| c * h.kappa * v);
        s.low.correct(xc, f);
        let (xp, xm) = state_sums(xc);
        inf = mat2(&s.l, h.influx(xp, xm));
    }
    for ((a, l), out) in h.atoms.iter().zip(&ld).zip(xh.chunks_exact_mut(2)) {
        out[0] = l[0] + c * a.w * inf[0];
        out[1] = l[1] + c * a.w * inf[1];
    }
}

impl ShiftedLinear for ForwardOperator {
    fn dim(&self) -> usize {
        ForwardOperator::dim(self)
    }

    fn apply(&self, u: &[f64], out: &mut [f64]) {
        ForwardOperator::apply(self, u, out)
    }

    fn solve_shifted(
        &mut self,
        c: f64,
        b: &[f64],
        x: &mut [f64],
    ) -> std::result::Result<(), Failure> {
        self.solve_shifted_into(c, b, x)
    }
}

/// (Σ u+, Σ u-) of interleaved cell values.
fn state_sums(u: &[f64]) -> (f64, f64) {
    u.chunks_exact(2)
        .fold((0.0, 0.0), |(a, b), c| (a + c[0], b + c[1]))
}

/// Cells receiving + and - mass placed at velocity w: the cell containing w,
/// or, if w is a node, + to the right cell and - to the left one.
pub(crate) fn target(g: &Grid, w: f64) -> (usize, usize) {
    let n = g.cells();
    // First edge > w: cell k - 1 contains w.
    let k = g.edges.partition_point(|&e| e <= w);
    let j = k.saturating_sub(1).min(n - 1);
    if j >= 1 && g.edges[j] == w {
        (j, j - 1)
    } else {
        (j, j)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::DragLaw;

    fn ops() -> Vec<ForwardOperator> {
        let mut out = Vec::new();
        for (d, s, l, r, vr) in [
            (DragLaw::Tan, 3.0, 0.5, 2.0, 0.0),
            (DragLaw::Tanh, 0.6, 0.5, 10.0, 0.1),
            (DragLaw::Linear, 1.0, 0.3, 0.7, -0.2),
            (DragLaw::Tan, 3.0, 0.5, 0.0, 0.0),
        ] {
            let p = Params::new(d, s, l, r, vr).unwrap();
            out.push(ForwardOperator::new(&p, Mesh::Graded, 300).unwrap());
            out.push(ForwardOperator::new(&p, Mesh::Uniform, 200).unwrap());
        }
        out
    }

    #[test]
    fn columns_of_a_sum_to_zero() {
        for op in ops() {
            let n = op.dim();
            let mut col = vec![0.0; n];
            for j in 0..n {
                let mut e = vec![0.0; n];
                e[j] = 1.0;
                op.apply(&e, &mut col);
                let scale: f64 = col.iter().map(|x| x.abs()).sum();
                let sum: f64 = col.iter().sum();
                assert!(sum.abs() <= 1e-14 * scale, "column {j}: {sum} of {scale}");
                let off = col.iter().enumerate().filter(|&(i, _)| i != j);
                assert!(off.clone().all(|(_, &x)| x >= 0.0));
            }
        }
    }

    #[test]
    fn shifted_solve_satisfies_the_equations() {
        for mut op in ops() {
            let n = op.dim();
            for c in [1e-6, 0.03, 1.0, 1e4] {
                // Mixed signs, and a non-negative right-hand side.
                let b1: Vec<f64> = (0..n).map(|i| ((i * 7) % 11) as f64 - 5.0).collect();
                let b2: Vec<f64> = (0..n).map(|i| ((i * 3) % 5) as f64).collect();
                for b in [b1, b2] {
                    let mut x = vec![0.0; n];
                    op.solve_shifted_into(c, &b, &mut x).unwrap();
                    let mut ax = vec![0.0; n];
                    op.apply(&x, &mut ax);
                    // Residual against the sum of the magnitudes of the terms:
                    // |b| + |x| + c |A| |x| (|A| x: A with its diagonal negated).
                    let xa: Vec<f64> = x.iter().map(|v| v.abs()).collect();
                    let mut ab = vec![0.0; n];
                    op.apply(&xa, &mut ab);
                    let scales: Vec<f64> = (0..n)
                        .map(|i| {
                            let d = 2.0 * (op.grid.out_plus[i / 2] + op.grid.out_minus[i / 2])
                                + op.lambda
                                + op.rate;
                            b[i].abs() + xa[i] + c * (ab[i] + 2.0 * d * xa[i])
                        })
                        .collect();
                    // Componentwise for b >= 0 (no cancellation anywhere),
                    // normwise for mixed signs.
                    let positive = b.iter().all(|&v| v >= 0.0);
                    let norm = scales.iter().cloned().fold(0.0, f64::max);
                    for i in 0..n {
                        let scale = if positive { scales[i] } else { norm };
                        let res = x[i] - c * ax[i] - b[i];
                        assert!(
                            res.abs() <= 1e-13 * scale,
                            "c = {c}, i = {i}: {res} of {scale}"
                        );
                    }
                    if b.iter().all(|&v| v >= 0.0) {
                        assert!(x.iter().all(|&v| v >= 0.0));
                    }
                    // Mass: 1ᵀx = 1ᵀb.
                    let (sx, sb) = (x.iter().sum::<f64>(), b.iter().sum::<f64>());
                    let sa: f64 = b.iter().map(|v| v.abs()).sum();
                    assert!((sx - sb).abs() <= 1e-12 * sa, "{sx} vs {sb}");
                }
            }
        }
    }

    /// Operators with an exponential refractory period: point and uniform
    /// targets, noise kept and re-drawn.
    fn held_ops() -> Vec<ForwardOperator> {
        use crate::model::reset::{NoiseAtReset, Schedule, Target};
        let mut out = Vec::new();
        for (d, s, vr) in [(DragLaw::Tan, 3.0, 0.0), (DragLaw::Linear, 1.0, -0.2)] {
            let p = Params::new(d, s, 0.5, 2.0, vr).unwrap();
            let sched = Schedule::parse(None, None, Some("exp:mean=0.3")).unwrap();
            for noise in [NoiseAtReset::Kept, NoiseAtReset::Redrawn] {
                for t in [Target::point(vr), Target::uniform(-0.3, 0.2)] {
                    let q = p
                        .with_reset(t, noise)
                        .unwrap()
                        .with_schedule(sched.clone())
                        .unwrap();
                    out.push(ForwardOperator::new(&q, Mesh::Graded, 120).unwrap());
                }
            }
        }
        out
    }

    #[test]
    fn held_shifted_solve_satisfies_the_equations_and_conserves_mass() {
        for mut op in held_ops() {
            let n = op.dim();
            assert!(n > 2 * op.cells());
            // Columns of A sum to zero with the held pairs.
            let mut col = vec![0.0; n];
            for j in [0, n / 3, n - 2, n - 1] {
                let mut e = vec![0.0; n];
                e[j] = 1.0;
                op.apply(&e, &mut col);
                let scale: f64 = col.iter().map(|x| x.abs()).sum();
                assert!(col.iter().sum::<f64>().abs() <= 1e-14 * scale, "column {j}");
            }
            for c in [1e-6, 0.03, 1.0, 1e4] {
                for inject in [true, false] {
                    let b: Vec<f64> = (0..n).map(|i| ((i * 3) % 5) as f64).collect();
                    let mut x = vec![0.0; n];
                    op.solve_shifted_with(c, &b, &mut x, inject).unwrap();
                    let mut ax = vec![0.0; n];
                    op.apply_with(&x, &mut ax, inject);
                    let norm = b.iter().chain(&x).fold(0.0f64, |m, v| m.max(v.abs()));
                    let scale = norm * (1.0 + c * 1e4);
                    for i in 0..n {
                        let res = x[i] - c * ax[i] - b[i];
                        assert!(res.abs() <= 1e-11 * scale, "c = {c}, i = {i}: {res}");
                    }
                    if inject {
                        let (sx, sb) = (x.iter().sum::<f64>(), b.iter().sum::<f64>());
                        assert!((sx - sb).abs() <= 1e-12 * sb, "c = {c}: {sx} vs {sb}");
                    }
                }
            }
        }
    }

    #[test]
    fn point_mass_targets() {
        let p = Params::new(DragLaw::Tan, 3.0, 0.5, 2.0, 0.0).unwrap();
        let op = ForwardOperator::new(&p, Mesh::Graded, 300).unwrap();
        let u = op.point_mass(0.0);
        let g = &op.grid;
        assert_eq!(u[2 * g.reset_plus], 0.5);
        assert_eq!(u[2 * g.reset_minus + 1], 0.5);
        let op = ForwardOperator::new(&p, Mesh::Uniform, 201).unwrap();
        let k = op.centres().iter().position(|&v| v.abs() < 1e-12).unwrap();
        let u = op.point_mass(0.0);
        assert_eq!((u[2 * k], u[2 * k + 1]), (0.5, 0.5));
        assert_eq!(op.moments(&u)[0], 1.0);
    }
}
