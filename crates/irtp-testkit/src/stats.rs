//! Statistical bounds of the sampler tests: the 4-sigma family rate split
//! over m comparisons (Bonferroni).

/// The family rate of one two-sided 4-sigma comparison (6.3e-5).
pub fn family_rate() -> f64 {
    erfc(4.0 / std::f64::consts::SQRT_2)
}

/// z bound for m simultaneous two-sided comparisons at the family rate of
/// one 4-sigma comparison (Bonferroni), by bisection on erfc.
pub fn bonferroni_z(m: usize) -> f64 {
    upper_z(family_rate() / (2.0 * m as f64))
}

/// The upper p-quantile of chi-square with `df` degrees of freedom at the
/// 4-sigma family rate split over m tests (Wilson-Hilferty).
pub fn chi2_bonferroni(df: f64, m: usize) -> f64 {
    let z = upper_z(family_rate() / m as f64);
    df * (1.0 - 2.0 / (9.0 * df) + z * (2.0 / (9.0 * df)).sqrt()).powi(3)
}

/// z with P(Z > z) = p for a standard normal Z (bisection on erfc).
fn upper_z(p: f64) -> f64 {
    let tail = |z: f64| 0.5 * erfc(z / std::f64::consts::SQRT_2);
    let (mut lo, mut hi) = (0.0, 12.0);
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if tail(mid) > p {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    hi
}

/// erfc(x) for x >= 0 (Numerical Recipes' erfcc, relative error < 1.2e-7).
pub fn erfc(x: f64) -> f64 {
    let t = 1.0 / (1.0 + 0.5 * x);
    let p = -x * x - 1.265_512_23
        + t * (1.000_023_68
            + t * (0.374_091_96
                + t * (0.096_784_18
                    + t * (-0.186_288_06
                        + t * (0.278_868_07
                            + t * (-1.135_203_98
                                + t * (1.488_515_87 + t * (-0.822_152_23 + t * 0.170_872_77))))))));
    t * p.exp()
}
