//! Rendering scene runs with the screen-space renderer (`ssfr-render`): reading the VTK
//! frames the scene runner writes (`sph_sim::vtk`), the render parameters from a scene's
//! `[render]` table, and `cargo xtask render OUTPUT_DIR` / `cargo xtask run SCENE --render`.

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

use anyhow::{Context as _, Result};
use indicatif::{ProgressBar, ProgressStyle};
use sph_core::Vec3;
use sph_scene::Scene;
use ssfr_render::{ParticleView, RenderParams, Renderer, SsfrError};
use vtkio::model::{DataSet, Piece};
use vtkio::Vtk;

/// File in a scene run's output directory naming the scene and the mode it ran in, so that
/// `render OUTPUT_DIR` finds its `[render]` table: two lines, the absolute scene path and
/// `quick` or `full`.
pub const RUN_SOURCE_FILE: &str = "scene_source.txt";

/// Reads the particle positions (m) of one VTK frame written by `sph_sim::vtk`. A missing
/// file is [`SsfrError::MissingFrame`], anything unreadable [`SsfrError::CorruptFrame`].
pub fn read_frame_positions(path: &Path) -> Result<Vec<Vec3<f32>>, SsfrError> {
    if !path.is_file() {
        return Err(SsfrError::MissingFrame {
            path: path.to_path_buf(),
            reason: "no such file".into(),
        });
    }
    let corrupt = |reason: String| SsfrError::CorruptFrame {
        path: path.to_path_buf(),
        reason,
    };
    let vtk = Vtk::import(path).map_err(|e| corrupt(e.to_string()))?;
    let DataSet::PolyData { pieces, .. } = vtk.data else {
        return Err(corrupt(
            "not poly data (a particle frame is legacy VTK POLYDATA)".into(),
        ));
    };
    let mut out = Vec::new();
    for piece in pieces {
        let Piece::Inline(p) = piece else {
            return Err(corrupt("piece not inline".into()));
        };
        let pts: Vec<f32> = p
            .points
            .clone()
            .cast_into()
            .ok_or_else(|| corrupt("points are not numbers".into()))?;
        if !pts.len().is_multiple_of(3) {
            return Err(corrupt(format!(
                "{} coordinates: not a multiple of 3",
                pts.len()
            )));
        }
        out.extend(pts.chunks(3).map(|c| Vec3::new(c[0], c[1], c[2])));
    }
    if let Some((i, p)) = out
        .iter()
        .enumerate()
        .find(|(_, p)| !p.iter().all(|x| x.is_finite()))
    {
        return Err(corrupt(format!("particle {i} at {p:?} is not finite")));
    }
    Ok(out)
}

/// The render parameters of `scene`: its `[render]` table (defaults when absent) resolved
/// against the scene ([`Scene::render_params`]; checked when the scene was loaded). Errors
/// name the scene file and the field.
pub fn render_params(scene: &Scene) -> Result<RenderParams> {
    Ok(scene.render_params()?)
}

/// Renders one frame file to a PNG.
pub fn render_frame_file(
    renderer: &mut Renderer,
    params: &RenderParams,
    vtk: &Path,
    png: &Path,
) -> Result<ssfr_render::FrameStats> {
    let positions = read_frame_positions(vtk)?;
    let stats = render_positions(renderer, params, &positions)
        .with_context(|| format!("rendering {}", vtk.display()))?;
    renderer.image().write_png(png)?;
    Ok(stats)
}

/// Renders `positions` as spheres, or as Yu & Turk ellipsoids when the parameters ask for
/// them.
pub fn render_positions(
    renderer: &mut Renderer,
    params: &RenderParams,
    positions: &[Vec3<f32>],
) -> Result<ssfr_render::FrameStats> {
    let view = ParticleView::spheres(positions, params.particle_radius_m);
    Ok(match &params.anisotropy {
        None => renderer.render(params, &view)?,
        Some(a) => {
            let (centres, ellipsoids) =
                ssfr_render::anisotropy::anisotropic_ellipsoids(positions, a)?;
            renderer.render(
                params,
                &ParticleView {
                    positions: &centres,
                    ellipsoids: Some(&ellipsoids),
                    ..view
                },
            )?
        }
    })
}

/// The frame files `frame_NNNNN.vtk` of a run directory, sorted.
pub fn frame_files(dir: &Path) -> Result<Vec<PathBuf>> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(dir)
        .with_context(|| format!("{}: not a readable run directory", dir.display()))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| {
            p.file_name()
                .and_then(|n| n.to_str())
                .is_some_and(|n| n.starts_with("frame_") && n.ends_with(".vtk"))
        })
        .collect();
    v.sort();
    Ok(v)
}

/// Records the scene and mode of a run in its output directory ([`RUN_SOURCE_FILE`]).
pub fn write_run_source(out_dir: &Path, scene: &Path, quick: bool) -> Result<()> {
    std::fs::create_dir_all(out_dir)?;
    let abs = std::path::absolute(scene).unwrap_or_else(|_| scene.to_path_buf());
    std::fs::write(
        out_dir.join(RUN_SOURCE_FILE),
        format!(
            "{}\n{}\n",
            abs.display(),
            if quick { "quick" } else { "full" }
        ),
    )
    .with_context(|| format!("writing {}", out_dir.join(RUN_SOURCE_FILE).display()))
}

/// The scene of a run directory: `scene` if given (with `quick`), else the one recorded in
/// [`RUN_SOURCE_FILE`].
pub fn run_scene_of(dir: &Path, scene: Option<&Path>, quick: bool) -> Result<Scene> {
    let (path, quick) = match scene {
        Some(p) => (p.to_path_buf(), quick),
        None => {
            let f = dir.join(RUN_SOURCE_FILE);
            let text = std::fs::read_to_string(&f).with_context(|| {
                format!(
                    "{}: no scene recorded for this run directory (give --scene SCENE)",
                    f.display()
                )
            })?;
            let mut lines = text.lines();
            let p = PathBuf::from(lines.next().unwrap_or_default());
            (p, quick || lines.next() == Some("quick"))
        }
    };
    let s = Scene::load(&path)?;
    Ok(if quick { s.quick() } else { s })
}

fn bar(len: u64, what: &str) -> ProgressBar {
    let b = ProgressBar::new(len);
    b.set_style(
        ProgressStyle::with_template(&format!(
            "{{spinner}} [{{elapsed_precise}}] {{bar:40}} {{pos}}/{{len}} {what} ETA {{eta}} {{msg}}"
        ))
        .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    b
}

/// `render DIR`: every `frame_*.vtk` of `dir` to `out/frame_*.png`, with a progress bar.
/// Returns the number of frames rendered.
pub fn render_run_dir(dir: &Path, scene: &Scene, out: &Path) -> Result<usize> {
    let params = render_params(scene)?;
    let frames = frame_files(dir)?;
    if frames.is_empty() {
        return Err(SsfrError::MissingFrame {
            path: dir.join("frame_00000.vtk"),
            reason: "no frame_*.vtk in the run directory".into(),
        }
        .into());
    }
    std::fs::create_dir_all(out).with_context(|| format!("creating {}", out.display()))?;
    let b = bar(frames.len() as u64, "frames");
    let mut r = Renderer::default();
    for f in &frames {
        let png = out.join(f.with_extension("png").file_name().unwrap_or_default());
        let stats = render_frame_file(&mut r, &params, f, &png)?;
        b.set_message(format!("{:.0} ms/frame", stats.times.total_s() * 1e3));
        b.inc(1);
    }
    b.finish();
    eprintln!("{} frames rendered to {}", frames.len(), out.display());
    Ok(frames.len())
}

/// Renders the frames of a run while it is being written: a frame is rendered once the next
/// one exists or `done` is set (so a frame is never read half-written). Returns the number
/// rendered; run it on its own thread beside the simulation.
pub fn render_while_running(
    dir: &Path,
    params: &RenderParams,
    out: &Path,
    done: Arc<AtomicBool>,
) -> Result<usize> {
    std::fs::create_dir_all(out)?;
    let mut r = Renderer::default();
    let mut next = 0usize;
    loop {
        let finished = done.load(Ordering::Acquire);
        let frames = frame_files(dir)?;
        let ready: Vec<&PathBuf> = frames
            .iter()
            .filter(|p| {
                let k = frame_index(p);
                k >= next && (finished || frames.iter().any(|q| frame_index(q) > k))
            })
            .collect();
        for f in ready {
            let png = out.join(f.with_extension("png").file_name().unwrap_or_default());
            render_frame_file(&mut r, params, f, &png)?;
            next = frame_index(f) + 1;
        }
        if finished {
            return Ok(next);
        }
        std::thread::sleep(std::time::Duration::from_millis(50));
    }
}

fn frame_index(p: &Path) -> usize {
    p.file_stem()
        .and_then(|s| s.to_str())
        .and_then(|s| s.strip_prefix("frame_"))
        .and_then(|s| s.parse().ok())
        .unwrap_or(0)
}

/// Renders `positions` (a frame of `scene`) with the scene's `[render]` parameters to a PNG
/// of `width` pixels (height from the scene's aspect ratio): the rendered frames experiments
/// show beside their scatter plots.
pub fn render_particles_png(
    scene: &Scene,
    positions: &[Vec3<f32>],
    width: usize,
    path: &Path,
) -> Result<()> {
    let mut params = render_params(scene)?;
    let aspect = params.camera.height as f64 / params.camera.width as f64;
    params.camera.width = width;
    params.camera.height = ((width as f64 * aspect).round() as usize).max(1);
    let mut r = Renderer::default();
    render_positions(&mut r, &params, positions)
        .with_context(|| format!("rendering {}", path.display()))?;
    r.image().write_png(path)?;
    Ok(())
}
