//! Shared test models (in the spirit of diffsol's `test_models`): the paper's
//! parameter sets and Newtonian (linear-drag) cases with known answers.
//!
//! The paper is Howlader, Mondal & Das, "Velocity resetting of inertial
//! run-and-tumble particles in non-Newtonian media". Its two media are
//! g(v) = tan v with Sigma = 3 (shear-thickening) and g(v) = tanh v with
//! Sigma = 0.6 (shear-thinning); every figure resets to v_r = 0. Equation
//! numbers are the printed ones (see docs/equations.md).
//!
//! Each set comes as `(Params, description)` or, for linear drag,
//! `(Params, LinearAnswer)` with the closed-form stationary moments and D_eff,
//! written out here independently of `irtp::analytic::linear`.

use irtp::mfpt::Problem;
use irtp::{DragLaw, Params};

/// Sigma of the shear-thickening medium, g = tan (Figs. 1a, 2, 5a, 6a, 7a-b).
pub const TAN_SIGMA: f64 = 3.0;
/// Sigma of the shear-thinning medium, g = tanh (Figs. 1b, 3, 5b, 6b, 7c-d).
pub const TANH_SIGMA: f64 = 0.6;
/// Initial velocity v_0 of every panel of Fig. 7.
pub const FIG7_V0: f64 = -0.249;
/// Target velocity v_t of Fig. 7(b) and 7(d).
pub const FIG7_VT: f64 = 0.5;

/// The paper's Sigma for a drag law (1 for the linear reference and any
/// other law the paper does not use).
pub fn paper_sigma(drag: DragLaw) -> f64 {
    match drag {
        DragLaw::Tan => TAN_SIGMA,
        DragLaw::Tanh => TANH_SIGMA,
        _ => 1.0,
    }
}

/// The paper's medium for `drag` with flip rate `lambda`, reset rate `r` and
/// reset velocity `vr`.
pub fn medium(drag: DragLaw, lambda: f64, r: f64, vr: f64) -> Params {
    Params::new(drag.clone(), paper_sigma(drag), lambda, r, vr).unwrap()
}

/// Shear-thickening medium: tan drag, Sigma = 3, reset to v_r = 0.
pub fn tan(lambda: f64, r: f64) -> Params {
    medium(DragLaw::Tan, lambda, r, 0.0)
}

/// Shear-thinning medium: tanh drag, Sigma = 0.6, reset to v_r = 0.
pub fn tanh(lambda: f64, r: f64) -> Params {
    medium(DragLaw::Tanh, lambda, r, 0.0)
}

/// Newtonian drag g(v) = v with any Sigma (closed forms in [`linear_answer`]).
pub fn linear(sigma: f64, lambda: f64, r: f64, vr: f64) -> Params {
    Params::new(DragLaw::Linear, sigma, lambda, r, vr).unwrap()
}

/// Fig. 7 first-passage problem: the paper's medium for `drag`, v_r = 0,
/// start v_0 = -0.249, target `vt`.
pub fn fig7(drag: DragLaw, lambda: f64, r: f64, vt: f64) -> Problem {
    Problem::new(medium(drag, lambda, r, 0.0), FIG7_V0, vt).unwrap()
}

/// Fig. 1: <v²>(t) for lambda = 0.5, r ∈ {0, 0.5, 2, 10}, both media.
pub fn fig1() -> Vec<(Params, String)> {
    both_media(0.5, &[0.0, 0.5, 2.0, 10.0], |m, r| {
        format!("Fig. 1 {m}, r = {r}: <v²>(t) relaxes to <v²>_ss of Eq. (33), smaller for larger r")
    })
}

/// Fig. 2: tan, lambda ∈ {0.9, 7, 15, 25} (r = 0 regimes (i)-(iv) of
/// Eq. (34)), r ∈ {0, 1, 5, 15, 30}.
pub fn fig2() -> Vec<(Params, String)> {
    let panels = [
        (0.9, "a", "i"),
        (7.0, "b", "ii"),
        (15.0, "c", "iii"),
        (25.0, "d", "iv"),
    ];
    let mut out = Vec::new();
    for (lambda, panel, regime) in panels {
        for r in [0.0, 1.0, 5.0, 15.0, 30.0] {
            let what = format!("Fig. 2({panel}) tan, lambda = {lambda}, r = {r}: P_s^r(v); r = 0 is regime ({regime}) of Eq. (34)");
            out.push((tan(lambda, r), what));
        }
    }
    out
}

/// Fig. 3: tanh, lambda ∈ {0.5, 0.85, 1.2, 3} (r = 0 regimes (a)-(d) of
/// Eq. (35)), r ∈ {0, 0.2, 0.5, 2, 5}.
pub fn fig3() -> Vec<(Params, String)> {
    let panels = [(0.5, "a"), (0.85, "b"), (1.2, "c"), (3.0, "d")];
    let mut out = Vec::new();
    for (lambda, panel) in panels {
        for r in [0.0, 0.2, 0.5, 2.0, 5.0] {
            let what = format!("Fig. 3({panel}) tanh, lambda = {lambda}, r = {r}: P_s^r(v); r = 0 is regime ({panel}) of Eq. (35)");
            out.push((tanh(lambda, r), what));
        }
    }
    out
}

/// Fig. 5: <x²>(t) for lambda = 0.5, r ∈ {0, 0.1, 1, 10}, both media.
pub fn fig5() -> Vec<(Params, String)> {
    both_media(0.5, &[0.0, 0.1, 1.0, 10.0], |m, r| {
        format!("Fig. 5 {m}, r = {r}: <x²> ballistic early, 2 D_eff t late (Eq. (36))")
    })
}

/// Fig. 6: D_eff(r) for lambda ∈ {0.5, 1, 5} at the simulated rates
/// r ∈ {0.01, 0.1, 1, 10, 30, 100}, both media.
pub fn fig6() -> Vec<(Params, String)> {
    let mut out = Vec::new();
    for lambda in [0.5, 1.0, 5.0] {
        out.extend(both_media(lambda, &[0.01, 0.1, 1.0, 10.0, 30.0, 100.0], |m, r| {
            format!("Fig. 6 {m}, lambda = {lambda}, r = {r}: D_eff by the Eq. (36) fit, ~ r^-2 at large r")
        }));
    }
    out
}

/// Fig. 7: MFPT from v_0 = -0.249 (v_r = 0). Panels (a)/(c) scan v_t at
/// r = 2 (tan) / 0.2 (tanh), panels (b)/(d) scan r at v_t = 0.5; the
/// problem is given at the panel-(a)/(c) rate and v_t = 0.5.
pub fn fig7_cases() -> Vec<(Problem, String)> {
    let mut out = Vec::new();
    for lambda in [0.5, 1.0, 5.0, 50.0] {
        let what = format!("Fig. 7(a, b) tan, lambda = {lambda}: tau(v_t) at r = 2; tau(r) at v_t = 0.5 has an optimum for small lambda");
        out.push((fig7(DragLaw::Tan, lambda, 2.0, FIG7_VT), what));
    }
    for lambda in [0.5, 1.0, 2.0, 5.0] {
        let what = format!("Fig. 7(c, d) tanh, lambda = {lambda}: tau(v_t) at r = 0.2; tau(r) at v_t = 0.5 increases with r");
        out.push((fig7(DragLaw::Tanh, lambda, 0.2, FIG7_VT), what));
    }
    out
}

fn both_media(
    lambda: f64,
    rates: &[f64],
    what: impl Fn(&str, f64) -> String,
) -> Vec<(Params, String)> {
    let mut out = Vec::new();
    for (drag, name) in [(DragLaw::Tan, "(a) tan"), (DragLaw::Tanh, "(b) tanh")] {
        for &r in rates {
            out.push((medium(drag.clone(), lambda, r, 0.0), what(name, r)));
        }
    }
    out
}

/// Exact stationary answers for linear drag g(v) = v.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LinearAnswer {
    /// <v> = r v_r / (1 + r).
    pub v_mean: f64,
    /// <v²> = (2 <v eta> + r v_r²) / (2 + r), <v eta> = Sigma² / (1 + 2 lambda + r).
    pub v2: f64,
    /// D_eff = (Var v + <v eta>/(2 lambda)) / (1 + r) (infinite for lambda = 0).
    pub d_eff: f64,
}

/// Closed forms for a linear-drag parameter set (from the generator: the
/// stationary means of L v, L (v eta), L v² vanish; D_eff by integrating
/// E[v(t) | v_0, eta_0]).
pub fn linear_answer(p: &Params) -> LinearAnswer {
    assert_eq!(p.drag(), DragLaw::Linear, "closed forms need linear drag");
    let (s, l, r, vr) = (p.sigma(), p.lambda(), p.rate(), p.reset_velocity());
    let v_eta = s * s / (1.0 + 2.0 * l + r);
    let v_mean = r * vr / (1.0 + r);
    let v2 = (2.0 * v_eta + r * vr * vr) / (2.0 + r);
    let d_eff = if l > 0.0 {
        (v2 - v_mean * v_mean + v_eta / (2.0 * l)) / (1.0 + r)
    } else {
        f64::INFINITY
    };
    LinearAnswer { v_mean, v2, d_eff }
}

/// Linear-drag cases (sigma, lambda, r, v_r): singular and bounded edges,
/// r from 0 to 10, v_r ≠ 0.
pub const LINEAR_CASES: [(f64, f64, f64, f64); 7] = [
    (1.0, 0.3, 0.0, 0.0), // singular edges, a = -0.7
    (1.0, 0.3, 0.5, 0.0), // still singular, a = -0.2
    (1.0, 0.3, 2.0, 0.0),
    (1.0, 0.3, 10.0, 0.0),
    (2.0, 1.5, 0.0, 0.0),
    (1.0, 0.3, 2.0, 0.3),  // v_r != 0
    (1.5, 2.0, 1.0, -0.2), // v_r != 0, bounded density
];

/// [`LINEAR_CASES`] with their known answers.
pub fn linear_cases() -> Vec<(Params, LinearAnswer)> {
    LINEAR_CASES
        .iter()
        .map(|&(s, l, r, vr)| {
            let p = linear(s, l, r, vr);
            (p.clone(), linear_answer(&p))
        })
        .collect()
}

/// `p` with the protocol modifiers of the flags `--reset-period`,
/// `--reset-position`, `--refractory` (validated).
pub fn with_schedule(
    p: Params,
    period: Option<f64>,
    position: Option<f64>,
    refractory: Option<&str>,
) -> Params {
    let s = irtp::model::reset::Schedule::parse(period, position, refractory).unwrap();
    p.with_schedule(s).unwrap()
}
