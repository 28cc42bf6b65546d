//! `particles render DIR`: an earlier run's VTK frames rendered to PNG images.

use std::path::{Path, PathBuf};

use anyhow::{Context as _, Result};
use indicatif::{ProgressBar, ProgressStyle};
use sph_scene::Scene;
use sph_sim::render::render_params;
use sph_sim::{RunDir, RunSource};
use ssfr_render::Renderer;

/// Arguments of `particles render`.
#[derive(Debug, clap::Args)]
pub struct RenderArgs {
    /// The run's output directory (as given to `run --out`).
    dir: PathBuf,
    /// The scene file [default: the one recorded in DIR by `run`].
    #[arg(long, value_name = "SCENE")]
    scene: Option<PathBuf>,
    /// With --scene: apply its `[quick]` overrides (the particle radius follows them).
    #[arg(long)]
    quick: bool,
    /// Output directory for the PNGs [default: DIR/render].
    #[arg(long, value_name = "DIR", value_parser = crate::directory)]
    out: Option<PathBuf>,
}

/// The scene of a run directory: `scene` if given (with `quick`), else the one the run
/// recorded (with its overrides).
pub fn scene_of_run(run: &RunDir, scene: Option<&Path>, quick: bool) -> Result<Scene> {
    let source = match scene {
        Some(p) => RunSource {
            scene: p.to_path_buf(),
            quick,
            overrides: Vec::new(),
        },
        None => run.read_source()?,
    };
    Ok(source.load()?)
}

/// Runs `particles render`.
pub fn run(a: &RenderArgs) -> Result<()> {
    let run = RunDir::new(&a.dir);
    let scene = scene_of_run(&run, a.scene.as_deref(), a.quick)?;
    let params = render_params(&scene)?;
    let frames = run.frames()?;
    anyhow::ensure!(
        !frames.is_empty(),
        "{}: no frame_*.vtk in the run directory",
        a.dir.display()
    );
    let out = a.out.clone().unwrap_or_else(|| run.render_dir());
    std::fs::create_dir_all(&out).with_context(|| format!("{}: cannot create", out.display()))?;
    let bar = ProgressBar::new(frames.len() as u64);
    bar.set_style(
        ProgressStyle::with_template(
            "{spinner} [{elapsed_precise}] {bar:40} {pos}/{len} frames ETA {eta} {msg}",
        )
        .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let mut r = Renderer::default();
    for (f, vtk) in &frames {
        let positions = sph_sim::vtk::read_positions(vtk)?;
        let png = out.join(RunDir::frame_png_name(*f));
        let stats = r
            .render_points(&params, &positions)
            .with_context(|| format!("rendering {}", vtk.display()))?;
        r.image()
            .write_png(&png)
            .with_context(|| format!("writing {}", png.display()))?;
        bar.set_message(format!("{:.0} ms/frame", stats.times.total_s() * 1e3));
        bar.inc(1);
    }
    bar.finish();
    eprintln!("{} frames rendered to {}", frames.len(), out.display());
    Ok(())
}
