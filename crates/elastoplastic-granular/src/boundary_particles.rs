//! Walls of boundary particles for the elastic–plastic solver: `sph-solver`'s boundary
//! particles (`sph_solver::boundary::particles`, Adami, Hu & Adams 2012) on the particle
//! lattice over [`ElastoplasticParams::boundary_particle_region`], [`BOUNDARY_PARTICLE_ROWS`]
//! rows deep, with the stress tensor extrapolated in place of the pressure
//! (`sph_solver::boundary::wall_extrapolation`, as Bui et al. 2008 and Project Chrono's CRM
//! do) and the artificial stress of each boundary particle derived from it. Their density
//! is `ρ0` and their mass that of a grain; they enter every sum (velocity gradient,
//! continuity, momentum, artificial viscosity and stress) as neighbours.
//!
//! Measured (`tests/walls.rs`, an elastic slab periodic along the slope at 20 mm, `μ_w` =
//! 0.4): it holds 5° below `atan μ_w` (0.02 mm in 0.6 s) and slides 5° above it, but it
//! slides faster than a Coulomb block, `g (sin θ − μ_w cos θ)` (0.69 m in 0.6 s against
//! 0.17 m): `μ_w |t_n|` caps the traction the wall takes, and the grains' own shear stress
//! next to a sliding wall, which the wall's share cannot exceed, stays below that cap.
//!

use sph_core::{Aabb, Real, Sdf, Vec3};
use sph_solver::boundary::WallLattice;
use sph_solver::{Dimensions, SolverError};

use crate::name::NAME;
use crate::params::{ElastoplasticParams, MovingWall, WallModel, BOUNDARY_PARTICLE_ROWS};

pub use sph_solver::boundary::wall_extrapolation::coulomb;
pub use sph_solver::boundary::{
    BoundaryParticle, MAX_BOUNDARY_LATTICE_NODES, MAX_BOUNDARY_PARTICLES,
};

/// Boundary particles on the cubic lattice of spacing `spacing` filling `region`, all with
/// `normal` and `model` (`sph_solver::boundary::boundary_block`, errors naming this solver).
pub fn boundary_block<R: Real>(
    region: &Aabb<R>,
    spacing: R,
    normal: Vec3<R>,
    model: WallModel,
    max_count: usize,
) -> Result<Vec<BoundaryParticle<R>>, SolverError> {
    sph_solver::boundary::boundary_block(NAME, region, spacing, normal, model, max_count)
}

/// The wall lattice of `params`: the particle lattice (spacing
/// `params.common.particle_spacing`) over `params.boundary_particle_region` extended by
/// [`BOUNDARY_PARTICLE_ROWS`] spacings off the periodic axes, cut to the plane `z = 0` in a
/// planar run ([`ElastoplasticParams::dimensions`]); `None` without a region.
pub fn wall_lattice<R: Real>(
    params: &ElastoplasticParams<R>,
) -> Result<Option<WallLattice<R>>, SolverError> {
    params
        .boundary_particle_region
        .as_ref()
        .map(|region| {
            let lattice = WallLattice::new(
                NAME,
                region,
                params.common.particle_spacing,
                BOUNDARY_PARTICLE_ROWS,
                &params.periodic,
            )?;
            if params.dimensions == Dimensions::Two {
                lattice.in_plane(2, R::zero())
            } else {
                Ok(lattice)
            }
        })
        .transpose()
}

/// The solids' walls as boundary particles on [`wall_lattice`], each with its solid's model
/// ([`ElastoplasticParams::wall_model`]; `WallLattice::sample_solids`). No region: none.
pub fn sample_solids<R: Real>(
    solids: &[Box<dyn Sdf<R>>],
    params: &ElastoplasticParams<R>,
    max_count: usize,
) -> Result<Vec<BoundaryParticle<R>>, SolverError> {
    match wall_lattice(params)? {
        Some(lattice) => lattice.sample_solids(solids, |k| params.wall_model(k), max_count),
        None => Ok(Vec::new()),
    }
}

/// The particles of the moving wall `wall` on [`wall_lattice`]
/// (`WallLattice::sample_moving_wall`). No region: none.
pub fn sample_moving_wall<R: Real>(
    wall: &MovingWall<R>,
    params: &ElastoplasticParams<R>,
    max_count: usize,
) -> Result<Vec<BoundaryParticle<R>>, SolverError> {
    match wall_lattice(params)? {
        Some(lattice) => lattice.sample_moving_wall(wall, max_count),
        None => Ok(Vec::new()),
    }
}
