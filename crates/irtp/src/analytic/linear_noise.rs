//! Linear drag g = γ v with any finite-state noise ([`NoiseModel`]: levels
//! a_s, generator Q, thermal noise of temperature T) and velocity
//! resetting at rate r ≥ 0 to v_r (noise state and position kept):
//! stationary `<v>`, `<v²>`, the drift velocity of x and D_eff, in closed
//! form up to an N×N solve (docs/equations.md, "Noise kinds", (N3)-(N7)).
//!
//! Derivation: the generator (Eq. (N1)) is
//!
//! ```text
//! L f(x, v, s) = v ∂_x f + (a_s - γv) ∂_v f + T ∂_v² f + Σ_s' Q_ss' [f(s') - f(s)] + r [f(x, v_r, s) - f],
//! ```
//!
//! and stationary means satisfy `<L f>` = 0. With π the stationary law of
//! the noise (a reset keeps s, so it is the noise's own, Eq. (N2)) and the
//! conditional moments m_s = E[v 1{η = s}]:
//!
//! ```text
//! f = v 1{s}:  a_s π_s - γ m_s + Σ_s' m_s' Q_s's + r (<v_r> π_s - m_s) = 0        (N3)
//!              ⇒ [(γ + r) I - Qᵀ] m = (a + r <v_r>) ∘ π,   <v> = Σ m_s = (<a> + r <v_r>)/(γ + r)
//! f = v²:      2 Σ a_s m_s - 2γ <v²> + 2T + r (<v_r²> - <v²>) = 0                   (N4)
//! ```
//!
//! The drift velocity of x is `<v>` (N5). D_eff = ∫_0^∞ C_v(t) dt
//! = `<(v - <v>) φ>` with -L φ = v - `<v>`; φ = α v + β_s solves it with
//! α = 1/(γ + r) and Q β = `<v>` - α (a + r `<v_r>`) (solvable: its
//! π-mean vanishes by (N3)), so
//!
//! ```text
//! D_eff = α Var v + Σ_s β_s (m_s - <v> π_s)                                           (N6)
//! ```
//!
//! (β up to a constant, which drops out as Σ (m_s - `<v>` π_s) = 0).
//! Symmetric telegraph ±Σ at rate λ, γ = 1: m± = ±`<vη>`/(2Σ) + `<v>`/2,
//! β± = ±αΣ/(2λ), and (N3)-(N6) are [`super::linear`]'s
//! `<vη>` = Σ²/(1 + 2λ + r), D_eff = (Var v + `<vη>`/(2λ))/(1 + r).

use crate::error::{Error, Result};
use crate::model::noise::{chain, NoiseModel};
use serde::{Deserialize, Serialize};

/// The stationary moments of linear drag with a noise model and velocity
/// resetting.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct NoiseMoments {
    /// The stationary law π of the noise state.
    pub pi: Vec<f64>,
    /// m_s = E[v 1{η = s}], Eq. (N3).
    pub conditional_mean: Vec<f64>,
    /// `<v>`.
    pub v_mean: f64,
    /// `<v²>`, Eq. (N4).
    pub v2: f64,
    /// The drift velocity lim x(t)/t = `<v>`, Eq. (N5).
    pub drift: f64,
    /// D_eff = lim Var x(t) / (2t), Eq. (N6).
    pub d_eff: f64,
}

/// The problem: drag g = γ v, the noise, reset rate r and the first two
/// moments of the reset velocity.
#[derive(Clone, Debug, PartialEq)]
pub struct LinearNoise {
    gamma: f64,
    noise: NoiseModel,
    rate: f64,
    target: (f64, f64),
}

impl LinearNoise {
    /// γ > 0, r ≥ 0, v_r finite (every value finite); errors name `gamma`,
    /// `rate`, `reset_velocity`.
    pub fn new(gamma: f64, noise: NoiseModel, rate: f64, reset_velocity: f64) -> Result<Self> {
        if !(reset_velocity.is_finite()) {
            return Err(Error::invalid(
                "reset_velocity",
                reset_velocity,
                "a finite number",
            ));
        }
        let v = reset_velocity;
        Self::with_target(gamma, noise, rate, (v, v * v))
    }

    /// A random reset velocity with moments (`<v_r>`, `<v_r²>`) (finite,
    /// `<v_r²>` ≥ `<v_r>`²); otherwise as [`LinearNoise::new`].
    pub fn with_target(
        gamma: f64,
        noise: NoiseModel,
        rate: f64,
        target: (f64, f64),
    ) -> Result<Self> {
        if !(gamma > 0.0 && gamma.is_finite()) {
            return Err(Error::invalid("gamma", gamma, "gamma > 0, finite"));
        }
        if !(rate >= 0.0 && rate.is_finite()) {
            return Err(Error::invalid("rate", rate, "rate >= 0, finite"));
        }
        let (m1, m2) = target;
        if !(m1.is_finite() && m2.is_finite() && m2 >= m1 * m1) {
            return Err(Error::invalid(
                "reset_velocity",
                format!("moments ({m1}, {m2})"),
                "finite moments with <v_r^2> >= <v_r>^2",
            ));
        }
        Ok(LinearNoise {
            gamma,
            noise,
            rate,
            target,
        })
    }

    /// The stationary moments (N3)-(N6), checked: `<v>` from the solve
    /// against its closed form (N3) to 1e-12, Var v ≥ 0 and D_eff ≥ 0 (to
    /// rounding).
    pub fn moments(&self) -> Result<NoiseMoments> {
        let (g, r, t) = (self.gamma, self.rate, self.noise.temperature());
        let (m1, m2) = self.target;
        let a = self.noise.levels();
        let q = self.noise.generator();
        let pi = self.noise.stationary()?;
        let n = a.len();
        let lhs: Vec<Vec<f64>> = (0..n)
            .map(|s| {
                (0..n)
                    .map(|j| if s == j { g + r } else { 0.0 } - q[j][s])
                    .collect()
            })
            .collect();
        let rhs: Vec<f64> = (0..n).map(|s| (a[s] + r * m1) * pi[s]).collect();
        let m = chain::solve(&lhs, &rhs, "linear-drag noise moments")?;
        // <v> in closed form (N3); the solve's Σ m_s is checked against it,
        // and the Poisson right side below then has π-mean 0 to rounding.
        let mean_level: f64 = pi.iter().zip(&a).map(|(p, x)| p * x).sum();
        let v_mean = (mean_level + r * m1) / (g + r);
        let scale = a.iter().fold(r * m1.abs(), |s, x| s.max(x.abs())) / (g + r);
        check_mean(m.iter().sum(), v_mean, scale)?;
        let am: f64 = a.iter().zip(&m).map(|(x, y)| x * y).sum();
        let v2 = (2.0 * am + 2.0 * t + r * m2) / (2.0 * g + r);
        let alpha = 1.0 / (g + r);
        let b: Vec<f64> = a.iter().map(|x| v_mean - alpha * (x + r * m1)).collect();
        let beta = chain::poisson(&q, &pi, &b)?;
        let var = v2 - v_mean * v_mean;
        let cross: f64 = (0..n).map(|s| beta[s] * (m[s] - v_mean * pi[s])).sum();
        let d_eff = alpha * var + cross;
        let scale = v2.abs() * alpha + cross.abs();
        if !(var >= -1e-12 * v2.abs() && d_eff >= -1e-12 * scale) {
            return Err(Error::Numerical {
                method: "linear-drag noise moments",
                reason: format!("Var v = {var:e} or D_eff = {d_eff:e} is negative"),
            });
        }
        Ok(NoiseMoments {
            pi,
            conditional_mean: m,
            v_mean,
            v2,
            drift: v_mean,
            d_eff,
        })
    }
}

/// `<v>` = Σ m_s from the solve against (`<a>` + r `<v_r>`)/(γ + r), to 1e-12
/// of the velocity scale max(|a_s|, r |`<v_r>`|)/(γ + r).
fn check_mean(solved: f64, closed: f64, scale: f64) -> Result<()> {
    if (solved - closed).abs() <= 1e-12 * scale.max(closed.abs()).max(f64::MIN_POSITIVE) {
        return Ok(());
    }
    Err(Error::Numerical {
        method: "linear-drag noise moments",
        reason: format!("<v> = {solved} from the solve, {closed} in closed form"),
    })
}
