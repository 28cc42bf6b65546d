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
    /// `ρ0 / (m0 σ0)` of the density summation: `σ0 = Σ_k W(|k| s)` the number density
    /// (1/m³) of the full cubic lattice of spacing `s`, `m0 = ρ0 s³` ([`lattice_number_density`]),
    /// so that a grain inside a full lattice of grains of mass `m0` sums to `ρ0`.
    pub summation_scale: R,
}

/// The number density `σ0 = Σ_k W(|k| s)` (1/m³) of the simple cubic lattice of spacing `s`
/// (the particle at the origin included) under `kernel`: what a particle inside a full
/// lattice sums.
pub(crate) fn lattice_number_density<R: Real>(kernel: &CubicSpline<R>, s: R) -> R {
    let reach = (kernel.support_radius() / s).as_f64().ceil() as i64;
    let mut sum = R::zero();
    for i in -reach..=reach {
        for j in -reach..=reach {
            for k in -reach..=reach {
                let r2 = (i * i + j * j + k * k) as f64;
                sum += kernel.value(s * R::of_f64(r2.sqrt()));
            }
        }
    }
    sum
}

impl<R: Real> Consts<R> {
    pub(crate) fn new(p: &ElastoplasticParams<R>) -> Result<Self, SolverError> {
        let kernel = CubicSpline::new(p.common.support_radius)?;
        let h = p.smoothing_length();
        let s = p.common.particle_spacing;
        let sigma0 = lattice_number_density(&kernel, s);
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
            summation_scale: R::one() / (s * s * s * sigma0),
        })
    }
}
