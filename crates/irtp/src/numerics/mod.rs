//! Small hand-written numerical kernels shared by the model (exact flow),
//! the solvers and the closed-form densities: Gauss–Kronrod quadrature, a
//! safeguarded root finder, banded LU and its low-rank corrections,
//! Chebyshev tables, fast elementary functions, point grids and validated
//! time grids.
//! Neutral ground so that `model` does not depend on `analytic`.
//!
//! Every iterative kernel reports failure ([`Failure`]) instead of returning
//! its last iterate: callers either propagate it with `?` (it converts into
//! [`crate::Error`]) or document their fallback.

pub mod band;
pub mod bordered;
pub mod chebyshev;
pub mod dense;
pub mod fastmath;
pub mod grid;
pub mod quad;
pub mod root;
pub mod time_grid;
pub mod trbdf2;

/// Why a numerical kernel gave up. Small and `Copy`, so that the exact
/// sampler's hot loop can return it at no cost; `?` turns it into
/// [`crate::Error::NotConverged`] or [`crate::Error::NonFinite`].
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
pub enum Failure {
    /// The iteration (or panel) budget ran out before the tolerance was met.
    #[error(
        "{method}: no convergence after {iterations} iterations \
         (residual {residual:e}, tolerance {tolerance:e})"
    )]
    NotConverged {
        /// Which kernel.
        method: &'static str,
        /// Iterations (root finder) or panels (quadrature) spent.
        iterations: usize,
        /// Bracket width (root finder) or error estimate (quadrature) left.
        residual: f64,
        /// The tolerance `residual` had to meet.
        tolerance: f64,
    },
    /// The integrand returned NaN or ±∞ on the panel around `at`.
    #[error("{method}: non-finite value near x = {at}")]
    NonFinite {
        /// Which kernel.
        method: &'static str,
        /// Panel midpoint.
        at: f64,
    },
}

impl Failure {
    /// `Ok` when every value of `x` is finite, else
    /// [`Failure::NonFinite`] of `method` at `at`.
    pub fn check_finite(x: &[f64], method: &'static str, at: f64) -> Result<(), Failure> {
        match x.iter().all(|v| v.is_finite()) {
            true => Ok(()),
            false => Err(Failure::NonFinite { method, at }),
        }
    }

    /// The failure of the shifted solve (M - cA) x = b of `method`
    /// ([`Failure::NonFinite`] at c): Ok(it), for the solve to report
    /// later, where c is a shift it takes (positive and finite), else
    /// Err(it).
    pub fn shifted_solve(method: &'static str, c: f64) -> Result<Failure, Failure> {
        let fail = Failure::NonFinite { method, at: c };
        match c > 0.0 && c.is_finite() {
            true => Ok(fail),
            false => Err(fail),
        }
    }

    /// The same failure attributed to `method` (a caller's name for the
    /// computation, e.g. "r0 density normalisation").
    pub fn in_method(self, method: &'static str) -> Self {
        match self {
            Failure::NotConverged {
                iterations,
                residual,
                tolerance,
                ..
            } => Failure::NotConverged {
                method,
                iterations,
                residual,
                tolerance,
            },
            Failure::NonFinite { at, .. } => Failure::NonFinite { method, at },
        }
    }
}

impl From<Failure> for crate::Error {
    fn from(f: Failure) -> Self {
        match f {
            Failure::NotConverged {
                method,
                iterations,
                residual,
                tolerance,
            } => crate::Error::NotConverged {
                method,
                iterations,
                residual,
                tolerance,
            },
            Failure::NonFinite { method, at } => crate::Error::NonFinite { method, at },
        }
    }
}
