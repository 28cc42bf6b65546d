//! The renderer's view of a scene: [`Scene::render_info`] (what the `[render]` defaults are
//! computed from) and [`Scene::render_params`] (the `[render]` table resolved against it),
//! checked when the scene is checked.

use ssfr_render::{Obstacle, RenderConfig, RenderParams, SceneInfo, SsfrError};

use crate::error::Ctx;
use crate::{Scene, SceneError, SolidSpec};

fn f3(a: [f64; 3]) -> [f32; 3] {
    [a[0] as f32, a[1] as f32, a[2] as f32]
}

/// Colour of the solids drawn in the background.
const SOLID_COLOUR: [f32; 3] = [0.55, 0.45, 0.40];

impl Scene {
    /// What the renderer's defaults need from the scene: tank, liquid bounds, spacing, and
    /// the box and sphere solids as obstacles (mesh and cylinder solids as their bounding box; planes are
    /// not drawn).
    pub fn render_info(&self) -> SceneInfo {
        let mut liquid: Option<([f32; 3], [f32; 3])> = None;
        for f in &self.fluids {
            let b = f.bounds();
            let (lo, hi) = (f3(b.min.into()), f3(b.max.into()));
            liquid = Some(match liquid {
                None => (lo, hi),
                Some((a, b)) => (
                    [a[0].min(lo[0]), a[1].min(lo[1]), a[2].min(lo[2])],
                    [b[0].max(hi[0]), b[1].max(hi[1]), b[2].max(hi[2])],
                ),
            });
        }
        // A moving solid (a wall of boundary particles) is not drawn where it started.
        let obstacles = self
            .standing_solids()
            .filter_map(|j| match &self.solids[j] {
                SolidSpec::Box { min, max } => Some(Obstacle::Box {
                    min: f3(*min),
                    max: f3(*max),
                    colour: SOLID_COLOUR,
                }),
                SolidSpec::Sphere { center, radius } => Some(Obstacle::Sphere {
                    center: f3(*center),
                    radius: *radius as f32,
                    colour: SOLID_COLOUR,
                }),
                SolidSpec::Mesh { mesh, .. } => {
                    let b = mesh.mesh.bounds();
                    Some(Obstacle::Box {
                        min: f3(b.min.into()),
                        max: f3(b.max.into()),
                        colour: SOLID_COLOUR,
                    })
                }
                SolidSpec::Cylinder {
                    base_center: c,
                    radius: r,
                    height: h,
                } => Some(Obstacle::Box {
                    min: f3([c[0] - r, c[1], c[2] - r]),
                    max: f3([c[0] + r, c[1] + h, c[2] + r]),
                    colour: SOLID_COLOUR,
                }),
                SolidSpec::Plane { .. } => None,
            })
            .collect();
        SceneInfo {
            tank: self.tank.map(|t| (f3(t.min.into()), f3(t.max.into()))),
            liquid,
            particle_spacing: self.particle_spacing as f32,
            obstacles,
        }
    }

    /// The render parameters of the scene: its `[render]` table (defaults when absent)
    /// resolved against [`Scene::render_info`]. Errors name the field (`render.camera.eye`).
    pub fn render_params(&self) -> Result<RenderParams, SceneError> {
        let ctx = Ctx {
            lines: Some(&self.lines),
            ..Ctx::new(&self.source)
        };
        self.resolve_render(&ctx)
    }

    /// `[render]` resolved: part of [`Scene::check`].
    pub(crate) fn check_render(&self, ctx: &Ctx) -> Result<(), SceneError> {
        self.resolve_render(ctx).map(|_| ())
    }

    fn resolve_render(&self, ctx: &Ctx) -> Result<RenderParams, SceneError> {
        let default = RenderConfig::default();
        let config = self.render.as_ref().unwrap_or(&default);
        config.resolve(&self.render_info()).map_err(|e| {
            let field = match &e {
                SsfrError::Config { field, .. } if !field.is_empty() => {
                    let f = field.strip_prefix("render.").unwrap_or(field);
                    format!("render.{f}")
                }
                SsfrError::ImageSize { .. } => "render.width".to_string(),
                _ => "render".to_string(),
            };
            let reason = match e {
                SsfrError::Config { reason, .. } => reason,
                other => other.to_string(),
            };
            ctx.invalid(field, reason)
        })
    }
}
