//! Assembly of per-task neighbour buffers into [`NeighbourLists`], without allocation once
//! the buffers have grown.

// Unsafe: disjoint parallel writes through `SyncPtr` (each index written by one task), and unchecked indexing in the hot loop behind checked bounds; see the SAFETY comments.
#![allow(unsafe_code)]

use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

use rayon::prelude::*;

use crate::sync_ptr::SyncPtr;
use crate::{NeighbourLists, SearchError, SearchLimits};

/// Pairs a task finds between two reports to the shared [`PairGuard`] (one atomic
/// addition per this many pairs: negligible next to the distance tests).
pub(crate) const REPORT_EVERY: usize = 1 << 14;

/// The [`SearchLimits`] of one search, shared by its parallel tasks: the pairs found so far
/// against `max_pairs`, the caller's interrupt flag, and a stop flag that the first task
/// to hit either (or a failed allocation) raises for all.
pub(crate) struct PairGuard<'a> {
    limit: usize,
    found: AtomicUsize,
    stop: AtomicBool,
    interrupt: Option<&'a AtomicBool>,
}

impl<'a> PairGuard<'a> {
    pub fn new(limits: &'a SearchLimits) -> Self {
        Self {
            limit: limits.max_pairs.unwrap_or(usize::MAX),
            found: AtomicUsize::new(0),
            stop: AtomicBool::new(false),
            interrupt: limits.interrupt.as_deref(),
        }
    }

    /// `true` when the search must stop (limit passed, a task failed, or interrupted).
    #[inline]
    pub fn stopped(&self) -> bool {
        self.stop.load(Ordering::Relaxed)
            || self.interrupt.is_some_and(|f| f.load(Ordering::Relaxed))
    }

    /// Adds `pairs` found by a task; `false` when the search must stop.
    pub fn report(&self, pairs: usize) -> bool {
        let total = self
            .found
            .fetch_add(pairs, Ordering::Relaxed)
            .saturating_add(pairs);
        if total > self.limit {
            self.stop.store(true, Ordering::Relaxed);
        }
        !self.stopped()
    }

    /// Stops every task (after a failed allocation).
    pub fn halt(&self) {
        self.stop.store(true, Ordering::Relaxed);
    }

    /// The search's verdict once its tasks have returned: the first task's error, the pair
    /// limit passed, or the interrupt; `Ok` when the lists are complete.
    pub fn verdict<'t>(
        &self,
        mut tasks: impl Iterator<Item = &'t TaskOutput>,
    ) -> Result<(), SearchError> {
        if let Some(e) = tasks.find_map(|t| t.failed.clone()) {
            return Err(e);
        }
        let found = self.found.load(Ordering::Relaxed);
        if found > self.limit {
            return Err(too_many_pairs(found, self.limit));
        }
        if self.stopped() {
            return Err(SearchError::Interrupted);
        }
        Ok(())
    }
}

/// [`SearchError::TooManyPairs`].
pub(crate) fn too_many_pairs(found: usize, limit: usize) -> SearchError {
    let bytes = |p: usize| p.saturating_mul(std::mem::size_of::<u32>());
    SearchError::TooManyPairs {
        found,
        found_bytes: bytes(found),
        limit,
        limit_bytes: bytes(limit),
    }
}

/// What one parallel task found: for each of its particles, `(particle, count)`, and the
/// concatenated neighbour indices.
#[derive(Debug, Default, Clone)]
pub(crate) struct TaskOutput {
    pub particles: Vec<(u32, u32)>,
    pub neighbours: Vec<u32>,
    /// Where this task's block starts in the CSR indices (fast path of `assemble_by`).
    start: usize,
    /// Candidate pairs tested.
    pub tests: u64,
    /// Pairs found since the last report to the [`PairGuard`].
    pending: usize,
    /// Why this task stopped early, if it did.
    failed: Option<SearchError>,
}

impl TaskOutput {
    pub fn clear(&mut self) {
        self.particles.clear();
        self.neighbours.clear();
        self.tests = 0;
        self.pending = 0;
        self.failed = None;
    }

    /// Scans one particle with `scan` (which appends its neighbours to the task's buffer
    /// and returns how many) and records it as particle `i`; `false` when the task must
    /// stop (a failed allocation, the pair limit passed, or the search interrupted).
    #[inline]
    pub fn record(
        &mut self,
        i: u32,
        guard: &PairGuard<'_>,
        scan: impl FnOnce(&mut Vec<u32>) -> Result<u32, std::collections::TryReserveError>,
    ) -> bool {
        let before = self.neighbours.len();
        match scan(&mut self.neighbours) {
            Ok(found) => {
                self.particles.push((i, found));
                self.pending += found as usize;
                self.pending < REPORT_EVERY || self.report(guard)
            }
            Err(e) => self.fail(before, e, guard),
        }
    }

    /// Scans a run of particles with `scan` (which appends their lists to the task's buffer
    /// and `(particle, count)` to its particles, and returns the pairs found); `false`
    /// when the task must stop, as [`TaskOutput::record`].
    #[inline]
    pub fn record_run(
        &mut self,
        guard: &PairGuard<'_>,
        scan: impl FnOnce(
            &mut Vec<u32>,
            &mut Vec<(u32, u32)>,
        ) -> Result<usize, std::collections::TryReserveError>,
    ) -> bool {
        let before = self.neighbours.len();
        match scan(&mut self.neighbours, &mut self.particles) {
            Ok(found) => {
                self.pending += found;
                self.pending < REPORT_EVERY || self.report(guard)
            }
            Err(e) => self.fail(before, e, guard),
        }
    }

    /// Records a failed allocation of the neighbour indices and stops every task.
    fn fail(
        &mut self,
        before: usize,
        e: std::collections::TryReserveError,
        guard: &PairGuard<'_>,
    ) -> bool {
        let want = self.neighbours.capacity().max(before) * 2;
        self.failed = Some(SearchError::out_of_memory::<u32>(
            "neighbour indices",
            want,
            e,
        ));
        guard.halt();
        false
    }

    /// Reports the pending pairs to `guard` (at the end of a task, so that its count is
    /// complete); `false` when the search must stop.
    pub fn report(&mut self, guard: &PairGuard<'_>) -> bool {
        guard.report(std::mem::take(&mut self.pending))
    }
}

/// Writes the tasks' results into `out` for `n` particles.
/// Every particle must appear in exactly one task. The tasks may be any type holding a
/// [`TaskOutput`]. Fails only when the index buffer cannot be allocated.
pub(crate) fn assemble_by<T: Sync>(
    out: &mut NeighbourLists,
    n: usize,
    tasks: &mut [T],
    output: impl Fn(&T) -> &TaskOutput + Sync,
    output_mut: impl Fn(&mut T) -> &mut TaskOutput,
) -> Result<(), SearchError> {
    out.reset(n)?;
    if tasks.len() == 1 && in_caller_order(n, tasks, &output) {
        // One task holding every list in caller order: its buffer becomes the indices
        // (swapped, not copied; the old index buffer becomes the task's next buffer).
        let t = output_mut(&mut tasks[0]);
        for (k, &(_, c)) in t.particles.iter().enumerate() {
            out.offsets[k + 1] = out.offsets[k] + c as usize;
        }
        std::mem::swap(&mut out.indices, &mut t.neighbours);
        return Ok(());
    }
    if in_caller_order(n, tasks, &output) {
        // Fast path (particles already sorted by cell, as a solver keeps them): the tasks'
        // lists, concatenated, are the CSR indices; each task copies its block in parallel.
        let mut total = 0;
        for t in tasks.iter_mut().map(&output_mut) {
            t.start = total;
            total += t.neighbours.len();
        }
        reserve_indices(out, total)?;
        let offs = SyncPtr(out.offsets.as_mut_ptr());
        let idx = SyncPtr(out.indices.as_mut_ptr());
        tasks.par_iter().map(&output).for_each(|t| {
            let (offs, idx) = (offs, idx);
            // SAFETY: the tasks cover consecutive, disjoint particle ranges and index
            // ranges (checked by `in_caller_order`); each writes only its own offsets
            // `offsets[i + 1]` for its particles and its own block of indices.
            unsafe {
                let mut at = t.start;
                std::ptr::copy_nonoverlapping(
                    t.neighbours.as_ptr(),
                    idx.0.add(at),
                    t.neighbours.len(),
                );
                for &(i, c) in &t.particles {
                    at += c as usize;
                    *offs.0.add(i as usize + 1) = at;
                }
            }
        });
        // SAFETY: the tasks' blocks tile [0, total).
        unsafe { out.indices.set_len(total) };
        return Ok(());
    }
    let tasks = &*tasks;
    let offs = SyncPtr(out.offsets.as_mut_ptr());
    tasks.par_iter().map(&output).for_each(|t| {
        let p = offs;
        for &(i, c) in &t.particles {
            debug_assert!((i as usize) < n);
            // SAFETY: each particle index occurs in exactly one task, so each slot of
            // `offsets[1..=n]` is written by one thread only.
            unsafe { *p.0.add(i as usize + 1) = c as usize };
        }
    });
    for i in 0..n {
        out.offsets[i + 1] += out.offsets[i];
    }
    let total = out.offsets[n];
    reserve_indices(out, total)?;
    let idx = SyncPtr(out.indices.as_mut_ptr());
    let offsets = &out.offsets;
    tasks.par_iter().map(&output).for_each(|t| {
        let p = idx;
        let mut src = 0usize;
        for &(i, c) in &t.particles {
            let dst = offsets[i as usize];
            let c = c as usize;
            debug_assert_eq!(offsets[i as usize + 1] - dst, c);
            // SAFETY: `[dst, dst + c)` is particle i's own range of `indices`, disjoint from
            // every other particle's, and within `total` by construction of the offsets.
            // An element loop: lists are short and a `memcpy` call each costs more.
            for (k, &j) in t.neighbours[src..src + c].iter().enumerate() {
                unsafe { *p.0.add(dst + k) = j };
            }
            src += c;
        }
    });
    // SAFETY: the tasks wrote every slot of [0, total): each particle's range is covered
    // by its own list, and the ranges tile [0, total) by construction of the offsets.
    unsafe { out.indices.set_len(total) };
    Ok(())
}

/// Empties `out.indices` and makes room for `total` of them, fallibly.
fn reserve_indices(out: &mut NeighbourLists, total: usize) -> Result<(), SearchError> {
    out.indices.clear();
    out.indices
        .try_reserve(total)
        .map_err(|e| SearchError::out_of_memory::<u32>("neighbour indices", total, e))
}

/// `true` when the tasks, in order, list the particles 0, 1, …, n − 1.
fn in_caller_order<T: Sync>(
    n: usize,
    tasks: &[T],
    output: &(impl Fn(&T) -> &TaskOutput + Sync),
) -> bool {
    let mut next = 0u32;
    for t in tasks.iter().map(output) {
        let Some(&(first, _)) = t.particles.first() else {
            continue;
        };
        if first != next {
            return false;
        }
        let consecutive = t
            .particles
            .iter()
            .enumerate()
            .all(|(k, &(i, _))| i == first + k as u32);
        if !consecutive {
            return false;
        }
        next += t.particles.len() as u32;
    }
    next as usize == n
}

/// Work items (cells or runs) per parallel task: `default`, or all of them in one task when
/// the pool has a single thread (which lets [`assemble_by`] hand the task's buffer over
/// without a copy). The lists do not depend on this choice.
pub(crate) fn items_per_task(items: usize, default: usize) -> usize {
    if rayon::current_num_threads() == 1 {
        items.max(1)
    } else {
        default
    }
}
