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
