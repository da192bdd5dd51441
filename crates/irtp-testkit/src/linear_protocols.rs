//! Closed forms for linear drag g(v) = v under the modifiers of the
//! resetting rule, from the moment equations of the generator
//! L f = v ∂_x f + (η - v) ∂_v f + λ [f(η → -η) - f] + (reset terms):
//! (a) Poisson resetting (rate r) with position resetting to x_r,
//! (b) an exponential refractory period, (c) periodic resetting.
//! The reset target enters through its moments (m1, m2) = (<v_r>, <v_r²>).
//! By the symmetry η → -η of the flips and of both noise rules, <η> = 0 in
//! every state, so E[v_r η'] = E[x_r η'] = 0 after a reset whether the noise
//! state is kept or re-drawn: the second moments below hold for both.

/// Stationary first and second moments under Poisson resetting with
/// position resetting.
#[derive(Clone, Copy, Debug)]
pub struct PositionMoments {
    pub v: f64,
    pub v2: f64,
    pub x: f64,
    pub x2: f64,
}

/// (a) Stationary moments for Poisson resetting at rate r > 0 to a target
/// of moments (m1, m2), position reset to x_r. The stationary equations
/// d<f>/dt = 0 for f = v, x, vη, v², xη, xv, x² read
/// 0 = -(1 + r)<v> + r m1, 0 = <v> - r(<x> - x_r),
/// 0 = Σ² - (1 + 2λ + r)<vη>, 0 = 2<vη> - (2 + r)<v²> + r m2,
/// 0 = <vη> - (2λ + r)<xη>, 0 = <v²> + <xη> - (1 + r)<xv> + r x_r m1,
/// 0 = 2<xv> - r<x²> + r x_r², solved in that order.
pub fn position_poisson(
    sigma: f64,
    lambda: f64,
    r: f64,
    m: (f64, f64),
    x_r: f64,
) -> PositionMoments {
    let (m1, m2) = m;
    let v = r * m1 / (1.0 + r);
    let x = x_r + v / r;
    let v_eta = sigma * sigma / (1.0 + 2.0 * lambda + r);
    let v2 = (2.0 * v_eta + r * m2) / (2.0 + r);
    let x_eta = v_eta / (2.0 * lambda + r);
    let x_v = (v2 + x_eta + r * x_r * m1) / (1.0 + r);
    let x2 = (2.0 * x_v + r * x_r * x_r) / r;
    PositionMoments { v, v2, x, x2 }
}

/// (b) Stationary (<v>, <v²>) with Poisson resetting at rate r and an
/// exponential refractory period of mean M (rate κ = 1/M). With F the
/// flowing state and R the refractory one (probabilities p_F = κ/(r + κ),
/// p_R = r/(r + κ)) and partial moments <·; F>, <·; R>: in R the velocity
/// is constant, entered at rate r p_F with v = v_r, left at rate κ, so
/// <v; R> = r p_F m1 / κ, <v²; R> = r p_F m2 / κ, <vη; R> = 0; in F
/// 0 = -(1 + r)<v; F> + κ<v; R>,
/// 0 = Σ² p_F - (1 + 2λ + r)<vη; F>,
/// 0 = 2<vη; F> - (2 + r)<v²; F> + κ<v²; R>.
pub fn refractory_exp(sigma: f64, lambda: f64, r: f64, m: (f64, f64), mean: f64) -> (f64, f64) {
    let (m1, m2) = m;
    let kappa = 1.0 / mean;
    let p_f = kappa / (r + kappa);
    let (b1, b2) = (r * p_f * m1 / kappa, r * p_f * m2 / kappa);
    let a1 = kappa * b1 / (1.0 + r);
    let c_f = sigma * sigma * p_f / (1.0 + 2.0 * lambda + r);
    let a2 = (2.0 * c_f + kappa * b2) / (2.0 + r);
    (a1 + b1, a2 + b2)
}

/// (e^{-a τ} - e^{-2 τ}) / (2 - a), continued to τ e^{-2τ} at a = 2.
fn kernel(a: f64, tau: f64) -> f64 {
    if (a - 2.0).abs() < 1e-6 {
        tau * (-2.0 * tau).exp()
    } else {
        ((-a * tau).exp() - (-2.0 * tau).exp()) / (2.0 - a)
    }
}

/// (c) (<v>(t), <v²>(t)) with periodic resetting every T (no Poisson
/// clock), started at v = 0, η = ±Σ. Between resets (r = 0)
/// d<v>/dt = -<v>, d<vη>/dt = Σ² - (1 + 2λ)<vη>, d<v²>/dt = 2<vη> - 2<v²>;
/// at t = kT the jump map sets (<v>, <vη>, <v²>) to (m1, 0, m2). From
/// (m, c, s) at the last reset, after τ: <v> = m e^{-τ},
/// <vη> = c∞ + (c - c∞) e^{-aτ} (a = 1 + 2λ, c∞ = Σ²/a),
/// <v²> = s e^{-2τ} + c∞ (1 - e^{-2τ}) + 2 (c - c∞)(e^{-aτ} - e^{-2τ})/(2 - a).
/// Left-continuous at t = kT (a reset at t acts just after t: the value
/// before the reset, as the samplers record it).
pub fn periodic(sigma: f64, lambda: f64, period: f64, m: (f64, f64), t: f64) -> (f64, f64) {
    let k = ((t / period).ceil() - 1.0).max(0.0);
    let tau = t - k * period;
    let (m0, c0, s0) = if k >= 1.0 {
        (m.0, 0.0, m.1)
    } else {
        (0.0, 0.0, 0.0)
    };
    let a = 1.0 + 2.0 * lambda;
    let c_inf = sigma * sigma / a;
    let v = m0 * (-tau).exp();
    let e2 = (-2.0 * tau).exp();
    let v2 = s0 * e2 + c_inf * (1.0 - e2) + 2.0 * (c0 - c_inf) * kernel(a, tau);
    (v, v2)
}
