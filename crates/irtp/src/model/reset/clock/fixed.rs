//! `fixed:t=T`: every waiting time is T (sharp resetting). With no
//! refractory period the clock restarts at the resets themselves, T, 2T,
//! ..., as with `--reset-period T`: [`crate::model::reset::Schedule`] then
//! computes the next one as that clock does (the next multiple of T), so
//! the two give the same bits and rounding does not accumulate over many
//! periods. After a refractory period the next reset is its end + T.

use super::{bad, check_mean, keyed, Law};
use crate::error::Result;
use crate::model::drag::spec::number;
use rand::Rng;

/// A deterministic waiting time.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FixedClock {
    /// The waiting time T > 0.
    pub t: f64,
}

impl Law for FixedClock {
    const KIND: &'static str = "fixed";
    const USAGE: &'static str = "fixed:t=T (T > 0)";
    fn parse(args: &str, spec: &str) -> Result<Self> {
        let v = keyed(args, spec, &["t"], Self::USAGE)?;
        if !(v[0] > 0.0) {
            return Err(bad(spec, "t > 0", Self::USAGE));
        }
        Ok(FixedClock { t: v[0] })
    }
    fn spec(&self) -> String {
        format!("fixed:t={}", number(self.t))
    }
    #[inline]
    fn draw<R: Rng + ?Sized>(&self, _rng: &mut R) -> f64 {
        self.t
    }
    fn survival(&self, t: f64) -> f64 {
        if t < self.t {
            1.0
        } else {
            0.0
        }
    }
    fn density(&self, _t: f64) -> Option<f64> {
        None
    }
    fn mean(&self) -> f64 {
        self.t
    }
    fn with_mean(&self, mean: f64) -> Result<Self> {
        Ok(FixedClock {
            t: check_mean(mean)?,
        })
    }
    fn tail_integral(&self, t: f64) -> f64 {
        (self.t - t).max(0.0)
    }
    fn survival_integral(&self, a: f64, b: f64) -> f64 {
        b.min(self.t) - a.min(self.t)
    }
    fn survival_moment(&self, a: f64, b: f64) -> f64 {
        let e = b.min(self.t).max(a) - a;
        0.5 * e * e
    }
    fn horizon(&self, _tail: f64) -> f64 {
        self.t
    }
    /// With t_max = T: the trapezoid weights of ∫_0^T f, and the point
    /// mass of rho at T.
    fn renewal_weights(&self, _t_max: f64, steps: usize) -> (Vec<f64>, Vec<f64>, f64) {
        let dt = self.t / steps as f64;
        let wq = (0..=steps)
            .map(|n| if n == 0 || n == steps { 0.5 * dt } else { dt })
            .collect();
        let rq = (0..=steps)
            .map(|n| if n == steps { 1.0 } else { 0.0 })
            .collect();
        (wq, rq, 0.0)
    }
    fn support_end(&self) -> f64 {
        self.t
    }
}
