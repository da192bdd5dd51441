//! Poissonian resetting to a fixed velocity v_r with the noise state kept:
//! the paper's protocol (Eq. (3)).

use super::{NoiseAtReset, Reset, Target};
use serde::{Deserialize, Serialize};

/// At rate r, v → v_r; position and noise state kept.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct PoissonReset {
    /// Reset rate r.
    pub rate: f64,
    /// Reset velocity v_r.
    pub velocity: f64,
}

impl Reset for PoissonReset {
    fn name(&self) -> &'static str {
        "poisson"
    }
    fn rate(&self) -> f64 {
        self.rate
    }
    fn target(&self) -> Target {
        Target::point(self.velocity)
    }
    fn noise(&self) -> NoiseAtReset {
        NoiseAtReset::Kept
    }
    fn mirrored(&self) -> Self {
        PoissonReset {
            rate: self.rate,
            velocity: -self.velocity,
        }
    }
    fn with_rate(&self, rate: f64) -> Self {
        PoissonReset {
            rate,
            velocity: self.velocity,
        }
    }
}
