//! Solid boundaries as values: the [`Boundary`] trait and its two models.
//!
//! - [`CollisionBoundary`]: particles are projected out of the solids' signed distance fields
//!   to a contact distance (the PBF paper's "collision detection against solids as part of
//!   the constraint solving loop"). The walls contribute no density.
//! - `VolumeMapBoundary`: Bender, Kugelstadt, Weiler & Koschier (2019), "Volume Maps: An
//!   Implicit Boundary Representation for SPH" (MIG '19). Each solid contributes its share
//!   of every particle's density, `ρ_B = ρ0 Ψ(x)` with `Ψ(x) = ∫_solid W(x − y) dy`, and its
//!   gradient `∇Ψ` to the pressure forces; see the module `volume_map` for the equations.
//!
//! Walls of boundary particles (Adami, Hu & Adams 2012), for a solver that declares them
//! ([`crate::scene_boundary::BoundaryFeatures::particles`]): their layout on the particle
//! lattice ([`particles`]: solids' walls, moving walls, blocks) and the extrapolation of
//! their stress and velocity with a wall model per particle ([`wall_extrapolation`]).

mod clearance;
mod collision;
pub mod particles;
pub mod volume_map;
pub mod wall_extrapolation;

pub use clearance::ContactGuard;
pub use collision::CollisionBoundary;
pub use particles::{
    boundary_block, BoundaryParticle, WallLattice, MAX_BOUNDARY_LATTICE_NODES,
    MAX_BOUNDARY_PARTICLES,
};
pub use volume_map::{
    half_space_volume, half_space_volume_derivative, CacheUse, Interpolation, VolumeMap,
    VolumeMapBoundary, VolumeMapBuild, VolumeMapCache, VolumeMapKey, VolumeMapOptions,
    VolumeMapStats,
};

use sph_core::{Real, Sdf, Vec3};
use sph_kernels::KernelKind;

use crate::error::SolverError;

/// What the boundary contributes to a particle at one position.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BoundarySample<R: Real> {
    /// `Ψ(x) = Σ_k ∫_{solid k} W(x − y) dy` (dimensionless): the boundary's share of the
    /// density is `ρ0 Ψ`. In the notation of Bender et al. (2019) and of the SPH boundary
    /// literature (Akinci et al. 2012), `Ψ(x_i) = Σ_b V_b W_ib`. 0 for [`CollisionBoundary`].
    pub volume: R,
    /// `∇Ψ(x) = Σ_b V_b ∇W_ib` (1/m); points into the solids. Zero for
    /// [`CollisionBoundary`].
    pub volume_gradient: Vec3<R>,
}

impl<R: Real> Default for BoundarySample<R> {
    fn default() -> Self {
        Self {
            volume: R::zero(),
            volume_gradient: Vec3::zeros(),
        }
    }
}

/// The nearest solid surface to a position.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ClosestPoint<R: Real> {
    /// Index of the solid (in [`Boundary::solids`] order).
    pub solid: usize,
    /// Signed distance to its surface (m; negative inside the solid).
    pub distance: R,
    /// Unit outward normal of the solid at the closest point (the SDF gradient).
    pub normal: Vec3<R>,
    /// The closest surface point, `x − distance · normal`.
    pub point: Vec3<R>,
}

/// A solid boundary model shared by the particle solvers.
///
/// Solvers call [`Boundary::sample`] wherever they sum densities or pressure forces (when
/// [`Boundary::has_volume`]) and [`Boundary::project`] on every position they predict.
pub trait Boundary<R: Real>: Send + Sync {
    /// Short name for reports: `"collision"` or `"volume-map"`.
    fn name(&self) -> &'static str;
    /// The solids (signed distance fields, negative inside).
    fn solids(&self) -> &[Box<dyn Sdf<R>>];
    /// Whether [`Boundary::sample`] can be non-zero (the boundary takes part in the density).
    fn has_volume(&self) -> bool;
    /// The kernel the boundary volumes were integrated with and its support radius (`None`
    /// when [`Boundary::has_volume`] is false). Solvers refuse a boundary whose kernel
    /// differs from their density kernel.
    fn volume_kernel(&self) -> Option<(KernelKind, R)>;
    /// `Ψ` and `∇Ψ` at `x` (zero when the boundary has no volume).
    fn sample(&self, x: &Vec3<R>) -> BoundarySample<R>;
    /// The contact response: `x` moved out of each solid in turn, along the solid's SDF
    /// gradient, to at least [`Boundary::contact_distance`] from its surface.
    fn project(&self, x: Vec3<R>) -> Vec3<R>;
    /// The distance (m) [`Boundary::project`] keeps particles from the surfaces.
    fn contact_distance(&self) -> R;
    /// The nearest solid surface (`None` without solids).
    fn closest(&self, x: &Vec3<R>) -> Option<ClosestPoint<R>> {
        closest_of(self.solids(), x)
    }
    /// The guard that lets a solver skip [`Boundary::project`] where a particle's distance
    /// bound proves it a no-op ([`ContactGuard`]); `Some` only when `project` is
    /// [`project_out`] over [`Boundary::solids`] at [`Boundary::contact_distance`] and the
    /// solids declare Lipschitz bounds. The default, `None`: every position is projected.
    fn contact_guard(&self) -> Option<ContactGuard<R>> {
        None
    }
    /// A distance (m) at or beyond which [`Boundary::sample`] is exactly zero: a position
    /// whose signed distance to every solid, as evaluated, is at least this samples `Ψ = 0`,
    /// `∇Ψ = 0` (the same bits as [`BoundarySample::default`]). `None` (the default): no
    /// such promise.
    fn volume_reach(&self) -> Option<f64> {
        None
    }
    /// [`Boundary::distance`] at `x`, and whether `x` is at or beyond
    /// [`Boundary::volume_reach`] from every solid (so that [`Boundary::sample`] is zero
    /// there), from one evaluation of each solid's distance. A NaN distance is never beyond.
    fn distance_beyond_reach(&self, x: &Vec3<R>) -> (R, bool) {
        let reach = self.volume_reach();
        let mut nearest = R::of_f64(f64::INFINITY);
        let mut beyond = reach.is_some();
        for s in self.solids() {
            let d = s.signed_distance(x);
            if d < nearest {
                nearest = d;
            }
            beyond &= reach.is_some_and(|r| d.as_f64() >= r);
        }
        (nearest, beyond)
    }
    /// The smallest signed distance from `x` to the solids (m; `+∞` without solids).
    fn distance(&self, x: &Vec3<R>) -> R {
        self.solids()
            .iter()
            .map(|s| s.signed_distance(x))
            .fold(R::of_f64(f64::INFINITY), |a, b| if b < a { b } else { a })
    }
}

/// A boundary that takes part in the density ([`Boundary::has_volume`]) must have been
/// integrated with the solver's density kernel `kernel` at the solver's support radius `h` (relative difference at most 1e-6);
/// otherwise [`SolverError::InvalidParameter`] naming `solver` and `boundary`.
pub fn check_volume_kernel<R: Real>(
    boundary: &dyn Boundary<R>,
    solver: &'static str,
    kernel: KernelKind,
    h: R,
) -> Result<(), SolverError> {
    if !boundary.has_volume() {
        return Ok(());
    }
    match boundary.volume_kernel() {
        Some((kind, hb)) if kind == kernel && (hb - h).abs() <= h * R::of_f64(1e-6) => Ok(()),
        Some((_, hb)) => Err(SolverError::InvalidParameter {
            solver,
            name: "boundary",
            value: hb.as_f64(),
            reason: "the boundary's volumes were integrated with another kernel or support radius than the solver's density kernel",
        }),
        None => Err(SolverError::InvalidParameter {
            solver,
            name: "boundary",
            value: f64::NAN,
            reason: "a boundary with volume must name its kernel",
        }),
    }
}

/// [`Boundary::closest`] over a list of solids.
pub fn closest_of<R: Real>(solids: &[Box<dyn Sdf<R>>], x: &Vec3<R>) -> Option<ClosestPoint<R>> {
    let mut best: Option<ClosestPoint<R>> = None;
    for (k, s) in solids.iter().enumerate() {
        let d = s.signed_distance(x);
        if best.is_none_or(|b| d < b.distance) {
            let normal = unit_or_zero(s.gradient(x));
            best = Some(ClosestPoint {
                solid: k,
                distance: d,
                normal,
                point: x - normal * d,
            });
        }
    }
    best
}

/// Moves `x` out of each solid in turn to at least `radius` from its surface, along the
/// normalised SDF gradient (no move where the gradient vanishes or is not finite).
#[inline]
pub fn project_out<R: Real>(solids: &[Box<dyn Sdf<R>>], mut x: Vec3<R>, radius: R) -> Vec3<R> {
    for s in solids {
        let d = s.signed_distance(&x);
        if d < radius {
            let g = s.gradient(&x);
            let len = g.norm();
            if len > R::zero() && len.is_finite_value() {
                x += g * ((radius - d) / len);
            }
        }
    }
    x
}

fn unit_or_zero<R: Real>(g: Vec3<R>) -> Vec3<R> {
    let len = g.norm();
    if len > R::zero() && len.is_finite_value() {
        g / len
    } else {
        Vec3::zeros()
    }
}
