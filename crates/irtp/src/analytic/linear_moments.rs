//! Newtonian drag g(v) = v: exact time-dependent moments `<v>(t)`, `<v²>(t)`,
//! `<x>(t)`, `<x v>(t)`, `<x²>(t)` from the paper's start (x = v = 0, η = ±Σ
//! with probability ½), for any reset rate (docs/equations.md, entry (D1)).
//!
//! Derivation: the generator of the simulated process (Eqs. (5), (6), (3),
//! position and noise state kept at a reset to v_r) is
//!
//! ```text
//! L f(x, v, η) = v ∂_x f + (η - v) ∂_v f + λ [f(x, v, -η) - f] + r [f(x, v_r, η) - f],
//! ```
//!
//! and d⟨f⟩/dt = ⟨L f⟩. With η² = Σ² and <η>(t) = 0 (L η = -2λ η, <η>(0) = 0):
//!
//! ```text
//! ⟨v⟩'   = -(1 + r) ⟨v⟩ + r <v_r>
//! <vη>'  = Σ² - (1 + 2λ + r) <vη>                       (+ r v_r <η> = 0)
//! ⟨v²⟩'  = 2 <vη> - (2 + r) ⟨v²⟩ + r <v_r²>
//! ⟨x⟩'   = ⟨v⟩
//! <xη>'  = <vη> - κ <xη>        (κ = 2λ: a reset keeps x and η; κ = 2λ + r: it re-draws η)
//! ⟨xv⟩'  = ⟨v²⟩ + <xη> - (1 + r) ⟨xv⟩ + r <v_r> ⟨x⟩
//! ⟨x²⟩'  = 2 ⟨xv⟩
//! ```
//!
//! Every right side involves only these seven moments: the system closes, also
//! with the reset terms (a rule that also reset x would add r (x_r v_r - ⟨xv⟩)
//! and r (x_r² - ⟨x²⟩); the rules here keep x and add none). A rule that
//! re-draws η ([`crate::model::reset::NoiseAtReset::Redrawn`]) changes only the equations of the
//! η-weighted moments: f(x, v_r, ±Σ) averages to 0 for f = xη and vη, so the
//! reset term of <xη> is -r <xη> (that of <vη> is -r <vη> either way, as
//! <η> = 0). It reads u' = A u + b with A lower triangular and constant, u(0) = 0,
//! so u(t) = ∫_0^t e^{As} b ds exactly.
//!
//! Evaluation (our choice): the diagonal of A holds rates that coincide at
//! the paper's own λ = ½ (1 + 2λ + r = 2 + r), so a hand eigen-decomposition
//! would need separate degenerate cases, and a general `expm` (Padé, scaling
//! and squaring) is accurate only normwise, while `<x²>` ~ Σ² t⁴/4 is tiny at
//! early times. We step the exact propagator: over each output interval, in
//! equal substeps h with h ρ ≤ ¼ (ρ = the largest rate), u ← E u + w with
//! E = e^{Ah} and w = ∫_0^h e^{As} b ds summed as Taylor series until the
//! terms fall below 1e-18 of the sum. With h ρ ≤ ¼ each series is dominated by
//! its first non-zero term, so every component, tiny ones included, is
//! accurate to a few ulp per substep (measured: 1e-14 relative against the
//! small-t expansion and the explicit `<v²>`, see the tests).

use super::linear::{eta_decay, require_linear};
use crate::error::{finite, Error, Result};
use crate::model::reset::Solver;
use crate::model::reset::{NoiseAtReset, Refractory, Reset};
use crate::model::Params;

mod refractory;

const N: usize = 7;
/// Indices of the moments in the state vector.
const V: usize = 0;
const VE: usize = 1;
const V2: usize = 2;
const X: usize = 3;
const XE: usize = 4;
const XV: usize = 5;
const X2: usize = 6;

/// The exact moments at the requested times.
#[derive(Clone, Debug, PartialEq)]
pub struct LinearMoments {
    /// Times.
    pub t: Vec<f64>,
    /// `<v>(t)`.
    pub v_mean: Vec<f64>,
    /// `<v²>(t)`.
    pub v2: Vec<f64>,
    /// `<v η>(t)`.
    pub v_eta: Vec<f64>,
    /// `<x>(t)`.
    pub x_mean: Vec<f64>,
    /// `<x v>(t)`.
    pub xv: Vec<f64>,
    /// `<x²>(t)`.
    pub x2: Vec<f64>,
}

impl LinearMoments {
    /// No times yet, room for `n`.
    pub(crate) fn empty(n: usize) -> Self {
        LinearMoments {
            t: Vec::with_capacity(n),
            v_mean: Vec::with_capacity(n),
            v2: Vec::with_capacity(n),
            v_eta: Vec::with_capacity(n),
            x_mean: Vec::with_capacity(n),
            xv: Vec::with_capacity(n),
            x2: Vec::with_capacity(n),
        }
    }
}

type Mat = [[f64; N]; N];

/// A and b of u' = A u + b (rows: the moment equations above).
fn system(p: &Params) -> Result<(Mat, [f64; N])> {
    require_linear(p)?; // refuses other drag laws
    let (l, r, s2) = (p.lambda(), p.rate(), p.sigma() * p.sigma());
    let eta_decay = eta_decay(p);
    let (m1, m2) = p.reset().target().moments();
    let mut a = [[0.0; N]; N];
    a[V][V] = -(1.0 + r);
    a[VE][VE] = -(1.0 + 2.0 * l + r);
    a[V2][VE] = 2.0;
    a[V2][V2] = -(2.0 + r);
    a[X][V] = 1.0;
    a[XE][VE] = 1.0;
    a[XE][XE] = -eta_decay;
    a[XV][V2] = 1.0;
    a[XV][XE] = 1.0;
    a[XV][XV] = -(1.0 + r);
    a[XV][X] = r * m1;
    a[X2][XV] = 2.0;
    let mut b = [0.0; N];
    b[V] = r * m1;
    b[VE] = s2;
    b[V2] = r * m2;
    if let Some(x) = p.schedule().position {
        // A reset also sends x to x_r, Eq. (R4): f(x_r, v_r, η') for
        // f = x, xη, xv, x² averages to x_r, 0, x_r <v_r>, x_r².
        let xr = x.x;
        a[X][X] = -r;
        b[X] = r * xr;
        a[XE][XE] = -(2.0 * l + r);
        a[XV][X] = 0.0;
        b[XV] = r * xr * m1;
        a[X2][X2] = -r;
        b[X2] = r * xr * xr;
    }
    Ok((a, b))
}

fn mat_vec<const K: usize>(a: &[[f64; K]; K], u: &[f64; K]) -> [f64; K] {
    let mut out = [0.0; K];
    for (o, row) in out.iter_mut().zip(a) {
        *o = row.iter().zip(u).map(|(x, y)| x * y).sum();
    }
    out
}

/// (E, w) = (e^{Ah}, ∫_0^h e^{As} b ds) by Taylor series, column by column:
/// E e_j = Σ_k (hA)^k e_j / k!, w = Σ_k h^{k+1} A^k b / (k+1)!.
fn propagator<const K: usize>(
    a: &[[f64; K]; K],
    b: &[f64; K],
    h: f64,
) -> ([[f64; K]; K], [f64; K]) {
    let series = |start: [f64; K], shift: usize| {
        let mut term = start;
        let mut sum = start;
        for k in 1..200 {
            let next = mat_vec(a, &term);
            let div = (k + shift) as f64;
            term = next.map(|x| x * h / div);
            let done = term
                .iter()
                .zip(&sum)
                .all(|(t, s)| t.abs() <= 1e-18 * s.abs());
            for (s, t) in sum.iter_mut().zip(&term) {
                *s += t;
            }
            if done {
                break;
            }
        }
        sum
    };
    let mut e = [[0.0; K]; K];
    for j in 0..K {
        let mut unit = [0.0; K];
        unit[j] = 1.0;
        let col = series(unit, 0);
        for i in 0..K {
            e[i][j] = col[i];
        }
    }
    let w = series(b.map(|x| x * h), 1);
    (e, w)
}

/// Advance u by `span` with the exact propagator (substeps h ρ ≤ ¼).
fn advance<const K: usize>(
    a: &[[f64; K]; K],
    b: &[f64; K],
    rho: f64,
    u: &mut [f64; K],
    span: f64,
    at: f64,
) -> Result<()> {
    if !(span > 0.0) {
        return Ok(());
    }
    let steps = (span * rho * 4.0).ceil().max(1.0);
    if !(steps <= 1e8) {
        return Err(Error::invalid(
            "times",
            at,
            "t * (2 + r + 2 lambda) <= 2.5e7",
        ));
    }
    let (e, w) = propagator(a, b, span / steps);
    for _ in 0..steps as u64 {
        let eu = mat_vec(&e, u);
        for i in 0..K {
            u[i] = eu[i] + w[i];
        }
    }
    Ok(())
}

/// The jump map of a periodic reset, Eq. (R5): v → u drawn from the
/// target (independent of everything else), η kept or re-drawn (<η> = 0
/// either way), x kept or sent to x_r.
fn jump(p: &Params, u: &mut [f64; N]) {
    let (m1, m2) = p.reset().target().moments();
    u[V] = m1;
    u[VE] = 0.0;
    u[V2] = m2;
    match p.schedule().position {
        Some(x) => {
            u[X] = x.x;
            u[XE] = 0.0;
            u[XV] = x.x * m1;
            u[X2] = x.x * x.x;
        }
        None => {
            if p.reset().noise() == NoiseAtReset::Redrawn {
                u[XE] = 0.0;
            }
            u[XV] = m1 * u[X];
        }
    }
}

/// Exact moments of the Newtonian IRTP at `times` (sorted, >= 0) from
/// x = v = 0, η = ±Σ with probability ½. With periodic resetting the
/// moments at t = kT are those just after the reset (paths are
/// right-continuous). With an exponential refractory period the
/// phase-resolved system of Eq. (R9) (module `refractory`; not with periodic
/// resetting); a fixed one is refused.
pub fn moments(p: &Params, times: &[f64]) -> Result<LinearMoments> {
    p.require(Solver::ClosedForm)?;
    match p.schedule().refractory {
        None => {}
        Some(Refractory::Exp { mean }) if p.schedule().periodic.is_none() => {
            return refractory::moments(p, mean, times);
        }
        Some(r) => {
            return Err(Error::invalid(
                "refractory",
                r.spec(),
                "exp:mean=M without --reset-period for the time-dependent linear moments",
            ));
        }
    }
    let (a, b) = system(p)?;
    let rho = (0..N).map(|i| a[i][i].abs()).fold(1.0, f64::max);
    let mut out = LinearMoments::empty(times.len());
    let period = p.schedule().periodic.map(|t| t.period);
    let mut resets = 0.0;
    let mut u = [0.0; N];
    let mut t = 0.0;
    for &tk in times {
        let tk = finite("times", tk)?;
        if !(tk >= t) {
            return Err(Error::invalid("times", tk, "sorted times >= 0"));
        }
        if let Some(tp) = period {
            // Every reset time in (t, tk], counted so as not to drift.
            while (resets + 1.0) * tp <= tk {
                resets += 1.0;
                advance(&a, &b, rho, &mut u, resets * tp - t, tk)?;
                t = resets * tp;
                jump(p, &mut u);
            }
        }
        advance(&a, &b, rho, &mut u, tk - t, tk)?;
        t = tk;
        out.t.push(tk);
        out.v_mean.push(u[V]);
        out.v2.push(u[V2]);
        out.v_eta.push(u[VE]);
        out.x_mean.push(u[X]);
        out.xv.push(u[XV]);
        out.x2.push(u[X2]);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::DragLaw;

    fn lin(s: f64, l: f64, r: f64, vr: f64) -> Params {
        Params::new(DragLaw::Linear, s, l, r, vr).unwrap()
    }

    /// Explicit solutions of the first three equations (distinct rates).
    #[test]
    fn velocity_moments_match_explicit_forms() {
        for (l, r, vr) in [(0.7, 0.0, 0.0), (0.3, 2.0, 0.4), (0.5, 1.0, -0.2)] {
            let p = lin(1.5, l, r, vr);
            let ts = [0.0, 0.01, 0.3, 1.0, 4.0, 30.0];
            let m = moments(&p, &ts).unwrap();
            let (a, b) = (1.0 + 2.0 * l + r, 2.0 + r);
            for (k, &t) in ts.iter().enumerate() {
                let v = r * vr * (-(-(1.0 + r) * t).exp_m1()) / (1.0 + r);
                let ve = 2.25 * (-(-a * t).exp_m1()) / a;
                // <v²> = ∫_0^t e^{-b(t-s)} (2 <vη>(s) + r v_r²) ds.
                let ex = |c: f64| -(-c * t).exp_m1() / c;
                let v2 = 2.0 * 2.25 / a
                    * (ex(b)
                        - if a == b {
                            t * (-b * t).exp()
                        } else {
                            ((-a * t).exp() - (-b * t).exp()) / (b - a)
                        })
                    + r * vr * vr * ex(b);
                // The explicit <v²> subtracts two O(t) terms to get O(t²):
                // it loses digits like 1/(b t) at small t.
                let tol = 1e-13 * (1.0 / (b * t)).max(1.0);
                let close = |x: f64, y: f64| (x - y).abs() <= tol * y.abs().max(1e-300);
                assert!(
                    close(m.v_mean[k], v) || (v == 0.0 && m.v_mean[k] == 0.0),
                    "{t} {} {v}",
                    m.v_mean[k]
                );
                assert!(close(m.v_eta[k], ve) || t == 0.0, "{t} {} {ve}", m.v_eta[k]);
                assert!(close(m.v2[k], v2) || t == 0.0, "{t} {} {v2}", m.v2[k]);
            }
        }
    }

    #[test]
    fn small_time_expansion_and_long_time_limits() {
        // Coinciding rates 1 + 2λ + r = 2 + r at λ = ½ (the paper's case).
        let p = lin(2.0, 0.5, 0.0, 0.0);
        let m = moments(&p, &[1e-4, 1e-3, 2000.0]).unwrap();
        for k in 0..2 {
            let t: f64 = m.t[k];
            // x ≈ η t²/2 - (η λ/3 + η/6) t³ + ...: <x²> = Σ² t⁴/4 (1 + O(t)).
            let rel = m.x2[k] / (4.0 * t.powi(4) / 4.0) - 1.0;
            assert!(rel.abs() < 2.0 * t, "{t}: {rel}");
        }
        // <x²> → 2 D_eff t + c: the slope 2 <xv> → 2 D_eff.
        let d = super::super::linear::d_eff(&p).unwrap();
        assert!((m.xv[2] / d - 1.0).abs() < 1e-12, "{} {d}", m.xv[2]);
        assert!((m.v2[2] / super::super::linear::v2(&p).unwrap() - 1.0).abs() < 1e-13);
        let p = lin(2.0, 0.8, 3.0, 0.3);
        let m = moments(&p, &[3000.0]).unwrap();
        let d = super::super::linear::d_eff(&p).unwrap();
        let vm = super::super::linear::v_mean(&p).unwrap();
        // <xv> - <x><v> → D_eff with a drift <v> ≠ 0.
        assert!(((m.xv[0] - m.x_mean[0] * vm) / d - 1.0).abs() < 1e-9);
    }

    #[test]
    fn refuses_unsorted_and_other_drags() {
        assert!(moments(&lin(1.0, 1.0, 0.0, 0.0), &[1.0, 0.5]).is_err());
        let p = Params::new(DragLaw::Tan, 3.0, 1.0, 1.0, 0.0).unwrap();
        assert!(moments(&p, &[1.0]).is_err());
    }
}
