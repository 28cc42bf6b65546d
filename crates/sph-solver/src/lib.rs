//! The shared layer of the workspace's particle solvers (work in progress: boundaries and
//! errors first).

pub mod boundary;
mod error;

pub use boundary::{Boundary, BoundarySample, ClosestPoint, CollisionBoundary};
pub use error::SolverError;
