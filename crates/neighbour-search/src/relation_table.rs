//! The particle–cell relation table of Im & Chan (2016), section III.

use rayon::prelude::*;
use sph_core::{Real, Vec3};

use crate::cells::{cell_size, compute_cells, Key, KeyPacker};
use crate::csr::{PairGuard, TaskOutput};
use crate::radix::{sort_pairs, RadixScratch};
use crate::runs::run_starts;
use crate::scan::Gathered;
use crate::{NeighbourLists, NeighbourSearch, SearchError, SearchStats, Stopwatch};

/// Offset index of a particle's own cell among its 27 (dx, dy, dz ∈ {−1, 0, 1}, x major).
const SELF_OFFSET: u32 = 13;
/// Runs handled by one parallel task.
const RUNS_PER_TASK: usize = 128;

/// Neighbour search with the **particle–cell relation table** of
///
/// > Jaeyong Im and Chee-Kong Chan, "SPH neighbour searching and screen space fluid
/// > rendering for unlimited scenes", *International Journal of Modeling and Optimization*
/// > 6(2), 2016, section III (eq. 5, Figs. 2–3).
///
/// Each particle `i` in cell `c_i = floor(x_i / h)` (eq. 5; negative cells allowed, no
/// bounding box) writes 27 entries `(c_i + o, i)`, one for each of its 27 surrounding cells
/// `o ∈ {−1,0,1}³`: "particle `i` is a candidate for anyone in cell `c_i + o`". The table is
/// sorted lexicographically by cell with a stable parallel radix sort (the paper's Fig. 2
/// comparison, realised as an order-preserving packed key), so that the run of entries for
/// cell `C` holds exactly the particles of the 27 cells around `C`. Each particle then
/// scans the one run of its own cell, found through its own `o = 0` entry, testing the
/// distance to every entry. No cell start table over a bounded grid exists at any point.
///
/// Deviations from the paper, all documented here:
/// - cells are `h(1 + 10⁻⁶)` wide, not `h` (see [`crate::CELL_MARGIN`]);
/// - the lexicographic comparison of `(X, Y, Z)` is done on an integer key whose field
///   widths follow the occupied cell range (`u64` when it fits, `u128` otherwise), which a
///   radix sort can use directly; the order is exactly the paper's;
/// - the table stores `27·i + o` instead of `i`, so that a particle recognises its own entry.
///
/// Cost: 27 entries (12 or 20 bytes) written and radix-sorted per particle, against one
/// for the cell-start grid; the query reads one contiguous run per particle. Neighbours
/// come out in increasing index order (the sort is stable).
#[derive(Debug, Clone)]
pub struct RelationTable<R: Real> {
    cells: Vec<[i32; 3]>,
    narrow: Table<u64>,
    wide: Table<u128>,
    work: Workspace<R>,
}

#[derive(Debug, Default, Clone)]
struct Table<K> {
    keys: Vec<K>,
    vals: Vec<u32>,
    radix: RadixScratch<K>,
}

#[derive(Debug, Clone)]
struct Workspace<R: Real> {
    runs: Vec<u32>,
    block_counts: Vec<usize>,
    tasks: Vec<(TaskOutput, Gathered<R>)>,
    stats: SearchStats,
}

impl<R: Real> Default for RelationTable<R> {
    fn default() -> Self {
        Self::new()
    }
}

impl<R: Real> RelationTable<R> {
    /// A new search with empty buffers (they grow on first use and are reused).
    pub fn new() -> Self {
        Self {
            cells: Vec::new(),
            narrow: Table::default(),
            wide: Table::default(),
            work: Workspace {
                runs: Vec::new(),
                block_counts: Vec::new(),
                tasks: Vec::new(),
                stats: SearchStats::default(),
            },
        }
    }

    /// Entries in the last relation table (27 per particle).
    pub fn table_len(&self) -> usize {
        self.narrow.keys.len().max(self.wide.keys.len())
    }
}

impl<R: Real> NeighbourSearch<R> for RelationTable<R> {
    fn name(&self) -> &'static str {
        "relation-table"
    }

    fn stats(&self) -> SearchStats {
        self.work.stats
    }

    fn search(
        &mut self,
        positions: &[Vec3<R>],
        radius: R,
        out: &mut NeighbourLists,
    ) -> Result<(), SearchError> {
        let watch = Stopwatch::start();
        let cell = cell_size(radius)?;
        let bounds = compute_cells(positions, cell, &mut self.cells)?;
        let Some((lo, hi)) = bounds else {
            return out.reset(0);
        };
        let packer = KeyPacker::new(lo, hi, 1);
        let (cells, r2, work) = (&self.cells[..], radius * radius, &mut self.work);
        if packer.fits_u64() {
            self.wide.keys.clear();
            build_and_query(
                &mut self.narrow,
                cells,
                &packer,
                positions,
                r2,
                work,
                out,
                watch,
            )
        } else {
            self.narrow.keys.clear();
            build_and_query(
                &mut self.wide,
                cells,
                &packer,
                positions,
                r2,
                work,
                out,
                watch,
            )
        }
    }
}

#[allow(clippy::too_many_arguments)]
fn build_and_query<K: Key, R: Real>(
    t: &mut Table<K>,
    cells: &[[i32; 3]],
    packer: &KeyPacker,
    positions: &[Vec3<R>],
    r2: R,
    work: &mut Workspace<R>,
    out: &mut NeighbourLists,
    mut watch: Stopwatch,
) -> Result<(), SearchError> {
    let n = cells.len();
    // 1. Each particle writes its 27 entries (Fig. 3a).
    let entries = 27 * n;
    let oom = |e| SearchError::out_of_memory::<(K, u32)>("the relation table", entries, e);
    t.keys
        .try_reserve(entries.saturating_sub(t.keys.len()))
        .map_err(oom)?;
    t.vals
        .try_reserve(entries.saturating_sub(t.vals.len()))
        .map_err(oom)?;
    t.keys.resize(27 * n, K::default());
    t.vals.resize(27 * n, 0);
    t.keys
        .par_chunks_mut(27)
        .zip(t.vals.par_chunks_mut(27))
        .zip(cells.par_iter())
        .enumerate()
        .with_min_len(1024)
        .for_each(|(i, ((k, v), c))| {
            let mut o = 0;
            for dx in -1..=1 {
                for dy in -1..=1 {
                    for dz in -1..=1 {
                        k[o] = packer.pack([c[0] + dx, c[1] + dy, c[2] + dz]);
                        v[o] = 27 * i as u32 + o as u32;
                        o += 1;
                    }
                }
            }
        });
    work.stats.cells_s = watch.lap();
    // 2. Lexicographic sort by cell (Fig. 3b).
    sort_pairs(&mut t.keys, &mut t.vals, packer.bits, &mut t.radix);
    work.stats.sort_s = watch.lap();
    // 3. Runs of equal cells (Fig. 3c: each run's start and number).
    run_starts(&t.keys, &mut work.runs, &mut work.block_counts);
    let run_count = work.runs.len() - 1;
    work.stats.table_s = watch.lap();
    // 4. Each particle scans the run of its own cell.
    let per_task = crate::csr::items_per_task(run_count, RUNS_PER_TASK);
    let task_count = run_count.div_ceil(per_task);
    if work.tasks.len() < task_count {
        work.tasks.resize_with(task_count, Default::default);
    }
    let vals = &t.vals;
    let runs = &work.runs[..];
    let limits = out.limits.clone();
    let guard = PairGuard::new(&limits);
    work.tasks[..task_count]
        .par_iter_mut()
        .enumerate()
        .for_each(|(task, (buf, g))| {
            buf.clear();
            let first = task * per_task;
            let last = (first + per_task).min(run_count);
            'runs: for r in first..last {
                if guard.stopped() {
                    break;
                }
                let run = &vals[runs[r] as usize..runs[r + 1] as usize];
                if !run.iter().any(|&v| v % 27 == SELF_OFFSET) {
                    continue; // a cell that holds no particle: nobody scans this run
                }
                g.clear();
                for &v in run {
                    let p = &positions[(v / 27) as usize];
                    g.push(p.x, p.y, p.z, v / 27);
                }
                let len = g.finish();
                for (e, &v) in run.iter().enumerate() {
                    if v % 27 == SELF_OFFSET {
                        buf.tests += len as u64;
                        let scan = |nb: &mut Vec<u32>| g.neighbours_of(len, e, r2, nb);
                        if !buf.record(v / 27, &guard, scan) {
                            break 'runs;
                        }
                    }
                }
            }
            buf.report(&guard);
        });
    work.stats.query_s = watch.lap();
    crate::scan::equalise_capacities(&mut work.tasks[..]);
    work.stats.candidate_tests = work.tasks[..task_count].iter().map(|t| t.0.tests).sum();
    let tasks = &mut work.tasks[..task_count];
    guard.verdict(tasks.iter().map(|t| &t.0))?;
    crate::csr::assemble_by(out, n, tasks, |t| &t.0, |t| &mut t.0)?;
    work.stats.assemble_s = watch.lap();
    Ok(())
}
