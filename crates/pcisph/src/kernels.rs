//! The kernels and constants of the per-particle loops, built once from the parameters.

use sph_core::Real;
use sph_kernels::{KernelKind, Poly6, Spiky};
use sph_solver::SolverError;

use crate::params::PcisphParams;

/// The density kernel of PCISPH here (Solenthaler & Pajarola 2009 use Poly6 for the
/// density, as Müller et al. 2003): a volume-map boundary must have been integrated with it.
pub const PCISPH_KERNEL: KernelKind = KernelKind::Poly6;

/// Kernels and constants of the per-particle loops.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Consts<R: Real> {
    pub poly6: Poly6<R>,
    pub spiky: Spiky<R>,
    pub rho0: R,
    pub inv_rho0: R,
    /// `1/ρ0²` of the pressure force.
    pub inv_rho0_sq: R,
    pub delta: R,
}

impl<R: Real> Consts<R> {
    pub(crate) fn new(p: &PcisphParams<R>) -> Result<Self, SolverError> {
        let h = p.common.support_radius;
        let poly6 = Poly6::new(h)?;
        let rho0 = p.common.rest_density;
        let inv_rho0 = R::one() / rho0;
        Ok(Self {
            poly6,
            spiky: Spiky::new(h)?,
            rho0,
            inv_rho0,
            inv_rho0_sq: inv_rho0 * inv_rho0,
            delta: p.scaling_factor()?,
        })
    }
}
