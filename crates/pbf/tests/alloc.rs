//! `Pbf::step` does not allocate once its buffers have grown (counting global allocator;
//! this file is its own test binary, with a single test so nothing else allocates).

// Unsafe: the allocation counter is a `GlobalAlloc` wrapping `System` (the only way to count allocations).
#![allow(unsafe_code)]

mod common;

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};

use pbf::Pbf;

struct Counting;
static ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

#[test]
fn step_does_not_allocate_when_warm() {
    common::in_pool(2, || {
        let (mut p, mut state, solids) = common::dam_break::<f32>();
        p.common.reorder_every = 3;
        let mut solver = Pbf::new(p, solids).unwrap();
        let start = ALLOCATIONS.load(Ordering::SeqCst);
        solver.step(&mut state).unwrap();
        assert!(
            ALLOCATIONS.load(Ordering::SeqCst) > start,
            "the counter sees the first step's buffers"
        );
        // Warm up: buffers grow to the particle count and the neighbour lists to the
        // largest pair count of the run so far.
        for _ in 0..19 {
            solver.step(&mut state).unwrap();
        }
        let before = ALLOCATIONS.load(Ordering::SeqCst);
        for _ in 0..6 {
            solver.step(&mut state).unwrap();
        }
        let count = ALLOCATIONS.load(Ordering::SeqCst) - before;
        assert_eq!(
            count, 0,
            "{count} allocations in 6 warm steps (with 2 reorders)"
        );
    });
}
