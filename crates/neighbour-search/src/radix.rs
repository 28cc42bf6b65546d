//! Stable, parallel least-significant-digit radix sort of `(u64 key, u32 value)` pairs.
//!
//! Used for Im & Chan's relation table (27 entries per particle) and for sorting particles
//! by cell in the grid methods. Only the key bits in use are sorted (11-bit digits), so a
//! scene spanning 64 cells per axis needs 2 passes instead of 6. The input is cut into a
//! fixed number of blocks that depends on the length only (never on the thread count),
//! so the output is identical for any number of threads; the sort is stable.

// Unsafe: disjoint parallel writes through `SyncPtr` (each index written by one task), and unchecked indexing in the hot loop behind checked bounds; see the SAFETY comments.
#![allow(unsafe_code)]

use rayon::prelude::*;

use crate::cells::Key;
use crate::sync_ptr::SyncPtr;

const DIGIT_BITS: u32 = 11;
const BUCKETS: usize = 1 << DIGIT_BITS;
/// Entries per block; blocks are the unit of parallel work.
const BLOCK: usize = 1 << 16;

/// Reusable buffers of [`sort_pairs`].
#[derive(Debug, Default, Clone)]
pub(crate) struct RadixScratch<K> {
    keys: Vec<K>,
    vals: Vec<u32>,
    histograms: Vec<[usize; BUCKETS]>,
}

/// Sorts `keys` (ascending, only the low `bits` bits are significant: higher bits must be
/// zero) and permutes `vals` alongside, stably.
pub(crate) fn sort_pairs<K: Key>(
    keys: &mut Vec<K>,
    vals: &mut Vec<u32>,
    bits: u32,
    s: &mut RadixScratch<K>,
) {
    let n = keys.len();
    debug_assert_eq!(n, vals.len());
    if n < 2 || bits == 0 {
        return;
    }
    let blocks = n.div_ceil(BLOCK);
    s.keys.resize(n, K::default());
    s.vals.resize(n, 0);
    s.histograms.resize(blocks, [0; BUCKETS]);
    let passes = bits.div_ceil(DIGIT_BITS);
    for pass in 0..passes {
        let shift = pass * DIGIT_BITS;
        // 1. Histogram of each block.
        keys.par_chunks(BLOCK)
            .zip(s.histograms.par_iter_mut())
            .for_each(|(chunk, h)| {
                *h = [0; BUCKETS];
                for &k in chunk {
                    h[k.shifted(shift) & (BUCKETS - 1)] += 1;
                }
            });
        // Skip a pass whose digit is the same for every key (common for the top digit).
        let first = keys[0].shifted(shift) & (BUCKETS - 1);
        let total_first: usize = s.histograms.iter().map(|h| h[first]).sum();
        if total_first == n {
            continue;
        }
        // 2. Exclusive prefix sum, digit-major then block-major: the write offset of each
        // (block, digit) pair. Stability follows from blocks being in input order.
        let mut sum = 0usize;
        for d in 0..BUCKETS {
            for h in s.histograms.iter_mut() {
                let c = h[d];
                h[d] = sum;
                sum += c;
            }
        }
        // 3. Scatter each block to its offsets.
        let out_k = SyncPtr(s.keys.as_mut_ptr());
        let out_v = SyncPtr(s.vals.as_mut_ptr());
        keys.par_chunks(BLOCK)
            .zip(vals.par_chunks(BLOCK))
            .zip(s.histograms.par_iter_mut())
            .for_each(|((kc, vc), offs)| {
                let (ok, ov) = (out_k, out_v);
                for (&k, &v) in kc.iter().zip(vc) {
                    let d = k.shifted(shift) & (BUCKETS - 1);
                    let dst = offs[d];
                    offs[d] += 1;
                    // SAFETY: the prefix sums give every (block, digit) a disjoint range of
                    // [0, n), and each block writes only within its own ranges.
                    unsafe {
                        *ok.0.add(dst) = k;
                        *ov.0.add(dst) = v;
                    }
                }
            });
        std::mem::swap(keys, &mut s.keys);
        std::mem::swap(vals, &mut s.vals);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #[test]
        fn matches_stable_std_sort(keys in proptest::collection::vec(0u64..1 << 20, 0..3000), big in any::<bool>()) {
            // Optionally stretch the input over several blocks.
            let mut keys: Vec<u64> = if big { keys.iter().cycle().take(keys.len() * 70).copied().collect() } else { keys };
            let mut vals: Vec<u32> = (0..keys.len() as u32).collect();
            let mut expected: Vec<(u64, u32)> = keys.iter().copied().zip(vals.iter().copied()).collect();
            expected.sort_by_key(|&(k, _)| k); // stable
            let mut s = RadixScratch::default();
            let mut wide: Vec<u128> = keys.iter().map(|&k| (k as u128) << 70).collect();
            let mut wide_vals = vals.clone();
            sort_pairs(&mut keys, &mut vals, 20, &mut s);
            sort_pairs(&mut wide, &mut wide_vals, 90, &mut RadixScratch::default());
            prop_assert_eq!(&wide_vals, &vals);
            let got: Vec<(u64, u32)> = keys.into_iter().zip(vals).collect();
            prop_assert_eq!(got, expected);
        }
    }
}
