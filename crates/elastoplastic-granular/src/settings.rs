//! The scene-facing settings (`[solver] kind = "elastoplastic"`): each key is the name of
//! the [`ElastoplasticParams`] field it sets, defaults are
//! [`ElastoplasticParams::for_spacing`]'s, the range checks [`ElastoplasticParams::validate`]'s.
//! The walls (each solid's [`WallModel`] and the region whose solids become boundary
//! particles) come from the scene's solids, not from this table.

use serde::Deserialize;
use sph_core::{Aabb, Real};
use sph_solver::scene_boundary::{BoundaryFeatures, MovingWall, PeriodicAxis, Pour, SceneBoundary};
use sph_solver::settings::convert;
use sph_solver::{
    Boundary, CommonSettings, FluidSolver, KernelKind, SceneValues, SolverError, SolverSettings,
};

use crate::kernels::ELASTOPLASTIC_KERNEL;
use crate::name::NAME;
use crate::params::{ElastoplasticParams, InitialStress};
use crate::solver::Elastoplastic;
use crate::stress::ConeMatch;

/// The friction angle (degrees) of settings made for this kind from another solver's
/// ([`SolverSettings::with_common`]): 30°, the shipped heaps' (a cohesionless material
/// needs one; the other solvers have none).
pub const WITH_COMMON_FRICTION_ANGLE_DEG: f64 = 30.0;

/// The `[solver]` settings of `kind = "elastoplastic"`; `None` = the default of
/// [`ElastoplasticParams::for_spacing`]. Units and ranges as in [`ElastoplasticParams`].
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ElastoplasticSettings {
    /// The settings every solver has.
    #[serde(flatten)]
    pub common: CommonSettings,
    /// [`ElastoplasticParams::friction_angle_deg`] (degrees, required).
    pub friction_angle_deg: f64,
    /// [`ElastoplasticParams::cone_match`]: `"plane-strain-associated"` (the default),
    /// `"plane-strain"` or `"simple-shear"` (the heap stands at `friction_angle_deg`).
    pub cone_match: Option<ConeMatch>,
    /// [`ElastoplasticParams::youngs_modulus`] (Pa).
    pub youngs_modulus: Option<f64>,
    /// [`ElastoplasticParams::poisson_ratio`].
    pub poisson_ratio: Option<f64>,
    /// [`ElastoplasticParams::dilatancy_angle_deg`] (degrees).
    pub dilatancy_angle_deg: Option<f64>,
    /// [`ElastoplasticParams::cohesion`] (Pa).
    pub cohesion: Option<f64>,
    /// [`ElastoplasticParams::viscosity_alpha`].
    pub viscosity_alpha: Option<f64>,
    /// [`ElastoplasticParams::viscosity_beta`].
    pub viscosity_beta: Option<f64>,
    /// [`ElastoplasticParams::viscosity_speed_m_s`] (m/s; absent = the speed of sound).
    pub viscosity_speed_m_s: Option<f64>,
    /// [`ElastoplasticParams::artificial_stress_epsilon`].
    pub artificial_stress_epsilon: Option<f64>,
    /// [`ElastoplasticParams::artificial_stress_exponent`].
    pub artificial_stress_exponent: Option<f64>,
    /// [`ElastoplasticParams::cfl_number`].
    pub cfl_number: Option<f64>,
    /// [`ElastoplasticParams::skin`] (m).
    pub skin: Option<f64>,
    /// [`ElastoplasticParams::density_reinit_interval_s`] (s; 0: never).
    pub density_reinit_interval_s: Option<f64>,
    /// [`ElastoplasticParams::initial_stress`]: `"none"` (the default) or `"geostatic"`.
    pub initial_stress: Option<InitialStress>,
}

impl SolverSettings for ElastoplasticSettings {
    type Params<R: Real> = ElastoplasticParams<R>;

    const DENSITY_KERNEL: KernelKind = ELASTOPLASTIC_KERNEL;

    /// Walls of boundary particles (the solver's only walls in scene files), a model per
    /// wall, moving walls, periodic axes and a pour.
    const BOUNDARY_FEATURES: BoundaryFeatures = BoundaryFeatures {
        collision: false,
        volume_map: false,
        particles: true,
        wall_models: true,
        moving_walls: true,
        periodic: true,
        pour: true,
    };

    /// Plane-strain runs in the plane `z = 0` ([`ElastoplasticParams::dimensions`]).
    const PLANAR: bool = true;

    /// Friction angle [`WITH_COMMON_FRICTION_ANGLE_DEG`], every other setting the default.
    fn with_common(common: CommonSettings, _iterations: usize) -> Self {
        Self {
            common,
            friction_angle_deg: WITH_COMMON_FRICTION_ANGLE_DEG,
            cone_match: None,
            youngs_modulus: None,
            poisson_ratio: None,
            dilatancy_angle_deg: None,
            cohesion: None,
            viscosity_alpha: None,
            viscosity_beta: None,
            viscosity_speed_m_s: None,
            artificial_stress_epsilon: None,
            artificial_stress_exponent: None,
            cfl_number: None,
            skin: None,
            density_reinit_interval_s: None,
            initial_stress: None,
        }
    }

    fn common(&self) -> &CommonSettings {
        &self.common
    }

    fn common_mut(&mut self) -> &mut CommonSettings {
        &mut self.common
    }

    /// Explicit steps are sub-cycled to the CFL limit: no iteration count (1).
    fn iterations(&self) -> usize {
        1
    }

    fn set_iterations(&mut self, _n: usize) {}

    fn params(&self, scene: &SceneValues) -> ElastoplasticParams<f64> {
        let mut p =
            ElastoplasticParams::for_spacing(scene.particle_spacing, self.friction_angle_deg);
        self.common.apply(scene, &mut p.common);
        let set = |target: &mut f64, v: Option<f64>| {
            if let Some(v) = v {
                *target = v;
            }
        };
        if let Some(m) = self.cone_match {
            p.cone_match = m;
        }
        set(&mut p.youngs_modulus, self.youngs_modulus);
        set(&mut p.poisson_ratio, self.poisson_ratio);
        set(&mut p.dilatancy_angle_deg, self.dilatancy_angle_deg);
        set(&mut p.cohesion, self.cohesion);
        set(&mut p.viscosity_alpha, self.viscosity_alpha);
        set(&mut p.viscosity_beta, self.viscosity_beta);
        if self.viscosity_speed_m_s.is_some() {
            p.viscosity_speed_m_s = self.viscosity_speed_m_s;
        }
        set(
            &mut p.artificial_stress_epsilon,
            self.artificial_stress_epsilon,
        );
        set(
            &mut p.artificial_stress_exponent,
            self.artificial_stress_exponent,
        );
        set(&mut p.cfl_number, self.cfl_number);
        set(&mut p.skin, self.skin);
        set(
            &mut p.density_reinit_interval_s,
            self.density_reinit_interval_s,
        );
        if let Some(s) = self.initial_stress {
            p.initial_stress = s;
        }
        p.dimensions = scene.dimensions;
        p
    }

    /// Each solid's wall model (unstated: `default_wall`), the moving walls, the region of
    /// the boundary particles, the periodic axes and the pour.
    fn take_scene_boundary(
        params: &mut ElastoplasticParams<f64>,
        boundary: SceneBoundary<f64>,
    ) -> Result<(), SolverError> {
        boundary.check_supported(NAME, &Self::BOUNDARY_FEATURES)?;
        let default = boundary.default_wall;
        params.default_wall = default;
        params.wall_models = boundary
            .wall_models
            .iter()
            .map(|w| w.unwrap_or(default))
            .collect();
        params.moving_walls = boundary.moving_walls;
        params.pour = boundary.pour;
        params.boundary_particle_region = boundary.boundary_particle_region;
        params.periodic = boundary.periodic;
        Ok(())
    }

    fn build<R: Real>(
        params: ElastoplasticParams<R>,
        boundary: Box<dyn Boundary<R>>,
    ) -> Result<Box<dyn FluidSolver<R>>, SolverError> {
        Ok(Box::new(Elastoplastic::with_boundary(params, boundary)?))
    }
}

impl<R: Real> ElastoplasticParams<R> {
    /// These parameters in precision `S`, each value rounded to nearest (an error names the
    /// first finite value that does not fit).
    pub fn try_convert<S: Real>(&self) -> Result<ElastoplasticParams<S>, SolverError> {
        let c = |name: &'static str, v: R| convert::<R, S>(NAME, name, v);
        let region = match &self.boundary_particle_region {
            Some(a) => Some(Aabb {
                min: sph_solver::settings::convert3(NAME, "boundary_particle_region", &a.min)?,
                max: sph_solver::settings::convert3(NAME, "boundary_particle_region", &a.max)?,
            }),
            None => None,
        };
        Ok(ElastoplasticParams {
            common: self.common.try_convert(NAME)?,
            youngs_modulus: c("youngs_modulus", self.youngs_modulus)?,
            poisson_ratio: c("poisson_ratio", self.poisson_ratio)?,
            friction_angle_deg: c("friction_angle_deg", self.friction_angle_deg)?,
            cone_match: self.cone_match,
            dilatancy_angle_deg: c("dilatancy_angle_deg", self.dilatancy_angle_deg)?,
            cohesion: c("cohesion", self.cohesion)?,
            viscosity_alpha: c("viscosity_alpha", self.viscosity_alpha)?,
            viscosity_beta: c("viscosity_beta", self.viscosity_beta)?,
            viscosity_speed_m_s: self
                .viscosity_speed_m_s
                .map(|u| c("viscosity_speed_m_s", u))
                .transpose()?,
            artificial_stress_epsilon: c(
                "artificial_stress_epsilon",
                self.artificial_stress_epsilon,
            )?,
            artificial_stress_exponent: c(
                "artificial_stress_exponent",
                self.artificial_stress_exponent,
            )?,
            cfl_number: c("cfl_number", self.cfl_number)?,
            skin: c("skin", self.skin)?,
            density_reinit_interval_s: c(
                "density_reinit_interval_s",
                self.density_reinit_interval_s,
            )?,
            default_wall: self.default_wall,
            wall_models: self.wall_models.clone(),
            periodic: self
                .periodic
                .iter()
                .map(|a| {
                    Ok(PeriodicAxis {
                        axis: a.axis,
                        lo: c("periodic", a.lo)?,
                        hi: c("periodic", a.hi)?,
                    })
                })
                .collect::<Result<_, SolverError>>()?,
            boundary_particle_region: region,
            moving_walls: self
                .moving_walls
                .iter()
                .map(|w| {
                    let v3 = |v| sph_solver::settings::convert3(NAME, "moving_walls", v);
                    Ok(MovingWall {
                        region: Aabb {
                            min: v3(&w.region.min)?,
                            max: v3(&w.region.max)?,
                        },
                        model: w.model,
                        velocity: v3(&w.velocity)?,
                        duration_s: c("moving_walls", w.duration_s)?,
                    })
                })
                .collect::<Result<_, SolverError>>()?,
            pour: self
                .pour
                .map(|p| {
                    let v3 = |v| sph_solver::settings::convert3(NAME, "pour", v);
                    Ok::<_, SolverError>(Pour {
                        region: Aabb {
                            min: v3(&p.region.min)?,
                            max: v3(&p.region.max)?,
                        },
                        volume_m3: c("pour", p.volume_m3)?,
                        rate_m3_s: c("pour", p.rate_m3_s)?,
                        seed: p.seed,
                    })
                })
                .transpose()?,
            initial_stress: self.initial_stress,
            dimensions: self.dimensions,
        })
    }
}
