//! Scenes seen by the screen-space renderer (`ssfr-render`): rendered PNGs of a scene's
//! particles, and a frame observer that renders each frame of a running scene in process
//! (the renderer's view of a scene and its `[render]` table are `sph_scene::Scene`'s).

use std::path::{Path, PathBuf};

use sph_core::Real;
use sph_scene::Scene;
use ssfr_render::{RenderParams, Renderer};

use crate::error::SimError;
use crate::frame_loop::{Flow, FrameObserver, RunPlan};
use crate::record::FrameRecord;
use crate::run_dir::RunDir;
use crate::sim::SceneSim;

/// The render parameters of `scene`: its `[render]` table (defaults when absent) resolved
/// against the scene (`sph_scene::Scene::render_params`, checked when the scene was loaded).
pub fn render_params(scene: &Scene) -> Result<RenderParams, SimError> {
    Ok(scene.render_params()?)
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

    fn frame(&mut self, sim: &SceneSim<R>, _: &FrameRecord) -> Result<Flow, SimError> {
        if sim.frame.is_multiple_of(self.every) {
            self.render(sim)?;
        }
        Ok(Flow::Continue)
    }
}
