//! An exponential refractory period on the finite-volume chain
//! (docs/equations.md, entry (R1)).
//!
//! During the period the velocity is held at the value the reset gave, so
//! the refractory state carries no transport: per noise state s it is a
//! mass q_s sitting at the target (for a random target, spread over the
//! target's cells as the target's law, q_s(u) = q_s ρ(u)). With κ = 1/M:
//!
//! ```text
//! dq_s/dt = [W (r M+, r M-)]_s - κ q_s + λ (q_{-s} - q_s)
//! ```
//!
//! (M± the continuous state masses, W the noise rule
//! [`NoiseAtReset::mix`]), and the continuous densities lose r P_s and gain
//! κ q_s at the target instead of the reset influx. With
//! K = [[κ + λ, -λ], [-λ, κ + λ]] the refractory rows read
//! K q = W r M. The held velocities are the [`Atom`]s: one for a point
//! target (v_r, re-entering the reset cells), one per target cell for a
//! random one (its cell mass and centre).

use super::grid::Grid;
use super::solve::solve_reset;
use crate::error::{Error, Result};
use crate::model::reset::{NoiseAtReset, Refractory, Reset};
use crate::model::Params;

/// A held velocity: where its mass re-enters the continuous chain.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Atom {
    /// Cell receiving + mass when the period ends.
    pub plus: usize,
    /// Cell receiving - mass.
    pub minus: usize,
    /// Probability of this held velocity (the atoms sum to 1).
    pub w: f64,
    /// The held velocity.
    pub v: f64,
}

/// The refractory block of the chain.
#[derive(Clone, Debug)]
pub(crate) struct Held {
    /// Leaving rate κ = 1/M.
    pub kappa: f64,
    lambda: f64,
    rate: f64,
    noise: NoiseAtReset,
    /// The held velocities.
    pub atoms: Vec<Atom>,
}

impl Held {
    /// The block of `p` on `g`; None without an exponential refractory
    /// period (a fixed one is refused by the support table before this).
    pub fn new(g: &Grid, p: &Params) -> Option<Held> {
        let mean = match p.schedule().refractory {
            Some(Refractory::Exp { mean }) => mean,
            Some(Refractory::Fixed { .. }) | None => return None,
        };
        let atoms = match (&g.spread, p.reset().point()) {
            (None, Some(v)) => vec![Atom {
                plus: g.reset_plus,
                minus: g.reset_minus,
                w: 1.0,
                v,
            }],
            (Some(w), _) => w
                .iter()
                .enumerate()
                .filter(|(_, &w)| w > 0.0)
                .map(|(k, &w)| Atom {
                    plus: k,
                    minus: k,
                    w,
                    v: g.centres[k],
                })
                .collect(),
            (None, None) => unreachable!("a grid without spread has a point target"),
        };
        Some(Held {
            kappa: 1.0 / mean,
            lambda: p.lambda(),
            rate: p.rate(),
            noise: p.reset().noise(),
            atoms,
        })
    }

    /// The flip rate λ.
    pub fn lambda(&self) -> f64 {
        self.lambda
    }

    /// K⁻¹ x, K = [[κ + λ, -λ], [-λ, κ + λ]] (positive entries).
    pub fn k_inv(&self, x: [f64; 2]) -> [f64; 2] {
        let (k, l) = (self.kappa, self.lambda);
        let det = k * (k + 2.0 * l);
        [
            ((k + l) * x[0] + l * x[1]) / det,
            (l * x[0] + (k + l) * x[1]) / det,
        ]
    }

    /// W (r a, r b): the refractory influx of the reset outflux (a, b).
    pub fn influx(&self, a: f64, b: f64) -> [f64; 2] {
        let (x, y) = self.noise.mix(self.rate * a, self.rate * b);
        [x, y]
    }

    /// Add to `b` the re-entry `per_atom(atom)` (per state) at each atom.
    pub fn add_exit(&self, b: &mut [[f64; 2]], per_atom: impl Fn(usize, &Atom) -> [f64; 2]) {
        for (i, a) in self.atoms.iter().enumerate() {
            let x = per_atom(i, a);
            b[a.plus][0] += x[0];
            b[a.minus][1] += x[1];
        }
    }

    /// (Σ w v, Σ w v²) of the held velocity.
    pub fn velocity_moments(&self) -> (f64, f64) {
        self.atoms.iter().fold((0.0, 0.0), |(s1, s2), a| {
            (s1 + a.w * a.v, s2 + a.w * a.v * a.v)
        })
    }

    /// The continuous responses Z± to a unit re-entry in each state (spread
    /// over the atoms) and their state sums a[s][t] = Σ Z_t[s].
    fn responses(&self, g: &Grid) -> ([Vec<[f64; 2]>; 2], [[f64; 2]; 2]) {
        let n = g.cells();
        let unit = |t: usize| {
            let mut b = vec![[0.0; 2]; n];
            self.add_exit(&mut b, |_, a| {
                let mut x = [0.0; 2];
                x[t] = -a.w;
                x
            });
            solve_reset(g, self.lambda, self.rate, &b)
        };
        let z = [unit(0), unit(1)];
        let sums = |z: &[[f64; 2]]| state_sums(z);
        let (s0, s1) = (sums(&z[0]), sums(&z[1]));
        (z, [[s0[0], s1[0]], [s0[1], s1[1]]])
    }

    /// T = κ K⁻¹ W r a, the map from the re-entry amplitudes back to
    /// themselves through one reset-and-refractory cycle (columns sum to 1).
    fn cycle(&self, a: &[[f64; 2]; 2]) -> [[f64; 2]; 2] {
        let mut t = [[0.0; 2]; 2];
        for col in 0..2 {
            let w = self.influx(a[0][col], a[1][col]);
            let k = self.k_inv(w);
            t[0][col] = self.kappa * k[0];
            t[1][col] = self.kappa * k[1];
        }
        t
    }

    /// Stationary continuous masses and refractory masses (q+, q-), total
    /// 1: the continuous part is J+ Z+ + J- Z- with J = κ q the Perron
    /// vector (T01, T10) of the column-stochastic T.
    pub fn stationary(&self, g: &Grid) -> Result<(Vec<[f64; 2]>, [f64; 2])> {
        let (z, a) = self.responses(g);
        let t = self.cycle(&a);
        let (al, be) = (t[1][0], t[0][1]);
        let j = if al + be > 0.0 { [be, al] } else { [1.0, 1.0] };
        let mut m: Vec<[f64; 2]> = z[0]
            .iter()
            .zip(&z[1])
            .map(|(p, q)| [j[0] * p[0] + j[1] * q[0], j[0] * p[1] + j[1] * q[1]])
            .collect();
        let mut q = [j[0] / self.kappa, j[1] / self.kappa];
        let total: f64 = m.iter().map(|c| c[0] + c[1]).sum::<f64>() + q[0] + q[1];
        if !(total.is_finite() && total > 0.0) {
            return Err(Error::Numerical {
                method: "fp stationary",
                reason: format!("refractory stationary solve gave total mass {total}"),
            });
        }
        m.iter_mut().for_each(|c| {
            c[0] /= total;
            c[1] /= total;
        });
        q.iter_mut().for_each(|x| *x /= total);
        Ok((m, q))
    }

    /// D_eff = Σ π f y of the chain with the refractory states, from the
    /// dual problem A y = -(π∘f), f = v - `<v>` (the held velocity in the
    /// refractory states). The refractory rows give
    /// y_R(a) = w_a K⁻¹ (W r Y + f_a q), Y the continuous state sums of y;
    /// the continuous part is y0 + J+ Z+ + J- Z- with
    /// B y0 = -(π∘f) - Σ_a κ w_a f_a K⁻¹ q and J = κ K⁻¹ W r Y, i.e.
    /// (I - T) J = κ K⁻¹ W r Y0: singular (the free multiple of π), and
    /// consistent since Σ π f = 0; one row is solved. Needs λ > 0.
    pub fn d_eff(&self, g: &Grid, m: &[[f64; 2]], q: [f64; 2], v_mean: f64) -> f64 {
        let f: Vec<f64> = g.centres.iter().map(|&v| v - v_mean).collect();
        let kq = self.k_inv(q);
        let mut b: Vec<[f64; 2]> = m
            .iter()
            .zip(&f)
            .map(|(c, &fi)| [-c[0] * fi, -c[1] * fi])
            .collect();
        self.add_exit(&mut b, |_, a| {
            let s = -self.kappa * a.w * (a.v - v_mean);
            [s * kq[0], s * kq[1]]
        });
        let y0 = solve_reset(g, self.lambda, self.rate, &b);
        let (z, a) = self.responses(g);
        let t = self.cycle(&a);
        let y0s = state_sums(&y0);
        let c = self
            .k_inv(self.influx(y0s[0], y0s[1]))
            .map(|x| self.kappa * x);
        // 1 - T00 = T10 (columns sum to 1), without the cancellation.
        let (al, be) = (t[1][0], t[0][1]);
        let j = if al >= be {
            [c[0] / al, 0.0]
        } else {
            [0.0, -c[0] / be]
        };
        let ys = [
            y0s[0] + a[0][0] * j[0] + a[0][1] * j[1],
            y0s[1] + a[1][0] * j[0] + a[1][1] * j[1],
        ];
        let cont: f64 = (0..g.cells())
            .map(|i| {
                let y = y0[i][0]
                    + y0[i][1]
                    + j[0] * (z[0][i][0] + z[0][i][1])
                    + j[1] * (z[1][i][0] + z[1][i][1]);
                f[i] * y
            })
            .sum();
        let inf = self.influx(ys[0], ys[1]);
        let held: f64 = self
            .atoms
            .iter()
            .map(|at| {
                let fa = at.v - v_mean;
                let y = self.k_inv([inf[0] + fa * q[0], inf[1] + fa * q[1]]);
                fa * at.w * (y[0] + y[1])
            })
            .sum();
        cont + held
    }
}

/// (Σ u+, Σ u-).
pub(crate) fn state_sums(u: &[[f64; 2]]) -> [f64; 2] {
    u.iter().fold([0.0, 0.0], |s, c| [s[0] + c[0], s[1] + c[1]])
}
