//! The collision model: projection out of SDF solids, no density contribution.

use std::fmt;

use sph_core::{Real, Sdf, Vec3};
use sph_kernels::KernelKind;

use super::{project_out, Boundary, BoundarySample};
use crate::SolverError;

/// Solids that only push particles out: each predicted position closer than
/// `contact_distance` to a solid (signed distance `d`) is moved along the solid's normalised
/// SDF gradient by `contact_distance − d`, solid after solid (the PBF paper, Algorithm 1
/// line 14). No friction or restitution; the walls add nothing to the density, so particles
/// next to a wall lack neighbours (the volume-map model is the alternative).
pub struct CollisionBoundary<R: Real> {
    solids: Vec<Box<dyn Sdf<R>>>,
    contact_distance: R,
}

impl<R: Real> fmt::Debug for CollisionBoundary<R> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("CollisionBoundary")
            .field("solids", &self.solids.len())
            .field("contact_distance", &self.contact_distance)
            .finish()
    }
}

impl<R: Real> CollisionBoundary<R> {
    /// Solids with a contact distance (m, finite and ≥ 0; the solvers use the particle
    /// radius, half the particle spacing).
    pub fn new(solids: Vec<Box<dyn Sdf<R>>>, contact_distance: R) -> Result<Self, SolverError> {
        if !(contact_distance.is_finite_value() && contact_distance >= R::zero()) {
            return Err(SolverError::InvalidParameter {
                solver: "boundary",
                name: "contact_distance",
                value: contact_distance.as_f64(),
                reason: "must be finite and >= 0",
            });
        }
        Ok(Self {
            solids,
            contact_distance,
        })
    }
}

impl<R: Real> Boundary<R> for CollisionBoundary<R> {
    fn name(&self) -> &'static str {
        "collision"
    }
    fn solids(&self) -> &[Box<dyn Sdf<R>>] {
        &self.solids
    }
    fn has_volume(&self) -> bool {
        false
    }
    fn volume_kernel(&self) -> Option<(KernelKind, R)> {
        None
    }
    fn sample(&self, _x: &Vec3<R>) -> BoundarySample<R> {
        BoundarySample::default()
    }
    #[inline]
    fn project(&self, x: Vec3<R>) -> Vec3<R> {
        project_out(&self.solids, x, self.contact_distance)
    }
    fn contact_distance(&self) -> R {
        self.contact_distance
    }
    /// The walls sample nothing anywhere.
    fn volume_reach(&self) -> Option<f64> {
        Some(f64::NEG_INFINITY)
    }
    fn contact_guard(&self) -> Option<super::ContactGuard<R>> {
        super::ContactGuard::for_solids(&self.solids, self.contact_distance)
    }
}
