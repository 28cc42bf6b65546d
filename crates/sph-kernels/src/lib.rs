//! SPH smoothing kernels as values.
//!
//! Every kernel is a small `Copy` value built from its **support radius** `h` (absolute
//! length: `W(r) = 0` for `r >= h`), generic over [`Real`] (`f32` or `f64`).
//!
//! (Kernel implementations, citations and equation numbers: see each type's docs.)

use nalgebra::SVector;
pub use sph_core::Real;

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
