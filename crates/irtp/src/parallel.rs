//! Deterministic parallel map-reduce over independent samples.
//!
//! Samples are cut into fixed-size chunks of [`CHUNK`] samples, and chunks
//! into units of [`UNIT_CHUNKS`] chunks ([`UNIT`] samples). Each chunk is
//! reduced sequentially (in index order, from `init()`) on some rayon thread;
//! the chunk results of a unit are merged in chunk order into the unit's
//! total (from `init()`), and the unit totals in unit order into the grand
//! total (from `init()`). The floating-point summation order therefore
//! depends only on the chunk and unit sizes, never on the number of threads
//! or on work stealing.
//!
//! Units are also the grain of sharding: [`reduce_units`] computes the totals
//! of any contiguous range of units, so a run split into unit-aligned shards
//! (separate processes or machines) whose unit totals are merged in unit
//! order gives [`reduce_chunks`]'s result bit for bit. With at most one unit
//! (n <= [`UNIT`]) and an additive-zero `init()` the tree is the same as a
//! single running sum of the chunk results.

use rayon::prelude::*;
use std::ops::Range;
use std::sync::atomic::{AtomicU64, Ordering};

pub use crate::stop::{
    check_stop, stop_due, stop_during, stop_flag, stop_requested, STOP_POLL_STEPS,
};

/// Number of samples per chunk. Part of the value-stability contract:
/// changing it changes the last bits of every pinned result.
pub const CHUNK: u64 = 256;

/// Chunks per unit. Part of the value-stability contract (for runs of more
/// than one unit) and of the sharding contract: shards are whole units.
pub const UNIT_CHUNKS: u64 = 16;

/// Samples per unit (4096): the grain of bit-identical sharding.
pub const UNIT: u64 = CHUNK * UNIT_CHUNKS;

/// Chunks computed side by side before their results are merged (bounds
/// the memory of a reduction; the result does not depend on it). A multiple
/// of [`UNIT_CHUNKS`], so a block holds whole units.
const BLOCK: u64 = 64 * UNIT_CHUNKS;

/// Progress observer: called with the number of samples finished so far
/// (monotone, from any thread). The library never prints; the binary turns
/// this into a progress bar.
pub trait Progress: Sync {
    /// `done` of `total` samples are finished.
    fn update(&self, done: u64, total: u64);
    /// Whether the caller wants the computation stopped. The parallel loops
    /// below then skip their remaining chunks, so a long run ends within one
    /// chunk's work; its (partial) result must be discarded by whoever asked,
    /// as `irtp_app` does by returning [`crate::Error::Interrupted`].
    /// By default: the process-wide [`stop_requested`].
    fn cancelled(&self) -> bool {
        stop_requested()
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
/// `merge` in chunk order into unit totals, and those in unit order (see the
/// module docs). Bit-identical for any thread count.
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
                // A cancelled chunk is discarded: stop within one sample.
                if progress.cancelled() {
                    return;
                }
                sample(i, acc);
            }
        },
        merge,
        progress,
    )
}

/// [`reduce`] with the work of a whole chunk in one call: `chunk(lo, hi, acc)`
/// must add items `lo..hi` to `acc` in index order (it may compute them in
/// any order, e.g. several side by side). Same chunks, same merge tree as
/// [`reduce`], so the result is bit-identical to it: the unit totals of
/// [`reduce_units`] over all units, merged in unit order into `init()`.
pub fn reduce_chunks<A, I, C, M>(n: u64, init: I, chunk: C, merge: M, progress: &dyn Progress) -> A
where
    A: Send,
    I: Fn() -> A + Sync,
    C: Fn(u64, u64, &mut A) + Sync,
    M: Fn(&mut A, A),
{
    let mut total = init();
    // Each unit total is merged as soon as it is complete: memory stays
    // bounded by one block of chunk accumulators whatever n is.
    for_each_unit(
        n,
        0..unit_count(n),
        &init,
        &chunk,
        &merge,
        progress,
        |unit| merge(&mut total, unit),
    );
    total
}

/// Number of units of `n` samples: unit `u` covers samples
/// `u * UNIT .. min((u + 1) * UNIT, n)`.
pub fn unit_count(n: u64) -> u64 {
    n.div_ceil(UNIT)
}

/// The totals of units `units` (in order) of the reduction of `n` samples by
/// [`reduce_chunks`]: each is `init()` with the unit's chunk accumulators
/// merged in chunk order. Merging the totals of all units in unit order into
/// `init()` gives [`reduce_chunks`]'s result bit for bit, however the unit
/// range was split into calls (shards on separate processes or machines).
/// Progress counts the samples of these units. If the progress is cancelled,
/// the result is partial (the units not finished are left out: padding
/// millions of them would delay the stop) and must be discarded.
///
/// Panics if `units` reaches past [`unit_count`]`(n)`.
pub fn reduce_units<A, I, C, M>(
    n: u64,
    units: Range<u64>,
    init: I,
    chunk: C,
    merge: M,
    progress: &dyn Progress,
) -> Vec<A>
where
    A: Send,
    I: Fn() -> A + Sync,
    C: Fn(u64, u64, &mut A) + Sync,
    M: Fn(&mut A, A),
{
    let len = units.end.saturating_sub(units.start) as usize;
    let mut totals = Vec::with_capacity(len);
    for_each_unit(n, units, &init, &chunk, &merge, progress, |unit| {
        totals.push(unit)
    });
    if !progress.cancelled() {
        totals.resize_with(len, &init);
    }
    totals
}

/// The one reduction loop: chunk accumulators of units `units`, computed in
/// parallel in blocks of BLOCK chunks, merged in chunk order into their
/// unit's total; `sink` receives each unit total in unit order. Cancellation
/// skips the remaining chunks (and the units not started).
fn for_each_unit<A, I, C, M>(
    n: u64,
    units: Range<u64>,
    init: &I,
    chunk: &C,
    merge: &M,
    progress: &dyn Progress,
    mut sink: impl FnMut(A),
) where
    A: Send,
    I: Fn() -> A + Sync,
    C: Fn(u64, u64, &mut A) + Sync,
    M: Fn(&mut A, A),
{
    assert!(
        units.end <= unit_count(n),
        "units {units:?} past the {} units of {n} samples",
        unit_count(n)
    );
    if units.is_empty() {
        return;
    }
    let chunks = units.start * UNIT_CHUNKS..n.div_ceil(CHUNK).min(units.end * UNIT_CHUNKS);
    let total = n.min(units.end * UNIT) - units.start * UNIT;
    let done = AtomicU64::new(0);
    let mut unit: Option<A> = None;
    // Chunks run in blocks of BLOCK: memory holds at most BLOCK chunk
    // accumulators whatever n is, and the merge order stays chunk order.
    for first in chunks.clone().step_by(BLOCK as usize) {
        if progress.cancelled() {
            break;
        }
        let parts: Vec<A> = (first..chunks.end.min(first + BLOCK))
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
                progress.update(d, total);
                acc
            })
            .collect();
        for (c, p) in (first..).zip(parts) {
            if c % UNIT_CHUNKS == 0 {
                if let Some(u) = unit.replace(init()) {
                    sink(u);
                }
            }
            merge(unit.as_mut().expect("a unit is open"), p);
        }
    }
    if let Some(u) = unit {
        sink(u);
    }
}

/// Map every index to a value in parallel, keeping index order. Once the
/// progress is cancelled the items not started are skipped as
/// [`crate::Error::Interrupted`].
pub fn map<T, F>(n: u64, f: F, progress: &dyn Progress) -> Vec<crate::Result<T>>
where
    T: Send,
    F: Fn(u64) -> crate::Result<T> + Sync,
{
    let done = AtomicU64::new(0);
    (0..n)
        .into_par_iter()
        .map(|i| {
            if progress.cancelled() {
                return Err(crate::Error::Interrupted);
            }
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

    fn term(i: u64) -> f64 {
        (i as f64 * 0.618).sin() * 1e-3 + 1e10 * ((i % 7) as f64)
    }

    fn sum_chunk(lo: u64, hi: u64, acc: &mut f64) {
        for i in lo..hi {
            *acc += term(i);
        }
    }

    #[test]
    fn unit_totals_merge_into_the_whole_reduction() {
        let n = 3 * UNIT + 123;
        let whole = reduce_chunks(n, || 0.0f64, sum_chunk, |a, b| *a += b, &NoProgress);
        for cuts in [
            vec![0, 4],
            vec![0, 1, 3, 4],
            vec![0, 2, 2, 4],
            vec![0, 1, 2, 3, 4],
        ] {
            let mut total = 0.0f64;
            for w in cuts.windows(2) {
                let units = reduce_units(
                    n,
                    w[0]..w[1],
                    || 0.0,
                    sum_chunk,
                    |a, b| *a += b,
                    &NoProgress,
                );
                assert_eq!(units.len() as u64, w[1] - w[0]);
                units.into_iter().for_each(|u| total += u);
            }
            assert_eq!(total.to_bits(), whole.to_bits(), "cuts {cuts:?}");
        }
        // The tree: chunk sums into unit sums, unit sums into the total.
        let mut expected = 0.0f64;
        for u in 0..unit_count(n) {
            let mut unit = 0.0f64;
            for c in u * UNIT_CHUNKS..((u + 1) * UNIT_CHUNKS).min(n.div_ceil(CHUNK)) {
                let mut acc = 0.0;
                sum_chunk(c * CHUNK, ((c + 1) * CHUNK).min(n), &mut acc);
                unit += acc;
            }
            expected += unit;
        }
        assert_eq!(whole.to_bits(), expected.to_bits());
    }

    #[test]
    fn one_unit_is_one_running_sum_of_chunks() {
        let n = UNIT - 77;
        let mut expected = 0.0f64;
        for c in 0..n.div_ceil(CHUNK) {
            let mut acc = 0.0;
            sum_chunk(c * CHUNK, ((c + 1) * CHUNK).min(n), &mut acc);
            expected += acc;
        }
        let got = reduce_chunks(n, || 0.0f64, sum_chunk, |a, b| *a += b, &NoProgress);
        assert_eq!(got.to_bits(), expected.to_bits());
        assert_eq!(unit_count(0), 0);
        assert_eq!(
            reduce_chunks(0, || 1.5f64, sum_chunk, |a, b| *a += b, &NoProgress),
            1.5
        );
        assert!(
            reduce_units(0, 0..0, || 0.0f64, sum_chunk, |a, b| *a += b, &NoProgress).is_empty()
        );
    }
}
