//! Banded LU factorisation with partial pivoting (LINPACK's `dgbfa`/`dgbsl`
//! layout), for the first-passage solvers' interleaved two-state meshes.
//!
//! Hand-written rather than taken from a crate: the matrices have 2 sub-
//! and 2 super-diagonals and O(10⁵) rows, where a dense or sparse general
//! solver would be far slower, and no banded solver is in the dependency
//! tree. Partial pivoting is kept: the box-scheme rows of the backward
//! equations weigh a cell's two nodes by ±a - h(λ + r)/2 and are not
//! diagonally dominant, so elimination without row interchanges is not
//! safe there; the interchanges stay within the band (fill of at most `kl`
//! extra super-diagonals). The operation order is fixed (row by row, left
//! to right), so results are reproducible to the bit.
//!
//! The storage of a dropped matrix is kept for the next one built on the
//! same thread ([`Band::new`]): solvers that factor one mesh after another
//! (a rate optimisation solves the same few shapes dozens of times) then
//! neither allocate nor page-fault fresh memory for each.

use std::cell::{Cell, RefCell};
use std::ops::RangeInclusive;

thread_local! {
    /// Floating-point operations of the factorisations and solves run on
    /// this thread so far (see [`work_done`]).
    static WORK: Cell<f64> = const { Cell::new(0.0) };
}

/// Floating-point operations counted by [`Band::factor`] (2 per
/// multiply-subtract actually performed, 1 per multiplier) and
/// [`Band::solve`] (2 per multiply-subtract) on the calling thread since it
/// started: a solver reads it before and after its work to report what it
/// did, to compare with its cost estimate.
pub fn work_done() -> f64 {
    WORK.with(|w| w.get())
}

fn count(flops: f64) {
    WORK.with(|w| w.set(w.get() + flops));
}

thread_local! {
    /// The storage of band matrices dropped on this thread, at most
    /// [`SPARES`], for [`Band::new`] to reuse.
    static SPARE: RefCell<Vec<Vec<f64>>> = const { RefCell::new(Vec::new()) };
}

/// Dropped storages kept per thread (the largest): a backward solve's
/// meshes come in a few sizes, each factored and dropped before the next,
/// so the largest serves them all.
const SPARES: usize = 1;

/// The largest storage kept (values; 64 MiB): a solve's larger matrix
/// is freed when dropped, so a long-lived process (a Python session)
/// holds at most this much per thread after its solves.
const SPARE_MAX_LEN: usize = 1 << 23;

/// Zeroed storage of `len` values: the smallest spare that holds them,
/// else a fresh allocation, the spares (all too small) freed first. A
/// thread so holds, besides its live matrices, at most [`SPARES`] storages
/// of at most [`SPARE_MAX_LEN`] values each.
fn storage(len: usize) -> Vec<f64> {
    let spare = SPARE.try_with(|s| {
        let mut s = s.try_borrow_mut().ok()?;
        let fits = (0..s.len())
            .filter(|&i| s[i].capacity() >= len)
            .min_by_key(|&i| s[i].capacity());
        match fits {
            Some(i) => Some(s.swap_remove(i)),
            None => {
                s.clear();
                None
            }
        }
    });
    match spare.ok().flatten() {
        Some(mut a) => {
            a.clear();
            a.resize(len, 0.0);
            a
        }
        None => vec![0.0; len],
    }
}

/// Keep `a` for [`storage`] (unless larger than [`SPARE_MAX_LEN`]), the
/// smallest spare dropped beyond [`SPARES`].
fn keep(a: Vec<f64>) {
    if a.capacity() == 0 || a.capacity() > SPARE_MAX_LEN {
        return;
    }
    let _ = SPARE.try_with(|s| {
        let Ok(mut s) = s.try_borrow_mut() else {
            return;
        };
        s.push(a);
        if s.len() > SPARES {
            let i = (0..s.len())
                .min_by_key(|&i| s[i].capacity())
                .expect("more than SPARES spares");
            s.swap_remove(i);
        }
    });
}

/// A zero or non-finite pivot: the matrix is singular (or overflowed) at
/// this row of the elimination.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
#[error("singular band matrix at row {row}")]
pub struct Singular {
    /// Elimination step at which no usable pivot was found.
    pub row: usize,
}

impl Singular {
    /// This failure as the library's error in `method`:
    /// [`crate::Error::Interrupted`] when a stop request ended the
    /// factorisation (see [`Band::factor`]), else
    /// [`crate::Error::Numerical`] giving `reason`.
    pub fn into_error(self, method: &'static str, reason: String) -> crate::Error {
        if crate::stop::stop_requested() {
            return crate::Error::Interrupted;
        }
        crate::Error::Numerical { method, reason }
    }
}

/// Rows eliminated between two polls of the stop request: one relaxed load
/// per block, against kl·(kl + ku) flops a row.
pub const STOP_POLL_ROWS: usize = 256;

/// Rows substituted between two polls of the stop request in
/// [`Band::solve`] (a few flops a row).
pub const STOP_POLL_SOLVE_ROWS: usize = 1 << 14;

/// An n×n band matrix with `kl` sub- and `ku` super-diagonals, stored by
/// rows with room for the `kl` extra super-diagonals that pivoting fills
/// in; [`Band::factor`] overwrites it with its LU factors. Its storage is
/// kept for reuse on the thread that drops it (module docs).
#[derive(Clone, Debug)]
pub struct Band {
    n: usize,
    kl: usize,
    ku: usize,
    w: usize,
    a: Vec<f64>,
    piv: Vec<usize>,
}

impl Band {
    /// The zero n×n matrix with `kl` sub- and `ku` super-diagonals, in the
    /// storage of one dropped earlier on this thread where one fits (every
    /// entry set to zero all the same).
    pub fn new(n: usize, kl: usize, ku: usize) -> Self {
        let w = 2 * kl + ku + 1;
        Band {
            n,
            kl,
            ku,
            w,
            a: storage(n * w),
            piv: vec![0; n],
        }
    }

    /// Number of rows (and columns).
    pub fn dim(&self) -> usize {
        self.n
    }

    #[inline]
    fn idx(&self, i: usize, j: usize) -> usize {
        debug_assert!(j + self.kl >= i && j <= i + self.ku + self.kl);
        i * self.w + (j + self.kl - i)
    }

    /// Set entry (i, j), |i - j| within the band.
    #[inline]
    pub fn set(&mut self, i: usize, j: usize, x: f64) {
        let k = self.idx(i, j);
        self.a[k] = x;
    }

    /// Entry (i, j) of an unfactored matrix, |i - j| within the band.
    #[inline]
    pub fn get(&self, i: usize, j: usize) -> f64 {
        self.a[self.idx(i, j)]
    }

    /// The columns j of row i inside the band (unfactored).
    pub fn row_range(&self, i: usize) -> RangeInclusive<usize> {
        i.saturating_sub(self.kl)..=(i + self.ku).min(self.n - 1)
    }

    /// LU-factor in place (Gaussian elimination with partial pivoting
    /// within the band); [`Singular`] at the first zero or non-finite pivot.
    /// A stop request ([`crate::stop::stop_requested`], polled every
    /// [`STOP_POLL_ROWS`] rows) ends it early with [`Singular`] at the row
    /// reached: the factors are then unusable, and the caller that asked
    /// to stop discards the run.
    pub fn factor(&mut self) -> Result<(), Singular> {
        let (n, kl, ku) = (self.n, self.kl, self.ku);
        let mut flops = 0.0;
        for k in 0..n {
            if k % STOP_POLL_ROWS == 0 {
                count(std::mem::take(&mut flops));
                if crate::stop::stop_requested() {
                    return Err(Singular { row: k });
                }
            }
            let last = (k + kl).min(n - 1);
            let mut p = k;
            let mut best = self.a[self.idx(k, k)].abs();
            for i in k + 1..=last {
                let x = self.a[self.idx(i, k)].abs();
                if x > best {
                    best = x;
                    p = i;
                }
            }
            if !(best > 0.0) || !best.is_finite() {
                count(flops);
                return Err(Singular { row: k });
            }
            self.piv[k] = p;
            let jmax = (k + ku + kl).min(n - 1);
            if p != k {
                for j in k..=jmax {
                    let (x, y) = (self.idx(k, j), self.idx(p, j));
                    self.a.swap(x, y);
                }
            }
            flops += self.eliminate(k, last, jmax);
        }
        count(flops);
        Ok(())
    }

    /// Eliminate column k from rows k+1..=last (columns up to `jmax`),
    /// storing the multipliers in place of the eliminated entries; returns
    /// the floating-point operations done.
    #[inline]
    fn eliminate(&mut self, k: usize, last: usize, jmax: usize) -> f64 {
        let (w, kl) = (self.w, self.kl);
        // Row k's columns k..=jmax are contiguous in its storage, and every
        // row below starts after row k's storage ends: split there, so the
        // update of row i runs over two plain slices (no index arithmetic,
        // no bounds checks in the loop; the same operations in any order,
        // each entry's own a_ij - l a_kj).
        let (above, below) = self.a.split_at_mut((k + 1) * w);
        let row_k = &above[k * w + kl..k * w + kl + 1 + (jmax - k)];
        let d = row_k[0];
        let pivot_row = &row_k[1..];
        let mut flops = 0.0;
        for i in k + 1..=last {
            // Entry (i, j) of row i sits at i w + j + kl - i (see `idx`).
            let at = (i - k - 1) * w + kl + k - i;
            let l = below[at] / d;
            below[at] = l;
            flops += 1.0;
            if l != 0.0 {
                flops += 2.0 * (jmax - k) as f64;
                let row_i = &mut below[at + 1..at + 1 + (jmax - k)];
                for (x, y) in row_i.iter_mut().zip(pivot_row) {
                    *x -= l * y;
                }
            }
        }
        flops
    }

    /// [`Band::factor`] with its failure as the library's error in `method`
    /// ([`Singular::into_error`], the reason naming the row).
    pub fn factor_for(&mut self, method: &'static str) -> crate::Result<()> {
        self.factor()
            .map_err(|e| e.into_error(method, e.to_string()))
    }

    /// Solve A x = b in place with the factors of [`Band::factor`]. A stop
    /// request (polled every [`STOP_POLL_SOLVE_ROWS`] rows) ends it early
    /// with `b` unfinished, for the caller that asked to stop to discard.
    #[allow(clippy::needless_range_loop)] // index form mirrors the band algebra
    pub fn solve(&self, b: &mut [f64]) {
        let (n, kl, ku) = (self.n, self.kl, self.ku);
        // Full rows but near the end: 2 (kl + kl + ku) + 1 a row.
        count(n as f64 * (2.0 * (2 * kl + ku) as f64 + 1.0));
        for k in 0..n {
            if k % STOP_POLL_SOLVE_ROWS == 0 && crate::stop::stop_requested() {
                return;
            }
            b.swap(k, self.piv[k]);
            let bk = b[k];
            let last = (k + kl).min(n - 1);
            if last > k {
                // Column k below the diagonal: entry (i, k) at i (w - 1) + k + kl.
                let first = (k + 1) * (self.w - 1) + k + kl;
                let col = self.a[first..].iter().step_by(self.w - 1);
                for (bi, a) in b[k + 1..=last].iter_mut().zip(col) {
                    *bi -= a * bk;
                }
            }
        }
        for k in (0..n).rev() {
            if k % STOP_POLL_SOLVE_ROWS == 0 && crate::stop::stop_requested() {
                return;
            }
            // Row k's entries k..=jmax are contiguous (see `idx`); the sum
            // runs left to right as before.
            let jmax = (k + ku + kl).min(n - 1);
            let row = &self.a[k * self.w + kl..k * self.w + kl + 1 + (jmax - k)];
            let mut s = b[k];
            for (a, x) in row[1..].iter().zip(&b[k + 1..=jmax]) {
                s -= a * x;
            }
            b[k] = s / row[0];
        }
    }
}

impl Drop for Band {
    fn drop(&mut self) {
        keep(std::mem::take(&mut self.a));
    }
}

#[cfg(test)]
mod tests {
    // The dense reference solve and the copy read as the textbook loops.
    #![allow(clippy::needless_range_loop)]
    use super::*;

    /// Dense Gaussian elimination with partial pivoting, the reference.
    fn dense_solve(mut a: Vec<Vec<f64>>, mut b: Vec<f64>) -> Vec<f64> {
        let n = b.len();
        for k in 0..n {
            let p = (k..n)
                .max_by(|&i, &j| a[i][k].abs().total_cmp(&a[j][k].abs()))
                .unwrap();
            a.swap(k, p);
            b.swap(k, p);
            for i in k + 1..n {
                let f = a[i][k] / a[k][k];
                for j in k..n {
                    a[i][j] -= f * a[k][j];
                }
                b[i] -= f * b[k];
            }
        }
        let mut x = vec![0.0; n];
        for i in (0..n).rev() {
            let s: f64 = (i + 1..n).map(|j| a[i][j] * x[j]).sum();
            x[i] = (b[i] - s) / a[i][i];
        }
        x
    }

    /// A pseudo-random band matrix (entries in [-1, 1), a weak diagonal so
    /// that pivoting is exercised) and its dense copy.
    fn matrix(n: usize, kl: usize, ku: usize, diag: f64) -> (Band, Vec<Vec<f64>>) {
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 52) as f64 - 1.0
        };
        let mut band = Band::new(n, kl, ku);
        let mut dense = vec![vec![0.0; n]; n];
        for i in 0..n {
            for j in band.row_range(i) {
                let x = next() + if i == j { diag } else { 0.0 };
                band.set(i, j, x);
                dense[i][j] = x;
            }
        }
        (band, dense)
    }

    #[test]
    fn agrees_with_a_dense_solve() {
        for &(n, kl, ku, diag) in &[
            (40, 2, 2, 0.1),
            (40, 2, 2, 5.0),
            (25, 1, 3, 0.0),
            (7, 3, 1, 0.5),
        ] {
            let (mut band, dense) = matrix(n, kl, ku, diag);
            assert_eq!(band.get(1, 0), dense[1][0]);
            let b: Vec<f64> = (0..n).map(|i| (i as f64 * 0.37).sin()).collect();
            let want = dense_solve(dense, b.clone());
            band.factor().unwrap();
            let mut x = b;
            band.solve(&mut x);
            for (x, y) in x.iter().zip(&want) {
                assert!((x - y).abs() < 1e-10 * (1.0 + y.abs()), "{x} vs {y}");
            }
        }
    }

    /// A matrix built in a dropped one's storage (its LU factors, the
    /// fill included) holds what one built fresh holds, to the bit; a
    /// smaller matrix takes a larger spare, a larger one frees the spare.
    #[test]
    fn reused_storage_is_zeroed() {
        let spares = || SPARE.with(|s| s.borrow().len());
        let (mut first, _) = matrix(30, 2, 2, 0.5);
        first.factor().unwrap();
        let at = first.a.as_ptr();
        drop(first);
        let (band, _) = matrix(30, 2, 2, 0.5);
        assert_eq!(band.a.as_ptr(), at, "the dropped storage is reused");
        let mut fresh = band.clone();
        fresh.a = vec![0.0; band.a.len()];
        for i in 0..30 {
            for j in band.row_range(i) {
                fresh.set(i, j, band.get(i, j));
            }
        }
        assert_eq!(band.a, fresh.a);
        drop((band, fresh));
        assert_eq!(spares(), 1);
        let large = Band::new(100, 2, 2);
        assert_eq!(spares(), 0, "the spare too small is freed");
        drop(large);
        let small = Band::new(3, 1, 1);
        assert!(small.a.len() == 12 && small.a.iter().all(|&x| x == 0.0));
        assert!(small.a.capacity() >= 700 && spares() == 0);
    }

    #[test]
    fn singular_is_reported() {
        let mut band = Band::new(4, 1, 1);
        for i in 0..4 {
            band.set(i, i, 1.0);
        }
        band.set(2, 2, 0.0);
        band.set(2, 1, 0.0);
        band.set(3, 2, 0.0);
        assert_eq!(band.factor(), Err(Singular { row: 2 }));
    }
}
