//! The uniform target: a reset draws the velocity uniformly from [a, b],
//! inside the velocity interval.

use super::TargetLaw;
use rand::Rng;
use serde::{Deserialize, Serialize};

/// v → U(a, b) at a reset.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct UniformTarget {
    /// Left end.
    pub a: f64,
    /// Right end (> a).
    pub b: f64,
}

impl TargetLaw for UniformTarget {
    const KIND: &'static str = "uniform";
    const KEYS: &'static [&'static str] = &["a", "b"];
    fn from_values(values: &[f64]) -> Self {
        UniformTarget {
            a: values[0],
            b: values[1],
        }
    }
    fn values(&self) -> Vec<f64> {
        vec![self.a, self.b]
    }
    fn fit(&self, vu: f64) -> Result<Self, String> {
        let (a, b) = (self.a, self.b);
        if !(a > -vu && a < b && b < vu) {
            return Err(format!(
                "-{vu} < a < b < {vu} (inside the open velocity interval)"
            ));
        }
        Ok(*self)
    }
    fn moments(&self) -> (f64, f64) {
        let (a, b) = (self.a, self.b);
        (0.5 * (a + b), (a * a + a * b + b * b) / 3.0)
    }
    fn mirrored(&self) -> Self {
        UniformTarget {
            a: -self.b,
            b: -self.a,
        }
    }
    fn centre(&self) -> f64 {
        0.5 * (self.a + self.b)
    }
    fn support(&self) -> (f64, f64) {
        (self.a, self.b)
    }
    fn mass(&self, x0: f64, x1: f64) -> f64 {
        let (a, b) = (self.a, self.b);
        (x1.min(b) - x0.max(a)).max(0.0) / (b - a)
    }
    fn moment_from(&self, x0: f64, x1: f64) -> f64 {
        let (a, b) = (self.a, self.b);
        let (u0, u1) = (x0.max(a), x1.min(b));
        let d = (u1 - u0).max(0.0);
        d * (0.5 * (u0 + u1) - x0) / (b - a)
    }
    #[inline]
    fn draw<R: Rng + ?Sized>(&self, rng: &mut R) -> f64 {
        self.a + (self.b - self.a) * rng.gen::<f64>()
    }
}
