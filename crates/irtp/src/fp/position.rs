//! Position resetting on the finite-volume chain (docs/equations.md,
//! entry (R2)): the stationary `<x>` and `<x²>`.
//!
//! The x-weighted cell masses M_k = ∫ x^k P dx obey
//! dM_k/dt = A M_k + k v M_{k-1} (as in [`super::msd()`]); with position
//! resetting a reset removes x-weighted mass at rate r and injects
//! r x_r^k times the (mixed) state masses at the target, so in the
//! stationary state
//!
//! ```text
//! B M_k = -k v M_{k-1} - (re-injection of W r x_r^k (M0+, M0-)),
//! ```
//!
//! B the operator with the reset loss and without re-injection (nonsingular
//! for r > 0). With a refractory period the re-injection is the refractory
//! exit κ Q_k, and the refractory x-moments per held velocity u_a obey
//! K Q_k(a) = w_a W r x_r^k M0 + k u_a Q_{k-1}(a) (x moves at u_a).

use super::grid::Grid;
use super::refractory::{state_sums, Held};
use super::solve::solve_reset;
use crate::model::Params;

/// (`<x>`, `<x²>`) in the stationary state with continuous masses `m` and
/// refractory masses `q`, position reset to `x_r`; needs r > 0.
pub(crate) fn stationary_x(
    g: &Grid,
    p: &Params,
    held: Option<&Held>,
    m: &[[f64; 2]],
    q: [f64; 2],
    x_r: f64,
) -> [f64; 2] {
    let (lambda, r) = (p.lambda(), p.rate());
    let s0 = state_sums(m);
    let mut prev = m.to_vec();
    let mut prev_q: Vec<[f64; 2]> = held
        .map(|h| h.atoms.iter().map(|a| [a.w * q[0], a.w * q[1]]).collect())
        .unwrap_or_default();
    let mut out = [0.0; 2];
    for k in 1..=2usize {
        let kf = k as f64;
        let xk = x_r.powi(k as i32);
        let mut b: Vec<[f64; 2]> = prev
            .iter()
            .zip(&g.centres)
            .map(|(c, &v)| [-kf * v * c[0], -kf * v * c[1]])
            .collect();
        let mut held_mass = 0.0;
        match held {
            None => {
                let (ip, im) = g.reinject(r * xk * s0[0], r * xk * s0[1]);
                g.add_reset(&mut b, -ip, -im);
            }
            Some(h) => {
                let inf = h.influx(xk * s0[0], xk * s0[1]);
                let qk: Vec<[f64; 2]> = h
                    .atoms
                    .iter()
                    .zip(&prev_q)
                    .map(|(a, pq)| {
                        h.k_inv([
                            a.w * inf[0] + kf * a.v * pq[0],
                            a.w * inf[1] + kf * a.v * pq[1],
                        ])
                    })
                    .collect();
                h.add_exit(&mut b, |i, _| [-h.kappa * qk[i][0], -h.kappa * qk[i][1]]);
                held_mass = qk.iter().map(|x| x[0] + x[1]).sum();
                prev_q = qk;
            }
        }
        let mk = solve_reset(g, lambda, r, &b);
        let s = state_sums(&mk);
        out[k - 1] = s[0] + s[1] + held_mass;
        prev = mk;
    }
    out
}
