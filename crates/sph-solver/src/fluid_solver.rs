//! The object-safe interface of every particle solver.

use sph_core::{ParticleSet, Real, Sdf, Vec3};
use sph_kernels::KernelKind;

use crate::boundary::Boundary;
use crate::error::SolverError;
use crate::params::CommonParams;
use crate::state::SolverState;
use crate::stats::StepStats;

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
    /// Readies the solver's per-particle state for `state` before its first
    /// [`FluidSolver::step`] (e.g. the elastic–plastic solver's initial stress), so that
    /// [`FluidSolver::particle_fields`] describes frame 0; a solver that is not prepared
    /// does the same at its first step, with the same result. Nothing by default.
    fn prepare(&mut self, state: &ParticleSet<R>) -> Result<(), SolverError> {
        let _ = state;
        Ok(())
    }
    /// Per-particle fields the solver carries beside the [`ParticleSet`], for output frames:
    /// `(name, values)` in the particles' current order, `values.len()` a multiple `k` of the
    /// particle count (`k` values per particle: 1 a scalar, 3 a vector, 6 a symmetric tensor
    /// `xx, yy, zz, xy, yz, zx`). None by default; e.g. the elastic–plastic solver's
    /// `stress` (Pa) and `plastic_strain`.
    fn particle_fields(&self) -> Vec<(String, Vec<R>)> {
        Vec::new()
    }
    /// The kernel of the solver's density sum (a volume-map boundary must have been
    /// integrated with it).
    fn density_kernel(&self) -> KernelKind;
    /// Everything the solver carries from one frame to the next besides the
    /// [`ParticleSet`] (frame counter, warm starts, passive points, …), in the particles'
    /// current order. Saving the particles and this state after any frame, and restoring
    /// both into a fresh solver built with the same parameters
    /// ([`FluidSolver::restore_state`]), continues the run bit for bit.
    fn save_state(&self) -> SolverState<R>;
    /// Takes back a [`FluidSolver::save_state`] for a run with `particles` particles.
    /// Refuses ([`SolverError::InvalidSolverState`], naming what) a state written by another
    /// solver, or with array names or lengths that do not fit `particles` particles, and
    /// then leaves the solver unchanged.
    fn restore_state(
        &mut self,
        state: &SolverState<R>,
        particles: usize,
    ) -> Result<(), SolverError>;
}
