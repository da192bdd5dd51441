//! Rank-2 corrections of a factored solve (bordering, the
//! Sherman-Morrison-Woodbury formula): the solvers' reset terms couple
//! every row to two reset values, which would fill a band or block
//! tridiagonal matrix; they are kept out of the factorisation and added
//! back through a 2×2 capacitance system.
//!
//! For A + U Vᵀ with U, V of two columns, w = A⁻¹ b and Z = A⁻¹ U,
//!
//!   (A + U Vᵀ)⁻¹ b = w - Z S⁻¹ Vᵀ w,   S = I + Vᵀ Z.
//!
//! The callers know more about S than the formula: its columns often sum
//! to a known number, so its diagonal and determinant can be formed as sums
//! of non-negative terms where I + Vᵀ Z would cancel (astronomically large
//! first-passage times, stiff shifts). [`Capacitance`] therefore takes S
//! and det S as the caller forms them; [`LowRank::standard`] is the plain
//! formula. The operation order is fixed, so every caller's results are
//! reproducible to the bit.

/// The 2×2 capacitance system S a = f of a [`LowRank`] correction.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Capacitance {
    /// Cramer's rule on S (row-major) with its determinant.
    Cramer {
        /// S, row-major.
        s: [[f64; 2]; 2],
        /// det S.
        det: f64,
    },
    /// S⁻¹ (row-major), formed once for many right-hand sides.
    Inverse([[f64; 2]; 2]),
}

impl Capacitance {
    /// Cramer's rule with det S = s00 s11 - s01 s10.
    pub fn new(s: [[f64; 2]; 2]) -> Self {
        let det = s[0][0] * s[1][1] - s[0][1] * s[1][0];
        Capacitance::Cramer { s, det }
    }

    /// Cramer's rule with a determinant the caller formed (without the
    /// cancellation of s00 s11 - s01 s10).
    pub fn with_det(s: [[f64; 2]; 2], det: f64) -> Self {
        Capacitance::Cramer { s, det }
    }

    /// S⁻¹ = adj(S) / det, formed once, with a determinant the caller
    /// formed.
    pub fn inverted(s: [[f64; 2]; 2], det: f64) -> Self {
        Capacitance::Inverse([
            [s[1][1] / det, -s[0][1] / det],
            [-s[1][0] / det, s[0][0] / det],
        ])
    }

    /// a = S⁻¹ f.
    #[inline]
    pub fn solve(&self, f: [f64; 2]) -> [f64; 2] {
        match self {
            Capacitance::Cramer { s, det } => [
                (f[0] * s[1][1] - s[0][1] * f[1]) / det,
                (s[0][0] * f[1] - s[1][0] * f[0]) / det,
            ],
            Capacitance::Inverse(m) => [
                m[0][0] * f[0] + m[0][1] * f[1],
                m[1][0] * f[0] + m[1][1] * f[1],
            ],
        }
    }
}

/// Z = A⁻¹ U: the base solve (in place) applied to each of U's columns.
pub fn responses(solve: impl Fn(&mut [f64]), u: [Vec<f64>; 2]) -> [Vec<f64>; 2] {
    u.map(|mut col| {
        solve(&mut col);
        col
    })
}

/// The rank-2 correction that turns the base solve w = A⁻¹ b into the
/// solve of (A + U Vᵀ) x = b (module docs).
#[derive(Clone, Debug)]
pub struct LowRank {
    z: [Vec<f64>; 2],
    s: Capacitance,
}

impl LowRank {
    /// The correction from Z = A⁻¹ U ([`responses`]) and the capacitance
    /// system as the caller formed it.
    pub fn new(z: [Vec<f64>; 2], s: Capacitance) -> Self {
        LowRank { z, s }
    }

    /// The correction with the plain capacitance S = I + Vᵀ Z (Cramer's
    /// rule); `v` maps a vector y to Vᵀ y.
    pub fn standard(z: [Vec<f64>; 2], v: impl Fn(&[f64]) -> [f64; 2]) -> Self {
        let (v0, v1) = (v(&z[0]), v(&z[1]));
        let s = [[1.0 + v0[0], v1[0]], [v0[1], 1.0 + v1[1]]];
        LowRank::new(z, Capacitance::new(s))
    }

    /// Z = A⁻¹ U.
    pub fn z(&self) -> &[Vec<f64>; 2] {
        &self.z
    }

    /// x ← x - Z S⁻¹ f. With x = A⁻¹ b on entry and f = Vᵀ x, x solves
    /// (A + U Vᵀ) x = b on return.
    #[inline]
    pub fn correct(&self, x: &mut [f64], f: [f64; 2]) {
        let a = self.s.solve(f);
        let [z0, z1] = &self.z;
        for ((xi, y0), y1) in x.iter_mut().zip(z0).zip(z1) {
            *xi -= a[0] * y0 + a[1] * y1;
        }
    }

    /// The whole solve: x ← (A + U Vᵀ)⁻¹ x, with `base` the solve by A (in
    /// place) and `v` as for [`LowRank::standard`].
    pub fn solve(&self, base: impl Fn(&mut [f64]), x: &mut [f64], v: impl Fn(&[f64]) -> [f64; 2]) {
        base(x);
        let f = v(x);
        self.correct(x, f);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A diagonal A plus two dense rank-1 terms against a dense solve.
    #[test]
    fn corrects_a_diagonal_solve() {
        let n = 6;
        let d: Vec<f64> = (0..n).map(|i| 2.0 + i as f64).collect();
        let u = [
            (0..n).map(|i| 0.1 * i as f64).collect::<Vec<_>>(),
            (0..n).map(|i| 0.3 - 0.05 * i as f64).collect(),
        ];
        let v = |y: &[f64]| [y[1] + 0.5 * y[4], y.iter().sum::<f64>() * 0.2];
        let base = |y: &mut [f64]| {
            for (yi, di) in y.iter_mut().zip(&d) {
                *yi /= di;
            }
        };
        let b: Vec<f64> = (0..n).map(|i| 1.0 - 0.1 * i as f64).collect();
        let low = LowRank::standard(responses(base, u.clone()), v);
        let mut x = b.clone();
        low.solve(base, &mut x, v);
        // Residual of (A + U Vᵀ) x = b.
        let vx = v(&x);
        for i in 0..n {
            let r = d[i] * x[i] + u[0][i] * vx[0] + u[1][i] * vx[1] - b[i];
            assert!(r.abs() < 1e-14, "row {i}: {r}");
        }
        // The inverse form gives the same solution.
        let s = [
            [1.0 + v(&low.z()[0])[0], v(&low.z()[1])[0]],
            [v(&low.z()[0])[1], 1.0 + v(&low.z()[1])[1]],
        ];
        let det = s[0][0] * s[1][1] - s[0][1] * s[1][0];
        let inv = LowRank::new(low.z().clone(), Capacitance::inverted(s, det));
        let mut y = b;
        inv.solve(base, &mut y, v);
        for (x, y) in x.iter().zip(&y) {
            assert!((x - y).abs() < 1e-15);
        }
    }
}
