//! Workspace automation (`cargo xtask <command>`, alias in `.cargo/config.toml`).
//!
//! - `cargo xtask validate [--full] [--only ID...] [--out DIR]` — builds the `validation`
//!   crate in release and runs the experiments (`validation run ...`); exit code 1 when any
//!   check fails or an experiment errors.
//! - `cargo xtask list` — the experiments and the paper figure each reproduces.
//! - `cargo xtask run SCENE [--quick] [--frames N] [--out DIR] [--render]
//!   [--checkpoint-every N] [--resume]`, `cargo xtask render DIR …`, `cargo xtask repose DIR …`,
//!   `cargo xtask comets POPULATION.toml [--out DIR]`
//!   — build the command-line crate `particles-cli` in release and run `particles run|render|
//!   repose ARGS...` from the directory the command was typed in (see `particles --help`).
//! - `cargo xtask bench [ARGS...]` — `cargo bench -p benches -- ARGS...` (criterion).
//! - `cargo xtask package-check [--tests]` — packages every published crate, unpacks the
//!   tarballs and builds and runs each crate's README example against them as a user's
//!   project would ([`package_check`]); `--tests` also runs the packaged crates' tests.
//!
//! Deliberately light: clap + anyhow + std. Cargo is the one running this (`$CARGO`).

use std::ffi::OsString;
use std::path::{Path, PathBuf};
use std::process::{Command, ExitCode};

mod package_check;

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
    /// Run a scene file (`particles run`): VTK frames, `stats.csv`, checkpoints
    /// (`--checkpoint-every N`, `--resume`), rendered frames (`--render`). See
    /// `cargo xtask run --help`.
    #[command(disable_help_flag = true)]
    Run {
        /// Arguments of `particles run` (paths relative to where you typed the command).
        #[arg(
            trailing_var_arg = true,
            allow_hyphen_values = true,
            value_name = "ARGS"
        )]
        args: Vec<OsString>,
    },
    /// Render an earlier run's VTK frames to PNG (`particles render`).
    #[command(disable_help_flag = true)]
    Render {
        /// Arguments of `particles render`.
        #[arg(
            trailing_var_arg = true,
            allow_hyphen_values = true,
            value_name = "ARGS"
        )]
        args: Vec<OsString>,
    },
    /// A population study of comets among the planets (`particles comets POPULATION.toml
    /// [--out DIR]`): Parquet snapshots and final table, checkpoints; rerun to resume.
    #[command(disable_help_flag = true)]
    Comets {
        /// Arguments of `particles comets`.
        #[arg(
            trailing_var_arg = true,
            allow_hyphen_values = true,
            value_name = "ARGS"
        )]
        args: Vec<OsString>,
    },
    /// The angle of repose of a granular run's last frame (`particles repose`).
    #[command(disable_help_flag = true)]
    Repose {
        /// Arguments of `particles repose`.
        #[arg(
            trailing_var_arg = true,
            allow_hyphen_values = true,
            value_name = "ARGS"
        )]
        args: Vec<OsString>,
    },
    /// Package the published crates and build and run each README example against the
    /// tarballs, as a user's project outside the workspace (`--tests`: also the packaged
    /// crates' own tests).
    PackageCheck {
        /// Also run the unpacked crates' tests (many minutes).
        #[arg(long)]
        tests: bool,
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
fn run_cargo(args: &[OsString], in_dir: &Path) -> Result<u8> {
    let root = in_dir;
    let status = Command::new(cargo())
        .args(args)
        .current_dir(root)
        .status()
        .with_context(|| format!("running cargo {args:?} in {}", root.display()))?;
    Ok(match status.code() {
        Some(0) => 0,
        Some(code) => u8::try_from(code).unwrap_or(1).max(1),
        None => 1, // killed by a signal
    })
}

/// `cargo run --release -p particles-cli -- COMMAND ARGS...`, run from the directory the
/// user typed the command in (so relative paths mean what they typed), with the default
/// output under the workspace's `target/`.
fn particles(command: &str, args: Vec<OsString>) -> Vec<OsString> {
    let manifest = workspace_root().join("Cargo.toml");
    let mut a = os(&["run", "--release", "--quiet", "--manifest-path"]);
    a.push(manifest.into_os_string());
    a.extend(os(&["-p", "particles-cli", "--", command]));
    a.extend(args);
    a
}

fn os(args: &[&str]) -> Vec<OsString> {
    args.iter().map(OsString::from).collect()
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    // The scene commands run where the user typed them (their relative paths); the others
    // from the workspace root.
    let dir = match &cli.command {
        Task::Run { .. } | Task::Render { .. } | Task::Repose { .. } | Task::Comets { .. } => {
            std::env::current_dir().unwrap_or_else(|_| workspace_root())
        }
        _ => workspace_root(),
    };
    if let Task::PackageCheck { tests } = cli.command {
        return match package_check::run(tests) {
            Ok(()) => ExitCode::SUCCESS,
            Err(e) => {
                eprintln!("xtask package-check: {e:#}");
                ExitCode::from(1)
            }
        };
    }
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
        Task::Run { args } => particles("run", args),
        Task::Render { args } => particles("render", args),
        Task::Repose { args } => particles("repose", args),
        Task::Comets { args } => particles("comets", args),
        Task::List => os(&["run", "--release", "-p", "validation", "--", "list"]),
        Task::PackageCheck { .. } => unreachable!("handled above"),
        Task::Bench { args } => {
            let mut a = os(&["bench", "-p", "benches", "--"]);
            a.extend(args);
            a
        }
    };
    match run_cargo(&args, &dir) {
        Ok(code) => ExitCode::from(code),
        Err(e) => {
            eprintln!("xtask: {e:#}");
            ExitCode::from(1)
        }
    }
}
