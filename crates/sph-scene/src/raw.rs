//! The scene file as written (serde), before validation.

use serde::Deserialize;

use ssfr_render::RenderConfig;

use crate::{BoundarySpec, PourSpec, Precision, SolidMotion, SolverKind, WallModel};

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawScene {
    pub name: String,
    pub simulation: RawSimulation,
    /// Only the tag here: the rest of the `[solver]` table is read by `parse::solver`.
    pub solver: RawSolverTag,
    #[serde(default)]
    pub boundary: BoundarySpec,
    pub tank: Option<RawTank>,
    #[serde(default)]
    pub fluid: Vec<RawFluid>,
    #[serde(default)]
    pub solid: Vec<RawSolid>,
    pub pour: Option<PourSpec>,
    pub output: Option<RawOutput>,
    pub quick: Option<RawQuick>,
    /// The renderer's settings (`ssfr-render`), checked against the scene by `Scene::check`.
    pub render: Option<RenderConfig>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawSimulation {
    pub precision: Option<Precision>,
    pub particle_spacing: f64,
    pub duration: f64,
    pub frame_dt: f64,
    pub gravity: Option<[f64; 3]>,
    pub dimensions: Option<sph_solver::Dimensions>,
}

/// The tag of the `[solver]` table. Its other fields are ignored here and read by
/// `parse::solver` from the same table as the variant struct of this kind (see there why).
#[derive(Debug, Deserialize)]
#[serde(expecting = "a table with a solver kind")]
pub(crate) struct RawSolverTag {
    pub kind: SolverKind,
}

#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawBox {
    pub min: [f64; 3],
    pub max: [f64; 3],
}

#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawTank {
    pub min: [f64; 3],
    pub max: [f64; 3],
    pub wall: Option<WallModel>,
}

#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub(crate) enum RawFluidKind {
    Block,
    Mesh,
    Cylinder,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawFluid {
    pub kind: RawFluidKind,
    pub min: Option<[f64; 3]>,
    pub max: Option<[f64; 3]>,
    pub velocity: Option<[f64; 3]>,
    pub path: Option<String>,
    pub scale: Option<f64>,
    pub translate: Option<[f64; 3]>,
    pub fit: Option<RawBox>,
    pub base_center: Option<[f64; 3]>,
    pub radius: Option<f64>,
    pub height: Option<f64>,
}

#[derive(Debug, Clone, Copy, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "lowercase")]
pub(crate) enum RawSolidKind {
    Sphere,
    Box,
    Plane,
    Mesh,
    Cylinder,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawSolid {
    pub kind: RawSolidKind,
    pub center: Option<[f64; 3]>,
    pub radius: Option<f64>,
    pub min: Option<[f64; 3]>,
    pub max: Option<[f64; 3]>,
    pub point: Option<[f64; 3]>,
    pub normal: Option<[f64; 3]>,
    pub path: Option<String>,
    pub scale: Option<f64>,
    pub translate: Option<[f64; 3]>,
    pub fit: Option<RawBox>,
    pub sdf_cell: Option<f64>,
    pub base_center: Option<[f64; 3]>,
    pub height: Option<f64>,
    pub wall: Option<WallModel>,
    pub motion: Option<SolidMotion>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawOutput {
    pub every_frames: Option<usize>,
    pub vtk: Option<bool>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawQuick {
    pub particle_spacing: Option<f64>,
    pub duration: Option<f64>,
    pub frame_dt: Option<f64>,
    pub substeps: Option<usize>,
    pub iterations: Option<usize>,
    pub every_frames: Option<usize>,
}
