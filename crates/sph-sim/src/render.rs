//! Scenes seen by the screen-space renderer (`ssfr-render`): the renderer's view of a scene
//! (tank, liquid bounds, obstacles), its `[render]` table resolved against it, and a frame
//! observer that renders each frame of a running scene in process.

use std::path::{Path, PathBuf};

use sph_core::Real;
use sph_scene::{FluidSpec, Scene, SolidSpec};
use sph_solver::StepStats;
use ssfr_render::config::SceneInfo;
use ssfr_render::{Obstacle, RenderConfig, RenderParams, Renderer};

use crate::run::{FrameObserver, RunPlan};
use crate::run_dir::RunDir;
use crate::{SceneSim, SimError};

fn f3(a: [f64; 3]) -> [f32; 3] {
    [a[0] as f32, a[1] as f32, a[2] as f32]
}

/// What the renderer's defaults need from a scene: tank, liquid bounds, spacing, and the
/// box and sphere solids as obstacles (mesh solids as their bounding box; planes are not
/// drawn).
pub fn scene_info(scene: &Scene) -> SceneInfo {
    let mut liquid: Option<([f32; 3], [f32; 3])> = None;
    let mut grow = |lo: [f32; 3], hi: [f32; 3]| {
        liquid = Some(match liquid {
            None => (lo, hi),
            Some((a, b)) => (
                [a[0].min(lo[0]), a[1].min(lo[1]), a[2].min(lo[2])],
                [b[0].max(hi[0]), b[1].max(hi[1]), b[2].max(hi[2])],
            ),
        })
    };
    for f in &scene.fluids {
        match f {
            FluidSpec::Block { min, max, .. } => grow(f3(*min), f3(*max)),
            FluidSpec::Mesh { mesh, .. } => {
                let b = mesh.mesh.bounds();
                grow(f3(b.min.into()), f3(b.max.into()))
            }
        }
    }
    let grey = [0.55, 0.45, 0.40];
    let obstacles = scene
        .solids
        .iter()
        .filter_map(|s| match s {
            SolidSpec::Box { min, max } => Some(Obstacle::Box {
                min: f3(*min),
                max: f3(*max),
                colour: grey,
            }),
            SolidSpec::Sphere { center, radius } => Some(Obstacle::Sphere {
                center: f3(*center),
                radius: *radius as f32,
                colour: grey,
            }),
            SolidSpec::Mesh { mesh, .. } => {
                let b = mesh.mesh.bounds();
                Some(Obstacle::Box {
                    min: f3(b.min.into()),
                    max: f3(b.max.into()),
                    colour: grey,
                })
            }
            SolidSpec::Plane { .. } => None,
        })
        .collect();
    SceneInfo {
        tank: scene.tank.map(|t| (f3(t.min.into()), f3(t.max.into()))),
        liquid,
        particle_spacing: scene.particle_spacing as f32,
        obstacles,
    }
}

/// The render parameters of `scene`: its `[render]` table (defaults when absent) resolved
/// against the scene. Errors name the scene file and the table.
pub fn render_params(scene: &Scene) -> Result<RenderParams, SimError> {
    let cfg = match &scene.render {
        Some(t) => RenderConfig::from_table(t),
        None => Ok(RenderConfig::default()),
    };
    cfg.and_then(|c| c.resolve(&scene_info(scene)))
        .map_err(|e| SimError::Invalid(format!("{}: [render]: {e}", scene.source.display())))
}

/// Renders `positions` (a frame of `scene`) with the scene's `[render]` parameters to a PNG
/// of `width` pixels (height from the scene's aspect ratio).
pub fn render_particles_png<R: Real>(
    scene: &Scene,
    positions: &[sph_core::Vec3<R>],
    width: usize,
    path: &Path,
) -> Result<(), SimError> {
    let mut params = render_params(scene)?;
    let aspect = params.camera.height as f64 / params.camera.width as f64;
    params.camera.width = width;
    params.camera.height = ((width as f64 * aspect).round() as usize).max(1);
    let mut r = Renderer::default();
    r.render_points(&params, positions)
        .map_err(|e| SimError::output(path, format!("rendering: {e}")))?;
    r.image()
        .write_png(path)
        .map_err(|e| SimError::output(path, e))
}

/// A [`FrameObserver`] rendering every frame the run writes (the VTK cadence,
/// `output.every_frames`) from the particles in memory to `render/frame_NNNNN.png` in the
/// run directory.
#[derive(Debug)]
pub struct RenderObserver {
    params: RenderParams,
    renderer: Renderer,
    dir: PathBuf,
    every: usize,
    /// Frames rendered so far by this observer.
    pub rendered: usize,
    /// Milliseconds the last frame took to render.
    pub last_ms: f64,
}

impl RenderObserver {
    /// The observer of `scene`'s `[render]` table, writing into `run.render_dir()`. Errors
    /// name the scene's `[render]` table.
    pub fn new(scene: &Scene, run: &RunDir) -> Result<Self, SimError> {
        Ok(Self {
            params: render_params(scene)?,
            renderer: Renderer::default(),
            dir: run.render_dir(),
            every: scene.output.every_frames.max(1),
            rendered: 0,
            last_ms: 0.0,
        })
    }

    fn render<R: Real>(&mut self, sim: &SceneSim<R>) -> Result<(), SimError> {
        let path = self.dir.join(RunDir::frame_png_name(sim.frame));
        let stats = self
            .renderer
            .render_points(&self.params, &sim.state.positions)
            .map_err(|e| SimError::output(&path, format!("rendering frame {}: {e}", sim.frame)))?;
        self.renderer
            .image()
            .write_png(&path)
            .map_err(|e| SimError::output(&path, e))?;
        self.rendered += 1;
        self.last_ms = stats.times.total_s() * 1e3;
        Ok(())
    }
}

impl<R: Real> FrameObserver<R> for RenderObserver {
    fn start(&mut self, sim: &SceneSim<R>, plan: &RunPlan) -> Result<(), SimError> {
        std::fs::create_dir_all(&self.dir).map_err(|e| SimError::output(&self.dir, e))?;
        if !plan.resumed {
            self.render(sim)?;
        }
        Ok(())
    }

    fn frame(&mut self, sim: &SceneSim<R>, _stats: &StepStats) -> Result<(), SimError> {
        if sim.frame.is_multiple_of(self.every) {
            self.render(sim)?;
        }
        Ok(())
    }
}
