//! Small dense linear algebra: a 3×3 solve and the quadratic least-squares
//! fit built on it. Hand-written: fixed size, no allocation, and a fixed
//! operation order (results reproducible to the bit).

/// Solve the 3×3 system a x = b by Gaussian elimination with partial
/// pivoting. A singular `a` gives non-finite entries (no check: the
/// callers' normal equations are regular when they have three distinct
/// abscissae).
pub fn solve3(mut a: [[f64; 3]; 3], mut b: [f64; 3]) -> [f64; 3] {
    for k in 0..3 {
        let piv = (k..3)
            .max_by(|&i, &j| a[i][k].abs().total_cmp(&a[j][k].abs()))
            .expect("non-empty");
        a.swap(k, piv);
        b.swap(k, piv);
        for i in k + 1..3 {
            let f = a[i][k] / a[k][k];
            let row = a[k];
            for (x, y) in a[i][k..].iter_mut().zip(&row[k..]) {
                *x -= f * y;
            }
            b[i] -= f * b[k];
        }
    }
    let mut x = [0.0; 3];
    for i in (0..3).rev() {
        let s: f64 = (i + 1..3).map(|j| a[i][j] * x[j]).sum();
        x[i] = (b[i] - s) / a[i][i];
    }
    x
}

/// The least-squares quadratic c0 + c1 u + c2 u² through the points (u, y),
/// from the normal equations (well conditioned for u on a short interval
/// near 0); non-finite with fewer than three distinct u.
pub fn fit_quadratic(points: impl IntoIterator<Item = (f64, f64)>) -> [f64; 3] {
    let mut s = [[0.0f64; 3]; 3];
    let mut b = [0.0f64; 3];
    for (u, y) in points {
        let phi = [1.0, u, u * u];
        for i in 0..3 {
            for j in 0..3 {
                s[i][j] += phi[i] * phi[j];
            }
            b[i] += phi[i] * y;
        }
    }
    solve3(s, b)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn solves_with_pivoting() {
        // A zero leading entry needs the row interchange.
        let a = [[0.0, 2.0, 1.0], [1.0, 1.0, 0.0], [3.0, 0.0, 1.0]];
        let x = [0.5, -1.0, 2.0];
        let b = [0, 1, 2].map(|i| (0..3).map(|j| a[i][j] * x[j]).sum::<f64>());
        for (got, want) in solve3(a, b).iter().zip(&x) {
            assert!((got - want).abs() < 1e-15, "{got} vs {want}");
        }
    }

    #[test]
    fn fits_a_quadratic_exactly() {
        let c = fit_quadratic((0..20).map(|i| {
            let u = 0.01 * i as f64;
            (u, 1.0 - 2.0 * u + 0.5 * u * u)
        }));
        assert!(
            (c[0] - 1.0).abs() < 1e-12 && (c[1] + 2.0).abs() < 1e-10 && (c[2] - 0.5).abs() < 1e-8
        );
    }
}
