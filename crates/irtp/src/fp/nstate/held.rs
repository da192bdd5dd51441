//! An exponential refractory period on the N-state chain
//! (docs/equations.md, entry (R10); the paper's noise: (R1)).
//!
//! During the period the velocity is held where the reset put it and the
//! noise keeps jumping with its generator Q; the period ends at rate
//! κ = 1/M. Per noise state s the held phase is a mass q_s at the target
//! (a random target's law spread over its cells), with
//!
//! ```text
//! dq/dt = W r M - K q,   K = κ I - Qᵀ
//! ```
//!
//! (M the continuous state masses, W the reset's noise rule), and the
//! continuous densities gain κ q_s at the target instead of the reset
//! influx. Summed over the phases the noise is the autonomous chain Q
//! (both noise rules map π to π), so M + q = π; with Qᵀ π = 0 the
//! stationary held masses are q = r/(κ + r) π: the hold fraction
//! r M/(1 + r M), whatever the noise.

use super::NoiseOperator;
use crate::error::Result;
use crate::model::noise::chain;
use crate::model::reset::{Refractory, Reset};
use crate::model::Params;
use crate::numerics::band::Band;

const METHOD: &str = "fp stationary (refractory)";

/// K y = κ y − Qᵀ y: the held block's operator on one vector of per-state
/// values (held masses, or a held block of the moment chain).
pub(crate) fn k_times(ch: &chain::Chain, kappa: f64, y: &[f64]) -> Vec<f64> {
    (0..y.len())
        .map(|s| {
            let inflow: f64 = (0..y.len())
                .filter(|&t| t != s)
                .map(|t| ch.q[t][s] * y[t])
                .sum();
            (kappa + ch.exit[s]) * y[s] - inflow
        })
        .collect()
}

/// The held block of an N-state chain.
#[derive(Clone, Debug)]
pub(crate) struct Hold {
    /// Leaving rate κ = 1/M.
    pub kappa: f64,
    /// Stationary held masses per state, q = r/(κ + r) π.
    pub q: Vec<f64>,
    /// The held velocities and their weights (the point target v_r, or a
    /// random target's cell centres with its cell masses), per target
    /// cell of state 0 (the same for every state on a random target).
    pub atoms: Vec<(f64, f64)>,
    /// The point target v_r (None: a random target).
    point: Option<f64>,
}

impl Hold {
    /// The block of `p` on `op`; None without an exponential refractory
    /// period or without resets (nothing is then held).
    pub(crate) fn of(p: &Params, op: &NoiseOperator) -> Option<Hold> {
        let mean = match p.schedule().refractory {
            Some(Refractory::Exp { mean }) if op.rate > 0.0 => mean,
            _ => return None,
        };
        let kappa = 1.0 / mean;
        let share = op.rate / (kappa + op.rate);
        let atoms = match p.reset().point() {
            Some(v) => vec![(v, 1.0)],
            None => op.mesh.target[0]
                .iter()
                .map(|&(i, w)| (op.mesh.centres[i], w))
                .collect(),
        };
        Some(Hold {
            kappa,
            q: op.chain.pi.iter().map(|p| share * p).collect(),
            atoms,
            point: p.reset().point(),
        })
    }

    /// Total held mass Σ q.
    pub(crate) fn mass(&self) -> f64 {
        self.q.iter().sum()
    }

    /// (Σ w u, Σ w u²) of the held velocity u.
    pub(crate) fn velocity_moments(&self) -> (f64, f64) {
        self.atoms
            .iter()
            .fold((0.0, 0.0), |(a, b), &(u, w)| (a + w * u, b + w * u * u))
    }

    /// The held velocity of target cell `i` (v_r for a point target).
    fn velocity_of(&self, op: &NoiseOperator, i: usize) -> f64 {
        self.point.unwrap_or(op.mesh.centres[i])
    }

    /// κ K⁻¹ x with K = κ I - Qᵀ, deflated so that it stays well posed as
    /// κ → 0: with x = (1ᵀx) π + z (1ᵀ z = 0), κ K⁻¹ π = π and
    /// K⁻¹ z = (K + π 1ᵀ)⁻¹ z (whose solution has 1ᵀ = 0), K + π 1ᵀ
    /// nonsingular for every κ ≥ 0 (Q irreducible).
    pub(crate) fn kappa_k_inv(&self, op: &NoiseOperator, x: &[f64]) -> Result<Vec<f64>> {
        let c = &op.chain;
        let ns = c.states();
        let k: Vec<Vec<f64>> = (0..ns)
            .map(|i| {
                (0..ns)
                    .map(|j| f64::from(u8::from(i == j)) * self.kappa - c.q[j][i] + c.pi[i])
                    .collect()
            })
            .collect();
        let total: f64 = x.iter().sum();
        let z: Vec<f64> = x.iter().zip(&c.pi).map(|(x, p)| x - total * p).collect();
        let y = chain::solve(&k, &z, METHOD)?;
        Ok(y.iter()
            .zip(&c.pi)
            .map(|(y, p)| total * p + self.kappa * y)
            .collect())
    }

    /// The re-entry κ q at the target: out -= κ q placed as a reset.
    pub(crate) fn stationary_source(&self, op: &NoiseOperator, out: &mut [f64]) {
        let j: Vec<f64> = self.q.iter().map(|q| -self.kappa * q).collect();
        op.add_target(&j, out);
    }

    /// The state sums Y of the dual problem A y = -(π∘f) with the held
    /// rows eliminated, y_R(a) = w_a K⁻¹ (W r Y + f_a q) (f_a = u_a - `<v>`):
    /// [(Qᵀ - r) + κ K⁻¹ W r] Y = -F - f̄ q (F the continuous state sums of
    /// m∘f, f̄ = Σ w_a f_a; κ K⁻¹ q = q since Qᵀ q = 0). The matrix has the
    /// left null vector 1 (the system is consistent as Σ π f = 0) and the
    /// right one M; its last row is replaced by Σ Y = 0.
    pub(crate) fn dual_state_sums(
        &self,
        op: &NoiseOperator,
        big_f: &[f64],
        f_bar: f64,
    ) -> Result<Vec<f64>> {
        let c = &op.chain;
        let ns = c.states();
        let mut cols = Vec::with_capacity(ns);
        for j in 0..ns {
            let mut e = vec![0.0; ns];
            e[j] = 1.0;
            let back = self.kappa_k_inv(op, &op.influx(&e))?;
            let col: Vec<f64> = (0..ns)
                .map(|i| {
                    let diag = if i == j { op.rate } else { 0.0 };
                    c.q[j][i] - diag + back[i]
                })
                .collect();
            cols.push(col);
        }
        let mut a: Vec<Vec<f64>> = (0..ns)
            .map(|i| (0..ns).map(|j| cols[j][i]).collect())
            .collect();
        let mut b: Vec<f64> = (0..ns).map(|i| -big_f[i] - f_bar * self.q[i]).collect();
        a[ns - 1] = vec![1.0; ns];
        b[ns - 1] = 0.0;
        chain::solve(&a, &b, METHOD)
    }

    /// The right side of the dual problem's continuous rows beyond -(m∘f):
    /// out -= κ K⁻¹ W r Y + f_a q at the target (the re-entry of the held
    /// rows' y_R).
    pub(crate) fn dual_source(
        &self,
        op: &NoiseOperator,
        y: &[f64],
        v_mean: f64,
        out: &mut [f64],
    ) -> Result<()> {
        let back = self.kappa_k_inv(op, &op.influx(y))?;
        let j: Vec<f64> = back.iter().map(|x| -x).collect();
        op.add_target(&j, out);
        let ns = op.mesh.states;
        for (s, cells) in op.mesh.target.iter().enumerate() {
            for &(i, w) in cells {
                let f = self.velocity_of(op, i) - v_mean;
                out[i * ns + s] -= w * f * self.q[s];
            }
        }
        Ok(())
    }

    /// The held rows' share of D_eff = Σ f y:
    /// Σ_a f_a 1ᵀ y_R(a) = (f̄ r Σ Y + q_tot Σ w_a f_a²)/κ (1ᵀ K⁻¹ = 1ᵀ/κ).
    pub(crate) fn d_eff_share(&self, op: &NoiseOperator, y: &[f64], v_mean: f64) -> f64 {
        let (u1, u2) = self.velocity_moments();
        let f_bar = u1 - v_mean;
        let f2 = u2 - 2.0 * v_mean * u1 + v_mean * v_mean;
        let y_sum: f64 = y.iter().sum();
        (f_bar * op.rate * y_sum + self.mass() * f2) / self.kappa
    }
}

/// The factors of the shifted solve (I − cA) x = b with the held masses
/// (R10) (and per atom (R14)): (I − cB)'s band factors (B without the
/// reset influx), Z_s = (I − cB)⁻¹ E_s, I + cK (K = κI − Qᵀ) and the
/// capacitance I − c G S Z, G = cκ (I + cK)⁻¹ r W. One factorisation for
/// `fp transient`'s held masses and `fp msd`'s held blocks.
pub(crate) struct HeldFactor {
    /// The shift c.
    pub c: f64,
    /// (I − cB)'s band factors.
    pub band: Band,
    /// Z_s per noise state s.
    pub z: Vec<Vec<f64>>,
    /// I + cK.
    pub ik: Vec<Vec<f64>>,
    /// The capacitance I − c G S Z.
    pub cap: Vec<Vec<f64>>,
}

impl HeldFactor {
    /// The factors at shift `c` of `op` with the hold's leaving rate
    /// `kappa`; `method` names the solve in a failure.
    pub(crate) fn new(
        op: &NoiseOperator,
        c: f64,
        kappa: f64,
        method: &'static str,
    ) -> Result<Self> {
        let ns = op.mesh.states;
        let mut band = op.band(Some(c));
        band.factor_for(method)?;
        let z: Vec<Vec<f64>> = (0..ns)
            .map(|s| {
                let mut e = vec![0.0; op.dim()];
                let mut w = vec![0.0; ns];
                w[s] = 1.0;
                op.add_target(&w, &mut e);
                band.solve(&mut e);
                e
            })
            .collect();
        let ik: Vec<Vec<f64>> = (0..ns)
            .map(|i| {
                (0..ns)
                    .map(|j| match i == j {
                        true => 1.0 + c * (kappa + op.chain.exit[i]),
                        false => -c * op.chain.q[j][i],
                    })
                    .collect()
            })
            .collect();
        let mut f = HeldFactor {
            c,
            band,
            z,
            ik,
            cap: Vec::new(),
        };
        let cols =
            f.z.iter()
                .map(|zs| f.g_times(op, kappa, &op.state_sums(zs), method))
                .collect::<Result<Vec<_>>>()?;
        f.cap = (0..ns)
            .map(|i| {
                (0..ns)
                    .map(|j| f64::from(u8::from(i == j)) - c * cols[j][i])
                    .collect()
            })
            .collect();
        Ok(f)
    }

    /// G y = cκ (I + cK)⁻¹ r W y.
    pub(crate) fn g_times(
        &self,
        op: &NoiseOperator,
        kappa: f64,
        y: &[f64],
        method: &'static str,
    ) -> Result<Vec<f64>> {
        let l = chain::solve(&self.ik, &op.influx(y), method)?;
        Ok(l.iter().map(|x| self.c * kappa * x).collect())
    }
}
