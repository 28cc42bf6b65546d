//! Assembly of per-task neighbour buffers into [`NeighbourLists`], without allocation once
//! the buffers have grown.

// Unsafe: disjoint parallel writes through `SyncPtr` (each index written by one task), and unchecked indexing in the hot loop behind checked bounds; see the SAFETY comments.
#![allow(unsafe_code)]

use rayon::prelude::*;

use crate::sync_ptr::SyncPtr;
use crate::NeighbourLists;

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
}

impl TaskOutput {
    pub fn clear(&mut self) {
        self.particles.clear();
        self.neighbours.clear();
        self.tests = 0;
    }
}

/// Writes the tasks' results into `out` for `n` particles.
/// Every particle must appear in exactly one task. The tasks may be any type holding a
/// [`TaskOutput`].
pub(crate) fn assemble_by<T: Sync>(
    out: &mut NeighbourLists,
    n: usize,
    tasks: &mut [T],
    output: impl Fn(&T) -> &TaskOutput + Sync,
    output_mut: impl Fn(&mut T) -> &mut TaskOutput,
) {
    out.reset(n);
    if tasks.len() == 1 && in_caller_order(n, tasks, &output) {
        // One task holding every list in caller order: its buffer becomes the indices
        // (swapped, not copied; the old index buffer becomes the task's next buffer).
        let t = output_mut(&mut tasks[0]);
        for (k, &(_, c)) in t.particles.iter().enumerate() {
            out.offsets[k + 1] = out.offsets[k] + c as usize;
        }
        std::mem::swap(&mut out.indices, &mut t.neighbours);
        return;
    }
    if in_caller_order(n, tasks, &output) {
        // Fast path (particles already sorted by cell, as a solver keeps them): the tasks'
        // lists, concatenated, are the CSR indices; each task copies its block in parallel.
        let mut total = 0;
        for t in tasks.iter_mut().map(&output_mut) {
            t.start = total;
            total += t.neighbours.len();
        }
        out.indices.clear();
        out.indices.reserve(total);
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
        return;
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
    out.indices.clear();
    out.indices.reserve(total);
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
