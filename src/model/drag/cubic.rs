//! g(v) = v + v³/3: a shear-thickening medium given only by g and g' (no
//! closed-form flow), the worked example of `docs/extending.md`. Every
//! method runs it through the trait's defaults: the tabulated exact flow,
//! the numerical inverse and the sampled slope bound.

use super::{Drag, TabulatedFlow};

/// g(v) = v + v³/3, unbounded: any Sigma > 0.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct Cubic;

impl Drag for Cubic {
    type Flow = TabulatedFlow<Cubic>;

    fn name(&self) -> &'static str {
        "cubic"
    }
    fn force(&self, v: f64) -> f64 {
        v + v * v * v / 3.0
    }
    fn derivative(&self, v: f64) -> f64 {
        1.0 + v * v
    }
    fn flow(&self, s: f64) -> TabulatedFlow<Cubic> {
        TabulatedFlow::new(*self, s)
    }
    fn description(&self) -> &'static str {
        "shear-thickening, g = v + v³/3"
    }
}
