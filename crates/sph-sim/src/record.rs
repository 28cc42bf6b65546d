//! [`FrameRecord`]: the one per-frame record of a scene run, from which the statistics CSV
//! (`stats.csv`: [`FrameRecord::csv_header`], [`FrameRecord::csv_row`]), the Python
//! statistics dict (its serde form) and the experiments' rows come.

use serde::{Deserialize, Serialize, Serializer};
use sph_core::Real;
use sph_solver::{PhaseTimes, StepStats};

use crate::sim::SceneSim;

/// What one frame of a scene run did, and the state at its end.
///
/// Its serde form is the Python statistics dict's; read back, a record has no phase times
/// (they are wall-clock measurements of the run that wrote it, not its results).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct FrameRecord {
    /// Frames done (this frame's number, 1 for the first).
    pub frame: usize,
    /// Simulated time at the end of the frame (s).
    pub time_s: f64,
    /// Particles simulated.
    pub particles: usize,
    /// `max_i ρ_i / ρ0` at the end of the frame (boundary contribution included).
    pub max_density_ratio: f64,
    /// Mean of `ρ_i / ρ0` at the end of the frame.
    pub mean_density_ratio: f64,
    /// Solver iterations over the frame's substeps (PBF: Jacobi; PCISPH:
    /// prediction–correction; IISPH: relaxed Jacobi).
    pub iterations: usize,
    /// Substeps whose iterations reached the maximum without meeting the stopping tolerance.
    pub unconverged_substeps: usize,
    /// Ordered neighbour pairs found in the frame's last substep.
    pub neighbour_pairs: usize,
    /// Kinetic energy `Σ m_i |v_i|² / 2` at the end of the frame (J).
    pub kinetic_energy_j: f64,
    /// Substeps done.
    pub substeps: usize,
    /// The density error the stopping rule saw in the last iteration of the last substep
    /// (the solver's definition; 0 without a tolerance).
    pub last_solve_error: f64,
    /// Friction-stress iterations over the frame's substeps (granular solvers; 0 otherwise).
    pub friction_iterations: usize,
    /// Substeps whose friction-stress solve reached its maximum iterations.
    pub unconverged_friction_substeps: usize,
    /// The friction solve's residual in its last iteration of the frame (granular).
    pub last_friction_residual: f64,
    /// The largest particle speed at the end of the frame (m/s).
    pub max_speed_m_s: f64,
    /// Whether the solver reordered the particles at the start of the frame.
    pub reordered: bool,
    /// Wall-clock seconds per phase of the solver, by name.
    #[serde(rename = "phases_s", serialize_with = "phase_map", skip_deserializing)]
    pub phases: PhaseTimes,
    /// Wall-clock seconds of the frame's phases together.
    pub total_s: f64,
}

fn phase_map<S: Serializer>(phases: &PhaseTimes, s: S) -> Result<S::Ok, S::Error> {
    s.collect_map(phases.iter())
}

/// The columns of the statistics CSV before the solver's phase times.
pub const STATS_COLUMNS: [&str; 9] = [
    "frame",
    "time_s",
    "particles",
    "max_density_ratio",
    "mean_density_ratio",
    "iterations",
    "unconverged_substeps",
    "neighbour_pairs",
    "kinetic_energy_j",
];

/// The columns of the statistics CSV after the wall-clock ones (added later than those, so
/// at the end: a reader of the earlier file finds every column where it was).
pub const STATS_EXTRA_COLUMNS: [&str; 7] = [
    "substeps",
    "last_solve_error",
    "friction_iterations",
    "unconverged_friction_substeps",
    "last_friction_residual",
    "max_speed_m_s",
    "reordered",
];

impl FrameRecord {
    /// The record of the frame `sim` has just done, with its solver's statistics `stats`.
    pub fn new<R: Real>(sim: &SceneSim<R>, stats: &StepStats) -> Self {
        let max_speed_m_s = sim
            .state
            .velocities
            .iter()
            .map(|v| v.norm().as_f64())
            .fold(0.0, f64::max);
        Self {
            frame: sim.frame,
            time_s: sim.time_s,
            particles: sim.state.len(),
            max_density_ratio: stats.max_density_ratio,
            mean_density_ratio: stats.mean_density_ratio,
            iterations: stats.iterations,
            unconverged_substeps: stats.unconverged_substeps,
            neighbour_pairs: stats.neighbour_pairs,
            kinetic_energy_j: stats.kinetic_energy,
            substeps: stats.substeps,
            last_solve_error: stats.last_solve_error,
            friction_iterations: stats.friction_iterations,
            unconverged_friction_substeps: stats.unconverged_friction_substeps,
            last_friction_residual: stats.last_friction_residual,
            max_speed_m_s,
            reordered: stats.reordered,
            phases: stats.phases,
            total_s: stats.total_s(),
        }
    }

    /// Seconds of phase `name` (0 if the solver has no such phase).
    pub fn phase_s(&self, name: &str) -> f64 {
        self.phases.get(name).unwrap_or(0.0)
    }

    /// The header of the statistics CSV for a solver with phases `phases`:
    /// [`STATS_COLUMNS`], then `<phase>_s` for each phase and `total_s` (the wall-clock
    /// columns), then [`STATS_EXTRA_COLUMNS`].
    pub fn csv_header(phases: &[&str]) -> Vec<String> {
        STATS_COLUMNS
            .iter()
            .map(|s| s.to_string())
            .chain(phases.iter().map(|p| format!("{p}_s")))
            .chain(std::iter::once("total_s".to_string()))
            .chain(STATS_EXTRA_COLUMNS.iter().map(|s| s.to_string()))
            .collect()
    }

    /// This record as a row of the statistics CSV ([`FrameRecord::csv_header`] of its
    /// solver's phases).
    pub fn csv_row(&self) -> Vec<String> {
        let mut row = vec![
            self.frame.to_string(),
            format!("{:.6}", self.time_s),
            self.particles.to_string(),
            format!("{:.6}", self.max_density_ratio),
            format!("{:.6}", self.mean_density_ratio),
            self.iterations.to_string(),
            self.unconverged_substeps.to_string(),
            self.neighbour_pairs.to_string(),
            format!("{:.6e}", self.kinetic_energy_j),
        ];
        row.extend(self.phases.iter().map(|(_, secs)| format!("{secs:.6e}")));
        row.push(format!("{:.6e}", self.total_s));
        row.extend([
            self.substeps.to_string(),
            format!("{:.6e}", self.last_solve_error),
            self.friction_iterations.to_string(),
            self.unconverged_friction_substeps.to_string(),
            format!("{:.6e}", self.last_friction_residual),
            format!("{:.6e}", self.max_speed_m_s),
            self.reordered.to_string(),
        ]);
        row
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_csv_row_has_one_field_per_header_column_in_the_serde_order() {
        let mut stats = StepStats::new(&["a", "b"]);
        stats.phases.add(1, 0.5);
        let r = FrameRecord {
            frame: 3,
            time_s: 0.048,
            particles: 10,
            max_density_ratio: 1.01,
            mean_density_ratio: 0.99,
            iterations: 40,
            unconverged_substeps: 1,
            neighbour_pairs: 300,
            kinetic_energy_j: 2.5,
            substeps: 4,
            last_solve_error: 1e-3,
            friction_iterations: 7,
            unconverged_friction_substeps: 0,
            last_friction_residual: 2e-4,
            max_speed_m_s: 1.5,
            reordered: true,
            phases: stats.phases,
            total_s: stats.total_s(),
        };
        let header = FrameRecord::csv_header(stats.phases.names());
        let row = r.csv_row();
        assert_eq!(header.len(), row.len());
        assert_eq!(header[9..12], ["a_s", "b_s", "total_s"]);
        assert_eq!(row[10], "5.000000e-1");
        // Every serde field is a CSV column (the phases expanded by name).
        let json = serde_json::to_value(r).unwrap();
        let fields = json.as_object().unwrap();
        for key in fields.keys().filter(|k| *k != "phases_s") {
            assert!(header.contains(key), "{key} is not a CSV column");
        }
        assert_eq!(fields["phases_s"]["b"], 0.5);
        assert_eq!(header.len(), fields.len() - 1 + 2);
    }
}
