//! A scene being simulated: its particles, the solver the factory built, and the ids that
//! follow particles across the solver's reordering.

use std::path::Path;

use sph_core::{apply_permutation, ParticleSet, Real};
use sph_scene::Scene;
use sph_solver::boundary::CacheUse;
use sph_solver::initial::MassCalibration;
use sph_solver::{FluidSolver, StepStats};

use crate::error::SimError;
use crate::factory::build_solver;
use crate::setup::SceneSetup;
use crate::vtk::{values_per_particle, write_particle_frame, write_point_frame, ParticleFrame};

/// A scene being simulated in precision `R`.
pub struct SceneSim<R: Real> {
    /// The scene (with quick-mode overrides applied if asked for).
    pub scene: Scene,
    /// The particles (reordered by cell by the solver from time to time).
    pub state: ParticleSet<R>,
    /// For each particle of `state`, its index in the scene's initial order (the grains a
    /// pour adds take the next indices, in the order they are poured).
    pub ids: Vec<u32>,
    /// Frames done.
    pub frame: usize,
    /// Simulated time (s).
    pub time_s: f64,
    /// What the mass calibration did (`[boundary] initial_masses = "calibrated"`), `None`
    /// for lattice masses.
    pub calibration: Option<MassCalibration>,
    /// How each solid's volume map was obtained (built, loaded from the cache, ...), in
    /// solid order; empty for the collision boundary.
    pub volume_maps: Vec<CacheUse>,
    solver: Box<dyn FluidSolver<R>>,
    id_scratch: Vec<u32>,
    /// The particles the scene starts with.
    initial_particles: usize,
}

impl<R: Real> std::fmt::Debug for SceneSim<R> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SceneSim")
            .field("scene", &self.scene.name)
            .field("particles", &self.state.len())
            .field("solver", &self.solver.name())
            .field("boundary", &self.solver.boundary().name())
            .field("frame", &self.frame)
            .finish()
    }
}

impl<R: Real> SceneSim<R> {
    /// Builds the scene once ([`SceneSetup::new`]: the fluid sampled, the solids' signed
    /// distance fields and the boundary built, the masses calibrated if asked) and its
    /// solver ([`SceneSim::from_setup`]). Errors name the scene file.
    pub fn new(scene: &Scene) -> Result<Self, SimError> {
        Self::from_setup(SceneSetup::new(scene)?)
    }

    /// [`SceneSim::new`] with the volume maps from (or into) `cache`.
    pub fn with_cache(
        scene: &Scene,
        cache: Option<&sph_solver::boundary::VolumeMapCache>,
    ) -> Result<Self, SimError> {
        Self::from_setup(SceneSetup::with_cache(scene, cache)?)
    }

    /// [`SceneSim::new`] with the volume maps obtained as `how` says (a cache, a
    /// cancellation flag: [`SceneSetup::with_maps`]).
    pub fn with_maps(
        scene: &Scene,
        how: sph_solver::boundary::VolumeMapBuild<'_>,
    ) -> Result<Self, SimError> {
        Self::from_setup(SceneSetup::with_maps(scene, how)?)
    }

    /// The simulation of a scene built once: its solver made from the set-up's parameters
    /// and boundary ([`build_solver`]), its particles the set-up's. Nothing is sampled or
    /// built again.
    pub fn from_setup(setup: SceneSetup<R>) -> Result<Self, SimError> {
        let SceneSetup {
            scene,
            params,
            state,
            boundary,
            calibration,
            volume_maps,
        } = setup;
        let setup_error = |source| SimError::Setup {
            file: scene.source.display().to_string(),
            source,
        };
        let mut solver = build_solver(params, boundary).map_err(setup_error)?;
        // Frame 0 is written with the solver's fields (an initial stress) before any step.
        solver.prepare(&state).map_err(setup_error)?;
        let n = state.len() as u32;
        Ok(Self {
            scene,
            state,
            ids: (0..n).collect(),
            frame: 0,
            time_s: 0.0,
            calibration,
            volume_maps,
            solver,
            id_scratch: Vec::new(),
            initial_particles: n as usize,
        })
    }

    /// The particles the scene starts with (a pour adds [`Scene::poured_grains`] more).
    pub fn initial_particles(&self) -> usize {
        self.initial_particles
    }

    /// Whether the scene's pour (if any) has added all its grains.
    pub fn pour_finished(&self) -> bool {
        self.state.len() >= self.initial_particles + self.scene.poured_grains()
    }

    /// The solver.
    pub fn solver(&self) -> &dyn FluidSolver<R> {
        &*self.solver
    }

    pub(crate) fn solver_mut(&mut self) -> &mut dyn FluidSolver<R> {
        &mut *self.solver
    }

    /// Advances one frame (`frame_dt`); keeps [`SceneSim::ids`] in step with the solver's
    /// reordering. A blow-up is a [`SimError::Frame`] naming the frame and the solver's step
    /// and particle; the state then holds the last completed substep.
    pub fn advance(&mut self) -> Result<StepStats, SimError> {
        let stats = self
            .solver
            .step(&mut self.state)
            .map_err(|source| SimError::Frame {
                file: self.scene.source.display().to_string(),
                frame: self.frame,
                time_s: self.time_s,
                source,
            })?;
        if let Some(perm) = self.solver.last_permutation() {
            apply_permutation(&mut self.ids, perm, &mut self.id_scratch);
        }
        // Grains a pour added during the frame, after the others.
        let n = self.state.len() as u32;
        self.ids.extend(self.ids.len() as u32..n);
        self.frame += 1;
        self.time_s = self.frame as f64 * self.scene.frame_dt_s;
        Ok(stats)
    }

    /// `per_particle` (one value per particle in the solver's current order, e.g.
    /// `&self.state.positions`) in the order the scene created the particles: element `k`
    /// of the result belongs to the particle with id `k` ([`SceneSim::ids`] follows every
    /// reordering the solver does). Errors if `per_particle` is not one value per particle.
    pub fn to_original_order<T: Copy>(&self, per_particle: &[T]) -> Result<Vec<T>, SimError> {
        if per_particle.len() != self.ids.len() {
            return Err(SimError::Invalid(format!(
                "{} values for {} particles: need one value per particle",
                per_particle.len(),
                self.ids.len()
            )));
        }
        let mut out = per_particle.to_vec();
        for (&id, &value) in self.ids.iter().zip(per_particle) {
            out[id as usize] = value;
        }
        Ok(out)
    }

    /// The solver's per-particle fields (`FluidSolver::particle_fields`, e.g. the
    /// elastic–plastic stress and plastic strain) in the scene's original particle order:
    /// `(name, k, values)` with `k` values per particle, particle `i`'s at `k i .. k (i + 1)`.
    /// A field whose length is not a multiple of the particle count is an error; with no
    /// particles yet (a pour before its first layer) the fields are left out.
    pub fn particle_fields(&self) -> Result<Vec<(String, usize, Vec<R>)>, SimError> {
        let n = self.ids.len();
        let mut out = Vec::new();
        for (name, values) in self.solver.particle_fields() {
            let Some(k) = values_per_particle(&name, values.len(), n).map_err(SimError::Invalid)?
            else {
                continue; // no particles yet (a pour before its first layer)
            };
            let mut ordered = values.clone();
            for (&id, chunk) in self.ids.iter().zip(values.chunks_exact(k)) {
                let at = id as usize * k;
                ordered[at..at + k].copy_from_slice(chunk);
            }
            out.push((name, k, ordered));
        }
        Ok(out)
    }

    /// Writes the solver's passive points (upscaling) of the current frame to `path` (legacy
    /// VTK, the format of [`SceneSim::write_vtk`]); returns `false` and writes nothing when
    /// the solver has none ([`FluidSolver::passive_points`]; an upscaling solver seeds them
    /// in its first step, so frame 0 has none).
    pub fn write_passive_vtk(&self, path: &Path) -> Result<bool, SimError> {
        match self.solver.passive_points() {
            Some(points) => {
                write_point_frame(path, self.time_s, points)?;
                Ok(true)
            }
            None => Ok(false),
        }
    }

    /// Writes the current frame to `path` (legacy VTK), with the solver's per-particle
    /// fields (`FluidSolver::particle_fields`).
    pub fn write_vtk(&self, path: &Path) -> Result<(), SimError> {
        let fields = self.solver.particle_fields();
        write_particle_frame(
            path,
            &ParticleFrame {
                time_s: self.time_s,
                positions: &self.state.positions,
                velocities: &self.state.velocities,
                densities: &self.state.densities,
                ids: &self.ids,
                fields: &fields,
            },
        )
    }
}
