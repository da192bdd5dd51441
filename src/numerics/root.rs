//! Safeguarded Halley/Newton root finder for monotone functions (hand-written:
//! the exact flow inverts flow times inside the particle sampler's hot loop,
//! with a bracket and derivatives already at hand).

/// Root of an increasing function H on [lo, hi] (H(lo) ≤ 0 ≤ H(hi) is
/// assumed, not evaluated) by Halley steps (Newton when H'' = 0) from
/// `guess`, falling back to bisection whenever a step leaves the current
/// bracket. `h` returns (H, H', H''). Stops once a step is below
/// `rel_tol` |w| + `abs_tol` (1e-6 for Halley and 1e-9 for Newton leave
/// ~1e-18 |w| by cubic/quadratic convergence) or the bracket has collapsed.
pub fn solve_increasing(
    h: &dyn Fn(f64) -> (f64, f64, f64),
    mut lo: f64,
    mut hi: f64,
    guess: f64,
    rel_tol: f64,
    abs_tol: f64,
) -> f64 {
    let mut w = guess.clamp(lo, hi);
    for _ in 0..200 {
        let (hv, d1, d2) = h(w);
        if hv == 0.0 {
            return w;
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
                return next;
            }
            w = next;
        } else {
            let mid = 0.5 * (lo + hi);
            if hi - lo <= 4.0 * f64::EPSILON * lo.abs().max(hi.abs()) {
                return mid;
            }
            w = mid;
        }
    }
    w
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finds_roots_with_and_without_second_derivative() {
        // Halley on x³ - 2 from a poor guess.
        let h = |x: f64| (x * x * x - 2.0, 3.0 * x * x, 6.0 * x);
        let x = solve_increasing(&h, 0.0, 4.0, 3.9, 1e-6, 0.0);
        assert!((x - 2f64.cbrt()).abs() < 1e-15, "{x}");
        // Newton (H'' = 0) on ln x - 1, guess outside the bracket gets clamped.
        let h = |x: f64| (x.ln() - 1.0, 1.0 / x, 0.0);
        let x = solve_increasing(&h, 1.0, 5.0, 100.0, 1e-9, 0.0);
        assert!((x - std::f64::consts::E).abs() < 1e-14, "{x}");
    }
}
