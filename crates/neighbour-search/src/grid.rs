//! Sorted uniform grids: the cell start/end table of Green (2008) and a hashed variant.

use rayon::prelude::*;
use rustc_hash::FxHashMap;
use sph_core::{Real, Vec3};

use crate::cells::{cell_size, compute_cells, Key, KeyPacker};
use crate::csr::{assemble_by, items_per_task, PairGuard, TaskOutput, REPORT_EVERY};
use crate::radix::{sort_pairs, RadixScratch};
use crate::runs::run_starts;
use crate::scan::Gathered;
use crate::{NeighbourLists, NeighbourSearch, SearchError, SearchStats, Stopwatch};

/// Cells (runs) handled by one parallel task.
const CELLS_PER_TASK: usize = 64;
const EMPTY: u32 = u32::MAX;
/// Default limit on the cells of [`CellStartGrid`]: 2²⁶ cells, 512 MiB of start/end table.
pub const DEFAULT_MAX_CELLS: usize = 1 << 26;

/// Up to nine candidate ranges (one per (dx, dy) column of three z-cells, which are
/// contiguous in the sorted order) in sorted-particle indices.
type Ranges = ([(u32, u32); 9], usize);

/// Particles sorted by cell key, with their runs; shared by both grids.
#[derive(Debug, Clone)]
struct SortedParticles<R: Real, K> {
    cells: Vec<[i32; 3]>,
    keys: Vec<K>,
    /// `order[k]` = caller's index of the k-th particle in cell order.
    order: Vec<u32>,
    /// Positions in cell order, structure of arrays.
    xs: Vec<R>,
    ys: Vec<R>,
    zs: Vec<R>,
    runs: Vec<u32>,
    block_counts: Vec<usize>,
    radix: RadixScratch<K>,
    tasks: Vec<(TaskOutput, Gathered<R>)>,
    stats: SearchStats,
}

impl<R: Real, K: Key> Default for SortedParticles<R, K> {
    fn default() -> Self {
        Self {
            cells: Vec::new(),
            keys: Vec::new(),
            order: Vec::new(),
            xs: Vec::new(),
            ys: Vec::new(),
            zs: Vec::new(),
            runs: Vec::new(),
            block_counts: Vec::new(),
            radix: RadixScratch::default(),
            tasks: Vec::new(),
            stats: SearchStats::default(),
        }
    }
}

impl<R: Real, K: Key> SortedParticles<R, K> {
    /// Sorts the particles by `key(cell)` (Green's "calcHash + sort"), copies the positions
    /// into that order and finds the runs of equal cells ("find cell start").
    fn sort(&mut self, positions: &[Vec3<R>], bits: u32, key: impl Fn([i32; 3]) -> K + Sync) {
        let n = positions.len();
        let mut watch = Stopwatch::start();
        self.keys.clear();
        self.keys.par_extend(self.cells.par_iter().map(|&c| key(c)));
        self.order.clear();
        self.order.par_extend((0..n as u32).into_par_iter());
        self.stats.cells_s += watch.lap();
        // Particles kept in cell order by the caller (the usual case in a solver, see
        // `CellSorter`) need no sort: check first, it costs one pass over the keys.
        let sorted = self
            .keys
            .par_windows(2)
            .with_min_len(4096)
            .all(|w| w[0] <= w[1]);
        if !sorted {
            sort_pairs(&mut self.keys, &mut self.order, bits, &mut self.radix);
        }
        for (a, dst) in [&mut self.xs, &mut self.ys, &mut self.zs]
            .into_iter()
            .enumerate()
        {
            dst.clear();
            dst.par_extend(self.order.par_iter().map(|&i| positions[i as usize][a]));
        }
        self.stats.sort_s = watch.lap();
        run_starts(&self.keys, &mut self.runs, &mut self.block_counts);
        self.stats.table_s = watch.lap();
    }
}

/// Tests each particle of each run against the candidate ranges given by `locate` (called
/// with the sorted index of the run's first particle). The candidates of a cell's 27
/// neighbour cells are first gathered into one contiguous block: measured on the dam-break
/// anchor scene, this beats scanning the nine ranges in place (their ragged ends cost
/// more than the copy, which is shared by the ~8 particles of a cell). The cell's particles
/// are then scanned in one call of the kernel (one output reservation per cell, not per
/// particle), with the lists of a particle-by-particle scan. Keeps to the
/// [`crate::SearchLimits`] of `out`.
///
/// Points `active..` are passive ([`NeighbourSearch::search_active`]): a cell's particles
/// are in increasing caller index (the stable sort), so its active particles come first
/// and are scanned as above; its passive ones are scanned once per cell against the active
/// candidates only, gathered in the same order, so that each passive list is the full
/// search's list with the passive entries taken out, entry for entry. `active >= n`: the
/// full search.
#[allow(clippy::too_many_arguments)]
fn query_runs<R: Real>(
    runs: &[u32],
    (xs, ys, zs): (&[R], &[R], &[R]),
    order: &[u32],
    tasks: &mut Vec<(TaskOutput, Gathered<R>)>,
    active: usize,
    r2: R,
    out: &mut NeighbourLists,
    stats: &mut SearchStats,
    locate: impl Fn(usize) -> Ranges + Sync,
) -> Result<(), SearchError> {
    let mut watch = Stopwatch::start();
    let n = xs.len();
    let bound = active.min(n) as u32;
    let run_count = runs.len() - 1;
    let per_task = items_per_task(run_count, CELLS_PER_TASK);
    let task_count = run_count.div_ceil(per_task);
    if tasks.len() < task_count {
        tasks.resize_with(task_count, Default::default);
    }
    let limits = out.limits.clone();
    let guard = PairGuard::new(&limits);
    tasks[..task_count]
        .par_iter_mut()
        .enumerate()
        .for_each(|(task, (buf, g))| {
            buf.clear();
            let first = task * per_task;
            'runs: for r in first..(first + per_task).min(run_count) {
                if guard.stopped() {
                    break;
                }
                let (start, end) = (runs[r] as usize, runs[r + 1] as usize);
                let mid = start + order[start..end].partition_point(|&i| i < bound);
                let (ranges, count) = locate(start);
                let ranges = &ranges[..count];
                if mid > start {
                    g.clear();
                    let mut own = 0;
                    for &(a, b) in ranges {
                        let (a, b) = (a as usize, b as usize);
                        if a <= start && start < b {
                            own = g.len() + start - a;
                        }
                        g.extend(&xs[a..b], &ys[a..b], &zs[a..b], &order[a..b]);
                    }
                    let len = g.finish();
                    if !scan_cell(buf, g, &guard, len, own, &order[start..mid], r2) {
                        break 'runs;
                    }
                }
                if mid < end {
                    g.clear();
                    for &(a, b) in ranges {
                        let (a, b) = (a as usize, b as usize);
                        g.extend_below(&xs[a..b], &ys[a..b], &zs[a..b], &order[a..b], bound);
                    }
                    let len = g.len();
                    g.extend(
                        &xs[mid..end],
                        &ys[mid..end],
                        &zs[mid..end],
                        &order[mid..end],
                    );
                    g.finish();
                    if !scan_cell(buf, g, &guard, len, len, &order[mid..end], r2) {
                        break 'runs;
                    }
                }
            }
            buf.report(&guard);
        });
    stats.query_s = watch.lap();
    crate::scan::equalise_capacities(&mut tasks[..]);
    stats.candidate_tests = tasks[..task_count].iter().map(|t| t.0.tests).sum();
    guard.verdict(tasks[..task_count].iter().map(|t| &t.0))?;
    assemble_by(out, n, &mut tasks[..task_count], |t| &t.0, |t| &mut t.0)?;
    stats.assemble_s = watch.lap();
    Ok(())
}

/// Scans the particles `ids` (at `own..` in the gathered block `g`) against its first `len`
/// candidates into `buf`, in pieces whose lists can hold at most about `REPORT_EVERY`
/// pairs, so that a dense cell neither reserves nor finds much past the pair limit;
/// `false` when the search must stop.
#[inline]
fn scan_cell<R: Real>(
    buf: &mut TaskOutput,
    g: &Gathered<R>,
    guard: &PairGuard<'_>,
    len: usize,
    own: usize,
    ids: &[u32],
    r2: R,
) -> bool {
    buf.tests += (len * ids.len()) as u64;
    let piece = (REPORT_EVERY / len.max(1)).max(1);
    for first in (0..ids.len()).step_by(piece) {
        let part = &ids[first..(first + piece).min(ids.len())];
        let at = own + first;
        let scan = |nb: &mut Vec<u32>, ps: &mut Vec<(u32, u32)>| {
            g.neighbours_of_run(len, at, part, r2, nb, ps)
        };
        if !buf.record_run(guard, scan) {
            return false;
        }
    }
    true
}

/// Merges the ranges of three z-consecutive cells (contiguous in sorted order) into one.
#[inline]
fn push_column(ranges: &mut Ranges, cells: impl Iterator<Item = Option<(u32, u32)>>) {
    let (mut a, mut b) = (EMPTY, 0);
    for (s, e) in cells.flatten() {
        a = a.min(s);
        b = b.max(e);
    }
    if a != EMPTY {
        ranges.0[ranges.1] = (a, b);
        ranges.1 += 1;
    }
}

/// The classic sorted uniform grid with a cell start/end table, after
///
/// > Simon Green, "Particle Simulation using CUDA", NVIDIA whitepaper, 2008 (2010 revision),
/// > sections "Uniform grid", "Building the grid using sorting".
///
/// Per search: the cells' bounding grid `[lo, hi]` is taken from the particles, each particle
/// gets the linear index of its cell, particles are radix-sorted by it and copied into that
/// order, and a start/end table over **every cell of the bounding grid** is cleared and
/// filled. A particle then visits its 27 neighbour cells through the table (the three cells
/// of each z-column are contiguous, so nine ranges). The table costs memory and clearing
/// time proportional to the bounding grid's volume, which is what Im & Chan's method avoids;
/// a grid of more than `max_cells` cells is refused with [`SearchError::DomainTooLarge`].
#[derive(Debug, Clone)]
pub struct CellStartGrid<R: Real> {
    max_cells: usize,
    sorted: SortedParticles<R, u64>,
    cell_start: Vec<u32>,
    cell_end: Vec<u32>,
}

impl<R: Real> Default for CellStartGrid<R> {
    fn default() -> Self {
        Self::new()
    }
}

impl<R: Real> CellStartGrid<R> {
    /// A grid limited to [`DEFAULT_MAX_CELLS`] cells.
    pub fn new() -> Self {
        Self::with_max_cells(DEFAULT_MAX_CELLS)
    }

    /// A grid limited to `max_cells` cells in its start/end table.
    pub fn with_max_cells(max_cells: usize) -> Self {
        Self {
            max_cells,
            sorted: SortedParticles::default(),
            cell_start: Vec::new(),
            cell_end: Vec::new(),
        }
    }

    /// Cells in the last start/end table.
    pub fn table_cells(&self) -> usize {
        self.cell_start.len()
    }
}

impl<R: Real> NeighbourSearch<R> for CellStartGrid<R> {
    fn name(&self) -> &'static str {
        "cell-start-grid"
    }

    fn stats(&self) -> SearchStats {
        self.sorted.stats
    }

    fn search(
        &mut self,
        positions: &[Vec3<R>],
        radius: R,
        out: &mut NeighbourLists,
    ) -> Result<(), SearchError> {
        self.search_active(positions, positions.len(), radius, out)
    }

    fn search_active(
        &mut self,
        positions: &[Vec3<R>],
        active: usize,
        radius: R,
        out: &mut NeighbourLists,
    ) -> Result<(), SearchError> {
        let mut watch = Stopwatch::start();
        let cell = cell_size(radius)?;
        let bounds = compute_cells(positions, cell, &mut self.sorted.cells)?;
        let Some((lo, hi)) = bounds else {
            return out.reset(0);
        };
        let dims: [u64; 3] = std::array::from_fn(|a| (hi[a] as i64 - lo[a] as i64 + 1) as u64);
        let total = dims[0] as f64 * dims[1] as f64 * dims[2] as f64;
        if total > self.max_cells as f64 {
            return Err(SearchError::DomainTooLarge {
                cells: total,
                limit: self.max_cells,
            });
        }
        let total = (dims[0] * dims[1] * dims[2]) as usize;
        let linear = move |c: [i32; 3]| -> u64 {
            let x = (c[0] as i64 - lo[0] as i64) as u64;
            let y = (c[1] as i64 - lo[1] as i64) as u64;
            let z = (c[2] as i64 - lo[2] as i64) as u64;
            (x * dims[1] + y) * dims[2] + z
        };
        let bits = 64 - ((total - 1) as u64).leading_zeros();
        self.sorted.stats = SearchStats {
            cells_s: watch.lap(),
            ..Default::default()
        };
        self.sorted.sort(positions, bits, linear);
        watch.lap();
        // Clear and fill the start/end table over the whole bounding grid.
        self.cell_start.clear();
        for table in [&mut self.cell_start, &mut self.cell_end] {
            let more = total.saturating_sub(table.len());
            table.try_reserve(more).map_err(|e| {
                SearchError::out_of_memory::<u32>("the cell start/end table", total, e)
            })?;
        }
        self.cell_start.resize(total, EMPTY);
        self.cell_end.resize(total, 0);
        let runs = &self.sorted.runs;
        for r in 0..runs.len() - 1 {
            let key = self.sorted.keys[runs[r] as usize] as usize;
            self.cell_start[key] = runs[r];
            self.cell_end[key] = runs[r + 1];
        }
        self.sorted.stats.table_s += watch.lap();
        let (start, end) = (&self.cell_start[..], &self.cell_end[..]);
        let (cells, order) = (&self.sorted.cells[..], &self.sorted.order[..]);
        let locate = |k: usize| -> Ranges {
            let c = cells[order[k] as usize];
            let mut ranges: Ranges = ([(0, 0); 9], 0);
            let rel: [i64; 3] = std::array::from_fn(|a| c[a] as i64 - lo[a] as i64);
            let (z0, z1) = ((rel[2] - 1).max(0), (rel[2] + 1).min(dims[2] as i64 - 1));
            for dx in -1..=1i64 {
                let x = rel[0] + dx;
                if x < 0 || x >= dims[0] as i64 {
                    continue;
                }
                for dy in -1..=1i64 {
                    let y = rel[1] + dy;
                    if y < 0 || y >= dims[1] as i64 {
                        continue;
                    }
                    let base = ((x as u64 * dims[1] + y as u64) * dims[2]) as usize;
                    push_column(
                        &mut ranges,
                        (z0..=z1).map(|z| {
                            let i = base + z as usize;
                            (start[i] != EMPTY).then(|| (start[i], end[i]))
                        }),
                    );
                }
            }
            ranges
        };
        query_runs(
            &self.sorted.runs,
            (&self.sorted.xs, &self.sorted.ys, &self.sorted.zs),
            &self.sorted.order,
            &mut self.sorted.tasks,
            active,
            radius * radius,
            out,
            &mut self.sorted.stats,
            locate,
        )
    }
}

/// A sorted grid for **unbounded** domains, in the spirit of compact hashing:
///
/// > Markus Ihmsen, Nadir Akinci, Markus Becker and Matthias Teschner, "A Parallel SPH
/// > Implementation on Multi-Core CPUs", *Computer Graphics Forum* 30(1), 2011, 99–112
/// > (compact hashing), the scheme behind CompactNSearch, SPlisHSPlasH's search.
///
/// Like [`CellStartGrid`], particles are sorted by cell, but the cell → particle-range table
/// is a hash map over the **occupied** cells only, so memory scales with the particles, not
/// with the extent of the scene. Deviation: Ihmsen et al. hash cells into a fixed-size table
/// of buckets with a handle array of used cells; here a general hash map (FxHash) of the
/// occupied cells' packed keys is rebuilt each search, and the particles are sorted by an
/// order-preserving packed cell key (lexicographic, `u64` when the occupied range fits,
/// `u128` otherwise), so the three cells of a z-column are one contiguous range.
#[derive(Debug, Clone)]
pub struct HashedGrid<R: Real> {
    narrow: SortedParticles<R, u64>,
    wide: SortedParticles<R, u128>,
    map_narrow: FxHashMap<u64, (u32, u32)>,
    map_wide: FxHashMap<u128, (u32, u32)>,
    stats: SearchStats,
}

impl<R: Real> Default for HashedGrid<R> {
    fn default() -> Self {
        Self::new()
    }
}

impl<R: Real> HashedGrid<R> {
    /// A new search with empty buffers.
    pub fn new() -> Self {
        Self {
            narrow: SortedParticles::default(),
            wide: SortedParticles::default(),
            map_narrow: FxHashMap::default(),
            map_wide: FxHashMap::default(),
            stats: SearchStats::default(),
        }
    }
}

#[allow(clippy::too_many_arguments)]
fn hashed_search<R: Real, K: Key>(
    s: &mut SortedParticles<R, K>,
    map: &mut FxHashMap<K, (u32, u32)>,
    packer: &KeyPacker,
    positions: &[Vec3<R>],
    active: usize,
    r2: R,
    out: &mut NeighbourLists,
    cells_s: f64,
) -> Result<(), SearchError> {
    s.stats = SearchStats {
        cells_s,
        ..Default::default()
    };
    s.sort(positions, packer.bits, |c| packer.pack(c));
    let mut watch = Stopwatch::start();
    map.clear();
    for r in 0..s.runs.len() - 1 {
        map.insert(s.keys[s.runs[r] as usize], (s.runs[r], s.runs[r + 1]));
    }
    s.stats.table_s += watch.lap();
    let (cells, order) = (&s.cells[..], &s.order[..]);
    let map = &*map;
    let locate = |k: usize| -> Ranges {
        let c = cells[order[k] as usize];
        let mut ranges: Ranges = ([(0, 0); 9], 0);
        for dx in -1..=1 {
            for dy in -1..=1 {
                push_column(
                    &mut ranges,
                    (-1..=1).map(|dz| {
                        map.get(&packer.pack::<K>([c[0] + dx, c[1] + dy, c[2] + dz]))
                            .copied()
                    }),
                );
            }
        }
        ranges
    };
    query_runs(
        &s.runs,
        (&s.xs, &s.ys, &s.zs),
        &s.order,
        &mut s.tasks,
        active,
        r2,
        out,
        &mut s.stats,
        locate,
    )
}

impl<R: Real> NeighbourSearch<R> for HashedGrid<R> {
    fn name(&self) -> &'static str {
        "hashed-grid"
    }

    fn stats(&self) -> SearchStats {
        self.stats
    }

    fn search(
        &mut self,
        positions: &[Vec3<R>],
        radius: R,
        out: &mut NeighbourLists,
    ) -> Result<(), SearchError> {
        self.search_active(positions, positions.len(), radius, out)
    }

    fn search_active(
        &mut self,
        positions: &[Vec3<R>],
        active: usize,
        radius: R,
        out: &mut NeighbourLists,
    ) -> Result<(), SearchError> {
        let mut watch = Stopwatch::start();
        let cell = cell_size(radius)?;
        // Both key widths share the cell computation; the narrow one holds the cells.
        let bounds = compute_cells(positions, cell, &mut self.narrow.cells)?;
        let Some((lo, hi)) = bounds else {
            return out.reset(0);
        };
        let packer = KeyPacker::new(lo, hi, 1);
        let r2 = radius * radius;
        let t = watch.lap();
        if packer.fits_u64() {
            hashed_search(
                &mut self.narrow,
                &mut self.map_narrow,
                &packer,
                positions,
                active,
                r2,
                out,
                t,
            )?;
            self.stats = self.narrow.stats;
        } else {
            std::mem::swap(&mut self.narrow.cells, &mut self.wide.cells);
            let result = hashed_search(
                &mut self.wide,
                &mut self.map_wide,
                &packer,
                positions,
                active,
                r2,
                out,
                t,
            );
            std::mem::swap(&mut self.narrow.cells, &mut self.wide.cells);
            result?;
            self.stats = self.wide.stats;
        }
        Ok(())
    }
}
