//! The public, validated scene types: [`Scene`] and its parts (the `[solver]` table is in
//! `solver_spec.rs`, parsing in `parse.rs`, the value checks in `check.rs`, particle
//! sampling and solid building in `build.rs`).

use std::path::PathBuf;
use std::sync::Arc;

use serde::Deserialize;
use sph_core::{Aabb, TriangleMesh};
use sph_solver::scene_boundary::PeriodicSetting;
use ssfr_render::RenderConfig;

pub use sph_solver::WallModel;

use crate::error::FieldLines;
use crate::sample_cache::FluidSampleCache;
use crate::SolverSpec;

/// Floating-point precision the solver should run in.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Precision {
    /// `f32`.
    F32,
    /// `f64`.
    F64,
}

/// How the solver treats the tank and the solids (the `[boundary]` table's `model`).
///
/// The default, used when `[boundary]` or its `model` is absent, is the variant marked
/// `#[default]` below ([`BoundaryModel::VolumeMap`]); change it there.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum BoundaryModel {
    /// Boundary volume maps: the solids contribute to the fluid's density and pressure
    /// through their volume within the support radius (`model = "volume-map"`).
    #[default]
    VolumeMap,
    /// Collision handling only: particles entering a solid are projected back to its
    /// surface (`model = "collision"`).
    Collision,
    /// Walls of fixed boundary particles (`model = "particles"`; the elastoplastic solver's,
    /// which requires it): the lattice nodes inside the tank's walls and the solids within
    /// three spacings of their surfaces, each with its solid's `wall` model; the solids
    /// also keep particles out as `collision` does, at a quarter spacing from their surfaces
    /// (the volume maps' contact distance) rather than half: the boundary particles carry
    /// the wall, the contact only catches a particle that would pass through it.
    Particles,
}

/// Boundary settings: the `[boundary]` table (optional; [`BoundarySpec::default`] when
/// absent).
#[derive(Debug, Clone, PartialEq, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BoundarySpec {
    /// The boundary model (default [`BoundaryModel::default`]).
    #[serde(default)]
    pub model: BoundaryModel,
    /// The periodic axes (`periodic = [{ axis = "z", lo = 0.0, hi = 0.03 }]`, m; default
    /// none): the medium repeats along each with period `hi − lo`, for a solver that takes
    /// them (`sph_solver::scene_boundary::BoundaryFeatures::periodic`). With a tank the
    /// period is the tank's extent along the axis, and the tank is open along it.
    #[serde(default)]
    pub periodic: Vec<PeriodicSetting>,
    /// The fluid's initial masses with respect to the density the solver sees at the start,
    /// the lattice's plus the boundary's (`initial_masses`; default
    /// [`InitialMasses::Lattice`]).
    #[serde(default)]
    pub initial_masses: InitialMasses,
}

/// The fluid's initial particle masses (the `[boundary]` table's `initial_masses`).
///
/// With volume-map walls a lattice of masses `ρ0 s³` starts compressed next to the walls
/// (its first layer, half a spacing from a wall, sees the wall's share `ρ0 Ψ` on top of the
/// lattice's: `ρ/ρ0` ≈ 1.038 at a wall, 1.075 in a corner for the cubic spline at `h = 2 s`),
/// and a unilateral pressure solver releases that compression as a jet along the walls in
/// its first steps. [`InitialMasses::Calibrated`] lowers the masses of those particles until
/// none starts above `ρ0` (`sph_solver::initial::calibrate_masses`); positions are not moved.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum InitialMasses {
    /// Every particle `ρ0 s³` (`initial_masses = "lattice"`, the default): the lattice's mass
    /// per cell, whatever the walls add.
    #[default]
    Lattice,
    /// `ρ0 s³`, lowered where the lattice plus the boundary would start above `ρ0`, so that
    /// no particle does (`initial_masses = "calibrated"`).
    Calibrated,
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
    /// A solid cylinder with a vertical axis (along `y`): the points within `radius` of the
    /// axis through `base_center`, from `base_center[1]` up to `base_center[1] + height`.
    Cylinder {
        /// Centre of the base disc (m).
        base_center: [f64; 3],
        /// Radius (m, > 0).
        radius: f64,
        /// Height (m, > 0).
        height: f64,
        /// Initial velocity (m/s).
        velocity: [f64; 3],
    },
}

impl FluidSpec {
    /// The initial velocity (m/s).
    pub fn velocity(&self) -> [f64; 3] {
        match self {
            FluidSpec::Block { velocity, .. }
            | FluidSpec::Mesh { velocity, .. }
            | FluidSpec::Cylinder { velocity, .. } => *velocity,
        }
    }

    /// The axis-aligned bounding box of the fluid's region (m).
    pub fn bounds(&self) -> Aabb<f64> {
        match self {
            FluidSpec::Block { min, max, .. } => Aabb {
                min: (*min).into(),
                max: (*max).into(),
            },
            FluidSpec::Mesh { mesh, .. } => mesh.mesh.bounds(),
            FluidSpec::Cylinder {
                base_center: c,
                radius: r,
                height: h,
                ..
            } => Aabb {
                min: [c[0] - r, c[1], c[2] - r].into(),
                max: [c[0] + r, c[1] + h, c[2] + r].into(),
            },
        }
    }
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
    /// The inside of a closed mesh, as a [`sph_core::GridSdf`].
    Mesh {
        /// The mesh.
        mesh: MeshSpec,
        /// Grid spacing (m) of its signed distance field; `None` = `particle_spacing / 2`.
        sdf_cell: Option<f64>,
    },
    /// A solid cylinder with a vertical axis (along `y`), as a [`sph_core::CylinderSdf`].
    Cylinder {
        /// Centre of the base disc (m).
        base_center: [f64; 3],
        /// Radius (m, > 0).
        radius: f64,
        /// Height (m, > 0).
        height: f64,
    },
}

impl SolidSpec {
    /// A solid cylinder's top disc: its centre (m) and radius (m); `None` for other solids.
    /// A heap poured on a cylinder (a pedestal) stands on this disc.
    pub fn cylinder_top(&self) -> Option<([f64; 3], f64)> {
        match *self {
            SolidSpec::Cylinder {
                base_center: c,
                radius,
                height,
            } => Some(([c[0], c[1] + height, c[2]], radius)),
            _ => None,
        }
    }
}

/// A solid's motion (`[[solid]] motion = { velocity = [0.0, -0.05, 0.0], duration = 12.0 }`):
/// it moves at `velocity` from the run's start for `duration` seconds, then stands still.
/// Only a box moves, and only as a wall of boundary particles (`[boundary] model =
/// "particles"`, the elastoplastic solver's: a [`sph_solver::MovingWall`]); a
/// moving solid is not one of the boundary's solids ([`Scene::build_solids`]), so nothing
/// but its particles keeps the grains out of it.
#[derive(Debug, Clone, Copy, PartialEq, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SolidMotion {
    /// Velocity while it moves (m/s).
    pub velocity: [f64; 3],
    /// How long it moves from the start (s, > 0).
    #[serde(rename = "duration")]
    pub duration_s: f64,
}

/// A pour (`[pour]`): grains added during the run a layer at a time, where the heap under
/// the box grows (the funnel method of forming a heap; the elastoplastic solver's
/// [`sph_solver::Pour`]; the solver says where each layer goes and when). The
/// volume is bulk volume (grains × spacing³), so a pour is the same at every spacing.
#[derive(Debug, Clone, Copy, PartialEq, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PourSpec {
    /// The funnel's box (m): its lower corner.
    pub min: [f64; 3],
    /// Its upper corner (m): the heap must stay below its top.
    pub max: [f64; 3],
    /// The bulk volume poured (m³).
    #[serde(rename = "volume")]
    pub volume_m3: f64,
    /// The rate (m³ of bulk volume per second).
    #[serde(rename = "rate")]
    pub rate_m3_s: f64,
    /// The seed of the layers' random shifts ([`sph_solver::Pour::seed`]; absent: alternate
    /// layers shifted a quarter spacing either way): pours of different seeds are an
    /// ensemble.
    #[serde(default)]
    pub seed: Option<u64>,
}

impl PourSpec {
    /// The solver's pour ([`sph_solver::Pour`]) this table describes.
    pub fn to_pour(&self) -> sph_solver::Pour<f64> {
        sph_solver::Pour {
            region: Aabb {
                min: crate::geom::v3(self.min),
                max: crate::geom::v3(self.max),
            },
            volume_m3: self.volume_m3,
            rate_m3_s: self.rate_m3_s,
            seed: self.seed,
        }
    }
}

/// The wall model of the tank and of each solid as written (`wall = "free-slip"`,
/// `"no-slip"` or `{ coulomb = μ_w }`; absent = [`SceneWalls::DEFAULT`]). Only walls of
/// boundary particles (`[boundary] model = "particles"`) have models.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SceneWalls {
    /// The tank's (`[tank] wall`).
    pub tank: Option<WallModel>,
    /// Each solid's (`[[solid]] wall`), in file order.
    pub solids: Vec<Option<WallModel>>,
}

impl SceneWalls {
    /// The model of a wall that does not say: no-slip (Bui et al. 2008's rows of fixed
    /// boundary particles).
    pub const DEFAULT: WallModel = WallModel::NoSlip;

    /// Whether any wall states a model.
    pub fn any_given(&self) -> bool {
        self.tank.is_some() || self.solids.iter().any(Option::is_some)
    }
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
    /// Three dimensions, or the plane `z = 0` (`[simulation] dimensions = 2`): the scene's
    /// section there. In the plane the fluid blocks fill the one lattice layer at `z = 0`,
    /// the tank and the pour's box are open along `z` (their `z` extents are not read), the
    /// pour's `volume` and `rate` are per metre of depth (m³/m, m³/s per m), each particle
    /// stands for a slab one spacing deep, and only solvers that run in the plane take it
    /// ([`sph_solver::SolverSettings::PLANAR`]).
    pub dimensions: sph_solver::Dimensions,
    /// The container, if any.
    pub tank: Option<Aabb<f64>>,
    /// Fluid bodies, in file order.
    pub fluids: Vec<FluidSpec>,
    /// Solid obstacles, in file order.
    pub solids: Vec<SolidSpec>,
    /// The wall model of the tank and of each solid (`wall` of `[tank]` and of each
    /// `[[solid]]`), for boundary particles.
    pub walls: SceneWalls,
    /// Each solid's motion (`[[solid]] motion`), in file order; `None`: it stands still.
    pub motions: Vec<Option<SolidMotion>>,
    /// Grains poured during the run (`[pour]`), if any.
    pub pour: Option<PourSpec>,
    /// Solver settings.
    pub solver: SolverSpec,
    /// Boundary settings.
    pub boundary: BoundarySpec,
    /// Output settings.
    pub output: OutputSpec,
    /// The `[quick]` overrides (`None` when absent, and in the scene returned by
    /// [`Scene::quick`]).
    pub quick_overrides: Option<QuickSpec>,
    /// The `[render]` table (`None` when absent): camera, light and background of the
    /// screen-space renderer, checked against the scene when it is loaded (see
    /// [`Scene::render_params`]).
    pub render: Option<RenderConfig>,
    /// The line of each field path in the scene file, for the messages of [`Scene::check`].
    pub(crate) lines: Arc<FieldLines>,
    /// The fluid sample of the last particle check, for the set-up that follows.
    pub(crate) fluid_samples: FluidSampleCache,
}

impl Scene {
    /// The periodic axes (`[boundary] periodic`) as `(axis, lo, hi)` (0 = x, 1 = y, 2 = z;
    /// m): the tank is open along them.
    pub fn periodic_axes(&self) -> Vec<(usize, f64, f64)> {
        self.boundary
            .periodic
            .iter()
            .map(|p| (p.axis.index(), p.lo, p.hi))
            .collect()
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
                s.solver.common_mut().substeps = v;
            }
            if let Some(v) = q.iterations {
                s.solver.set_iterations(v);
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
}
