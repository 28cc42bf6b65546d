//! The value checks of a scene, on its typed fields ([`Scene::check`]): the same whether the
//! scene was just read from a file or edited in code. One function per section, in the
//! order of the file documentation, then the time stepping (`check/time_step.rs`), the
//! particles (`build.rs`), the solver's settings (`params.rs`: the checks of the settings as
//! written, then the parameters' own `validate`, the one range check of every solver
//! setting) and the `[render]` table (`render.rs`); the scene with its `[quick]` overrides
//! is checked too, so that [`Scene::quick`] gives a valid scene.

// NaN-rejecting checks are written as `!(x > 0.0)` on purpose.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

mod time_step;

use sph_core::Aabb;

use crate::error::Ctx;
use crate::geom::{fmt3, v3, AXES};
use crate::mesh_io::placement_field;
use crate::{
    BoundaryModel, FluidSpec, QuickSpec, Scene, SceneError, SolidSpec, SolverKind, WallModel,
};
use sph_solver::scene_boundary::{BoundaryFeature, MAX_WALL_FRICTION, MAX_WALL_MOTION_S};

impl Scene {
    /// Checks every value of the scene, as [`Scene::load`] does: after editing a loaded
    /// scene's fields in code, this says whether the result is a scene a file could give
    /// (errors name the field, with its line in the file the scene was read from when the
    /// field is written there). Meshes are not read again: a [`crate::MeshSpec`] keeps the
    /// mesh as loaded and placed.
    pub fn check(&self) -> Result<(), SceneError> {
        let ctx = Ctx {
            lines: Some(&self.lines),
            ..Ctx::new(&self.source)
        };
        self.check_sections(&ctx)?;
        time_step::check(&ctx, self, None)?;
        self.validate_particles(&ctx)?;
        self.check_solver_params(&ctx)?;
        self.check_render(&ctx)?;
        if let Some(overrides) = &self.quick_overrides {
            let quick = self.quick();
            let ctx = Ctx {
                note: "with the [quick] overrides: ",
                ..ctx
            };
            time_step::check(&ctx, &quick, Some(overrides))?;
            quick.validate_particles(&ctx)?;
            quick.check_solver_params(&ctx)?;
            quick.check_render(&ctx)?;
        }
        Ok(())
    }

    /// The sections but `[solver]`, in file-documentation order.
    fn check_sections(&self, ctx: &Ctx) -> Result<(), SceneError> {
        check_name(ctx, &self.name)?;
        ctx.positive("simulation.particle_spacing", self.particle_spacing)?;
        ctx.positive("simulation.duration", self.duration_s)?;
        ctx.positive("simulation.frame_dt", self.frame_dt_s)?;
        ctx.finite3("simulation.gravity", &self.gravity)?;
        if let Some(t) = &self.tank {
            ctx.check_box("tank", &t.min.into(), &t.max.into())?;
        }
        for (i, f) in self.fluids.iter().enumerate() {
            check_fluid(ctx, &format!("fluid[{i}]"), f, self.tank.as_ref())?;
        }
        for (j, s) in self.solids.iter().enumerate() {
            check_solid(ctx, &format!("solid[{j}]"), s)?;
        }
        self.check_walls(ctx)?;
        self.check_planar(ctx)?;
        if self.output.every_frames == 0 {
            return Err(ctx.invalid("output.every_frames", "must be >= 1, got 0"));
        }
        if let Some(q) = &self.quick_overrides {
            self.check_quick(ctx, q)?;
        }
        Ok(())
    }

    /// The boundary model against the solver (its declared
    /// [`BoundaryFeatures`](sph_solver::BoundaryFeatures)), the walls' models, moving solids,
    /// the pour and the periodic axes against the solver and the tank.
    fn check_walls(&self, ctx: &Ctx) -> Result<(), SceneError> {
        let takes = self.solver.kind().boundary_features();
        let model = match self.boundary.model {
            BoundaryModel::VolumeMap => BoundaryFeature::VolumeMap,
            BoundaryModel::Collision => BoundaryFeature::Collision,
            BoundaryModel::Particles => BoundaryFeature::Particles,
        };
        if !takes.supports(model) {
            let models: Vec<String> = [
                BoundaryFeature::VolumeMap,
                BoundaryFeature::Collision,
                BoundaryFeature::Particles,
            ]
            .into_iter()
            .filter(|f| takes.supports(*f))
            .map(|f| f.scene_key().to_string())
            .collect();
            return Err(ctx.invalid(
                "boundary.model",
                format!(
                    "solver kind = \"{}\" does not take {} (it takes {}){}",
                    self.solver.kind_name(),
                    model.scene_key(),
                    models.join(" or "),
                    takers(model)
                ),
            ));
        }
        let particles = self.boundary.model == BoundaryModel::Particles;
        let walls = std::iter::once(("tank.wall".to_string(), self.walls.tank)).chain(
            self.walls
                .solids
                .iter()
                .enumerate()
                .map(|(j, w)| (format!("solid[{j}].wall"), *w)),
        );
        for (field, wall) in walls {
            let Some(wall) = wall else { continue };
            if !particles {
                return Err(ctx.invalid(
                    field,
                    "a wall model applies to walls of boundary particles: set [boundary] model = \"particles\"",
                ));
            }
            self.refuse_untaken(ctx, &field, BoundaryFeature::WallModels)?;
            if let WallModel::Coulomb(mu) = wall {
                if !(0.0..=MAX_WALL_FRICTION).contains(&mu) {
                    return Err(ctx.invalid(
                        field,
                        format!("the Coulomb friction coefficient must be in [0, MAX_WALL_FRICTION = {MAX_WALL_FRICTION}], got {mu}"),
                    ));
                }
            }
        }
        for (j, m) in self.motions.iter().enumerate() {
            let Some(m) = m else { continue };
            let field = format!("solid[{j}].motion");
            if !particles {
                return Err(ctx.invalid(
                    field,
                    format!(
                        "a moving solid is a wall of boundary particles: set [boundary] model = \"particles\"{}",
                        takers(BoundaryFeature::MovingWalls)
                    ),
                ));
            }
            self.refuse_untaken(ctx, &field, BoundaryFeature::MovingWalls)?;
            match self.solids.get(j) {
                Some(SolidSpec::Box { .. }) => {}
                Some(_) => return Err(ctx.invalid(field, "only a solid of kind = \"box\" moves")),
                None => return Err(ctx.invalid(field, "a motion without its solid")),
            }
            ctx.finite3(&format!("{field}.velocity"), &m.velocity)?;
            ctx.positive(&format!("{field}.duration"), m.duration_s)?;
            if m.duration_s > MAX_WALL_MOTION_S {
                return Err(ctx.invalid(
                    format!("{field}.duration"),
                    format!(
                        "at most MAX_WALL_MOTION_S = {MAX_WALL_MOTION_S} s, got {}",
                        m.duration_s
                    ),
                ));
            }
        }
        if let Some(p) = &self.pour {
            self.refuse_untaken(ctx, "pour", BoundaryFeature::Pour)?;
            ctx.check_box("pour", &p.min, &p.max)?;
            if let Some(t) = &self.tank {
                let (lo, hi) = (t.min, t.max);
                if (0..3).any(|a| p.min[a] < lo[a] || p.max[a] > hi[a]) {
                    return Err(ctx.invalid(
                        "pour",
                        format!(
                            "the pour's box {} – {} must lie inside the tank {} – {}",
                            fmt3(&v3(p.min)),
                            fmt3(&v3(p.max)),
                            fmt3(&lo),
                            fmt3(&hi)
                        ),
                    ));
                }
            }
        }
        if self.walls.tank.is_some() && self.tank.is_none() {
            return Err(ctx.invalid("tank.wall", "a wall model without a tank"));
        }
        if !self.boundary.periodic.is_empty() {
            self.refuse_untaken(ctx, "boundary.periodic", BoundaryFeature::Periodic)?;
        }
        if let Some(t) = &self.tank {
            for (axis, lo, hi) in self.periodic_axes() {
                if axis < 3 && (lo != t.min[axis] || hi != t.max[axis]) {
                    return Err(ctx.invalid(
                        "boundary.periodic",
                        format!(
                            "the period along {} must be the tank's extent [{}, {}] (the tank is open along a periodic axis), got [{lo}, {hi}]",
                            AXES[axis], t.min[axis], t.max[axis]
                        ),
                    ));
                }
            }
        }
        Ok(())
    }

    /// An error at `field` when the scene's solver does not take `feature`.
    fn refuse_untaken(
        &self,
        ctx: &Ctx,
        field: &str,
        feature: BoundaryFeature,
    ) -> Result<(), SceneError> {
        if self.solver.kind().boundary_features().supports(feature) {
            return Ok(());
        }
        Err(ctx.invalid(
            field,
            format!(
                "solver kind = \"{}\" does not take {}{}",
                self.solver.kind_name(),
                feature.scene_key(),
                takers(feature)
            ),
        ))
    }

    /// `[quick]`: each override in range and consistent with the solver.
    fn check_quick(&self, ctx: &Ctx, q: &QuickSpec) -> Result<(), SceneError> {
        for (name, v) in [
            ("particle_spacing", q.particle_spacing),
            ("duration", q.duration_s),
            ("frame_dt", q.frame_dt_s),
        ] {
            if let Some(v) = v {
                ctx.positive(&format!("quick.{name}"), v)?;
            }
        }
        for (name, v) in [
            ("substeps", q.substeps),
            ("iterations", q.iterations),
            ("every_frames", q.every_frames),
        ] {
            if v == Some(0) {
                return Err(ctx.invalid(format!("quick.{name}"), "must be >= 1, got 0"));
            }
        }
        if let Some(k) = q.iterations {
            if let Some(min) = self.solver.min_iterations().filter(|&min| k < min) {
                return Err(ctx.invalid(
                    "quick.iterations",
                    format!("must be >= solver.min_iterations = {min}, got {k}"),
                ));
            }
        }
        Ok(())
    }
}

/// The solvers that take `feature`, for a message: `; solver kind = "…" takes it` (empty
/// when none does).
pub(crate) fn takers(feature: BoundaryFeature) -> String {
    let kinds: Vec<String> = SolverKind::ALL
        .iter()
        .filter(|k| k.boundary_features().supports(feature))
        .map(|k| format!("\"{}\"", k.name()))
        .collect();
    if kinds.is_empty() {
        String::new()
    } else {
        format!("; solver kind = {} takes it", kinds.join(" or "))
    }
}

/// `name`: non-empty, `[A-Za-z0-9_.-]+`.
fn check_name(ctx: &Ctx, name: &str) -> Result<(), SceneError> {
    let ok = !name.is_empty()
        && name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || "_-.".contains(c));
    if ok {
        Ok(())
    } else {
        Err(ctx.invalid(
            "name",
            format!(
                "{name:?}: must be non-empty and use only ASCII letters, digits, '_', '-' and '.'"
            ),
        ))
    }
}

/// One fluid at `field`: finite velocity, a proper block, inside the tank (box level).
fn check_fluid(
    ctx: &Ctx,
    field: &str,
    f: &FluidSpec,
    tank: Option<&Aabb<f64>>,
) -> Result<(), SceneError> {
    ctx.finite3(&format!("{field}.velocity"), &f.velocity())?;
    let (b, bfield) = match f {
        FluidSpec::Block { min, max, .. } => {
            (ctx.check_box(field, min, max)?, format!("{field}.max"))
        }
        FluidSpec::Mesh { mesh, .. } => (mesh.mesh.bounds(), placement_field(field, mesh)),
        FluidSpec::Cylinder {
            base_center,
            radius,
            height,
            ..
        } => {
            check_cylinder(ctx, field, base_center, *radius, *height)?;
            (f.bounds(), format!("{field}.base_center"))
        }
    };
    let Some(t) = tank else {
        return Ok(());
    };
    let tol = 1e-9 * (t.extent().norm() + 1.0);
    match (0..3).find(|&a| b.min[a] < t.min[a] - tol || b.max[a] > t.max[a] + tol) {
        Some(a) => Err(ctx.invalid(
            bfield,
            format!(
                "the fluid's box {} – {} is not inside the tank {} – {} (axis {})",
                fmt3(&b.min),
                fmt3(&b.max),
                fmt3(&t.min),
                fmt3(&t.max),
                AXES[a]
            ),
        )),
        None => Ok(()),
    }
}

/// A cylinder's fields at `field` (fluid or solid): a finite base centre, a positive radius
/// and height.
fn check_cylinder(
    ctx: &Ctx,
    field: &str,
    base_center: &[f64; 3],
    radius: f64,
    height: f64,
) -> Result<(), SceneError> {
    ctx.finite3(&format!("{field}.base_center"), base_center)?;
    ctx.positive(&format!("{field}.radius"), radius)?;
    ctx.positive(&format!("{field}.height"), height)
}

/// One solid at `field`.
fn check_solid(ctx: &Ctx, field: &str, s: &SolidSpec) -> Result<(), SceneError> {
    match s {
        SolidSpec::Sphere { center, radius } => {
            ctx.finite3(&format!("{field}.center"), center)?;
            ctx.positive(&format!("{field}.radius"), *radius)
        }
        SolidSpec::Box { min, max } => ctx.check_box(field, min, max).map(|_| ()),
        SolidSpec::Plane { point, normal } => {
            ctx.finite3(&format!("{field}.point"), point)?;
            ctx.finite3(&format!("{field}.normal"), normal)?;
            let n = v3(*normal).norm();
            if !(n.is_finite() && n > 0.0) {
                return Err(ctx.invalid(
                    format!("{field}.normal"),
                    "must have a finite, non-zero length",
                ));
            }
            Ok(())
        }
        SolidSpec::Cylinder {
            base_center,
            radius,
            height,
        } => check_cylinder(ctx, field, base_center, *radius, *height),
        SolidSpec::Mesh { sdf_cell, .. } => match sdf_cell {
            Some(c) => ctx.positive(&format!("{field}.sdf_cell"), *c),
            None => Ok(()),
        },
    }
}
