//! Parallel detection of runs of equal keys in a sorted array.

// Unsafe: disjoint parallel writes through `SyncPtr` (each index written by one task), and unchecked indexing in the hot loop behind checked bounds; see the SAFETY comments.
#![allow(unsafe_code)]

use rayon::prelude::*;

use crate::sync_ptr::SyncPtr;

const BLOCK: usize = 1 << 15;

/// Writes the start index of every run of equal keys in `keys` to `starts`, followed by a
/// final sentinel `keys.len()`; run `r` is `starts[r]..starts[r + 1]`.
pub(crate) fn run_starts<K: PartialEq + Sync>(
    keys: &[K],
    starts: &mut Vec<u32>,
    counts: &mut Vec<usize>,
) {
    let n = keys.len();
    starts.clear();
    if n == 0 {
        starts.push(0);
        return;
    }
    let blocks = n.div_ceil(BLOCK);
    counts.clear();
    counts.resize(blocks, 0);
    let is_start = |k: usize| k == 0 || keys[k] != keys[k - 1];
    counts.par_iter_mut().enumerate().for_each(|(b, c)| {
        let (lo, hi) = (b * BLOCK, ((b + 1) * BLOCK).min(n));
        *c = (lo..hi).filter(|&k| is_start(k)).count();
    });
    let mut sum = 0;
    for c in counts.iter_mut() {
        let v = *c;
        *c = sum;
        sum += v;
    }
    starts.resize(sum + 1, 0);
    starts[sum] = n as u32;
    let out = SyncPtr(starts.as_mut_ptr());
    counts.par_iter().enumerate().for_each(|(b, &off)| {
        let p = out;
        let (lo, hi) = (b * BLOCK, ((b + 1) * BLOCK).min(n));
        let mut w = off;
        for k in lo..hi {
            if is_start(k) {
                // SAFETY: block b owns slots [off, off + its count), disjoint across blocks.
                unsafe { *p.0.add(w) = k as u32 };
                w += 1;
            }
        }
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finds_runs() {
        let mut s = Vec::new();
        let mut c = Vec::new();
        run_starts::<u64>(&[], &mut s, &mut c);
        assert_eq!(s, vec![0]);
        run_starts(&[1u64, 1, 2, 5, 5, 5], &mut s, &mut c);
        assert_eq!(s, vec![0, 2, 3, 6]);
        let long: Vec<u64> = (0..100_000u64).map(|k| k / 3).collect();
        run_starts(&long, &mut s, &mut c);
        assert_eq!(s.len(), 33_334 + 1);
        assert!(s.windows(2).all(|w| w[1] - w[0] <= 3 && w[1] > w[0]));
    }
}
