//! Fast, platform-independent kernels of the elementary functions the Euler
//! kernel evaluates every step. Hand-written because the platform libm `tan`
//! costs ~18 ns and dominates the Euler step (the linear-drag step costs
//! ~4 ns); these are ~3x faster and identical on every platform (bit
//! reproducibility across libms).

/// tan(x), Cephes algorithm (Moshier): Cody-Waite reduction by π/4 in three
/// parts, then tan z ≈ z + z³ P(z²)/Q(z²) on |z| ≤ π/4, and -1/tan for the
/// odd octants. Relative error ≲ 3 ulp (tested against `f64::tan` below);
/// NaN for |x| ≥ 2³⁰, ±∞ and NaN (where the reduction would lose accuracy;
/// no drag law evaluates tan there: the velocity stays below π/2).
///
/// Hand-written because the platform libm `tan` costs ~18 ns and dominates
/// the Euler step (the linear-drag step costs ~4 ns), and written without
/// branches or calls (integer octant, one division for both the tan and the
/// -1/tan branch, selects instead of jumps) so that the Euler kernel's lanes
/// vectorise with plain SSE2; identical on every platform (bit
/// reproducibility across libms).
#[inline(always)]
#[allow(clippy::excessive_precision)] // Cephes coefficients quoted verbatim
pub fn tan(xx: f64) -> f64 {
    const P: [f64; 3] = [
        -1.309_369_391_813_837_776_46e4,
        1.153_516_648_385_874_161_40e6,
        -1.795_652_519_764_848_779_88e7,
    ];
    const Q: [f64; 4] = [
        1.368_129_634_706_929_546_78e4,
        -1.320_892_344_402_109_674_47e6,
        2.500_838_018_233_579_158_39e7,
        -5.386_957_559_294_546_298_81e7,
    ];
    const DP1: f64 = 7.853_981_554_508_209_228_515_625e-1;
    const DP2: f64 = 7.946_627_356_147_928_367_14e-9;
    const DP3: f64 = 3.061_616_997_868_382_943_07e-17;
    const LIMIT: f64 = 1.073_741_824e9;
    let x = xx.abs();
    // Octant: floor(x 4/π) by truncation (x ≥ 0, and < 2³¹ where it matters;
    // `as` saturates elsewhere and the result is replaced by NaN below),
    // rounded up to even as in Cephes.
    let octant = (x * (4.0 * std::f64::consts::FRAC_1_PI)) as i32;
    let j = octant.wrapping_add(octant & 1);
    let y = j as f64;
    let z = ((x - y * DP1) - y * DP2) - y * DP3;
    let zz = z * z;
    let p = (P[0] * zz + P[1]) * zz + P[2];
    let q = (((zz + Q[0]) * zz + Q[1]) * zz + Q[2]) * zz + Q[3];
    // tan z = (z q + z zz p) / q; -1/tan z = -q / (z q + z zz p).
    let a = z * q + z * (zz * p);
    let recip = j & 2 != 0;
    let t = if recip { -q / a } else { a / q };
    let t = if xx < 0.0 { -t } else { t };
    if x < LIMIT {
        t
    } else {
        f64::NAN
    }
}

/// tanh(x) = expm1(2x) / (expm1(2x) + 2), accurate for small |x| too
/// (expm1 avoids cancellation); faster than the platform `tanh`.
#[inline(always)]
pub fn tanh(x: f64) -> f64 {
    let a = x.abs();
    if !(a < 22.0) {
        return x.tanh(); // |tanh| = 1 to double precision, or NaN
    }
    let e = (2.0 * a).exp_m1();
    let t = e / (e + 2.0);
    if x < 0.0 {
        -t
    } else {
        t
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Max relative error in units of 2^-52 against the platform libm.
    fn max_ulps(f: fn(f64) -> f64, g: fn(f64) -> f64, lo: f64, hi: f64) -> f64 {
        let n = 400_000;
        (0..=n)
            .map(|i| lo + (hi - lo) * i as f64 / n as f64)
            .map(|x| {
                let (a, b) = (f(x), g(x));
                if b == 0.0 {
                    (a - b).abs() / f64::MIN_POSITIVE
                } else {
                    ((a - b) / b).abs() / f64::EPSILON
                }
            })
            .fold(0.0, f64::max)
    }

    #[test]
    fn fast_tan_and_tanh_are_accurate() {
        let h = std::f64::consts::FRAC_PI_2;
        let tan_err = max_ulps(tan, f64::tan, -h + 1e-9, h - 1e-9);
        assert!(tan_err < 3.0, "tan: {tan_err} ulp");
        let tiny = max_ulps(tan, f64::tan, -1e-6, 1e-6);
        assert!(tiny < 2.0, "tan near 0: {tiny} ulp");
        let tanh_err = max_ulps(tanh, f64::tanh, -25.0, 25.0);
        assert!(tanh_err < 3.0, "tanh: {tanh_err} ulp");
        let tiny = max_ulps(tanh, f64::tanh, -1e-6, 1e-6);
        assert!(tiny < 3.0, "tanh near 0: {tiny} ulp");
        assert_eq!(tan(0.0), 0.0);
        assert_eq!(tanh(0.0), 0.0);
        assert!(tan(f64::NAN).is_nan() && tanh(f64::NAN).is_nan());
        assert!(tan(f64::INFINITY).is_nan() && tan(-2e9).is_nan());
        // Beyond the first period too (the reduction is general).
        let far = max_ulps(tan, f64::tan, 2.0, 1000.0);
        assert!(far < 8.0, "tan on [2, 1000]: {far} ulp");
    }
}
