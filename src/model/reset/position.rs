//! Position resetting ("full" resetting): at every reset the position jumps
//! to x_r together with the velocity. The position then has a stationary
//! distribution P_s(x) instead of spreading diffusively; the velocity
//! process, and everything computed from it alone (P_s(v), first passages
//! in velocity), is unchanged.

use crate::error::{finite, Result};
use serde::{Deserialize, Serialize};

/// At every reset, x → `x`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct PositionReset {
    /// The reset position x_r.
    pub x: f64,
}

impl PositionReset {
    /// Validate: x_r finite.
    pub fn new(x: f64) -> Result<Self> {
        Ok(PositionReset {
            x: finite("reset_position", x)?,
        })
    }
}
