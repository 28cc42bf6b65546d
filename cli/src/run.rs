//! `particles run SCENE`: a scene run with its observers ([`sph_sim::run_scene`]).

use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

use anyhow::{Context, Result};
use sph_scene::Override;
use sph_sim::observe::RestCriterion;
use sph_sim::{run_scene, SceneRunOptions};

/// Arguments of `particles run`.
#[derive(Debug, clap::Args)]
pub struct RunArgs {
    /// The scene file (TOML).
    scene: PathBuf,
    /// Apply the scene's `[quick]` overrides (fewer particles, shorter).
    #[arg(long)]
    quick: bool,
    /// Stop at this frame (>= 1) [default: the scene's duration].
    #[arg(long, value_name = "N", value_parser = frame_count, allow_hyphen_values = true)]
    frames: Option<usize>,
    /// Output directory [default: target/scenes/STEM under the current directory, STEM the scene file name without .toml].
    #[arg(long, value_name = "DIR", value_parser = crate::directory)]
    out: Option<PathBuf>,
    /// Also render the frames (PNG in OUT/render) in process while the scene runs.
    #[arg(long)]
    render: bool,
    /// Write an atomic checkpoint (OUT/checkpoint.sphck) every N frames and at the end
    /// (0: none).
    #[arg(long, value_name = "N", default_value_t = 25)]
    checkpoint_every: usize,
    /// Directory of cached volume maps, reused by later runs
    /// [default: target/cache/volume-maps under the current directory].
    #[arg(long, value_name = "DIR", value_parser = crate::directory)]
    cache: Option<PathBuf>,
    /// Build volume maps afresh and keep none.
    #[arg(long, conflicts_with = "cache")]
    no_cache: bool,
    /// Continue from OUT's checkpoint: the frames and statistics come out bit-identical to
    /// an uninterrupted run's (but for the wall-clock columns). The overrides recorded in
    /// OUT apply (a --set given must repeat them).
    #[arg(long)]
    resume: bool,
    /// Override a key of the scene file by its dotted path, e.g. `--set
    /// solver.friction_angle_deg=40 --set fluid[0].max=[0.5,0.3,0.1]` (VALUE is TOML; a bare
    /// word is a string); checked as the file is, and recorded in OUT so that `render`,
    /// `repose` and `--resume` see the same scene. Repeatable; applied in order, before
    /// `--quick`'s overrides.
    #[arg(long = "set", value_name = "KEY=VALUE", value_parser = Override::parse)]
    set: Vec<Override>,
    /// Stop once the material is at rest (crate granular-measure's criterion: the
    /// 99th-percentile speed and the fastest particle two spacings below the surface under
    /// 0.05 sqrt(g s) for 0.5 s, the heap's angle moving less than 0.3° over 1 s), the
    /// scene's duration then a cap. The heap's angle is taken as a planar heap (profile
    /// along x) or, with `--until-rest conical`, a pile around its centroid. The samples go
    /// to OUT/rest_samples.csv and the verdict to OUT/rest.json.
    #[arg(long, value_name = "SHAPE", value_enum, num_args = 0..=1, default_missing_value = "planar")]
    until_rest: Option<crate::repose::Shape>,
}

/// `--frames N`: a whole number >= 1.
fn frame_count(s: &str) -> Result<usize, String> {
    match s.parse::<usize>() {
        Ok(0) => Err("0 frames would run nothing (give at least 1)".into()),
        Ok(n) => Ok(n),
        Err(e) => Err(format!("not a whole number of frames >= 1 ({e})")),
    }
}

/// Runs `particles run`.
pub fn run(a: &RunArgs) -> Result<()> {
    let stem = a
        .scene
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "scene".into());
    // Ctrl-C stops the volume maps' build, or the run after its frame (its checkpoint
    // written: `--resume` goes on from it); a second one ends the process at once.
    let cancel = Arc::new(AtomicBool::new(false));
    let flag = cancel.clone();
    ctrlc::set_handler(move || {
        if flag.swap(true, Ordering::Relaxed) {
            std::process::exit(130);
        }
    })
    .context("installing the Ctrl-C handler")?;
    let opts = SceneRunOptions {
        quick: a.quick,
        out_dir: a
            .out
            .clone()
            .unwrap_or_else(|| PathBuf::from("target").join("scenes").join(stem)),
        max_frames: a.frames,
        progress: true,
        checkpoint_every: (a.checkpoint_every > 0).then_some(a.checkpoint_every),
        resume: a.resume,
        render: a.render,
        volume_map_cache: (!a.no_cache).then(|| {
            a.cache
                .clone()
                .unwrap_or_else(|| PathBuf::from("target").join("cache").join("volume-maps"))
        }),
        overrides: a.set.clone(),
        until_rest: a.until_rest.map(|shape| RestCriterion {
            shape: shape.pile(),
            ..RestCriterion::default()
        }),
        cancel: Some(cancel.clone()),
    };
    // A blow-up fails the command (exit status 1) with the solver's message naming the
    // frame, step and particle.
    let outcome = run_scene(&a.scene, &opts)?;
    if matches!(outcome.ending, sph_sim::Ending::Interrupted) {
        let resume = match opts.checkpoint_every {
            Some(_) => ": run the same command with --resume to go on from its checkpoint",
            None => " (no checkpoint: --checkpoint-every 0)",
        };
        anyhow::bail!("interrupted (Ctrl-C) at frame {}{resume}", outcome.frame);
    }
    outcome.diverged_as_error()?;
    Ok(())
}
