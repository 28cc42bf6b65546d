//! The cubic B-spline (M4) kernel in 3D and 2D.

use std::f64::consts::PI;

use crate::scale::Scale;
use crate::{Kernel, KernelError, Real};

/// Shape functions of the M4 spline in units of the support radius (`q = r/h ∈ [0, 1)`).
mod shape {
    use crate::Real;

    #[inline(always)]
    pub(super) fn half<R: Real>() -> R {
        R::of_f64(0.5)
    }

    /// `f(q)`: `6q³ − 6q² + 1` for `q <= 1/2`, `2(1 − q)³` above.
    #[inline(always)]
    pub(super) fn f<R: Real>(q: R, t: R) -> R {
        if q <= half() {
            R::one() + R::of_f64(6.0) * q * q * (q - R::one())
        } else {
            R::of_f64(2.0) * t * t * t
        }
    }

    /// `f'(q)`: `6q(3q − 2)` for `q <= 1/2`, `−6(1 − q)²` above.
    #[inline(always)]
    pub(super) fn df<R: Real>(q: R, t: R) -> R {
        if q <= half() {
            R::of_f64(6.0) * q * (R::of_f64(3.0) * q - R::of_f64(2.0))
        } else {
            -R::of_f64(6.0) * t * t
        }
    }

    /// `f'' + 2f'/q`: `36(2q − 1)` for `q <= 1/2`, `12(1 − q)(2q − 1)/q` above.
    #[inline(always)]
    pub(super) fn lap3<R: Real>(q: R, t: R) -> R {
        let two_q_m1 = R::of_f64(2.0) * q - R::one();
        if q <= half() {
            R::of_f64(36.0) * two_q_m1
        } else {
            R::of_f64(12.0) * t * two_q_m1 / q
        }
    }

    /// `f'' + f'/q`: `6(9q − 4)` for `q <= 1/2`, `6(1 − q)(3q − 1)/q` above.
    #[inline(always)]
    pub(super) fn lap2<R: Real>(q: R, t: R) -> R {
        if q <= half() {
            R::of_f64(6.0) * (R::of_f64(9.0) * q - R::of_f64(4.0))
        } else {
            R::of_f64(6.0) * t * (R::of_f64(3.0) * q - R::one()) / q
        }
    }
}

macro_rules! cubic_kernel {
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
                    Some((q, t)) => self.s.k * shape::f(q, t),
                    None => R::zero(),
                }
            }

            #[inline]
            fn derivative(&self, r: R) -> R {
                match self.s.q_t(r) {
                    Some((q, t)) => self.s.k_h * shape::df(q, t),
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

cubic_kernel!(
    /// Monaghan, J. J. (1992), "Smoothed particle hydrodynamics", Annu. Rev. Astron.
    /// Astrophys. 30, 543–574: the M4 cubic B-spline kernel (Monaghan & Lattanzio 1985),
    /// here normalised in **3D** and written with the support radius `h` (as SPlisHSPlasH's
    /// `CubicKernel` does; Monaghan's smoothing length is `h/2`). (The equation number in
    /// Monaghan (1992) is not given here because it could not be checked against the paper.)
    ///
    /// With `q = r/h` and `k = 8/(π h³)`:
    /// - `W = k (6q³ − 6q² + 1)` for `q <= 1/2`, `W = 2k (1 − q)³` for `1/2 < q < 1`, `0` beyond,
    /// - `dW/dr = (k/h) 6q(3q − 2)`, resp. `−6 (k/h)(1 − q)²`,
    /// - `∇²W = 36 (k/h²)(2q − 1)`, resp. `12 (k/h²)(1 − q)(2q − 1)/q`; finite everywhere,
    ///   `∇²W(0) = −36 k/h²`.
    ///
    /// `W` is C² (the third derivative jumps at `q = 1/2` and `q = 1`).
    CubicSpline,
    "cubic-spline",
    3,
    8.0 / PI,
    shape::lap3
);

cubic_kernel!(
    /// Monaghan, J. J. (1992), "Smoothed particle hydrodynamics", Annu. Rev. Astron.
    /// Astrophys. 30, 543–574: the M4 cubic B-spline kernel (Monaghan & Lattanzio 1985),
    /// here normalised in **2D** and written with the support radius `h` (as SPlisHSPlasH's
    /// `CubicKernel2D` does). (The equation number in Monaghan (1992) is not given here
    /// because it could not be checked against the paper.)
    ///
    /// Same shape as [`CubicSpline`] with `k = 40/(7π h²)`; the Laplacian is the 2D one,
    /// `∇²W = W'' + W'/r = 6 (k/h²)(9q − 4)` for `q <= 1/2`, `6 (k/h²)(1 − q)(3q − 1)/q` above
    /// (`∇²W(0) = −24 k/h²`).
    CubicSpline2D,
    "cubic-spline-2d",
    2,
    40.0 / (7.0 * PI),
    shape::lap2
);

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    #[test]
    fn cubic_constants_at_h1() {
        let k = CubicSpline::<f64>::new(1.0).unwrap();
        assert_relative_eq!(k.value(0.0), 8.0 / PI, max_relative = 1e-15);
        // Both branches meet at q = 1/2 with W = 8/π · 1/4.
        assert_relative_eq!(k.value(0.5), 2.0 / PI, max_relative = 1e-15);
        assert_relative_eq!(k.value(0.75), 8.0 / PI * 2.0 / 64.0, max_relative = 1e-15);
        assert_relative_eq!(k.derivative(0.5), -8.0 / PI * 1.5, max_relative = 1e-15);
        assert_relative_eq!(
            k.laplacian(0.0).unwrap(),
            -36.0 * 8.0 / PI,
            max_relative = 1e-15
        );
        let k2 = CubicSpline2D::<f64>::new(1.0).unwrap();
        assert_relative_eq!(k2.value(0.0), 40.0 / (7.0 * PI), max_relative = 1e-15);
        assert_relative_eq!(
            k2.laplacian(0.0).unwrap(),
            -24.0 * 40.0 / (7.0 * PI),
            max_relative = 1e-15
        );
        // h = 2 in 2D: W(0) = 40/(7π · 4)
        let k3 = CubicSpline2D::<f64>::new(2.0).unwrap();
        assert_relative_eq!(k3.value(0.0), 10.0 / (7.0 * PI), max_relative = 1e-15);
    }
}
