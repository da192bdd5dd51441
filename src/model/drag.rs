//! Drag laws g(v) (paper Table 1) behind the [`Drag`] trait.
//!
//! Between noise flips and resets the velocity follows the deterministic flow
//! dv/dt = s - g(v) with s = ±Sigma (paper Eq. 5). Its fixed point v* = g⁻¹(s)
//! bounds the velocity: v ∈ (-g⁻¹(Sigma), g⁻¹(Sigma)) (paper Eqs. 8-10).

use serde::{Deserialize, Serialize};
use std::fmt;
use std::str::FromStr;

/// A velocity-dependent drag force g(v): odd, smooth, strictly increasing,
/// g'(v) > 0. Everything the solvers need about a medium lives here.
pub trait Drag: Copy + Send + Sync + fmt::Debug {
    /// Short name (`tan`, `tanh`, `linear`).
    fn name(&self) -> &'static str;
    /// The drag force g(v).
    fn force(&self, v: f64) -> f64;
    /// Its derivative g'(v).
    fn derivative(&self, v: f64) -> f64;
    /// The inverse g⁻¹(f): the fixed point of dv/dt = f - g(v).
    fn inverse(&self, f: f64) -> f64;
    /// sup_v g(v): the noise amplitude Sigma must stay strictly below it
    /// (1 for tanh, +∞ for tan and linear).
    fn force_limit(&self) -> f64;
    /// max of g'(v) over the admissible interval [-g⁻¹(Sigma), g⁻¹(Sigma)].
    /// Sets the Euler stability limit dt < 1/max g' and the FP CFL number.
    fn max_derivative(&self, sigma: f64) -> f64;
}

/// The drag laws shipped with irtp.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum DragLaw {
    /// g(v) = tan(v): shear-thickening medium (any Sigma > 0).
    Tan,
    /// g(v) = tanh(v): shear-thinning medium (needs 0 < Sigma < 1).
    Tanh,
    /// g(v) = v: Newtonian medium, the exactly solvable reference case.
    Linear,
}

impl DragLaw {
    /// All drag laws, for iteration in tests and sweeps.
    pub const ALL: [DragLaw; 3] = [DragLaw::Tan, DragLaw::Tanh, DragLaw::Linear];
}

impl Drag for DragLaw {
    fn name(&self) -> &'static str {
        match self {
            DragLaw::Tan => "tan",
            DragLaw::Tanh => "tanh",
            DragLaw::Linear => "linear",
        }
    }

    #[inline]
    fn force(&self, v: f64) -> f64 {
        match self {
            DragLaw::Tan => v.tan(),
            DragLaw::Tanh => v.tanh(),
            DragLaw::Linear => v,
        }
    }

    #[inline]
    fn derivative(&self, v: f64) -> f64 {
        match self {
            DragLaw::Tan => {
                let t = v.tan();
                1.0 + t * t
            }
            DragLaw::Tanh => {
                let c = v.cosh();
                1.0 / (c * c)
            }
            DragLaw::Linear => 1.0,
        }
    }

    #[inline]
    fn inverse(&self, f: f64) -> f64 {
        match self {
            DragLaw::Tan => f.atan(),
            DragLaw::Tanh => f.atanh(),
            DragLaw::Linear => f,
        }
    }

    fn force_limit(&self) -> f64 {
        match self {
            DragLaw::Tanh => 1.0,
            DragLaw::Tan | DragLaw::Linear => f64::INFINITY,
        }
    }

    fn max_derivative(&self, sigma: f64) -> f64 {
        match self {
            // g' = 1 + tan² is largest at the edges, where tan = ±Sigma.
            DragLaw::Tan => 1.0 + sigma * sigma,
            // g' = sech² is largest at v = 0.
            DragLaw::Tanh | DragLaw::Linear => 1.0,
        }
    }
}

impl fmt::Display for DragLaw {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for DragLaw {
    type Err = crate::Error;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "tan" => Ok(DragLaw::Tan),
            "tanh" => Ok(DragLaw::Tanh),
            "linear" => Ok(DragLaw::Linear),
            _ => Err(crate::Error::invalid(
                "--drag",
                s,
                "one of tan, tanh, linear",
            )),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn derivative_matches_finite_difference() {
        for d in DragLaw::ALL {
            for &v in &[-0.9, -0.3, 0.0, 0.2, 0.7] {
                let h = 1e-6;
                let fd = (d.force(v + h) - d.force(v - h)) / (2.0 * h);
                assert!((fd - d.derivative(v)).abs() < 1e-8, "{d} at {v}");
            }
        }
    }

    #[test]
    fn inverse_is_inverse() {
        for d in DragLaw::ALL {
            for &f in &[-0.9, -0.1, 0.0, 0.4, 0.95] {
                assert!((d.force(d.inverse(f)) - f).abs() < 1e-14);
            }
        }
    }

    #[test]
    fn max_derivative_bounds_derivative_on_interval() {
        for (d, sigma) in [
            (DragLaw::Tan, 3.0),
            (DragLaw::Tanh, 0.6),
            (DragLaw::Linear, 2.0),
        ] {
            let vu = d.inverse(sigma);
            let m = d.max_derivative(sigma);
            for i in 0..=100 {
                let v = -vu + 2.0 * vu * i as f64 / 100.0;
                assert!(d.derivative(v) <= m * (1.0 + 1e-12));
            }
        }
    }
}
