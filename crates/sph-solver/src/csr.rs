//! Safe parallel writes into per-pair buffers laid out like the neighbour lists (CSR order):
//! each rayon task gets a contiguous block of particles, their per-particle outputs, and the
//! block's contiguous range of the per-pair buffer, split with `split_at_mut` (no raw
//! pointers). The split tree depends only on the particle count, so a caller that sums per
//! block gets the same result on any number of threads.

use crate::step::MIN_LEN;

/// Per-particle outputs that can be split at a particle index: a mutable slice, or a tuple
/// of them (all of the same length).
pub trait SplitMut: Sized + Send {
    /// Number of particles.
    fn len(&self) -> usize;
    /// Whether there are no particles.
    fn is_empty(&self) -> bool {
        self.len() == 0
    }
    /// The first `mid` particles and the rest.
    fn split_at(self, mid: usize) -> (Self, Self);
}

impl<T: Send> SplitMut for &mut [T] {
    fn len(&self) -> usize {
        <[T]>::len(self)
    }
    fn split_at(self, mid: usize) -> (Self, Self) {
        self.split_at_mut(mid)
    }
}

impl<A: SplitMut, B: SplitMut> SplitMut for (A, B) {
    fn len(&self) -> usize {
        self.0.len()
    }
    fn split_at(self, mid: usize) -> (Self, Self) {
        let (a0, a1) = self.0.split_at(mid);
        let (b0, b1) = self.1.split_at(mid);
        ((a0, b0), (a1, b1))
    }
}

impl<A: SplitMut, B: SplitMut, C: SplitMut> SplitMut for (A, B, C) {
    fn len(&self) -> usize {
        self.0.len()
    }
    fn split_at(self, mid: usize) -> (Self, Self) {
        let (a0, a1) = self.0.split_at(mid);
        let (b0, b1) = self.1.split_at(mid);
        let (c0, c1) = self.2.split_at(mid);
        ((a0, b0, c0), (a1, b1, c1))
    }
}

/// Calls `f(first, outputs, pairs)` on blocks of particles in parallel: `outputs` holds the
/// block's per-particle outputs (particles `first..first + outputs.len()`), `pairs` the
/// block's range `offsets[first]..offsets[first + len]` of a per-pair buffer in CSR order
/// (`offsets` as [`neighbour_search::NeighbourLists::offsets`]). `pairs` must hold
/// `offsets[n] - offsets[0]` entries for the `n` particles of `outputs`. Blocks are halved
/// (rayon `join`) down to [`MIN_LEN`] particles. Returns the sum of `f`'s results over the
/// blocks, summed along the split tree (deterministic for a given particle count).
pub fn par_csr_blocks<P, T, F>(offsets: &[usize], outputs: P, pairs: &mut [T], f: &F) -> f64
where
    P: SplitMut,
    T: Send,
    F: Fn(usize, P, &mut [T]) -> f64 + Sync,
{
    block(offsets, 0, outputs, pairs, f)
}

fn block<P, T, F>(offsets: &[usize], first: usize, outputs: P, pairs: &mut [T], f: &F) -> f64
where
    P: SplitMut,
    T: Send,
    F: Fn(usize, P, &mut [T]) -> f64 + Sync,
{
    let n = outputs.len();
    if n > MIN_LEN {
        let mid = n / 2;
        let split = offsets[first + mid] - offsets[first];
        let (o0, o1) = outputs.split_at(mid);
        let (p0, p1) = pairs.split_at_mut(split);
        let (a, b) = rayon::join(
            || block(offsets, first, o0, p0, f),
            || block(offsets, first + mid, o1, p1, f),
        );
        return a + b;
    }
    f(first, outputs, pairs)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn blocks_cover_every_particle_and_pair_once() {
        // 1000 particles with 0..7 pairs each.
        let counts: Vec<usize> = (0..1000).map(|i| (i * 7919) % 8).collect();
        let mut offsets = vec![0];
        for c in &counts {
            offsets.push(offsets.last().unwrap() + c);
        }
        let mut owner = vec![usize::MAX; offsets[1000]];
        let mut first_pair = vec![usize::MAX; 1000];
        let mut count = vec![0usize; 1000];
        let total = par_csr_blocks(
            &offsets,
            (&mut first_pair[..], &mut count[..]),
            &mut owner,
            &|first, (fp, c): (&mut [usize], &mut [usize]), pairs: &mut [usize]| {
                let base = offsets[first];
                for (k, (fp, c)) in fp.iter_mut().zip(c.iter_mut()).enumerate() {
                    let i = first + k;
                    let range = offsets[i] - base..offsets[i + 1] - base;
                    *fp = offsets[i];
                    *c = range.len();
                    for p in &mut pairs[range] {
                        *p = i;
                    }
                }
                fp.len() as f64
            },
        );
        assert_eq!(total, 1000.0);
        assert_eq!(count, counts);
        for i in 0..1000 {
            assert_eq!(first_pair[i], offsets[i]);
            assert!(owner[offsets[i]..offsets[i + 1]].iter().all(|&o| o == i));
        }
    }
}
