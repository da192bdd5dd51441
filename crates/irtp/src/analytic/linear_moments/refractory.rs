//! Newtonian drag with an exponential refractory period of mean M
//! (κ = 1/M): the time-dependent moments, resolved by phase
//! (docs/equations.md, entry (R9)).
//!
//! The process has a continuous phase C (the generator of the parent
//! module) and a held phase R, where the velocity stays at the value u the
//! reset drew, x moves at u and η keeps flipping:
//!
//! ```text
//! L_C f = v ∂_x f + (η - v) ∂_v f + λ [f(-η) - f] + r [f_R(x', u, η') - f_C]
//! L_R f = v ∂_x f + λ [f(-η) - f] + κ [f_C - f_R]
//! ```
//!
//! (u from the target, η' kept or re-drawn, x' = x or x_r). For the phase
//! moments E[f; C], E[f; R], d E[f; C]/dt = E[L_C-part f; C] - r E[f; C] +
//! κ E[f; R] and d E[f; R]/dt = E[v ∂_x f + flips; R] - κ E[f; R] +
//! r E[f(x', u, η'); C]. E[η; C] = E[η; R] = 0 from the symmetric start (a
//! closed pair with zero data), so with m_1 = `<u>`, m_2 = `<u²>`, ν = 1 (η
//! kept) or 0 (re-drawn):
//!
//! ```text
//! m_C'    = -r m_C + κ m_R                    m_R'    = r m_C - κ m_R
//! v_C'    = -(1+r) v_C + κ v_R                 v_R'    = r m_1 m_C - κ v_R
//! ve_C'   = Σ² m_C - (1+2λ+r) ve_C + κ ve_R    ve_R'   = -(2λ+κ) ve_R
//! v2_C'   = 2 ve_C - (2+r) v2_C + κ v2_R       v2_R'   = r m_2 m_C - κ v2_R
//! x_C'    = v_C - r x_C + κ x_R                x_R'    = v_R - κ x_R + r ξ_1
//! xe_C'   = ve_C - (2λ+r) xe_C + κ xe_R        xe_R'   = ve_R - (2λ+κ) xe_R + r ν' xe_C
//! xv_C'   = v2_C + xe_C - (1+r) xv_C + κ xv_R  xv_R'   = v2_R - κ xv_R + r m_1 ξ_1
//! x2_C'   = 2 xv_C - r x2_C + κ x2_R           x2_R'   = 2 xv_R - κ x2_R + r ξ_2
//! ```
//!
//! with ξ_k = x^k_C (x kept) or x_r^k m_C (position reset), ν' = ν with x
//! kept and 0 with position resetting (x_r η' averages to 0). The totals
//! are the sums of the two phases. Evaluation: the exact propagator of
//! the parent module (u(0) = e_{m_C}).

use super::{advance, LinearMoments};
use crate::error::{finite, Error, Result};
use crate::model::reset::{NoiseAtReset, Reset};
use crate::model::Params;

const N: usize = 16;
/// Continuous phase: mass, v, vη, v², x, xη, xv, x²; held phase: R + the same.
const MC: usize = 0;
const VC: usize = 1;
const VEC: usize = 2;
const V2C: usize = 3;
const XC: usize = 4;
const XEC: usize = 5;
const XVC: usize = 6;
const X2C: usize = 7;
const R: usize = 8;

/// The matrix of the phase system (module docs).
fn system(p: &Params, mean: f64) -> [[f64; N]; N] {
    let (l, r, s2, k) = (p.lambda(), p.rate(), p.sigma() * p.sigma(), 1.0 / mean);
    let (m1, m2) = p.reset().target().moments();
    let kept = p.reset().noise() == NoiseAtReset::Kept;
    let mut a = [[0.0; N]; N];
    // Continuous phase: the plain equations, loss r, gain κ from R.
    a[MC][MC] = -r;
    a[VC][VC] = -(1.0 + r);
    a[VEC][MC] = s2;
    a[VEC][VEC] = -(1.0 + 2.0 * l + r);
    a[V2C][VEC] = 2.0;
    a[V2C][V2C] = -(2.0 + r);
    a[XC][VC] = 1.0;
    a[XC][XC] = -r;
    a[XEC][VEC] = 1.0;
    a[XEC][XEC] = -(2.0 * l + r);
    a[XVC][V2C] = 1.0;
    a[XVC][XEC] = 1.0;
    a[XVC][XVC] = -(1.0 + r);
    a[X2C][XVC] = 2.0;
    a[X2C][X2C] = -r;
    for i in 0..R {
        a[i][R + i] = k;
    }
    // Held phase: v fixed, x moving at v, flips; loss κ, reset gain from C.
    let (mr, vr, ver, v2r, xr, xer, xvr, x2r) =
        (R, R + 1, R + 2, R + 3, R + 4, R + 5, R + 6, R + 7);
    for (i, row) in a.iter_mut().enumerate().skip(R) {
        row[i] = -k;
    }
    a[ver][ver] = -(2.0 * l + k);
    a[xer][xer] = -(2.0 * l + k);
    a[mr][MC] = r;
    a[vr][MC] = r * m1;
    a[v2r][MC] = r * m2;
    a[xr][vr] = 1.0;
    a[xer][ver] = 1.0;
    a[xvr][v2r] = 1.0;
    a[x2r][xvr] = 2.0;
    match p.schedule().position {
        None => {
            a[xr][XC] = r;
            a[xer][XEC] = if kept { r } else { 0.0 };
            a[xvr][XC] = r * m1;
            a[x2r][X2C] = r;
        }
        Some(x) => {
            a[xr][MC] = r * x.x;
            a[xvr][MC] = r * m1 * x.x;
            a[x2r][MC] = r * x.x * x.x;
        }
    }
    a
}

/// The moments at `times` (sorted, >= 0) with a refractory period of
/// `mean`.
pub(super) fn moments(p: &Params, mean: f64, times: &[f64]) -> Result<LinearMoments> {
    let a = system(p, mean);
    let b = [0.0; N];
    let rho = (0..N).map(|i| a[i][i].abs()).fold(1.0, f64::max);
    let mut u = [0.0; N];
    u[MC] = 1.0;
    let mut out = LinearMoments::empty(times.len());
    let mut t = 0.0;
    for &tk in times {
        let tk = finite("times", tk)?;
        if !(tk >= t) {
            return Err(Error::invalid("times", tk, "sorted times >= 0"));
        }
        advance(&a, &b, rho, &mut u, tk - t, tk)?;
        t = tk;
        let tot = |i: usize| u[i] + u[R + i];
        out.t.push(tk);
        out.v_mean.push(tot(VC));
        out.v2.push(tot(V2C));
        out.v_eta.push(tot(VEC));
        out.x_mean.push(tot(XC));
        out.xv.push(tot(XVC));
        out.x2.push(tot(X2C));
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::super::super::linear;
    use super::*;
    use crate::model::reset::{Schedule, Target};
    use crate::model::DragLaw;

    fn held(noise: NoiseAtReset, target: Target, position: Option<f64>) -> Params {
        let p = Params::new(DragLaw::Linear, 1.2, 0.6, 1.5, 0.2).unwrap();
        let s = Schedule::parse(None, position, Some("exp:mean=0.4")).unwrap();
        p.with_reset(target, noise)
            .unwrap()
            .with_schedule(s)
            .unwrap()
    }

    /// Long times: the stationary closed forms of (R3) and (R4).
    #[test]
    fn long_times_give_the_stationary_closed_forms() {
        let targets = [Target::point(0.2), Target::uniform(-0.3, 0.5)];
        for noise in [NoiseAtReset::Kept, NoiseAtReset::Redrawn] {
            for t in targets {
                let p = held(noise, t, None);
                let m = super::super::moments(&p, &[400.0]).unwrap();
                let close = |a: f64, b: f64| (a - b).abs() <= 1e-12 * b.abs().max(1.0);
                assert!(close(m.v_mean[0], linear::v_mean(&p).unwrap()));
                assert!(close(m.v2[0], linear::v2(&p).unwrap()));
                assert!(close(m.v_eta[0], linear::v_eta(&p).unwrap()));
                let d = m.xv[0] - m.x_mean[0] * m.v_mean[0];
                assert!((d / linear::d_eff(&p).unwrap() - 1.0).abs() < 1e-9, "{d}");
                let p = held(noise, t, Some(-0.3));
                let m = super::super::moments(&p, &[400.0]).unwrap();
                let (x1, x2) = linear::position_moments(&p).unwrap();
                assert!(close(m.x_mean[0], x1), "{} {x1}", m.x_mean[0]);
                assert!(close(m.x2[0], x2), "{} {x2}", m.x2[0]);
            }
        }
    }

    /// M → 0 is the plain protocol, at every time: the difference is first
    /// order in r M (here 1.5e-4), bounded by 3 r M.
    #[test]
    fn short_refractory_period_is_the_plain_protocol() {
        let ts = [0.1, 0.7, 2.0, 6.0];
        for pos in [None, Some(0.4)] {
            let plain = Params::new(DragLaw::Linear, 1.2, 0.6, 1.5, 0.2).unwrap();
            let plain = plain
                .with_schedule(Schedule::parse(None, pos, None).unwrap())
                .unwrap();
            let s = Schedule::parse(None, pos, Some("exp:mean=1e-4")).unwrap();
            let p = plain.with_schedule(s).unwrap();
            let (a, b) = (
                super::super::moments(&plain, &ts).unwrap(),
                super::super::moments(&p, &ts).unwrap(),
            );
            for k in 0..ts.len() {
                for (x, y) in [(a.v2[k], b.v2[k]), (a.x2[k], b.x2[k]), (a.xv[k], b.xv[k])] {
                    assert!((x - y).abs() < 4.5e-4 * x.abs().max(1.0), "{x} {y}");
                }
            }
        }
    }
}
