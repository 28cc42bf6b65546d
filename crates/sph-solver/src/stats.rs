//! Solver-neutral step statistics.

/// Most phases a solver can time (see [`PhaseTimes`]).
pub const MAX_PHASES: usize = 10;

/// Wall-clock seconds spent in each named phase of one [`crate::FluidSolver::step`] call.
///
/// Each solver names its own phases (a `&'static` list, e.g. PBF's rows of Macklin & Müller
/// 2013, Table 2: `integrate`, `create_hash_grid`, `detect_neighbours`, `constraint_solve`,
/// `velocity_update`, `reorder`), so reports and CSV columns follow the solver.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PhaseTimes {
    names: &'static [&'static str],
    seconds: [f64; MAX_PHASES],
}

impl Default for PhaseTimes {
    fn default() -> Self {
        Self::new(&[])
    }
}

impl PhaseTimes {
    /// Zero times for the phases `names` (at most [`MAX_PHASES`]; further names are ignored).
    pub const fn new(names: &'static [&'static str]) -> Self {
        Self {
            names,
            seconds: [0.0; MAX_PHASES],
        }
    }

    /// The phase names, in the solver's order.
    pub fn names(&self) -> &'static [&'static str] {
        let n = if self.names.len() < MAX_PHASES {
            self.names.len()
        } else {
            MAX_PHASES
        };
        &self.names[..n]
    }

    /// Adds `seconds` to phase number `phase` (ignored when out of range).
    #[inline]
    pub fn add(&mut self, phase: usize, seconds: f64) {
        if phase < self.names().len() {
            self.seconds[phase] += seconds;
        }
    }

    /// Seconds of phase `name`, `None` if the solver has no such phase.
    pub fn get(&self, name: &str) -> Option<f64> {
        self.names()
            .iter()
            .position(|n| *n == name)
            .map(|k| self.seconds[k])
    }

    /// `(name, seconds)` of every phase, in order.
    pub fn iter(&self) -> impl Iterator<Item = (&'static str, f64)> + '_ {
        self.names()
            .iter()
            .copied()
            .zip(self.seconds.iter().copied())
    }

    /// Sum of the phase times (s).
    pub fn total(&self) -> f64 {
        self.iter().map(|(_, s)| s).sum()
    }
}

/// What one [`crate::FluidSolver::step`] call (one frame of substeps) did, and the state at
/// its end. Non-convergence is reported here ([`StepStats::unconverged_substeps`]), never as
/// an error.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct StepStats {
    /// Wall-clock time per named phase (s).
    pub phases: PhaseTimes,
    /// Time steps done (the `substeps` parameter unless the call failed).
    pub substeps: usize,
    /// Solver iterations done in total over the substeps (PBF: Jacobi iterations; PCISPH:
    /// prediction–correction iterations).
    pub iterations: usize,
    /// Substeps whose iterations reached the maximum without meeting the solver's stopping
    /// tolerance (0 without one).
    pub unconverged_substeps: usize,
    /// The density error the stopping rule saw in the last iteration of the last substep
    /// (its definition is the solver's; 0 without a tolerance).
    pub last_solve_error: f64,
    /// Iterations of a friction-stress solve in total over the substeps (granular solvers;
    /// 0 otherwise).
    pub friction_iterations: usize,
    /// Substeps whose friction-stress solve reached its maximum iterations without meeting
    /// its tolerance.
    pub unconverged_friction_substeps: usize,
    /// The residual the friction solve's stopping rule saw in the last iteration of the
    /// last substep (its definition is the solver's; 0 without one).
    pub last_friction_residual: f64,
    /// Ordered neighbour pairs found in the last substep.
    pub neighbour_pairs: usize,
    /// `max_i ρ_i / ρ0` at the end of the call (boundary contribution included). 0 without
    /// particles.
    pub max_density_ratio: f64,
    /// Mean of `ρ_i / ρ0` at the end of the call. 0 without particles.
    pub mean_density_ratio: f64,
    /// Kinetic energy `Σ m_i |v_i|² / 2` at the end of the call (J).
    pub kinetic_energy: f64,
    /// Whether the particles were reordered at the start of this call (see
    /// [`crate::FluidSolver::last_permutation`]).
    pub reordered: bool,
}

impl StepStats {
    /// Empty statistics for a solver with the phases `names`.
    pub const fn new(names: &'static [&'static str]) -> Self {
        Self {
            phases: PhaseTimes::new(names),
            substeps: 0,
            iterations: 0,
            unconverged_substeps: 0,
            last_solve_error: 0.0,
            friction_iterations: 0,
            unconverged_friction_substeps: 0,
            last_friction_residual: 0.0,
            neighbour_pairs: 0,
            max_density_ratio: 0.0,
            mean_density_ratio: 0.0,
            kinetic_energy: 0.0,
            reordered: false,
        }
    }

    /// Seconds of phase `name` (0 if the solver has no such phase).
    pub fn phase_s(&self, name: &str) -> f64 {
        self.phases.get(name).unwrap_or(0.0)
    }

    /// Sum of the phase times (s).
    pub fn total_s(&self) -> f64 {
        self.phases.total()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn phases_by_name() {
        let mut s = StepStats::new(&["a", "b"]);
        s.phases.add(0, 1.0);
        s.phases.add(1, 2.0);
        s.phases.add(1, 0.5);
        s.phases.add(7, 100.0); // out of range: ignored
        assert_eq!(s.phase_s("a"), 1.0);
        assert_eq!(s.phase_s("b"), 2.5);
        assert_eq!(s.phases.get("c"), None);
        assert_eq!(s.total_s(), 3.5);
        assert_eq!(s.phases.iter().count(), 2);
    }
}
