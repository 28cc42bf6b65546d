//! Counts of the work an integration does, kept by the integrators themselves.

use serde::{Deserialize, Serialize};

/// The work done by an integration, counted where it is done: a deterministic measure of
/// cost, the same on every machine and in every run (unlike CPU time).
///
/// - `kepler_solves`: two-body drifts ([`kepler::drift`](crate::kepler::drift)), one per body
///   and Kepler stage;
/// - `kepler_iterations`: Halley/Newton iterations inside them (one Stumpff evaluation each);
/// - `force_evaluations`: gravitational terms `G m/|d|³` between a pair of bodies (planet–planet
///   in the interaction kick and in the ephemeris' accelerations, body–particle in a test
///   particle's perturbation kick);
/// - `interpolations`: evaluations of the ephemeris at one time (all bodies).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct WorkCounters {
    /// Two-body drifts.
    pub kepler_solves: u64,
    /// Iterations of Kepler's equation over all drifts.
    pub kepler_iterations: u64,
    /// Pairwise gravitational terms.
    pub force_evaluations: u64,
    /// Ephemeris evaluations.
    pub interpolations: u64,
}

impl std::ops::Add for WorkCounters {
    type Output = Self;
    fn add(self, o: Self) -> Self {
        Self {
            kepler_solves: self.kepler_solves + o.kepler_solves,
            kepler_iterations: self.kepler_iterations + o.kepler_iterations,
            force_evaluations: self.force_evaluations + o.force_evaluations,
            interpolations: self.interpolations + o.interpolations,
        }
    }
}

impl std::ops::AddAssign for WorkCounters {
    fn add_assign(&mut self, o: Self) {
        *self = *self + o;
    }
}

impl std::iter::Sum for WorkCounters {
    fn sum<I: Iterator<Item = Self>>(iter: I) -> Self {
        iter.fold(Self::default(), |a, b| a + b)
    }
}
