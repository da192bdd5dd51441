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

/// Tail constant c of the histogram range of P_s(x) under a Poisson clock:
/// the time since the last reset is Exp(r), so |x - x_r| > v_max c / r has
/// probability below e^{-c} (the mass outside is reported anyway).
pub const TAIL: f64 = 8.0;

impl PositionReset {
    /// The range x_r ± L of the histogram of P_s(x) at t_max. Since
    /// |v| < v_max, |x - x_r| <= v_max A with A the time since the last
    /// reset; A is bounded by T with a periodic clock (plus D for a fixed
    /// refractory period: the range then holds all the mass of the particles
    /// that have reset), and taken as c/r for a Poisson clock of rate r
    /// (plus c M for an exponential refractory period of mean M), and never
    /// above t_max. The particles that never reset move from x = 0, not from
    /// x_r: the mass outside the range is reported, not dropped.
    pub fn range(
        &self,
        v_max: f64,
        rate: f64,
        schedule: &super::Schedule,
        t_max: f64,
    ) -> (f64, f64) {
        let clock = match schedule.periodic {
            Some(p) => p.period,
            None if schedule.clock.is_some() => schedule
                .clock
                .as_ref()
                .map_or(0.0, |c| c.horizon((-TAIL).exp())),
            None if rate > 0.0 => TAIL / rate,
            None => f64::INFINITY,
        };
        let hold = match schedule.refractory {
            Some(super::Refractory::Fixed { duration }) => duration,
            Some(super::Refractory::Exp { mean }) => TAIL * mean,
            None => 0.0,
        };
        let half = v_max * (clock + hold).min(t_max);
        (self.x - half, self.x + half)
    }
}
