//! `Pbf::step` does not allocate once its buffers have grown (counting global allocator;
//! this file is its own test binary, with a single test so nothing else allocates).

mod common;

use pbf::Pbf;
use sph_solver::testing::CountingAllocator;

#[global_allocator]
static GLOBAL: CountingAllocator = CountingAllocator::new();

#[test]
fn step_does_not_allocate_when_warm() {
    common::in_pool(2, || {
        let (mut p, mut state, solids) = common::dam_break::<f32>();
        p.common.reorder_every = 3;
        let mut solver = Pbf::new(p, solids).unwrap();
        let start = GLOBAL.count();
        solver.step(&mut state).unwrap();
        assert!(
            GLOBAL.count() > start,
            "the counter sees the first step's buffers"
        );
        // Warm up: buffers grow to the particle count and the neighbour lists to the
        // largest pair count of the run so far.
        for _ in 0..19 {
            solver.step(&mut state).unwrap();
        }
        let before = GLOBAL.count();
        for _ in 0..6 {
            solver.step(&mut state).unwrap();
        }
        let count = GLOBAL.count() - before;
        assert_eq!(
            count, 0,
            "{count} allocations in 6 warm steps (with 2 reorders)"
        );
    });
}
