#![doc = include_str!("../README.md")]
//!
//! ## In detail
//!
//! Fixed-radius neighbour search for particle simulations.
//!
//! Given positions `x_i` and a radius `h`, find for every particle all `j ≠ i` with
//! `|x_i − x_j| < h` ([`is_neighbour`]: strict, so a particle at exactly `h` is not a
//! neighbour; coincident particles are). Methods, all behind [`NeighbourSearch`]:
//!
//! | type | method | memory beyond the particles |
//! | --- | --- | --- |
//! | [`RelationTable`] | Im & Chan (2016) §III: 27 particle–cell entries per particle, radix-sorted lexicographically, one run scanned per particle; unbounded | 27 entries / particle |
//! | [`CellStartGrid`] | Green (2008): particles sorted by linear cell index, start/end table over the bounding grid | 8 bytes / cell of the bounding grid |
//! | [`HashedGrid`] | sorted grid with a hash map of occupied cells (as CompactNSearch); unbounded | one map entry / occupied cell |
//! | [`BruteForce`] | O(N²) oracle | none |
//!
//! Results are [`NeighbourLists`] in CSR form (offsets + indices into the caller's order),
//! refilled in place by each search. Every method is rayon-parallel and deterministic:
//! the output does not depend on the number of threads. [`CellSorter`] gives a permutation
//! that sorts particles by cell (lexicographic or Morton), to apply to the particle arrays
//! for locality.
//!
//! # Example
//!
//! ```
//! use neighbour_search::{BruteForce, CellStartGrid, NeighbourLists, NeighbourSearch, Vec3};
//!
//! // A 10×10×10 lattice of spacing s = 0.025 m, searched within h = 0.045 m.
//! let positions: Vec<Vec3<f32>> = (0..1000)
//!     .map(|i| Vec3::new((i % 10) as f32, (i / 10 % 10) as f32, (i / 100) as f32) * 0.025)
//!     .collect();
//! let mut grid = CellStartGrid::<f32>::new();
//! let mut lists = NeighbourLists::new();
//! grid.search(&positions, 0.045, &mut lists)?;
//! // An interior particle has its 6 face, 12 edge and 8 corner neighbours (distances s, s√2,
//! // s√3 = 0.0433 m < h); those at 2s = 0.05 m are beyond h.
//! let centre = 5 + 10 * 5 + 100 * 5;
//! assert_eq!(lists.neighbours(centre).len(), 26);
//! // Same sets as the O(N²) oracle.
//! let mut oracle = NeighbourLists::new();
//! BruteForce::new().search(&positions, 0.045, &mut oracle)?;
//! assert_eq!(lists.to_sorted_sets(), oracle.to_sorted_sets());
//! # Ok::<(), neighbour_search::SearchError>(())
//! ```
//!
//! Input errors ([`SearchError`]) name the offending particle or value: NaN/infinite
//! positions, `h <= 0`, cells that overflow `i32`, a bounding grid too large for
//! [`CellStartGrid`]. No method panics or aborts on user input: every buffer whose size
//! the input sets is allocated fallibly ([`SearchError::OutOfMemory`]), and the
//! [`SearchLimits`] the lists carry bound the pairs ([`SearchError::TooManyPairs`], for a
//! radius in the wrong units or coincident particles, before the memory runs out) and let
//! another thread stop a long search ([`SearchError::Interrupted`]).
//!
//! ## Performance
//!
//! Anchor scene: SPlisHSPlasH's dam break at particle radius 0.0125 m — 59,319 fluid
//! particles at spacing 0.025 m plus 131,976 tank-wall particles, `h = 0.05` m, f32,
//! 22.7 neighbours and 113.5 candidate distance tests per particle ([`SearchStats`]).
//! `cargo bench -p benches --bench neighbour_search -- dam-break-anchor` times every method
//! (build + query, lists written); the figures, against SPlisHSPlasH's CompactNSearch on the
//! same scene, are in the workspace's `docs/performance.md`.
//!
//! **Bound.** Per particle the cell-start grid tests 113.5 candidates (16 per AVX-512 step,
//! about 12 instructions each: ~85 instructions), gathers its cell's ~216 candidates shared
//! by ~8 particles (~110 element copies) and moves about 220 bytes through memory (cells,
//! keys, cell-ordered positions, 91 bytes of neighbour indices, offsets). At the measured
//! single-thread copy bandwidth of 23 GB/s (`cargo run --release -p benches --example
//! bandwidth`) the memory part is ≈ 0.01 µs, and the instruction count at 2–3 per cycle is
//! ≈ 0.03–0.04 µs: a bound of about 0.04 µs/particle. The particles of a cell are scanned
//! by one call of the kernel with one output reservation per cell (in pieces of at most
//! 2¹⁴ pairs), so no per-particle dispatch or reservation remains; what stands above the
//! bound is the gathering of the 27 cells' candidates (nine column ranges copied and padded
//! per cell, about a third of the search's samples under `perf`, against about half for
//! the distance tests) and the candidate count of cells of edge `h` (about 7 tests per
//! neighbour found on the dam break's fluid block). The relation table's cost is its 27
//! entries per particle: 27 × 12 bytes written and radix-sorted in two passes (≈ 250 MB of
//! traffic for this scene, ≈ 11 ms at 23 GB/s even before the sort's scattered writes), which is why it
//! is 5–10× slower than the cell-start grid on a CPU; see the `neighbour-search` experiment
//! of `cargo xtask validate` for the comparison with Im & Chan's claim.

mod brute;
mod cells;
mod csr;
mod error;
mod grid;
mod lists;
pub mod point_sets;
mod radix;
mod relation_table;
mod reorder;
mod runs;
mod scan;
mod sync_ptr;

pub use brute::BruteForce;
pub use cells::{is_neighbour, squared_distance, CELL_MARGIN};
pub use error::SearchError;
pub use grid::{CellStartGrid, HashedGrid, DEFAULT_MAX_CELLS};
pub use lists::{NeighbourLists, SearchLimits};
pub use relation_table::RelationTable;
pub use reorder::{CellOrder, CellSorter};
pub use sph_core::{Real, Vec3};

/// A fixed-radius neighbour search. Implementations keep their scratch buffers between
/// calls, so repeated searches (one per simulation step) do not reallocate once warm.
pub trait NeighbourSearch<R: Real>: Send {
    /// Short stable name ("relation-table", "cell-start-grid", ...).
    fn name(&self) -> &'static str;

    /// Finds the neighbours of every particle within the absolute `radius` (see
    /// [`is_neighbour`]) and writes them to `out`, replacing its contents.
    fn search(
        &mut self,
        positions: &[Vec3<R>],
        radius: R,
        out: &mut NeighbourLists,
    ) -> Result<(), SearchError>;

    /// As [`NeighbourSearch::search`], with the points `0..active` active and the others
    /// passive: an active point lists all its neighbours, a passive one only its active
    /// neighbours (no pair of two passive points; e.g. a solver's boundary particles, which
    /// no sum over boundary particles reads). Each passive point's list is the full search's
    /// list with its passive entries taken out, in the same order; the active points' lists
    /// are the full search's. `active >= positions.len()` is the full search.
    ///
    /// The default searches every pair and then drops the passive–passive ones; the grids
    /// ([`CellStartGrid`], [`HashedGrid`]) scan a cell's passive points against its active
    /// candidates only.
    fn search_active(
        &mut self,
        positions: &[Vec3<R>],
        active: usize,
        radius: R,
        out: &mut NeighbourLists,
    ) -> Result<(), SearchError> {
        self.search(positions, radius, out)?;
        out.drop_passive_pairs(active);
        Ok(())
    }

    /// Statistics of the last successful search (zero if the method does not keep them).
    fn stats(&self) -> SearchStats {
        SearchStats::default()
    }
}

/// Statistics of the last search: wall-clock time of its phases, in seconds, and work done.
///
/// `build_s()` is what the PBF paper's Table 2 calls "Create Hash Grid" (cells, sort, cell
/// table) and `detect_s()` its "Detect Neighbors" (distance tests and list assembly).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct SearchStats {
    /// Candidate pairs whose distance was tested (the self pair included).
    pub candidate_tests: u64,
    /// Validation and cell coordinates (and, for the relation table, its 27 entries per particle).
    pub cells_s: f64,
    /// Sorting by cell.
    pub sort_s: f64,
    /// Runs of equal cells and the cell lookup (start/end table or hash map).
    pub table_s: f64,
    /// Distance tests.
    pub query_s: f64,
    /// Assembly of the CSR lists.
    pub assemble_s: f64,
}

impl SearchStats {
    /// Build time: cells + sort + table.
    pub fn build_s(&self) -> f64 {
        self.cells_s + self.sort_s + self.table_s
    }
    /// Neighbour detection time: distance tests + assembly.
    pub fn detect_s(&self) -> f64 {
        self.query_s + self.assemble_s
    }
    /// Total.
    pub fn total_s(&self) -> f64 {
        self.build_s() + self.detect_s()
    }
}

/// Accumulates phase times.
pub(crate) struct Stopwatch(std::time::Instant);
impl Stopwatch {
    pub(crate) fn start() -> Self {
        Self(std::time::Instant::now())
    }
    /// Seconds since the last lap (or the start), and restarts.
    pub(crate) fn lap(&mut self) -> f64 {
        let now = std::time::Instant::now();
        let dt = (now - self.0).as_secs_f64();
        self.0 = now;
        dt
    }
}

/// The available methods, for run-time selection (scene files, benchmarks, reports).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum Method {
    /// [`RelationTable`].
    RelationTable,
    /// [`CellStartGrid`].
    CellStartGrid,
    /// [`HashedGrid`].
    HashedGrid,
    /// [`BruteForce`].
    BruteForce,
}

impl Method {
    /// The fast methods (everything but the oracle).
    pub const FAST: [Method; 3] = [
        Method::RelationTable,
        Method::CellStartGrid,
        Method::HashedGrid,
    ];

    /// The method's stable name.
    pub fn name(self) -> &'static str {
        match self {
            Method::RelationTable => "relation-table",
            Method::CellStartGrid => "cell-start-grid",
            Method::HashedGrid => "hashed-grid",
            Method::BruteForce => "brute-force",
        }
    }

    /// A boxed searcher of this method for precision `R`.
    pub fn build<R: Real>(self) -> Box<dyn NeighbourSearch<R>> {
        match self {
            Method::RelationTable => Box::new(RelationTable::<R>::new()),
            Method::CellStartGrid => Box::new(CellStartGrid::<R>::new()),
            Method::HashedGrid => Box::new(HashedGrid::<R>::new()),
            Method::BruteForce => Box::new(BruteForce::new()),
        }
    }
}

impl std::str::FromStr for Method {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        [
            Method::RelationTable,
            Method::CellStartGrid,
            Method::HashedGrid,
            Method::BruteForce,
        ]
        .into_iter()
        .find(|m| m.name() == s)
        .ok_or_else(|| {
            format!(
                "unknown neighbour-search method {s:?} (expected relation-table, \
                     cell-start-grid, hashed-grid or brute-force)"
            )
        })
    }
}
