//! Periodic axes: the medium repeats along an axis with a period, as a scene states it
//! (`[solver] periodic = [{ axis = "z", lo = 0.0, hi = 0.03 }]`).

use serde::Deserialize;
use sph_core::Real;

/// One periodic axis: the particles' coordinate `axis` (0 = x, 1 = y, 2 = z) lives in
/// `[lo, hi)` (m) and the medium repeats with period `hi − lo`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PeriodicAxis<R: Real> {
    /// The axis (0 = x, 1 = y, 2 = z).
    pub axis: usize,
    /// Lower end of the period (m).
    pub lo: R,
    /// Upper end of the period (m).
    pub hi: R,
}

impl<R: Real> PeriodicAxis<R> {
    /// The period `hi − lo` (m).
    pub fn period(&self) -> R {
        self.hi - self.lo
    }
}

/// An axis in scene files: `"x"`, `"y"` or `"z"`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Axis {
    /// `x` (0).
    X,
    /// `y` (1).
    Y,
    /// `z` (2).
    Z,
}

impl Axis {
    /// The coordinate index (0, 1, 2).
    pub fn index(self) -> usize {
        match self {
            Axis::X => 0,
            Axis::Y => 1,
            Axis::Z => 2,
        }
    }
}

/// One periodic axis as a scene writes it: `{ axis = "z", lo = 0.0, hi = 0.03 }` (m),
/// [`PeriodicAxis`].
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PeriodicSetting {
    /// The axis.
    pub axis: Axis,
    /// Lower end of the period (m).
    pub lo: f64,
    /// Upper end of the period (m).
    pub hi: f64,
}

impl PeriodicSetting {
    /// The axis as the solvers take it.
    pub fn to_axis(&self) -> PeriodicAxis<f64> {
        PeriodicAxis {
            axis: self.axis.index(),
            lo: self.lo,
            hi: self.hi,
        }
    }
}
