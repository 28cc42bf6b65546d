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
    n: u32,
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
            n,
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
        -self.k * pow_u32(w * self.inv_w_dq, self.n)
    }

    /// `1 / W(Δq, h)`.
    pub fn inverse_w_delta_q(&self) -> R {
        self.inv_w_dq
    }

    /// The strength `k` of eq. 13.
    pub(crate) fn strength(&self) -> R {
        self.k
    }

    /// The exponent `n` of eq. 13.
    pub(crate) fn exponent(&self) -> u32 {
        self.n
    }
}

/// `x^n` by repeated squaring, inlined (a runtime `powi` compiles to a library call, which in
/// the constraint loop costs more than the rest of the pair's arithmetic). The same sequence
/// of products as compiler-rt's `__powisf2`/`__powidf2` for `n ≥ 0` (LLVM may fold or
/// reorder a `powi`, so the two agree to a few ulp, not always bit for bit).
#[inline]
fn pow_u32<R: Real>(x: R, mut n: u32) -> R {
    if n == 4 {
        // The paper's n; the loop below computes 1 · (x²)², the same value.
        let q = x * x;
        return q * q;
    }
    let mut result = R::one();
    let mut base = x;
    loop {
        if n & 1 == 1 {
            result *= base;
        }
        n >>= 1;
        if n == 0 {
            return result;
        }
        base *= base;
    }
}

#[cfg(test)]
mod tests {
    use super::pow_u32;

    /// Against `powi`, to 8 ulp: each of the at most 7 products of repeated squaring for
    /// `n < 12` rounds once (½ ulp each), and `powi` may use another order.
    #[test]
    fn pow_u32_matches_powi() {
        for n in 0..12u32 {
            for x in [0.0f64, 0.3, 0.999, 1.0, 1.7, -2.5] {
                let (a, b) = (pow_u32(x, n), x.powi(n as i32));
                assert!(
                    (a - b).abs() <= 8.0 * f64::EPSILON * b.abs(),
                    "{x}^{n}: {a} vs {b}"
                );
                let y = x as f32;
                let (a, b) = (pow_u32(y, n), y.powi(n as i32));
                assert!(
                    (a - b).abs() <= 8.0 * f32::EPSILON * b.abs(),
                    "{y}^{n}: {a} vs {b} (f32)"
                );
            }
        }
        // The paper's n = 4 exactly: (x²)².
        assert_eq!(pow_u32(0.3f64, 4), (0.3f64 * 0.3) * (0.3 * 0.3));
    }
}
