//! Extrapolation over nested meshes N/4, N/2, N and its error estimates
//! (docs/equations.md Eq. (N27)).

/// Richardson extrapolation of a value on meshes N/4, N/2, N with the
/// observed order (Eq. (N27)): (value, error estimate, order). Where the
/// differences do not shrink like h^p with 1/2 ≤ p ≤ 3 the fine value is
/// returned with twice its last change as the estimate (order NaN).
pub(crate) fn richardson(x0: f64, x1: f64, x2: f64) -> (f64, f64, f64) {
    let (d0, d1) = (x1 - x0, x2 - x1);
    let floor = 1e-14 * x2.abs();
    if d1.abs() <= floor {
        return (x2, d1.abs().max(d0.abs()).max(floor), f64::NAN);
    }
    let rho = d0 / d1;
    if (1.4..=8.0).contains(&rho) {
        let corr = d1 / (rho - 1.0);
        (x2 + corr, corr.abs().max(floor), rho.log2())
    } else {
        (x2, 2.0 * d1.abs(), f64::NAN)
    }
}

/// Error estimate of the first-order extrapolation E₁ = 2 x₂ - x₁ from
/// the values x₀, x₁, x₂ on the meshes N/4, N/2, N. With x_h = x + a h +
/// b h², E₁ - x = -2 b h² and E₀ = 2 x₁ - x₀ has 4 times that error, so
/// |E₁ - E₀| is 3 times E₁'s error. Where the changes d₀ = x₁ - x₀,
/// d₁ = x₂ - x₁ shrink like h^p with 1/2 <= p <= 3 (1.4 <= d₀/d₁ <= 8,
/// the N-state solver's check, Eq. (N27)) the estimate is 2 |E₁ - E₀|
/// (6 times the model's error: E₀'s error may pass near 0 where the
/// density has a kink between nodes, at v_r); otherwise (not yet
/// asymptotic) 2 |d₁| + 2 |E₁ - E₀|. Never below 1e-14 |x₂|.
pub fn extrapolation_error(x0: f64, x1: f64, x2: f64) -> f64 {
    let (d0, d1) = (x1 - x0, x2 - x1);
    let gap = ((2.0 * x2 - x1) - (2.0 * x1 - x0)).abs();
    let floor = 1e-14 * x2.abs();
    let rho = d0 / d1;
    let est = if (1.4..=8.0).contains(&rho) {
        2.0 * gap
    } else {
        2.0 * (d1.abs() + gap)
    };
    est.max(floor)
}
