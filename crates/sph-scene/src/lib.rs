//! Scene files (TOML) shared by the workspace's particle solvers (PBF, PCISPH; later an IISPH
//! granular solver): fluid blocks and meshes, the tank, solid obstacles, solver parameters,
//! duration and output.
//!
//! [`Scene::load`] reads and validates a file; [`Scene::fluid_positions`] samples the initial
//! particles and [`Scene::build_solids`] builds the boundary signed distance fields (the tank
//! first, as `Inverted<BoxSdf>`, then the solids in file order, meshes as
//! [`GridSdf`], the PBF paper's "signed distance fields stored as volume
//! textures" after Bridson et al. 2006 / SDFGen). [`Scene::quick`] applies the optional
//! `[quick]` overrides used by `cargo xtask validate` and `run --quick`.
//!
//! # Format
//!
//! SI units throughout (m, s, kg/m³). Every table rejects unknown keys. Vectors are arrays of
//! three numbers `[x, y, z]`; gravity is along −y by convention.
//!
//! ```toml
//! name = "dam_break"               # [A-Za-z0-9_.-]+, used for output directories
//!
//! [simulation]
//! precision = "f32"                # "f32" | "f64" (default "f32")
//! particle_spacing = 0.025         # m, lattice spacing of the fluid = 2 × particle radius
//! duration = 6.0                   # s, simulated time
//! frame_dt = 0.016                 # s, one output/solver frame
//! gravity = [0.0, -9.81, 0.0]      # m/s² (default [0, -9.81, 0])
//!
//! [solver]
//! kind = "pbf"                     # "pbf" | "pcisph"
//! substeps = 4                     # solver steps per frame (>= 1)
//! iterations = 3                   # PBF: constraint iterations per step; PCISPH: max
//!                                  # pressure iterations per step (>= 1)
//! # Optional overrides (the solver's defaults otherwise):
//! # rest_density = 1000.0          # kg/m³ (> 0)
//! # support_over_spacing = 2.0     # h / particle_spacing (> 1)
//! # relative_cfm = 1.0             # PBF CFM ε relative to the full-lattice denominator (> 0)
//! # scorr_k = 0.1                  # PBF artificial pressure k (>= 0)
//! # scorr_n = 4                    # PBF artificial pressure exponent (>= 1)
//! # scorr_delta_q = 0.2            # PBF |Δq| / h, in (0, 1)
//! # vorticity_epsilon = 0.0        # vorticity confinement ε, m/s (>= 0)
//! # xsph_c = 0.01                  # XSPH viscosity c, in [0, 1]
//! # reorder_every = 10             # frames between particle reorderings (0 = never)
//! # clamp_negative_constraint = false # PBF only: unilateral C = max(ρ/ρ0 − 1, 0)
//! # mean_compression_tolerance = 0.001 # PBF only: stop iterating at this mean compression
//! #                                # (> 0); `iterations` is then the maximum
//! # min_iterations = 2             # PBF only, with mean_compression_tolerance (>= 1)
//! # clamp_negative_pressure = true # PCISPH only
//! # density_error_tolerance = 0.01 # PCISPH only: relative density error to stop at (> 0)
//!
//! [tank]                           # optional: the container, a closed box (particles inside)
//! min = [0.0, 0.0, 0.0]            # m
//! max = [1.6, 1.0, 0.6]            # m, > min on every axis
//!
//! [[fluid]]                        # any number of fluid bodies, sampled in file order
//! kind = "block"
//! min = [0.0, 0.0, 0.0]            # m
//! max = [0.5, 0.8, 0.6]            # m, > min on every axis
//! velocity = [0.0, 0.0, 0.0]       # m/s, initial velocity (default 0)
//!
//! [[fluid]]
//! kind = "mesh"                    # a closed triangle mesh (OBJ), filled with fluid
//! path = "../reference-data/meshes/bunny.obj"   # relative to this scene file
//! scale = 0.05                     # uniform scale applied first (default 1, > 0)
//! translate = [0.8, 0.4, 0.3]      # m, then this translation (default 0)
//! # or, instead of scale/translate:
//! # fit = { min = [0.6, 0.3, 0.1], max = [1.0, 0.8, 0.5] }
//! #   uniform scale making the mesh's bounding box as large as fits in the box (aspect
//! #   kept), centred in it
//! velocity = [0.0, -1.0, 0.0]      # m/s (default 0)
//!
//! [[solid]]                        # obstacles, in file order after the tank
//! kind = "sphere"                  # center (m), radius (m, > 0)
//! center = [0.8, 0.2, 0.3]
//! radius = 0.1
//! # kind = "box":   min, max (m)
//! # kind = "plane": point (m), normal (points into the free side, normalised)
//! # kind = "mesh":  path, scale/translate or fit (as for fluids), sdf_cell (m, grid spacing of
//! #                 the signed distance field, default particle_spacing / 2)
//!
//! [output]                         # optional
//! every_frames = 1                 # write a VTK frame every N frames (>= 1, default 1)
//! vtk = true                       # default true
//!
//! [quick]                          # optional overrides for quick mode (all optional)
//! particle_spacing = 0.05          # m
//! duration = 1.0                   # s
//! # frame_dt, substeps, iterations, every_frames
//! ```
//!
//! # Sampling and validation
//!
//! * Blocks are sampled with [`sph_core::sampling::cubic_lattice`] at `particle_spacing`:
//!   the first particle half a spacing inside the lower corner, so a block of `n` spacings
//!   holds `n` particles per axis.
//! * Meshes are filled with the points of the same kind of lattice laid over the placed
//!   mesh's bounding box whose signed distance to the mesh is **< 0** (centre inside the
//!   surface), so that `N s³` approximates the mesh volume without bias. The distance is a
//!   [`GridSdf`] with cell = `particle_spacing` (only its sign matters).
//! * Meshes must be closed ([`TriangleMesh::check_closed`]); OBJ files are loaded with `tobj`
//!   (polygons triangulated; vertices of several objects welded by exact position).
//! * After parsing, every value is checked: spacing, durations, radii and cells finite and
//!   positive, every number finite, `min < max`, substeps/iterations ≥ 1, fluids inside the tank
//!   (block or mesh bounds inside the tank box, every particle strictly inside it), no fluid
//!   particle inside (or on) a solid, at most [`MAX_PARTICLES`] particles, mesh files that
//!   exist and are closed. The scene with its `[quick]` overrides is validated too, so
//!   [`Scene::quick`] cannot fail.
//! * Every [`SceneError`] names the scene file, the field path (`fluid[1].min`,
//!   `solver.substeps`, …) and the reason. The library does not panic on any input.

// NaN-rejecting checks are written as `!(x > 0.0)` on purpose.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

mod raw;

use std::collections::HashMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use serde::Deserialize;
use sph_core::{
    sampling::cubic_lattice, Aabb, BoxSdf, GridSdf, Inverted, Plane, Real, Sdf, Sphere,
    TriangleMesh, Vec3,
};

use raw::{RawBox, RawFluidKind, RawScene, RawSolidKind};

/// Largest total number of fluid particles a scene may produce (20 M).
pub const MAX_PARTICLES: usize = 20_000_000;

/// Largest number of nodes of a signed distance grid built for a mesh (16 M).
pub const MAX_SDF_NODES: usize = 16 << 20;

/// Errors of scene loading and building. Every variant names the scene file, the field path
/// and the reason.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum SceneError {
    /// The scene file could not be read.
    #[error("{}: cannot read the scene file: {reason}", file.display())]
    Read {
        /// The scene file.
        file: PathBuf,
        /// Operating-system reason.
        reason: String,
    },
    /// TOML syntax error, wrong type, unknown or missing field.
    #[error("{}: {field}: {reason}", file.display())]
    Syntax {
        /// The scene file.
        file: PathBuf,
        /// Field path (`solver.substeps`), or `<document>` for a syntax error.
        field: String,
        /// What is wrong, with line and column.
        reason: String,
    },
    /// A value is out of range or inconsistent with others.
    #[error("{}: {field}: {reason}", file.display())]
    Invalid {
        /// The scene file.
        file: PathBuf,
        /// Field path, e.g. `fluid[1].min`.
        field: String,
        /// What is wrong.
        reason: String,
    },
    /// A mesh file is missing, unreadable, malformed or not closed.
    #[error("{}: {field}: mesh {}: {reason}", file.display(), mesh.display())]
    Mesh {
        /// The scene file.
        file: PathBuf,
        /// Field path of the mesh's `path`, e.g. `solid[0].path`.
        field: String,
        /// The mesh file, resolved against the scene file's directory.
        mesh: PathBuf,
        /// What is wrong (for an open mesh: the first offending edge).
        reason: String,
    },
}

impl SceneError {
    /// The field path the error refers to.
    pub fn field(&self) -> &str {
        match self {
            SceneError::Read { .. } => "<file>",
            SceneError::Syntax { field, .. }
            | SceneError::Invalid { field, .. }
            | SceneError::Mesh { field, .. } => field,
        }
    }
}

/// Floating-point precision the solver should run in.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Precision {
    /// `f32`.
    F32,
    /// `f64`.
    F64,
}

/// Which solver a scene is meant for.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum SolverKind {
    /// Position Based Fluids (Macklin & Müller 2013).
    Pbf,
    /// Predictive-corrective incompressible SPH (Solenthaler & Pajarola 2009).
    Pcisph,
}

/// Solver settings: step counts and optional overrides of the solver's defaults (`None` =
/// the solver's default). Units as in the crate documentation. Read from the `[solver]`
/// table as written (serde) and range-checked by the scene parser.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SolverSpec {
    /// Which solver.
    pub kind: SolverKind,
    /// Solver steps per frame (≥ 1).
    pub substeps: usize,
    /// PBF: constraint iterations per step; PCISPH: maximum pressure iterations (≥ 1).
    pub iterations: usize,
    /// Rest density (kg/m³, > 0).
    pub rest_density: Option<f64>,
    /// Support radius over particle spacing (> 1).
    pub support_over_spacing: Option<f64>,
    /// PBF CFM relaxation relative to the full-lattice denominator (> 0).
    pub relative_cfm: Option<f64>,
    /// PBF artificial pressure strength `k` (≥ 0).
    pub scorr_k: Option<f64>,
    /// PBF artificial pressure exponent `n` (≥ 1).
    pub scorr_n: Option<u32>,
    /// PBF `|Δq|` as a fraction of `h`, in (0, 1).
    pub scorr_delta_q: Option<f64>,
    /// Vorticity confinement `ε` (m/s, ≥ 0).
    pub vorticity_epsilon: Option<f64>,
    /// XSPH viscosity `c`, in [0, 1].
    pub xsph_c: Option<f64>,
    /// Reorder particles every this many frames (0 = never).
    pub reorder_every: Option<usize>,
    /// PCISPH: clamp negative pressures to zero.
    pub clamp_negative_pressure: Option<bool>,
    /// PCISPH: relative density error at which the pressure iteration stops (> 0).
    pub density_error_tolerance: Option<f64>,
    /// PBF: unilateral density constraint `max(ρ/ρ0 − 1, 0)`.
    pub clamp_negative_constraint: Option<bool>,
    /// PBF: mean compression at which the Jacobi iterations stop (> 0; `iterations` is then
    /// the maximum).
    pub mean_compression_tolerance: Option<f64>,
    /// PBF: fewest iterations per step with `mean_compression_tolerance` (≥ 1, ≤
    /// `iterations`).
    pub min_iterations: Option<usize>,
}

/// Output settings.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct OutputSpec {
    /// Write a frame every this many frames (≥ 1).
    pub every_frames: usize,
    /// Write VTK files.
    pub vtk: bool,
}

/// How a mesh file is placed in the scene.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum MeshPlacement {
    /// `p ↦ scale · p + translate` (file units to metres).
    Transform {
        /// Uniform scale (> 0).
        scale: f64,
        /// Translation (m).
        translate: [f64; 3],
    },
    /// Uniformly scaled to the largest size fitting in the box (aspect kept) and centred in
    /// it.
    Fit {
        /// Lower corner (m).
        min: [f64; 3],
        /// Upper corner (m).
        max: [f64; 3],
    },
}

/// A mesh referenced by the scene, loaded once (shared by [`Scene::quick`] copies).
#[derive(Debug, Clone)]
pub struct MeshSpec {
    /// The mesh file, resolved against the scene file's directory.
    pub path: PathBuf,
    /// How it is placed.
    pub placement: MeshPlacement,
    /// The closed mesh, placed (scene coordinates, metres).
    pub mesh: Arc<TriangleMesh<f64>>,
}

/// A body of fluid.
#[derive(Debug, Clone)]
pub enum FluidSpec {
    /// An axis-aligned block.
    Block {
        /// Lower corner (m).
        min: [f64; 3],
        /// Upper corner (m).
        max: [f64; 3],
        /// Initial velocity (m/s).
        velocity: [f64; 3],
    },
    /// The inside of a closed mesh.
    Mesh {
        /// The mesh.
        mesh: MeshSpec,
        /// Initial velocity (m/s).
        velocity: [f64; 3],
    },
}

/// A solid obstacle (particles live outside it).
#[derive(Debug, Clone)]
pub enum SolidSpec {
    /// A ball.
    Sphere {
        /// Centre (m).
        center: [f64; 3],
        /// Radius (m, > 0).
        radius: f64,
    },
    /// An axis-aligned box.
    Box {
        /// Lower corner (m).
        min: [f64; 3],
        /// Upper corner (m).
        max: [f64; 3],
    },
    /// A half-space; `normal` points into the free side.
    Plane {
        /// A point on the plane (m).
        point: [f64; 3],
        /// Normal (normalised when built).
        normal: [f64; 3],
    },
    /// The inside of a closed mesh, as a [`GridSdf`].
    Mesh {
        /// The mesh.
        mesh: MeshSpec,
        /// Grid spacing (m) of its signed distance field; `None` = `particle_spacing / 2`.
        sdf_cell: Option<f64>,
    },
}

/// The `[quick]` overrides (all optional).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct QuickSpec {
    /// Particle spacing (m).
    pub particle_spacing: Option<f64>,
    /// Duration (s).
    pub duration_s: Option<f64>,
    /// Frame length (s).
    pub frame_dt_s: Option<f64>,
    /// Solver steps per frame.
    pub substeps: Option<usize>,
    /// Solver iterations.
    pub iterations: Option<usize>,
    /// Output every N frames.
    pub every_frames: Option<usize>,
}

/// A validated scene (see the crate documentation for the file format).
#[derive(Debug, Clone)]
pub struct Scene {
    /// Scene name.
    pub name: String,
    /// The file it was read from (as given to [`Scene::load`] / [`Scene::parse_str`]).
    pub source: PathBuf,
    /// Solver precision.
    pub precision: Precision,
    /// Lattice spacing of the fluid (m) = 2 × particle radius.
    pub particle_spacing: f64,
    /// Simulated time (s).
    pub duration_s: f64,
    /// Frame length (s).
    pub frame_dt_s: f64,
    /// Gravity (m/s²).
    pub gravity: [f64; 3],
    /// The container, if any.
    pub tank: Option<Aabb<f64>>,
    /// Fluid bodies, in file order.
    pub fluids: Vec<FluidSpec>,
    /// Solid obstacles, in file order.
    pub solids: Vec<SolidSpec>,
    /// Solver settings.
    pub solver: SolverSpec,
    /// Output settings.
    pub output: OutputSpec,
    /// The `[quick]` overrides (`None` when absent, and in the scene returned by
    /// [`Scene::quick`]).
    pub quick_overrides: Option<QuickSpec>,
}

// ---------------------------------------------------------------------------------------
// Error helpers.

struct Ctx<'a> {
    file: &'a Path,
    /// Prefix for reasons (e.g. "with the [quick] overrides: ").
    note: &'a str,
}

impl Ctx<'_> {
    fn invalid(&self, field: impl Into<String>, reason: impl AsRef<str>) -> SceneError {
        SceneError::Invalid {
            file: self.file.to_path_buf(),
            field: field.into(),
            reason: format!("{}{}", self.note, reason.as_ref()),
        }
    }

    fn positive(&self, field: &str, v: f64) -> Result<(), SceneError> {
        if v.is_finite() && v > 0.0 {
            Ok(())
        } else {
            Err(self.invalid(field, format!("must be finite and > 0, got {v}")))
        }
    }

    fn finite3(&self, field: &str, v: &[f64; 3]) -> Result<(), SceneError> {
        match (0..3).find(|&a| !v[a].is_finite()) {
            Some(a) => Err(self.invalid(
                field,
                format!("component {} is not finite ({})", AXES[a], v[a]),
            )),
            None => Ok(()),
        }
    }

    fn check_box(&self, field: &str, b: &RawBox) -> Result<Aabb<f64>, SceneError> {
        self.finite3(&format!("{field}.min"), &b.min)?;
        self.finite3(&format!("{field}.max"), &b.max)?;
        if let Some(a) = (0..3).find(|&a| b.min[a] >= b.max[a]) {
            return Err(self.invalid(
                format!("{field}.min"),
                format!(
                    "min must be < max on every axis ({}: min {} >= max {})",
                    AXES[a], b.min[a], b.max[a]
                ),
            ));
        }
        Ok(Aabb {
            min: v3(b.min),
            max: v3(b.max),
        })
    }
}

const AXES: [char; 3] = ['x', 'y', 'z'];

fn v3(a: [f64; 3]) -> Vec3<f64> {
    Vec3::new(a[0], a[1], a[2])
}

fn cast3<R: Real>(v: &Vec3<f64>) -> Vec3<R> {
    Vec3::new(R::of_f64(v.x), R::of_f64(v.y), R::of_f64(v.z))
}

fn fmt3(v: &Vec3<f64>) -> String {
    format!("({:.6}, {:.6}, {:.6})", v.x, v.y, v.z)
}

/// Line and column (1-based) of a byte offset.
fn line_col(text: &str, offset: usize) -> (usize, usize) {
    let offset = offset.min(text.len());
    let mut line = 1;
    let mut col = 1;
    for (i, ch) in text.char_indices() {
        if i >= offset {
            break;
        }
        if ch == '\n' {
            line += 1;
            col = 1;
        } else {
            col += 1;
        }
    }
    (line, col)
}

fn toml_reason(text: &str, e: &toml::de::Error) -> String {
    let mut s = e.message().trim().to_string();
    if let Some(span) = e.span() {
        let (l, c) = line_col(text, span.start);
        let _ = write!(s, " (line {l}, column {c})");
    }
    s
}

// ---------------------------------------------------------------------------------------
// Mesh loading.

fn load_obj(path: &Path) -> Result<TriangleMesh<f64>, String> {
    if !path.is_file() {
        return Err("file not found".into());
    }
    let opts = tobj::LoadOptions {
        triangulate: true,
        single_index: false,
        ignore_points: true,
        ignore_lines: true,
    };
    let file = std::fs::File::open(path).map_err(|e| format!("cannot open: {e}"))?;
    let mut reader = std::io::BufReader::new(file);
    let (models, _) = tobj::load_obj_buf(&mut reader, &opts, |_| {
        Err(tobj::LoadError::MaterialParseError)
    })
    .map_err(|e| format!("not a valid OBJ file: {e}"))?;
    let mut vertices: Vec<Vec3<f64>> = Vec::new();
    let mut triangles: Vec<[u32; 3]> = Vec::new();
    let weld = models.len() > 1;
    let mut seen: HashMap<[u64; 3], u32> = HashMap::new();
    for m in &models {
        let mesh = &m.mesh;
        if mesh.positions.len() % 3 != 0 || mesh.indices.len() % 3 != 0 {
            return Err(format!(
                "object {:?}: malformed position or index arrays",
                m.name
            ));
        }
        let mut local = Vec::with_capacity(mesh.positions.len() / 3);
        for p in mesh.positions.chunks_exact(3) {
            let v = Vec3::new(p[0], p[1], p[2]);
            let id = if weld {
                let key = [p[0].to_bits(), p[1].to_bits(), p[2].to_bits()];
                *seen.entry(key).or_insert_with(|| {
                    vertices.push(v);
                    (vertices.len() - 1) as u32
                })
            } else {
                vertices.push(v);
                (vertices.len() - 1) as u32
            };
            local.push(id);
        }
        for t in mesh.indices.chunks_exact(3) {
            let mut tri = [0u32; 3];
            for c in 0..3 {
                tri[c] = *local.get(t[c] as usize).ok_or_else(|| {
                    format!("object {:?}: face index {} out of range", m.name, t[c])
                })?;
            }
            triangles.push(tri);
        }
        if vertices.len() > u32::MAX as usize / 2 {
            return Err("too many vertices".into());
        }
    }
    let mesh = TriangleMesh::new(vertices, triangles).map_err(|e| e.to_string())?;
    mesh.check_closed().map_err(|e| e.to_string())?;
    Ok(mesh)
}

type MeshCache = HashMap<PathBuf, Arc<TriangleMesh<f64>>>;

#[allow(clippy::too_many_arguments)]
fn mesh_spec(
    ctx: &Ctx,
    field: &str,
    base: &Path,
    cache: &mut MeshCache,
    path: Option<&String>,
    scale: Option<f64>,
    translate: Option<[f64; 3]>,
    fit: Option<RawBox>,
) -> Result<MeshSpec, SceneError> {
    let Some(path) = path else {
        return Err(ctx.invalid(
            format!("{field}.path"),
            "missing (required for kind = \"mesh\")",
        ));
    };
    let resolved = base.join(path);
    let raw = match cache.get(&resolved) {
        Some(m) => m.clone(),
        None => {
            let m = Arc::new(load_obj(&resolved).map_err(|reason| SceneError::Mesh {
                file: ctx.file.to_path_buf(),
                field: format!("{field}.path"),
                mesh: resolved.clone(),
                reason,
            })?);
            cache.insert(resolved.clone(), m.clone());
            m
        }
    };
    let (placement, s, t) = if let Some(fit) = fit {
        if scale.is_some() || translate.is_some() {
            return Err(ctx.invalid(
                format!("{field}.fit"),
                "give either fit or scale/translate, not both",
            ));
        }
        let b = ctx.check_box(&format!("{field}.fit"), &fit)?;
        let mb = raw.bounds();
        let (me, be) = (mb.extent(), b.extent());
        let mut s = f64::INFINITY;
        for a in 0..3 {
            if me[a] > 0.0 {
                s = s.min(be[a] / me[a]);
            }
        }
        if !(s.is_finite() && s > 0.0) {
            return Err(ctx.invalid(
                format!("{field}.fit"),
                "cannot fit the mesh into this box (degenerate mesh or box)",
            ));
        }
        let t = b.center() - mb.center() * s;
        (
            MeshPlacement::Fit {
                min: fit.min,
                max: fit.max,
            },
            s,
            t,
        )
    } else {
        let s = scale.unwrap_or(1.0);
        ctx.positive(&format!("{field}.scale"), s)?;
        let t = translate.unwrap_or([0.0; 3]);
        ctx.finite3(&format!("{field}.translate"), &t)?;
        (
            MeshPlacement::Transform {
                scale: s,
                translate: t,
            },
            s,
            v3(t),
        )
    };
    let placed = raw
        .transformed(s, t)
        .map_err(|e| ctx.invalid(format!("{field}.scale"), format!("placing the mesh: {e}")))?;
    Ok(MeshSpec {
        path: resolved,
        placement,
        mesh: Arc::new(placed),
    })
}

fn placement_field(field: &str, m: &MeshSpec) -> String {
    match m.placement {
        MeshPlacement::Fit { .. } => format!("{field}.fit"),
        MeshPlacement::Transform { .. } => format!("{field}.translate"),
    }
}

/// Rejects fields that do not belong to a kind.
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

fn require<T: Copy>(ctx: &Ctx, field: &str, kind: &str, v: Option<T>) -> Result<T, SceneError> {
    v.ok_or_else(|| ctx.invalid(field, format!("missing (required for kind = \"{kind}\")")))
}

// ---------------------------------------------------------------------------------------

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
        let ctx = Ctx {
            file: path,
            note: "",
        };
        let de = toml::Deserializer::parse(text).map_err(|e| SceneError::Syntax {
            file: path.to_path_buf(),
            field: "<document>".into(),
            reason: toml_reason(text, &e),
        })?;
        let raw: RawScene = serde_path_to_error::deserialize(de).map_err(|e| {
            let mut field = e.path().to_string();
            if field == "." || field.is_empty() {
                field.clear();
            }
            let reason = toml_reason(text, e.inner());
            // Unknown and missing fields: name the field itself.
            for prefix in ["unknown field `", "missing field `"] {
                if let Some(rest) = reason.strip_prefix(prefix) {
                    if let Some(end) = rest.find('`') {
                        let name = &rest[..end];
                        let already = field == name || field.ends_with(&format!(".{name}"));
                        field = if already {
                            field
                        } else if field.is_empty() {
                            name.to_string()
                        } else {
                            format!("{field}.{name}")
                        };
                    }
                }
            }
            if field.is_empty() {
                field = "<document>".into();
            }
            SceneError::Syntax {
                file: path.to_path_buf(),
                field,
                reason,
            }
        })?;
        let base = path.parent().unwrap_or(Path::new("")).to_path_buf();
        let scene = Self::from_raw(&ctx, raw, &base)?;
        scene.validate_particles(&ctx)?;
        if scene.quick_overrides.is_some() {
            let quick = scene.quick();
            quick.validate_particles(&Ctx {
                file: path,
                note: "with the [quick] overrides: ",
            })?;
        }
        Ok(scene)
    }

    #[allow(clippy::needless_range_loop)]
    fn from_raw(ctx: &Ctx, raw: RawScene, base: &Path) -> Result<Scene, SceneError> {
        if raw.name.is_empty()
            || !raw
                .name
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || "_-.".contains(c))
        {
            return Err(ctx.invalid(
                "name",
                format!(
                    "{:?}: must be non-empty and use only ASCII letters, digits, '_', '-' and '.'",
                    raw.name
                ),
            ));
        }
        let sim = &raw.simulation;
        ctx.positive("simulation.particle_spacing", sim.particle_spacing)?;
        ctx.positive("simulation.duration", sim.duration)?;
        ctx.positive("simulation.frame_dt", sim.frame_dt)?;
        let gravity = sim.gravity.unwrap_or([0.0, -9.81, 0.0]);
        ctx.finite3("simulation.gravity", &gravity)?;

        let rs = &raw.solver;
        if rs.substeps == 0 {
            return Err(ctx.invalid("solver.substeps", "must be >= 1, got 0"));
        }
        if rs.iterations == 0 {
            return Err(ctx.invalid("solver.iterations", "must be >= 1, got 0"));
        }
        let opt_pos = |name: &str, v: Option<f64>| -> Result<(), SceneError> {
            match v {
                Some(v) => ctx.positive(&format!("solver.{name}"), v),
                None => Ok(()),
            }
        };
        opt_pos("rest_density", rs.rest_density)?;
        opt_pos("relative_cfm", rs.relative_cfm)?;
        opt_pos("density_error_tolerance", rs.density_error_tolerance)?;
        opt_pos("mean_compression_tolerance", rs.mean_compression_tolerance)?;
        if let Some(k) = rs.min_iterations {
            if rs.mean_compression_tolerance.is_none() {
                return Err(ctx.invalid(
                    "solver.min_iterations",
                    "only applies with solver.mean_compression_tolerance",
                ));
            }
            if k == 0 || k > rs.iterations {
                return Err(ctx.invalid(
                    "solver.min_iterations",
                    format!(
                        "must be >= 1 and <= solver.iterations = {}, got {k}",
                        rs.iterations
                    ),
                ));
            }
        }
        if let Some(v) = rs.support_over_spacing {
            if !(v.is_finite() && v > 1.0) {
                return Err(ctx.invalid(
                    "solver.support_over_spacing",
                    format!("must be finite and > 1, got {v}"),
                ));
            }
        }
        for (name, v) in [
            ("scorr_k", rs.scorr_k),
            ("vorticity_epsilon", rs.vorticity_epsilon),
        ] {
            if let Some(v) = v {
                if !(v.is_finite() && v >= 0.0) {
                    return Err(ctx.invalid(
                        format!("solver.{name}"),
                        format!("must be finite and >= 0, got {v}"),
                    ));
                }
            }
        }
        if rs.scorr_n == Some(0) {
            return Err(ctx.invalid("solver.scorr_n", "must be >= 1, got 0"));
        }
        if let Some(v) = rs.scorr_delta_q {
            if !(v.is_finite() && v > 0.0 && v < 1.0) {
                return Err(ctx.invalid(
                    "solver.scorr_delta_q",
                    format!("must be in (0, 1), got {v}"),
                ));
            }
        }
        if let Some(v) = rs.xsph_c {
            if !(v.is_finite() && (0.0..=1.0).contains(&v)) {
                return Err(ctx.invalid("solver.xsph_c", format!("must be in [0, 1], got {v}")));
            }
        }
        // Fields of one solver kind, rejected for the other (in file-documentation order).
        let (other_kind, only_other): (&str, &[(&str, bool)]) = match rs.kind {
            SolverKind::Pbf => (
                "pcisph",
                &[
                    (
                        "clamp_negative_pressure",
                        rs.clamp_negative_pressure.is_some(),
                    ),
                    (
                        "density_error_tolerance",
                        rs.density_error_tolerance.is_some(),
                    ),
                ],
            ),
            SolverKind::Pcisph => (
                "pbf",
                &[
                    ("relative_cfm", rs.relative_cfm.is_some()),
                    ("scorr_k", rs.scorr_k.is_some()),
                    ("scorr_n", rs.scorr_n.is_some()),
                    ("scorr_delta_q", rs.scorr_delta_q.is_some()),
                    ("vorticity_epsilon", rs.vorticity_epsilon.is_some()),
                    (
                        "clamp_negative_constraint",
                        rs.clamp_negative_constraint.is_some(),
                    ),
                    (
                        "mean_compression_tolerance",
                        rs.mean_compression_tolerance.is_some(),
                    ),
                    ("min_iterations", rs.min_iterations.is_some()),
                ],
            ),
        };
        if let Some((name, _)) = only_other.iter().find(|(_, given)| *given) {
            return Err(ctx.invalid(
                format!("solver.{name}"),
                format!("only applies to kind = \"{other_kind}\""),
            ));
        }
        let solver = rs.clone();

        let tank = match &raw.tank {
            Some(t) => Some(ctx.check_box("tank", t)?),
            None => None,
        };

        let mut cache = MeshCache::new();
        let mut fluids = Vec::with_capacity(raw.fluid.len());
        for (i, f) in raw.fluid.iter().enumerate() {
            let field = format!("fluid[{i}]");
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
                    forbid(ctx, &field, "block", &present, &["min", "max"])?;
                    let b = RawBox {
                        min: require(ctx, &format!("{field}.min"), "block", f.min)?,
                        max: require(ctx, &format!("{field}.max"), "block", f.max)?,
                    };
                    ctx.check_box(&field, &b)?;
                    FluidSpec::Block {
                        min: b.min,
                        max: b.max,
                        velocity,
                    }
                }
                RawFluidKind::Mesh => {
                    forbid(
                        ctx,
                        &field,
                        "mesh",
                        &present,
                        &["path", "scale", "translate", "fit"],
                    )?;
                    let mesh = mesh_spec(
                        ctx,
                        &field,
                        base,
                        &mut cache,
                        f.path.as_ref(),
                        f.scale,
                        f.translate,
                        f.fit,
                    )?;
                    FluidSpec::Mesh { mesh, velocity }
                }
            };
            // Inside the tank (box level).
            if let Some(t) = &tank {
                let (b, bfield) = match &spec {
                    FluidSpec::Block { min, max, .. } => (
                        Aabb {
                            min: v3(*min),
                            max: v3(*max),
                        },
                        format!("{field}.max"),
                    ),
                    FluidSpec::Mesh { mesh, .. } => {
                        (mesh.mesh.bounds(), placement_field(&field, mesh))
                    }
                };
                let tol = 1e-9 * (t.extent().norm() + 1.0);
                for a in 0..3 {
                    if b.min[a] < t.min[a] - tol || b.max[a] > t.max[a] + tol {
                        return Err(ctx.invalid(
                            bfield,
                            format!(
                                "the fluid's box {} – {} is not inside the tank {} – {} (axis {})",
                                fmt3(&b.min),
                                fmt3(&b.max),
                                fmt3(&t.min),
                                fmt3(&t.max),
                                AXES[a]
                            ),
                        ));
                    }
                }
            }
            fluids.push(spec);
        }

        let mut solids = Vec::with_capacity(raw.solid.len());
        for (i, s) in raw.solid.iter().enumerate() {
            let field = format!("solid[{i}]");
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
            let spec = match s.kind {
                RawSolidKind::Sphere => {
                    forbid(ctx, &field, "sphere", &present, &["center", "radius"])?;
                    let center = require(ctx, &format!("{field}.center"), "sphere", s.center)?;
                    ctx.finite3(&format!("{field}.center"), &center)?;
                    let radius = require(ctx, &format!("{field}.radius"), "sphere", s.radius)?;
                    ctx.positive(&format!("{field}.radius"), radius)?;
                    SolidSpec::Sphere { center, radius }
                }
                RawSolidKind::Box => {
                    forbid(ctx, &field, "box", &present, &["min", "max"])?;
                    let b = RawBox {
                        min: require(ctx, &format!("{field}.min"), "box", s.min)?,
                        max: require(ctx, &format!("{field}.max"), "box", s.max)?,
                    };
                    ctx.check_box(&field, &b)?;
                    SolidSpec::Box {
                        min: b.min,
                        max: b.max,
                    }
                }
                RawSolidKind::Plane => {
                    forbid(ctx, &field, "plane", &present, &["point", "normal"])?;
                    let point = require(ctx, &format!("{field}.point"), "plane", s.point)?;
                    ctx.finite3(&format!("{field}.point"), &point)?;
                    let normal = require(ctx, &format!("{field}.normal"), "plane", s.normal)?;
                    ctx.finite3(&format!("{field}.normal"), &normal)?;
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
                    forbid(
                        ctx,
                        &field,
                        "mesh",
                        &present,
                        &["path", "scale", "translate", "fit", "sdf_cell"],
                    )?;
                    if let Some(c) = s.sdf_cell {
                        ctx.positive(&format!("{field}.sdf_cell"), c)?;
                    }
                    let mesh = mesh_spec(
                        ctx,
                        &field,
                        base,
                        &mut cache,
                        s.path.as_ref(),
                        s.scale,
                        s.translate,
                        s.fit,
                    )?;
                    SolidSpec::Mesh {
                        mesh,
                        sdf_cell: s.sdf_cell,
                    }
                }
            };
            solids.push(spec);
        }

        let output = OutputSpec {
            every_frames: raw
                .output
                .as_ref()
                .and_then(|o| o.every_frames)
                .unwrap_or(1),
            vtk: raw.output.as_ref().and_then(|o| o.vtk).unwrap_or(true),
        };
        if output.every_frames == 0 {
            return Err(ctx.invalid("output.every_frames", "must be >= 1, got 0"));
        }

        let quick_overrides = match &raw.quick {
            None => None,
            Some(q) => {
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
                if let (Some(k), Some(min)) = (q.iterations, solver.min_iterations) {
                    if k < min {
                        return Err(ctx.invalid(
                            "quick.iterations",
                            format!("must be >= solver.min_iterations = {min}, got {k}"),
                        ));
                    }
                }
                Some(QuickSpec {
                    particle_spacing: q.particle_spacing,
                    duration_s: q.duration,
                    frame_dt_s: q.frame_dt,
                    substeps: q.substeps,
                    iterations: q.iterations,
                    every_frames: q.every_frames,
                })
            }
        };

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
            output,
            quick_overrides,
        })
    }

    /// The scene with the `[quick]` overrides applied (and `quick_overrides` cleared); a
    /// copy of `self` when there are none. Meshes are shared, not reloaded.
    pub fn quick(&self) -> Scene {
        let mut s = self.clone();
        if let Some(q) = s.quick_overrides.take() {
            if let Some(v) = q.particle_spacing {
                s.particle_spacing = v;
            }
            if let Some(v) = q.duration_s {
                s.duration_s = v;
            }
            if let Some(v) = q.frame_dt_s {
                s.frame_dt_s = v;
            }
            if let Some(v) = q.substeps {
                s.solver.substeps = v;
            }
            if let Some(v) = q.iterations {
                s.solver.iterations = v;
            }
            if let Some(v) = q.every_frames {
                s.output.every_frames = v;
            }
        }
        s
    }

    /// Number of frames: `ceil(duration / frame_dt)` (at least 1).
    pub fn frame_count(&self) -> usize {
        let n = (self.duration_s / self.frame_dt_s - 1e-9).ceil();
        if n.is_finite() && n >= 1.0 {
            n.min(usize::MAX as f64 / 2.0) as usize
        } else {
            1
        }
    }

    /// Initial fluid particle positions (m), fluid by fluid in file order (see the crate
    /// documentation for the sampling rules).
    pub fn fluid_positions<R: Real>(&self) -> Result<Vec<Vec3<R>>, SceneError> {
        let ctx = Ctx {
            file: &self.source,
            note: "",
        };
        let mut out = Vec::new();
        for i in 0..self.fluids.len() {
            out.extend(self.sample_fluid(&ctx, i)?.iter().map(cast3::<R>));
        }
        Ok(out)
    }

    /// Initial velocities (m/s), one per particle of [`Scene::fluid_positions`] (same order).
    pub fn fluid_velocities<R: Real>(&self) -> Result<Vec<Vec3<R>>, SceneError> {
        let ctx = Ctx {
            file: &self.source,
            note: "",
        };
        let mut out = Vec::new();
        for (i, f) in self.fluids.iter().enumerate() {
            let v = match f {
                FluidSpec::Block { velocity, .. } | FluidSpec::Mesh { velocity, .. } => {
                    cast3::<R>(&v3(*velocity))
                }
            };
            let n = self.sample_fluid(&ctx, i)?.len();
            out.extend(std::iter::repeat_n(v, n));
        }
        Ok(out)
    }

    /// Upper bound of the particle count of fluid `i` (lattice points over its box).
    fn lattice_estimate(&self, i: usize) -> f64 {
        let s = self.particle_spacing;
        let b = match &self.fluids[i] {
            FluidSpec::Block { min, max, .. } => Aabb {
                min: v3(*min),
                max: v3(*max),
            },
            FluidSpec::Mesh { mesh, .. } => mesh.mesh.bounds(),
        };
        let e = b.extent();
        (0..3)
            .map(|a| ((e[a] / s) + 1e-9).floor().max(1.0))
            .product()
    }

    fn sample_fluid(&self, ctx: &Ctx, i: usize) -> Result<Vec<Vec3<f64>>, SceneError> {
        let s = self.particle_spacing;
        let field = format!("fluid[{i}]");
        let lattice_err = |e: sph_core::CoreError| {
            ctx.invalid(
                field.clone(),
                format!("sampling at particle_spacing {s} m: {e}"),
            )
        };
        match &self.fluids[i] {
            FluidSpec::Block { min, max, .. } => {
                let b = Aabb {
                    min: v3(*min),
                    max: v3(*max),
                };
                cubic_lattice(&b, s, MAX_PARTICLES).map_err(lattice_err)
            }
            FluidSpec::Mesh { mesh, .. } => {
                let b = mesh.mesh.bounds();
                let grid = build_grid(ctx, &field, &mesh.mesh, s, 2.0 * s)?;
                let pts = cubic_lattice(&b, s, MAX_PARTICLES).map_err(lattice_err)?;
                Ok(pts
                    .into_iter()
                    .filter(|p| grid.signed_distance(p) < 0.0)
                    .collect())
            }
        }
    }

    fn solid_sdf<R: Real>(&self, ctx: &Ctx, j: usize) -> Result<Box<dyn Sdf<R>>, SceneError> {
        let field = format!("solid[{j}]");
        let core = |sub: &str, e: sph_core::CoreError| {
            ctx.invalid(format!("{field}.{sub}"), format!("in {}: {e}", R::NAME))
        };
        Ok(match &self.solids[j] {
            SolidSpec::Sphere { center, radius } => Box::new(
                Sphere::new(cast3::<R>(&v3(*center)), R::of_f64(*radius))
                    .map_err(|e| core("radius", e))?,
            ),
            SolidSpec::Box { min, max } => {
                let b = Aabb::new(cast3::<R>(&v3(*min)), cast3::<R>(&v3(*max)))
                    .map_err(|e| core("min", e))?;
                Box::new(BoxSdf::new(b).map_err(|e| core("min", e))?)
            }
            SolidSpec::Plane { point, normal } => Box::new(
                Plane::new(cast3::<R>(&v3(*point)), cast3::<R>(&v3(*normal)))
                    .map_err(|e| core("normal", e))?,
            ),
            SolidSpec::Mesh { mesh, sdf_cell } => {
                let cell = sdf_cell.unwrap_or(self.particle_spacing * 0.5);
                let m = &mesh.mesh;
                let verts: Vec<Vec3<R>> = m.vertices().iter().map(cast3::<R>).collect();
                let mr = TriangleMesh::new(verts, m.triangles().to_vec()).map_err(|e| {
                    ctx.invalid(format!("{field}.path"), format!("in {}: {e}", R::NAME))
                })?;
                let margin = 2.0 * self.particle_spacing + 2.0 * cell;
                Box::new(build_grid(ctx, &field, &mr, cell, margin)?)
            }
        })
    }

    /// The boundary signed distance fields in precision `R`: the tank first (as
    /// `Inverted<BoxSdf>`, when there is one), then the solids in file order (meshes as
    /// [`GridSdf`] with cell `sdf_cell`, default `particle_spacing / 2`, and margin
    /// `2 · particle_spacing + 2 · cell`). Errors only when a value does not fit in `R`
    /// (e.g. a box too thin for `f32`).
    pub fn build_solids<R: Real>(&self) -> Result<Vec<Box<dyn Sdf<R>>>, SceneError> {
        let ctx = Ctx {
            file: &self.source,
            note: "",
        };
        let mut out: Vec<Box<dyn Sdf<R>>> = Vec::with_capacity(self.solids.len() + 1);
        if let Some(t) = &self.tank {
            let b = Aabb::new(cast3::<R>(&t.min), cast3::<R>(&t.max))
                .and_then(BoxSdf::new)
                .map_err(|e| ctx.invalid("tank.min", format!("in {}: {e}", R::NAME)))?;
            out.push(Box::new(Inverted(b)));
        }
        for j in 0..self.solids.len() {
            out.push(self.solid_sdf::<R>(&ctx, j)?);
        }
        Ok(out)
    }

    /// Particle-level checks: count limit, non-empty fluids, inside the tank, outside solids.
    fn validate_particles(&self, ctx: &Ctx) -> Result<(), SceneError> {
        let mut total = 0.0;
        for i in 0..self.fluids.len() {
            total += self.lattice_estimate(i);
            if !(total <= MAX_PARTICLES as f64) {
                return Err(ctx.invalid(
                    format!("fluid[{i}]"),
                    format!(
                        "the fluids up to this one need about {total:.3e} particles at particle_spacing {} m, more than the maximum of {MAX_PARTICLES}",
                        self.particle_spacing
                    ),
                ));
            }
        }
        let solids: Vec<Box<dyn Sdf<f64>>> = (0..self.solids.len())
            .map(|j| self.solid_sdf::<f64>(ctx, j))
            .collect::<Result<_, _>>()?;
        for i in 0..self.fluids.len() {
            let pts = self.sample_fluid(ctx, i)?;
            let field = format!("fluid[{i}]");
            if pts.is_empty() {
                return Err(ctx.invalid(
                    field,
                    format!(
                        "contains no particle at particle_spacing {} m (smaller than a spacing?)",
                        self.particle_spacing
                    ),
                ));
            }
            if let Some(t) = &self.tank {
                if let Some(p) = pts
                    .iter()
                    .find(|p| !(0..3).all(|a| p[a] > t.min[a] && p[a] < t.max[a]))
                {
                    return Err(ctx.invalid(
                        field,
                        format!("particle at {} is not strictly inside the tank", fmt3(p)),
                    ));
                }
            }
            for (j, sdf) in solids.iter().enumerate() {
                if let Some(p) = pts.iter().find(|p| !(sdf.signed_distance(p) > 0.0)) {
                    return Err(ctx.invalid(
                        field,
                        format!(
                            "overlaps solid[{j}]: particle at {} has signed distance {:.6} m to it (fluids must lie outside solids)",
                            fmt3(p),
                            sdf.signed_distance(p)
                        ),
                    ));
                }
            }
        }
        Ok(())
    }
}

/// A [`GridSdf`] for a scene mesh, with the node count checked against [`MAX_SDF_NODES`]
/// first.
fn build_grid<R: Real>(
    ctx: &Ctx,
    field: &str,
    mesh: &TriangleMesh<R>,
    cell: f64,
    margin: f64,
) -> Result<GridSdf<R>, SceneError> {
    let e = mesh.bounds().extent();
    let nodes: f64 = (0..3)
        .map(|a| ((e[a].as_f64() + 2.0 * margin) / cell).ceil() + 1.0)
        .product();
    if !(nodes <= MAX_SDF_NODES as f64) {
        return Err(ctx.invalid(
            field,
            format!(
                "the mesh's signed distance grid at cell {cell} m would have {nodes:.3e} nodes, more than the maximum of {MAX_SDF_NODES} (use a larger sdf_cell/particle_spacing or a smaller mesh)"
            ),
        ));
    }
    GridSdf::new(mesh, R::of_f64(cell), R::of_f64(margin))
        .map_err(|e| ctx.invalid(field, format!("building the signed distance grid: {e}")))
}
