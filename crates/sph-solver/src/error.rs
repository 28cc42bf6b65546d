use neighbour_search::SearchError;
use sph_core::CoreError;
use sph_kernels::KernelError;

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
