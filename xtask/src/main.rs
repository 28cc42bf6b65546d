//! Workspace automation (`cargo xtask <command>`, alias in `.cargo/config.toml`).
//!
//! - `cargo xtask validate [--full] [--only ID...] [--out DIR]` — builds the `validation`
//!   crate in release and runs the experiments (`validation run ...`); exit code 1 when any
//!   check fails or an experiment errors.
//! - `cargo xtask list` — the experiments and the paper figure each reproduces.
//! - `cargo xtask run SCENE [--quick] [--frames N] [--out DIR]` — builds `validation` in release
//!   and runs a scene file (`validation scene ...`): ParaView frames and per-frame statistics.
//!   With `--render`, the frames are also rendered (PNG in `OUT/render`) while it runs.
//! - `cargo xtask render OUTPUT_DIR [--scene SCENE] [--quick] [--out DIR]` — renders a scene
//!   run's VTK frames to PNG images with the screen-space renderer (`validation render ...`).
//! - `cargo xtask repose OUTPUT_DIR [--frame FILE] [--shape planar|conical]` — the angle of
//!   repose of a granular scene run's last frame (`validation repose ...`).
//! - `cargo xtask bench [ARGS...]` — `cargo bench -p benches -- ARGS...` (criterion).
//!
//! Deliberately light: clap + anyhow + std. Cargo is the one running this (`$CARGO`), and
//! every command runs from the workspace root.

use std::ffi::OsString;
use std::path::{Path, PathBuf};
use std::process::{Command, ExitCode};

use anyhow::{Context, Result};
use clap::{Parser, Subcommand};

#[derive(Parser)]
#[command(
    name = "cargo xtask",
    about = "Workspace tasks: validation experiments and benchmarks"
)]
struct Cli {
    #[command(subcommand)]
    command: Task,
}

#[derive(Subcommand)]
enum Task {
    /// Build `validation` in release and run the experiments (exit code 1 on any failure).
    Validate {
        /// Paper-sized runs (minutes) instead of the quick ones.
        #[arg(long)]
        full: bool,
        /// Run only these experiment ids (see `cargo xtask list`).
        #[arg(long, num_args = 1.., value_name = "ID")]
        only: Vec<String>,
        /// Output directory [default: target/validation under the workspace root].
        #[arg(long, value_name = "DIR")]
        out: Option<PathBuf>,
    },
    /// List the experiments and the figure or claim each reproduces.
    List,
    /// Run a scene file (e.g. `scenes/dam_break.toml`): VTK frames for ParaView and a CSV of
    /// per-frame statistics in `--out` [default: `target/scenes/SCENE_NAME`].
    Run {
        /// The scene file (TOML).
        scene: PathBuf,
        /// Apply the scene's `[quick]` overrides (fewer particles, shorter).
        #[arg(long)]
        quick: bool,
        /// Stop after this many frames.
        #[arg(long, value_name = "N")]
        frames: Option<usize>,
        /// Output directory.
        #[arg(long, value_name = "DIR")]
        out: Option<PathBuf>,
        /// Also render the frames (PNG in OUT/render) while the scene runs.
        #[arg(long)]
        render: bool,
    },
    /// Render a scene run's VTK frames (`frame_*.vtk` in OUTPUT_DIR) to PNG images, with the
    /// camera, light and background of the scene's `[render]` table.
    Render {
        /// The run's output directory (as given to `run --out`).
        dir: PathBuf,
        /// The scene file [default: the one recorded in OUTPUT_DIR by `run`].
        #[arg(long, value_name = "SCENE")]
        scene: Option<PathBuf>,
        /// With --scene: apply its `[quick]` overrides.
        #[arg(long)]
        quick: bool,
        /// Output directory for the PNGs [default: OUTPUT_DIR/render].
        #[arg(long, value_name = "DIR")]
        out: Option<PathBuf>,
    },
    /// Measure the angle of repose of a granular scene run's last frame (or `--frame FILE`).
    Repose {
        /// The run's output directory (as given to `run --out`).
        dir: PathBuf,
        /// The frame to measure [default: the last `frame_*.vtk` in OUTPUT_DIR].
        #[arg(long, value_name = "FILE")]
        frame: Option<PathBuf>,
        /// `planar` (a 2.5D heap, profile along x) or `conical`.
        #[arg(long, default_value = "planar")]
        shape: String,
    },
    /// Run the criterion benchmarks: `cargo bench -p benches -- ARGS...`.
    Bench {
        /// Arguments passed to criterion (e.g. a filter, `--save-baseline main`).
        #[arg(
            trailing_var_arg = true,
            allow_hyphen_values = true,
            value_name = "ARGS"
        )]
        args: Vec<OsString>,
    },
}

/// The workspace root: the parent of this crate's manifest directory.
fn workspace_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .map(Path::to_path_buf)
        .unwrap_or_else(|| PathBuf::from("."))
}

/// The cargo that runs us (`$CARGO`), else the one this crate was built with, else `cargo`.
fn cargo() -> OsString {
    std::env::var_os("CARGO")
        .or_else(|| option_env!("CARGO").map(OsString::from))
        .unwrap_or_else(|| OsString::from("cargo"))
}

/// Runs `cargo <args>` from the workspace root; returns its exit code.
fn run_cargo(args: &[OsString]) -> Result<u8> {
    let root = workspace_root();
    let status = Command::new(cargo())
        .args(args)
        .current_dir(&root)
        .status()
        .with_context(|| format!("running cargo {args:?} in {}", root.display()))?;
    Ok(match status.code() {
        Some(0) => 0,
        Some(code) => u8::try_from(code).unwrap_or(1).max(1),
        None => 1, // killed by a signal
    })
}

/// `path` made absolute against the directory the user typed the command in (cargo runs
/// the commands from the workspace root).
fn abs(path: PathBuf) -> OsString {
    std::path::absolute(&path).unwrap_or(path).into_os_string()
}

fn os(args: &[&str]) -> Vec<OsString> {
    args.iter().map(OsString::from).collect()
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let args = match cli.command {
        Task::Validate { full, only, out } => {
            let mut a = os(&["run", "--release", "-p", "validation", "--", "run"]);
            if full {
                a.push("--full".into());
            }
            if !only.is_empty() {
                a.push("--only".into());
                a.extend(only.into_iter().map(OsString::from));
            }
            if let Some(out) = out {
                // Relative to where the user typed the command, not the workspace root.
                let out = std::path::absolute(&out).unwrap_or(out);
                a.push("--out".into());
                a.push(out.into_os_string());
            }
            a
        }
        Task::Run {
            scene,
            quick,
            frames,
            out,
            render,
        } => {
            let mut a = os(&["run", "--release", "-p", "validation", "--", "scene"]);
            if render {
                a.push("--render".into());
            }
            // Paths relative to where the user typed the command, not the workspace root.
            a.push(
                std::path::absolute(&scene)
                    .unwrap_or(scene)
                    .into_os_string(),
            );
            if quick {
                a.push("--quick".into());
            }
            if let Some(n) = frames {
                a.push("--frames".into());
                a.push(n.to_string().into());
            }
            if let Some(out) = out {
                a.push("--out".into());
                a.push(std::path::absolute(&out).unwrap_or(out).into_os_string());
            }
            a
        }
        Task::Render {
            dir,
            scene,
            quick,
            out,
        } => {
            let mut a = os(&["run", "--release", "-p", "validation", "--", "render"]);
            a.push(abs(dir));
            for (flag, path) in [("--scene", scene), ("--out", out)] {
                if let Some(p) = path {
                    a.extend([flag.into(), abs(p)]);
                }
            }
            if quick {
                a.push("--quick".into());
            }
            a
        }
        Task::Repose { dir, frame, shape } => {
            let mut a = os(&["run", "--release", "-p", "validation", "--", "repose"]);
            a.push(abs(dir));
            if let Some(f) = frame {
                a.extend(["--frame".into(), abs(f)]);
            }
            a.extend(["--shape".into(), shape.into()]);
            a
        }
        Task::List => os(&["run", "--release", "-p", "validation", "--", "list"]),
        Task::Bench { args } => {
            let mut a = os(&["bench", "-p", "benches", "--"]);
            a.extend(args);
            a
        }
    };
    match run_cargo(&args) {
        Ok(code) => ExitCode::from(code),
        Err(e) => {
            eprintln!("xtask: {e:#}");
            ExitCode::from(1)
        }
    }
}
