//! The one frame loop of the workspace's scene runs: [`run_frames`] advances a
//! [`SceneSim`] and calls its [`FrameObserver`]s after each frame.

use sph_core::Real;
use sph_solver::StepStats;

use crate::error::SimError;
use crate::sim::SceneSim;

/// What a run will do, given to the observers when it starts.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RunPlan {
    /// The frame the run starts from (0, or the checkpoint's frame when resumed).
    pub first_frame: usize,
    /// The frame the run stops at (exclusive of nothing: the last frame advanced to).
    pub last_frame: usize,
    /// Whether the run continues from a checkpoint.
    pub resumed: bool,
}

impl RunPlan {
    /// Frames this run advances.
    pub fn frames(&self) -> usize {
        self.last_frame.saturating_sub(self.first_frame)
    }
}

/// Something that follows a run frame by frame: writes files, shows progress, renders.
/// Observers are called in the order given to [`run_frames`]; an observer's error stops
/// the run (the observers after it are not called for that frame).
pub trait FrameObserver<R: Real> {
    /// Once, before the first frame, with the simulation at `plan.first_frame`.
    fn start(&mut self, sim: &SceneSim<R>, plan: &RunPlan) -> Result<(), SimError> {
        let _ = (sim, plan);
        Ok(())
    }
    /// After each frame, with the frame's statistics (`sim.frame` is the frame just done).
    fn frame(&mut self, sim: &SceneSim<R>, stats: &StepStats) -> Result<(), SimError>;
    /// Once at the end, also when the run stopped on an error (`completed` is then false).
    fn finish(&mut self, sim: &SceneSim<R>, completed: bool) -> Result<(), SimError> {
        let _ = (sim, completed);
        Ok(())
    }
}

/// Advances `sim` to `plan.last_frame`, calling every observer after each frame. The first
/// error (a blow-up names the frame, step and particle; an observer's error names its
/// file) stops the run; every observer's `finish` is still called.
pub fn run_frames<R: Real>(
    sim: &mut SceneSim<R>,
    plan: &RunPlan,
    observers: &mut [&mut dyn FrameObserver<R>],
) -> Result<(), SimError> {
    let mut result = observers.iter_mut().try_for_each(|o| o.start(sim, plan));
    while result.is_ok() && sim.frame < plan.last_frame {
        result = sim
            .advance()
            .and_then(|stats| observers.iter_mut().try_for_each(|o| o.frame(sim, &stats)));
    }
    let completed = result.is_ok();
    for o in observers.iter_mut() {
        let finished = o.finish(sim, completed);
        if result.is_ok() {
            result = finished;
        }
    }
    result
}
