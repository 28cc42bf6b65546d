use std::sync::atomic::AtomicBool;
use std::sync::Arc;

use crate::SearchError;

/// Bounds a search keeps to, carried by the caller's [`NeighbourLists`]: a search that
/// would exceed them stops with a [`SearchError`] instead of exhausting memory or running
/// on after the caller gave up.
///
/// Every buffer whose size the input sets is allocated fallibly whatever the limits
/// ([`SearchError::OutOfMemory`]); `max_pairs` bounds the pairs before the allocator has
/// to (an operating system that overcommits memory may otherwise grant the allocations
/// and kill the process when they are touched).
#[derive(Debug, Clone, Default)]
pub struct SearchLimits {
    /// Most (ordered) pairs the lists may hold: beyond it the search stops with
    /// [`SearchError::TooManyPairs`]. `None`: no limit but the allocator's.
    pub max_pairs: Option<usize>,
    /// Raised by the caller (another thread, a signal handler) to stop the search early
    /// with [`SearchError::Interrupted`]; checked once per cell and every few thousand
    /// pairs.
    pub interrupt: Option<Arc<AtomicBool>>,
}

/// Neighbour lists in compressed sparse row form: the neighbours of particle `i` are
/// `indices[offsets[i]..offsets[i + 1]]`, as indices into the caller's particle order.
///
/// The buffers are kept between searches: a search refills them in place and only
/// reallocates when the number of particles or pairs grows beyond the capacity. The lists
/// also carry the [`SearchLimits`] every search into them keeps to (none by default);
/// equality compares the lists only.
#[derive(Debug, Clone, Default)]
pub struct NeighbourLists {
    pub(crate) offsets: Vec<usize>,
    pub(crate) indices: Vec<u32>,
    pub(crate) limits: SearchLimits,
}

impl PartialEq for NeighbourLists {
    fn eq(&self, other: &Self) -> bool {
        self.offsets == other.offsets && self.indices == other.indices
    }
}

impl Eq for NeighbourLists {}

impl NeighbourLists {
    /// Empty lists.
    pub fn new() -> Self {
        Self {
            offsets: vec![0],
            indices: Vec::new(),
            limits: SearchLimits::default(),
        }
    }

    /// Empty lists whose searches keep to `limits`.
    pub fn with_limits(limits: SearchLimits) -> Self {
        Self {
            limits,
            ..Self::new()
        }
    }

    /// The limits searches into these lists keep to.
    pub fn limits(&self) -> &SearchLimits {
        &self.limits
    }

    /// Replaces the limits searches into these lists keep to.
    pub fn set_limits(&mut self, limits: SearchLimits) {
        self.limits = limits;
    }

    /// Number of particles the lists describe.
    pub fn particle_count(&self) -> usize {
        self.offsets.len().saturating_sub(1)
    }

    /// Neighbours of particle `i` (excluding `i` itself).
    ///
    /// # Panics
    /// Panics if `i >= particle_count()`.
    #[inline]
    pub fn neighbours(&self, i: usize) -> &[u32] {
        &self.indices[self.offsets[i]..self.offsets[i + 1]]
    }

    /// CSR offsets (`particle_count() + 1` entries, starting at 0).
    pub fn offsets(&self) -> &[usize] {
        &self.offsets
    }

    /// CSR neighbour indices.
    pub fn indices(&self) -> &[u32] {
        &self.indices
    }

    /// The CSR arrays `(offsets, indices)` by value, without a copy (for a caller that
    /// hands them on, e.g. to Python as numpy arrays).
    pub fn into_parts(self) -> (Vec<usize>, Vec<u32>) {
        (self.offsets, self.indices)
    }

    /// Total number of (ordered) neighbour pairs, i.e. `indices().len()`.
    pub fn pair_count(&self) -> usize {
        self.indices.len()
    }

    /// Iterator over `(i, neighbours of i)`.
    pub fn iter(&self) -> impl Iterator<Item = (usize, &[u32])> + '_ {
        (0..self.particle_count()).map(move |i| (i, self.neighbours(i)))
    }

    /// Sorts every particle's neighbour list in place (for comparisons; the search order
    /// is deterministic but method-specific).
    pub fn sort_each(&mut self) {
        for i in 0..self.particle_count() {
            let (a, b) = (self.offsets[i], self.offsets[i + 1]);
            self.indices[a..b].sort_unstable();
        }
    }

    /// The lists as sorted vectors, for tests and reports.
    pub fn to_sorted_sets(&self) -> Vec<Vec<u32>> {
        self.iter()
            .map(|(_, n)| {
                let mut v = n.to_vec();
                v.sort_unstable();
                v
            })
            .collect()
    }

    /// Bytes held by the two buffers (capacity, not length).
    pub fn heap_bytes(&self) -> usize {
        self.offsets.capacity() * std::mem::size_of::<usize>()
            + self.indices.capacity() * std::mem::size_of::<u32>()
    }

    /// Drops from the lists of the particles `active..` their entries `active..` (the
    /// passive–passive pairs of [`crate::NeighbourSearch::search_active`]), keeping the
    /// order of the others; in place.
    pub(crate) fn drop_passive_pairs(&mut self, active: usize) {
        let n = self.particle_count();
        if active >= n {
            return;
        }
        let mut kept = self.offsets[active];
        for i in active..n {
            let (a, b) = (self.offsets[i], self.offsets[i + 1]);
            self.offsets[i] = kept;
            for k in a..b {
                let j = self.indices[k];
                self.indices[kept] = j;
                kept += usize::from((j as usize) < active);
            }
        }
        self.offsets[n] = kept;
        self.indices.truncate(kept);
    }

    /// Empties the lists and sizes the offsets for `n` particles (all zero).
    pub(crate) fn reset(&mut self, n: usize) -> Result<(), SearchError> {
        self.offsets.clear();
        self.indices.clear();
        self.offsets
            .try_reserve(n + 1)
            .map_err(|e| SearchError::out_of_memory::<usize>("neighbour offsets", n + 1, e))?;
        self.offsets.resize(n + 1, 0);
        Ok(())
    }
}
