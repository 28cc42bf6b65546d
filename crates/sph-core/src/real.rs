use std::fmt::{Debug, Display};

/// Floating-point scalar used by every numeric crate of the workspace.
///
/// Implemented for `f32` and `f64`. It extends nalgebra's [`nalgebra::RealField`] with the few
/// things generic SPH code needs: conversion from `f64` literals, the machine epsilon and a
/// name for reports.
pub trait Real:
    nalgebra::RealField + Copy + Default + PartialOrd + Debug + Display + Send + Sync + 'static
{
    /// Machine epsilon (distance from 1 to the next representable number).
    const MACHINE_EPSILON: Self;
    /// `"f32"` or `"f64"`, for reports and test names.
    const NAME: &'static str;

    /// Converts an `f64` (a literal or a parameter) to this precision, rounding to nearest
    /// (named `of_f64` to avoid clashing with `num_traits::FromPrimitive::from_f64`).
    fn of_f64(x: f64) -> Self;
    /// Widens (or keeps) this value as an `f64`.
    fn as_f64(self) -> f64;
    /// `true` unless NaN or ±∞.
    fn is_finite_value(self) -> bool;
}

impl Real for f32 {
    const MACHINE_EPSILON: Self = f32::EPSILON;
    const NAME: &'static str = "f32";
    #[inline(always)]
    fn of_f64(x: f64) -> Self {
        x as f32
    }
    #[inline(always)]
    fn as_f64(self) -> f64 {
        self as f64
    }
    #[inline(always)]
    fn is_finite_value(self) -> bool {
        self.is_finite()
    }
}

impl Real for f64 {
    const MACHINE_EPSILON: Self = f64::EPSILON;
    const NAME: &'static str = "f64";
    #[inline(always)]
    fn of_f64(x: f64) -> Self {
        x
    }
    #[inline(always)]
    fn as_f64(self) -> f64 {
        self
    }
    #[inline(always)]
    fn is_finite_value(self) -> bool {
        self.is_finite()
    }
}
