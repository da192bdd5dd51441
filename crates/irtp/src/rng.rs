//! Per-particle random streams.
//!
//! Every particle (or any other independent sample) gets its own generator
//! derived from (seed, index) only, never from a shared or per-thread stream,
//! so results are bit-identical for any thread count.

use rand::SeedableRng;
use rand_xoshiro::Xoshiro256PlusPlus;

/// The generator used everywhere in irtp.
pub type Rng = Xoshiro256PlusPlus;

#[inline]
fn splitmix64(mut z: u64) -> u64 {
    z = z.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// Independent stream for sample `index` of a run with master `seed`.
///
/// The 256-bit Xoshiro state is filled from two SplitMix64 chains keyed by
/// the seed and the index, so distinct (seed, index) pairs give unrelated
/// streams (no shared prefix, no overlap for practical run lengths).
pub fn stream(seed: u64, index: u64) -> Rng {
    let a = splitmix64(seed ^ 0x6A09_E667_F3BC_C909);
    let b = splitmix64(index ^ 0xBB67_AE85_84CA_A73B);
    let mut s = [0u8; 32];
    let words = [
        splitmix64(a ^ b),
        splitmix64(a.wrapping_add(b.rotate_left(17))),
        splitmix64(a.rotate_left(31) ^ b.wrapping_mul(3)),
        splitmix64(a.wrapping_mul(5) ^ b.rotate_left(43)),
    ];
    for (chunk, w) in s.chunks_exact_mut(8).zip(words) {
        chunk.copy_from_slice(&w.to_le_bytes());
    }
    Rng::from_seed(s)
}

/// A second, independent family of streams for the same run (e.g. for a
/// different purpose than particle dynamics) keyed by `purpose`.
pub fn stream_for(seed: u64, purpose: u64, index: u64) -> Rng {
    stream(splitmix64(seed ^ splitmix64(purpose)), index)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::Rng as _;

    #[test]
    fn deterministic_and_distinct() {
        let x: u64 = stream(7, 3).gen();
        let y: u64 = stream(7, 3).gen();
        let z: u64 = stream(7, 4).gen();
        let w: u64 = stream(8, 3).gen();
        assert_eq!(x, y);
        assert_ne!(x, z);
        assert_ne!(x, w);
    }

    /// Value stability: changing the stream derivation changes every pinned
    /// simulation result, so it is pinned here first.
    #[test]
    fn pinned_first_values() {
        let v: u64 = stream(42, 0).gen();
        let again: u64 = stream(42, 0).gen();
        assert_eq!(v, again);
        assert_eq!(v, PINNED_42_0);
    }
    const PINNED_42_0: u64 = 6_516_984_144_552_355_497;
}
