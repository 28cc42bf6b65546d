//! The kernel and constants of the per-particle loops, built once from the parameters.

use sph_core::Real;
use sph_kernels::{CubicSpline, CubicSpline2D, Kernel, KernelKind};
use sph_solver::{Dimensions, SolverError};

use crate::params::ElastoplasticParams;
use crate::stress::DruckerPrager;

/// The kernel of every sum (Bui et al. 2008 use the cubic B-spline): a volume-map boundary
/// must have been integrated with it.
pub const ELASTOPLASTIC_KERNEL: KernelKind = KernelKind::CubicSpline;

/// The cubic B-spline of a planar run ([`Dimensions::Two`]): Monaghan's M4 normalised in
/// 2D ([`CubicSpline2D`], `40/(7π h²)`) over the thickness `s` (the particle spacing) of
/// the slab each particle stands for, `W = W_2D(r)/s` (1/m³). Grains of mass `ρ0 s³` then
/// sum to `Σ m_j W_ij = Σ (ρ0 s²) W_2D`: the 2D SPH sums of a plane-strain continuum with
/// the mass per unit depth `ρ0 s²`, as Bui et al. (2008) compute theirs, with densities
/// and stresses in the 3D units of the rest of the solver.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct PlaneCubicSpline<R> {
    planar: CubicSpline2D<R>,
    per_depth: R,
}

impl<R: Real> PlaneCubicSpline<R> {
    pub(crate) fn new(h: R, spacing: R) -> Result<Self, SolverError> {
        Ok(Self {
            planar: CubicSpline2D::new(h)?,
            per_depth: R::one() / spacing,
        })
    }
}

impl<R: Real> Kernel<R> for PlaneCubicSpline<R> {
    const DIM: usize = 2;

    fn name(&self) -> &'static str {
        "cubic-spline-2d-per-spacing"
    }
    #[inline]
    fn support_radius(&self) -> R {
        self.planar.support_radius()
    }
    #[inline]
    fn value(&self, r: R) -> R {
        self.planar.value(r) * self.per_depth
    }
    #[inline]
    fn derivative(&self, r: R) -> R {
        self.planar.derivative(r) * self.per_depth
    }
    fn laplacian(&self, r: R) -> Option<R> {
        self.planar.laplacian(r).map(|l| l * self.per_depth)
    }
}

/// The constants of the per-particle loops of a run in 3D or in the plane.
#[derive(Debug, Clone, Copy)]
pub(crate) enum SpaceConsts<R: Real> {
    Three(Consts<R, CubicSpline<R>>),
    Two(Consts<R, PlaneCubicSpline<R>>),
}

impl<R: Real> SpaceConsts<R> {
    pub(crate) fn new(p: &ElastoplasticParams<R>) -> Result<Self, SolverError> {
        let h = p.common.support_radius;
        Ok(match p.dimensions {
            Dimensions::Two => Self::Two(Consts::new(
                p,
                PlaneCubicSpline::new(h, p.common.particle_spacing)?,
            )?),
            _ => Self::Three(Consts::new(p, CubicSpline::new(h)?)?),
        })
    }
}

/// Kernel and constants of the per-particle loops.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Consts<R: Real, K> {
    pub kernel: K,
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
/// (the square lattice in the plane for a 2D kernel; the particle at the origin included)
/// under `kernel`: what a particle inside a full lattice sums.
pub(crate) fn lattice_number_density<R: Real, K: Kernel<R>>(kernel: &K, s: R) -> R {
    let reach = (kernel.support_radius() / s).as_f64().ceil() as i64;
    let depth = if K::DIM == 2 { 0 } else { reach };
    let mut sum = R::zero();
    for i in -reach..=reach {
        for j in -reach..=reach {
            for k in -depth..=depth {
                let r2 = (i * i + j * j + k * k) as f64;
                sum += kernel.value(s * R::of_f64(r2.sqrt()));
            }
        }
    }
    sum
}

impl<R: Real, K: Kernel<R>> Consts<R, K> {
    pub(crate) fn new(p: &ElastoplasticParams<R>, kernel: K) -> Result<Self, SolverError> {
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

#[cfg(test)]
mod tests {
    use super::*;

    /// A normalised kernel (`∫W dV = 1`, in 2D over the plane per unit depth `s`) sums over
    /// a lattice of spacing `s` to `1/s³`: the lattice sum is the integral up to the
    /// kernel's Fourier transform at the reciprocal lattice vectors (Poisson summation).
    /// The M4 spline of support `h = 2.4 s` is four boxes of width `h/2` convolved, whose
    /// transform at `|k| = 2π/s` is about `sinc⁴(k h/4) = 6·10⁻⁴` per vector; with four
    /// nearest vectors in 2D and six in 3D the sum is within about 0.4 % of `1/s³`: the
    /// bound checked is 1 %.
    #[test]
    fn the_lattice_sums_are_the_kernels_normalisation() {
        let s = 0.02;
        let h = 2.4 * s;
        let planar = PlaneCubicSpline::<f64>::new(h, s).unwrap();
        let cubic = CubicSpline::<f64>::new(h).unwrap();
        for (name, sum) in [
            ("2D", lattice_number_density(&planar, s)),
            ("3D", lattice_number_density(&cubic, s)),
        ] {
            let relative = sum * s * s * s - 1.0;
            assert!(relative.abs() < 0.01, "{name}: s³ σ0 − 1 = {relative}");
        }
    }
}
