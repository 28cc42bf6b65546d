//! The kernels and constants of the per-particle loops, built once from the parameters.

use sph_core::Real;
use sph_kernels::{Kernel, KernelKind, Poly6, Spiky};
use sph_solver::SolverError;

use crate::params::PbfParams;
use crate::scorr::ArtificialPressure;

/// The density kernel of PBF (Macklin & Müller 2013, eq. 2): Poly6. A volume-map boundary
/// must have been integrated with it.
pub const PBF_KERNEL: KernelKind = KernelKind::Poly6;

/// Kernels and constants shared by the per-particle loops.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Consts<R: Real> {
    pub poly6: Poly6<R>,
    pub spiky: Spiky<R>,
    /// `W(0)` of Poly6: the self term of the density sum.
    pub w0: R,
    pub scorr: ArtificialPressure<R>,
    pub scorr_on: bool,
    /// `1 / D_ref` (m²): the unit in which `s_corr` is added to `λ_i + λ_j`.
    pub scorr_unit: R,
    pub rho0: R,
    pub inv_rho0: R,
    pub eps: R,
    /// [`PbfParams::clamp_negative_constraint`].
    pub unilateral: bool,
    /// Support radius `h` (m).
    pub h: R,
}

impl<R: Real> Consts<R> {
    pub(crate) fn new(p: &PbfParams<R>) -> Result<Self, SolverError> {
        let h = p.common.support_radius;
        let poly6 = Poly6::new(h)?;
        Ok(Self {
            poly6,
            spiky: Spiky::new(h)?,
            w0: poly6.value_r2(R::zero()),
            scorr: ArtificialPressure::new(h, p.scorr_k, p.scorr_n, p.scorr_delta_q)?,
            scorr_on: p.scorr_k > R::zero(),
            scorr_unit: p.scorr_unit()?,
            rho0: p.common.rest_density,
            inv_rho0: R::one() / p.common.rest_density,
            eps: p.cfm_epsilon,
            unilateral: p.clamp_negative_constraint,
            h,
        })
    }
}
