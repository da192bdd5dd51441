//! The truncated Gaussian target: a reset draws the velocity from
//! N(mean, std²) truncated to the velocity interval (lo, hi) = (-v_u, v_u).

use super::TargetLaw;
use rand::Rng;
use serde::{Deserialize, Serialize};

/// v → N(mean, std²) restricted to (lo, hi) at a reset.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct GaussianTarget {
    /// Mean of the untruncated Gaussian (inside (lo, hi)).
    pub mean: f64,
    /// Its standard deviation (> 0).
    pub std: f64,
    /// Lower truncation point.
    pub lo: f64,
    /// Upper truncation point.
    pub hi: f64,
}

/// The standard normal density.
fn phi(z: f64) -> f64 {
    (-0.5 * z * z).exp() / (2.0 * std::f64::consts::PI).sqrt()
}

/// ∫_α^β φ. On an interval no wider than 1 (φ's own scale) by adaptive
/// Gauss-Kronrod, relative 1e-14: no cancellation, however far out in a
/// tail. On a wider one from libm's `erfc` (FreeBSD's, below 1 ulp) as
/// the difference of two upper tails on the side of 0 where the interval
/// lies, so that neither term is close to 1: a quadrature over a wide
/// interval would sample a narrow peak at too few nodes (a target of std
/// 1e-4 in (-v_u, v_u) has α, β = ∓10^4 and lost its whole mass).
fn normal_mass(al: f64, be: f64) -> f64 {
    if !(be > al) {
        return 0.0;
    }
    if be - al <= 1.0 {
        return crate::numerics::quad::integrate(&phi, al, be, 1e-14).unwrap_or(f64::NAN);
    }
    // P(Z > z).
    let upper = |z: f64| 0.5 * libm::erfc(z / std::f64::consts::SQRT_2);
    if al >= 0.0 {
        upper(al) - upper(be)
    } else if be <= 0.0 {
        upper(-be) - upper(-al)
    } else {
        1.0 - upper(-al) - upper(be)
    }
}

impl TargetLaw for GaussianTarget {
    const KIND: &'static str = "gauss";
    const KEYS: &'static [&'static str] = &["mean", "std"];
    fn from_values(values: &[f64]) -> Self {
        GaussianTarget {
            mean: values[0],
            std: values[1],
            lo: f64::NEG_INFINITY,
            hi: f64::INFINITY,
        }
    }
    fn values(&self) -> Vec<f64> {
        vec![self.mean, self.std]
    }
    fn fit(&self, vu: f64) -> Result<Self, String> {
        super::check_location_scale(self.mean, "std", self.std, vu)?;
        Ok(GaussianTarget {
            lo: -vu,
            hi: vu,
            ..*self
        })
    }
    /// Exact for the truncated Gaussian (its normalisation Z by adaptive
    /// Gauss-Kronrod to 1e-14, the rest in closed form:
    /// <v_r> = m + s (φ(α) - φ(β))/Z, Var = s² [1 + (α φ(α) - β φ(β))/Z
    /// - ((φ(α) - φ(β))/Z)²], α, β = (lo - m)/s, (hi - m)/s).
    fn moments(&self) -> (f64, f64) {
        let GaussianTarget { mean, std, lo, hi } = *self;
        let (al, be) = ((lo - mean) / std, (hi - mean) / std);
        let z = normal_mass(al, be);
        let d = (phi(al) - phi(be)) / z;
        let var = std * std * (1.0 + (al * phi(al) - be * phi(be)) / z - d * d);
        let m1 = mean + std * d;
        (m1, var + m1 * m1)
    }
    fn mirrored(&self) -> Self {
        GaussianTarget {
            mean: -self.mean,
            std: self.std,
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
    fn mass(&self, x0: f64, x1: f64) -> f64 {
        let GaussianTarget { mean, std, lo, hi } = *self;
        let (u0, u1) = (x0.max(lo), x1.min(hi));
        if u1 > u0 {
            normal_mass((u0 - mean) / std, (u1 - mean) / std)
        } else {
            0.0
        }
    }
    /// On the clipped interval: (m - x0) Z + s (φ(α0) - φ(α1)).
    fn moment_from(&self, x0: f64, x1: f64) -> f64 {
        let GaussianTarget { mean, std, lo, hi } = *self;
        let (u0, u1) = (x0.max(lo), x1.min(hi));
        if u1 > u0 {
            let (a0, a1) = ((u0 - mean) / std, (u1 - mean) / std);
            (mean - x0) * normal_mass(a0, a1) + std * (phi(a0) - phi(a1))
        } else {
            0.0
        }
    }
    /// By rejection: from the Gaussian itself when std ≤ half the interval
    /// (acceptance ≥ 0.34 since the mean is inside); else from the uniform
    /// on (lo, hi) with acceptance e^{-(v-m)²/2s²} ≥ e^{-2}.
    fn draw<R: Rng + ?Sized>(&self, rng: &mut R) -> f64 {
        let GaussianTarget { mean, std, lo, hi } = *self;
        loop {
            let v = if std <= 0.5 * (hi - lo) {
                let z: f64 = rng.sample(rand_distr::StandardNormal);
                let v = mean + std * z;
                if v > lo && v < hi {
                    return v;
                }
                continue;
            } else {
                lo + (hi - lo) * rng.gen::<f64>()
            };
            let u = (v - mean) / std;
            if v > lo && rng.gen::<f64>() < (-0.5 * u * u).exp() {
                return v;
            }
        }
    }
}
