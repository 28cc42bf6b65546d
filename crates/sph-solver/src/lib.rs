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
//! Adding a solver means one crate that implements [`FluidSolver`] on top of this one; no
//! solver depends on another.

pub mod boundary;
pub mod csr;
mod error;
pub mod initial;
mod params;
pub mod state;
mod stats;
pub mod step;
#[cfg(feature = "testing")]
pub mod testing;

pub use boundary::{
    half_space_volume, half_space_volume_derivative, Boundary, BoundarySample, ClosestPoint,
    CollisionBoundary, Interpolation, VolumeMap, VolumeMapBoundary, VolumeMapOptions,
    VolumeMapStats,
};
pub use error::SolverError;
pub use params::{CommonParams, DEFAULT_SUPPORT_OVER_SPACING, MAX_SUBSTEPS};
pub use state::{ArraySpec, SolverState};
pub use stats::{PhaseTimes, StepStats, MAX_PHASES};

pub use neighbour_search::{Method, NeighbourLists};
pub use sph_core::{ParticleSet, Real, Sdf, Vec3};

/// The solids of a scene: signed distance fields, negative inside the solid (a tank is
/// `sph_core::Inverted<sph_core::BoxSdf>`).
pub type Solids<R> = Vec<Box<dyn Sdf<R>>>;

/// A particle solver advancing a [`ParticleSet`] by one frame per call: the object-safe
/// common interface of the workspace's solvers.
pub trait FluidSolver<R: Real>: Send {
    /// Advances `state` by one whole frame ([`FluidSolver::frame_dt`]) of
    /// `common().substeps` time steps. Errors leave `state` at the last completed substep,
    /// never with a non-finite value.
    fn step(&mut self, state: &mut ParticleSet<R>) -> Result<StepStats, SolverError>;
    /// Time advanced by one [`FluidSolver::step`] call (s).
    fn frame_dt(&self) -> R {
        self.common().dt
    }
    /// The parameters every solver has.
    fn common(&self) -> &CommonParams<R>;
    /// The boundary (solids and their model).
    fn boundary(&self) -> &dyn Boundary<R>;
    /// The permutation applied to the particles by the last step (`new[k] = old[perm[k]]`),
    /// or `None` if it did not reorder. Apply it to anything kept per particle beside the
    /// state (`sph_core::apply_permutation`) to track particles across reordering.
    fn last_permutation(&self) -> Option<&[u32]>;
    /// Short name for reports, e.g. `"PBF"`.
    fn name(&self) -> &'static str;
    /// The names of the phases its [`StepStats::phases`] report, in order.
    fn phase_names(&self) -> &'static [&'static str];
    /// Passive points the solver advects beside the particles (e.g. the high-resolution
    /// points of an upscaling), to be written with the output; `None` (the default) when it
    /// has none.
    fn passive_points(&self) -> Option<&[Vec3<R>]> {
        None
    }
    /// Everything the solver carries from one frame to the next besides the
    /// [`ParticleSet`] (TEMPORARY default until the frame shell lands).
    fn save_state(&self) -> SolverState<R> {
        SolverState::new(self.name(), 0, Vec::new())
    }
    /// Takes back a [`FluidSolver::save_state`] (TEMPORARY default until the frame shell
    /// lands: refuses).
    fn restore_state(
        &mut self,
        state: &SolverState<R>,
        particles: usize,
    ) -> Result<(), SolverError> {
        let _ = (state, particles);
        Err(SolverError::InvalidSolverState {
            solver: self.name().into(),
            reason: "not supported yet".into(),
        })
    }
}
