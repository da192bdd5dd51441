//! Poissonian resetting to a random velocity: any registered target law
//! other than the point ([`super::target`]); the noise state kept or
//! re-drawn.

use super::{NoiseAtReset, Reset, Target};
use serde::{Deserialize, Serialize};

/// At rate r, v → a draw of `target`; position kept, noise state by
/// `noise`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct RandomReset {
    /// Reset rate r.
    pub rate: f64,
    /// Where a reset sends the velocity (checked against the velocity
    /// interval: [`Target::fit`]).
    pub target: Target,
    /// What a reset does to the noise state.
    pub noise: NoiseAtReset,
}

impl Reset for RandomReset {
    fn name(&self) -> &'static str {
        self.target.kind()
    }
    fn rate(&self) -> f64 {
        self.rate
    }
    fn target(&self) -> Target {
        self.target
    }
    fn noise(&self) -> NoiseAtReset {
        self.noise
    }
    fn mirrored(&self) -> Self {
        RandomReset {
            target: self.target.mirrored(),
            ..*self
        }
    }
    fn with_rate(&self, rate: f64) -> Self {
        RandomReset { rate, ..*self }
    }
}
