//! The artificial pressure term of §4 (after Monaghan 2000).

use sph_core::Real;
use sph_kernels::{Kernel, KernelError, Poly6};

/// Macklin & Müller (2013), **eq. 13**: the artificial pressure
///
/// `s_corr = −k (W(p_i − p_j, h) / W(Δq, h))ⁿ`,
///
/// with `W` the Poly6 kernel (the paper's density kernel) and `|Δq|` a fixed distance inside
/// the support. It is added to `λ_i + λ_j` in the position update (eq. 14).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ArtificialPressure<R: Real> {
    poly6: Poly6<R>,
    k: R,
    n: i32,
    inv_w_dq: R,
}

impl<R: Real> ArtificialPressure<R> {
    /// `k` (≥ 0), `n` (≥ 1), `|Δq| = delta_q · h` with `delta_q` in (0, 1), for support `h`.
    /// Parameter ranges are checked by [`crate::PbfParams::validate`]; here only the kernel
    /// construction can fail.
    pub fn new(h: R, k: R, n: u32, delta_q: R) -> Result<Self, KernelError> {
        let poly6 = Poly6::new(h)?;
        let w_dq = poly6.value(delta_q * h);
        Ok(Self {
            poly6,
            k,
            n: n.min(i32::MAX as u32) as i32,
            inv_w_dq: R::one() / w_dq,
        })
    }

    /// `s_corr` for a pair at squared distance `r2` (m²); 0 at and beyond `h`.
    #[inline]
    pub fn value_r2(&self, r2: R) -> R {
        self.from_kernel_value(self.poly6.value_r2(r2))
    }

    /// `s_corr` from an already evaluated `W(p_i − p_j, h)` (Poly6).
    #[inline]
    pub fn from_kernel_value(&self, w: R) -> R {
        -self.k * (w * self.inv_w_dq).powi(self.n)
    }

    /// `1 / W(Δq, h)`.
    pub fn inverse_w_delta_q(&self) -> R {
        self.inv_w_dq
    }
}
