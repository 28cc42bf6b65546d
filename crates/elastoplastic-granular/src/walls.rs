//! Walls with a model per solid: volume maps (Bender, Kugelstadt, Weiler & Koschier 2019)
//! integrated with the solver's kernel, sampled solid by solid so that each solid's share
//! `∇Ψ_k` of the SPH sums takes its own [`WallModel`].
//!
//! A wall at rest whose stress mirrors the particle's adds to particle `i`'s sums, for each
//! solid `k` with `∇Ψ_k = Σ_b V_b ∇W_ib` (pointing into the solid, `n_k` its unit vector)
//! and `M_k = I` (no-slip) or `n_k n_kᵀ` (free-slip):
//!
//! ```text
//! velocity gradient   L_i   += −(M_k v_i) ⊗ ∇Ψ_k
//! continuity          ρ̇_i   += ρ0 v_i · ∇Ψ_k
//! momentum            a_i   += 2 ρ0 M_k σ_i ∇Ψ_k / ρ_i²
//! ```

use std::sync::Arc;

use sph_core::{Real, Sdf, Vec3};
use sph_kernels::KernelKind;
use sph_solver::boundary::{Boundary, ClosestPoint, VolumeMapBoundary};

use crate::params::WallModel;

/// A [`VolumeMapBoundary`] shared between the frame shell (as its [`Boundary`]) and the
/// scheme (which samples it solid by solid).
pub(crate) struct SharedWalls<R: Real>(pub Arc<VolumeMapBoundary<R>>);

impl<R: Real> Boundary<R> for SharedWalls<R> {
    fn name(&self) -> &'static str {
        self.0.name()
    }
    fn solids(&self) -> &[Box<dyn Sdf<R>>] {
        self.0.solids()
    }
    fn has_volume(&self) -> bool {
        self.0.has_volume()
    }
    fn volume_kernel(&self) -> Option<(KernelKind, R)> {
        self.0.volume_kernel()
    }
    fn sample(&self, x: &Vec3<R>) -> sph_solver::BoundarySample<R> {
        self.0.sample(x)
    }
    fn project(&self, x: Vec3<R>) -> Vec3<R> {
        self.0.project(x)
    }
    fn contact_distance(&self) -> R {
        self.0.contact_distance()
    }
    fn contact_guard(&self) -> Option<sph_solver::ContactGuard<R>> {
        self.0.contact_guard()
    }
    fn volume_reach(&self) -> Option<f64> {
        self.0.volume_reach()
    }
    fn closest(&self, x: &Vec3<R>) -> Option<ClosestPoint<R>> {
        self.0.closest(x)
    }
    fn distance(&self, x: &Vec3<R>) -> R {
        self.0.distance(x)
    }
}

/// Where the scheme's wall gradients come from.
pub(crate) enum WallSampler<R: Real> {
    /// One `∇Ψ_k` per solid, each with its own model.
    PerSolid(Arc<VolumeMapBoundary<R>>),
    /// The boundary's summed `∇Ψ` with the default model (any [`Boundary`]; none at all
    /// without volume).
    Combined,
}

impl<R: Real> WallSampler<R> {
    /// `∇Ψ_k` of each wall slot at `x` into `out` (one per solid, or one for the combined
    /// boundary).
    #[inline]
    pub(crate) fn sample(&self, boundary: &dyn Boundary<R>, x: &Vec3<R>, out: &mut [Vec3<R>]) {
        match self {
            Self::PerSolid(w) => {
                for ((map, solid), o) in w.maps().iter().zip(w.solids()).zip(out.iter_mut()) {
                    *o = map.sample(&**solid, x).1;
                }
            }
            Self::Combined => {
                if let Some(o) = out.first_mut() {
                    *o = if boundary.has_volume() {
                        boundary.sample(x).volume_gradient
                    } else {
                        Vec3::zeros()
                    };
                }
            }
        }
    }
}

/// `M_k v` for wall model `model` and wall gradient `grad` (module docs).
#[inline]
pub(crate) fn wall_part<R: Real>(model: WallModel, grad: &Vec3<R>, v: &Vec3<R>) -> Vec3<R> {
    match model {
        // Coulomb walls are boundary particles only (the scheme refuses them with volume
        // maps); the full traction if one reaches here.
        WallModel::NoSlip | WallModel::Coulomb(_) => *v,
        WallModel::ContactOnly => Vec3::zeros(),
        WallModel::FreeSlip => {
            let g2 = grad.norm_squared();
            if g2 > R::zero() {
                grad * (grad.dot(v) / g2)
            } else {
                Vec3::zeros()
            }
        }
    }
}
