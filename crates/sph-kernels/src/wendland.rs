//! Wendland's C² kernel in 3D and 2D.

use std::f64::consts::PI;

use crate::scale::Scale;
use crate::{Kernel, KernelError, Real};

/// `f'' + 2f'/q = −60 (1 − q)²(1 − 2q)` for `f = (1 − q)⁴(1 + 4q)`.
#[inline(always)]
fn lap3<R: Real>(q: R, t: R) -> R {
    -R::of_f64(60.0) * t * t * (R::one() - R::of_f64(2.0) * q)
}

/// `f'' + f'/q = −20 (1 − q)²(2 − 5q)`.
#[inline(always)]
fn lap2<R: Real>(q: R, t: R) -> R {
    -R::of_f64(20.0) * t * t * (R::of_f64(2.0) - R::of_f64(5.0) * q)
}

macro_rules! wendland_kernel {
    ($(#[$doc:meta])* $ty:ident, $name:literal, $dim:literal, $sigma:expr, $lap:path) => {
        $(#[$doc])*
        #[derive(Debug, Clone, Copy, PartialEq)]
        pub struct $ty<R> {
            s: Scale<R>,
        }

        impl<R: Real> $ty<R> {
            /// Name returned by [`Kernel::name`].
            pub const NAME: &'static str = $name;

            /// Builds the kernel with support radius `h` (rejects `h <= 0`, NaN, ±∞).
            pub fn new(h: R) -> Result<Self, KernelError> {
                Ok(Self {
                    s: Scale::new(Self::NAME, h, $sigma, $dim)?,
                })
            }
        }

        impl<R: Real> Kernel<R> for $ty<R> {
            const DIM: usize = $dim;

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
                    Some((q, t)) => {
                        let t2 = t * t;
                        self.s.k * t2 * t2 * (R::one() + R::of_f64(4.0) * q)
                    }
                    None => R::zero(),
                }
            }

            #[inline]
            fn derivative(&self, r: R) -> R {
                match self.s.q_t(r) {
                    Some((q, t)) => -R::of_f64(20.0) * self.s.k_h * q * t * t * t,
                    None => R::zero(),
                }
            }

            #[inline]
            fn laplacian(&self, r: R) -> Option<R> {
                Some(match self.s.q_t(r) {
                    Some((q, t)) => self.s.k_h2 * $lap(q, t),
                    None => R::zero(),
                })
            }
        }
    };
}

wendland_kernel!(
    /// Wendland, H. (1995), "Piecewise polynomial, positive definite and compactly supported
    /// radial functions of minimal degree", Adv. Comput. Math. 4, 389–396: the C² function
    /// `φ_{3,1}(q) = (1 − q)⁴₊(4q + 1)`, normalised in **3D** as in Dehnen, W. & Aly, H.
    /// (2012), "Improving convergence in smoothed particle hydrodynamics simulations without
    /// pairing instability", MNRAS 425, 1068–1082, **Table 1** (`21/(2π)`).
    ///
    /// With `q = r/h` and `k = 21/(2π h³)`:
    /// - `W = k (1 − q)⁴(1 + 4q)` for `q < 1`, `0` beyond,
    /// - `dW/dr = −20 (k/h) q (1 − q)³`,
    /// - `∇²W = −60 (k/h²)(1 − q)²(1 − 2q)`; finite everywhere, `∇²W(0) = −60 k/h²`.
    WendlandC2,
    "wendland-c2",
    3,
    21.0 / (2.0 * PI),
    lap3
);

wendland_kernel!(
    /// Wendland, H. (1995), "Piecewise polynomial, positive definite and compactly supported
    /// radial functions of minimal degree", Adv. Comput. Math. 4, 389–396: the C² function
    /// `φ_{3,1}(q) = (1 − q)⁴₊(4q + 1)` (positive definite up to 3D, hence also in 2D),
    /// normalised in **2D** as in Dehnen, W. & Aly, H. (2012), "Improving convergence in
    /// smoothed particle hydrodynamics simulations without pairing instability", MNRAS 425,
    /// 1068–1082, **Table 1** (`7/π`).
    ///
    /// The planar (2D) counterpart of [`WendlandC2`]. With `q = r/h` and `k = 7/(π h²)`:
    /// - `W = k (1 − q)⁴(1 + 4q)` for `q < 1`, `0` beyond,
    /// - `dW/dr = −20 (k/h) q (1 − q)³`,
    /// - `∇²W = W'' + W'/r = −20 (k/h²)(1 − q)²(2 − 5q)`; `∇²W(0) = −40 k/h²`.
    #[doc(alias = "WendlandC2D2")]
    WendlandC2Planar,
    "wendland-c2-2d",
    2,
    7.0 / PI,
    lap2
);

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn wendland_constants_at_h1() {
        let k = WendlandC2::<f64>::new(1.0).unwrap();
        assert_relative_eq!(k.value(0.0), 21.0 / (2.0 * PI), max_relative = 1e-15);
        assert_relative_eq!(
            k.value(0.5),
            21.0 / (2.0 * PI) * 3.0 / 16.0,
            max_relative = 1e-15
        );
        assert_relative_eq!(
            k.derivative(0.5),
            -21.0 / (2.0 * PI) * 20.0 * 0.5 / 8.0,
            max_relative = 1e-15
        );
        assert_relative_eq!(
            k.laplacian(0.0).unwrap(),
            -60.0 * 21.0 / (2.0 * PI),
            max_relative = 1e-15
        );
        let k2 = WendlandC2Planar::<f64>::new(1.0).unwrap();
        assert_relative_eq!(k2.value(0.0), 7.0 / PI, max_relative = 1e-15);
        assert_relative_eq!(
            k2.laplacian(0.0).unwrap(),
            -40.0 * 7.0 / PI,
            max_relative = 1e-15
        );
    }
}
