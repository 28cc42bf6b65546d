//! From scene text to a [`Scene`]: serde reads the document into the `raw` types (the
//! `[solver]` table in two steps, see [`solver`]), the kinds of fluids and solids get their
//! fields, the meshes are loaded and placed; then [`Scene::check`] checks every value.

mod solver;

use std::path::Path;
use std::sync::Arc;

use sph_core::Aabb;
use toml::de::{DeTable, DeValue};
use toml::Spanned;

use crate::error::{document_error, serde_error, Ctx, FieldLines};
use crate::geom::v3;
use crate::limits::MAX_SCENE_FILE_BYTES;
use crate::mesh_io::{MeshFields, MeshLoader};
use crate::overrides::{self, Override};
use crate::raw::{
    RawBox, RawFluid, RawFluidKind, RawOutput, RawQuick, RawScene, RawSolid, RawSolidKind,
};
use crate::read::read_limited;
use crate::sample_cache::FluidSampleCache;
use crate::{
    FluidSpec, OutputSpec, Precision, QuickSpec, Scene, SceneError, SceneWalls, SolidSpec,
    SolverSpec,
};

/// The `[solver]` table as parsed (with spans), for [`solver::parse`].
type SolverTable<'i> = Spanned<DeValue<'i>>;

/// Gravity when `simulation.gravity` is absent (m/s²).
const DEFAULT_GRAVITY: [f64; 3] = [0.0, -9.81, 0.0];

impl Scene {
    /// Reads, parses and checks the scene file at `path` (mesh paths are relative to its
    /// directory). Only a regular file of at most [`MAX_SCENE_FILE_BYTES`] is read.
    pub fn load(path: &Path) -> Result<Scene, SceneError> {
        Self::load_with(path, &[])
    }

    /// [`Scene::load`] with `overrides` applied to the file's document before it is read
    /// (see [`Override`]): errors name the overridden keys as the file would.
    pub fn load_with(path: &Path, overrides: &[Override]) -> Result<Scene, SceneError> {
        Self::parse_str_with(&Self::read_text(path)?, path, overrides)
    }

    /// The text of the scene file at `path`, as [`Scene::load`] reads it: a regular file of
    /// at most [`MAX_SCENE_FILE_BYTES`], UTF-8.
    pub fn read_text(path: &Path) -> Result<String, SceneError> {
        let read_error = |reason: String| SceneError::Read {
            file: path.to_path_buf(),
            reason,
        };
        let bytes = read_limited(
            path,
            MAX_SCENE_FILE_BYTES,
            "scene file (MAX_SCENE_FILE_BYTES)",
        )
        .map_err(read_error)?;
        String::from_utf8(bytes).map_err(|e| {
            let at = e.utf8_error().valid_up_to();
            let line = e.as_bytes()[..at].iter().filter(|&&b| b == b'\n').count() + 1;
            read_error(format!("line {line}: not UTF-8 text (is it a scene file?)"))
        })
    }

    /// Parses and checks scene text ([`Scene::check`]); `path` names the file in messages and
    /// is the base of relative mesh paths (its directory).
    pub fn parse_str(text: &str, path: &Path) -> Result<Scene, SceneError> {
        Self::parse_str_with(text, path, &[])
    }

    /// [`Scene::parse_str`] with `overrides` applied, in order, to the parsed document
    /// before serde reads it ([`Override`]).
    pub fn parse_str_with(
        text: &str,
        path: &Path,
        overrides: &[Override],
    ) -> Result<Scene, SceneError> {
        let value_docs = overrides::value_documents(path, overrides)?;
        let mut doc = DeTable::parse(text).map_err(|e| document_error(path, text, &e))?;
        overrides::apply(path, doc.get_mut(), overrides, &value_docs)?;
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
        let scene = Scene {
            lines: Arc::new(lines),
            ..scene
        };
        scene.check()?;
        Ok(scene)
    }
}

/// The typed scene of `raw` and `solver`: each fluid and solid with the fields of its kind,
/// meshes loaded and placed. The values are checked later, by [`Scene::check`].
fn from_raw(
    ctx: &Ctx,
    raw: RawScene,
    solver: SolverSpec,
    base: &Path,
) -> Result<Scene, SceneError> {
    let mut meshes = MeshLoader::new(base);
    let fluids = raw
        .fluid
        .iter()
        .enumerate()
        .map(|(i, f)| fluid(ctx, &format!("fluid[{i}]"), f, &mut meshes))
        .collect::<Result<Vec<_>, _>>()?;
    let solids = raw
        .solid
        .iter()
        .enumerate()
        .map(|(i, s)| solid(ctx, &format!("solid[{i}]"), s, &mut meshes))
        .collect::<Result<Vec<_>, _>>()?;
    let walls = SceneWalls {
        tank: raw.tank.and_then(|t| t.wall),
        solids: raw.solid.iter().map(|s| s.wall).collect(),
    };
    let motions = raw.solid.iter().map(|s| s.motion).collect();
    let sim = raw.simulation;
    Ok(Scene {
        name: raw.name,
        source: ctx.file.to_path_buf(),
        precision: sim.precision.unwrap_or(Precision::F32),
        particle_spacing: sim.particle_spacing,
        duration_s: sim.duration,
        frame_dt_s: sim.frame_dt,
        gravity: sim.gravity.unwrap_or(DEFAULT_GRAVITY),
        dimensions: sim.dimensions.unwrap_or_default(),
        tank: raw.tank.map(|t| Aabb {
            min: v3(t.min),
            max: v3(t.max),
        }),
        fluids,
        solids,
        walls,
        motions,
        pour: raw.pour,
        solver,
        boundary: raw.boundary,
        output: output(raw.output.as_ref()),
        quick_overrides: raw.quick.as_ref().map(quick),
        render: raw.render,
        lines: Arc::default(),
        fluid_samples: FluidSampleCache::default(),
    })
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
    Ok(RawBox {
        min: require(ctx, &format!("{field}.min"), kind, min)?,
        max: require(ctx, &format!("{field}.max"), kind, max)?,
    })
}

/// The fields of `kind = "cylinder"` (fluid and solid).
const CYLINDER_FIELDS: [&str; 3] = ["base_center", "radius", "height"];

/// One `[[fluid]]` table at `field`.
fn fluid(
    ctx: &Ctx,
    field: &str,
    f: &RawFluid,
    meshes: &mut MeshLoader,
) -> Result<FluidSpec, SceneError> {
    let velocity = f.velocity.unwrap_or([0.0; 3]);
    // The kind-specific fields given, in the order errors report them.
    let present = [
        ("min", f.min.is_some()),
        ("max", f.max.is_some()),
        ("path", f.path.is_some()),
        ("scale", f.scale.is_some()),
        ("translate", f.translate.is_some()),
        ("fit", f.fit.is_some()),
        ("base_center", f.base_center.is_some()),
        ("radius", f.radius.is_some()),
        ("height", f.height.is_some()),
    ];
    Ok(match f.kind {
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
            let mesh = meshes.mesh_spec(ctx, field, MeshFields::of_fluid(f))?;
            FluidSpec::Mesh { mesh, velocity }
        }
        RawFluidKind::Cylinder => {
            forbid(ctx, field, "cylinder", &present, &CYLINDER_FIELDS)?;
            let required = |name: &str, v| require(ctx, &format!("{field}.{name}"), "cylinder", v);
            FluidSpec::Cylinder {
                base_center: require(
                    ctx,
                    &format!("{field}.base_center"),
                    "cylinder",
                    f.base_center,
                )?,
                radius: required("radius", f.radius)?,
                height: required("height", f.height)?,
                velocity,
            }
        }
    })
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
        ("base_center", s.base_center.is_some()),
        ("height", s.height.is_some()),
    ];
    let vector = |name: &str, kind: &str, v: Option<[f64; 3]>| {
        require(ctx, &format!("{field}.{name}"), kind, v)
    };
    Ok(match s.kind {
        RawSolidKind::Sphere => {
            forbid(ctx, field, "sphere", &present, &["center", "radius"])?;
            let center = vector("center", "sphere", s.center)?;
            let radius = require(ctx, &format!("{field}.radius"), "sphere", s.radius)?;
            SolidSpec::Sphere { center, radius }
        }
        _ if s.motion.is_some() && s.kind != RawSolidKind::Box => {
            return Err(ctx.invalid(
                format!("{field}.motion"),
                "only a solid of kind = \"box\" moves (a wall of boundary particles)",
            ))
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
            SolidSpec::Plane { point, normal }
        }
        RawSolidKind::Mesh => {
            let own = ["path", "scale", "translate", "fit", "sdf_cell"];
            forbid(ctx, field, "mesh", &present, &own)?;
            let mesh = meshes.mesh_spec(ctx, field, MeshFields::of_solid(s))?;
            SolidSpec::Mesh {
                mesh,
                sdf_cell: s.sdf_cell,
            }
        }
        RawSolidKind::Cylinder => {
            forbid(ctx, field, "cylinder", &present, &CYLINDER_FIELDS)?;
            SolidSpec::Cylinder {
                base_center: vector("base_center", "cylinder", s.base_center)?,
                radius: require(ctx, &format!("{field}.radius"), "cylinder", s.radius)?,
                height: require(ctx, &format!("{field}.height"), "cylinder", s.height)?,
            }
        }
    })
}

/// `[output]` (optional, defaults: every frame, VTK on).
fn output(o: Option<&RawOutput>) -> OutputSpec {
    OutputSpec {
        every_frames: o.and_then(|o| o.every_frames).unwrap_or(1),
        vtk: o.and_then(|o| o.vtk).unwrap_or(true),
    }
}

/// `[quick]`, as written.
fn quick(q: &RawQuick) -> QuickSpec {
    QuickSpec {
        particle_spacing: q.particle_spacing,
        duration_s: q.duration,
        frame_dt_s: q.frame_dt,
        substeps: q.substeps,
        iterations: q.iterations,
        every_frames: q.every_frames,
    }
}
