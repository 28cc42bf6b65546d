//! `particles`: the workspace's command line (`cargo xtask run|render|repose …` forward to
//! it).
//!
//! - `particles run SCENE [--quick] [--frames N] [--out DIR] [--render]
//!   [--checkpoint-every N] [--resume] [--set KEY=VALUE]... [--until-rest [planar|conical]]`:
//!   runs a scene file, its keys overridden, to its end or until the material is at rest:
//!   VTK frames, `stats.csv`, rendered frames, checkpoints, the rest verdict
//!   ([`sph_sim::run_scene`]);
//! - `particles render DIR [--scene SCENE] [--quick] [--out DIR]`: renders an earlier run's
//!   VTK frames to PNG;
//! - `particles comets POPULATION.toml [--out DIR]`: a population study of test particles
//!   among the planets: Parquet snapshots and final table, checkpoints, resume;
//! - `particles repose DIR [--frame FILE] [--shape planar|conical]`: the angle of repose of a
//!   granular run's last frame.

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand};

mod comets;
mod render;
mod repose;
mod run;

#[derive(Parser)]
#[command(
    name = "particles",
    version,
    about = "Particle simulation from four papers: run scenes, render and measure them"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run a scene file: VTK frames, per-frame statistics, checkpoints, rendered frames.
    Run(run::RunArgs),
    /// Render the VTK frames of an earlier run (`frame_*.vtk` in DIR) to PNG images.
    Render(render::RenderArgs),
    /// Measure the angle of repose of a granular run's last frame (or `--frame FILE`).
    Repose(repose::ReposeArgs),
    /// Integrate a population of comets among the planets (TOML specification): Parquet
    /// snapshots and final table, checkpoints; rerun the same command to resume.
    Comets(comets::CometsArgs),
}

/// `--out DIR` and run directories: refuses a path that exists and is not a directory.
pub(crate) fn directory(s: &str) -> Result<PathBuf, String> {
    let p = PathBuf::from(s);
    if p.exists() && !p.is_dir() {
        return Err("exists and is not a directory (give a directory for the output)".into());
    }
    Ok(p)
}

/// The error and its causes, `outer: inner`, each cause left out when the message before
/// it already says it (library errors that print their source in their own message).
fn error_chain(e: &anyhow::Error) -> String {
    let mut text = String::new();
    for cause in e.chain() {
        let message = cause.to_string();
        if !text.contains(&message) {
            if !text.is_empty() {
                text.push_str(": ");
            }
            text.push_str(&message);
        }
    }
    text
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Run(a) => run::run(&a),
        Command::Render(a) => render::run(&a),
        Command::Repose(a) => repose::run(&a),
        Command::Comets(a) => comets::run(&a),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {}", error_chain(&e));
            ExitCode::from(1)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::error_chain;

    #[test]
    fn a_cause_the_message_already_says_is_printed_once() {
        /// An error that prints its source in its own message, and names it as its source.
        #[derive(Debug)]
        struct Outer {
            source: std::io::Error,
        }
        impl std::fmt::Display for Outer {
            fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                write!(f, "frame 3: {}", self.source)
            }
        }
        impl std::error::Error for Outer {
            fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
                Some(&self.source)
            }
        }
        let inner = std::io::Error::other("blow-up at particle 4");
        let e = anyhow::Error::new(Outer { source: inner }).context("scene.toml");
        assert_eq!(
            error_chain(&e),
            "scene.toml: frame 3: blow-up at particle 4"
        );
        let plain = anyhow::anyhow!("no such file").context("reading a.toml");
        assert_eq!(error_chain(&plain), "reading a.toml: no such file");
    }
}
