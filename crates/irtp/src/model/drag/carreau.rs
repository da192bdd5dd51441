//! g(v) = v [1 + (a v)²]^((n-1)/2): the Carreau medium, Newtonian (g ≈ v)
//! for |a v| ≪ 1 and power-law-like (g ≈ a^(n-1) |v|^n sign v) for
//! |a v| ≫ 1: shear-thinning for n < 1, shear-thickening for n > 1, exactly
//! linear for n = 1. Written `carreau:n=N,a=A` (a defaults to 1).
//!
//! irtp requires n > 0: then g' = [1 + (a v)²]^((n-3)/2) (1 + n (a v)²) > 0
//! and g is unbounded, so any Sigma > 0 is admissible. (At n = 0 the law
//! would be bounded by 1/a, at n < 0 no longer monotone; both are refused.)
//! g' is smooth and monotone in |v| (d g'/d(a v)² ∝ (n - 1)(3 + n (a v)²)),
//! so its largest value on [-v_u, v_u] is g'(0) = 1 for n <= 1 and
//! g'(v_u) for n > 1.

use super::spec::{self, Key, ParamLaw};
use super::{Drag, TabulatedFlow};
use crate::error::Result;

/// g(v) = v [1 + (a v)²]^((n-1)/2), n > 0, a > 0, unbounded: any Sigma > 0.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Carreau {
    n: f64,
    a: f64,
}

impl Carreau {
    /// The law with flow index `n` and time constant `a`, both finite and > 0.
    pub fn new(n: f64, a: f64) -> Result<Self> {
        Ok(Carreau {
            n: spec::positive::<Carreau>("n", n)?,
            a: spec::positive::<Carreau>("a", a)?,
        })
    }
    /// The flow index n.
    pub fn n(&self) -> f64 {
        self.n
    }
    /// The time constant a (the velocity scale of the crossover is 1/a).
    pub fn a(&self) -> f64 {
        self.a
    }
}

impl ParamLaw for Carreau {
    const KEYS: &'static [Key] = &[
        Key {
            name: "n",
            default: None,
            meaning: "flow index n > 0, finite (n < 1 shear-thinning, n > 1 shear-thickening)",
        },
        Key {
            name: "a",
            default: Some(1.0),
            meaning: "time constant a > 0, finite",
        },
    ];
    fn from_values(values: &[f64]) -> Result<Self> {
        Carreau::new(values[0], values[1])
    }
    fn values(&self) -> Vec<f64> {
        vec![self.n, self.a]
    }
    fn example() -> Self {
        Carreau { n: 0.5, a: 1.0 }
    }
}

impl Drag for Carreau {
    type Flow = TabulatedFlow<Carreau>;

    fn name(&self) -> &'static str {
        "carreau"
    }
    /// v hypot(1, a v)^(n-1): no overflow of (a v)², exactly v for n = 1.
    #[inline]
    fn force(&self, v: f64) -> f64 {
        v * (self.a * v).hypot(1.0).powf(self.n - 1.0)
    }
    /// hypot(1, a v)^(n-1) (q + n (1 - q)), q = 1 / (1 + (a v)²).
    #[inline]
    fn derivative(&self, v: f64) -> f64 {
        let h = (self.a * v).hypot(1.0);
        let q = 1.0 / (h * h);
        h.powf(self.n - 1.0) * (q + self.n * (1.0 - q))
    }
    fn flow(&self, s: f64) -> TabulatedFlow<Carreau> {
        TabulatedFlow::new(*self, s)
    }
    fn description(&self) -> &'static str {
        "Carreau, g = v [1 + (a v)²]^((n-1)/2): shear-thinning n < 1, shear-thickening n > 1"
    }
    /// g'(0) = 1 for n <= 1, g'(v_u) for n > 1 (g' is monotone in |v|).
    fn max_derivative(&self, sigma: f64) -> f64 {
        if self.n <= 1.0 {
            1.0
        } else {
            self.derivative(self.inverse(sigma))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn force_inverse_and_derivative() {
        for (n, a) in [(0.3, 1.0), (0.5, 2.0), (1.0, 1.0), (2.0, 0.5), (3.0, 1.0)] {
            let d = Carreau::new(n, a).unwrap();
            for f in [-30.0, -2.0, -0.3, 0.0, 1e-6, 0.4, 5.0, 1e3] {
                let v = d.inverse(f);
                assert!(
                    (d.force(v) - f).abs() <= 1e-13 * f.abs().max(1.0),
                    "n={n} f={f}"
                );
                assert_eq!(d.inverse(-f), -v);
            }
            for v in [-2.0, -0.3, 0.0, 0.2, 1.1] {
                let h = 1e-6;
                let fd = (d.force(v + h) - d.force(v - h)) / (2.0 * h);
                assert!((fd - d.derivative(v)).abs() < 1e-7, "n={n} v={v}");
                let x = a * v;
                let closed = (1.0 + x * x).powf(0.5 * (n - 3.0)) * (1.0 + n * x * x);
                assert!(
                    (closed - d.derivative(v)).abs() < 1e-14 * closed,
                    "n={n} v={v}"
                );
            }
        }
        let lin = Carreau::new(1.0, 3.0).unwrap();
        assert_eq!(lin.force(-0.37), -0.37);
        assert_eq!(lin.max_derivative(5.0), 1.0);
    }

    #[test]
    fn max_derivative_bounds_the_slope() {
        for (n, sigma) in [(0.5, 3.0), (1.0, 2.0), (2.0, 3.0), (0.2, 50.0)] {
            let d = Carreau::new(n, 1.0).unwrap();
            let vu = d.inverse(sigma);
            let m = d.max_derivative(sigma);
            let mut best = 0.0f64;
            for i in 0..=2000 {
                best = best.max(d.derivative(-vu + 2.0 * vu * i as f64 / 2000.0));
            }
            assert!(
                m >= best * (1.0 - 1e-14) && m <= best * (1.0 + 1e-12),
                "n={n}"
            );
        }
    }

    #[test]
    fn invalid_parameters_are_named() {
        for (n, a, key) in [
            (0.0, 1.0, "n=0"),
            (-0.5, 1.0, "n=-0.5"),
            (f64::NAN, 1.0, "n=NaN"),
            (1.0, 0.0, "a=0"),
            (1.0, f64::NEG_INFINITY, "a=-inf"),
        ] {
            let e = Carreau::new(n, a).unwrap_err().to_string();
            assert!(e.contains(key) && e.contains("> 0"), "{e}");
        }
    }
}
