//! Permutations that sort particles by cell, for memory locality.

use sph_core::{Real, Vec3};

use crate::cells::{cell_size, compute_cells, Key, KeyPacker};
use crate::radix::{sort_pairs, RadixScratch};
use crate::SearchError;

/// Order of the cells in [`CellSorter::permutation`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[non_exhaustive]
pub enum CellOrder {
    /// Lexicographic `(X, Y, Z)`, the order every search of this crate sorts into. Particles
    /// kept in this order (with cells of the search radius) let the searches skip their sort
    /// and write the lists without a scatter: the fastest choice for the search itself.
    #[default]
    Lexicographic,
    /// Z-order (Morton) curve of the cells: better memory locality for a solver's own
    /// neighbour loops across rows and planes, at the price of the search's sort. Falls back
    /// to lexicographic order when an axis spans more than 2²¹ cells.
    Morton,
}

/// Computes permutations that sort particles by cell (stable: particles of one cell keep
/// their relative order). Apply the result with `sph_core::ParticleSet::permute` (or
/// `sph_core::apply_permutation` for a solver's extra arrays): `new[k] = old[perm[k]]`.
#[derive(Debug, Default, Clone)]
pub struct CellSorter {
    cells: Vec<[i32; 3]>,
    keys: Vec<u64>,
    wide_keys: Vec<u128>,
    perm: Vec<u32>,
    radix: RadixScratch<u64>,
    wide_radix: RadixScratch<u128>,
}

/// Spreads the low 21 bits of `v` to every third bit.
#[inline]
fn spread3(v: u64) -> u64 {
    let mut x = v & 0x1f_ffff;
    x = (x | x << 32) & 0x001f_0000_0000_ffff;
    x = (x | x << 16) & 0x001f_0000_ff00_00ff;
    x = (x | x << 8) & 0x100f_00f0_0f00_f00f;
    x = (x | x << 4) & 0x10c3_0c30_c30c_30c3;
    x = (x | x << 2) & 0x1249_2492_4924_9249;
    x
}

impl CellSorter {
    /// A sorter with empty buffers.
    pub fn new() -> Self {
        Self::default()
    }

    /// The permutation sorting `positions` by their cell of edge `cell_size` (e.g. the
    /// search radius), in the given order. Errors as the searches do (non-finite positions,
    /// invalid size, cell overflow).
    pub fn permutation<R: Real>(
        &mut self,
        positions: &[Vec3<R>],
        cell_size_abs: R,
        order: CellOrder,
    ) -> Result<&[u32], SearchError> {
        let cell = cell_size(cell_size_abs)?;
        let bounds = compute_cells(positions, cell, &mut self.cells)?;
        self.perm.clear();
        self.perm.extend(0..positions.len() as u32);
        let Some((lo, hi)) = bounds else {
            return Ok(&self.perm);
        };
        let packer = KeyPacker::new(lo, hi, 0);
        let morton_ok = (0..3).all(|a| (hi[a] as i64 - lo[a] as i64) < (1 << 21));
        if order == CellOrder::Morton && morton_ok {
            self.keys.clear();
            self.keys.extend(self.cells.iter().map(|c| {
                let f = |a: usize| (c[a] as i64 - lo[a] as i64) as u64;
                spread3(f(0)) << 2 | spread3(f(1)) << 1 | spread3(f(2))
            }));
            sort_pairs(&mut self.keys, &mut self.perm, 63, &mut self.radix);
        } else if packer.fits_u64() {
            sort_by(
                &self.cells,
                &packer,
                &mut self.keys,
                &mut self.perm,
                &mut self.radix,
            );
        } else {
            sort_by(
                &self.cells,
                &packer,
                &mut self.wide_keys,
                &mut self.perm,
                &mut self.wide_radix,
            );
        }
        Ok(&self.perm)
    }
}

fn sort_by<K: Key>(
    cells: &[[i32; 3]],
    packer: &KeyPacker,
    keys: &mut Vec<K>,
    perm: &mut Vec<u32>,
    radix: &mut RadixScratch<K>,
) {
    keys.clear();
    keys.extend(cells.iter().map(|&c| packer.pack::<K>(c)));
    sort_pairs(keys, perm, packer.bits, radix);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn morton_interleaves() {
        assert_eq!(spread3(0b101), 0b1_000_001);
        assert_eq!(spread3(0x1f_ffff).count_ones(), 21);
    }

    #[test]
    fn permutation_groups_cells() {
        let pts: Vec<Vec3<f64>> = (0..200)
            .map(|i| {
                let t = i as f64 * 0.7371;
                Vec3::new(
                    (t * 13.1).sin() * 5.0,
                    (t * 7.3).cos() * 5.0,
                    (t * 3.7).sin() * -5.0,
                )
            })
            .collect();
        for order in [CellOrder::Lexicographic, CellOrder::Morton] {
            let mut s = CellSorter::new();
            let perm = s.permutation(&pts, 1.0, order).unwrap().to_vec();
            let mut seen = perm.clone();
            seen.sort_unstable();
            assert_eq!(seen, (0..200).collect::<Vec<u32>>());
            // Particles of one cell are contiguous in the new order.
            let cell = |p: &Vec3<f64>| {
                [p.x, p.y, p.z].map(|v| (v / (1.0 + crate::CELL_MARGIN)).floor() as i32)
            };
            let cells: Vec<[i32; 3]> = perm.iter().map(|&i| cell(&pts[i as usize])).collect();
            for (k, c) in cells.iter().enumerate() {
                let last = cells.iter().rposition(|d| d == c).unwrap();
                let first = cells.iter().position(|d| d == c).unwrap();
                assert!(
                    cells[first..=last].iter().all(|d| d == c),
                    "cell {c:?} split at {k}"
                );
            }
            if order == CellOrder::Lexicographic {
                assert!(cells.windows(2).all(|w| w[0] <= w[1]));
            }
        }
    }
}
