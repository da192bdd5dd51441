//! `pareto:alpha=A,scale=X`: Pareto I (power-law) waiting times on
//! t ≥ X, W(t) = (X/t)^A, drawn by `rand_distr::Pareto` (inversion,
//! exact). Pareto I rather than Lomax because it is `rand_distr`'s and
//! its scale is a hard minimum waiting time; its tail is the same power
//! law. The mean A X / (A - 1) is finite only for A > 1: for A ≤ 1
//! [`Law::mean`] and [`Law::tail_integral`] are ∞, [`Law::with_mean`]
//! refuses, and the renewal route refuses the law by name (its neglected
//! tail has no finite bound); the samplers run it.

use super::{bad, check_mean, keyed, Law};
use crate::error::{Error, Result};
use crate::model::drag::spec::number;
use rand::Rng;
use rand_distr::Distribution;

/// Pareto I waiting times.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ParetoClock {
    /// Tail exponent A > 0.
    pub alpha: f64,
    /// Minimum waiting time X > 0.
    pub scale: f64,
}

impl Law for ParetoClock {
    const KIND: &'static str = "pareto";
    const USAGE: &'static str = "pareto:alpha=A,scale=X (A, X > 0; finite mean for A > 1)";
    fn parse(args: &str, spec: &str) -> Result<Self> {
        let v = keyed(args, spec, &["alpha", "scale"], Self::USAGE)?;
        if !(v[0] > 0.0 && v[1] > 0.0) {
            return Err(bad(spec, "alpha > 0 and scale > 0", Self::USAGE));
        }
        Ok(ParetoClock {
            alpha: v[0],
            scale: v[1],
        })
    }
    fn spec(&self) -> String {
        format!(
            "pareto:alpha={},scale={}",
            number(self.alpha),
            number(self.scale)
        )
    }
    #[inline]
    fn draw<R: Rng + ?Sized>(&self, rng: &mut R) -> f64 {
        rand_distr::Pareto::new(self.scale, self.alpha)
            .expect("validated scale and shape")
            .sample(rng)
    }
    fn survival(&self, t: f64) -> f64 {
        if t < self.scale {
            1.0
        } else {
            (self.scale / t).powf(self.alpha)
        }
    }
    fn density(&self, t: f64) -> Option<f64> {
        Some(if t < self.scale {
            0.0
        } else {
            self.alpha / t * (self.scale / t).powf(self.alpha)
        })
    }
    fn mean(&self) -> f64 {
        if self.alpha > 1.0 {
            self.alpha * self.scale / (self.alpha - 1.0)
        } else {
            f64::INFINITY
        }
    }
    fn with_mean(&self, mean: f64) -> Result<Self> {
        if !(self.alpha > 1.0) {
            return Err(Error::invalid(
                super::FLAG,
                self.spec(),
                "a law with a finite mean to rescale (pareto: alpha > 1)",
            ));
        }
        Ok(ParetoClock {
            alpha: self.alpha,
            scale: check_mean(mean)? * (self.alpha - 1.0) / self.alpha,
        })
    }
    fn tail_integral(&self, t: f64) -> f64 {
        if !(self.alpha > 1.0) {
            return f64::INFINITY;
        }
        if t < self.scale {
            return self.mean() - t.max(0.0);
        }
        t * self.survival(t) / (self.alpha - 1.0)
    }
    fn survival_integral(&self, a: f64, b: f64) -> f64 {
        let flat = b.min(self.scale) - a.min(self.scale);
        let (lo, hi) = (a.max(self.scale), b.max(self.scale));
        let power = if hi > lo {
            if self.alpha == 1.0 {
                self.scale * (hi / lo).ln()
            } else {
                (hi * self.survival(hi) - lo * self.survival(lo)) / (1.0 - self.alpha)
            }
        } else {
            0.0
        };
        flat + power
    }
    fn horizon(&self, tail: f64) -> f64 {
        self.scale * tail.powf(-1.0 / self.alpha)
    }
}
