//! `validation run [--full] [--only ID...] [--out DIR]`, `validation list` and
//! `validation scene PATH [--quick] [--frames N] [--out DIR] [--render]` and
//! `validation render DIR [--scene PATH] [--quick] [--out DIR]`.

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand};
use sph_sim::{run_scene, SceneRunOptions};
use validation::runner::{self, RunOptions};
use validation::{registry, render, repose_cmd, workspace_root, Mode};

#[derive(Parser)]
#[command(
    name = "validation",
    about = "Runs the validation experiments (reproduced figures and claims)"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run experiments; exit code 1 when a check fails undocumented (not listed in
    /// reference-data/deviations.toml), a documented deviation passes, or an experiment errors.
    Run {
        /// Paper-sized runs (minutes) instead of the quick ones (seconds).
        #[arg(long)]
        full: bool,
        /// Run only these experiment ids (see `validation list`).
        #[arg(long, num_args = 1.., value_name = "ID")]
        only: Vec<String>,
        /// Output directory [default: target/validation under the workspace root].
        #[arg(long, value_name = "DIR", value_parser = output_dir)]
        out: Option<PathBuf>,
    },
    /// List the experiments and what each reproduces.
    List,
    /// Run a scene file: VTK frames and per-frame statistics.
    Scene {
        /// The scene file (TOML).
        path: PathBuf,
        /// Apply the scene's `[quick]` overrides.
        #[arg(long)]
        quick: bool,
        /// Stop after this many frames (>= 1).
        #[arg(long, value_name = "N", value_parser = frame_count, allow_hyphen_values = true)]
        frames: Option<usize>,
        /// Output directory [default: target/scenes/<file stem> under the workspace root].
        #[arg(long, value_name = "DIR", value_parser = output_dir)]
        out: Option<PathBuf>,
        /// Also render the frames (PNG, in DIR/render) while the scene runs.
        #[arg(long)]
        render: bool,
    },
    /// Measure the angle of repose of a scene run's last frame (or `--frame FILE`).
    Repose {
        /// The run's output directory.
        dir: PathBuf,
        /// The frame to measure [default: the last `frame_*.vtk` in DIR].
        #[arg(long, value_name = "FILE")]
        frame: Option<PathBuf>,
        /// Planar heap (profile along x) or conical pile.
        #[arg(long, value_enum, default_value = "planar")]
        shape: repose_cmd::Shape,
        /// The scene file [default: the one recorded by `scene` in DIR].
        #[arg(long, value_name = "PATH")]
        scene: Option<PathBuf>,
        /// With --scene: apply its `[quick]` overrides.
        #[arg(long)]
        quick: bool,
    },
    /// Render the VTK frames of a scene run (`frame_*.vtk` in DIR) to PNG images.
    Render {
        /// The run's output directory.
        dir: PathBuf,
        /// The scene file [default: the one recorded by `scene` in DIR].
        #[arg(long, value_name = "PATH")]
        scene: Option<PathBuf>,
        /// With --scene: apply its `[quick]` overrides (the particle radius follows them).
        #[arg(long)]
        quick: bool,
        /// Output directory for the PNGs [default: DIR/render].
        #[arg(long, value_name = "DIR")]
        out: Option<PathBuf>,
    },
}

fn report(r: anyhow::Result<()>) -> ExitCode {
    match r {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e:#}");
            ExitCode::from(1)
        }
    }
}

/// `scene PATH --render`: the scene runs on this thread, the renderer follows on another.
fn run_and_render(path: &std::path::Path, opts: &SceneRunOptions) -> anyhow::Result<()> {
    use std::sync::atomic::{AtomicBool, Ordering};
    use std::sync::Arc;
    let scene = render::run_scene_of(&opts.out_dir, Some(path), opts.quick)?;
    let params = render::render_params(&scene)?;
    let done = Arc::new(AtomicBool::new(false));
    let (dir, out) = (opts.out_dir.clone(), opts.out_dir.join("render"));
    let flag = done.clone();
    let worker =
        std::thread::spawn(move || render::render_while_running(&dir, &params, &out, flag));
    let sim = run_scene(path, opts);
    done.store(true, Ordering::Release);
    let rendered = worker
        .join()
        .map_err(|_| anyhow::anyhow!("the rendering thread panicked"))?;
    sim?;
    let n = rendered?;
    eprintln!(
        "{n} frames rendered to {}",
        opts.out_dir.join("render").display()
    );
    Ok(())
}

/// `--out DIR`: refuses a path that exists and is not a directory (before any work).
fn output_dir(s: &str) -> Result<PathBuf, String> {
    let p = PathBuf::from(s);
    if p.exists() && !p.is_dir() {
        return Err("exists and is not a directory (give a directory for the output)".into());
    }
    Ok(p)
}

/// `--frames N`: a whole number >= 1.
fn frame_count(s: &str) -> Result<usize, String> {
    match s.parse::<usize>() {
        Ok(0) => Err("0 frames would run nothing (give at least 1)".into()),
        Ok(n) => Ok(n),
        Err(e) => Err(format!("not a whole number of frames >= 1 ({e})")),
    }
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let all = registry();
    match cli.command {
        Command::List => {
            let w = all.iter().map(|e| e.id().len()).max().unwrap_or(0);
            for e in &all {
                println!("{:<w$}  {}", e.id(), e.source());
            }
            ExitCode::SUCCESS
        }
        Command::Scene {
            path,
            quick,
            frames,
            out,
            render: with_render,
        } => {
            let stem = path
                .file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_else(|| "scene".into());
            let opts = SceneRunOptions {
                quick,
                max_frames: frames,
                out_dir: out
                    .unwrap_or_else(|| workspace_root().join("target").join("scenes").join(stem)),
                progress: true,
            };
            if let Err(e) = render::write_run_source(&opts.out_dir, &path, quick) {
                return report(Err(e));
            }
            if with_render {
                report(run_and_render(&path, &opts))
            } else {
                report(run_scene(&path, &opts).map_err(Into::into))
            }
        }
        Command::Repose {
            dir,
            frame,
            shape,
            scene,
            quick,
        } => report(repose_cmd::measure_run(
            &dir,
            frame,
            shape,
            scene.as_deref(),
            quick,
        )),
        Command::Render {
            dir,
            scene,
            quick,
            out,
        } => report((|| {
            let scene = render::run_scene_of(&dir, scene.as_deref(), quick)?;
            let out = out.unwrap_or_else(|| dir.join("render"));
            render::render_run_dir(&dir, &scene, &out).map(|_| ())
        })()),
        Command::Run { full, only, out } => {
            let opts = RunOptions {
                mode: if full { Mode::Full } else { Mode::Quick },
                only,
                out: out.unwrap_or_else(|| workspace_root().join("target").join("validation")),
            };
            match runner::run(&all, &opts) {
                Ok(verdicts) if runner::succeeded(&verdicts) => ExitCode::SUCCESS,
                Ok(_) => ExitCode::from(1),
                Err(e) => {
                    eprintln!("error: {e:#}");
                    ExitCode::from(1)
                }
            }
        }
    }
}
