//! Energy measures of a simulation.

use sph_core::Real;

use super::SceneSim;

/// Potential energy `Σ m_i |g| (y_i − y_floor)` (J) of the particles of `sim` above the
/// scene's tank floor (the lowest particle without a tank).
pub fn potential_energy_j<R: Real>(sim: &SceneSim<R>) -> f64 {
    let g = sim.scene.gravity.iter().map(|x| x * x).sum::<f64>().sqrt();
    let floor = sim.scene.tank.map_or_else(
        || {
            sim.state
                .positions
                .iter()
                .map(|p| p.y.as_f64())
                .fold(f64::INFINITY, f64::min)
        },
        |t| t.min.y,
    );
    sim.state
        .positions
        .iter()
        .zip(&sim.state.masses)
        .map(|(p, m)| m.as_f64() * g * (p.y.as_f64() - floor))
        .sum()
}
