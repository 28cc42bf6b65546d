//! Runtime selection of a 3D kernel by name (for scene files and command lines).

use std::fmt;
use std::str::FromStr;

use crate::{CubicSpline, Kernel, KernelError, Poly6, Real, Spiky, ViscosityKernel, WendlandC2};

/// The 3D kernels by name, for configuration files: `"poly6"`, `"spiky"`, `"viscosity"`,
/// `"cubic-spline"`, `"wendland-c2"` (parsing ignores ASCII case, surrounding whitespace, and
/// accepts `_` for `-`).
///
/// Only 3D kernels are listed: [`Kernel::DIM`] is an associated constant, so one enum cannot
/// hold kernels of different dimensions; the 2D kernels ([`crate::CubicSpline2D`],
/// [`crate::WendlandC2Planar`]) are used through their concrete types.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum KernelKind {
    /// [`Poly6`].
    Poly6,
    /// [`Spiky`].
    Spiky,
    /// [`ViscosityKernel`].
    Viscosity,
    /// [`CubicSpline`].
    CubicSpline,
    /// [`WendlandC2`].
    WendlandC2,
}

const EXPECTED: &str = "poly6, spiky, viscosity, cubic-spline, wendland-c2";

impl KernelKind {
    /// Every kind, in the order of the crate docs.
    pub const ALL: [KernelKind; 5] = [
        KernelKind::Poly6,
        KernelKind::Spiky,
        KernelKind::Viscosity,
        KernelKind::CubicSpline,
        KernelKind::WendlandC2,
    ];

    /// The name used by [`FromStr`], [`fmt::Display`] and [`Kernel::name`].
    pub const fn name(self) -> &'static str {
        match self {
            KernelKind::Poly6 => "poly6",
            KernelKind::Spiky => "spiky",
            KernelKind::Viscosity => "viscosity",
            KernelKind::CubicSpline => "cubic-spline",
            KernelKind::WendlandC2 => "wendland-c2",
        }
    }

    /// Builds the kernel of this kind with support radius `h`.
    pub fn build<R: Real>(self, h: R) -> Result<AnyKernel<R>, KernelError> {
        Ok(match self {
            KernelKind::Poly6 => AnyKernel::Poly6(Poly6::new(h)?),
            KernelKind::Spiky => AnyKernel::Spiky(Spiky::new(h)?),
            KernelKind::Viscosity => AnyKernel::Viscosity(ViscosityKernel::new(h)?),
            KernelKind::CubicSpline => AnyKernel::CubicSpline(CubicSpline::new(h)?),
            KernelKind::WendlandC2 => AnyKernel::WendlandC2(WendlandC2::new(h)?),
        })
    }
}

impl fmt::Display for KernelKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for KernelKind {
    type Err = KernelError;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let key = s.trim().to_ascii_lowercase().replace('_', "-");
        KernelKind::ALL
            .into_iter()
            .find(|k| k.name() == key)
            .ok_or_else(|| KernelError::UnknownKernel {
                name: s.to_owned(),
                expected: EXPECTED,
            })
    }
}

/// One of the 3D kernels, chosen at run time ([`KernelKind::build`]); implements [`Kernel`]
/// (`DIM = 3`) by a `match` per call.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum AnyKernel<R> {
    /// [`Poly6`].
    Poly6(Poly6<R>),
    /// [`Spiky`].
    Spiky(Spiky<R>),
    /// [`ViscosityKernel`].
    Viscosity(ViscosityKernel<R>),
    /// [`CubicSpline`].
    CubicSpline(CubicSpline<R>),
    /// [`WendlandC2`].
    WendlandC2(WendlandC2<R>),
}

impl<R: Real> AnyKernel<R> {
    /// Which kernel this is.
    pub fn kind(&self) -> KernelKind {
        match self {
            AnyKernel::Poly6(_) => KernelKind::Poly6,
            AnyKernel::Spiky(_) => KernelKind::Spiky,
            AnyKernel::Viscosity(_) => KernelKind::Viscosity,
            AnyKernel::CubicSpline(_) => KernelKind::CubicSpline,
            AnyKernel::WendlandC2(_) => KernelKind::WendlandC2,
        }
    }
}

macro_rules! dispatch {
    ($self:expr, $k:ident => $e:expr) => {
        match $self {
            AnyKernel::Poly6($k) => $e,
            AnyKernel::Spiky($k) => $e,
            AnyKernel::Viscosity($k) => $e,
            AnyKernel::CubicSpline($k) => $e,
            AnyKernel::WendlandC2($k) => $e,
        }
    };
}

impl<R: Real> Kernel<R> for AnyKernel<R> {
    const DIM: usize = 3;

    #[inline]
    fn name(&self) -> &'static str {
        dispatch!(self, k => k.name())
    }

    #[inline]
    fn support_radius(&self) -> R {
        dispatch!(self, k => k.support_radius())
    }

    #[inline]
    fn value(&self, r: R) -> R {
        dispatch!(self, k => k.value(r))
    }

    #[inline]
    fn value_r2(&self, r2: R) -> R {
        dispatch!(self, k => k.value_r2(r2))
    }

    #[inline]
    fn derivative(&self, r: R) -> R {
        dispatch!(self, k => k.derivative(r))
    }

    #[inline]
    fn laplacian(&self, r: R) -> Option<R> {
        dispatch!(self, k => k.laplacian(r))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip_and_dispatch() {
        for kind in KernelKind::ALL {
            assert_eq!(kind.name().parse::<KernelKind>().unwrap(), kind);
            assert_eq!(kind.to_string(), kind.name());
            let k = kind.build(0.5f64).unwrap();
            assert_eq!(k.kind(), kind);
            assert_eq!(k.name(), kind.name());
            assert_eq!(k.support_radius(), 0.5);
        }
        assert_eq!(
            " Cubic_Spline ".parse::<KernelKind>().unwrap(),
            KernelKind::CubicSpline
        );
        let p = KernelKind::Poly6.build(2.0f32).unwrap();
        assert_eq!(p.value(0.3), Poly6::new(2.0f32).unwrap().value(0.3));
        assert_eq!(p.value_r2(0.09), Poly6::new(2.0f32).unwrap().value_r2(0.09));
        let w = KernelKind::WendlandC2.build(1.0f64).unwrap();
        assert_eq!(
            w.laplacian(0.2),
            WendlandC2::new(1.0).unwrap().laplacian(0.2)
        );
        assert_eq!(
            w.derivative(0.2),
            WendlandC2::new(1.0).unwrap().derivative(0.2)
        );
    }

    #[test]
    fn unknown_name_is_rejected_with_the_list() {
        let err = "gaussian".parse::<KernelKind>().unwrap_err();
        let msg = err.to_string();
        assert!(
            msg.contains("gaussian") && msg.contains("wendland-c2"),
            "{msg}"
        );
    }

    #[test]
    fn build_propagates_invalid_h() {
        let err = KernelKind::Spiky.build(-1.0f64).unwrap_err();
        assert!(err.to_string().contains("spiky"), "{err}");
    }
}
