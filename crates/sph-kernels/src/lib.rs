#![doc = include_str!("../README.md")]
//!
//! ## In detail
//!
//! SPH smoothing kernels as values.
//!
//! Every kernel is a small `Copy` value built from its **support radius** `h` (absolute
//! length: `W(r) = 0` and `∇W = 0` for `r >= h`), generic over [`Real`] (`f32` or `f64`).
//! Constructors (`Type::new(h)`) reject `h <= 0`, NaN and ±∞ with
//! [`KernelError::InvalidSupportRadius`], and an `h` so extreme that a normalisation constant
//! over- or underflows in `R` with [`KernelError::SupportRadiusOutOfRange`]. The normalisation
//! constants are computed once, in `f64`, and stored.
//!
//! | Type | [`Kernel::name`] | `DIM` | `W(r)`, `q = r/h` | Source |
//! |---|---|---|---|---|
//! | [`Poly6`] | `poly6` | 3 | `315/(64π h³) (1−q²)³` | Müller, Charypar & Gross (2003), eq. 20 |
//! | [`Spiky`] | `spiky` | 3 | `15/(π h³) (1−q)³` | Müller, Charypar & Gross (2003), eq. 21 |
//! | [`ViscosityKernel`] | `viscosity` | 3 | `15/(2π h³) (−q³/2 + q² + 1/(2q) − 1)` | Müller, Charypar & Gross (2003), eq. 22 |
//! | [`CubicSpline`] | `cubic-spline` | 3 | `8/(π h³) (6q³−6q²+1 ; 2(1−q)³)` | Monaghan (1992), M4 B-spline |
//! | [`CubicSpline2D`] | `cubic-spline-2d` | 2 | `40/(7π h²) (same)` | Monaghan (1992), M4 B-spline |
//! | [`WendlandC2`] | `wendland-c2` | 3 | `21/(2π h³) (1−q)⁴(1+4q)` | Wendland (1995); Dehnen & Aly (2012), Table 1 |
//! | [`WendlandC2Planar`] | `wendland-c2-2d` | 2 | `7/(π h²) (1−q)⁴(1+4q)` | Wendland (1995); Dehnen & Aly (2012), Table 1 |
//!
//! References:
//! - M. Müller, D. Charypar, M. Gross, "Particle-based fluid simulation for interactive
//!   applications", Proc. ACM SIGGRAPH/Eurographics Symposium on Computer Animation (SCA
//!   2003), pp. 154–159.
//! - J. J. Monaghan, "Smoothed particle hydrodynamics", Annu. Rev. Astron. Astrophys. 30
//!   (1992) 543–574 (the M4 cubic B-spline, written here with support radius `h` as in
//!   SPlisHSPlasH's `CubicKernel`).
//! - H. Wendland, "Piecewise polynomial, positive definite and compactly supported radial
//!   functions of minimal degree", Adv. Comput. Math. 4 (1995) 389–396.
//! - W. Dehnen, H. Aly, "Improving convergence in smoothed particle hydrodynamics
//!   simulations without pairing instability", MNRAS 425 (2012) 1068–1082.
//!
//! # Example
//!
//! The summation density of a particle at rest in a simple cubic lattice of spacing `s`
//! (mass `m = ρ0 s³`) with the poly6 kernel at `h = 4s` is `ρ0` to the lattice-sum deviation
//! tabulated below (−2.2e-6), and a kernel can also be chosen by name at run time:
//!
//! ```
//! use sph_kernels::{Kernel, KernelKind, Poly6};
//!
//! let (rho0, s) = (1000.0_f64, 0.025); // kg/m³, m
//! let h = 4.0 * s;
//! let w = Poly6::new(h)?;
//! let mass = rho0 * s * s * s;
//! let mut density = 0.0;
//! for i in -4..=4 {
//!     for j in -4..=4 {
//!         for k in -4..=4 {
//!             let r2 = ((i * i + j * j + k * k) as f64) * s * s;
//!             density += mass * w.value_r2(r2);
//!         }
//!     }
//! }
//! assert!((density / rho0 - 1.0).abs() < 1e-5, "ρ/ρ0 = {}", density / rho0);
//!
//! // Runtime selection, and the gradient ∇W(x_i − x_j), zero beyond the support radius.
//! let spiky = "spiky".parse::<KernelKind>()?.build(h)?;
//! let r = nalgebra::Vector3::new(0.5 * h, 0.0, 0.0);
//! assert!(spiky.gradient(&r).x < 0.0);
//! assert_eq!(spiky.value(h), 0.0);
//! # Ok::<(), sph_kernels::KernelError>(())
//! ```
//!
//! # Derivatives
//!
//! [`Kernel::derivative`] is the analytic `dW/dr`; [`Kernel::gradient`] is `dW/dr · r̂` and the
//! zero vector at `r = 0`. [`Kernel::laplacian`] is the analytic radial Laplacian
//! `∇²W = W'' + (D−1)/r · W'`; it is `Some` for every kernel and every `r`, at `r = 0` the finite
//! limit, **except** [`Spiky`] at exactly `r = 0`, where `∇²W → −∞` and `None` is returned.
//!
//! # Singular kernel
//!
//! [`ViscosityKernel`] diverges at the origin (`W(0) = +∞`, `dW/dr(0) = −∞`). It exists for its
//! Laplacian (Müller et al. use it only in the viscosity force); do not use its value or
//! gradient in sums that include the self pair.
//!
//! # Lattice sums (density of a particle at rest in a perfect lattice)
//!
//! On a simple cubic lattice (square lattice in 2D) of spacing `s` with `m = ρ0 s^D`, the
//! summation density `Σ_j m W(x_i − x_j)` equals `ρ0 (1 + ε)` with `ε = Σ_{k≠0} Ŵ(2πk/s)` (Poisson
//! summation; `Ŵ` the Fourier transform, `Ŵ(0) = 1`). Relative deviations `ε` (f64, exact
//! lattice; the tests recompute them independently in reciprocal space):
//!
//! | kernel | `h = 2s` | `h = 3s` | `h = 4s` |
//! |---|---|---|---|
//! | `poly6` | +9.8e-3 | +2.2e-3 | −2.2e-6 |
//! | `spiky` | **+0.236** | **+0.047** | +0.015 |
//! | `viscosity` | +∞ | +∞ | +∞ |
//! | `cubic-spline` | −2.8e-5 | +1.8e-3 | +7.9e-5 |
//! | `wendland-c2` | +3.4e-2 | +3.1e-3 | +5.5e-4 |
//! | `cubic-spline-2d` | +8.6e-4 | +3.4e-3 | −4.2e-5 |
//! | `wendland-c2-2d` | +3.8e-2 | +5.1e-3 | +1.2e-3 |
//!
//! [`Spiky`]'s cusp at the origin makes its Fourier transform decay only like `|k|⁻⁴` with a
//! non-oscillating sign, so its lattice density is biased high by `≈ 3.82 (s/h)⁴` (23.6 % at
//! `h = 2s`): use it for pressure gradients, not for densities. The viscosity kernel's self
//! term is infinite.
//!
//! # Runtime selection
//!
//! [`KernelKind`] names the 3D kernels (`"poly6"`, `"spiky"`, `"viscosity"`, `"cubic-spline"`,
//! `"wendland-c2"`, via [`std::str::FromStr`]) and [`KernelKind::build`] returns an
//! [`AnyKernel`], which implements [`Kernel`] with `DIM = 3` by dispatching on a `match`.

use nalgebra::SVector;
pub use sph_core::{Real, Vec3};

mod any;
mod cubic;
mod muller;
pub mod quadrature;
mod scale;
mod wendland;

pub use any::{AnyKernel, KernelKind};
pub use cubic::{CubicSpline, CubicSpline2D};
pub use muller::{Poly6, Spiky, ViscosityKernel};
pub use wendland::{WendlandC2, WendlandC2Planar};

/// Errors of `sph-kernels`.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum KernelError {
    /// The support radius is zero, negative or not finite.
    #[error("{kernel}: support radius h = {value} must be finite and > 0")]
    InvalidSupportRadius {
        /// Kernel name.
        kernel: &'static str,
        /// The rejected value, widened to f64.
        value: f64,
    },
    /// The support radius is finite and positive, but so small or large that a normalisation
    /// constant (e.g. `1/h³`) over- or underflows in the chosen precision.
    #[error(
        "{kernel}: support radius h = {value} is out of range: its normalisation constants \
         are not representable in {precision}"
    )]
    SupportRadiusOutOfRange {
        /// Kernel name.
        kernel: &'static str,
        /// The rejected value, widened to f64.
        value: f64,
        /// `"f32"` or `"f64"`.
        precision: &'static str,
    },
    /// [`KernelKind::from_str`](std::str::FromStr::from_str) got an unknown name.
    #[error("unknown kernel {name:?}; expected one of: {expected}")]
    UnknownKernel {
        /// The name that was given.
        name: String,
        /// The accepted names, comma separated.
        expected: &'static str,
    },
}

/// A radially symmetric smoothing kernel `W(|r|, h)` with compact support `h`.
pub trait Kernel<R: Real>: Copy + Send + Sync + std::fmt::Debug {
    /// Spatial dimension the kernel is normalised for (2 or 3).
    const DIM: usize;

    /// Short name for reports ("poly6", "spiky", ...).
    fn name(&self) -> &'static str;

    /// Support radius `h` (absolute length): `W = 0` and `∇W = 0` for `r >= h`.
    fn support_radius(&self) -> R;

    /// `W(r)` for a distance `r >= 0`.
    fn value(&self, r: R) -> R;

    /// `W` from the squared distance `r²` (Poly6 overrides this to avoid the square root).
    #[inline]
    fn value_r2(&self, r2: R) -> R {
        self.value(r2.sqrt())
    }

    /// Radial derivative `dW/dr` at `r >= 0`.
    fn derivative(&self, r: R) -> R;

    /// Laplacian `∇²W` at `r`, `None` where the kernel defines none.
    fn laplacian(&self, r: R) -> Option<R>;

    /// `W(|r|)` for a difference vector `r = x_i − x_j`.
    #[inline]
    fn value_vec<const D: usize>(&self, r: &SVector<R, D>) -> R {
        self.value_r2(r.norm_squared())
    }

    /// `∇_i W(x_i − x_j) = dW/dr · r/|r|`; the zero vector at `r = 0` (the direction is
    /// undefined there and the zero choice keeps `∇W` antisymmetric).
    #[inline]
    fn gradient<const D: usize>(&self, r: &SVector<R, D>) -> SVector<R, D> {
        let len = r.norm();
        if len > R::zero() && len < self.support_radius() {
            r * (self.derivative(len) / len)
        } else {
            SVector::zeros()
        }
    }
}
