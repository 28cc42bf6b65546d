//! The per-particle working arrays of the solver.

use sph_core::{Real, Vec3};

use crate::passes::PairCache;

/// Per-particle working arrays of the solver (structure of arrays, one `Vec` per quantity),
/// kept between steps so that a step does not allocate. After a [`crate::Pbf::step`] they hold the
/// values of its last substep, in the state's current particle order.
#[derive(Debug, Clone, Default)]
pub struct PbfScratch<R: Real> {
    pub(crate) predicted: Vec<Vec3<R>>,
    pub(crate) next: Vec<Vec3<R>>,
    pub(crate) lambda: Vec<R>,
    pub(crate) delta_p: Vec<Vec3<R>>,
    pub(crate) density: Vec<R>,
    pub(crate) boundary_grad: Vec<Vec3<R>>,
    pub(crate) near_boundary: Vec<bool>,
    /// A lower bound on each particle's distance to the solids, carried through the Jacobi
    /// iterations ([`sph_solver::ContactGuard`]).
    pub(crate) clearance: Vec<R>,
    pub(crate) velocity: Vec<Vec3<R>>,
    pub(crate) velocity_new: Vec<Vec3<R>>,
    pub(crate) vorticity: Vec<Vec3<R>>,
    pub(crate) vorticity_norm: Vec<R>,
    pub(crate) pairs: PairCache<R>,
}

impl<R: Real> PbfScratch<R> {
    pub(crate) fn resize(&mut self, n: usize) {
        if self.predicted.len() == n {
            return;
        }
        let z = Vec3::zeros();
        self.predicted.resize(n, z);
        self.next.resize(n, z);
        self.lambda.resize(n, R::zero());
        self.delta_p.resize(n, z);
        self.density.resize(n, R::zero());
        self.boundary_grad.resize(n, z);
        self.near_boundary.resize(n, false);
        self.clearance.resize(n, R::zero());
        self.velocity.resize(n, z);
        self.velocity_new.resize(n, z);
        self.vorticity.resize(n, z);
        self.vorticity_norm.resize(n, R::zero());
    }

    /// Predicted positions `x*` (m): after a step, the final positions of its last substep.
    pub fn predicted(&self) -> &[Vec3<R>] {
        &self.predicted
    }
    /// `λ_i` of the last iteration (eq. 11; m², see the crate docs for units).
    pub fn lambda(&self) -> &[R] {
        &self.lambda
    }
    /// `Δp_i` of the last iteration (eq. 14, before the contact response; m).
    pub fn delta_p(&self) -> &[Vec3<R>] {
        &self.delta_p
    }
    /// Densities `ρ_i` (eq. 2 plus the boundary's `ρ0 Ψ`, kg/m³): after a step, at the final
    /// positions; after [`crate::PbfScheme::evaluate_constraints`], at the given positions.
    pub fn density(&self) -> &[R] {
        &self.density
    }
    /// Velocities `(x* − x)/Δt` of Algorithm 1 line 21 (m/s), before vorticity confinement
    /// and XSPH.
    pub fn velocity(&self) -> &[Vec3<R>] {
        &self.velocity
    }
    /// Vorticity `ω_i` of eq. 15 (1/s); zero when vorticity confinement is off.
    pub fn vorticity(&self) -> &[Vec3<R>] {
        &self.vorticity
    }
}
