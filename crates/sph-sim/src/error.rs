use std::path::PathBuf;

use sph_scene::SceneError;
use sph_solver::SolverError;

/// Errors of running a scene. Each names the scene file (or output path) and what failed.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum SimError {
    /// The scene file is invalid or its geometry cannot be built.
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// The solver or its boundary refused the scene's parameters.
    #[error("{file}: {source}")]
    Setup {
        /// The scene file.
        file: String,
        /// What the solver said.
        source: SolverError,
    },
    /// The simulation failed during a frame (a blow-up names the step and particle).
    #[error("{file}: frame {frame} (t = {time_s:.4} s): {source}")]
    Frame {
        /// The scene file.
        file: String,
        /// 0-based frame that failed.
        frame: usize,
        /// Simulated time at its start (s).
        time_s: f64,
        /// What the solver said.
        source: SolverError,
    },
    /// A request that cannot be run (e.g. zero frames), with the reason.
    #[error("{0}")]
    Invalid(String),
    /// An input file (a VTK frame, a checkpoint, a run directory) is missing, unreadable,
    /// corrupt or foreign.
    #[error("{path}: {reason}")]
    Input {
        /// The path.
        path: PathBuf,
        /// What is wrong with it.
        reason: String,
    },
    /// An output path could not be created or written.
    #[error("{path}: {reason}")]
    Output {
        /// The path.
        path: PathBuf,
        /// Why (the system's message, or "is not a directory").
        reason: String,
    },
}

impl SimError {
    /// A [`SimError::Output`] for `path`.
    pub fn output(path: impl Into<PathBuf>, reason: impl ToString) -> Self {
        SimError::Output {
            path: path.into(),
            reason: reason.to_string(),
        }
    }

    /// A [`SimError::Input`] for `path`.
    pub fn input(path: impl Into<PathBuf>, reason: impl ToString) -> Self {
        SimError::Input {
            path: path.into(),
            reason: reason.to_string(),
        }
    }

    /// The solver error behind a [`SimError::Frame`] or [`SimError::Setup`], if any.
    pub fn solver_error(&self) -> Option<&SolverError> {
        match self {
            SimError::Frame { source, .. } | SimError::Setup { source, .. } => Some(source),
            _ => None,
        }
    }
}

impl From<sph_core::CoreError> for SimError {
    /// An input file refused by `sph_core::input` becomes [`SimError::Input`] with its path;
    /// any other core error is [`SimError::Invalid`].
    fn from(e: sph_core::CoreError) -> Self {
        match e {
            sph_core::CoreError::Input { path, reason } => SimError::Input { path, reason },
            other => SimError::Invalid(other.to_string()),
        }
    }
}
