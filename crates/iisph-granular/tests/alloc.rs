//! `Iisph::step` does not allocate once its buffers have grown, for water and for granular
//! matter (friction, drag): counting global allocator. This file is its own test binary,
//! with a single test so that nothing else allocates while it counts.
//!
//! The scene is a block filling the floor of its tank, which settles in place (water) or,
//! for granular matter, without gravity (it stays at rest; friction and drag are still
//! evaluated every step). In scenes that keep moving, the neighbour search's per-task
//! buffers (`neighbour_search::grid::query_runs`, `scan::Gathered`, whose task partition
//! follows the occupied cells) keep meeting new largest neighbourhoods and grow now and
//! then: measured with 2 threads, a 12 × 16 × 10 water block collapsing in a 24 × 20 × 10
//! tank allocated 1–8 times in 10 of 60 steps after 20 warm-up steps, and this granular
//! block under gravity (it keeps creeping, see the crate docs on friction) once per 6 steps
//! after 50; every such allocation traced to the neighbour search, none to the solver's own
//! buffers.

mod common;

use iisph_granular::{IisphParams, Vec3};
use sph_solver::testing::{assert_warm_steps_do_not_allocate, in_pool, CountingAllocator};

#[global_allocator]
static GLOBAL: CountingAllocator = CountingAllocator::new();

#[test]
fn step_does_not_allocate_when_warm() {
    in_pool(2, || {
        for (name, mut p) in [
            ("water", IisphParams::<f32>::for_spacing(0.025)),
            ("granular", {
                let mut p = IisphParams::<f32>::granular(0.025, 30.0);
                p.granular.as_mut().unwrap().drag_coefficient = 1.0;
                p.common.gravity = Vec3::zeros();
                p
            }),
        ] {
            // a 10 × 12 × 10 block filling the floor of a 10 × 16 × 10 tank, masses scaled
            // so that it starts at most at ρ0 (it stays in place)
            p.common.dt = 0.004;
            p.common.substeps = 2;
            p.common.reorder_every = 3;
            let (mut solver, mut state) =
                common::relaxed_block_solver(p, [10, 12, 10], [10.0, 16.0, 10.0]);
            assert_warm_steps_do_not_allocate(&GLOBAL, name, &mut solver, &mut state);
        }
    });
}
