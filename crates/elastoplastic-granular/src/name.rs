//! The solver's name in errors and reports: a leaf module every other module may import.

/// Name of the solver in errors and reports (its [`sph_solver::SolverParameters::NAME`]).
pub(crate) const NAME: &str = "elastoplastic";
