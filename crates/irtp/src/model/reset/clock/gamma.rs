//! `gamma:k=K,theta=TH`: Gamma waiting times, density
//! t^{k-1} e^{-t/θ} / (Γ(k) θ^k), mean kθ. Drawn by `rand_distr::Gamma`
//! (Marsaglia-Tsang, exact), except k = 1, drawn as Exp1 × θ: the same
//! arithmetic as [`super::ExpClock`], so `gamma:k=1,theta=1/R` and
//! `exp:rate=R` give the same bits.

use super::special::{gamma_p, gamma_q};
use super::{bad, check_mean, keyed, Law};
use crate::error::Result;
use crate::model::drag::spec::number;
use rand::Rng;
use rand_distr::Distribution;

/// Gamma(k, θ) waiting times.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GammaClock {
    /// Shape k > 0.
    pub k: f64,
    /// Scale θ > 0.
    pub theta: f64,
}

impl Law for GammaClock {
    const KIND: &'static str = "gamma";
    const USAGE: &'static str = "gamma:k=K,theta=TH (K, TH > 0)";
    fn parse(args: &str, spec: &str) -> Result<Self> {
        let v = keyed(args, spec, &["k", "theta"], Self::USAGE)?;
        if !(v[0] > 0.0 && v[1] > 0.0) {
            return Err(bad(spec, "k > 0 and theta > 0", Self::USAGE));
        }
        Ok(GammaClock {
            k: v[0],
            theta: v[1],
        })
    }
    fn spec(&self) -> String {
        format!("gamma:k={},theta={}", number(self.k), number(self.theta))
    }
    #[inline]
    fn draw<R: Rng + ?Sized>(&self, rng: &mut R) -> f64 {
        if self.k == 1.0 {
            return rng.sample::<f64, _>(rand_distr::Exp1) * self.theta;
        }
        rand_distr::Gamma::new(self.k, self.theta)
            .expect("validated shape and scale")
            .sample(rng)
    }
    fn survival(&self, t: f64) -> f64 {
        gamma_q(self.k, t / self.theta)
    }
    fn cdf(&self, t: f64) -> f64 {
        gamma_p(self.k, t / self.theta)
    }
    fn density(&self, t: f64) -> Option<f64> {
        if !(t > 0.0) {
            return Some(if self.k == 1.0 && t == 0.0 {
                1.0 / self.theta
            } else {
                0.0
            });
        }
        let x = t / self.theta;
        Some(((self.k - 1.0) * x.ln() - x - libm::lgamma(self.k)).exp() / self.theta)
    }
    fn mean(&self) -> f64 {
        self.k * self.theta
    }
    fn with_mean(&self, mean: f64) -> Result<Self> {
        Ok(GammaClock {
            k: self.k,
            theta: check_mean(mean)? / self.k,
        })
    }
    /// θ [k Q(k+1, x) - x Q(k, x)], x = t/θ (∫_x^∞ Q(k, y) dy by parts).
    fn tail_integral(&self, t: f64) -> f64 {
        let x = t.max(0.0) / self.theta;
        (self.theta * (self.k * gamma_q(self.k + 1.0, x) - x * gamma_q(self.k, x))).max(0.0)
    }
}
