//! Deterministic parallel map-reduce over independent samples.
//!
//! Samples are cut into fixed-size chunks; each chunk is reduced sequentially
//! (in index order) on some rayon thread, and the chunk results are merged in
//! chunk order. The floating-point summation order therefore depends only on
//! the chunk size, never on the number of threads or on work stealing.

use rayon::prelude::*;
use std::sync::atomic::{AtomicU64, Ordering};

/// Number of samples per chunk. Part of the value-stability contract:
/// changing it changes the last bits of every pinned result.
pub const CHUNK: u64 = 256;

/// Chunks computed side by side before their results are merged (bounds
/// the memory of a reduction; the result does not depend on it).
const BLOCK: u64 = 1024;

/// Progress observer: called with the number of samples finished so far
/// (monotone, from any thread). The library never prints; the binary turns
/// this into a progress bar.
pub trait Progress: Sync {
    /// `done` of `total` samples are finished.
    fn update(&self, done: u64, total: u64);
    /// Whether the caller wants the computation stopped. The parallel loops
    /// below then skip their remaining chunks, so a long run ends within one
    /// chunk's work; its (partial) result must be discarded by whoever asked,
    /// as `crate::app` does by returning [`crate::Error::Interrupted`].
    fn cancelled(&self) -> bool {
        false
    }
}

/// Observer that ignores progress.
pub struct NoProgress;
impl Progress for NoProgress {
    fn update(&self, _done: u64, _total: u64) {}
}

impl<F: Fn(u64, u64) + Sync> Progress for F {
    fn update(&self, done: u64, total: u64) {
        self(done, total)
    }
}

/// Reduce `n` independent samples: `sample(i, &mut acc)` adds sample `i` to a
/// chunk accumulator created by `init`; chunk accumulators are merged with
/// `merge` in chunk order. Bit-identical for any thread count.
pub fn reduce<A, I, S, M>(n: u64, init: I, sample: S, merge: M, progress: &dyn Progress) -> A
where
    A: Send,
    I: Fn() -> A + Sync,
    S: Fn(u64, &mut A) + Sync,
    M: Fn(&mut A, A),
{
    reduce_chunks(
        n,
        &init,
        |lo, hi, acc| {
            for i in lo..hi {
                sample(i, acc);
            }
        },
        merge,
        progress,
    )
}

/// [`reduce`] with the work of a whole chunk in one call: `chunk(lo, hi, acc)`
/// must add items `lo..hi` to `acc` in index order (it may compute them in
/// any order, e.g. several side by side). Same chunks, same merge order as
/// [`reduce`], so the result is bit-identical to it.
pub fn reduce_chunks<A, I, C, M>(n: u64, init: I, chunk: C, merge: M, progress: &dyn Progress) -> A
where
    A: Send,
    I: Fn() -> A + Sync,
    C: Fn(u64, u64, &mut A) + Sync,
    M: Fn(&mut A, A),
{
    let chunks = n.div_ceil(CHUNK);
    let done = AtomicU64::new(0);
    let mut total = init();
    // Chunks run in blocks of BLOCK: memory holds at most BLOCK chunk
    // accumulators whatever n is, and the merge order stays chunk order.
    for first in (0..chunks).step_by(BLOCK as usize) {
        if progress.cancelled() {
            break;
        }
        let parts: Vec<A> = (first..chunks.min(first + BLOCK))
            .into_par_iter()
            .map(|c| {
                let lo = c * CHUNK;
                let hi = (lo + CHUNK).min(n);
                let mut acc = init();
                if progress.cancelled() {
                    return acc;
                }
                chunk(lo, hi, &mut acc);
                let d = done.fetch_add(hi - lo, Ordering::Relaxed) + (hi - lo);
                progress.update(d, n);
                acc
            })
            .collect();
        for p in parts {
            merge(&mut total, p);
        }
    }
    total
}

/// Map every index to a value in parallel, keeping index order.
pub fn map<T, F>(n: u64, f: F, progress: &dyn Progress) -> Vec<T>
where
    T: Send,
    F: Fn(u64) -> T + Sync,
{
    let done = AtomicU64::new(0);
    (0..n)
        .into_par_iter()
        .map(|i| {
            let v = f(i);
            let d = done.fetch_add(1, Ordering::Relaxed) + 1;
            progress.update(d, n);
            v
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn identical_across_thread_counts() {
        let run = |threads: usize| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| {
                reduce(
                    10_007,
                    || 0.0f64,
                    |i, acc| *acc += (i as f64 * 0.618).sin() * 1e-3 + 1e10 * ((i % 7) as f64),
                    |a, b| *a += b,
                    &NoProgress,
                )
            })
        };
        let a = run(1);
        assert_eq!(a.to_bits(), run(2).to_bits());
        assert_eq!(a.to_bits(), run(5).to_bits());
    }
}
