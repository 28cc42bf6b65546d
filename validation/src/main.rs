//! `validation run [--full] [--only ID...] [--out DIR]`, `validation list` and
//! `validation scene PATH [--quick] [--frames N] [--out DIR]`.

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand};
use sph_sim::{run_scene, SceneRunOptions};
use validation::runner::{self, RunOptions};
use validation::{registry, workspace_root, Mode};

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
    },
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
            match run_scene(&path, &opts) {
                Ok(()) => ExitCode::SUCCESS,
                Err(e) => {
                    eprintln!("error: {e:#}");
                    ExitCode::from(1)
                }
            }
        }
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
