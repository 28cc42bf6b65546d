use neighbour_search::SearchError;
use sph_core::CoreError;
use sph_kernels::KernelError;

use sph_core::Real;

use crate::scene_boundary::feature::BoundaryFeature;

/// Why a volume-map file was refused (in [`SolverError::MapFile`]).
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum MapFileProblem {
    /// The file could not be read, written or renamed.
    #[error("{operation} failed: {message}")]
    Io {
        /// What was attempted (`"read"`, `"create"`, `"write"`, `"sync"`, `"rename"`).
        operation: &'static str,
        /// The operating system's message.
        message: String,
    },
    /// The file does not start with the volume-map magic bytes.
    #[error("not a volume map file (bad magic bytes)")]
    BadMagic,
    /// The file was written by another version of the format.
    #[error("format version {found}, this build reads only version {supported}")]
    UnsupportedVersion {
        /// Version in the file.
        found: u32,
        /// Version this build reads and writes.
        supported: u32,
    },
    /// The file is shorter than its header says (an interrupted copy).
    #[error("truncated: {found} bytes, its header announces {expected}")]
    Truncated {
        /// Bytes the header announces.
        expected: u64,
        /// Bytes in the file.
        found: u64,
    },
    /// The file is longer than its header says.
    #[error("{found} bytes, its header announces {expected} (trailing data)")]
    TrailingBytes {
        /// Bytes the header announces.
        expected: u64,
        /// Bytes in the file.
        found: u64,
    },
    /// The SHA-256 checksum of the contents does not match: the file is corrupt.
    #[error("checksum mismatch: the contents are corrupt")]
    ChecksumMismatch,
    /// The map in the file was built for other inputs (solid, kernel, support radius,
    /// domain, options or precision) than those asked for.
    #[error(
        "built for other inputs (solid, kernel, support radius, domain, options or precision)"
    )]
    ForeignKey,
    /// The contents pass the checksum but are inconsistent (a writer bug or a crafted file).
    #[error("malformed contents: {0}")]
    Malformed(&'static str),
}

/// Errors of the particle solvers. Each names the offending solver parameter or particle.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum SolverError {
    /// A parameter of a solver (or of a boundary) is out of its valid range.
    #[error("invalid {solver} parameter {name} = {value}: {reason}")]
    InvalidParameter {
        /// Which solver or component: `"PBF"`, `"PCISPH"`, `"boundary"`, ….
        solver: &'static str,
        /// Name of the field, e.g. `"support_radius"`.
        name: &'static str,
        /// The offending value, widened to `f64` (a count is converted as is).
        value: f64,
        /// Why it is rejected.
        reason: &'static str,
    },
    /// The scene asks for a boundary feature the solver does not take
    /// ([`SolverSettings::take_scene_boundary`](crate::SolverSettings::take_scene_boundary)).
    #[error("solver {solver} does not take {}", feature.scene_key())]
    UnsupportedFeature {
        /// Which solver.
        solver: &'static str,
        /// The feature, with its scene key ([`BoundaryFeature::scene_key`]).
        feature: BoundaryFeature,
    },
    /// The particle state given to the solver is invalid (array lengths, non-finite position
    /// or velocity); the inner error names the particle and axis.
    #[error("invalid particle state: {0}")]
    InvalidState(#[from] CoreError),
    /// A particle mass is zero, negative or not finite.
    #[error("particle {index}: mass {value} must be finite and > 0")]
    InvalidMass {
        /// Index of the particle.
        index: usize,
        /// The offending mass, widened to `f64`.
        value: f64,
    },
    /// A kernel could not be built for the support radius.
    #[error(transparent)]
    Kernel(#[from] KernelError),
    /// The neighbour search failed for a reason other than the solver's own positions
    /// running away (those are reported as [`SolverError::BlowUp`]).
    #[error("neighbour search: {0}")]
    NeighbourSearch(#[from] SearchError),
    /// A boundary could not be built (e.g. a volume map grid too large for the domain).
    #[error("boundary: {0}")]
    Boundary(String),
    /// A long construction was cancelled through its cancellation flag (Ctrl-C): nothing
    /// of it was kept.
    #[error("{what}: cancelled")]
    Cancelled {
        /// What was being built (`"solid 1: volume map"`).
        what: String,
    },
    /// A volume-map file (see `boundary::volume_map::VolumeMapCache`) was refused: nothing
    /// of it was loaded.
    #[error("volume map file {}: {problem}", path.display())]
    MapFile {
        /// The file.
        path: std::path::PathBuf,
        /// Why it was refused.
        problem: MapFileProblem,
    },
    /// The simulation diverged during call number `step` (0-based count of
    /// [`crate::FluidSolver::step`] calls): a non-finite predicted or final position or
    /// velocity, or a particle that ended more than one support radius inside a solid. The
    /// particle state is left as it was after the last completed substep; no non-finite value
    /// is written to it.
    #[error("{solver} blow-up in step {step} at particle {particle}: {reason}")]
    BlowUp {
        /// The solver's name.
        solver: &'static str,
        /// 0-based index of the `step` call that diverged.
        step: u64,
        /// Index of the first offending particle (in the state's current order).
        particle: usize,
        /// What was detected (substep, quantity and value).
        reason: String,
    },
    /// A saved [`crate::SolverState`] does not fit the solver it is restored into (another
    /// solver, or arrays whose names or lengths do not fit the particle count).
    #[error("cannot restore the state into {solver}: {reason}")]
    InvalidSolverState {
        /// The solver restoring the state ([`crate::FluidSolver::name`]).
        solver: String,
        /// What does not fit.
        reason: String,
    },
}

impl SolverError {
    /// [`SolverError::InvalidParameter`]: `solver`'s parameter `name` = `value`, refused for
    /// `reason`.
    pub fn invalid(
        solver: &'static str,
        name: &'static str,
        value: f64,
        reason: &'static str,
    ) -> Self {
        SolverError::InvalidParameter {
            solver,
            name,
            value,
            reason,
        }
    }

    /// `Ok` when `v` (parameter `name` of `solver`) is finite and `>= 0`, else
    /// [`SolverError::InvalidParameter`] ("must be finite and >= 0").
    pub fn non_negative<R: Real>(
        solver: &'static str,
        name: &'static str,
        v: R,
    ) -> Result<(), SolverError> {
        if v.is_finite_value() && v >= R::zero() {
            Ok(())
        } else {
            Err(Self::invalid(
                solver,
                name,
                v.as_f64(),
                "must be finite and >= 0",
            ))
        }
    }
}
