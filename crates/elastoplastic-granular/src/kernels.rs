//! The kernel and constants of the per-particle loops, built once from the parameters.

use sph_core::Real;
use sph_kernels::{CubicSpline, Kernel, KernelKind};
use sph_solver::SolverError;

use crate::params::ElastoplasticParams;
use crate::stress::DruckerPrager;

/// The kernel of every sum (Bui et al. 2008 use the cubic B-spline): a volume-map boundary
/// must have been integrated with it.
pub const ELASTOPLASTIC_KERNEL: KernelKind = KernelKind::CubicSpline;

/// Kernel and constants of the per-particle loops.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Consts<R: Real> {
    pub kernel: CubicSpline<R>,
    pub material: DruckerPrager<R>,
    pub rho0: R,
    /// Smoothing length `h` (m) of the viscosity's `φ_ij`.
    pub h: R,
    /// `0.01 h²` of the viscosity's denominator.
    pub eta2: R,
    /// The viscosity's velocity scale (m/s): the speed of sound `c = √(E/ρ0)` unless
    /// `viscosity_speed_m_s` fixes it.
    pub c0: R,
    pub alpha: R,
    pub beta: R,
    pub eps_stress: R,
    pub exponent: R,
    /// `1 / W(s)`: the artificial stress's `f_ij = (W(r_ij)/W(s))^n`.
    pub inv_w_spacing: R,
    /// A squared distance (m²) a little above the support radius squared: a pair farther
    /// apart has a zero kernel and gradient (the relative margin `1e-4` covers the
    /// rounding of the squares, so that the exact test stays the kernel's own).
    pub support2_above: R,
}

impl<R: Real> Consts<R> {
    pub(crate) fn new(p: &ElastoplasticParams<R>) -> Result<Self, SolverError> {
        let kernel = CubicSpline::new(p.common.support_radius)?;
        let h = p.smoothing_length();
        Ok(Self {
            kernel,
            material: p.material(),
            rho0: p.common.rest_density,
            h,
            eta2: h * h * R::of_f64(0.01),
            c0: p.viscosity_speed(),
            alpha: p.viscosity_alpha,
            beta: p.viscosity_beta,
            eps_stress: p.artificial_stress_epsilon,
            exponent: p.artificial_stress_exponent,
            inv_w_spacing: R::one() / kernel.value(p.common.particle_spacing),
            support2_above: p.common.support_radius
                * p.common.support_radius
                * R::of_f64(1.0 + 1e-4),
        })
    }
}
