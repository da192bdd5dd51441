//! Statistics shared by the tests: the Bonferroni z bound.

/// z bound for m simultaneous two-sided comparisons at the family rate of
/// one 4-sigma comparison (6.3e-5, Bonferroni), by bisection on erfc.
pub fn bonferroni_z(m: usize) -> f64 {
    let tail = |z: f64| m as f64 * erfc(z / std::f64::consts::SQRT_2);
    let family = erfc(4.0 / std::f64::consts::SQRT_2);
    let (mut lo, mut hi) = (3.0, 9.0);
    for _ in 0..100 {
        let mid = 0.5 * (lo + hi);
        if tail(mid) > family {
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
