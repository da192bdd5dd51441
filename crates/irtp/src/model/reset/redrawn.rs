//! Poissonian resetting to a fixed velocity v_r with the noise state
//! re-drawn: after a reset eta = +Sigma or -Sigma with probability ½ each,
//! whatever it was before (position kept).

use super::{NoiseAtReset, Reset, Target};
use serde::{Deserialize, Serialize};

/// At rate r, v → v_r and eta → ±Sigma (probability ½ each); position kept.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct RedrawnReset {
    /// Reset rate r.
    pub rate: f64,
    /// Reset velocity v_r.
    pub velocity: f64,
}

impl Reset for RedrawnReset {
    fn name(&self) -> &'static str {
        "redrawn"
    }
    fn rate(&self) -> f64 {
        self.rate
    }
    fn target(&self) -> Target {
        Target::point(self.velocity)
    }
    fn noise(&self) -> NoiseAtReset {
        NoiseAtReset::Redrawn
    }
    fn mirrored(&self) -> Self {
        RedrawnReset {
            rate: self.rate,
            velocity: -self.velocity,
        }
    }
    fn with_rate(&self, rate: f64) -> Self {
        RedrawnReset {
            rate,
            velocity: self.velocity,
        }
    }
}
