//! The point target: every reset sends the velocity to v_r (the paper's
//! Eq. (3)).

use super::TargetLaw;
use rand::Rng;
use serde::{Deserialize, Serialize};

/// v → v_r at a reset. Its range is checked by [`crate::Params::new`] with
/// the reset velocity.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct PointTarget {
    /// The reset velocity v_r.
    pub v: f64,
}

impl TargetLaw for PointTarget {
    const KIND: &'static str = "point";
    const KEYS: &'static [&'static str] = &["v"];
    fn from_values(values: &[f64]) -> Self {
        PointTarget { v: values[0] }
    }
    fn values(&self) -> Vec<f64> {
        vec![self.v]
    }
    fn fit(&self, _v_upper: f64) -> Result<Self, String> {
        Ok(*self)
    }
    fn point(&self) -> Option<f64> {
        Some(self.v)
    }
    fn moments(&self) -> (f64, f64) {
        (self.v, self.v * self.v)
    }
    fn mirrored(&self) -> Self {
        PointTarget { v: -self.v }
    }
    fn centre(&self) -> f64 {
        self.v
    }
    fn support(&self) -> (f64, f64) {
        (self.v, self.v)
    }
    fn mass(&self, x0: f64, x1: f64) -> f64 {
        f64::from(u8::from(x0 <= self.v && self.v < x1))
    }
    fn moment_from(&self, x0: f64, x1: f64) -> f64 {
        (self.v - x0) * self.mass(x0, x1)
    }
    #[inline]
    fn draw<R: Rng + ?Sized>(&self, _rng: &mut R) -> f64 {
        self.v
    }
}
