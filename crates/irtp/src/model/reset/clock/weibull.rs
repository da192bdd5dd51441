//! `weibull:k=K,scale=L`: Weibull waiting times, W(t) = e^{-(t/L)^k}
//! (hazard (k/L)(t/L)^{k-1}: decreasing for k < 1, increasing for k > 1),
//! mean L Γ(1 + 1/k). Drawn by `rand_distr::Weibull` (inversion, exact).

use super::special::gamma_q;
use super::{bad, check_mean, keyed, Law};
use crate::error::Result;
use crate::model::drag::spec::number;
use rand::Rng;
use rand_distr::Distribution;

/// Weibull(k, L) waiting times.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WeibullClock {
    /// Shape k > 0.
    pub k: f64,
    /// Scale L > 0.
    pub scale: f64,
}

impl Law for WeibullClock {
    const KIND: &'static str = "weibull";
    const USAGE: &'static str = "weibull:k=K,scale=L (K, L > 0)";
    fn parse(args: &str, spec: &str) -> Result<Self> {
        let v = keyed(args, spec, &["k", "scale"], Self::USAGE)?;
        if !(v[0] > 0.0 && v[1] > 0.0) {
            return Err(bad(spec, "k > 0 and scale > 0", Self::USAGE));
        }
        Ok(WeibullClock {
            k: v[0],
            scale: v[1],
        })
    }
    fn spec(&self) -> String {
        format!("weibull:k={},scale={}", number(self.k), number(self.scale))
    }
    #[inline]
    fn draw<R: Rng + ?Sized>(&self, rng: &mut R) -> f64 {
        rand_distr::Weibull::new(self.scale, self.k)
            .expect("validated shape and scale")
            .sample(rng)
    }
    fn survival(&self, t: f64) -> f64 {
        (-(t.max(0.0) / self.scale).powf(self.k)).exp()
    }
    fn cdf(&self, t: f64) -> f64 {
        -(-(t.max(0.0) / self.scale).powf(self.k)).exp_m1()
    }
    fn density(&self, t: f64) -> Option<f64> {
        if !(t > 0.0) {
            return Some(if self.k == 1.0 { 1.0 / self.scale } else { 0.0 });
        }
        let x = t / self.scale;
        Some(self.k / self.scale * x.powf(self.k - 1.0) * (-x.powf(self.k)).exp())
    }
    fn mean(&self) -> f64 {
        self.scale * libm::tgamma(1.0 + 1.0 / self.k)
    }
    fn with_mean(&self, mean: f64) -> Result<Self> {
        Ok(WeibullClock {
            k: self.k,
            scale: check_mean(mean)? / libm::tgamma(1.0 + 1.0 / self.k),
        })
    }
    /// L Γ(1 + 1/k) Q(1/k, (t/L)^k) (substituting y = (s/L)^k).
    fn tail_integral(&self, t: f64) -> f64 {
        let x = (t.max(0.0) / self.scale).powf(self.k);
        self.mean() * gamma_q(1.0 / self.k, x)
    }
    fn horizon(&self, tail: f64) -> f64 {
        self.scale * (1.0 / tail).ln().powf(1.0 / self.k)
    }
}
