//! `validation run [--full] [--only ID...] [--out DIR]` and `validation list`: the
//! experiments (scene runs, rendering and measuring are the `particles` command,
//! `particles-cli`).

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand};
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
}

/// `--out DIR`: refuses a path that exists and is not a directory (before any work).
fn output_dir(s: &str) -> Result<PathBuf, String> {
    let p = PathBuf::from(s);
    if p.exists() && !p.is_dir() {
        return Err("exists and is not a directory (give a directory for the output)".into());
    }
    Ok(p)
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
