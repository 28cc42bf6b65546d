//! From the `[solver]` settings to the solver's parameters ([`SolverParams`]): built once,
//! in `f64`, by the solver crate's settings ([`sph_solver::SolverSettings::params`]: the
//! solver's defaults for the scene's spacing, the scene's frame and gravity, then each
//! setting given), then converted to the precision the solver runs in
//! ([`SolverParams::try_convert`]). The checks, in this order: those of the settings as
//! written (a setting that only applies with another), the parameters' own `validate` in
//! `f64`, then in the solver's precision (a tolerance of `1e-300` is `0` in `f32`). An error
//! is reported once, at the scene key the parameter comes from, with its line: the keys are
//! the parameters' names (or an old name for one, as the file writes it; `support_radius`
//! is set as `support_over_spacing`, PBF's `cfm_epsilon` as `relative_cfm`, `dt`, `gravity`
//! and `particle_spacing` in `[simulation]`).

use sph_core::{Aabb, Real};
use sph_solver::scene_boundary::{BoundaryFeature, MovingWall, SceneBoundary};
use sph_solver::{CommonSettings, SceneValues, SolverError};

use crate::error::Ctx;
use crate::geom::v3;
use crate::{Precision, Scene, SceneError, SceneWalls, SolidSpec, SolverParams, WallModel};

impl Scene {
    /// The scene's values every solver's parameters take: spacing, frame length, gravity.
    pub(crate) fn scene_values(&self) -> SceneValues {
        SceneValues {
            particle_spacing: self.particle_spacing,
            frame_dt: self.frame_dt_s,
            gravity: self.gravity,
            dimensions: self.dimensions,
        }
    }

    /// The scene's boundary besides the solids' shapes, solver-neutral: each wall's stated
    /// model (the tank first, then the solids that stand still, as in
    /// [`Scene::build_solids`]; unstated walls [`SceneWalls::DEFAULT`]), the moving solids
    /// as moving walls ([`crate::SolidMotion`]), the region whose walls become boundary
    /// particles in a solver that makes them (the tank, or else the box of the fluids), the
    /// solver's periodic axes and the pour.
    pub fn scene_boundary(&self) -> SceneBoundary<f64> {
        let default = SceneWalls::DEFAULT;
        SceneBoundary {
            default_wall: default,
            wall_models: self
                .tank
                .iter()
                .map(|_| self.walls.tank)
                .chain(self.standing_solids().map(|j| self.wall_of(j)))
                .collect(),
            moving_walls: self.moving_walls(default),
            boundary_particle_region: self.tank.or_else(|| {
                self.fluids.iter().map(|f| f.bounds()).reduce(|a, b| Aabb {
                    min: a.min.inf(&b.min),
                    max: a.max.sup(&b.max),
                })
            }),
            periodic: self.boundary.periodic.iter().map(|p| p.to_axis()).collect(),
            pour: self.pour.as_ref().map(|p| self.pour_of(p)),
        }
    }

    /// The solver's parameters in `f64` from the `[solver]` settings and the scene's values,
    /// with the parts of the scene's boundary ([`Scene::scene_boundary`]) the solver takes
    /// ([`sph_solver::SolverSettings::BOUNDARY_FEATURES`],
    /// [`sph_solver::SolverSettings::take_scene_boundary`]). A part the solver does not take
    /// is left out here and refused by [`Scene::check`] at its key (`check.rs`), so that
    /// the parameters of a scene's solver changed in code
    /// ([`SolverSpec::with_kind`](crate::SolverSpec::with_kind)) can still be built.
    fn solver_params_f64(&self) -> Result<SolverParams<f64>, SolverError> {
        let mut p = self.solver.params(&self.scene_values());
        let takes = self.solver.kind().boundary_features();
        p.take_scene_boundary(self.scene_boundary().only(&takes))?;
        Ok(p)
    }

    /// The moving solids as moving walls: each a box (the parser refuses a motion on another
    /// kind) with its wall model.
    fn moving_walls(&self, default: WallModel) -> Vec<MovingWall<f64>> {
        self.solids
            .iter()
            .enumerate()
            .filter_map(|(j, solid)| match (solid, self.motions.get(j)) {
                (SolidSpec::Box { min, max }, Some(Some(m))) => Some(MovingWall {
                    region: Aabb {
                        min: v3(*min),
                        max: v3(*max),
                    },
                    model: self.wall_of(j).unwrap_or(default),
                    velocity: v3(m.velocity),
                    duration_s: m.duration_s,
                }),
                _ => None,
            })
            .collect()
    }

    /// The wall model solid `j` states (`None`: unstated, or no entry for it).
    fn wall_of(&self, j: usize) -> Option<WallModel> {
        self.walls.solids.get(j).copied().flatten()
    }

    /// The solver parameters the scene asks for, in precision `R`, checked (the settings as
    /// written, then the parameters' `validate` in `f64` and in `R`); an error names the
    /// scene key the refused parameter comes from ([`Scene::check`] runs this in the scene's
    /// precision).
    pub fn solver_params<R: Real>(&self) -> Result<SolverParams<R>, SceneError> {
        let ctx = Ctx {
            lines: Some(&self.lines),
            ..Ctx::new(&self.source)
        };
        self.checked_params::<R>(&ctx)
    }

    /// The solver parameters the scene asks for, built in `f64` and converted to `R`,
    /// without the checks (for a scene checked in `R` already: the solver's constructor
    /// runs `validate` again). An error names a value that does not fit in `R`.
    pub fn solver_params_unchecked<R: Real>(&self) -> Result<SolverParams<R>, SceneError> {
        let ctx = Ctx {
            lines: Some(&self.lines),
            ..Ctx::new(&self.source)
        };
        let p = self
            .solver_params_f64()
            .map_err(|e| self.boundary_error(&ctx, e))?;
        p.try_convert::<R>()
            .map_err(|e| self.param_error(&ctx, &p, Some(R::NAME), e))
    }

    /// The solver parameters in the scene's precision, checked: part of [`Scene::check`].
    pub(crate) fn check_solver_params(&self, ctx: &Ctx) -> Result<(), SceneError> {
        match self.precision {
            Precision::F32 => self.checked_params::<f32>(ctx).map(|_| ()),
            Precision::F64 => self.checked_params::<f64>(ctx).map(|_| ()),
        }
    }

    /// The parameters in `R`, after the checks of the settings as written and the
    /// parameters' `validate` in `f64` and in `R`.
    fn checked_params<R: Real>(&self, ctx: &Ctx) -> Result<SolverParams<R>, SceneError> {
        let key = |name: &'static str| self.key(name);
        self.solver
            .check_written(&key)
            .map_err(|(name, reason)| ctx.invalid(self.key(name), reason))?;
        let p = self
            .solver_params_f64()
            .map_err(|e| self.boundary_error(ctx, e))?;
        p.validate()
            .map_err(|e| self.param_error(ctx, &p, None, e))?;
        let converted = p
            .try_convert::<R>()
            .map_err(|e| self.param_error(ctx, &p, Some(R::NAME), e))?;
        if R::NAME != f64::NAME {
            converted
                .validate()
                .map_err(|e| self.param_error(ctx, &p, Some(R::NAME), e))?;
        }
        Ok(converted)
    }

    /// A solver's refusal `e` of the scene's boundary, at the key of the feature it does not
    /// take.
    fn boundary_error(&self, ctx: &Ctx, e: SolverError) -> SceneError {
        match e {
            SolverError::UnsupportedFeature { feature, .. } => ctx.invalid(
                feature_field(feature),
                format!(
                    "solver kind = \"{}\" does not take {}{}",
                    self.solver.kind_name(),
                    feature.scene_key(),
                    crate::check::takers(feature)
                ),
            ),
            e => ctx.invalid("solver", e.to_string()),
        }
    }

    /// A solver's refusal `e` of a parameter of `p`, at the scene key it comes from: the
    /// reason and the value as the key states it, or, when only the solver's `precision`
    /// refuses it (the `f64` parameters passed), the solver's whole message and the
    /// precision.
    fn param_error(
        &self,
        ctx: &Ctx,
        p: &SolverParams<f64>,
        precision: Option<&str>,
        e: SolverError,
    ) -> SceneError {
        let SolverError::InvalidParameter {
            name,
            value,
            reason,
            ..
        } = &e
        else {
            return ctx.invalid("solver", e.to_string());
        };
        let (key, value) = CommonSettings::key_of(name, *value, self.particle_spacing)
            .or_else(|| p.key_of(name, *value))
            .unwrap_or((name, *value));
        match precision {
            None => ctx.invalid(self.key(key), format!("{reason}, got {value}")),
            Some(precision) => ctx.invalid(
                self.key(key),
                format!("{e} (in {precision}, the precision the solver runs in)"),
            ),
        }
    }

    /// The scene key of the parameter (or setting) `name`: `dt`, `gravity` and
    /// `particle_spacing` in `[simulation]`, `pour` and `periodic` (`[boundary]`) where the
    /// scene states them, any other in `[solver]` under its name or the
    /// old name the file writes for it (the solver's `RENAMED`).
    pub(crate) fn key(&self, name: &str) -> String {
        if name == "pour" {
            return name.to_owned();
        }
        if name == "periodic" {
            return "boundary.periodic".to_owned();
        }
        let simulation = match name {
            "dt" => Some("frame_dt"),
            "gravity" | "particle_spacing" => Some(name),
            _ => None,
        };
        if let Some(field) = simulation {
            return format!("simulation.{field}");
        }
        let written: Vec<&str> = self.lines.fields_under("solver").collect();
        let old = self
            .solver
            .kind()
            .renamed()
            .iter()
            .filter(|(_, new)| *new == name)
            .map(|(old, _)| *old)
            .find(|old| written.contains(old));
        format!("solver.{}", old.unwrap_or(name))
    }
}

/// The scene field of a boundary feature, for the line of an error about it.
pub(crate) fn feature_field(feature: BoundaryFeature) -> &'static str {
    match feature {
        BoundaryFeature::Periodic => "boundary.periodic",
        BoundaryFeature::Pour => "pour",
        _ => "boundary.model",
    }
}

#[cfg(test)]
mod tests {
    use std::path::Path;

    use crate::Scene;

    /// `friction_relaxation` reaches the granular parameters, absent gives the crate's
    /// default, and a value the solver refuses is named by its scene key.
    #[test]
    fn friction_relaxation_reaches_the_granular_parameters() {
        let text = |extra: &str| {
            format!(
                "name = \"relax\"\n[simulation]\nparticle_spacing = 0.05\nduration = 0.1\nframe_dt = 0.02\n[solver]\nkind = \"granular\"\nsubsteps = 1\nfriction_angle_deg = 30.0\n{extra}\n[[fluid]]\nkind = \"block\"\nmin = [0.0, 0.0, 0.0]\nmax = [0.2, 0.2, 0.2]\n"
            )
        };
        let relaxation = |extra: &str| {
            let scene = Scene::parse_str(&text(extra), Path::new("relax.toml")).unwrap();
            let crate::SolverParams::Granular(p) = scene.solver_params::<f64>().unwrap() else {
                panic!("not granular")
            };
            p.granular.expect("granular parameters").friction_relaxation
        };
        assert_eq!(relaxation("friction_relaxation = 0.3"), 0.3);
        assert_eq!(relaxation(""), iisph_granular::DEFAULT_FRICTION_RELAXATION);
        let error = Scene::parse_str(&text("friction_relaxation = 1.5"), Path::new("relax.toml"))
            .unwrap_err()
            .to_string();
        assert!(
            error.contains("solver.friction_relaxation") && error.contains("(0, 1]"),
            "{error}"
        );
    }

    /// A parameter's scene key is its name, or the old name the file writes for it; the
    /// scene's values are in `[simulation]`.
    #[test]
    fn parameters_map_to_their_keys() {
        let text = |iterations: &str, min: &str| {
            format!(
                "name = \"keys\"\n[simulation]\nparticle_spacing = 0.05\nduration = 0.1\nframe_dt = 0.02\n[solver]\nkind = \"pbf\"\nsubsteps = 2\n{iterations} = 3\nmean_compression_tolerance = 0.01\n{min} = 2\n[[fluid]]\nkind = \"block\"\nmin = [0.0, 0.0, 0.0]\nmax = [0.2, 0.2, 0.2]\n"
            )
        };
        let old =
            Scene::parse_str(&text("iterations", "min_iterations"), Path::new("k.toml")).unwrap();
        let new = Scene::parse_str(
            &text("solver_iterations", "min_solver_iterations"),
            Path::new("k.toml"),
        )
        .unwrap();
        assert_eq!(old.solver, new.solver);
        for (scene, iterations, min) in [
            (&old, "solver.iterations", "solver.min_iterations"),
            (
                &new,
                "solver.solver_iterations",
                "solver.min_solver_iterations",
            ),
        ] {
            assert_eq!(scene.key("solver_iterations"), iterations);
            assert_eq!(scene.key("min_solver_iterations"), min);
            assert_eq!(
                scene.key("mean_compression_tolerance"),
                "solver.mean_compression_tolerance"
            );
            assert_eq!(scene.key("substeps"), "solver.substeps");
            assert_eq!(scene.key("dt"), "simulation.frame_dt");
            assert_eq!(scene.key("particle_spacing"), "simulation.particle_spacing");
        }
    }
}
