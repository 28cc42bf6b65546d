//! The simulation of a scene and its frame loop as the experiments use them: volume maps
//! from the experiments' cache, the progress bar ticked once a frame; scene running itself is
//! the `sph-sim` crate.

use anyhow::Result;
use sph_scene::Scene;

use sph_sim::observe::OnFrame;
pub use sph_sim::SceneSim;
use sph_sim::{Flow, FrameObserver, FrameRecord, RunOutcome, RunPlan};

use crate::{workspace_root, Context};

/// The volume-map cache of the experiments, `target/cache/volume-maps` under the workspace
/// root (shared with `particles run`'s default when run from the root): a map built by one
/// experiment (or an earlier validation) is loaded by the next that needs it.
pub fn volume_map_cache() -> Result<sph_solver::boundary::VolumeMapCache> {
    let dir = workspace_root()
        .join("target")
        .join("cache")
        .join("volume-maps");
    Ok(sph_solver::boundary::VolumeMapCache::new(dir)?)
}

/// The simulation of `scene` in precision `R`, its volume maps from the experiments' cache
/// ([`volume_map_cache`]).
pub fn scene_sim<R: sph_core::Real>(scene: &Scene) -> Result<SceneSim<R>> {
    Ok(SceneSim::with_cache(scene, Some(&volume_map_cache()?))?)
}

/// Advances `sim` by `frames` frames through the one frame loop
/// ([`sph_sim::run_frames`]) with `observers`, ticking the experiment's progress bar once a
/// frame (and the frames left when the run ended early); returns how the run ended (a
/// blow-up is [`sph_sim::Ending::Diverged`], kept as a result).
pub fn run_frames<R: sph_core::Real>(
    ctx: &Context,
    sim: &mut SceneSim<R>,
    frames: usize,
    observers: &mut [&mut dyn FrameObserver<R>],
) -> Result<RunOutcome> {
    let plan = RunPlan::next(sim, frames);
    let mut tick = OnFrame(|_: &SceneSim<R>, _: &FrameRecord| {
        ctx.progress.inc(1);
        Flow::Continue
    });
    let mut all: Vec<&mut dyn FrameObserver<R>> = Vec::with_capacity(observers.len() + 1);
    for o in observers.iter_mut() {
        all.push(&mut **o);
    }
    all.push(&mut tick);
    let outcome = sph_sim::run_frames(sim, &plan, &mut all)?;
    ctx.progress
        .inc(plan.last_frame.saturating_sub(outcome.frame) as u64);
    Ok(outcome)
}

/// Advances `sim` by `frames` frames through the one frame loop ([`run_frames`], with
/// `observers`), a divergence being an error (the solver's, naming the frame, step and
/// particle): for experiments whose scenes must not blow up.
pub fn advance_frames<R: sph_core::Real>(
    ctx: &Context,
    sim: &mut SceneSim<R>,
    frames: usize,
    observers: &mut [&mut dyn FrameObserver<R>],
) -> Result<()> {
    run_frames(ctx, sim, frames, observers)?.diverged_as_error()?;
    Ok(())
}
