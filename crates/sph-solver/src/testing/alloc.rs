//! A global allocator that counts allocations, for the solvers' "a warm step allocates
//! nothing" tests. Install it in a test binary of its own (one test, so that nothing else
//! allocates while it counts):
//!
//! ```ignore
//! #[global_allocator]
//! static GLOBAL: CountingAllocator = CountingAllocator::new();
//! ```

// Unsafe: counting allocations needs a `GlobalAlloc`, which wraps `System` here (the trait's
// methods are unsafe to implement and to call).
#![allow(unsafe_code)]

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};

/// `System`, counting every `alloc` and `realloc` (not `dealloc`).
#[derive(Debug, Default)]
pub struct CountingAllocator {
    allocations: AtomicUsize,
}

impl CountingAllocator {
    /// A counter at zero.
    pub const fn new() -> Self {
        Self {
            allocations: AtomicUsize::new(0),
        }
    }

    /// Allocations and reallocations so far.
    pub fn count(&self) -> usize {
        self.allocations.load(Ordering::SeqCst)
    }
}

unsafe impl GlobalAlloc for CountingAllocator {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        self.allocations.fetch_add(1, Ordering::Relaxed);
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        self.allocations.fetch_add(1, Ordering::Relaxed);
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

/// Runs `solver` on `state` for one step (whose buffers `counter` must see allocated), 19
/// warm-up steps (buffers grow to the particle count and the neighbour lists to the largest
/// pair count so far), then 6 more, and asserts that those 6 allocate nothing (`what`
/// names the case in the message; with `reorder_every = 3` they include 2 reorders).
pub fn assert_warm_steps_do_not_allocate<R: sph_core::Real>(
    counter: &CountingAllocator,
    what: &str,
    solver: &mut dyn crate::FluidSolver<R>,
    state: &mut sph_core::ParticleSet<R>,
) {
    let start = counter.count();
    solver.step(state).unwrap();
    assert!(
        counter.count() > start,
        "{what}: the counter sees the first step's buffers"
    );
    for _ in 0..19 {
        solver.step(state).unwrap();
    }
    let before = counter.count();
    for _ in 0..6 {
        solver.step(state).unwrap();
    }
    let count = counter.count() - before;
    assert_eq!(count, 0, "{what}: {count} allocations in 6 warm steps");
}
