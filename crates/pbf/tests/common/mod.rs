//! Scenes, oracle formulas and helpers shared by the integration tests.
#![allow(dead_code)]

#[allow(unused_imports)]
pub use sph_solver::testing::{assert_nan_position_rejected, bits, formulas, in_pool};

use pbf::{CommonParams, ParticleSet, PbfParams, Real, Solids};
use sph_core::Aabb;

/// [`sph_solver::testing::block_in_tank`] with PBF's parameters.
pub fn block_in_tank<R: Real>(
    params: &PbfParams<R>,
    n: [usize; 3],
    tank: [f64; 3],
) -> (ParticleSet<R>, Solids<R>, Aabb<R>) {
    sph_solver::testing::block_in_tank(&params.common, n, tank)
}

/// A small dam break: a block of 8 × 12 × 6 particles in the corner of a tank of
/// 24 × 16 × 6 spacings, with vorticity confinement on (so every code path runs).
pub fn dam_break<R: Real>() -> (PbfParams<R>, ParticleSet<R>, Solids<R>) {
    let mut p = PbfParams::<R> {
        vorticity_epsilon: R::of_f64(0.05),
        ..Default::default()
    };
    p.common = CommonParams {
        reorder_every: 5,
        ..p.common
    };
    let (state, solids, _) = block_in_tank(&p, [8, 12, 6], [24.0, 16.0, 6.0]);
    (p, state, solids)
}
