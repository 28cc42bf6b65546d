#![doc = include_str!("../README.md")]
//!
//! ## In detail
//!
//! Scene files (TOML) shared by the workspace's particle solvers (PBF, PCISPH, and IISPH for
//! water and granular matter): fluid blocks and meshes, the tank, solid obstacles, solver
//! and boundary parameters, duration, output and rendering.
//!
//! [`Scene::load`] reads a file and checks it ([`Scene::check`], which a program that edits
//! a scene's fields calls again); [`Scene::fluid_particles`] samples the initial particles
//! (positions and velocities from one sampling) and [`Scene::build_solids`] builds the
//! boundary signed distance fields (the tank first, as `Inverted<BoxSdf>`, then the solids
//! in file order, meshes as [`GridSdf`](sph_core::GridSdf), the PBF paper's "signed distance
//! fields stored as volume textures" after Bridson et al. 2006 / SDFGen).
//! [`Scene::solver_params`] makes the solver's parameters ([`SolverParams`]);
//! [`Scene::render_info`] and [`Scene::render_params`] are the renderer's view of the scene.
//! [`Scene::quick`] applies the optional `[quick]` overrides used by `cargo xtask validate`
//! and `run --quick`.
//!
//! # Example: a scene run with the PBF solver
//!
//! The workspace's scene runner (`sph-sim`, `cargo xtask run SCENE`) maps every setting of
//! a scene to its solver; a program that lifts the crates can also do it by hand. Solvers
//! reorder the particles by cell every `reorder_every` frames (for memory locality), so a
//! particle's index in the state changes: `last_permutation()` says how after each call, and
//! composing it into an index map follows the scene's particles across the whole run.
//!
//! ```
//! use std::path::Path;
//! use pbf::{ParticleSet, Pbf, PbfParams, Vec3};
//! use sph_scene::Scene;
//!
//! let text = r#"
//! name = "small_dam"
//! [simulation]
//! particle_spacing = 0.05          # m
//! duration = 0.16                  # s: 10 frames
//! frame_dt = 0.016
//! [solver]
//! kind = "pbf"
//! substeps = 2
//! solver_iterations = 3
//! [tank]
//! min = [0.0, 0.0, 0.0]
//! max = [1.0, 0.6, 0.3]
//! [[fluid]]
//! kind = "block"
//! min = [0.0, 0.0, 0.0]
//! max = [0.3, 0.4, 0.3]
//! "#;
//! // Mesh paths would be relative to the file's directory; this scene has none.
//! let scene = Scene::parse_str(text, Path::new("small_dam.toml")).unwrap();
//! let fluid = scene.fluid_particles::<f64>().unwrap(); // sampled once
//! assert_eq!(fluid.positions.len(), 6 * 8 * 6);
//!
//! let mut params = PbfParams::<f64>::for_spacing(scene.particle_spacing);
//! params.common.dt = scene.frame_dt_s; // one `step` call = one frame ...
//! params.common.substeps = scene.solver.substeps(); // ... of this many solver steps
//! params.common.gravity = Vec3::from(scene.gravity);
//! params.common.reorder_every = 3;
//! params.solver_iterations = scene.solver.iterations();
//! let (m, rho0) = (params.particle_mass(), params.common.rest_density);
//! let mut state = ParticleSet::from_positions(fluid.positions, m, rho0);
//! state.velocities = fluid.velocities;
//! let mut solver = Pbf::new(params, scene.build_solids::<f64>().unwrap()).unwrap();
//!
//! // `ids[k]`: the scene's index of the particle stored at `k` now.
//! let mut ids: Vec<u32> = (0..state.len() as u32).collect();
//! for _ in 0..scene.frame_count() {
//!     solver.step(&mut state).unwrap(); // a whole frame of `substeps` steps
//!     if let Some(perm) = solver.last_permutation() {
//!         // The call began by moving the particle at `perm[k]` to `k`.
//!         ids = perm.iter().map(|&old| ids[old as usize]).collect();
//!     }
//! }
//! // The scene's particle 0 started in the block's lower corner, half a spacing above the
//! // floor; the block has slumped towards +x and it stays on the floor.
//! let k = ids.iter().position(|&id| id == 0).unwrap();
//! assert!(state.positions[k].y < 0.05, "{:?}", state.positions[k]);
//! assert_ne!(ids, (0..state.len() as u32).collect::<Vec<_>>(), "reordered");
//! ```
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
//! # dimensions = 2                 # 3 (default) or 2: the scene's section at z = 0, plane
//! #                                #   strain (kind = "elastoplastic" only): blocks fill
//! #                                #   their layer at z = 0, the tank and the pour are open
//! #                                #   along z, the pour's volume and rate are per metre of
//! #                                #   depth; no periodic z axis, no mesh or cylinder fluid
//!
//! [solver]                         # one table per solver, selected by `kind` (the solver
//!                                  # crate's settings struct: PbfSettings, PcisphSettings,
//!                                  # WaterSettings, GranularSettings); each key is the name
//!                                  # of the parameter it sets; the keys of another solver
//!                                  # are refused (unknown field)
//! kind = "pbf"                     # "pbf" | "pcisph" | "iisph" | "granular" | "elastoplastic"
//! substeps = 4                     # solver steps per frame (>= 1)
//! solver_iterations = 3            # PBF: constraint iterations per step (>= 1; formerly
//!                                  # `iterations`, still accepted)
//! # Optional overrides (the solver's defaults otherwise), every solver:
//! # rest_density = 1000.0          # kg/m³ (> 0)
//! # support_over_spacing = 2.0     # h / particle_spacing (> 1)
//! # reorder_every = 10             # frames between particle reorderings (0 = never)
//! # kind = "pbf" only:
//! # xsph_c = 0.01                  # XSPH viscosity c, in [0, 1]
//! # relative_cfm = 1.0             # CFM ε relative to the full-lattice denominator (> 0)
//! # scorr_k = 0.1                  # artificial pressure k (>= 0)
//! # scorr_n = 4                    # artificial pressure exponent (>= 1)
//! # scorr_delta_q = 0.2            # |Δq| / h, in (0, 1)
//! # vorticity_epsilon = 0.0        # vorticity confinement ε, m/s (>= 0)
//! # clamp_negative_constraint = false # unilateral C = max(ρ/ρ0 − 1, 0)
//! # mean_compression_tolerance = 0.001 # stop iterating at this mean compression (> 0);
//! #                                # `solver_iterations` is then the maximum
//! # min_solver_iterations = 2      # with mean_compression_tolerance (>= 1,
//! #                                # <= solver_iterations; formerly `min_iterations`)
//! # kind = "pcisph":
//! # pressure_iterations = 4        # max pressure iterations per step (>= 1, required;
//! #                                # formerly `iterations`, still accepted)
//! # xsph_c = 0.05                  # XSPH viscosity c, in [0, 1]
//! # clamp_negative_pressure = true
//! # density_error_tolerance = 0.01 # relative density error to stop at (> 0)
//! ```
//!
//! The IISPH kinds (crate `iisph-granular`) have no `solver_iterations` and no `xsph_c`:
//!
//! ```toml
//! [solver]
//! kind = "iisph"                   # water; "granular" adds the fields below
//! substeps = 8                     # solver steps per frame (>= 1, required)
//! # max_iterations = 100           # relaxed-Jacobi cap (>= min_iterations)
//! # min_iterations = 2             # (>= 1)
//! # density_error_tolerance = 0.001 # average relative compression to stop at (> 0)
//! # relaxation = 0.5               # Jacobi ω, in (0, 1]
//! # rest_density, support_over_spacing, reorder_every as above
//! # viscosity = 0.0                # kinematic viscosity ν of an explicit SPH viscosity
//! #                                # force, m²/s (>= 0)
//! # kind = "granular" only:
//! # friction_angle_deg = 30.0      # required, in [0, 90): the friction angle θ
//! # cone_match = "plane-strain"    # how the Drucker–Prager cone is matched to θ:
//! #                                # "plane-strain" (default, the thesis's eq. 14:
//! #                                # α = √2 sin θ, slopes rest at atan(sin θ)) or
//! #                                # "simple-shear" (α = √2 tan θ: slopes rest at θ)
//! # drag_coefficient = 0.0         # C_D of the air drag (>= 0; 0 = off)
//! # air_velocity = [0.0, 0.0, 0.0] # m/s, uniform
//! # upscaling_factor = 8           # passive points per particle (>= 1; absent = off)
//! # friction_max_iterations = 20   # friction-stress iterations per step at most (>= 1)
//! # friction_tolerance = 1e-4      # mean unyielded strain per step to stop at (> 0)
//! # friction_relaxation = 0.35     # ω of the stress update, in (0, 1] (0.35 = the stability
//! #                                # bound; the thesis's eq. 9 implies 0.5, outside it)
//! ```
//!
//! The elastic–plastic granular solver (crate `elastoplastic-granular`, Bui, Fukagawa, Sako
//! & Ohno 2008: a per-particle stress, elastic and capped by the Drucker–Prager cone matched
//! to Mohr–Coulomb; explicit steps sub-cycled inside each frame) requires
//! `[boundary] model = "particles"`; each key is a field of that crate's parameters,
//! defaults their `for_spacing`'s:
//!
//! ```toml
//! [solver]
//! kind = "elastoplastic"
//! substeps = 1                     # (>= 1; the explicit steps, Δt = C h / √(E/ρ0), are
//!                                  # sub-cycled inside each)
//! friction_angle_deg = 30.0        # required, in [0, 70]: φ (0 with cohesion 0: a
//!                                  # granular liquid, no shear stress and no tension)
//! # cone_match = "plane-strain-associated" # how φ, ψ, c fix the cone (ConeMatch):
//! #                                # "plane-strain-associated" (Bui 2008's), "plane-strain"
//! #                                # or "simple-shear" (a heap comes to rest at φ)
//! # youngs_modulus = 5.84e6        # Pa, E (> 0)
//! # poisson_ratio = 0.3            # ν, in [0, 0.49]
//! # dilatancy_angle_deg = 0.0      # ψ, in [0, φ]
//! # cohesion = 0.0                 # Pa, c (>= 0)
//! # viscosity_alpha = 0.1          # Monaghan's α_Π, in [0, 10]
//! # viscosity_beta = 0.0           # Monaghan's β_Π, in [0, 10]
//! # viscosity_speed_m_s = 2.0      # m/s: a fixed velocity scale for the viscosity's linear
//! #                                # term (absent: the speed of sound √(E/ρ0), which makes
//! #                                # the damping grow with E)
//! # artificial_stress_epsilon = 0.5 # Gray et al.'s ε, in [0, 1]
//! # artificial_stress_exponent = 2.55 # Gray et al.'s n, in [1, 10]
//! # cfl_number = 0.46              # C of Δt ≤ C h/c_p (c_p: P-wave speed), in (0, 1]
//! # skin = 0.003                   # m, neighbour-list skin, in [0, support radius]
//! #                                # (default 0.3 particle_spacing)
//! # initial_stress = "none"        # "none" | "geostatic" (σ_v = −ρ0 g depth along gravity,
//! #                                # K0 σ_v across it, K0 = ν/(1 − ν), per column)
//! # rest_density, support_over_spacing (default 2.4), reorder_every as above
//! ```
//!
//! ```toml
//! [boundary]                       # optional
//! model = "volume-map"             # "volume-map" | "collision" | "particles" (default:
//!                                  # BoundaryModel's Default, "volume-map"); "particles":
//!                                  # walls of fixed boundary particles, the elastoplastic
//!                                  # solver's (and required by it): the lattice nodes inside
//!                                  # the tank's walls and the solids within three spacings
//!                                  # of their surfaces (over the tank, or the fluids' box),
//!                                  # each with its solid's `wall` model
//! initial_masses = "lattice"       # "lattice" (default): every particle ρ0 s³;
//!                                  # "calibrated": those masses lowered where the lattice
//!                                  # plus the walls' share ρ0 Ψ would start above ρ0 (see
//!                                  # InitialMasses; positions are not moved)
//! # periodic = [{ axis = "z", lo = 0.0, hi = 0.03 }] # m: periodic axes, for a solver that
//! #                                # takes them (the elastoplastic one); with a tank, the
//! #                                # period is its extent along the axis and the tank is
//! #                                # open there
//!
//! [tank]                           # optional: the container, a closed box (particles inside)
//! min = [0.0, 0.0, 0.0]            # m
//! max = [1.6, 1.0, 0.6]            # m, > min on every axis
//! # wall = "no-slip"               # with model = "particles" only: "no-slip" (default),
//! #                                # "free-slip" or { coulomb = 0.4 } (wall friction
//! #                                # coefficient μ_w in [0, 10]); also on each [[solid]]
//!
//! [[fluid]]                        # any number of fluid bodies, sampled in file order
//! kind = "block"
//! min = [0.0, 0.0, 0.0]            # m
//! max = [0.5, 0.8, 0.6]            # m, > min on every axis
//! velocity = [0.0, 0.0, 0.0]       # m/s, initial velocity (default 0)
//!
//! [[fluid]]
//! kind = "mesh"                    # a closed triangle mesh (OBJ), filled with fluid
//! path = "meshes/bunny.obj"   # relative to this scene file
//! scale = 0.05                     # uniform scale applied first (default 1, > 0)
//! translate = [0.8, 0.4, 0.3]      # m, then this translation (default 0)
//! # or, instead of scale/translate:
//! # fit = { min = [0.6, 0.3, 0.1], max = [1.0, 0.8, 0.5] }
//! #   uniform scale making the mesh's bounding box as large as fits in the box (aspect
//! #   kept), centred in it
//! velocity = [0.0, -1.0, 0.0]      # m/s (default 0)
//!
//! # [[fluid]]
//! # kind = "cylinder"              # a vertical cylinder (axis along y), filled with fluid
//! # base_center = [0.3, 0.0, 0.3]  # m, centre of the base disc
//! # radius = 0.1                   # m, > 0
//! # height = 0.2                   # m, >= particle_spacing
//!
//! [[solid]]                        # obstacles, in file order after the tank
//! kind = "sphere"                  # center (m), radius (m, > 0)
//! center = [0.8, 0.2, 0.3]
//! radius = 0.1
//! # kind = "box":   min, max (m); with model = "particles" a box may move:
//! #   motion = { velocity = [0.0, -0.05, 0.0], duration = 12.0 }  # m/s, s (> 0): it
//! #   moves from the start for `duration`, then stands still (SolidMotion; a trapdoor)
//! # kind = "plane": point (m), normal (points into the free side, normalised)
//! # kind = "cylinder": base_center (m), radius (m, > 0), height (m, > 0): vertical axis
//! # kind = "mesh":  path, scale/translate or fit (as for fluids), sdf_cell (m, grid spacing of
//! #                 the signed distance field, default particle_spacing / 2)
//!
//! # [pour]                         # optional, solver kind = "elastoplastic" only: grains
//! #                                # poured during the run, a layer at a time, onto the
//! #                                # heap under a funnel that follows its top (PourSpec,
//! #                                # elastoplastic_granular::Pour; gravity along −y)
//! # min = [0.79, 0.0, 0.0]         # m: the funnel's box, inside the tank; each layer is a
//! # max = [0.81, 1.0, 0.06]        # grain per lattice node over its x–z face, at rest, one
//! #                                # spacing above the highest landed grain under it; the
//! #                                # heap must stay below max[1]
//! # volume = 0.0096                # m³ of bulk volume (grains × spacing³), > 0
//! # rate = 0.0007                  # m³/s, > 0; a run is at rest only after the last layer
//! # seed = 1                       # optional: each layer shifted by a seeded random
//! #                                # fraction of a spacing along x and z (an ensemble of
//! #                                # pours: seeds varied); absent: alternate layers ±s/4 in x
//!
//! [output]                         # optional
//! every_frames = 1                 # write a VTK frame every N frames (>= 1, default 1)
//! vtk = true                       # default true
//!
//! [render]                         # optional: camera, light, background of the
//!                                  # screen-space renderer (`cargo xtask render`): the
//!                                  # fields of `ssfr_render::RenderConfig`, resolved
//!                                  # against the scene when it is loaded
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
//! * Cylinders ([`FluidSpec::Cylinder`]) are filled with a cubic lattice centred on their
//!   axis (the axis through the corners of four lattice cells, the first layer half a
//!   spacing above the base, `⌊height/s⌋` layers), keeping the points whose distance to the
//!   axis is **< radius**: mirror-symmetric about the axis, with `N s³` approximating
//!   `π r² H` without bias.
//! * Meshes must be closed
//!   ([`TriangleMesh::check_closed`](sph_core::TriangleMesh::check_closed)). OBJ files are
//!   read by the crate's own reader (`v` and `f` statements; polygons split into a fan of
//!   triangles; vertices of several objects welded by exact position) so that every problem
//!   in a mesh file is reported with its line: a malformed number, a face index that does not
//!   exist, a file cut short before its faces, and the face an open edge belongs to.
//! * Files are read with a stated size limit: the scene file at most
//!   [`MAX_SCENE_FILE_BYTES`], a mesh file at most [`MAX_MESH_FILE_BYTES`], and only regular
//!   files (a named pipe, a device such as `/dev/zero` or a directory is refused by name
//!   before it is opened).
//! * After parsing, every value is checked ([`Scene::check`]): spacing, durations, radii and cells finite and
//!   positive, every number finite, `min < max`, substeps/iterations ≥ 1, fluids inside the tank
//!   (block or mesh bounds inside the tank box, every particle strictly inside it), blocks and cylinders at
//!   least one spacing thick, no fluid particle inside (or on) a solid, at most
//!   [`MAX_PARTICLES`] particles and [`MAX_PASSIVE_POINTS`] passive points of granular
//!   upscaling (`upscaling_factor` times the particles), mesh files that exist and are closed. The scene with its
//!   `[quick]` overrides is validated too, so [`Scene::quick`] cannot fail.
//! * The `[solver]` settings are range-checked once, by the solver's own checks of the
//!   parameters made from them (`validate` of `PbfParams`, `PcisphParams`, `IisphParams`),
//!   run on the parameters built in `f64` and again in the scene's precision after the
//!   conversion: a tolerance of `1e-300` is `0` in `f32` and refused at its field. A
//!   refused parameter is reported at the scene key it comes from (keys are the parameters'
//!   names, or the old name the file writes; `support_radius` is set as
//!   `support_over_spacing`, PBF's `cfm_epsilon` as `relative_cfm`), with its line. Only
//!   the checks that make sense on the file alone come before (e.g. `min_solver_iterations`
//!   only applies with `mean_compression_tolerance`).
//! * The `[render]` table is resolved against the scene (image size, camera, material), so
//!   that a scene the renderer would refuse is refused when it is loaded.
//! * Time stepping: at most [`sph_solver::MAX_SUBSTEPS`] substeps per frame and
//!   [`MAX_FRAMES`] frames, and a solver step of `Δt = frame_dt / substeps` must not carry a
//!   particle farther than the support radius `h`: `(|v0| + |g| Δt) Δt <= h` with `|v0|` the
//!   largest initial speed (the Courant–Friedrichs–Lewy condition at Courant number 1 with
//!   respect to `h`, as a refusal bound: beyond it the neighbours found once per step cannot
//!   see what a particle hits). The message gives the fewest substeps that pass and the
//!   longest frame with the current ones. `frame_dt = 1e30` is refused here instead of
//!   blowing up at the first step.
//! * Every [`SceneError`] names the scene file, the field path (`fluid[1].min`,
//!   `solver.substeps`, …) and the reason, with the line (and column) of the field in the
//!   scene file. Mesh errors name the OBJ file and its line (a malformed number, a face
//!   index that does not exist, a face with fewer than 3 corners, a file cut short before
//!   its faces, the face an open edge belongs to). The library does not panic on any input.
//! * [`Scene::load_with`] and [`Scene::parse_str_with`] apply [`Override`]s (a key by its
//!   dotted path, `solver.friction_angle_deg`, and its value) to the parsed document before
//!   serde reads it: an overridden value is checked as the file's would be, at the same
//!   field path, its messages saying "given as an override" where a file's value gives its
//!   line; an unknown key is refused with the keys its table has.
//!
//! # Modules
//!
//! The public types are in `spec.rs` ([`Scene`], [`FluidSpec`], …), `solver_spec.rs` (the
//! registry of solvers, one line each, and the [`SolverKind`], [`SolverSpec`] and
//! [`SolverParams`] that follow from it; the settings themselves are the solver crates') and
//! `error.rs` ([`SceneError`]); `raw.rs` holds the
//! serde input structs, `parse.rs` the reading from them to a [`Scene`] (`parse/solver.rs`
//! for `[solver]`), `check.rs` the value checks (`check/time_step.rs`),
//! `params.rs` the solver parameters (built once in `f64`, converted, checked), `render.rs` the renderer's view, `read.rs` the
//! size-limited file reading, `mesh_io.rs` OBJ loading and mesh placement, `overrides.rs` the overrides, `build.rs`
//! particle sampling and the solids' signed distance fields, `limits.rs` the bounds. No two
//! modules import each other.

mod build;
mod check;
mod error;
mod geom;
mod limits;
mod mesh_io;
mod obj;
mod override_span;
mod overrides;
mod params;
mod parse;
mod planar;
mod raw;
mod read;
mod render;
mod sample_cache;
mod solver_spec;
mod spec;

pub use build::{FluidParticles, OPEN_TANK_REACH};
pub use error::SceneError;
pub use limits::{
    MAX_FRAMES, MAX_MESH_FILE_BYTES, MAX_PARTICLES, MAX_PASSIVE_POINTS, MAX_SCENE_FILE_BYTES,
    MAX_SDF_NODES,
};
pub use overrides::Override;
// The settings of each solver, owned by its crate (the variants of `SolverSpec`).
pub use iisph_granular::IisphSettings;
pub use solver_spec::settings::*;
pub use solver_spec::{SolverKind, SolverParams, SolverSpec};
pub use spec::{
    BoundaryModel, BoundarySpec, FluidSpec, InitialMasses, MeshPlacement, MeshSpec, OutputSpec,
    PourSpec, Precision, QuickSpec, Scene, SceneWalls, SolidMotion, SolidSpec, WallModel,
};
pub use sph_solver::CommonSettings;
