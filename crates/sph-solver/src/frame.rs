//! The frame shell: one [`FluidSolver`] implementation for every particle solver.
//!
//! A solver is a [`SubstepScheme`]: its name, phase table, density kernel, parameters and
//! the body of one time step (`substep`). [`FrameSolver`] wraps a scheme and runs the frame
//! around it, the same for every solver:
//!
//! 1. count the call (the frame counter drives `reorder_every` and names blow-ups);
//! 2. check the state and reorder it by cell every `common.reorder_every` calls
//!    ([`crate::step::begin_frame`]);
//! 3. [`SubstepScheme::begin_frame`]: the scheme resizes its buffers and permutes what it
//!    carries per particle;
//! 4. the scheme's pour ([`SubstepScheme::pour`]), if it has one: the layers due by the
//!    frame's start time are appended to the state ([`PourEmitter`]) and handed to the
//!    scheme ([`SubstepScheme::init_emitted`]);
//! 5. `common.substeps` calls of [`SubstepScheme::substep`];
//! 6. the density and energy statistics ([`crate::step::end_frame`]).
//!
//! [`FrameSolver`] dereferences to its scheme, so a scheme's own accessors (e.g. IISPH's
//! pressures) are methods of the solver.

use std::borrow::Cow;
use std::fmt;
use std::ops::{Deref, DerefMut};

use neighbour_search::{Method, NeighbourLists};
use sph_core::{Aabb, ParticleSet, Real, Sdf, Vec3};
use sph_kernels::KernelKind;

use crate::boundary::check_volume_kernel;
use crate::boundary::{
    Boundary, CollisionBoundary, VolumeMapBoundary, VolumeMapCache, VolumeMapOptions,
};
use crate::error::SolverError;
use crate::fluid_solver::{FluidSolver, Solids};
use crate::parameters::SolverParameters;
use crate::params::CommonParams;
use crate::scene_boundary::{PeriodicAxis, Pour, PourEmitter};
use crate::state::{match_arrays, ArraySpec, SolverState};
use crate::stats::StepStats;
use crate::step::{begin_frame, end_frame, CellReorder, FramePhases, StepAt, StepNeighbours};

/// What every scheme works with besides its own buffers: the boundary and the neighbour
/// search. A scheme owns its parts (so that its diagnostics can use them) and lends them to
/// [`FrameSolver`] through [`SubstepScheme::parts`].
pub struct SchemeParts<R: Real> {
    /// The boundary (solids and their model).
    pub boundary: Box<dyn Boundary<R>>,
    /// The neighbour search and its lists.
    pub neighbours: StepNeighbours<R>,
}

impl<R: Real> SchemeParts<R> {
    /// `boundary` and a neighbour search with `method`.
    pub fn new(boundary: Box<dyn Boundary<R>>, method: Method) -> Self {
        Self {
            boundary,
            neighbours: StepNeighbours::new(method),
        }
    }
}

impl<R: Real> fmt::Debug for SchemeParts<R> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("SchemeParts")
            .field("boundary", &self.boundary.name())
            .field("solids", &self.boundary.solids().len())
            .field("neighbours", &self.neighbours)
            .finish()
    }
}

/// One particle solver's time step, run frame by frame by [`FrameSolver`].
///
/// Adding a solver means implementing this trait (see the crate docs, "Adding a solver").
pub trait SubstepScheme<R: Real>: Send + Sized {
    /// The solver's parameters (embedding [`CommonParams`] as `common`; their name, range
    /// check and common part are their [`SolverParameters`]').
    type Params: SolverParameters<R>;
    /// The name in errors ([`SolverError::InvalidParameter`], [`SolverError::BlowUp`]): the
    /// parameters' [`SolverParameters::NAME`].
    const NAME: &'static str = <Self::Params as SolverParameters<R>>::NAME;
    /// The phases its [`StepStats::phases`] report, in order.
    const PHASES: &'static [&'static str];
    /// Which of [`SubstepScheme::PHASES`] take the frame shell's checks, reordering and
    /// statistics.
    const FRAME_PHASES: FramePhases;
    /// The kernel of its density sum (a volume boundary must have been integrated with it).
    const DENSITY_KERNEL: KernelKind;

    /// The scheme for `params` (validated by the caller) with `parts`.
    fn new(params: Self::Params, parts: SchemeParts<R>) -> Result<Self, SolverError>;
    /// The parameters.
    fn params(&self) -> &Self::Params;
    /// The boundary and neighbour search.
    fn parts(&self) -> &SchemeParts<R>;
    /// Short name for reports ([`FluidSolver::name`]); [`SubstepScheme::NAME`] unless the
    /// parameters make it another model.
    fn name(&self) -> &'static str {
        Self::NAME
    }
    /// The start of a frame, after the state was checked and reordered: resize the buffers
    /// to `state.len()` particles and apply `permutation` (`new[k] = old[perm[k]]`, `None`
    /// when the frame did not reorder) to anything carried per particle. Phases it times go
    /// to `stats`.
    fn begin_frame(
        &mut self,
        state: &mut ParticleSet<R>,
        permutation: Option<&[u32]>,
        stats: &mut StepStats,
    ) -> Result<(), SolverError>;
    /// Readies what the scheme carries per particle for `state` before its first frame
    /// ([`FluidSolver::prepare`]): e.g. an initial stress, so that the state at frame 0 can
    /// be written out with its [`SubstepScheme::particle_fields`]. Nothing by default.
    fn prepare(&mut self, state: &ParticleSet<R>) -> Result<(), SolverError> {
        let _ = state;
        Ok(())
    }
    /// One time step of `common.substeps` (`at`; `last` for the frame's last one): advances
    /// `state` by `Δt = dt / substeps` and writes positions, velocities and densities, after
    /// checking for divergence ([`SolverError::BlowUp`], `state` unchanged).
    fn substep(
        &mut self,
        state: &mut ParticleSet<R>,
        at: StepAt,
        last: bool,
        stats: &mut StepStats,
    ) -> Result<(), SolverError>;
    /// Appends what the scheme carries from one frame to the next (besides the particles)
    /// to `arrays` ([`SolverState::arrays`]); nothing by default.
    fn save_arrays(&self, arrays: &mut Vec<(String, Vec<R>)>) {
        let _ = arrays;
    }
    /// Takes back what [`SubstepScheme::save_arrays`] wrote, for `particles` particles.
    /// Must check everything before changing anything. By default refuses any array.
    fn restore_arrays(
        &mut self,
        arrays: &[(String, Vec<R>)],
        particles: usize,
    ) -> Result<(), SolverError> {
        let _ = particles;
        crate::state::match_arrays(self.name(), arrays, &[]).map(|_| ())
    }
    /// Passive points advected beside the particles ([`FluidSolver::passive_points`]).
    fn passive_points(&self) -> Option<&[Vec3<R>]> {
        None
    }
    /// The pour the frame shell steps for this scheme ([`PourEmitter`]), if its parameters
    /// have one (a scheme that declares
    /// [`BoundaryFeatures::pour`](crate::scene_boundary::BoundaryFeatures)); `None` by
    /// default.
    fn pour(&self) -> Option<&Pour<R>> {
        None
    }
    /// The periodic axes the scheme's particles live on (the pour wraps its room test
    /// across them); none by default.
    fn periodic_axes(&self) -> &[PeriodicAxis<R>] {
        &[]
    }
    /// The hook of the pour: the particles `first..state.len()` were just appended by the
    /// frame shell's [`PourEmitter`] (at rest, with the particle mass and the rest density)
    /// after [`SubstepScheme::begin_frame`] and before the frame's first substep. The
    /// scheme readies what it carries per particle for them (e.g. a zero stress) and drops
    /// anything sized to the old count (neighbour lists). Nothing by default.
    fn init_emitted(&mut self, state: &ParticleSet<R>, first: usize) -> Result<(), SolverError> {
        let _ = (state, first);
        Ok(())
    }
    /// Appends the per-particle fields written with each output frame
    /// ([`FluidSolver::particle_fields`]); nothing by default.
    fn particle_fields(&self, fields: &mut Vec<(String, Vec<R>)>) {
        let _ = fields;
    }
}

/// A particle solver: a [`SubstepScheme`] run frame by frame (see the module docs). Every
/// solver of the workspace is one, e.g. `pbf::Pbf<R> = FrameSolver<R, PbfScheme<R>>`.
pub struct FrameSolver<R: Real, S: SubstepScheme<R>> {
    scheme: S,
    reorder: CellReorder<R>,
    frames: u64,
    partials: Vec<[f64; 3]>,
    emitter: Option<PourEmitter>,
}

/// The name of the array that carries a pour's progress in a [`SolverState`]: the layers
/// placed so far, then the time the last was placed (s; absent before the first layer).
pub const POUR_STATE_ARRAY: &str = "pour";

impl<R: Real, S: SubstepScheme<R>> fmt::Debug for FrameSolver<R, S> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("FrameSolver")
            .field("name", &self.scheme.name())
            .field("params", self.scheme.params())
            .field("parts", self.scheme.parts())
            .field("frames", &self.frames)
            .finish()
    }
}

impl<R: Real, S: SubstepScheme<R>> FrameSolver<R, S> {
    /// A solver with validated `params` and the given solids as a [`CollisionBoundary`]
    /// with the particle radius `s / 2` as contact distance.
    pub fn new(params: S::Params, solids: Solids<R>) -> Result<Self, SolverError> {
        let radius = params.common().particle_radius();
        let boundary = CollisionBoundary::new(solids, radius)?;
        Self::with_boundary(params, Box::new(boundary))
    }

    /// A solver with validated `params` and any boundary model. A boundary that takes part
    /// in the density must have been integrated with the solver's density kernel
    /// ([`SubstepScheme::DENSITY_KERNEL`]) at its support radius, otherwise
    /// [`SolverError::InvalidParameter`].
    pub fn with_boundary(
        params: S::Params,
        boundary: Box<dyn Boundary<R>>,
    ) -> Result<Self, SolverError> {
        params.validate()?;
        let common = params.common();
        check_volume_kernel(
            &*boundary,
            S::NAME,
            S::DENSITY_KERNEL,
            common.support_radius,
        )?;
        let parts = SchemeParts::new(boundary, common.neighbour_method);
        Ok(Self::from_scheme(S::new(params, parts)?))
    }

    /// Volume-map walls of `solids` (Bender, Kugelstadt, Weiler & Koschier 2019) for this
    /// solver with `params`: integrated with its density kernel
    /// ([`SubstepScheme::DENSITY_KERNEL`]) at its support radius over `domain` (the region
    /// the particles can reach, e.g. the tank's box), with the recommended contact distance
    /// ([`CommonParams::volume_map_contact_distance`]), default [`VolumeMapOptions`] and
    /// optionally a [`VolumeMapCache`] directory (maps are then loaded from or written to
    /// it); what scene files get with `[boundary] model = "volume-map"`. Give them to
    /// [`FrameSolver::with_boundary`].
    ///
    /// Errors: those of [`VolumeMapBoundary::with_cache`] (bad domain, unusable support
    /// radius, a solid whose grid would be too large).
    pub fn volume_map_walls(
        solids: Solids<R>,
        params: &S::Params,
        domain: Aabb<R>,
        cache: Option<&VolumeMapCache>,
    ) -> Result<VolumeMapBoundary<R>, SolverError> {
        let common = params.common();
        VolumeMapBoundary::with_cache(
            solids,
            S::DENSITY_KERNEL,
            common.support_radius,
            domain,
            common.volume_map_contact_distance(),
            VolumeMapOptions::default(),
            cache,
        )
    }

    /// A solver running `scheme` from frame 0 (with an emitter for the scheme's pour, if it
    /// has one).
    pub fn from_scheme(scheme: S) -> Self {
        let common = scheme.params().common();
        let emitter = scheme.pour().map(|p| {
            PourEmitter::new(
                p,
                common.particle_spacing.as_f64(),
                common.gravity.norm().as_f64(),
                scheme.periodic_axes(),
            )
        });
        Self {
            scheme,
            reorder: CellReorder::default(),
            frames: 0,
            partials: Vec::new(),
            emitter,
        }
    }

    /// The pour under way: layers placed so far and in all (`None` without a pour).
    pub fn poured_layers(&self) -> Option<(usize, usize)> {
        self.emitter.as_ref().map(|p| (p.poured(), p.layers()))
    }

    /// The scheme.
    pub fn scheme(&self) -> &S {
        &self.scheme
    }

    /// The scheme, mutably.
    pub fn scheme_mut(&mut self) -> &mut S {
        &mut self.scheme
    }

    /// The parameters.
    pub fn params(&self) -> &S::Params {
        self.scheme.params()
    }

    /// The boundary.
    pub fn boundary(&self) -> &dyn Boundary<R> {
        &*self.scheme.parts().boundary
    }

    /// The solids, in the order contacts are resolved.
    pub fn solids(&self) -> &[Box<dyn Sdf<R>>] {
        self.scheme.parts().boundary.solids()
    }

    /// The neighbour lists of the last time step.
    pub fn neighbours(&self) -> &NeighbourLists {
        self.scheme.parts().neighbours.lists()
    }

    /// Number of [`FrameSolver::step`] calls made (including failed ones).
    pub fn steps_done(&self) -> u64 {
        self.frames
    }

    /// The density kernel ([`SubstepScheme::DENSITY_KERNEL`]).
    pub fn density_kernel(&self) -> KernelKind {
        S::DENSITY_KERNEL
    }

    /// The permutation applied to the particles at the start of the last
    /// [`FrameSolver::step`] call (`new[k] = old[perm[k]]`), or `None` if that call did not
    /// reorder. Apply it to any per-particle data kept beside the [`ParticleSet`]
    /// (`sph_core::apply_permutation`).
    pub fn last_permutation(&self) -> Option<&[u32]> {
        self.reorder.last_permutation()
    }

    /// The passive points advected beside the particles, if any.
    pub fn passive_points(&self) -> Option<&[Vec3<R>]> {
        self.scheme.passive_points()
    }

    /// Advances `state` by one whole frame, `common.dt` (16 ms by default), made of
    /// `common.substeps` time steps of the scheme: one call is a frame, not one time step.
    ///
    /// **Particle order.** Every `common.reorder_every` calls (the first call included), the
    /// call begins by reordering the particles of `state` by grid cell for memory locality:
    /// afterwards [`FrameSolver::last_permutation`] returns `perm` with
    /// `new[k] = old[perm[k]]` (`None` when the call did not reorder). To follow particles
    /// across a run, keep an index map `ids` (initially `0..n`) and compose it after each
    /// call, `ids = perm.iter().map(|&o| ids[o as usize]).collect()`, so `ids[k]` is the
    /// original index of the particle now at `k`; apply the same permutation to any
    /// per-particle data kept beside the state (`sph_core::apply_permutation`).
    /// `reorder_every = 0` keeps the input order.
    ///
    /// Checks the state first (array lengths, finite positions and velocities, positive
    /// masses: [`SolverError::InvalidState`], [`SolverError::InvalidMass`]), and after each
    /// time step checks for divergence before writing its result into `state`
    /// ([`SolverError::BlowUp`]; `state` then holds the last completed time step, never a
    /// non-finite value). Writes positions, velocities and densities (at the final
    /// positions). Does not allocate once its buffers have grown to the particle count (and
    /// the neighbour lists to the pair count).
    pub fn step(&mut self, state: &mut ParticleSet<R>) -> Result<StepStats, SolverError> {
        let frame = self.frames;
        self.frames += 1;
        let mut stats = StepStats::new(S::PHASES);
        let common = self.scheme.params().common();
        let substeps = common.substeps;
        let rest_density = common.rest_density;
        begin_frame(
            state,
            &mut self.reorder,
            common,
            frame,
            S::FRAME_PHASES,
            &mut stats,
        )?;
        self.scheme
            .begin_frame(state, self.reorder.last_permutation(), &mut stats)?;
        if let Some(emitter) = &mut self.emitter {
            let common = self.scheme.params().common();
            let time_s = frame as f64 * common.dt.as_f64();
            let first = state.len();
            let (mass, density) = (common.particle_mass(), common.rest_density);
            if emitter.emit(S::NAME, time_s, state, mass, density)? > 0 {
                self.scheme.init_emitted(state, first)?;
            }
        }
        for sub in 0..substeps {
            let at = StepAt {
                solver: S::NAME,
                step: frame,
                substep: sub,
            };
            self.scheme
                .substep(state, at, sub + 1 == substeps, &mut stats)?;
        }
        end_frame(
            state,
            rest_density,
            &mut self.partials,
            S::FRAME_PHASES,
            &mut stats,
        );
        Ok(stats)
    }

    /// Everything the solver carries to the next frame besides the particles (see
    /// [`FluidSolver::save_state`]).
    pub fn save_state(&self) -> SolverState<R> {
        let mut arrays = Vec::new();
        self.scheme.save_arrays(&mut arrays);
        if let Some(p) = &self.emitter {
            let mut values = vec![R::of_f64(p.poured() as f64)];
            values.extend(p.last_layer_s().map(R::of_f64));
            arrays.push((POUR_STATE_ARRAY.into(), values));
        }
        SolverState::new(self.scheme.name(), self.frames, arrays)
    }

    /// Restores a [`FrameSolver::save_state`] (see [`FluidSolver::restore_state`]).
    pub fn restore_state(
        &mut self,
        state: &SolverState<R>,
        particles: usize,
    ) -> Result<(), SolverError> {
        let name = self.scheme.name();
        if state.solver != name {
            return Err(SolverError::InvalidSolverState {
                solver: name.to_owned(),
                reason: format!("the state was written by solver `{}`", state.solver),
            });
        }
        // The pour's progress is the frame shell's; `save_state` writes it last, so the
        // scheme's arrays are the slice before it (copied apart only for a state that has it
        // elsewhere).
        let is_pour = |a: &(String, Vec<R>)| a.0 == POUR_STATE_ARRAY;
        let pour_at = state.arrays.iter().position(is_pour);
        if self.emitter.is_none() && pour_at.is_some() {
            return Err(SolverError::InvalidSolverState {
                solver: name.to_owned(),
                reason: format!(
                    "the state carries a pour's progress (`{POUR_STATE_ARRAY}`) but the parameters have no pour"
                ),
            });
        }
        type Arrays<'a, R> = Cow<'a, [(String, Vec<R>)]>;
        let (arrays, pour): (Arrays<'_, R>, Arrays<'_, R>) = match pour_at {
            None => (Cow::Borrowed(&state.arrays[..]), Cow::Borrowed(&[])),
            Some(k) if k + 1 == state.arrays.len() => {
                let (rest, pour) = state.arrays.split_at(k);
                (Cow::Borrowed(rest), Cow::Borrowed(pour))
            }
            Some(_) => {
                let (pour, rest): (Vec<_>, Vec<_>) =
                    state.arrays.iter().cloned().partition(|a| is_pour(a));
                (Cow::Owned(rest), Cow::Owned(pour))
            }
        };
        // The pour's values: the layers placed, then when the last was (absent before the
        // first layer, and in checkpoints older than that value).
        let poured = match &self.emitter {
            Some(p) => {
                let len = pour.first().map_or(1, |a| a.1.len().clamp(1, 2));
                let spec = [ArraySpec {
                    name: POUR_STATE_ARRAY,
                    len,
                }];
                Some(match match_arrays(name, &pour, &spec)?[0] {
                    Some(v) => (
                        p.check_poured(name, v[0].as_f64(), particles)?,
                        v.get(1).map(|t| t.as_f64()),
                    ),
                    None => (0, None),
                })
            }
            None => None,
        };
        self.scheme.restore_arrays(&arrays, particles)?;
        if let (Some(p), Some((k, last))) = (&mut self.emitter, poured) {
            p.set_poured(k);
            p.set_last_layer_s(last);
        }
        self.frames = state.frames;
        Ok(())
    }
}

impl<R: Real, S: SubstepScheme<R>> Deref for FrameSolver<R, S> {
    type Target = S;
    fn deref(&self) -> &S {
        &self.scheme
    }
}

impl<R: Real, S: SubstepScheme<R>> DerefMut for FrameSolver<R, S> {
    fn deref_mut(&mut self) -> &mut S {
        &mut self.scheme
    }
}

impl<R: Real, S: SubstepScheme<R>> FluidSolver<R> for FrameSolver<R, S> {
    fn step(&mut self, state: &mut ParticleSet<R>) -> Result<StepStats, SolverError> {
        FrameSolver::step(self, state)
    }
    fn common(&self) -> &CommonParams<R> {
        self.scheme.params().common()
    }
    fn boundary(&self) -> &dyn Boundary<R> {
        FrameSolver::boundary(self)
    }
    fn last_permutation(&self) -> Option<&[u32]> {
        FrameSolver::last_permutation(self)
    }
    fn name(&self) -> &'static str {
        self.scheme.name()
    }
    fn phase_names(&self) -> &'static [&'static str] {
        S::PHASES
    }
    fn density_kernel(&self) -> KernelKind {
        S::DENSITY_KERNEL
    }
    fn passive_points(&self) -> Option<&[Vec3<R>]> {
        self.scheme.passive_points()
    }
    fn prepare(&mut self, state: &ParticleSet<R>) -> Result<(), SolverError> {
        self.scheme.prepare(state)
    }
    fn particle_fields(&self) -> Vec<(String, Vec<R>)> {
        let mut fields = Vec::new();
        self.scheme.particle_fields(&mut fields);
        fields
    }
    fn save_state(&self) -> SolverState<R> {
        FrameSolver::save_state(self)
    }
    fn restore_state(
        &mut self,
        state: &SolverState<R>,
        particles: usize,
    ) -> Result<(), SolverError> {
        FrameSolver::restore_state(self, state, particles)
    }
}
