//! Poissonian resetting to a random velocity: a Gaussian N(mean, std²)
//! truncated to the admissible velocity interval (-v_u, v_u); the noise
//! state kept or re-drawn.

use super::{NoiseAtReset, Reset, Target};
use serde::{Deserialize, Serialize};

/// At rate r, v → a draw of the truncated Gaussian; position kept, noise
/// state by `noise`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct GaussianReset {
    /// Reset rate r.
    pub rate: f64,
    /// Mean of the untruncated Gaussian (inside (-v_u, v_u)).
    pub mean: f64,
    /// Its standard deviation (> 0).
    pub std: f64,
    /// The truncation point v_u (the interval is (-v_u, v_u)).
    pub bound: f64,
    /// What a reset does to the noise state.
    pub noise: NoiseAtReset,
}

impl Reset for GaussianReset {
    fn name(&self) -> &'static str {
        "gauss"
    }
    fn rate(&self) -> f64 {
        self.rate
    }
    fn target(&self) -> Target {
        Target::Gaussian {
            mean: self.mean,
            std: self.std,
            lo: -self.bound,
            hi: self.bound,
        }
    }
    fn noise(&self) -> NoiseAtReset {
        self.noise
    }
    fn mirrored(&self) -> Self {
        GaussianReset {
            mean: -self.mean,
            ..*self
        }
    }
    fn with_rate(&self, rate: f64) -> Self {
        GaussianReset { rate, ..*self }
    }
}
