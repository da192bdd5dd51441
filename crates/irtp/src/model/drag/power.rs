//! g(v) = k sign(v) |v|^n: the power-law (Ostwald-de Waele) medium,
//! shear-thinning for n < 1, Newtonian (k v) for n = 1, shear-thickening for
//! n > 1. Written `power:n=N,k=K` (k defaults to 1).
//!
//! For n < 1 the slope g'(v) = k n |v|^(n-1) is infinite at v = 0, while the
//! drift Sigma - g(v) stays bounded and continuous. What each method does
//! with that:
//! - [`Drag::max_derivative`] is honestly +∞ for n < 1.
//! - The Euler scheme does not need a bounded slope: it needs the step to
//!   keep the velocity inside (v_l, v_u), which holds exactly when
//!   dt < 1 / (the largest secant slope (Sigma - g(v)) / (v_u - v) over
//!   v ∈ [v_l, v_u)), finite for every n ([`Drag::euler_slope`], solved in
//!   closed form below). Near v = 0 its local error is then of lower order
//!   (g is only Hölder continuous there), which the particle crosses in a
//!   time of order dt; the bias stays O(dt) in practice and is measured
//!   against the Fokker-Planck solver (the conformance suite,
//!   `crates/irtp/tests/it/conformance.rs`).
//! - The exact flow is tabulated ([`TabulatedFlow`]), whose table has a
//!   break at v = 0 and refines adaptively into the |v|^n kink there; the
//!   exact sampler's potential table ([`super::PotentialTable`]) makes the
//!   kink a cell boundary and resolves it in a stretched variable.
//! - The Fokker-Planck mesh is graded at the edges ±v_u, where
//!   g'(v_u) = k n v_u^(n-1) is finite (the edge exponent
//!   (lambda + r) / g'(v_u) - 1 is finite likewise), and, for n < 1, towards
//!   a node at v = 0 with |v| ~ s^(1/n): the state densities have a |v|^n
//!   kink there, smooth in g, which that grading resolves at first order
//!   ([`crate::fp::Mesh::Graded`]).

use super::spec::{self, Key, ParamLaw};
use super::{Drag, TabulatedFlow};
use crate::error::Result;

/// g(v) = k sign(v) |v|^n, n > 0, k > 0, unbounded: any Sigma > 0,
/// v_u = (Sigma / k)^(1/n).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Power {
    n: f64,
    k: f64,
}

impl Power {
    /// The law with flow index `n` and consistency `k`, both finite and > 0.
    pub fn new(n: f64, k: f64) -> Result<Self> {
        Ok(Power {
            n: spec::positive::<Power>("n", n)?,
            k: spec::positive::<Power>("k", k)?,
        })
    }
    /// The flow index n.
    pub fn n(&self) -> f64 {
        self.n
    }
    /// The consistency k.
    pub fn k(&self) -> f64 {
        self.k
    }
}

impl ParamLaw for Power {
    const KEYS: &'static [Key] = &[
        Key {
            name: "n",
            default: None,
            meaning: "flow index n > 0, finite (n < 1 shear-thinning, n > 1 shear-thickening)",
        },
        Key {
            name: "k",
            default: Some(1.0),
            meaning: "consistency k > 0, finite",
        },
    ];
    fn from_values(values: &[f64]) -> Result<Self> {
        Power::new(values[0], values[1])
    }
    fn values(&self) -> Vec<f64> {
        vec![self.n, self.k]
    }
    fn example() -> Self {
        Power { n: 0.5, k: 1.0 }
    }
}

impl Drag for Power {
    type Flow = TabulatedFlow<Power>;

    fn name(&self) -> &'static str {
        "power"
    }
    #[inline]
    fn force(&self, v: f64) -> f64 {
        (self.k * v.abs().powf(self.n)).copysign(v)
    }
    /// k n |v|^(n-1): +∞ at v = 0 for n < 1, k for n = 1, 0 for n > 1.
    #[inline]
    fn derivative(&self, v: f64) -> f64 {
        self.k * self.n * v.abs().powf(self.n - 1.0)
    }
    fn flow(&self, s: f64) -> TabulatedFlow<Power> {
        TabulatedFlow::new(*self, s)
    }
    fn description(&self) -> &'static str {
        "power law, g = k sign(v)|v|^n: shear-thinning n < 1, shear-thickening n > 1"
    }
    /// (|f| / k)^(1/n) sign f, exactly odd.
    #[inline]
    fn inverse(&self, f: f64) -> f64 {
        (f.abs() / self.k).powf(1.0 / self.n).copysign(f)
    }
    /// g' is monotone in |v|: k n v_u^(n-1) at the edges for n >= 1; for
    /// n < 1 it is unbounded at v = 0 and this is +∞.
    fn max_derivative(&self, sigma: f64) -> f64 {
        if self.n < 1.0 {
            f64::INFINITY
        } else {
            self.derivative(self.inverse(sigma))
        }
    }
    /// For n >= 1, g'(v_u) (g is convex on v > 0, so no secant is steeper).
    /// For n < 1, in x = v / v_u the secant slope is
    /// (Sigma / v_u) (1 - sign(x)|x|^n) / (1 - x): at most 1 on [0, 1)
    /// (chords of the concave x^n), and on x = -y < 0 it is
    /// φ(y) = (1 + y^n) / (1 + y), largest at the one root of
    /// φ'(y) ∝ n y^(n-1) - 1 - (1 - n) y^n (strictly decreasing, > 0 as
    /// y → 0, 2n - 2 < 0 at y = 1), found by bisection. A relative margin of
    /// 1e-12 covers the rounding of the root and of Sigma / v_u.
    fn euler_slope(&self, sigma: f64) -> f64 {
        if self.n >= 1.0 {
            return self.max_derivative(sigma);
        }
        let n = self.n;
        let dphi = |y: f64| n * y.powf(n - 1.0) - 1.0 - (1.0 - n) * y.powf(n);
        let (mut lo, mut hi) = (0.0f64, 1.0f64);
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            if mid <= lo || mid >= hi {
                break;
            }
            if dphi(mid) > 0.0 {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        let phi = |y: f64| (1.0 + y.powf(n)) / (1.0 + y);
        let best = phi(lo).max(phi(hi)).max(1.0);
        (1.0 + 1e-12) * best * sigma / self.inverse(sigma)
    }
    /// s - g(v* - u) = -s expm1(n ln(1 - u/v*)) while v* - u keeps the sign
    /// of v* (no cancellation as u → 0), the plain difference beyond.
    #[inline]
    fn drift_at_distance(&self, s: f64, u: f64) -> f64 {
        let vs = self.inverse(s);
        let x = u / vs;
        if vs != 0.0 && x < 0.5 {
            -s * (self.n * (-x).ln_1p()).exp_m1()
        } else {
            s - self.force(vs - u)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn law(n: f64) -> Power {
        Power::new(n, 1.7).unwrap()
    }

    #[test]
    fn inverse_and_derivative() {
        for n in [0.3, 0.5, 1.0, 2.0, 3.5] {
            let d = law(n);
            for f in [-40.0, -2.0, -0.3, 0.0, 1e-6, 0.4, 5.0, 1e3] {
                let v = d.inverse(f);
                assert!(
                    (d.force(v) - f).abs() <= 1e-13 * f.abs().max(1.0),
                    "n={n} f={f}"
                );
                assert_eq!(d.inverse(-f), -v);
            }
            for v in [-2.0, -0.3, 0.2, 1.1] {
                let h = 1e-6;
                let fd = (d.force(v + h) - d.force(v - h)) / (2.0 * h);
                assert!(
                    (fd - d.derivative(v)).abs() < 1e-7 * d.derivative(v),
                    "n={n} v={v}"
                );
            }
        }
        assert_eq!(law(0.5).derivative(0.0), f64::INFINITY);
        assert_eq!(law(2.0).derivative(0.0), 0.0);
        assert_eq!(Power::new(1.0, 1.0).unwrap().force(-0.3), -0.3);
    }

    /// The secant bound is the largest secant slope: checked on a fine grid,
    /// it is above every sampled secant and within 2e-5 of the largest (for
    /// n >= 1 the supremum is the limit at v_u, a grid step away).
    #[test]
    fn euler_slope_is_the_largest_secant() {
        for (n, sigma) in [(0.2, 3.0), (0.5, 3.0), (0.8, 0.4), (1.0, 2.0), (2.0, 3.0)] {
            let d = law(n);
            let vu = d.inverse(sigma);
            let m = d.euler_slope(sigma);
            let mut best = 0.0f64;
            for i in 0..200_000 {
                let v = -vu + 2.0 * vu * i as f64 / 200_000.0;
                best = best.max((sigma - d.force(v)) / (vu - v));
            }
            // (sampled secants near v_u carry rounding of 1e-9 relative)
            assert!(
                m >= best * (1.0 - 1e-9) && m <= best * (1.0 + 2e-5),
                "n={n}: {m} vs {best}"
            );
            assert!(m <= d.max_derivative(sigma), "n={n}");
        }
        assert!(law(0.5).max_derivative(3.0).is_infinite());
    }

    #[test]
    fn drift_at_distance_matches_difference() {
        for n in [0.3, 0.5, 2.0] {
            let d = law(n);
            for s in [3.0, -0.7] {
                let vs = d.inverse(s);
                for u in [1e-3, 0.1, 0.45, 0.7, 1.5] {
                    let u = u * vs;
                    let plain = s - d.force(vs - u);
                    let acc = d.drift_at_distance(s, u);
                    assert!((acc - plain).abs() < 1e-13 * s.abs(), "n={n} s={s} u={u}");
                }
                let tiny = 1e-12 * vs;
                let lin = d.derivative(vs) * tiny;
                assert!((d.drift_at_distance(s, tiny) / lin - 1.0).abs() < 1e-9);
            }
        }
    }

    #[test]
    fn invalid_parameters_are_named() {
        for (n, k, key) in [
            (0.0, 1.0, "n=0"),
            (-1.0, 1.0, "n=-1"),
            (f64::NAN, 1.0, "n=NaN"),
            (f64::INFINITY, 1.0, "n=inf"),
            (1.0, 0.0, "k=0"),
            (1.0, -2.0, "k=-2"),
        ] {
            let e = Power::new(n, k).unwrap_err().to_string();
            assert!(e.contains(key) && e.contains("> 0"), "{e}");
        }
    }
}
