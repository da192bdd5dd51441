//! The search problem: first passage of the position x to a target
//! (docs/equations.md, "Search: the 2-D backward equation and the renewal
//! route").
//!
//! - [`backward`]: the mean first-passage time from the backward equation
//!   `L T = -1` for T(x, v, eta) on a 2-D mesh (full resetting; velocity-only
//!   resetting for an interval target).
//! - [`renewal`]: the state-resolved renewal route for full resetting, over
//!   any waiting-time law of the resets (Poisson, periodic).

pub mod backward;
mod mesh;
pub mod renewal;

use crate::error::{finite, Error, Result};
use crate::Params;
use serde::{Deserialize, Serialize};

/// Where the search ends.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum PositionTarget {
    /// The first time x reaches the level L (one-sided; L > x0 or L < x0).
    Level(f64),
    /// The first exit of x from the open interval (a, b), a < x0 < b.
    Interval(f64, f64),
}

/// A validated search problem.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SearchProblem {
    params: Params,
    x0: f64,
    v0: f64,
    target: PositionTarget,
}

impl SearchProblem {
    /// Validate: x0, v0 and the target finite; `L != x0` for a level,
    /// `a < x0 < b` for an interval; v0 in (v_l, v_u); a reset position
    /// (`params.schedule().position`) strictly on the start side of a level,
    /// strictly inside an interval.
    pub fn new(params: Params, x0: f64, v0: f64, target: PositionTarget) -> Result<Self> {
        let x0 = finite("x0", x0)?;
        let v0 = finite("v0", v0)?;
        let (vl, vu) = params.bounds();
        if !(v0 > vl && v0 < vu) {
            return Err(Error::invalid("v0", v0, format!("{vl:.6} < v0 < {vu:.6}")));
        }
        let inside: Box<dyn Fn(f64) -> bool> = match target {
            PositionTarget::Level(l) => {
                let l = finite("target", l)?;
                if l == x0 {
                    return Err(Error::invalid("target", l, "a level L != x0"));
                }
                Box::new(move |x: f64| (x - l) * (x0 - l) > 0.0)
            }
            PositionTarget::Interval(a, b) => {
                let (a, b) = (finite("target", a)?, finite("target", b)?);
                if !(a < x0 && x0 < b) {
                    return Err(Error::invalid(
                        "x0",
                        x0,
                        format!("a < x0 < b for the interval ({a}, {b})"),
                    ));
                }
                Box::new(move |x: f64| a < x && x < b)
            }
        };
        if let Some(p) = params.schedule().position {
            if !inside(p.x) {
                return Err(Error::invalid(
                    "reset_position",
                    p.x,
                    "strictly on the start side of the target (inside an interval)",
                ));
            }
        }
        Ok(SearchProblem {
            params,
            x0,
            v0,
            target,
        })
    }

    /// Model parameters (drag, noise, resetting rule and schedule).
    pub fn params(&self) -> &Params {
        &self.params
    }
    /// Start position.
    pub fn x0(&self) -> f64 {
        self.x0
    }
    /// Start velocity.
    pub fn v0(&self) -> f64 {
        self.v0
    }
    /// The target.
    pub fn target(&self) -> PositionTarget {
        self.target
    }
    /// Whether the mean first-passage time is finite: always for an
    /// interval; for a level only with full resetting (position reset) and
    /// resets that happen (a Poisson rate r > 0 or a period).
    pub fn mean_is_finite(&self) -> bool {
        match self.target {
            PositionTarget::Interval(..) => true,
            PositionTarget::Level(_) => {
                let s = self.params.schedule();
                s.position.is_some() && (self.params.rate() > 0.0 || s.periodic.is_some())
            }
        }
    }
}
