//! Mergeable estimators: sums, counts and sums of squares, never bare means,
//! so shards of a run (threads, SLURM array tasks) combine exactly.

use serde::{Deserialize, Serialize};

/// Running sums of independent samples x_i: n, Σx, Σx².
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct MeanAcc {
    /// Number of samples.
    pub n: u64,
    /// Σ x_i.
    pub sum: f64,
    /// Σ x_i².
    pub sum_sq: f64,
}

impl MeanAcc {
    /// Empty accumulator.
    pub const fn new() -> Self {
        MeanAcc {
            n: 0,
            sum: 0.0,
            sum_sq: 0.0,
        }
    }
    /// Add one sample.
    #[inline]
    pub fn push(&mut self, x: f64) {
        self.n += 1;
        self.sum += x;
        self.sum_sq += x * x;
    }
    /// Merge another accumulator into this one.
    #[inline]
    pub fn merge(&mut self, other: &MeanAcc) {
        self.n += other.n;
        self.sum += other.sum;
        self.sum_sq += other.sum_sq;
    }
    /// Sample mean (NaN when empty).
    pub fn mean(&self) -> f64 {
        self.sum / self.n as f64
    }
    /// Unbiased sample variance (NaN for n < 2).
    pub fn variance(&self) -> f64 {
        if self.n < 2 {
            return f64::NAN;
        }
        let n = self.n as f64;
        let m = self.sum / n;
        ((self.sum_sq - n * m * m) / (n - 1.0)).max(0.0)
    }
    /// Standard error of the mean, sqrt(var/n).
    pub fn sem(&self) -> f64 {
        (self.variance() / self.n as f64).sqrt()
    }
}

/// Element-wise merge of two equally long accumulator vectors.
pub fn merge_all(into: &mut [MeanAcc], from: &[MeanAcc]) {
    assert_eq!(
        into.len(),
        from.len(),
        "merging accumulators of different shapes"
    );
    for (a, b) in into.iter_mut().zip(from) {
        a.merge(b);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mean_variance_sem() {
        let mut a = MeanAcc::new();
        for x in [1.0, 2.0, 3.0, 4.0] {
            a.push(x);
        }
        assert_eq!(a.mean(), 2.5);
        assert!((a.variance() - 5.0 / 3.0).abs() < 1e-15);
        assert!((a.sem() - (5.0 / 12.0f64).sqrt()).abs() < 1e-15);
    }

    #[test]
    fn merge_equals_sequential() {
        let xs: Vec<f64> = (0..100).map(|i| (i as f64 * 0.37).sin()).collect();
        let mut whole = MeanAcc::new();
        xs.iter().for_each(|&x| whole.push(x));
        let (mut a, mut b) = (MeanAcc::new(), MeanAcc::new());
        xs[..40].iter().for_each(|&x| a.push(x));
        xs[40..].iter().for_each(|&x| b.push(x));
        a.merge(&b);
        assert_eq!(a.n, whole.n);
        assert!((a.mean() - whole.mean()).abs() < 1e-15);
        assert!((a.variance() - whole.variance()).abs() < 1e-13);
    }
}

/// Running sums of paired samples (x_i, y_i): n, Σx, Σy, Σx², Σy², Σxy.
/// Mergeable like [`MeanAcc`]; the pairs of a control variate (x the
/// quantity sought, y a correlated quantity whose mean is known exactly).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct PairAcc {
    /// Number of pairs.
    pub n: u64,
    /// Σ x_i.
    pub sx: f64,
    /// Σ y_i.
    pub sy: f64,
    /// Σ x_i².
    pub sxx: f64,
    /// Σ y_i².
    pub syy: f64,
    /// Σ x_i y_i.
    pub sxy: f64,
}

/// A control-variate estimate of the mean of x (see [`PairAcc::controlled`]).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Controlled {
    /// x̄ - β (ȳ - μ_y).
    pub mean: f64,
    /// Its standard error.
    pub se: f64,
    /// The plain mean x̄.
    pub plain: f64,
    /// The plain mean's standard error.
    pub plain_se: f64,
    /// Sample correlation of x and y.
    pub rho: f64,
    /// Equivalent independent samples Var(x) / se²: the number of plain
    /// samples of x with the same standard error (∞ when se = 0).
    pub equivalent_samples: f64,
}

impl Controlled {
    /// No estimate: every value NaN, no equivalent samples.
    pub const NAN: Controlled = Controlled {
        mean: f64::NAN,
        se: f64::NAN,
        plain: f64::NAN,
        plain_se: f64::NAN,
        rho: f64::NAN,
        equivalent_samples: 0.0,
    };
}

impl PairAcc {
    /// Empty accumulator.
    pub const fn new() -> Self {
        PairAcc {
            n: 0,
            sx: 0.0,
            sy: 0.0,
            sxx: 0.0,
            syy: 0.0,
            sxy: 0.0,
        }
    }
    /// Add one pair.
    #[inline]
    pub fn push(&mut self, x: f64, y: f64) {
        self.n += 1;
        self.sx += x;
        self.sy += y;
        self.sxx += x * x;
        self.syy += y * y;
        self.sxy += x * y;
    }
    /// Merge another accumulator into this one.
    #[inline]
    pub fn merge(&mut self, o: &PairAcc) {
        self.n += o.n;
        self.sx += o.sx;
        self.sy += o.sy;
        self.sxx += o.sxx;
        self.syy += o.syy;
        self.sxy += o.sxy;
    }

    /// The control-variate estimate of the mean of x given the exact mean `mu_y` of
    /// y: x̄ - β (ȳ - μ_y) with the least-squares β = S_xy / S_yy (centred
    /// sums). Its variance is σ²_res / n · (1 + 1/(n - 3)), σ²_res = (S_xx -
    /// S_xy²/S_yy)/(n - 2) the residual variance of x about its regression
    /// on y; the factor is the cost of estimating β (exact for Gaussian y,
    /// Lavenberg & Welch 1981), and never below the rounding of the sums
    /// (64 ε S_xx). Needs n >= 4 (NaN otherwise). Where y does
    /// not vary (S_yy = 0) the estimate is the plain mean.
    pub fn controlled(&self, mu_y: f64) -> Controlled {
        let n = self.n as f64;
        let (mx, my) = (self.sx / n, self.sy / n);
        let cxx = (self.sxx - n * mx * mx).max(0.0);
        let cyy = (self.syy - n * my * my).max(0.0);
        let cxy = self.sxy - n * mx * my;
        let plain_se = (cxx / (n - 1.0) / n).sqrt();
        // The residual sum is a difference of sums of size cxx: below a
        // few ulps of cxx it is rounding, and is taken as that floor
        // (the standard error never claims more than the arithmetic holds).
        let floor = 64.0 * f64::EPSILON * cxx;
        let (beta, res) = if cyy > 0.0 {
            (cxy / cyy, (cxx - cxy * cxy / cyy).max(floor))
        } else {
            (0.0, cxx)
        };
        let (dof, inflation) = if cyy > 0.0 {
            (n - 2.0, 1.0 + 1.0 / (n - 3.0))
        } else {
            (n - 1.0, 1.0)
        };
        let se = (res / dof / n * inflation).sqrt();
        let valid = self.n >= 4;
        let nan_unless = |v: f64| if valid { v } else { f64::NAN };
        Controlled {
            mean: nan_unless(mx - beta * (my - mu_y)),
            se: nan_unless(se),
            plain: mx,
            plain_se: nan_unless(plain_se),
            rho: nan_unless(if cxx > 0.0 && cyy > 0.0 {
                cxy / (cxx * cyy).sqrt()
            } else {
                0.0
            }),
            equivalent_samples: nan_unless(cxx / (n - 1.0) / (se * se)),
        }
    }
}

#[cfg(test)]
mod pair_tests {
    use super::*;
    use rand::{Rng, SeedableRng};

    /// x = 2 y + e with Var(e) = 0.01 Var(y): the estimate is within 4
    /// standard errors of the truth, its standard error is the residual's
    /// (within 10 % of σ_e / √n), and it is equivalent to Var(x)/se² plain
    /// samples.
    #[test]
    fn control_variate_recovers_the_mean_with_the_residual_error() {
        let mut rng = rand_xoshiro::Xoshiro256PlusPlus::seed_from_u64(3);
        let (n, mu_y, sig_e) = (20_000u64, 1.5, 0.1);
        let mut acc = PairAcc::new();
        for _ in 0..n {
            let y: f64 = mu_y + rng.gen::<f64>() * 2.0 - 1.0; // Var(y) = 1/3
            let e = sig_e * (rng.gen::<f64>() * 2.0 - 1.0) * 3f64.sqrt();
            acc.push(2.0 * y + 0.25 + e, y);
        }
        let c = acc.controlled(mu_y);
        let truth = 2.0 * mu_y + 0.25;
        assert!((c.mean - truth).abs() < 4.0 * c.se, "{c:?}");
        let expect = sig_e / (n as f64).sqrt();
        assert!((c.se / expect - 1.0).abs() < 0.1, "{} {expect}", c.se);
        assert!(c.se < c.plain_se / 5.0, "{c:?}");
        let var_x = 4.0 / 3.0 + sig_e * sig_e;
        let neq = var_x / (c.se * c.se);
        assert!((c.equivalent_samples / neq - 1.0).abs() < 0.05, "{c:?}");
        assert!(c.rho > 0.99 && c.rho <= 1.0);
    }

    /// Constant y: the plain mean and its standard error; too few pairs: NaN.
    #[test]
    fn control_variate_degenerate_cases() {
        let mut acc = PairAcc::new();
        for x in [1.0, 2.0, 3.0, 4.0, 5.0] {
            acc.push(x, 7.0);
        }
        let c = acc.controlled(7.0);
        assert_eq!(c.mean, 3.0);
        assert!((c.se - (2.5f64 / 5.0).sqrt()).abs() < 1e-15);
        let mut few = PairAcc::new();
        few.push(1.0, 1.0);
        assert!(few.controlled(0.0).mean.is_nan());
    }
}
