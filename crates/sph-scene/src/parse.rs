//! From scene text to a validated [`Scene`]: serde reads the document into the `raw` types
//! (the `[solver]` table in two steps, see [`solver`]), then one function per section checks
//! the values, and the particle-level checks run on the result (and on its `[quick]`
//! variant).

// NaN-rejecting checks are written as `!(x > 0.0)` on purpose.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

mod solver;
mod time_step;

use std::path::Path;

use sph_core::Aabb;
use toml::de::{DeTable, DeValue};
use toml::Spanned;

use crate::error::{document_error, serde_error, Ctx, FieldLines};
use crate::mesh_io::{placement_field, MeshLoader};
use crate::raw::{
    RawBox, RawFluid, RawFluidKind, RawOutput, RawQuick, RawScene, RawSimulation, RawSolid,
    RawSolidKind,
};
use crate::{
    fmt3, v3, FluidSpec, OutputSpec, Precision, QuickSpec, Scene, SceneError, SolidSpec,
    SolverSpec, AXES, DEFAULT_IISPH_MIN_ITERATIONS,
};

/// The `[solver]` table as parsed (with spans), for [`solver::parse`].
type SolverTable<'i> = Spanned<DeValue<'i>>;

/// Gravity when `simulation.gravity` is absent (m/s²).
const DEFAULT_GRAVITY: [f64; 3] = [0.0, -9.81, 0.0];

impl Scene {
    /// Reads, parses and validates the scene file at `path` (mesh paths are relative to its
    /// directory).
    pub fn load(path: &Path) -> Result<Scene, SceneError> {
        let text = std::fs::read_to_string(path).map_err(|e| SceneError::Read {
            file: path.to_path_buf(),
            reason: e.to_string(),
        })?;
        Self::parse_str(&text, path)
    }

    /// Parses and validates scene text; `path` names the file in messages and is the base of
    /// relative mesh paths (its directory).
    pub fn parse_str(text: &str, path: &Path) -> Result<Scene, SceneError> {
        let doc = DeTable::parse(text).map_err(|e| document_error(path, text, &e))?;
        let lines = FieldLines::new(text, doc.get_ref());
        let ctx = Ctx {
            lines: Some(&lines),
            ..Ctx::new(path)
        };
        let solver_table = doc.get_ref().get("solver").cloned();
        let raw: RawScene = serde_path_to_error::deserialize(toml::de::Deserializer::from(doc))
            .map_err(|e| serde_error(path, text, "", "", &e))?;
        // `RawScene` requires `[solver]` (with its `kind`), so the table is there.
        let solver = match solver_table {
            Some(table) => solver::parse(&ctx, text, raw.solver.kind, table)?,
            None => return Err(ctx.invalid("solver", "missing")),
        };
        let base = path.parent().unwrap_or(Path::new(""));
        let scene = from_raw(&ctx, raw, solver, base)?;
        time_step::check(&ctx, &scene, None)?;
        scene.validate_particles(&ctx)?;
        if let Some(overrides) = &scene.quick_overrides {
            let quick = scene.quick();
            let quick_ctx = Ctx {
                note: "with the [quick] overrides: ",
                ..ctx
            };
            time_step::check(&quick_ctx, &quick, Some(overrides))?;
            quick.validate_particles(&quick_ctx)?;
        }
        Ok(scene)
    }
}

/// Checks every section of `raw` but `[solver]` (already read and checked as `solver`), in
/// file-documentation order.
fn from_raw(
    ctx: &Ctx,
    raw: RawScene,
    solver: SolverSpec,
    base: &Path,
) -> Result<Scene, SceneError> {
    check_name(ctx, &raw.name)?;
    let gravity = simulation(ctx, &raw.simulation)?;
    let tank = match &raw.tank {
        Some(t) => Some(ctx.check_box("tank", t)?),
        None => None,
    };
    let mut meshes = MeshLoader::new(base);
    let fluids = raw
        .fluid
        .iter()
        .enumerate()
        .map(|(i, f)| fluid(ctx, &format!("fluid[{i}]"), f, tank.as_ref(), &mut meshes))
        .collect::<Result<Vec<_>, _>>()?;
    let solids = raw
        .solid
        .iter()
        .enumerate()
        .map(|(i, s)| solid(ctx, &format!("solid[{i}]"), s, &mut meshes))
        .collect::<Result<Vec<_>, _>>()?;
    let output = output(ctx, raw.output.as_ref())?;
    let quick_overrides = match &raw.quick {
        Some(q) => Some(quick(ctx, q, &solver)?),
        None => None,
    };
    let sim = raw.simulation;
    Ok(Scene {
        name: raw.name,
        source: ctx.file.to_path_buf(),
        precision: sim.precision.unwrap_or(Precision::F32),
        particle_spacing: sim.particle_spacing,
        duration_s: sim.duration,
        frame_dt_s: sim.frame_dt,
        gravity,
        tank,
        fluids,
        solids,
        solver,
        boundary: raw.boundary,
        output,
        quick_overrides,
        render: raw.render,
    })
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

/// `[simulation]`; returns the gravity (default [`DEFAULT_GRAVITY`]).
fn simulation(ctx: &Ctx, sim: &RawSimulation) -> Result<[f64; 3], SceneError> {
    ctx.positive("simulation.particle_spacing", sim.particle_spacing)?;
    ctx.positive("simulation.duration", sim.duration)?;
    ctx.positive("simulation.frame_dt", sim.frame_dt)?;
    let gravity = sim.gravity.unwrap_or(DEFAULT_GRAVITY);
    ctx.finite3("simulation.gravity", &gravity)?;
    Ok(gravity)
}

/// Rejects the first field of `present` (name, given?) that is given but not one of the
/// kind's `own` fields.
fn forbid(
    ctx: &Ctx,
    field: &str,
    kind: &str,
    present: &[(&str, bool)],
    own: &[&str],
) -> Result<(), SceneError> {
    if let Some((name, _)) = present.iter().find(|(n, p)| *p && !own.contains(n)) {
        return Err(ctx.invalid(
            format!("{field}.{name}"),
            format!("not a field of kind = \"{kind}\""),
        ));
    }
    Ok(())
}

/// The value of a field required by a kind.
fn require<T: Copy>(ctx: &Ctx, field: &str, kind: &str, v: Option<T>) -> Result<T, SceneError> {
    v.ok_or_else(|| ctx.invalid(field, format!("missing (required for kind = \"{kind}\")")))
}

/// The box of a block-like table (`min`, `max`, both required for `kind`).
fn required_box(
    ctx: &Ctx,
    field: &str,
    kind: &str,
    min: Option<[f64; 3]>,
    max: Option<[f64; 3]>,
) -> Result<RawBox, SceneError> {
    let b = RawBox {
        min: require(ctx, &format!("{field}.min"), kind, min)?,
        max: require(ctx, &format!("{field}.max"), kind, max)?,
    };
    ctx.check_box(field, &b)?;
    Ok(b)
}

/// One `[[fluid]]` table at `field`, checked to lie inside the tank (box level).
fn fluid(
    ctx: &Ctx,
    field: &str,
    f: &RawFluid,
    tank: Option<&Aabb<f64>>,
    meshes: &mut MeshLoader,
) -> Result<FluidSpec, SceneError> {
    let velocity = f.velocity.unwrap_or([0.0; 3]);
    ctx.finite3(&format!("{field}.velocity"), &velocity)?;
    // The kind-specific fields given, in the order errors report them.
    let present = [
        ("min", f.min.is_some()),
        ("max", f.max.is_some()),
        ("path", f.path.is_some()),
        ("scale", f.scale.is_some()),
        ("translate", f.translate.is_some()),
        ("fit", f.fit.is_some()),
    ];
    let spec = match f.kind {
        RawFluidKind::Block => {
            forbid(ctx, field, "block", &present, &["min", "max"])?;
            let b = required_box(ctx, field, "block", f.min, f.max)?;
            FluidSpec::Block {
                min: b.min,
                max: b.max,
                velocity,
            }
        }
        RawFluidKind::Mesh => {
            let own = ["path", "scale", "translate", "fit"];
            forbid(ctx, field, "mesh", &present, &own)?;
            let mesh = meshes.mesh_spec(ctx, field, f.mesh_fields())?;
            FluidSpec::Mesh { mesh, velocity }
        }
    };
    if let Some(t) = tank {
        fluid_inside_tank(ctx, field, &spec, t)?;
    }
    Ok(spec)
}

/// The fluid's bounding box lies inside the tank (up to rounding).
fn fluid_inside_tank(
    ctx: &Ctx,
    field: &str,
    spec: &FluidSpec,
    t: &Aabb<f64>,
) -> Result<(), SceneError> {
    let (b, bfield) = match spec {
        FluidSpec::Block { min, max, .. } => (
            Aabb {
                min: v3(*min),
                max: v3(*max),
            },
            format!("{field}.max"),
        ),
        FluidSpec::Mesh { mesh, .. } => (mesh.mesh.bounds(), placement_field(field, mesh)),
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

/// One `[[solid]]` table at `field`.
fn solid(
    ctx: &Ctx,
    field: &str,
    s: &RawSolid,
    meshes: &mut MeshLoader,
) -> Result<SolidSpec, SceneError> {
    // The kind-specific fields given, in the order errors report them.
    let present = [
        ("center", s.center.is_some()),
        ("radius", s.radius.is_some()),
        ("min", s.min.is_some()),
        ("max", s.max.is_some()),
        ("point", s.point.is_some()),
        ("normal", s.normal.is_some()),
        ("path", s.path.is_some()),
        ("scale", s.scale.is_some()),
        ("translate", s.translate.is_some()),
        ("fit", s.fit.is_some()),
        ("sdf_cell", s.sdf_cell.is_some()),
    ];
    let vector = |name: &str, kind: &str, v: Option<[f64; 3]>| {
        let f = format!("{field}.{name}");
        let v = require(ctx, &f, kind, v)?;
        ctx.finite3(&f, &v).map(|()| v)
    };
    Ok(match s.kind {
        RawSolidKind::Sphere => {
            forbid(ctx, field, "sphere", &present, &["center", "radius"])?;
            let center = vector("center", "sphere", s.center)?;
            let radius = require(ctx, &format!("{field}.radius"), "sphere", s.radius)?;
            ctx.positive(&format!("{field}.radius"), radius)?;
            SolidSpec::Sphere { center, radius }
        }
        RawSolidKind::Box => {
            forbid(ctx, field, "box", &present, &["min", "max"])?;
            let b = required_box(ctx, field, "box", s.min, s.max)?;
            SolidSpec::Box {
                min: b.min,
                max: b.max,
            }
        }
        RawSolidKind::Plane => {
            forbid(ctx, field, "plane", &present, &["point", "normal"])?;
            let point = vector("point", "plane", s.point)?;
            let normal = vector("normal", "plane", s.normal)?;
            let n = v3(normal).norm();
            if !(n.is_finite() && n > 0.0) {
                return Err(ctx.invalid(
                    format!("{field}.normal"),
                    "must have a finite, non-zero length",
                ));
            }
            SolidSpec::Plane { point, normal }
        }
        RawSolidKind::Mesh => {
            let own = ["path", "scale", "translate", "fit", "sdf_cell"];
            forbid(ctx, field, "mesh", &present, &own)?;
            if let Some(c) = s.sdf_cell {
                ctx.positive(&format!("{field}.sdf_cell"), c)?;
            }
            let mesh = meshes.mesh_spec(ctx, field, s.mesh_fields())?;
            SolidSpec::Mesh {
                mesh,
                sdf_cell: s.sdf_cell,
            }
        }
    })
}

/// `[output]` (optional, defaults: every frame, VTK on).
fn output(ctx: &Ctx, o: Option<&RawOutput>) -> Result<OutputSpec, SceneError> {
    let output = OutputSpec {
        every_frames: o.and_then(|o| o.every_frames).unwrap_or(1),
        vtk: o.and_then(|o| o.vtk).unwrap_or(true),
    };
    if output.every_frames == 0 {
        return Err(ctx.invalid("output.every_frames", "must be >= 1, got 0"));
    }
    Ok(output)
}

/// `[quick]`: each override in range and consistent with `solver`.
fn quick(ctx: &Ctx, q: &RawQuick, solver: &SolverSpec) -> Result<QuickSpec, SceneError> {
    for (name, v) in [
        ("particle_spacing", q.particle_spacing),
        ("duration", q.duration),
        ("frame_dt", q.frame_dt),
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
    let min_iterations = match solver {
        SolverSpec::Pbf(p) => p.min_iterations,
        SolverSpec::Pcisph(_) => None,
        SolverSpec::Iisph(p) => Some(p.min_iterations.unwrap_or(DEFAULT_IISPH_MIN_ITERATIONS)),
        SolverSpec::Granular(p) => Some(p.min_iterations.unwrap_or(DEFAULT_IISPH_MIN_ITERATIONS)),
    };
    if let Some(k) = q.iterations {
        if let Some(min) = min_iterations.filter(|&min| k < min) {
            return Err(ctx.invalid(
                "quick.iterations",
                format!("must be >= solver.min_iterations = {min}, got {k}"),
            ));
        }
    }
    Ok(QuickSpec {
        particle_spacing: q.particle_spacing,
        duration_s: q.duration,
        frame_dt_s: q.frame_dt,
        substeps: q.substeps,
        iterations: q.iterations,
        every_frames: q.every_frames,
    })
}
