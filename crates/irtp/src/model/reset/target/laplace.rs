//! The Laplace target: a reset draws the velocity from the two-sided
//! exponential density e^{-|v - m|/b} / 2b truncated to the velocity
//! interval (lo, hi) = (-v_u, v_u): a target with a cusp at its mode and
//! exponential tails, between the point (b → 0) and the uniform (b → ∞).

use super::TargetLaw;
use rand::Rng;
use serde::{Deserialize, Serialize};

/// v → Laplace(mean, scale) restricted to (lo, hi) at a reset.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct LaplaceTarget {
    /// The mode m (inside (lo, hi)).
    pub mean: f64,
    /// The scale b (> 0): the untruncated law has variance 2 b².
    pub scale: f64,
    /// Lower truncation point.
    pub lo: f64,
    /// Upper truncation point.
    pub hi: f64,
}

impl LaplaceTarget {
    /// The untruncated distribution function F(v).
    fn cdf(&self, v: f64) -> f64 {
        let z = (v - self.mean) / self.scale;
        if z < 0.0 {
            0.5 * z.exp()
        } else {
            1.0 - 0.5 * (-z).exp()
        }
    }
    /// Its inverse on (0, 1).
    fn quantile(&self, u: f64) -> f64 {
        let z = if u < 0.5 {
            (2.0 * u).ln()
        } else {
            -(2.0 * (1.0 - u)).ln()
        };
        self.mean + self.scale * z
    }
    /// ∫_{x0}^{x1} (v - x0)^k q(v) dv of the untruncated density, k = 0, 1, 2,
    /// by adaptive Gauss-Kronrod on each side of the mode (the density has
    /// a cusp there).
    fn integral(&self, x0: f64, x1: f64, k: i32) -> f64 {
        let q = |v: f64| {
            (v - x0).powi(k) * (-(v - self.mean).abs() / self.scale).exp() / (2.0 * self.scale)
        };
        let quad = |a: f64, b: f64| {
            if b > a {
                crate::numerics::quad::integrate(&q, a, b, 1e-13).unwrap_or(f64::NAN)
            } else {
                0.0
            }
        };
        let m = self.mean.clamp(x0, x1);
        quad(x0, m) + quad(m, x1)
    }
}

impl TargetLaw for LaplaceTarget {
    const KIND: &'static str = "laplace";
    const KEYS: &'static [&'static str] = &["mean", "scale"];
    fn from_values(values: &[f64]) -> Self {
        LaplaceTarget {
            mean: values[0],
            scale: values[1],
            lo: f64::NEG_INFINITY,
            hi: f64::INFINITY,
        }
    }
    fn values(&self) -> Vec<f64> {
        vec![self.mean, self.scale]
    }
    fn fit(&self, vu: f64) -> Result<Self, String> {
        super::check_location_scale(self.mean, "scale", self.scale, vu)?;
        Ok(LaplaceTarget {
            lo: -vu,
            hi: vu,
            ..*self
        })
    }
    /// By quadrature of (v - lo)^k q over (lo, hi), k = 0, 1, 2:
    /// `<v> = lo + M1/M0`, `<v²> = M2/M0 + 2 lo <v> - lo²`.
    fn moments(&self) -> (f64, f64) {
        let m = [0, 1, 2].map(|k| self.integral(self.lo, self.hi, k));
        let lo = self.lo;
        let m1 = lo + m[1] / m[0];
        (m1, m[2] / m[0] + 2.0 * lo * m1 - lo * lo)
    }
    fn mirrored(&self) -> Self {
        LaplaceTarget {
            mean: -self.mean,
            scale: self.scale,
            lo: -self.hi,
            hi: -self.lo,
        }
    }
    fn centre(&self) -> f64 {
        self.mean
    }
    fn support(&self) -> (f64, f64) {
        (self.lo, self.hi)
    }
    /// F(x1) - F(x0) on the interval clipped to (lo, hi), from the side
    /// of the smaller tail (no cancellation in the tails).
    fn mass(&self, x0: f64, x1: f64) -> f64 {
        let (u0, u1) = (x0.max(self.lo), x1.min(self.hi));
        if !(u1 > u0) {
            return 0.0;
        }
        if u0 >= self.mean {
            let s = |v: f64| 0.5 * (-(v - self.mean) / self.scale).exp();
            s(u0) - s(u1)
        } else {
            self.cdf(u1) - self.cdf(u0)
        }
    }
    fn moment_from(&self, x0: f64, x1: f64) -> f64 {
        let (u0, u1) = (x0.max(self.lo), x1.min(self.hi));
        if !(u1 > u0) {
            return 0.0;
        }
        self.integral(u0, u1, 1) + (u0 - x0) * self.mass(u0, u1)
    }
    /// By inversion of the distribution function on (F(lo), F(hi)).
    fn draw<R: Rng + ?Sized>(&self, rng: &mut R) -> f64 {
        let (f0, f1) = (self.cdf(self.lo), self.cdf(self.hi));
        loop {
            let v = self.quantile(f0 + (f1 - f0) * rng.gen::<f64>());
            if v > self.lo && v < self.hi {
                return v;
            }
        }
    }
}
