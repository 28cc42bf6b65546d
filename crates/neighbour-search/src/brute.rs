use std::sync::Mutex;

use rayon::prelude::*;
use sph_core::{Real, Vec3};

use crate::cells::{cell_size, compute_cells, is_neighbour};
use crate::csr::PairGuard;
use crate::{NeighbourLists, NeighbourSearch, SearchError};

/// The O(N²) oracle: tests every pair with [`crate::is_neighbour`]. Neighbours of each
/// particle come in increasing index order. Validates its input exactly like the fast
/// methods (same errors for the same input).
#[derive(Debug, Default, Clone)]
pub struct BruteForce {
    cells: Vec<[i32; 3]>,
}

impl BruteForce {
    /// A new oracle.
    pub fn new() -> Self {
        Self::default()
    }
}

impl<R: Real> NeighbourSearch<R> for BruteForce {
    fn name(&self) -> &'static str {
        "brute-force"
    }

    fn search(
        &mut self,
        positions: &[Vec3<R>],
        radius: R,
        out: &mut NeighbourLists,
    ) -> Result<(), SearchError> {
        let cell = cell_size(radius)?;
        compute_cells(positions, cell, &mut self.cells)?;
        let r2 = radius * radius;
        let guard = PairGuard::new(&out.limits);
        let failed: Mutex<Option<SearchError>> = Mutex::new(None);
        let lists: Vec<Vec<u32>> = positions
            .par_iter()
            .enumerate()
            .map(|(i, p)| {
                if guard.stopped() {
                    return Vec::new();
                }
                let mut list: Vec<u32> = Vec::new();
                for (j, q) in positions.iter().enumerate() {
                    if j != i && is_neighbour(p, q, r2) {
                        if list.len() == list.capacity() {
                            let more = list.len().max(8);
                            if let Err(e) = list.try_reserve(more) {
                                let err = SearchError::out_of_memory::<u32>(
                                    "neighbour indices",
                                    list.len() + more,
                                    e,
                                );
                                if let Ok(mut f) = failed.lock() {
                                    f.get_or_insert(err);
                                }
                                guard.halt();
                                return Vec::new();
                            }
                        }
                        list.push(j as u32);
                    }
                }
                guard.report(list.len());
                list
            })
            .collect();
        if let Some(e) = failed.into_inner().ok().flatten() {
            return Err(e);
        }
        guard.verdict(std::iter::empty())?;
        out.reset(positions.len())?;
        let total = lists.iter().map(Vec::len).sum();
        out.indices
            .try_reserve(total)
            .map_err(|e| SearchError::out_of_memory::<u32>("neighbour indices", total, e))?;
        for (i, l) in lists.iter().enumerate() {
            out.offsets[i + 1] = out.offsets[i] + l.len();
            out.indices.extend_from_slice(l);
        }
        Ok(())
    }
}
