#![doc = include_str!("../README.md")]
//!
//! ## In detail
//!
//! Shared foundation of the particle-simulation workspace.
//!
//! Everything numeric in the workspace is generic over [`Real`] (implemented for `f32` and
//! `f64`; the precision is chosen by the caller's type, at run time if the caller dispatches,
//! never by a cargo feature). This crate owns:
//!
//! - [`Real`] and the vector aliases [`Vec3`], [`Vec2`] (nalgebra),
//! - [`ParticleSet`], a structure-of-arrays particle container with an allocation-free
//!   [`ParticleSet::permute`] used to keep particles sorted by cell,
//! - [`Aabb`], an axis-aligned box,
//! - the signed-distance-field trait [`Sdf`] with analytic [`Plane`], [`BoxSdf`], [`Sphere`],
//!   [`CylinderSdf`] and the complement [`Inverted`] (a tank is `Inverted<BoxSdf>`),
//! - [`SampledGrid`], a scalar field sampled on a regular grid with trilinear interpolation
//!   (module [`grid`]),
//! - [`TriangleMesh`] and its sampled signed distance [`GridSdf`] (module [`mesh`]),
//! - [`random::SplitMix64`], a small seeded generator for reproducible point sets,
//! - [`memory::available_bytes`], the memory a process may still allocate,
//! - [`CoreError`], the crate's error enum.

mod aabb;
pub mod disk;
mod error;
pub mod grid;
pub mod input;
pub mod memory;
pub mod mesh;
mod particles;
pub mod random;
mod real;
pub mod sampling;
mod sdf;
mod sdf_cylinder;

pub use aabb::Aabb;
pub use error::CoreError;
pub use grid::SampledGrid;
pub use mesh::{GridSdf, MeshError, TriangleMesh};
pub use particles::{
    apply_permutation, validate_finite_positions, ParticleSet, PermutationScratch,
};
pub use real::Real;
pub use sdf::{push_fingerprint, BoxSdf, Inverted, Plane, Sdf, Sphere};
pub use sdf_cylinder::CylinderSdf;

/// A 3D column vector of [`Real`] (nalgebra).
pub type Vec3<R> = nalgebra::Vector3<R>;
/// A 2D column vector of [`Real`] (nalgebra).
pub type Vec2<R> = nalgebra::Vector2<R>;
