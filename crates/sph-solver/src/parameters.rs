//! [`SolverParameters`]: what every solver's parameters type says about itself, defined
//! once for the frame shell ([`SubstepScheme`](crate::SubstepScheme)) and the scene-facing
//! settings ([`SolverSettings`](crate::SolverSettings)).

use std::fmt;

use sph_core::Real;

use crate::{CommonParams, SolverError};

/// A solver's parameters in precision `R` (e.g. `PbfParams<R>`): the solver's name, the
/// parameters every solver has, the one range check and the conversion between precisions.
pub trait SolverParameters<R: Real>: Clone + fmt::Debug + PartialEq + Send {
    /// The same parameters in precision `S`.
    type In<S: Real>: SolverParameters<S>;

    /// The solver's name in errors and reports ([`SolverError::InvalidParameter`],
    /// [`SolverError::BlowUp`], [`FluidSolver::name`](crate::FluidSolver::name)): the one
    /// place each solver states it.
    const NAME: &'static str;

    /// The parameters every solver has (`common`).
    fn common(&self) -> &CommonParams<R>;

    /// Checks every parameter; the error ([`SolverError::InvalidParameter`]) names the first
    /// invalid one.
    fn validate(&self) -> Result<(), SolverError>;

    /// These parameters in precision `S`, each value rounded to nearest (an error names the
    /// first finite value that does not fit, [`crate::settings::convert`]).
    fn convert<S: Real>(&self) -> Result<Self::In<S>, SolverError>;
}
