//! Walls as a scene states them: each solid's [`WallModel`] and the [`MovingWall`]s.

use sph_core::{Aabb, Real, Vec3};

/// Largest wall friction coefficient `μ_w` of [`WallModel::Coulomb`] accepted: 10, a wall
/// friction angle of 84°, past any measured wall–grain pair (a rough wall is `NoSlip`).
pub const MAX_WALL_FRICTION: f64 = 10.0;
/// Longest motion of a moving wall accepted (s): a year, past any run.
pub const MAX_WALL_MOTION_S: f64 = 3.2e7;

/// How a solid acts on the particles next to it (in scene files `wall = "free-slip"`,
/// `"no-slip"` or `{ coulomb = 0.4 }` on `[tank]` and each `[[solid]]`).
///
/// The model names what the wall does to the particles' velocity and stress; a solver that
/// takes walls per solid ([`BoundaryFeatures::wall_models`](super::BoundaryFeatures))
/// documents its terms (crate `elastoplastic-granular`: volume-map walls in its module
/// `walls`, boundary particles in its module `boundary_particles`).
#[derive(Debug, Clone, Copy, PartialEq, serde::Deserialize)]
#[serde(rename_all = "kebab-case", deny_unknown_fields)]
pub enum WallModel {
    /// Only the normal part of the wall traction and of the velocity difference: grains
    /// slide along the wall without resistance (plane-strain slab walls).
    FreeSlip,
    /// The whole traction; the wall's velocity enters the velocity gradient.
    NoSlip,
    /// Coulomb friction with coefficient `μ_w` (the value, `0 ≤ μ_w ≤`
    /// [`MAX_WALL_FRICTION`]): the tangential traction the wall takes is at most `μ_w`
    /// times the compressive normal one (walls of boundary particles only).
    Coulomb(f64),
    /// The solid only keeps the particles out (projection to the contact distance); its
    /// share of the sums comes from boundary particles set apart from it.
    #[serde(skip)]
    ContactOnly,
}

/// A wall of boundary particles that moves at a constant velocity from the start of the run
/// for `duration_s` and then stands still (in scene files a `[[solid]]` box with a
/// `motion`): the nodes of the particle lattice (that of
/// [`SceneBoundary::boundary_particle_region`](super::SceneBoundary)) inside the box
/// `region` near its faces, each with the model `model` and the wall velocity `velocity`
/// while the wall moves. A solver that takes moving walls says how many rows it samples and
/// when exactly it stops the wall (crate `elastoplastic-granular`: at the explicit step
/// nearest `duration_s`, on a clock that checkpoints carry).
///
/// A moving wall is not a solid of the solver's boundary: nothing but its particles keeps
/// grains out of it (the collision boundary's contact projection is for solids that stand
/// still).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MovingWall<R: Real> {
    /// The box the wall's particles fill at the start (m).
    pub region: Aabb<R>,
    /// Its wall model (not [`WallModel::ContactOnly`]).
    pub model: WallModel,
    /// Its velocity while it moves (m/s).
    pub velocity: Vec3<R>,
    /// How long it moves from the run's start (s, ≥ 0).
    pub duration_s: R,
}
