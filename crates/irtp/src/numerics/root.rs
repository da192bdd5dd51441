//! Safeguarded Halley/Newton root finder for monotone functions (hand-written:
//! the exact flow inverts flow times inside the particle sampler's hot loop,
//! with a bracket and derivatives already at hand).

use super::Failure;

/// Iteration budget of [`solve_increasing`].
const MAX_ITER: usize = 200;

/// Root of an increasing function H on [lo, hi] (H(lo) ≤ 0 ≤ H(hi) is
/// assumed, not evaluated) by Halley steps (Newton when H'' = 0) from
/// `guess`, falling back to bisection whenever a step leaves the current
/// bracket. `h` returns (H, H', H''). Stops once a step is below
/// `rel_tol` |w| + `abs_tol` (1e-6 for Halley and 1e-9 for Newton leave
/// ~1e-18 |w| by cubic/quadratic convergence) or the bracket has collapsed.
/// A step that stays inside the bracket need not halve it, so convergence
/// within the budget is not guaranteed: after 200 iterations the bracket
/// width is reported as [`Failure::NotConverged`].
pub fn solve_increasing(
    h: &dyn Fn(f64) -> (f64, f64, f64),
    mut lo: f64,
    mut hi: f64,
    guess: f64,
    rel_tol: f64,
    abs_tol: f64,
) -> Result<f64, Failure> {
    let mut w = guess.clamp(lo, hi);
    for _ in 0..MAX_ITER {
        let (hv, d1, d2) = h(w);
        if hv == 0.0 {
            return Ok(w);
        }
        if hv > 0.0 {
            hi = w;
        } else {
            lo = w; // also for -∞ (u underflow) and NaN: move up
        }
        let denom = 2.0 * d1 * d1 - hv * d2;
        let step = if denom > 0.0 {
            2.0 * hv * d1 / denom
        } else {
            hv / d1
        };
        let next = w - step;
        if next > lo && next < hi {
            if step.abs() <= rel_tol * next.abs() + abs_tol {
                return Ok(next);
            }
            w = next;
        } else {
            let mid = 0.5 * (lo + hi);
            if hi - lo <= 4.0 * f64::EPSILON * lo.abs().max(hi.abs()) {
                return Ok(mid);
            }
            w = mid;
        }
    }
    Err(Failure::NotConverged {
        method: "safeguarded Halley root finder",
        iterations: MAX_ITER,
        residual: hi - lo,
        tolerance: rel_tol * w.abs() + abs_tol,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finds_roots_with_and_without_second_derivative() {
        // Halley on x³ - 2 from a poor guess.
        let h = |x: f64| (x * x * x - 2.0, 3.0 * x * x, 6.0 * x);
        let x = solve_increasing(&h, 0.0, 4.0, 3.9, 1e-6, 0.0).unwrap();
        assert!((x - 2f64.cbrt()).abs() < 1e-15, "{x}");
        // Newton (H'' = 0) on ln x - 1, guess outside the bracket gets clamped.
        let h = |x: f64| (x.ln() - 1.0, 1.0 / x, 0.0);
        let x = solve_increasing(&h, 1.0, 5.0, 100.0, 1e-9, 0.0).unwrap();
        assert!((x - std::f64::consts::E).abs() < 1e-14, "{x}");
    }

    #[test]
    fn reports_non_convergence_instead_of_the_last_iterate() {
        // A derivative 10⁶ times too large: every step stays inside the
        // bracket but shrinks the distance to the root by only 1e-6.
        let h = |x: f64| (x - 1.0, 1e6, 0.0);
        let e = solve_increasing(&h, 0.0, 4.0, 3.0, 1e-9, 0.0).unwrap_err();
        match e {
            Failure::NotConverged {
                iterations,
                residual,
                ..
            } => {
                assert_eq!(iterations, MAX_ITER);
                assert!(residual > 0.0, "{residual}");
            }
            other => panic!("{other:?}"),
        }
        // It converts into the crate error, which says which routine failed.
        let msg = crate::Error::from(e).to_string();
        assert!(
            msg.contains("Halley") && msg.contains("200 iterations"),
            "{msg}"
        );
    }
}
