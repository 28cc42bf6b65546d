//! `Pbf::step` does not allocate once its buffers have grown (counting global allocator;
//! this file is its own test binary, with a single test so nothing else allocates).

mod common;

use pbf::Pbf;
use sph_solver::testing::{assert_warm_steps_do_not_allocate, CountingAllocator};

#[global_allocator]
static GLOBAL: CountingAllocator = CountingAllocator::new();

#[test]
fn step_does_not_allocate_when_warm() {
    common::in_pool(2, || {
        let (mut p, mut state, solids) = common::dam_break::<f32>();
        p.common.reorder_every = 3;
        let mut solver = Pbf::new(p, solids).unwrap();
        assert_warm_steps_do_not_allocate(&GLOBAL, "PBF dam break", &mut solver, &mut state);
    });
}
