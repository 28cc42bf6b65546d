//! Scene files (TOML) shared by the workspace's particle solvers (PBF, PCISPH; later an IISPH
//! granular solver): fluid blocks and meshes, the tank, solid obstacles, solver parameters,
//! duration and output.
//!
//! [`Scene::load`] reads and validates a file; [`Scene::fluid_positions`] samples the initial
//! particles and [`Scene::build_solids`] builds the boundary signed distance fields (the tank
//! first, as `Inverted<BoxSdf>`, then the solids in file order, meshes as
//! [`GridSdf`](sph_core::GridSdf), the PBF paper's "signed distance fields stored as volume
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
//! [solver]                         # one table per solver, selected by `kind`; the fields of
//!                                  # another solver are refused (unknown field)
//! kind = "pbf"                     # "pbf" | "pcisph"
//! substeps = 4                     # solver steps per frame (>= 1)
//! iterations = 3                   # PBF: constraint iterations per step; PCISPH: max
//!                                  # pressure iterations per step (>= 1)
//! # Optional overrides (the solver's defaults otherwise), both solvers:
//! # rest_density = 1000.0          # kg/m³ (> 0)
//! # support_over_spacing = 2.0     # h / particle_spacing (> 1)
//! # xsph_c = 0.01                  # XSPH viscosity c, in [0, 1]
//! # reorder_every = 10             # frames between particle reorderings (0 = never)
//! # kind = "pbf" only:
//! # relative_cfm = 1.0             # CFM ε relative to the full-lattice denominator (> 0)
//! # scorr_k = 0.1                  # artificial pressure k (>= 0)
//! # scorr_n = 4                    # artificial pressure exponent (>= 1)
//! # scorr_delta_q = 0.2            # |Δq| / h, in (0, 1)
//! # vorticity_epsilon = 0.0        # vorticity confinement ε, m/s (>= 0)
//! # clamp_negative_constraint = false # unilateral C = max(ρ/ρ0 − 1, 0)
//! # mean_compression_tolerance = 0.001 # stop iterating at this mean compression (> 0);
//! #                                # `iterations` is then the maximum
//! # min_iterations = 2             # with mean_compression_tolerance (>= 1, <= iterations)
//! # kind = "pcisph" only:
//! # clamp_negative_pressure = true
//! # density_error_tolerance = 0.01 # relative density error to stop at (> 0)
//!
//! [boundary]                       # optional
//! model = "volume-map"             # "volume-map" | "collision" (default: BoundaryModel's
//!                                  # Default, "volume-map")
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
//! [render]                         # optional: camera, light, background of the
//!                                  # screen-space renderer (`cargo xtask render`); kept as
//!                                  # a raw table here and checked by the `ssfr-render` crate
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
//!   [`GridSdf`](sph_core::GridSdf) with cell = `particle_spacing` (only its sign matters).
//! * Meshes must be closed
//!   ([`TriangleMesh::check_closed`](sph_core::TriangleMesh::check_closed)); OBJ files are
//!   loaded with `tobj` (polygons triangulated; vertices of several objects welded by exact
//!   position).
//! * After parsing, every value is checked: spacing, durations, radii and cells finite and
//!   positive, every number finite, `min < max`, substeps/iterations ≥ 1, fluids inside the tank
//!   (block or mesh bounds inside the tank box, every particle strictly inside it), no fluid
//!   particle inside (or on) a solid, at most [`MAX_PARTICLES`] particles, mesh files that
//!   exist and are closed. The scene with its `[quick]` overrides is validated too, so
//!   [`Scene::quick`] cannot fail.
//! * Every [`SceneError`] names the scene file, the field path (`fluid[1].min`,
//!   `solver.substeps`, …) and the reason, with the line and column for errors found while
//!   reading the TOML (syntax, types, unknown or missing fields). The library does not panic
//!   on any input.
//!
//! # Modules
//!
//! The public types are in `spec.rs` ([`Scene`], [`SolverSpec`], …) and `error.rs`
//! ([`SceneError`]); `raw.rs` holds the serde input structs, `parse.rs` the validation from
//! them to a [`Scene`] (one function per section; `parse/solver.rs` for `[solver]`),
//! `mesh_io.rs` OBJ loading and mesh placement, `build.rs` particle sampling and the solids'
//! signed distance fields.

mod build;
mod error;
mod mesh_io;
mod parse;
mod raw;
mod spec;

use sph_core::{Real, Vec3};

pub use error::SceneError;
pub use spec::{
    BoundaryModel, BoundarySpec, FluidSpec, MeshPlacement, MeshSpec, OutputSpec, PbfSpec,
    PcisphSpec, Precision, QuickSpec, Scene, SolidSpec, SolverKind, SolverSpec,
};

/// Largest total number of fluid particles a scene may produce (20 M).
pub const MAX_PARTICLES: usize = 20_000_000;

/// Largest number of nodes of a signed distance grid built for a mesh (16 M).
pub const MAX_SDF_NODES: usize = 16 << 20;

/// Axis names, for messages.
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
