//! Point grids with exact endpoints: linear, logarithmic (base 10) and
//! Chebyshev. Callers validate the counts and ranges (with their own
//! parameter names); these functions only place the points.

/// `n` equally spaced values from `from` to `to`, both endpoints exact.
///
/// Interior values are `(from·(n-1-i) + to·i) / (n-1)`: one division, so a
/// grid from 0 is `to·i/(n-1)` and decimal ranges mostly come out as typed
/// (0.1, 0.2, ... rather than 0.30000000000000004). `n == 1` gives `[from]`,
/// `n == 0` an empty grid.
pub fn linspace(from: f64, to: f64, n: usize) -> Vec<f64> {
    let m = n.saturating_sub(1);
    (0..n)
        .map(|i| {
            if i == 0 {
                from
            } else if i == m {
                to
            } else {
                (from * (m - i) as f64 + to * i as f64) / m as f64
            }
        })
        .collect()
}

/// `n` log-spaced values from `from` to `to` (both > 0), both endpoints
/// exact: powers of ten of [`linspace`] over the base-10 logarithms, so whole
/// decades come out as typed (0.01, not 0.010000000000000004).
pub fn logspace(from: f64, to: f64, n: usize) -> Vec<f64> {
    let m = n.saturating_sub(1);
    linspace(from.log10(), to.log10(), n)
        .into_iter()
        .enumerate()
        .map(|(i, e)| {
            if i == 0 {
                from
            } else if i == m {
                to
            } else {
                10f64.powf(e)
            }
        })
        .collect()
}

/// The `n` Chebyshev points of the first kind on the open interval
/// (`lo`, `hi`), ascending: `mid - half·cos(π(i + ½)/n)`. Interior only and
/// clustered toward the edges, where a density may be singular.
pub fn chebyshev(lo: f64, hi: f64, n: usize) -> Vec<f64> {
    let (mid, half) = (0.5 * (lo + hi), 0.5 * (hi - lo));
    (0..n)
        .map(|i| mid - half * (std::f64::consts::PI * (i as f64 + 0.5) / n as f64).cos())
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn linspace_endpoints_exact_and_decimals_as_typed() {
        assert!(linspace(0.0, 1.0, 0).is_empty());
        assert_eq!(linspace(0.3, 1.0, 1), vec![0.3]);
        assert_eq!(linspace(0.1, 0.7, 2), vec![0.1, 0.7]);
        assert_eq!(
            linspace(0.1, 0.5, 5),
            vec![0.1, 0.2, 0.3, 0.4, 0.5],
            "one division per point"
        );
        // Endpoints exact even where t·(n-1)/(n-1) would round.
        for t in [0.1, 1.0 / 3.0, 7.7, 1e-7, 123.456] {
            for n in [2, 3, 7, 101, 1000] {
                let g = linspace(-t, t, n);
                assert_eq!((g[0], g[n - 1]), (-t, t));
                assert!(g.windows(2).all(|w| w[1] > w[0]));
            }
        }
    }

    #[test]
    fn linspace_from_zero_is_one_product_one_division() {
        // The recording times of the simulations and the FP solver: t·k/(n-1).
        let (t, n) = (20.0, 201);
        let g = linspace(0.0, t, n);
        for (k, &x) in g.iter().enumerate().take(n - 1) {
            assert_eq!(x.to_bits(), (t * k as f64 / (n - 1) as f64).to_bits());
        }
    }

    #[test]
    fn logspace_decades_exact() {
        assert_eq!(logspace(0.01, 100.0, 5), vec![0.01, 0.1, 1.0, 10.0, 100.0]);
        assert_eq!(logspace(1e-3, 1e3, 7)[1..6], [1e-2, 1e-1, 1.0, 1e1, 1e2]);
        let g = logspace(0.003, 7.0, 13);
        assert_eq!((g[0], g[12]), (0.003, 7.0));
        assert!(g.windows(2).all(|w| w[1] > w[0]));
        // Constant ratio.
        let q = g[1] / g[0];
        assert!(g.windows(2).all(|w| (w[1] / w[0] / q - 1.0).abs() < 1e-12));
    }

    #[test]
    fn chebyshev_interior_ascending_symmetric() {
        let g = chebyshev(-2.0, 2.0, 9);
        assert_eq!(g.len(), 9);
        assert!(g[0] > -2.0 && g[8] < 2.0);
        assert!(g.windows(2).all(|w| w[1] > w[0]));
        for i in 0..9 {
            assert!((g[i] + g[8 - i]).abs() < 1e-15);
        }
        // Symmetric interval: exactly -hi·cos(π(i+½)/n).
        for (i, &x) in g.iter().enumerate() {
            let c = (std::f64::consts::PI * (i as f64 + 0.5) / 9.0).cos();
            assert_eq!(x.to_bits(), (-2.0 * c).to_bits());
        }
        let s = chebyshev(1.0, 3.0, 4);
        assert!(s.iter().all(|&x| x > 1.0 && x < 3.0));
    }
}
