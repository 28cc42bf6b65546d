//! The three kernels of Müller, Charypar & Gross (2003): Poly6, Spiky and the viscosity kernel.

use std::f64::consts::PI;

use crate::scale::Scale;
use crate::{Kernel, KernelError, Real};

/// Müller, M., Charypar, D., Gross, M. (2003), "Particle-based fluid simulation for interactive
/// applications", Proc. ACM SIGGRAPH/Eurographics Symposium on Computer Animation (SCA 2003),
/// pp. 154–159, **eq. (20)**: the Poly6 kernel, 3D,
///
/// `W(r) = 315/(64π h⁹) (h² − r²)³` for `r < h`, `0` otherwise.
///
/// With `q = r/h` and `k = 315/(64π h³)`:
/// - `W = k (1 − q²)³` (evaluated from `r²` by [`Kernel::value_r2`], no square root),
/// - `dW/dr = −6 (k/h) q (1 − q²)²`,
/// - `∇²W = −6 (k/h²) (1 − q²)(3 − 7q²)` (= `−945/(32π h⁹)(h² − r²)(3h² − 7r²)`, the paper's
///   expression), finite everywhere: `∇²W(0) = −18 k/h²`.
///
/// `W` is a function of `r²`, so it is smooth at the origin with `∇W(0) = 0`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Poly6<R> {
    s: Scale<R>,
}

impl<R: Real> Poly6<R> {
    /// Name returned by [`Kernel::name`].
    pub const NAME: &'static str = "poly6";

    /// Builds the kernel with support radius `h` (rejects `h <= 0`, NaN, ±∞).
    pub fn new(h: R) -> Result<Self, KernelError> {
        Ok(Self {
            s: Scale::new(Self::NAME, h, 315.0 / (64.0 * PI), 3)?,
        })
    }

    /// `1 − q²` from `r²`, or `None` outside the support.
    #[inline(always)]
    fn t_of_r2(&self, r2: R) -> Option<R> {
        if r2 >= self.s.h2 {
            return None;
        }
        let t = R::one() - r2 * self.s.inv_h2;
        // `t <= 0` only by rounding just below `r = h`; NaN falls through and propagates.
        if t <= R::zero() {
            None
        } else {
            Some(t)
        }
    }
}

impl<R: Real> Kernel<R> for Poly6<R> {
    const DIM: usize = 3;

    #[inline]
    fn name(&self) -> &'static str {
        Self::NAME
    }

    #[inline]
    fn support_radius(&self) -> R {
        self.s.h
    }

    #[inline]
    fn value(&self, r: R) -> R {
        if r >= self.s.h {
            R::zero()
        } else {
            self.value_r2(r * r)
        }
    }

    #[inline]
    fn value_r2(&self, r2: R) -> R {
        match self.t_of_r2(r2) {
            Some(t) => self.s.k * t * t * t,
            None => R::zero(),
        }
    }

    #[inline]
    fn derivative(&self, r: R) -> R {
        if r >= self.s.h {
            return R::zero();
        }
        match self.t_of_r2(r * r) {
            // −6 (k/h) q t² = −6 (k/h²) r t²
            Some(t) => -R::of_f64(6.0) * self.s.k_h2 * r * t * t,
            None => R::zero(),
        }
    }

    #[inline]
    fn laplacian(&self, r: R) -> Option<R> {
        if r >= self.s.h {
            return Some(R::zero());
        }
        Some(match self.t_of_r2(r * r) {
            // (1 − q²)(3 − 7q²) = t (7t − 4) with t = 1 − q²
            Some(t) => -R::of_f64(6.0) * self.s.k_h2 * t * (R::of_f64(7.0) * t - R::of_f64(4.0)),
            None => R::zero(),
        })
    }
}

/// Müller, M., Charypar, D., Gross, M. (2003), "Particle-based fluid simulation for interactive
/// applications", Proc. ACM SIGGRAPH/Eurographics Symposium on Computer Animation (SCA 2003),
/// pp. 154–159, **eq. (21)**: the Spiky kernel (after Desbrun & Gascuel), 3D,
///
/// `W(r) = 15/(π h⁶) (h − r)³` for `r < h`, `0` otherwise.
///
/// With `q = r/h` and `k = 15/(π h³)`:
/// - `W = k (1 − q)³`,
/// - `dW/dr = −3 (k/h)(1 − q)²`, i.e. `∇W = −45/(π h⁶)(h − r)² r̂`. At `r = 0`,
///   [`Kernel::derivative`] returns the one-sided limit `−3k/h` (non-zero: the kernel has a
///   cusp), while [`Kernel::gradient`] returns the zero vector there.
/// - `∇²W = W'' + (2/r) W' = 6 (k/h²)(1 − q)(2q − 1)/q` for `0 < r < h`. It diverges like
///   `−6k/(h r)` as `r → 0`; at exactly `r = 0` [`Kernel::laplacian`] returns **`None`**
///   (there is no finite value to give, and `−∞` would silently turn sums into NaN).
///
/// The cusp also biases lattice densities high (23.6 % at `h = 2s`, see the crate docs): use
/// this kernel for pressure gradients, not for densities or Laplacians.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Spiky<R> {
    s: Scale<R>,
}

impl<R: Real> Spiky<R> {
    /// Name returned by [`Kernel::name`].
    pub const NAME: &'static str = "spiky";

    /// Builds the kernel with support radius `h` (rejects `h <= 0`, NaN, ±∞).
    pub fn new(h: R) -> Result<Self, KernelError> {
        Ok(Self {
            s: Scale::new(Self::NAME, h, 15.0 / PI, 3)?,
        })
    }
}

impl<R: Real> Kernel<R> for Spiky<R> {
    const DIM: usize = 3;

    #[inline]
    fn name(&self) -> &'static str {
        Self::NAME
    }

    #[inline]
    fn support_radius(&self) -> R {
        self.s.h
    }

    #[inline]
    fn value(&self, r: R) -> R {
        match self.s.q_t(r) {
            Some((_, t)) => self.s.k * t * t * t,
            None => R::zero(),
        }
    }

    #[inline]
    fn derivative(&self, r: R) -> R {
        match self.s.q_t(r) {
            Some((_, t)) => -R::of_f64(3.0) * self.s.k_h * t * t,
            None => R::zero(),
        }
    }

    #[inline]
    fn laplacian(&self, r: R) -> Option<R> {
        if r == R::zero() {
            return None;
        }
        Some(match self.s.q_t(r) {
            Some((q, t)) => R::of_f64(6.0) * self.s.k_h2 * t * (R::of_f64(2.0) * q - R::one()) / q,
            None => R::zero(),
        })
    }
}

/// Müller, M., Charypar, D., Gross, M. (2003), "Particle-based fluid simulation for interactive
/// applications", Proc. ACM SIGGRAPH/Eurographics Symposium on Computer Animation (SCA 2003),
/// pp. 154–159, **eq. (22)**: the viscosity kernel, 3D,
///
/// `W(r) = 15/(2π h³) (−r³/(2h³) + r²/h² + h/(2r) − 1)` for `0 < r < h`, `0` for `r >= h`,
///
/// whose Laplacian (the only thing it is meant for) is
/// `∇²W = 45/(π h⁶)(h − r) = 6 (k/h²)(1 − q)`, with `k = 15/(2π h³)`, `q = r/h`. That
/// Laplacian is finite everywhere; [`Kernel::laplacian`] returns `45/(π h⁵)` at `r = 0` (the
/// limit; the distributional Laplacian also has a `−15/h² δ(x)` term at the origin, so that
/// `∫∇²W = 0`, which no pointwise value can represent).
///
/// Evaluated in the factored form `W = k (1 − q)³(1 + q)/(2q)` (the same polynomial, without
/// the cancellation of the expanded form near `r = h`, so `W >= 0` holds in floating point),
/// `dW/dr = −(k/h)(1 − q)²(3q² + 2q + 1)/(2q²)`.
///
/// **Singular at the origin**: `W(0) = +∞` and `dW/dr(0) = −∞` are returned (the IEEE values of
/// the formula; [`Kernel::gradient`] still returns the zero vector at `r = 0`). Do not use this
/// kernel's value or gradient in sums that include the self pair (a density sum is `+∞`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ViscosityKernel<R> {
    s: Scale<R>,
}

impl<R: Real> ViscosityKernel<R> {
    /// Name returned by [`Kernel::name`].
    pub const NAME: &'static str = "viscosity";

    /// Builds the kernel with support radius `h` (rejects `h <= 0`, NaN, ±∞).
    pub fn new(h: R) -> Result<Self, KernelError> {
        Ok(Self {
            s: Scale::new(Self::NAME, h, 15.0 / (2.0 * PI), 3)?,
        })
    }
}

impl<R: Real> Kernel<R> for ViscosityKernel<R> {
    const DIM: usize = 3;

    #[inline]
    fn name(&self) -> &'static str {
        Self::NAME
    }

    #[inline]
    fn support_radius(&self) -> R {
        self.s.h
    }

    #[inline]
    fn value(&self, r: R) -> R {
        match self.s.q_t(r) {
            // q = 0 gives 1/0 = +∞ (documented).
            Some((q, t)) => self.s.k * t * t * t * (R::one() + q) / (R::of_f64(2.0) * q),
            None => R::zero(),
        }
    }

    #[inline]
    fn derivative(&self, r: R) -> R {
        match self.s.q_t(r) {
            Some((q, t)) => {
                let poly = (R::of_f64(3.0) * q + R::of_f64(2.0)) * q + R::one();
                -self.s.k_h * t * t * poly / (R::of_f64(2.0) * q * q)
            }
            None => R::zero(),
        }
    }

    #[inline]
    fn laplacian(&self, r: R) -> Option<R> {
        Some(match self.s.q_t(r) {
            Some((_, t)) => R::of_f64(6.0) * self.s.k_h2 * t,
            None => R::zero(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn poly6_constants_at_h1() {
        let k = Poly6::<f64>::new(1.0).unwrap();
        assert_relative_eq!(k.value(0.0), 315.0 / (64.0 * PI), max_relative = 1e-15);
        assert_relative_eq!(
            k.value_r2(0.25),
            315.0 / (64.0 * PI) * 0.75f64.powi(3),
            max_relative = 1e-15
        );
        // ∇²W(0) = −945/(32π) · 3 (h = 1)
        assert_relative_eq!(
            k.laplacian(0.0).unwrap(),
            -945.0 * 3.0 / (32.0 * PI),
            max_relative = 1e-15
        );
        // dW/dr(0.5) = −6 · 315/(64π) · 0.5 · 0.75²
        assert_relative_eq!(
            k.derivative(0.5),
            -6.0 * 315.0 / (64.0 * PI) * 0.5 * 0.5625,
            max_relative = 1e-15
        );
        // h = 2: W(0) = 315/(64π · 8)
        let k2 = Poly6::<f64>::new(2.0).unwrap();
        assert_relative_eq!(
            k2.value(0.0),
            315.0 / (64.0 * PI * 8.0),
            max_relative = 1e-15
        );
    }

    #[test]
    fn spiky_constants_at_h1() {
        let k = Spiky::<f64>::new(1.0).unwrap();
        assert_relative_eq!(k.value(0.0), 15.0 / PI, max_relative = 1e-15);
        assert_relative_eq!(k.derivative(0.0), -45.0 / PI, max_relative = 1e-15);
        assert_relative_eq!(k.derivative(0.5), -45.0 / PI * 0.25, max_relative = 1e-15);
        assert_eq!(k.laplacian(0.0), None);
        // ∇²W(0.25) = 6 · 15/π · 0.75 · (−0.5)/0.25
        assert_relative_eq!(
            k.laplacian(0.25).unwrap(),
            -6.0 * 15.0 / PI * 0.75 * 2.0,
            max_relative = 1e-14
        );
    }

    #[test]
    fn viscosity_constants_at_h1() {
        let k = ViscosityKernel::<f64>::new(1.0).unwrap();
        // Expanded form of the paper at r = 0.5: −1/16 + 1/4 + 1 − 1.
        let expanded = 15.0 / (2.0 * PI) * (-0.125 / 2.0 + 0.25 + 1.0 - 1.0);
        assert_relative_eq!(k.value(0.5), expanded, max_relative = 1e-15);
        assert_eq!(k.value(0.0), f64::INFINITY);
        assert_eq!(k.derivative(0.0), f64::NEG_INFINITY);
        assert_relative_eq!(k.laplacian(0.0).unwrap(), 45.0 / PI, max_relative = 1e-15);
        assert_relative_eq!(
            k.laplacian(0.25).unwrap(),
            45.0 / PI * 0.75,
            max_relative = 1e-15
        );
    }
}
