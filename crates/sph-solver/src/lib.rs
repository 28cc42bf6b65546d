#![doc = include_str!("../README.md")]
//!
//! ## In detail
//!
//! The shared layer of the workspace's particle solvers.
//!
//! - [`FluidSolver`]: the object-safe interface of every solver (PBF, PCISPH, …), so a scene
//!   runner holds a `Box<dyn FluidSolver<R>>`; one call advances one frame of substeps.
//! - [`StepStats`]: solver-neutral statistics of a frame, each solver naming its own phases
//!   ([`PhaseTimes`]); non-convergence is a statistic, a blow-up a [`SolverError`].
//! - [`CommonParams`]: rest density, spacing, support radius, frame length, substeps,
//!   gravity, reordering, neighbour method, embedded as `common` in each solver's parameters.
//! - [`step`]: the plumbing the solvers share inside a step (state checks, the neighbour
//!   search, reordering by cell, blow-up checks before the state is written, statistics).
//! - [`initial`]: the density a fluid lattice starts at with the boundary's share, and
//!   masses calibrated so that no particle starts above the rest density.
//! - [`boundary`]: solid boundaries as values behind the [`Boundary`] trait, with two
//!   models: [`CollisionBoundary`] (projection out of signed distance fields) and
//!   `VolumeMapBoundary` (Bender, Kugelstadt, Weiler & Koschier 2019, "Volume Maps: An
//!   Implicit Boundary Representation for SPH", MIG '19), where the walls take part in the
//!   density.
//!
//! - [`FrameSolver`]: the one frame shell. A solver is a [`SubstepScheme`] (its name, phase
//!   table, density kernel as a [`KernelKind`], parameters and one time step); the shell
//!   checks and reorders the state, runs the substeps, times the phases, keeps the frame
//!   counter and implements [`FluidSolver`] once for every solver.
//! - [`SolverState`]: what a solver carries from one frame to the next besides the
//!   particles ([`FluidSolver::save_state`], [`FluidSolver::restore_state`]), for runs that
//!   resume bit for bit from a checkpoint.
//!
//! # Adding a solver
//!
//! A new solver (DFSPH, say) is one crate that depends on this one and on no other solver,
//! shaped like `pbf`, `pcisph` and `iisph-granular`:
//!
//! - `params.rs`: its parameters with `common: CommonParams<R>` and a `validate` that bounds
//!   every iteration count by a named public maximum;
//! - `kernels.rs`: the kernels and constants of its loops, built once from the parameters;
//! - `scratch.rs`: its per-particle buffers (structure of arrays), resized once per frame;
//! - `passes.rs`: the per-particle loops (each writes one particle's values, so results do
//!   not depend on the thread count);
//! - `params.rs` also implements [`SolverParameters`] for the parameters (the solver's
//!   name, `common`, `validate`, `convert` between precisions), once for the frame shell
//!   and the settings;
//! - `solver.rs`: `pub struct DfsphScheme<R>` implementing [`SubstepScheme`] (
//!   `PHASES`, `FRAME_PHASES`, `DENSITY_KERNEL`, `new`, `begin_frame`,
//!   `substep`, and `save_arrays`/`restore_arrays` when it carries anything between frames,
//!   e.g. warm-started pressures) and `pub type Dfsph<R> = FrameSolver<R, DfsphScheme<R>>`.
//!
//! - `settings.rs`: `DfsphSettings`, its scene-facing `[solver]` table (serde,
//!   `deny_unknown_fields`, [`CommonSettings`] flattened, each key the name of the
//!   parameter it sets), implementing [`SolverSettings`] (see [`settings`]), which also
//!   declares the scene boundary features it takes ([`scene_boundary`]).
//!
//! `Dfsph::new(params, solids)` and `Dfsph::with_boundary(params, boundary)` then exist, and
//! `Dfsph<R>` is a [`FluidSolver`]. Scene files reach it through one registration line in
//! `sph-scene` (`Dfsph = "dfsph", dfsph::DfsphSettings [];`), from which the scene's solver
//! enums, the factory and the density kernel follow.

pub mod boundary;
pub mod cone_match;
pub mod csr;
pub mod density_lanes;
mod dimensions;
mod error;
mod fluid_solver;
pub mod frame;
pub mod initial;
pub mod pair_lanes;
mod parameters;
mod params;
pub mod scene_boundary;
pub mod settings;
pub mod state;
mod stats;
pub mod step;
#[cfg(feature = "testing")]
pub mod testing;

pub use boundary::{
    half_space_volume, half_space_volume_derivative, Boundary, BoundarySample, ClosestPoint,
    CollisionBoundary, ContactGuard, Interpolation, VolumeMap, VolumeMapBoundary, VolumeMapBuild,
    VolumeMapOptions, VolumeMapStats,
};
pub use cone_match::ConeMatch;
pub use dimensions::Dimensions;
pub use error::{MapFileProblem, SolverError};
pub use fluid_solver::{FluidSolver, Solids};
pub use frame::{FrameSolver, SchemeParts, SubstepScheme};
pub use parameters::SolverParameters;
pub use params::{
    CommonParams, DEFAULT_SUPPORT_OVER_SPACING, MAX_ITERATIONS_PER_FRAME, MAX_SUBSTEPS,
    VOLUME_MAP_CONTACT_FRACTION,
};
pub use scene_boundary::{
    BoundaryFeature, BoundaryFeatures, MovingWall, PeriodicAxis, Pour, SceneBoundary, WallModel,
};
pub use settings::{CommonSettings, SceneValues, SolverSettings};
pub use state::{ArraySpec, SolverState};
pub use stats::{PhaseTimes, StepStats, MAX_PHASES};

pub use neighbour_search::{Method, NeighbourLists};
pub use sph_core::{ParticleSet, Real, Sdf, Vec3};
pub use sph_kernels::KernelKind;
