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

/// Implements [`SolverParameters`] for a solver's parameters type `$Params<R>` named
/// `$name`: `common` is its field `common`, `validate` and `convert` are its inherent
/// `validate` and `try_convert` (e.g. `sph_solver::solver_parameters!(PbfParams, NAME);`).
#[macro_export]
macro_rules! solver_parameters {
    ($Params:ident, $name:expr) => {
        impl<R: $crate::Real> $crate::SolverParameters<R> for $Params<R> {
            type In<S: $crate::Real> = $Params<S>;
            const NAME: &'static str = $name;

            fn common(&self) -> &$crate::CommonParams<R> {
                &self.common
            }

            fn validate(&self) -> Result<(), $crate::SolverError> {
                $Params::validate(self)
            }

            fn convert<S: $crate::Real>(&self) -> Result<$Params<S>, $crate::SolverError> {
                self.try_convert()
            }
        }
    };
}
