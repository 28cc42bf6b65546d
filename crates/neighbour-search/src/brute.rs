use rayon::prelude::*;
use sph_core::{Real, Vec3};

use crate::cells::{cell_size, compute_cells, is_neighbour};
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
        let lists: Vec<Vec<u32>> = positions
            .par_iter()
            .enumerate()
            .map(|(i, p)| {
                (0..positions.len())
                    .filter(|&j| j != i && is_neighbour(p, &positions[j], r2))
                    .map(|j| j as u32)
                    .collect()
            })
            .collect();
        out.reset(positions.len());
        for (i, l) in lists.iter().enumerate() {
            out.offsets[i + 1] = out.offsets[i] + l.len();
            out.indices.extend_from_slice(l);
        }
        Ok(())
    }
}
