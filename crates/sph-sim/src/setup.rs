//! A scene built once: [`SceneSetup`] holds everything a run starts from — the solver's
//! parameters, the particles (positions, velocities, masses, calibrated if asked) and the
//! boundary — each made once from a checked [`Scene`], so that [`crate::SceneSim`] and any
//! other consumer (an experiment reading the initial state, a renderer) share one build.

use sph_core::{ParticleSet, Real};
use sph_scene::{InitialMasses, Precision, Scene, SolverParams};
use sph_solver::boundary::{CacheUse, VolumeMapBuild, VolumeMapCache};
use sph_solver::initial::{calibrate_masses, MassCalibration};
use sph_solver::Boundary;

use crate::error::SimError;
use crate::factory::{build_boundary_reporting, density_kernel};

/// A scene built once in precision `R`: the parameters, the initial particles and the
/// boundary. [`crate::SceneSim::from_setup`] builds the solver from it without sampling,
/// building a signed distance field or range-checking again.
pub struct SceneSetup<R: Real> {
    /// The scene it was built from.
    pub scene: Scene,
    /// The solver's parameters (checked: by [`Scene::check`] when `R` is the scene's
    /// precision, else here, in `R`).
    pub params: SolverParams<R>,
    /// The initial particles: the fluid sampled once, masses `ρ0 s³` (calibrated with
    /// `[boundary] initial_masses = "calibrated"`), the scene's initial velocities.
    pub state: ParticleSet<R>,
    /// The tank and solids as the solver's boundary (`[boundary] model`).
    pub boundary: Box<dyn Boundary<R>>,
    /// What the mass calibration did, `None` for lattice masses.
    pub calibration: Option<MassCalibration>,
    /// How each solid's volume map was obtained (built, loaded from the cache, stored in
    /// it, ...), in solid order; empty for the collision boundary.
    pub volume_maps: Vec<CacheUse>,
}

impl<R: Real> std::fmt::Debug for SceneSetup<R> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SceneSetup")
            .field("scene", &self.scene.name)
            .field("particles", &self.state.len())
            .field("boundary", &self.boundary.name())
            .field("calibration", &self.calibration)
            .finish()
    }
}

/// `R` is the scene's precision (its parameters were checked in it by [`Scene::check`]).
fn is_scene_precision<R: Real>(scene: &Scene) -> bool {
    let name = match scene.precision {
        Precision::F32 => f32::NAME,
        Precision::F64 => f64::NAME,
    };
    R::NAME == name
}

impl<R: Real> SceneSetup<R> {
    /// [`SceneSetup::with_cache`] without a volume-map cache.
    pub fn new(scene: &Scene) -> Result<Self, SimError> {
        Self::with_cache(scene, None)
    }

    /// Builds `scene` (checked, e.g. by [`Scene::load`] or [`Scene::check`]): samples the
    /// fluid once (positions and velocities together), builds the solids' signed distance
    /// fields and the boundary once, and calibrates the masses if the scene asks for it
    /// ([`calibrate_masses`] with the solver's density kernel, [`density_kernel`]). Errors
    /// name the scene file.
    ///
    /// With `cache`, the volume maps come from (or go into) that cache
    /// ([`sph_solver::boundary::VolumeMapCache`]).
    pub fn with_cache(scene: &Scene, cache: Option<&VolumeMapCache>) -> Result<Self, SimError> {
        let how = VolumeMapBuild {
            cache,
            cancel: None,
        };
        Self::with_maps(scene, how)
    }

    /// [`SceneSetup::with_cache`] with the volume maps obtained as `how` says: from (or
    /// into) `how.cache`, and stopped when `how.cancel` is set (Ctrl-C), the error then
    /// [`sph_solver::SolverError::Cancelled`] within [`SimError::Setup`].
    pub fn with_maps(scene: &Scene, how: VolumeMapBuild<'_>) -> Result<Self, SimError> {
        // Built once in f64 and converted to `R` (checked in `R` unless `Scene::check` did).
        let params = if is_scene_precision::<R>(scene) {
            scene.solver_params_unchecked::<R>()?
        } else {
            scene.solver_params::<R>()?
        };
        let common = params.common().clone();
        let fluid = scene.fluid_particles::<R>()?;
        let (boundary, volume_maps) =
            build_boundary_reporting(scene, &common, &fluid.positions, how)?;
        let mut state = ParticleSet::from_positions(
            fluid.positions,
            common.particle_mass(),
            common.rest_density,
        );
        state.velocities = fluid.velocities;
        let calibration = match scene.boundary.initial_masses {
            InitialMasses::Lattice => None,
            InitialMasses::Calibrated => Some(
                calibrate_masses(density_kernel(scene), &common, &*boundary, &mut state).map_err(
                    |source| SimError::Setup {
                        file: scene.source.display().to_string(),
                        source,
                    },
                )?,
            ),
        };
        Ok(Self {
            scene: scene.clone(),
            params,
            state,
            boundary,
            calibration,
            volume_maps,
        })
    }
}
