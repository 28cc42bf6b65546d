//! The one frame loop of the workspace's scene runs: [`run_frames`] advances a
//! [`SceneSim`], builds each frame's [`FrameRecord`] and calls its [`FrameObserver`]s, and
//! returns how the run ended ([`RunOutcome`]).
//!
//! How a run ends is a value, as REBOUND's exit statuses are (Rein & Liu 2012, `reb_status`:
//! success, a user's stop, SIGINT, a collision …), here in Rust form: the run completed at
//! its last frame, an observer stopped it with a reason (e.g. the material came to rest),
//! the user interrupted it (Ctrl-C), or it diverged (the solver's blow-up names the frame,
//! step and particle; an observer may also judge a finite state diverged). A caller keeps
//! the outcome as a result; only real failures (an output file that cannot be written, a
//! solver refusing its state) are `Err`.

use sph_core::Real;
use sph_solver::SolverError;

use crate::error::SimError;
use crate::record::FrameRecord;
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

    /// A fresh run of `frames` frames from `sim`'s current frame.
    pub fn next<R: Real>(sim: &SceneSim<R>, frames: usize) -> Self {
        Self {
            first_frame: sim.frame,
            last_frame: sim.frame.saturating_add(frames),
            resumed: false,
        }
    }
}

/// What an observer tells the loop after a frame.
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum Flow {
    /// Go on to the next frame.
    Continue,
    /// Stop after this frame: what the observer waits for has happened (the reason is kept
    /// in [`Ending::Stopped`]).
    Stop(String),
    /// Stop after this frame: the user asked (Ctrl-C).
    Interrupt,
    /// Stop after this frame: the state is finite but no longer a simulation of the scene
    /// (the reason names the frame and quantity).
    Diverged(String),
}

/// Why a run diverged.
#[derive(Debug)]
#[non_exhaustive]
pub enum Divergence {
    /// The solver's blow-up: a [`SimError::Frame`] whose source is
    /// [`SolverError::BlowUp`], naming the frame, step and particle. The state holds the last
    /// completed substep.
    Solver(SimError),
    /// An observer's judgement ([`Flow::Diverged`]) at the end of a completed frame.
    Observed(String),
}

impl std::fmt::Display for Divergence {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Divergence::Solver(e) => write!(f, "{e}"),
            Divergence::Observed(reason) => f.write_str(reason),
        }
    }
}

impl Divergence {
    /// The solver's step and particle of a blow-up (`None` for an observer's judgement).
    pub fn step_and_particle(&self) -> Option<(u64, usize)> {
        match self.solver_error() {
            Some(SolverError::BlowUp { step, particle, .. }) => Some((*step, *particle)),
            _ => None,
        }
    }

    fn solver_error(&self) -> Option<&SolverError> {
        match self {
            Divergence::Solver(e) => e.solver_error(),
            Divergence::Observed(_) => None,
        }
    }

    /// The divergence as an error (the solver's [`SimError::Frame`], or the observer's
    /// reason as [`SimError::Invalid`]), for callers to which a divergence is a failure.
    pub fn into_error(self) -> SimError {
        match self {
            Divergence::Solver(e) => e,
            Divergence::Observed(reason) => SimError::Invalid(reason),
        }
    }
}

/// How a run ended.
#[derive(Debug)]
#[non_exhaustive]
pub enum Ending {
    /// The run reached its plan's last frame.
    Completed,
    /// An observer stopped it ([`Flow::Stop`]) with this reason.
    Stopped {
        /// The observer's reason.
        reason: String,
    },
    /// The user interrupted it ([`Flow::Interrupt`], Ctrl-C).
    Interrupted,
    /// It diverged.
    Diverged(Divergence),
}

impl Ending {
    /// `"completed"`, `"stopped"`, `"interrupted"` or `"diverged"`.
    pub fn name(&self) -> &'static str {
        match self {
            Ending::Completed => "completed",
            Ending::Stopped { .. } => "stopped",
            Ending::Interrupted => "interrupted",
            Ending::Diverged(_) => "diverged",
        }
    }

    /// The reason of a stop or a divergence (`None` for a completed or interrupted run).
    pub fn reason(&self) -> Option<String> {
        match self {
            Ending::Stopped { reason } => Some(reason.clone()),
            Ending::Diverged(d) => Some(d.to_string()),
            Ending::Completed | Ending::Interrupted => None,
        }
    }
}

/// The end of a run: how, and where the simulation stands.
#[derive(Debug)]
pub struct RunOutcome {
    /// How the run ended.
    pub ending: Ending,
    /// Frames done when it ended (`sim.frame`); a solver's blow-up happened in the frame
    /// after it.
    pub frame: usize,
    /// Simulated time at `frame` (s).
    pub time_s: f64,
}

impl RunOutcome {
    /// Whether the run reached its last frame.
    pub fn completed(&self) -> bool {
        matches!(self.ending, Ending::Completed)
    }

    /// The divergence, if the run diverged.
    pub fn divergence(&self) -> Option<&Divergence> {
        match &self.ending {
            Ending::Diverged(d) => Some(d),
            _ => None,
        }
    }

    /// The outcome, or its divergence as an error ([`Divergence::into_error`]): for callers
    /// to which a blow-up is a failure (the command line).
    pub fn diverged_as_error(self) -> Result<Self, SimError> {
        match self.ending {
            Ending::Diverged(d) => Err(d.into_error()),
            _ => Ok(self),
        }
    }
}

/// Something that follows a run frame by frame: writes files, shows progress, records,
/// decides that the run has reached what it waits for. Observers are called in the order
/// given to [`run_frames`], each of them after every completed frame; the first
/// non-[`Flow::Continue`] answer of a frame ends the run after that frame. An observer's
/// error stops the run at once (the observers after it are not called for that frame).
pub trait FrameObserver<R: Real> {
    /// Once, before the first frame, with the simulation at `plan.first_frame`.
    fn start(&mut self, sim: &SceneSim<R>, plan: &RunPlan) -> Result<(), SimError> {
        let _ = (sim, plan);
        Ok(())
    }
    /// After each frame, with the frame's record (`sim.frame` is the frame just done).
    fn frame(&mut self, sim: &SceneSim<R>, record: &FrameRecord) -> Result<Flow, SimError>;
    /// Once at the end, with the outcome (`None` when the run failed with an error).
    fn finish(&mut self, sim: &SceneSim<R>, outcome: Option<&RunOutcome>) -> Result<(), SimError> {
        let _ = (sim, outcome);
        Ok(())
    }
}

/// Advances `sim` to `plan.last_frame`, building each frame's [`FrameRecord`] and calling
/// every observer after each frame, until the plan's last frame, an observer's stop
/// ([`Flow`]) or a divergence; returns how the run ended. A solver's blow-up is
/// [`Ending::Diverged`] (the state holds its last completed substep); any other error (an
/// observer's file, a solver error that is not a blow-up) is returned as `Err`. Every
/// observer's `finish` is called in all cases; its error is returned if the run had none.
pub fn run_frames<R: Real>(
    sim: &mut SceneSim<R>,
    plan: &RunPlan,
    observers: &mut [&mut dyn FrameObserver<R>],
) -> Result<RunOutcome, SimError> {
    let mut ending: Result<Option<Ending>, SimError> = observers
        .iter_mut()
        .try_for_each(|o| o.start(sim, plan))
        .map(|()| None);
    while let Ok(None) = ending {
        if sim.frame >= plan.last_frame {
            ending = Ok(Some(Ending::Completed));
            break;
        }
        ending = match sim.advance() {
            Ok(stats) => {
                let record = FrameRecord::new(sim, &stats);
                observe_frame(sim, &record, observers)
            }
            Err(e) if matches!(e.solver_error(), Some(SolverError::BlowUp { .. })) => {
                Ok(Some(Ending::Diverged(Divergence::Solver(e))))
            }
            Err(e) => Err(e),
        };
    }
    let mut outcome = ending.map(|e| RunOutcome {
        ending: e.unwrap_or(Ending::Completed),
        frame: sim.frame,
        time_s: sim.time_s,
    });
    for o in observers.iter_mut() {
        let finished = o.finish(sim, outcome.as_ref().ok());
        if let (Ok(_), Err(e)) = (&outcome, finished) {
            outcome = Err(e);
        }
    }
    outcome
}

/// Every observer's answer to one frame: the first that is not [`Flow::Continue`] ends the
/// run, after all observers have seen the frame.
fn observe_frame<R: Real>(
    sim: &SceneSim<R>,
    record: &FrameRecord,
    observers: &mut [&mut dyn FrameObserver<R>],
) -> Result<Option<Ending>, SimError> {
    let mut ending = None;
    for o in observers.iter_mut() {
        let flow = o.frame(sim, record)?;
        if ending.is_none() {
            ending = match flow {
                Flow::Continue => None,
                Flow::Stop(reason) => Some(Ending::Stopped { reason }),
                Flow::Interrupt => Some(Ending::Interrupted),
                Flow::Diverged(reason) => Some(Ending::Diverged(Divergence::Observed(reason))),
            };
        }
    }
    Ok(ending)
}
