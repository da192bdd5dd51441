//! Newtonian drag g(v) = v: exact stationary moments and D_eff for any r ≥ 0.
//!
//! Derived from the generator of the simulated process by setting the
//! stationary mean `<L f>` of L f to zero for f = v, vη, v²:
//!
//! ```text
//! L f(v, η) = (η - v) ∂_v f + λ [f(v, -η) - f(v, η)] + r [f(v_r, η) - f(v, η)]
//! f = v:   <η> - <v> + r (v_r - <v>) = 0, and <η> = 0   ⇒ <v> = r v_r / (1 + r)
//! f = vη:  Σ² - (1 + 2λ + r) <vη> + r v_r <η> = 0        ⇒ <vη> = Σ² / (1 + 2λ + r)
//! f = v²:  2<vη> - 2<v²> + r (v_r² - <v²>) = 0           ⇒ <v²> = (2<vη> + r v_r²) / (2 + r)
//! ```
//!
//! For D_eff = ∫_0^∞ [`<v(0) v(t)>` - `<v>`²] dt use
//!
//! ```text
//! E[v(t) | v_0, η_0] = <v> + (v_0 - <v>) e^{-(1+r)t} + η_0 (e^{-2λt} - e^{-(1+r)t}) / (1 + r - 2λ),
//! ```
//!
//! which integrates to D_eff = (Var v + `<vη>`/(2λ)) / (1 + r).
//! Checks: r = 0 gives `<v²>` = Σ²/(1+2λ) and D_eff = Σ²/(2λ) (free telegraph
//! noise integrated once); r → ∞ gives D_eff ≈ Σ²/(2λ r²), the paper's r⁻².
//!
//! With the noise state re-drawn at a reset (L gets r [½ f(v_r, Σ) +
//! ½ f(v_r, -Σ) - f(v, η)] instead), f = v and f = v² are unchanged
//! (their reset values do not depend on η), and so is f = vη: its reset
//! value averages to 0, and the kept rule's r v_r <η> vanished anyway. So
//! `<v>`, `<vη>` and `<v²>` are those above, and the stationary density
//! itself is the same (the reset influx of each state is r/2 either way).
//! What changes is the memory of η: L η = -(2λ + r) η, so
//! E[η(t) | η_0] = η_0 e^{-κt} with κ = 2λ + r (κ = 2λ when kept), and
//!
//! ```text
//! E[v(t) | v_0, η_0] = <v> + (v_0 - <v>) e^{-(1+r)t} + η_0 (e^{-κt} - e^{-(1+r)t}) / (1 + r - κ),
//! D_eff = (Var v + <vη>/κ) / (1 + r).
//! ```

use crate::error::{Error, Result};
use crate::model::reset::Solver;
use crate::model::reset::{NoiseAtReset, Refractory};
use crate::model::Reset;
use crate::model::{Drag, Params};

pub(super) fn require_linear(p: &Params) -> Result<()> {
    p.require(Solver::ClosedForm)?;
    if !p.drag().newtonian() {
        return Err(Error::invalid(
            "drag",
            p.drag(),
            "linear (closed forms exist only for Newtonian drag)",
        ));
    }
    Ok(())
}

/// κ, the decay rate of the noise memory E[η(t) | η_0] = η_0 e^{-κt}: 2λ
/// when a reset keeps η, 2λ + r when it re-draws it.
pub fn eta_decay(p: &Params) -> f64 {
    match p.reset().noise() {
        NoiseAtReset::Kept => 2.0 * p.lambda(),
        NoiseAtReset::Redrawn => 2.0 * p.lambda() + p.rate(),
    }
}

/// The refractory factors: (M, m_C, m_R) with M the mean refractory time
/// (0 without a refractory period), m_C = 1/(1 + rM) and m_R = rM/(1 + rM)
/// the stationary probabilities of the flowing and the held phase
/// (docs/equations.md, entry (R3)).
fn phases(p: &Params) -> Result<(f64, f64, f64)> {
    if let Some(t) = p.schedule().periodic {
        return Err(Error::invalid(
            "reset_period",
            t.period,
            "none for the stationary closed forms (periodic resetting has no stationary state; the time-dependent linear moments run it)",
        ));
    }
    let m = match p.schedule().refractory {
        None => 0.0,
        Some(Refractory::Exp { mean }) => mean,
        Some(r @ Refractory::Fixed { .. }) => {
            return Err(Error::invalid(
                "refractory",
                r.spec(),
                "exp:mean=M for the linear closed forms",
            ))
        }
    };
    let rm = p.rate() * m;
    Ok((m, 1.0 / (1.0 + rm), rm / (1.0 + rm)))
}

/// Stationary `<v η>`: Σ² m_C / (1 + 2λ + r) (the held phase contributes
/// `<u>` `<η>`_R = 0).
pub fn v_eta(p: &Params) -> Result<f64> {
    require_linear(p)?;
    let (_, mc, _) = phases(p)?;
    Ok(p.sigma() * p.sigma() * mc / (1.0 + 2.0 * p.lambda() + p.rate()))
}

/// Stationary `<v>`: the flowing part a = r m_C `<v_r>` / (1 + r) plus the
/// held part m_R `<v_r>`, Eq. (R3).
pub fn v_mean(p: &Params) -> Result<f64> {
    require_linear(p)?;
    let (_, mc, mr) = phases(p)?;
    let (m1, _) = p.reset().target().moments();
    Ok(p.rate() * mc * m1 / (1.0 + p.rate()) + mr * m1)
}

/// Stationary `<v²>`: (2 `<vη>` + r m_C `<v_r²>`) / (2 + r) + m_R `<v_r²>`,
/// Eq. (R3).
pub fn v2(p: &Params) -> Result<f64> {
    let c = v_eta(p)?;
    let (_, mc, mr) = phases(p)?;
    let (_, m2) = p.reset().target().moments();
    Ok((2.0 * c + p.rate() * mc * m2) / (2.0 + p.rate()) + mr * m2)
}

/// Effective diffusion coefficient D_eff = lim `<(x - <x>)²>/(2t)` (needs
/// λ > 0), from the linear solution of the Poisson equation of the
/// generator, Eq. (R3); without a refractory period
/// (Var v + `<vη>`/κ) / (1 + r).
pub fn d_eff(p: &Params) -> Result<f64> {
    if !(p.lambda() > 0.0) {
        return Err(Error::invalid(
            "lambda",
            p.lambda(),
            "lambda > 0 (with lambda = 0 the motion is ballistic)",
        ));
    }
    if let Some(x) = p.schedule().position {
        return Err(Error::invalid(
            "reset_position",
            x.x,
            "none for D_eff (with position resetting the position does not diffuse: see the stationary <x>, <x^2>)",
        ));
    }
    let (l, r) = (p.lambda(), p.rate());
    let (m, mc, mr) = phases(p)?;
    let (m1, m2) = p.reset().target().moments();
    let vm = v_mean(p)?;
    let c = v_eta(p)?;
    let a = r * mc * m1 / (1.0 + r);
    let b = (2.0 * c + r * mc * m2) / (2.0 + r);
    let alpha = 1.0 / (1.0 + r);
    let kept = match p.reset().noise() {
        NoiseAtReset::Kept => 1.0,
        NoiseAtReset::Redrawn => 0.0,
    };
    let beta = alpha / (2.0 * l + r - r * kept / (1.0 + 2.0 * l * m));
    Ok(
        alpha * (b - vm * a) + beta * c + (alpha + m) * mr * (m2 - vm * m1)
            - vm * m * mr * (m1 - vm),
    )
}

/// Stationary (`<x>`, `<x²>`) under position resetting to x_r (needs
/// r > 0), with or without an exponential refractory period, Eq. (R4).
pub fn position_moments(p: &Params) -> Result<(f64, f64)> {
    require_linear(p)?;
    let xr = match p.schedule().position {
        Some(x) => x.x,
        None => {
            return Err(Error::invalid(
                "reset_position",
                "none",
                "a reset position (without it the position has no stationary law)",
            ))
        }
    };
    let (l, r) = (p.lambda(), p.rate());
    if !(r > 0.0) {
        return Err(Error::invalid(
            "rate",
            r,
            "rate > 0 (without resets the position has no stationary law)",
        ));
    }
    let (m, mc, mr) = phases(p)?;
    let (m1, m2) = p.reset().target().moments();
    let c = v_eta(p)?;
    let a = r * mc * m1 / (1.0 + r);
    let b = (2.0 * c + r * mc * m2) / (2.0 + r);
    // Held phase (x moves at u): κ x_R = m_R <u> + r x_r m_C, etc.
    let kx_r = mr * m1 + r * xr * mc;
    let kxu_r = mr * m2 + r * xr * m1 * mc;
    let x_c = (a + kx_r) / r;
    let xe_c = c / (2.0 * l + r);
    let xv_c = (b + xe_c + kxu_r) / (1.0 + r);
    let kx2_r = 2.0 * m * kxu_r + r * xr * xr * mc;
    let x2_c = (2.0 * xv_c + kx2_r) / r;
    Ok((x_c + m * kx_r, x2_c + m * kx2_r))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::DragLaw;

    fn lin(s: f64, l: f64, r: f64, vr: f64) -> Params {
        Params::new(DragLaw::Linear, s, l, r, vr).unwrap()
    }

    #[test]
    fn limits() {
        let p = lin(2.0, 0.7, 0.0, 0.0);
        assert!((v2(&p).unwrap() - 4.0 / 2.4).abs() < 1e-15);
        assert!((d_eff(&p).unwrap() - 4.0 / 1.4).abs() < 1e-14);
        let big = lin(2.0, 0.7, 1e6, 0.0);
        let ratio = d_eff(&big).unwrap() / (4.0 / (1.4 * 1e12));
        assert!((ratio - 1.0).abs() < 1e-5, "{ratio}");
    }

    #[test]
    fn rejects_other_drags() {
        let p = Params::new(DragLaw::Tan, 3.0, 1.0, 1.0, 0.0).unwrap();
        assert!(v2(&p).is_err());
    }
}
