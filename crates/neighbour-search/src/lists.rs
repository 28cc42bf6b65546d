/// Neighbour lists in compressed sparse row form: the neighbours of particle `i` are
/// `indices[offsets[i]..offsets[i + 1]]`, as indices into the caller's particle order.
///
/// The buffers are kept between searches: a search refills them in place and only
/// reallocates when the number of particles or pairs grows beyond the capacity.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct NeighbourLists {
    pub(crate) offsets: Vec<usize>,
    pub(crate) indices: Vec<u32>,
}

impl NeighbourLists {
    /// Empty lists.
    pub fn new() -> Self {
        Self {
            offsets: vec![0],
            indices: Vec::new(),
        }
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

    pub(crate) fn reset(&mut self, n: usize) {
        self.offsets.clear();
        self.offsets.resize(n + 1, 0);
        self.indices.clear();
    }
}
