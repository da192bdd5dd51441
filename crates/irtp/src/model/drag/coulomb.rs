//! g(v) = mu sign(v) + gamma v: Coulomb (solid, dry) friction plus viscous
//! drag, the solid-friction setting of Antonov et al. Written
//! `coulomb:mu=MU,gamma=GAMMA` (gamma defaults to 1); mu = 0 is the linear
//! law gamma v.
//!
//! The force jumps by 2 mu at v = 0 (g(0) = 0, g(0±) = ±mu), so noise of
//! amplitude Sigma <= mu cannot overcome the static friction: a particle
//! that reaches v = 0 sticks there and the stationary state is a point mass
//! at v = 0 (D_eff = 0). [`Drag::static_friction`] reports mu, and
//! [`crate::model::Params::new`] refuses Sigma <= mu for every method with
//! that reason. For Sigma > mu the drift of each noise state keeps its sign
//! across v = 0 and the particle crosses it; the flow is linear on either
//! side, so everything is in closed form. What each method does with the
//! jump:
//! - The exact flow ([`ClosedFlow`]) crosses v = 0 at its exact time: for
//!   s = +Sigma and v < 0, dv/dt = Sigma + mu - gamma v relaxes towards the
//!   virtual fixed point w* = (Sigma + mu)/gamma, beyond 0 towards
//!   v* = (Sigma - mu)/gamma. The flow potential is ln(v* - v) for v >= 0 and
//!   ln(w* - v) + ln(v*/w*) for v < 0 (continuous, falling at rate gamma),
//!   the deficit integrals are elementary on each side.
//! - The exact sampler's tables in the potential
//!   ([`super::PotentialTable`]) make the potential's kink at v = 0 a cell
//!   boundary, so each piece is smooth (the fallback, the closed-form
//!   velocity with the deficit table in v, has a piece boundary at v = 0).
//! - The Fokker-Planck mesh evaluates the upwind drift at a node v = 0 on
//!   the upwind side, Sigma + mu for both states; the stationary flux is
//!   continuous there and the density jumps (by (Sigma + mu)/(Sigma - mu)
//!   for each state, the sum stays even).
//! - The r = 0 density is P ∝ (Sigma² - g²)^(lambda/gamma - 1) (closed form
//!   of the general quadrature), with a cusp at v = 0: d ln P / dv jumps
//!   from -x to x, x = 2 mu (gamma - lambda) / (Sigma² - mu²). Its regime
//!   labels the centre by the sign of g'(0±) - lambda = gamma - lambda
//!   (a cusp minimum for lambda < gamma, a maximum for lambda > gamma,
//!   uniform at lambda = gamma): [`Drag::derivative`] is gamma everywhere,
//!   the regular part of g' (the jump is [`Drag::static_friction`]).
//! - The Euler scheme's step limit is the steepest secant to the edge,
//!   gamma + 2 mu / v_u (just left of v = 0), finite.

use super::closed::{Canonical, ClosedFlow, ClosedForm, InverseGuide, Solve};
use super::spec::{self, Key, ParamLaw};
use super::{Drag, FlowMap};
use crate::error::Result;

/// g(v) = mu sign(v) + gamma v, mu >= 0, gamma > 0, unbounded:
/// Sigma > mu, v_u = (Sigma - mu)/gamma.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Coulomb {
    mu: f64,
    gamma: f64,
}

impl Coulomb {
    /// The law with static friction `mu` (finite, >= 0) and viscosity
    /// `gamma` (finite, > 0; at gamma = 0 the velocity is unbounded).
    pub fn new(mu: f64, gamma: f64) -> Result<Self> {
        Ok(Coulomb {
            mu: spec::non_negative::<Coulomb>("mu", mu)?,
            gamma: spec::positive::<Coulomb>("gamma", gamma)?,
        })
    }
    /// The Coulomb friction mu.
    pub fn mu(&self) -> f64 {
        self.mu
    }
    /// The viscosity gamma.
    pub fn gamma(&self) -> f64 {
        self.gamma
    }

    /// The deficit integrals (I_1, I_2) of [`Drag::flow_deficits`] in the
    /// canonical frame (s = a > mu, v* = (a - mu)/gamma) on a segment that
    /// does not cross v = 0: on v >= 0 the integrand is (v* - v)^k / (gamma
    /// (v* - v)); on v <= 0 it is (y - m)^k / (gamma y), y = w* - v,
    /// m = 2 mu / gamma, integrated in closed form.
    fn deficits_one_side(&self, vs: f64, va: f64, vb: f64) -> (f64, f64) {
        let g = self.gamma;
        let d = vb - va;
        if va >= 0.0 && vb >= 0.0 {
            let (ua, ub) = (vs - va, vs - vb);
            return (d / g, 0.5 * d * (ua + ub) / g);
        }
        let m = 2.0 * self.mu / g;
        let ws = vs + m;
        let (ya, yb) = (ws - va, ws - vb);
        let l = (d / yb).ln_1p();
        (
            (d - m * l) / g,
            (0.5 * (ya + yb) * d - 2.0 * m * d + m * m * l) / g,
        )
    }
}

impl ParamLaw for Coulomb {
    const KEYS: &'static [Key] = &[
        Key {
            name: "mu",
            default: None,
            meaning: "Coulomb (static) friction mu >= 0, finite; needs sigma > mu",
        },
        Key {
            name: "gamma",
            default: Some(1.0),
            meaning: "viscosity gamma > 0, finite (at gamma = 0 the velocity is unbounded)",
        },
    ];
    fn from_values(values: &[f64]) -> Result<Self> {
        Coulomb::new(values[0], values[1])
    }
    fn values(&self) -> Vec<f64> {
        vec![self.mu, self.gamma]
    }
    fn example() -> Self {
        Coulomb {
            mu: 0.5,
            gamma: 1.0,
        }
    }
}

impl Drag for Coulomb {
    type Flow = ClosedFlow<Coulomb>;

    fn name(&self) -> &'static str {
        "coulomb"
    }
    /// mu sign(v) + gamma v, with g(0) = 0 (odd).
    #[inline]
    fn force(&self, v: f64) -> f64 {
        if v == 0.0 {
            self.gamma * v
        } else {
            self.mu.copysign(v) + self.gamma * v
        }
    }
    /// gamma: the regular part of g' (the jump 2 mu at v = 0 is
    /// [`Drag::static_friction`]).
    #[inline]
    fn derivative(&self, _v: f64) -> f64 {
        self.gamma
    }
    fn flow(&self, s: f64) -> ClosedFlow<Coulomb> {
        ClosedFlow::new(*self, s)
    }
    fn description(&self) -> &'static str {
        "Coulomb plus viscous friction, g = mu sign(v) + gamma v: needs sigma > mu"
    }
    fn static_friction(&self) -> f64 {
        self.mu
    }
    /// (|f| - mu)/gamma sign f for |f| > mu; 0 for |f| <= mu (the particle
    /// rests: every force up to mu is balanced at v = 0).
    #[inline]
    fn inverse(&self, f: f64) -> f64 {
        let a = f.abs();
        if a > self.mu {
            ((a - self.mu) / self.gamma).copysign(f)
        } else if a <= self.mu {
            0.0f64.copysign(f)
        } else {
            f64::NAN
        }
    }
    fn max_derivative(&self, _sigma: f64) -> f64 {
        self.gamma
    }
    /// The secant (Sigma - g(v))/(v_u - v) is gamma on v >= 0 and
    /// gamma + 2 mu/(v_u - v) on v < 0: its supremum is gamma + 2 mu/v_u,
    /// approached just left of v = 0.
    fn euler_slope(&self, sigma: f64) -> f64 {
        self.gamma + 2.0 * self.mu / self.inverse(sigma)
    }
    /// s - g(v* - u) in the canonical frame (s > mu): gamma u where
    /// v = v* - u > 0 (no cancellation as u → 0), gamma u + 2 mu where
    /// v < 0; at v = 0 itself its limit from v*'s side, gamma v* = s - mu
    /// (so that the edge drift is continuous on 0 <= x <= v_u and the r = 0
    /// density at v = 0 is its limit). The plain difference where |s| <= mu.
    #[inline]
    fn drift_at_distance(&self, s: f64, u: f64) -> f64 {
        let a = s.abs();
        if !(a > self.mu) {
            return s - self.force(self.inverse(s) - u);
        }
        let sg = if s < 0.0 { -1.0 } else { 1.0 };
        let (uc, vs) = (sg * u, (a - self.mu) / self.gamma);
        let canonical = if uc <= vs {
            self.gamma * uc
        } else {
            self.gamma * uc + 2.0 * self.mu
        };
        sg * canonical
    }
    fn flow_time(&self, s: f64, va: f64, vb: f64) -> f64 {
        self.flow(s).time(va, vb)
    }
    fn flow_velocity(&self, s: f64, v0: f64, t: f64) -> f64 {
        self.flow(s).velocity(v0, t)
    }
    /// In closed form on each side of v = 0 (a segment crossing it is
    /// split there); s < 0 by the reflection I_k(s, va, vb) =
    /// (-1)^k I_k(-s, -va, -vb).
    fn flow_deficits(&self, s: f64, va: f64, vb: f64) -> (f64, f64) {
        let a = s.abs();
        if !(a > self.mu) {
            return super::quadrature_deficits(self, s, va, vb);
        }
        let sg = if s < 0.0 { -1.0 } else { 1.0 };
        let (va, vb, vs) = (sg * va, sg * vb, (a - self.mu) / self.gamma);
        let (i1, i2) = if (va < 0.0 && vb > 0.0) || (va > 0.0 && vb < 0.0) {
            let (p, q) = (
                self.deficits_one_side(vs, va, 0.0),
                self.deficits_one_side(vs, 0.0, vb),
            );
            (p.0 + q.0, p.1 + q.1)
        } else {
            self.deficits_one_side(vs, va, vb)
        };
        (sg * i1, i2)
    }
}

impl Coulomb {
    /// m = 2 mu / gamma: the distance from v* to the virtual fixed point
    /// w* = v* + m of the flow on v < 0 (canonical frame).
    #[inline]
    fn offset(&self) -> f64 {
        2.0 * self.mu / self.gamma
    }
}

impl ClosedForm for Coulomb {
    fn fixed_point_rate(&self, _s: f64) -> f64 {
        self.gamma
    }
    /// ln(ua/ub)/gamma on v >= 0, ln((ua + m)/(ub + m))/gamma on v <= 0,
    /// the sum of the two pieces across v = 0 (ua > v* > ub).
    #[inline]
    fn time_canonical(&self, c: &Canonical, ua: f64, ub: f64, d: f64) -> f64 {
        let (vs, m) = (c.vs, self.offset());
        let t = if ua <= vs {
            (d / ub).ln_1p()
        } else if ub >= vs {
            (d / (ub + m)).ln_1p()
        } else {
            ((ua - vs) / (vs + m)).ln_1p() + ((vs - ub) / ub).ln_1p()
        };
        t / self.gamma
    }
    /// Φ = ln|u| for u <= v* (v >= 0), ln v* + ln(1 + (u - v*)/(v* + m))
    /// beyond (v < 0).
    #[inline]
    fn potential_canonical(&self, c: &Canonical, u: f64) -> f64 {
        if u <= c.vs {
            u.abs().ln()
        } else {
            c.vs.ln() + ((u - c.vs) / (c.vs + self.offset())).ln_1p()
        }
    }
    fn potential_slope(&self, c: &Canonical, u: f64) -> f64 {
        if u <= c.vs {
            1.0 / u
        } else {
            1.0 / (u + self.offset())
        }
    }
    fn small_u_coefficient(&self, _c: &Canonical) -> f64 {
        0.0
    }
    /// Linear relaxation on each side: from v0 < 0 towards w* = v* + m until
    /// v = 0 at t0 = ln(1 - v0/w*)/gamma, then towards v*.
    fn velocity_canonical(&self, c: &Canonical, q: &Solve, _guide: Option<&InverseGuide>) -> f64 {
        let g = self.gamma;
        let relax = |v0: f64, target: f64, t: f64| {
            let kt = g * t;
            if kt < 1.0 {
                v0 - (target - v0) * (-kt).exp_m1()
            } else {
                target - (target - v0) * (-kt).exp()
            }
        };
        if q.v0 >= 0.0 {
            return relax(q.v0, c.vs, q.t);
        }
        let ws = c.vs + self.offset();
        let t0 = (-q.v0 / ws).ln_1p() / g;
        if q.t < t0 {
            relax(q.v0, ws, q.t).min(0.0)
        } else {
            relax(0.0, c.vs, q.t - t0)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::drag::quadrature_deficits;

    fn law(mu: f64) -> Coulomb {
        Coulomb::new(mu, 1.3).unwrap()
    }

    #[test]
    fn force_inverse_and_secant() {
        let d = law(0.5);
        assert_eq!(d.force(0.0), 0.0);
        assert_eq!(d.force(-0.2), -0.5 - 1.3 * 0.2);
        for f in [-4.0, -0.7, 0.6, 3.0] {
            assert!((d.force(d.inverse(f)) - f).abs() < 1e-14);
        }
        assert_eq!(d.inverse(0.3), 0.0);
        let sigma = 2.0;
        let vu = d.inverse(sigma);
        let m = d.euler_slope(sigma);
        let mut best = 0.0f64;
        for i in 0..100_000 {
            let v = -vu + 2.0 * vu * i as f64 / 100_000.0;
            best = best.max((sigma - d.force(v)) / (vu - v));
        }
        assert!(m >= best && m <= best * (1.0 + 1e-4), "{m} vs {best}");
    }

    /// The closed-form flow crosses v = 0 at its exact time: time and
    /// velocity invert each other, the potential falls at rate gamma, the
    /// deficits equal the quadrature of their integrands split at 0.
    #[test]
    fn flow_is_exact_across_zero() {
        let d = law(0.5);
        for s in [2.0, -2.0] {
            let f = d.flow(s);
            let vu = d.inverse(2.0);
            for (va, vb) in [
                (-0.9 * vu, 0.6 * vu),
                (-0.5 * vu, -0.1 * vu),
                (0.1, 0.9 * vu),
            ] {
                let (va, vb) = if s > 0.0 { (va, vb) } else { (-va, -vb) };
                let t = f.time(va, vb);
                assert!((f.velocity(va, t) - vb).abs() < 1e-13, "s={s} {va}->{vb}");
                let dphi = (f.potential(va) - f.potential(vb)) / f.rate();
                assert!((dphi - t).abs() < 1e-13 * t.max(1.0));
                let (i1, i2) = d.flow_deficits(s, va, vb);
                let mid = if va * vb < 0.0 { 0.0 } else { 0.5 * (va + vb) };
                let (p, q) = (
                    quadrature_deficits(&d, s, va, mid),
                    quadrature_deficits(&d, s, mid, vb),
                );
                assert!(
                    (i1 - p.0 - q.0).abs() < 1e-12,
                    "I1 s={s}: {i1} vs {}",
                    p.0 + q.0
                );
                assert!(
                    (i2 - p.1 - q.1).abs() < 1e-12,
                    "I2 s={s}: {i2} vs {}",
                    p.1 + q.1
                );
            }
        }
    }

    #[test]
    fn invalid_parameters_are_named() {
        for (mu, gamma, key) in [
            (-0.1, 1.0, "mu=-0.1"),
            (f64::NAN, 1.0, "mu=NaN"),
            (f64::INFINITY, 1.0, "mu=inf"),
            (0.5, 0.0, "gamma=0"),
            (0.5, f64::NAN, "gamma=NaN"),
        ] {
            let e = Coulomb::new(mu, gamma).unwrap_err().to_string();
            assert!(e.contains(key), "{e}");
        }
        assert!(Coulomb::new(0.0, 1.0).is_ok());
    }
}
