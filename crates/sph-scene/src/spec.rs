//! The public, validated scene types: [`Scene`] and its parts (parsing is in `parse.rs`,
//! particle sampling and solid building in `build.rs`).

use std::path::PathBuf;
use std::sync::Arc;

use serde::Deserialize;
use sph_core::{Aabb, TriangleMesh};

/// Floating-point precision the solver should run in.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Precision {
    /// `f32`.
    F32,
    /// `f64`.
    F64,
}

/// Which solver a scene is meant for: the tag (`kind`) of the `[solver]` table, and
/// [`SolverSpec::kind`]. Kept next to [`SolverSpec`] so that code can name a solver without
/// its settings (e.g. to run one scene with both solvers, [`SolverSpec::with_kind`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum SolverKind {
    /// Position Based Fluids (Macklin & Müller 2013).
    Pbf,
    /// Predictive-corrective incompressible SPH (Solenthaler & Pajarola 2009).
    Pcisph,
    /// Implicit incompressible SPH (Ihmsen et al. 2014), water.
    Iisph,
    /// IISPH with Drucker–Prager friction, drag and upscaling for granular matter (Neder
    /// 2024).
    Granular,
}

impl SolverKind {
    /// The name used in scene files: `"pbf"`, `"pcisph"`, `"iisph"` or `"granular"`.
    pub fn name(self) -> &'static str {
        match self {
            SolverKind::Pbf => "pbf",
            SolverKind::Pcisph => "pcisph",
            SolverKind::Iisph => "iisph",
            SolverKind::Granular => "granular",
        }
    }
}

/// Solver settings: the `[solver]` table, one variant per solver, selected by `kind`. Each
/// variant holds the step counts and optional overrides of that solver's defaults (`None` =
/// the solver's default); a field of another solver is refused (unknown field). Units as in
/// the crate documentation; values are range-checked by the scene parser.
///
/// Deserializes as an internally tagged table (`kind = "pbf"` + the [`PbfSpec`] fields). The
/// scene parser reads `kind` first and then the variant from the same table, so that its
/// errors keep the field path and line (see `parse.rs`); both accept the same tables.
///
/// Not `#[non_exhaustive]`: the workspace's matches on it should break when a solver is
/// added.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(tag = "kind", rename_all = "lowercase")]
pub enum SolverSpec {
    /// Position Based Fluids (`kind = "pbf"`).
    Pbf(PbfSpec),
    /// PCISPH (`kind = "pcisph"`).
    Pcisph(PcisphSpec),
    /// IISPH for water (`kind = "iisph"`).
    Iisph(IisphSpec),
    /// IISPH for granular matter (`kind = "granular"`).
    Granular(GranularSpec),
}

/// PBF settings (`[solver] kind = "pbf"`).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PbfSpec {
    /// Solver steps per frame (≥ 1).
    pub substeps: usize,
    /// Constraint (Jacobi) iterations per step (≥ 1); the maximum with
    /// `mean_compression_tolerance`.
    pub iterations: usize,
    /// Rest density (kg/m³, > 0).
    pub rest_density: Option<f64>,
    /// Support radius over particle spacing (> 1).
    pub support_over_spacing: Option<f64>,
    /// CFM relaxation relative to the full-lattice denominator (> 0).
    pub relative_cfm: Option<f64>,
    /// Artificial pressure strength `k` (≥ 0).
    pub scorr_k: Option<f64>,
    /// Artificial pressure exponent `n` (≥ 1).
    pub scorr_n: Option<u32>,
    /// Artificial pressure `|Δq|` as a fraction of `h`, in (0, 1).
    pub scorr_delta_q: Option<f64>,
    /// Vorticity confinement `ε` (m/s, ≥ 0).
    pub vorticity_epsilon: Option<f64>,
    /// XSPH viscosity `c`, in [0, 1].
    pub xsph_c: Option<f64>,
    /// Reorder particles every this many frames (0 = never).
    pub reorder_every: Option<usize>,
    /// Unilateral density constraint `max(ρ/ρ0 − 1, 0)`.
    pub clamp_negative_constraint: Option<bool>,
    /// Mean compression at which the Jacobi iterations stop (> 0; `iterations` is then the
    /// maximum).
    pub mean_compression_tolerance: Option<f64>,
    /// Fewest iterations per step with `mean_compression_tolerance` (≥ 1, ≤ `iterations`).
    pub min_iterations: Option<usize>,
}

/// PCISPH settings (`[solver] kind = "pcisph"`).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PcisphSpec {
    /// Solver steps per frame (≥ 1).
    pub substeps: usize,
    /// Maximum pressure iterations per step (≥ 1).
    pub iterations: usize,
    /// Rest density (kg/m³, > 0).
    pub rest_density: Option<f64>,
    /// Support radius over particle spacing (> 1).
    pub support_over_spacing: Option<f64>,
    /// XSPH viscosity `c`, in [0, 1].
    pub xsph_c: Option<f64>,
    /// Reorder particles every this many frames (0 = never).
    pub reorder_every: Option<usize>,
    /// Clamp negative pressures to zero.
    pub clamp_negative_pressure: Option<bool>,
    /// Relative density error at which the pressure iteration stops (> 0).
    pub density_error_tolerance: Option<f64>,
}

/// IISPH settings for water (`[solver] kind = "iisph"`); see the `iisph-granular` crate.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct IisphSpec {
    /// Solver steps per frame (≥ 1).
    pub substeps: usize,
    /// Most relaxed-Jacobi iterations per step (≥ `min_iterations`; default 100).
    pub max_iterations: Option<usize>,
    /// Fewest iterations per step (≥ 1; default 2).
    pub min_iterations: Option<usize>,
    /// Average relative density error at which the iterations stop (> 0; default 0.001).
    pub density_error_tolerance: Option<f64>,
    /// Jacobi relaxation `ω`, in (0, 1] (default 0.5).
    pub relaxation: Option<f64>,
    /// Rest density (kg/m³, > 0).
    pub rest_density: Option<f64>,
    /// Support radius over particle spacing (> 1).
    pub support_over_spacing: Option<f64>,
    /// Reorder particles every this many frames (0 = never).
    pub reorder_every: Option<usize>,
    /// Kinematic viscosity `ν` (m²/s, ≥ 0; default 0) of the explicit SPH viscosity force.
    pub viscosity: Option<f64>,
}

/// IISPH settings for granular matter (`[solver] kind = "granular"`): those of
/// [`IisphSpec`] plus friction, drag and upscaling.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GranularSpec {
    /// Solver steps per frame (≥ 1).
    pub substeps: usize,
    /// Most relaxed-Jacobi iterations per step (≥ `min_iterations`; default 100).
    pub max_iterations: Option<usize>,
    /// Fewest iterations per step (≥ 1; default 2).
    pub min_iterations: Option<usize>,
    /// Average relative density error at which the iterations stop (> 0; default 0.001).
    pub density_error_tolerance: Option<f64>,
    /// Jacobi relaxation `ω`, in (0, 1] (default 0.5).
    pub relaxation: Option<f64>,
    /// Rest density (kg/m³, > 0).
    pub rest_density: Option<f64>,
    /// Support radius over particle spacing (> 1).
    pub support_over_spacing: Option<f64>,
    /// Reorder particles every this many frames (0 = never).
    pub reorder_every: Option<usize>,
    /// Kinematic viscosity `ν` (m²/s, ≥ 0; default 0) of the explicit SPH viscosity force.
    pub viscosity: Option<f64>,
    /// Friction angle `θ` (degrees, in [0, 90); required): Drucker–Prager `α = √2 sin θ`.
    pub friction_angle_deg: f64,
    /// Drag coefficient `C_D` (≥ 0; default 0 = no drag).
    pub drag_coefficient: Option<f64>,
    /// Uniform air velocity (m/s; default 0).
    pub air_velocity: Option<[f64; 3]>,
    /// Passive high-resolution points per simulation particle (≥ 1; absent = no upscaling).
    pub upscaling_factor: Option<usize>,
    /// Most friction-stress iterations per step (≥ 1; default 20).
    pub friction_max_iterations: Option<usize>,
    /// Mean unyielded strain per step at which the friction iterations stop (> 0; default
    /// 1e-4).
    pub friction_tolerance: Option<f64>,
}

impl SolverSpec {
    /// Which solver.
    pub fn kind(&self) -> SolverKind {
        match self {
            SolverSpec::Pbf(_) => SolverKind::Pbf,
            SolverSpec::Pcisph(_) => SolverKind::Pcisph,
            SolverSpec::Iisph(_) => SolverKind::Iisph,
            SolverSpec::Granular(_) => SolverKind::Granular,
        }
    }

    /// The solver's name in scene files: `"pbf"` or `"pcisph"`.
    pub fn kind_name(&self) -> &'static str {
        self.kind().name()
    }

    /// Solver steps per frame.
    pub fn substeps(&self) -> usize {
        match self {
            SolverSpec::Pbf(s) => s.substeps,
            SolverSpec::Pcisph(s) => s.substeps,
            SolverSpec::Iisph(s) => s.substeps,
            SolverSpec::Granular(s) => s.substeps,
        }
    }

    /// PBF: constraint iterations per step; PCISPH: maximum pressure iterations per step;
    /// IISPH and granular: `max_iterations` (default [`DEFAULT_IISPH_MAX_ITERATIONS`]).
    pub fn iterations(&self) -> usize {
        match self {
            SolverSpec::Pbf(s) => s.iterations,
            SolverSpec::Pcisph(s) => s.iterations,
            SolverSpec::Iisph(s) => s.max_iterations.unwrap_or(DEFAULT_IISPH_MAX_ITERATIONS),
            SolverSpec::Granular(s) => s.max_iterations.unwrap_or(DEFAULT_IISPH_MAX_ITERATIONS),
        }
    }

    /// Sets the solver steps per frame (used by the `[quick]` overrides; not range-checked).
    pub fn set_substeps(&mut self, n: usize) {
        match self {
            SolverSpec::Pbf(s) => s.substeps = n,
            SolverSpec::Pcisph(s) => s.substeps = n,
            SolverSpec::Iisph(s) => s.substeps = n,
            SolverSpec::Granular(s) => s.substeps = n,
        }
    }

    /// Sets the iterations per step (used by the `[quick]` overrides; not range-checked).
    pub fn set_iterations(&mut self, n: usize) {
        match self {
            SolverSpec::Pbf(s) => s.iterations = n,
            SolverSpec::Pcisph(s) => s.iterations = n,
            SolverSpec::Iisph(s) => s.max_iterations = Some(n),
            SolverSpec::Granular(s) => s.max_iterations = Some(n),
        }
    }

    /// Support radius over particle spacing, if overridden.
    pub fn support_over_spacing(&self) -> Option<f64> {
        match self {
            SolverSpec::Pbf(s) => s.support_over_spacing,
            SolverSpec::Pcisph(s) => s.support_over_spacing,
            SolverSpec::Iisph(s) => s.support_over_spacing,
            SolverSpec::Granular(s) => s.support_over_spacing,
        }
    }

    /// Rest density (kg/m³), if overridden.
    pub fn rest_density(&self) -> Option<f64> {
        match self {
            SolverSpec::Pbf(s) => s.rest_density,
            SolverSpec::Pcisph(s) => s.rest_density,
            SolverSpec::Iisph(s) => s.rest_density,
            SolverSpec::Granular(s) => s.rest_density,
        }
    }

    /// These settings for solver `kind`: a copy when `kind` is this solver's; otherwise the
    /// settings the solvers share (substeps, rest density, support ratio, reordering; the
    /// iteration count and XSPH `c` between PBF and PCISPH; every IISPH setting between
    /// `iisph` and `granular`) carried over and the rest left to the other solver's defaults
    /// (a `granular` made from another kind gets `friction_angle_deg = 0`, i.e. no friction).
    pub fn with_kind(&self, kind: SolverKind) -> SolverSpec {
        if self.kind() == kind {
            return self.clone();
        }
        let xsph_c = match self {
            SolverSpec::Pbf(s) => s.xsph_c,
            SolverSpec::Pcisph(s) => s.xsph_c,
            _ => None,
        };
        let reorder_every = match self {
            SolverSpec::Pbf(s) => s.reorder_every,
            SolverSpec::Pcisph(s) => s.reorder_every,
            SolverSpec::Iisph(s) => s.reorder_every,
            SolverSpec::Granular(s) => s.reorder_every,
        };
        let iisph = match self {
            SolverSpec::Iisph(s) => s.clone(),
            SolverSpec::Granular(s) => IisphSpec {
                substeps: s.substeps,
                max_iterations: s.max_iterations,
                min_iterations: s.min_iterations,
                density_error_tolerance: s.density_error_tolerance,
                relaxation: s.relaxation,
                rest_density: s.rest_density,
                support_over_spacing: s.support_over_spacing,
                reorder_every: s.reorder_every,
                viscosity: s.viscosity,
            },
            _ => IisphSpec {
                substeps: self.substeps(),
                max_iterations: None,
                min_iterations: None,
                density_error_tolerance: None,
                relaxation: None,
                rest_density: self.rest_density(),
                support_over_spacing: self.support_over_spacing(),
                reorder_every,
                viscosity: None,
            },
        };
        match kind {
            SolverKind::Pbf => SolverSpec::Pbf(PbfSpec {
                substeps: self.substeps(),
                iterations: self.iterations(),
                rest_density: self.rest_density(),
                support_over_spacing: self.support_over_spacing(),
                relative_cfm: None,
                scorr_k: None,
                scorr_n: None,
                scorr_delta_q: None,
                vorticity_epsilon: None,
                xsph_c,
                reorder_every,
                clamp_negative_constraint: None,
                mean_compression_tolerance: None,
                min_iterations: None,
            }),
            SolverKind::Pcisph => SolverSpec::Pcisph(PcisphSpec {
                substeps: self.substeps(),
                iterations: self.iterations(),
                rest_density: self.rest_density(),
                support_over_spacing: self.support_over_spacing(),
                xsph_c,
                reorder_every,
                clamp_negative_pressure: None,
                density_error_tolerance: None,
            }),
            SolverKind::Iisph => SolverSpec::Iisph(iisph),
            SolverKind::Granular => SolverSpec::Granular(GranularSpec {
                substeps: iisph.substeps,
                max_iterations: iisph.max_iterations,
                min_iterations: iisph.min_iterations,
                density_error_tolerance: iisph.density_error_tolerance,
                relaxation: iisph.relaxation,
                rest_density: iisph.rest_density,
                support_over_spacing: iisph.support_over_spacing,
                reorder_every: iisph.reorder_every,
                viscosity: iisph.viscosity,
                friction_angle_deg: 0.0,
                drag_coefficient: None,
                air_velocity: None,
                upscaling_factor: None,
                friction_max_iterations: None,
                friction_tolerance: None,
            }),
        }
    }
}

/// Default `max_iterations` of the IISPH kinds (SPlisHSPlasH's default cap).
pub const DEFAULT_IISPH_MAX_ITERATIONS: usize = 100;

/// Default `min_iterations` of the IISPH kinds (Ihmsen et al. 2014: at least two).
pub const DEFAULT_IISPH_MIN_ITERATIONS: usize = 2;

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
}

/// Boundary settings: the `[boundary]` table (optional; [`BoundarySpec::default`] when
/// absent).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BoundarySpec {
    /// The boundary model (default [`BoundaryModel::default`]).
    #[serde(default)]
    pub model: BoundaryModel,
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
    /// Boundary settings.
    pub boundary: BoundarySpec,
    /// Output settings.
    pub output: OutputSpec,
    /// The `[quick]` overrides (`None` when absent, and in the scene returned by
    /// [`Scene::quick`]).
    pub quick_overrides: Option<QuickSpec>,
    /// The `[render]` table as written (`None` when absent): camera, light and background of
    /// the screen-space renderer, parsed and checked by the `ssfr-render` crate
    /// (`RenderConfig`), which reports its errors with the field path.
    pub render: Option<toml::Table>,
}

impl Scene {
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
                s.solver.set_substeps(v);
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
