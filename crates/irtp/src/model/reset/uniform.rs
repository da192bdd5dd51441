//! Poissonian resetting to a random velocity drawn uniformly from [a, b]
//! (inside the admissible velocity interval); the noise state kept or
//! re-drawn.

use super::{NoiseAtReset, Reset, Target};
use serde::{Deserialize, Serialize};

/// At rate r, v → a uniform draw from [a, b]; position kept, noise state by
/// `noise`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct UniformReset {
    /// Reset rate r.
    pub rate: f64,
    /// Left end of the support.
    pub a: f64,
    /// Right end of the support (> a).
    pub b: f64,
    /// What a reset does to the noise state.
    pub noise: NoiseAtReset,
}

impl Reset for UniformReset {
    fn name(&self) -> &'static str {
        "uniform"
    }
    fn rate(&self) -> f64 {
        self.rate
    }
    fn target(&self) -> Target {
        Target::Uniform {
            a: self.a,
            b: self.b,
        }
    }
    fn noise(&self) -> NoiseAtReset {
        self.noise
    }
    fn mirrored(&self) -> Self {
        UniformReset {
            a: -self.b,
            b: -self.a,
            ..*self
        }
    }
    fn with_rate(&self, rate: f64) -> Self {
        UniformReset { rate, ..*self }
    }
}
