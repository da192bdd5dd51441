//! The cusp of the stationary velocity density at the reset velocity
//! v_r = 0 (paper Eq. (18)), and its measurement on a computed density.
//!
//! With Poisson resetting to v_r = 0 the reset flux r/2 enters each noise
//! state at v = 0. The stationary equations, integrated across v = 0, make
//! the density P = P+ + P- continuous there (g(0) = 0 and the ± injections
//! are symmetric) but its slope jumps:
//!
//!   P'(0+) - P'(0-) = -r (2λ + r - g'(0)) / Σ².
//!
//! The jump is negative (a peak) whenever 2λ + r > g'(0).

use crate::model::{Drag, Params};
use crate::numerics::dense::fit_quadratic;

/// The exact slope jump P'(0+) - P'(0-) of the stationary density at the
/// reset velocity (module docs). Assumes the paper's protocol: a Poisson
/// clock, a point target v_r = 0 and no refractory period (the noise rule
/// at a reset does not matter there, by symmetry); for other rules the
/// number is not the cusp of their density.
pub fn slope_jump(p: &Params) -> f64 {
    let r = p.rate();
    -r * (2.0 * p.lambda() + r - p.drag().derivative(0.0)) / (p.sigma() * p.sigma())
}

/// One-sided slopes (P'(0-), P'(0+)) of a sampled density (`p` at the
/// velocities `v`) from quadratic least-squares fits on [lo, hi] and
/// [-hi, -lo], away from the kink at 0 that a mesh does not resolve: the
/// estimate that [`slope_jump`] is compared with.
pub fn one_sided_slopes(v: &[f64], p: &[f64], lo: f64, hi: f64) -> (f64, f64) {
    let fit = |sign: f64| {
        // Fit p = c0 + c1 u + c2 u² with u = sign * v in [lo, hi].
        let points = v
            .iter()
            .zip(p)
            .map(|(&vv, &pp)| (sign * vv, pp))
            .filter(|&(u, _)| u >= lo && u <= hi);
        sign * fit_quadratic(points)[1]
    };
    (fit(-1.0), fit(1.0))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::model::DragLaw;

    #[test]
    fn slopes_of_a_kink() {
        let v: Vec<f64> = (0..401).map(|i| -1.0 + i as f64 / 200.0).collect();
        let p: Vec<f64> = v
            .iter()
            .map(|v| 1.0 - 2.0 * v.abs() + 0.5 * v * v)
            .collect();
        let (l, r) = one_sided_slopes(&v, &p, 0.02, 0.3);
        assert!((l - 2.0).abs() < 1e-9 && (r + 2.0).abs() < 1e-9, "{l} {r}");
    }

    #[test]
    fn jump_sign() {
        let p = Params::new(DragLaw::Tan, 3.0, 0.9, 5.0, 0.0).unwrap();
        assert!((slope_jump(&p) + 5.0 * (1.8 + 5.0 - 1.0) / 9.0).abs() < 1e-12);
    }
}
