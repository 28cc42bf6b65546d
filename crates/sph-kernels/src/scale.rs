//! Support-radius validation and the precomputed constants shared by all kernels.

use crate::{KernelError, Real};

/// Powers of `h` and of the normalisation `k = σ/h^D`, computed in `f64` and rounded once to
/// `R` (so no intermediate `h⁹` can over- or underflow).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Scale<R> {
    /// Support radius `h`.
    pub h: R,
    /// `h²` (the exclusive cut-off of [`crate::Kernel::value_r2`]; equal to `h * h` in `R`).
    pub h2: R,
    /// `1/h`.
    pub inv_h: R,
    /// `1/h²`.
    pub inv_h2: R,
    /// `k = σ/h^D`, so that `W = k f(q)`.
    pub k: R,
    /// `k/h`, so that `dW/dr = (k/h) f'(q)`.
    pub k_h: R,
    /// `k/h²`, so that `d²W/dr² = (k/h²) f''(q)`.
    pub k_h2: R,
}

impl<R: Real> Scale<R> {
    /// `(q, 1 − q)` with `q = r/h` for `r < h` (and `1 − q > 0` after rounding), else `None`.
    /// NaN propagates as `Some((NaN, NaN))`.
    #[inline(always)]
    pub(crate) fn q_t(&self, r: R) -> Option<(R, R)> {
        if r >= self.h {
            return None;
        }
        let q = r * self.inv_h;
        let t = R::one() - q;
        if t <= R::zero() {
            None
        } else {
            Some((q, t))
        }
    }

    /// Validates `h` for the kernel `kernel` (dimension `dim`, normalisation `sigma`: the
    /// kernel is `W = sigma/h^dim · f(r/h)`).
    pub(crate) fn new(
        kernel: &'static str,
        h: R,
        sigma: f64,
        dim: i32,
    ) -> Result<Self, KernelError> {
        let value = h.as_f64();
        if !(h.is_finite_value() && h > R::zero()) {
            return Err(KernelError::InvalidSupportRadius { kernel, value });
        }
        let inv_h = 1.0 / value;
        let k = sigma * inv_h.powi(dim);
        let s = Self {
            h,
            h2: h * h,
            inv_h: R::of_f64(inv_h),
            inv_h2: R::of_f64(inv_h * inv_h),
            k: R::of_f64(k),
            k_h: R::of_f64(k * inv_h),
            k_h2: R::of_f64(k * inv_h * inv_h),
        };
        // Finite and normal (not subnormal, which would silently lose digits).
        let min_normal = R::of_f64(if R::NAME == "f32" {
            f32::MIN_POSITIVE as f64
        } else {
            f64::MIN_POSITIVE
        });
        let all = [s.h2, s.inv_h, s.inv_h2, s.k, s.k_h, s.k_h2];
        if all.iter().all(|&c| c.is_finite_value() && c >= min_normal) {
            Ok(s)
        } else {
            Err(KernelError::SupportRadiusOutOfRange {
                kernel,
                value,
                precision: R::NAME,
            })
        }
    }
}
