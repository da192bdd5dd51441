//! Periodic (sharp) resetting: the reset clock fires at t = T, 2T, 3T, ...
//! (deterministic times counted from the start of the run) instead of at
//! the events of a Poisson clock. The target and the noise rule are those
//! of the resetting rule; the Poisson rate is then 0.

use crate::error::{finite, Error, Result};
use serde::{Deserialize, Serialize};

/// Resets at every multiple of `period`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Periodic {
    /// The period T > 0.
    pub period: f64,
}

impl Periodic {
    /// Validate: T > 0 and finite.
    pub fn new(period: f64) -> Result<Self> {
        let period = finite("reset_period", period)?;
        if !(period > 0.0) {
            return Err(Error::invalid("reset_period", period, "T > 0, finite"));
        }
        Ok(Periodic { period })
    }

    /// The first reset time strictly after `t`.
    #[inline]
    pub fn next_after(&self, t: f64) -> f64 {
        let k = (t / self.period).floor() + 1.0;
        let next = k * self.period;
        // Rounding of t / T can land on the current multiple.
        if next > t {
            next
        } else {
            next + self.period
        }
    }
}

impl Periodic {
    /// The period of the long-time (cyclostationary) state: T, or m T with
    /// a fixed refractory period D, whose resets fall every
    /// m = floor(D/T) + 1 periods (the reset times inside a refractory
    /// period or at its end are skipped). Window time averages are period
    /// averages only over a whole number of these.
    pub fn cycle(&self, refractory: Option<super::Refractory>) -> f64 {
        match refractory {
            Some(super::Refractory::Fixed { duration }) => {
                ((duration / self.period).floor() + 1.0) * self.period
            }
            _ => self.period,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn validates_and_steps() {
        for bad in [0.0, -1.0, f64::NAN, f64::INFINITY] {
            assert!(Periodic::new(bad).is_err(), "{bad}");
        }
        let p = Periodic::new(0.1).unwrap();
        assert_eq!(p.next_after(0.0), 0.1);
        let t = p.next_after(0.25);
        assert!((t - 0.3).abs() < 1e-15);
        // At a multiple itself, the next one.
        let at = p.next_after(0.1);
        assert!(at > 0.1 && (at - 0.2).abs() < 1e-15);
    }
}
