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

#[cfg(test)]
mod tests {
    use super::*;

    /// The default numerical inverse solves v³ + 3v - 3f = 0 (one real root,
    /// v = 2 sinh(asinh(3f/2)/3) by the hyperbolic form of Cardano's
    /// formula, free of cancellation) to rounding, and is exactly odd.
    #[test]
    fn default_inverse_solves_the_cubic() {
        for f in [1e-300, 1e-8, 0.3, 1.0, 3.0, 17.5, 1e6, 1e100] {
            let v = Cubic.inverse(f);
            let cardano = 2.0 * ((1.5 * f).asinh() / 3.0).sinh();
            // sinh(x/3) amplifies the rounding of x = asinh(3f/2) by ~x/3.
            let tol = 4.0 * f64::EPSILON * (1.0 + (1.5 * f).asinh()) * v.abs();
            assert!((v - cardano).abs() <= tol, "f={f}: {v} vs {cardano}");
            assert_eq!(Cubic.inverse(-f), -v);
            // The bisection ends on adjacent doubles: v is within an ulp.
            let (below, above) = (
                Cubic.force(v * (1.0 - 4.0 * f64::EPSILON)),
                Cubic.force(v * (1.0 + 4.0 * f64::EPSILON)),
            );
            assert!(below <= f && f <= above, "f={f}");
        }
        assert_eq!(Cubic.inverse(0.0), 0.0);
    }

    /// g' = 1 + v² is largest at the edges ±v_u; the sampled default bound
    /// is that value plus its 1 % margin.
    #[test]
    fn default_max_derivative_is_the_edge_slope() {
        for sigma in [0.1, 1.0, 3.0, 100.0] {
            let vu = Cubic.inverse(sigma);
            let edge = 1.0 + vu * vu;
            let m = Cubic.max_derivative(sigma);
            assert!(
                m >= edge && m <= 1.0101 * edge,
                "sigma={sigma}: {m} vs {edge}"
            );
            assert!((m / 1.01 - edge).abs() <= 1e-15 * edge, "sigma={sigma}");
        }
    }
}
