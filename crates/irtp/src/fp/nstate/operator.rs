//! The N-state forward generator A = B + R on the N-state mesh (Eq. (N20)):
//! B moves mass between cells (Eq. (N22)), jumps the noise state with the
//! generator Q within a cell and removes mass at the reset rate r; R
//! re-injects the removed mass r Σ_i m_{i,s} at v_r, mixed by the reset's
//! noise rule (kept: state for state; re-drawn: spread by π). Unknowns
//! are interleaved by cell, m_{i,s} at index i N + s, so B is banded with
//! N sub- and super-diagonals; R has rank ≤ N and enters the shifted
//! solves by the Woodbury formula. Every column of A sums to 0 and its
//! off-diagonal entries are ≥ 0: A is the generator of a Markov jump
//! process on (cell, state), which conserves mass and positivity.

use super::mesh::{mesh, NMesh};
use crate::error::{Error, Result};
use crate::model::noise::chain::{self, Chain};
use crate::model::reset::{NoiseAtReset, Reset};
use crate::model::DragLaw;
use crate::model::Params;
use crate::numerics::band::Band;
use crate::numerics::trbdf2::ShiftedLinear;
use crate::numerics::Failure;

/// The N-state forward operator.
#[derive(Clone, Debug)]
pub struct NoiseOperator {
    pub(crate) mesh: NMesh,
    pub(crate) chain: Chain,
    pub(crate) drag: DragLaw,
    pub(crate) rate: f64,
    pub(crate) noise: NoiseAtReset,
    shifted: Option<ShiftedFactor>,
}

/// (I - cB)'s band factors, Z = (I - cB)⁻¹ E and the N×N capacitance
/// matrix K = I - c r W S Z of the Woodbury formula.
#[derive(Clone, Debug)]
struct ShiftedFactor {
    c: f64,
    band: Band,
    z: Vec<Vec<f64>>,
    k: Vec<Vec<f64>>,
}

impl NoiseOperator {
    pub(crate) fn new(
        mesh: NMesh,
        chain: Chain,
        drag: DragLaw,
        rate: f64,
        noise: NoiseAtReset,
    ) -> Self {
        NoiseOperator {
            mesh,
            chain,
            drag,
            rate,
            noise,
            shifted: None,
        }
    }

    /// Number of unknowns (cells × states).
    pub fn dim(&self) -> usize {
        self.mesh.widths.len() * self.mesh.states
    }

    /// Cell centres.
    pub fn centres(&self) -> &[f64] {
        &self.mesh.centres
    }

    /// The band matrix of B (`c` None) or of I - cB.
    pub(crate) fn band(&self, c: Option<f64>) -> Band {
        let (m, ns) = (&self.mesh, self.mesh.states);
        let n = m.widths.len();
        let mut a = Band::new(n * ns, ns, ns);
        let scale = c.map_or(1.0, |c| -c);
        for i in 0..n {
            for s in 0..ns {
                let col = i * ns + s;
                let right = m.fwd[(i + 1) * ns + s];
                let left = m.back[i * ns + s];
                let diag = -(right + left + self.chain.exit[s] + self.rate);
                a.set(col, col, scale * diag + if c.is_some() { 1.0 } else { 0.0 });
                if i + 1 < n {
                    a.set(col + ns, col, scale * right);
                }
                if i > 0 {
                    a.set(col - ns, col, scale * left);
                }
                for t in (0..ns).filter(|&t| t != s) {
                    a.set(i * ns + t, col, scale * self.chain.q[s][t]);
                }
            }
        }
        a
    }

    /// State sums S m = (Σ_i m_{i,s})_s.
    pub(crate) fn state_sums(&self, u: &[f64]) -> Vec<f64> {
        let ns = self.mesh.states;
        let mut out = vec![0.0; ns];
        for c in u.chunks_exact(ns) {
            for (o, x) in out.iter_mut().zip(c) {
                *o += x;
            }
        }
        out
    }

    /// out += Σ_s w_s × (unit mass of state s at the reset target).
    pub(crate) fn add_target(&self, w: &[f64], out: &mut [f64]) {
        let ns = self.mesh.states;
        for (s, cells) in self.mesh.target.iter().enumerate() {
            for &(i, f) in cells {
                out[i * ns + s] += f * w[s];
            }
        }
    }

    /// The reset influx per state of the state sums `sums`: r W sums.
    pub(crate) fn influx(&self, sums: &[f64]) -> Vec<f64> {
        let mixed = self.noise.mix_states(sums, &self.chain.pi);
        mixed.iter().map(|x| self.rate * x).collect()
    }

    /// out = A u.
    pub fn apply(&self, u: &[f64], out: &mut [f64]) {
        let (m, ns) = (&self.mesh, self.mesh.states);
        let n = m.widths.len();
        for i in 0..n {
            for s in 0..ns {
                let k = i * ns + s;
                let right = m.fwd[(i + 1) * ns + s];
                let left = m.back[i * ns + s];
                let mut acc = -(right + left + self.chain.exit[s] + self.rate) * u[k];
                if i > 0 {
                    acc += m.fwd[i * ns + s] * u[k - ns];
                }
                if i + 1 < n {
                    acc += m.back[(i + 1) * ns + s] * u[k + ns];
                }
                for t in (0..ns).filter(|&t| t != s) {
                    acc += self.chain.q[t][s] * u[i * ns + t];
                }
                out[k] = acc;
            }
        }
        if self.rate > 0.0 {
            let inf = self.influx(&self.state_sums(u));
            self.add_target(&inf, out);
        }
    }

    /// Solve (I - cA) x = b for c > 0 (Woodbury over the rank-N reset
    /// re-injection; the factorisation of the last c is cached).
    pub fn solve_shifted(
        &mut self,
        c: f64,
        b: &[f64],
        x: &mut [f64],
    ) -> std::result::Result<(), Failure> {
        let fail = Failure::shifted_solve("fp shifted solve (I - cA) x = b (N states)", c)?;
        if !matches!(&self.shifted, Some(f) if f.c == c) {
            self.shifted = Some(self.factorise(c).map_err(|_| fail)?);
        }
        let f = self.shifted.as_ref().expect("factorised above");
        x.copy_from_slice(b);
        f.band.solve(x);
        if self.rate > 0.0 {
            let t: Vec<f64> = self
                .influx(&self.state_sums(x))
                .iter()
                .map(|v| c * v)
                .collect();
            let u = chain::solve(&f.k, &t, "fp shifted solve (capacitance)").map_err(|_| fail)?;
            for (s, z) in f.z.iter().enumerate() {
                for (xi, zi) in x.iter_mut().zip(z) {
                    *xi += zi * u[s];
                }
            }
        }
        if x.iter().all(|v| v.is_finite()) {
            Ok(())
        } else {
            Err(fail)
        }
    }

    fn factorise(&self, c: f64) -> Result<ShiftedFactor> {
        let ns = self.mesh.states;
        let mut band = self.band(Some(c));
        band.factor_for("fp shifted solve (N states)")?;
        let z: Vec<Vec<f64>> = (0..ns)
            .map(|s| {
                let mut e = vec![0.0; self.dim()];
                let mut w = vec![0.0; ns];
                w[s] = 1.0;
                self.add_target(&w, &mut e);
                band.solve(&mut e);
                e
            })
            .collect();
        // K = I - c r W S Z: column s is e_s - c × influx(S Z_s).
        let cols: Vec<Vec<f64>> = z
            .iter()
            .map(|zs| self.influx(&self.state_sums(zs)))
            .collect();
        let k = (0..ns)
            .map(|i| {
                (0..ns)
                    .map(|j| f64::from(u8::from(i == j)) - c * cols[j][i])
                    .collect()
            })
            .collect();
        Ok(ShiftedFactor { c, band, z, k })
    }
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

/// `blocks` copies of the operator coupled by the moment chain.
pub(crate) struct Blocks {
    pub op: NoiseOperator,
    pub blocks: usize,
    /// The velocity of every unknown (its cell centre).
    pub v: Vec<f64>,
    tmp: Vec<f64>,
}

impl Blocks {
    pub(crate) fn new(op: NoiseOperator, blocks: usize) -> Self {
        let ns = op.mesh.states;
        let v: Vec<f64> = op
            .mesh
            .centres
            .iter()
            .flat_map(|&c| std::iter::repeat(c).take(ns))
            .collect();
        let tmp = vec![0.0; v.len()];
        Blocks { op, blocks, v, tmp }
    }

    /// Mass at v = 0 in the states drawn from π (Eq. (N28)), later blocks 0.
    pub(crate) fn initial(&self) -> Result<Vec<f64>> {
        let m = &self.op.mesh;
        if m.origin.is_empty() {
            return Err(Error::invalid(
                "noise",
                format!("levels {:?}", self.op.chain.levels),
                "a velocity interval containing v = 0 (the initial velocity of fp transient and fp msd)",
            ));
        }
        let mut u = vec![0.0; self.blocks * self.v.len()];
        for (s, cells) in m.origin.iter().enumerate() {
            for &(i, w) in cells {
                u[i * m.states + s] += w * self.op.chain.pi[s];
            }
        }
        Ok(u)
    }
}

impl ShiftedLinear for Blocks {
    fn dim(&self) -> usize {
        self.blocks * self.v.len()
    }

    fn apply(&self, u: &[f64], out: &mut [f64]) {
        let d = self.v.len();
        for k in 0..self.blocks {
            self.op
                .apply(&u[k * d..(k + 1) * d], &mut out[k * d..(k + 1) * d]);
            if k > 0 {
                for i in 0..d {
                    out[k * d + i] += k as f64 * self.v[i] * u[(k - 1) * d + i];
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
        // Block lower triangular: forward substitution, block k with the
        // source c k v∘x_{k-1} moved to its right side.
        let d = self.v.len();
        for k in 0..self.blocks {
            self.tmp.copy_from_slice(&b[k * d..(k + 1) * d]);
            let (prev, rest) = x.split_at_mut(k * d);
            if k > 0 {
                let ck = c * k as f64;
                for (i, t) in self.tmp.iter_mut().enumerate() {
                    *t += ck * self.v[i] * prev[(k - 1) * d + i];
                }
            }
            self.op.solve_shifted(c, &self.tmp, &mut rest[..d])?;
        }
        Ok(())
    }
}

/// Observables at one time of `blocks` blocks with unknown velocities
/// `v`: mass, `<v>`, `<v²>`, then `<x>`, `<x v>`, `<x²>` (3 blocks).
pub(crate) fn observe(v: &[f64], blocks: usize, u: &[f64]) -> [f64; 6] {
    let d = v.len();
    let sum = |k: usize, pow: i32| -> f64 {
        u[k * d..(k + 1) * d]
            .iter()
            .zip(v)
            .map(|(x, v)| x * v.powi(pow))
            .sum()
    };
    let mut o = [sum(0, 0), sum(0, 1), sum(0, 2), 0.0, 0.0, 0.0];
    if blocks == 3 {
        o[3] = sum(1, 0);
        o[4] = sum(1, 1);
        o[5] = sum(2, 0);
    }
    o
}
