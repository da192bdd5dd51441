//! The x-weighted moment chain of `fp msd` on the N-state operator with an
//! exponential refractory period (docs/equations.md, (R14): the chain of
//! (R8) over the held states of (R10)).
//!
//! Per block k = 0, 1, 2 the unknowns are the cells' x^k-weighted masses
//! x_k (as [`super::Blocks`]) and, after them, one held vector
//! y_k(a) = (y_k(a, s))_s per held velocity u_a (weight w_a: the point
//! target v_r, or a random target's cells) and noise state s:
//!
//! ```text
//! x_k' = B x_k + κ Σ_a E_a y_k(a) + k v∘x_{k-1}
//! y_k(a)' = w_a r W S x_k - K y_k(a) + k u_a y_{k-1}(a),   K = κ I - Qᵀ
//! ```
//!
//! (B: the operator without its reset influx; E_a: the cells of atom a,
//! Σ_a w_a E_a the reset target; S the state sums; W the noise rule). x
//! moves at the held velocity while held, so for k ≥ 1 the held vectors
//! are not proportional to w_a: one per atom. The shifted solve of each
//! block is that of `fp transient`'s held chain with the held right side
//! per atom: y(a) = L (d_a + c w_a r W S x), L = (I + cK)⁻¹, and the
//! cells' Woodbury over the rank-N re-entry with r W replaced by
//! G = cκ L r W, its constant cκ Σ_a E_a L d_a.

use super::{k_times, HeldFactor as Factor, Hold, NoiseOperator};
use crate::error::Result;
use crate::model::noise::chain;
use crate::model::reset::Reset;
use crate::model::Params;
use crate::numerics::trbdf2::ShiftedLinear;
use crate::numerics::Failure;

const METHOD: &str = "fp msd (held states)";

/// The three-block moment chain with held states.
pub(crate) struct HeldBlocks {
    op: NoiseOperator,
    kappa: f64,
    /// Per held atom: its velocity u_a, weight w_a and cell (None: the
    /// point target, placed as the reset places it).
    atoms: Vec<(f64, f64, Option<usize>)>,
    /// The velocity of every cell unknown (its cell centre).
    v: Vec<f64>,
    factor: Option<Factor>,
}

impl HeldBlocks {
    /// The chain of `p` on `op`; None without a hold (no exponential
    /// refractory period, or r = 0).
    pub(crate) fn of(p: &Params, op: NoiseOperator) -> Option<HeldBlocks> {
        let hold = Hold::of(p, &op)?;
        let atoms = match p.reset().point() {
            Some(u) => vec![(u, 1.0, None)],
            None => op.mesh.target[0]
                .iter()
                .map(|&(i, w)| (op.mesh.centres[i], w, Some(i)))
                .collect(),
        };
        let ns = op.mesh.states;
        let v = op
            .mesh
            .centres
            .iter()
            .flat_map(|&c| std::iter::repeat(c).take(ns))
            .collect();
        Some(HeldBlocks {
            op,
            kappa: hold.kappa,
            atoms,
            v,
            factor: None,
        })
    }

    fn ns(&self) -> usize {
        self.op.mesh.states
    }

    /// Unknowns of one block: the cells, then the held vectors.
    fn block(&self) -> usize {
        self.v.len() + self.atoms.len() * self.ns()
    }

    /// Mass at v = 0 in the states drawn from π, nothing held, later
    /// blocks 0.
    pub(crate) fn initial(&self) -> Result<Vec<f64>> {
        let cells = super::Blocks::new(self.op.clone(), 1).initial()?;
        let mut u = vec![0.0; 3 * self.block()];
        u[..cells.len()].copy_from_slice(&cells);
        Ok(u)
    }

    /// out += κ E_a y (the re-entry of atom a's held vector).
    fn place(&self, a: usize, y: &[f64], scale: f64, out: &mut [f64]) {
        let ns = self.ns();
        match self.atoms[a].2 {
            None => {
                let w: Vec<f64> = y.iter().map(|x| scale * x).collect();
                self.op.add_target(&w, out);
            }
            Some(i) => {
                for (s, x) in y.iter().enumerate() {
                    out[i * ns + s] += scale * x;
                }
            }
        }
    }

    /// What [`observe`] needs of this chain, owned (to observe while the
    /// time stepping holds the chain).
    pub(crate) fn observer(&self) -> Observer {
        Observer {
            v: self.v.clone(),
            u: self.atoms.iter().map(|a| a.0).collect(),
            ns: self.ns(),
        }
    }

    /// One block's operator: out = A_h [x; y] (no moment source).
    fn apply_block(&self, u: &[f64], out: &mut [f64]) {
        let (d, ns) = (self.v.len(), self.ns());
        let (x, y) = u.split_at(d);
        let (ox, oy) = out.split_at_mut(d);
        self.op.apply(x, ox);
        let inf = self.op.influx(&self.op.state_sums(x));
        let back: Vec<f64> = inf.iter().map(|r| -r).collect();
        self.op.add_target(&back, ox);
        for (a, (ya, oa)) in y.chunks_exact(ns).zip(oy.chunks_exact_mut(ns)).enumerate() {
            self.place(a, ya, self.kappa, ox);
            let ky = k_times(&self.op.chain, self.kappa, ya);
            let w = self.atoms[a].1;
            for s in 0..ns {
                oa[s] = w * inf[s] - ky[s];
            }
        }
    }

    fn factorise(&self, c: f64) -> Result<Factor> {
        Factor::new(&self.op, c, self.kappa, METHOD)
    }

    /// Solve (I − cA_h) [x; y] = b for one block (module docs).
    fn solve_block(&self, f: &Factor, b: &[f64], out: &mut [f64]) -> Result<()> {
        let (d, ns, c) = (self.v.len(), self.ns(), f.c);
        let (bx, by) = b.split_at(d);
        let mut rhs = bx.to_vec();
        for (a, da) in by.chunks_exact(ns).enumerate() {
            let l = chain::solve(&f.ik, da, METHOD)?;
            self.place(a, &l, c * self.kappa, &mut rhs);
        }
        f.band.solve(&mut rhs);
        let t = f.g_times(&self.op, self.kappa, &self.op.state_sums(&rhs), METHOD)?;
        let ct: Vec<f64> = t.iter().map(|y| c * y).collect();
        let w = chain::solve(&f.cap, &ct, "fp msd (capacitance)")?;
        for (zs, ws) in f.z.iter().zip(&w) {
            for (xi, zi) in rhs.iter_mut().zip(zs) {
                *xi += zi * ws;
            }
        }
        let inf = self.op.influx(&self.op.state_sums(&rhs));
        let (ox, oy) = out.split_at_mut(d);
        for (a, (da, oa)) in by.chunks_exact(ns).zip(oy.chunks_exact_mut(ns)).enumerate() {
            let w = self.atoms[a].1;
            let rhs_a: Vec<f64> = da.iter().zip(&inf).map(|(d, r)| d + c * w * r).collect();
            oa.copy_from_slice(&chain::solve(&f.ik, &rhs_a, METHOD)?);
        }
        ox.copy_from_slice(&rhs);
        Ok(())
    }

    /// The moment source k (v∘x_{k-1}, u_a y_{k-1}(a)) of block k, scaled.
    fn add_source(&self, k: usize, prev: &[f64], scale: f64, out: &mut [f64]) {
        let (d, ns) = (self.v.len(), self.ns());
        let kf = scale * k as f64;
        for i in 0..d {
            out[i] += kf * self.v[i] * prev[i];
        }
        for (a, (p, o)) in prev[d..]
            .chunks_exact(ns)
            .zip(out[d..].chunks_exact_mut(ns))
            .enumerate()
        {
            for (oi, pi) in o.iter_mut().zip(p) {
                *oi += kf * self.atoms[a].0 * pi;
            }
        }
    }
}

impl ShiftedLinear for HeldBlocks {
    fn dim(&self) -> usize {
        3 * self.block()
    }

    fn apply(&self, u: &[f64], out: &mut [f64]) {
        let n = self.block();
        for k in 0..3 {
            self.apply_block(&u[k * n..(k + 1) * n], &mut out[k * n..(k + 1) * n]);
            if k > 0 {
                let (prev, cur) = (&u[(k - 1) * n..k * n], &mut out[k * n..(k + 1) * n]);
                self.add_source(k, prev, 1.0, cur);
            }
        }
    }

    fn solve_shifted(
        &mut self,
        c: f64,
        b: &[f64],
        x: &mut [f64],
    ) -> std::result::Result<(), Failure> {
        let fail = Failure::shifted_solve(
            "fp msd shifted solve (I - cA) x = b (N states, held states)",
            c,
        )?;
        if !matches!(&self.factor, Some(f) if f.c == c) {
            self.factor = Some(self.factorise(c).map_err(|_| fail)?);
        }
        let f = self.factor.as_ref().expect("factorised above");
        let n = self.block();
        let mut tmp = vec![0.0; n];
        for k in 0..3 {
            tmp.copy_from_slice(&b[k * n..(k + 1) * n]);
            let (prev, rest) = x.split_at_mut(k * n);
            if k > 0 {
                self.add_source(k, &prev[(k - 1) * n..], c, &mut tmp);
            }
            self.solve_block(f, &tmp, &mut rest[..n])
                .map_err(|_| fail)?;
        }
        match x.iter().all(|v| v.is_finite()) {
            true => Ok(()),
            false => Err(fail),
        }
    }
}

/// The cell velocities, held velocities and states of a [`HeldBlocks`].
pub(crate) struct Observer {
    v: Vec<f64>,
    u: Vec<f64>,
    ns: usize,
}

impl Observer {
    /// Mass, `<v>`, `<v²>`, `<x>`, `<x v>`, `<x²>` of a chain state, the
    /// held vectors at their velocities.
    pub(crate) fn observe(&self, u: &[f64]) -> [f64; 6] {
        let (d, ns) = (self.v.len(), self.ns);
        let n = d + self.u.len() * ns;
        let mut o = [0.0; 6];
        for k in 0..3 {
            let (x, y) = u[k * n..(k + 1) * n].split_at(d);
            let mut m = [0.0; 3];
            for (xi, vi) in x.iter().zip(&self.v) {
                m[0] += xi;
                m[1] += xi * vi;
                m[2] += xi * vi * vi;
            }
            for (ya, ua) in y.chunks_exact(ns).zip(&self.u) {
                let s = ya.iter().sum::<f64>();
                m[0] += s;
                m[1] += s * ua;
                m[2] += s * ua * ua;
            }
            match k {
                0 => o[..3].copy_from_slice(&m),
                1 => (o[3], o[4]) = (m[0], m[1]),
                _ => o[5] = m[0],
            }
        }
        o
    }
}
