//! The shared layer of the workspace's particle solvers (work in progress: boundaries and
//! errors first).

pub mod boundary;
mod error;

pub use boundary::{
    half_space_volume, half_space_volume_derivative, Boundary, BoundarySample, ClosestPoint,
    CollisionBoundary, Interpolation, VolumeMap, VolumeMapBoundary, VolumeMapOptions,
    VolumeMapStats,
};
pub use error::SolverError;
