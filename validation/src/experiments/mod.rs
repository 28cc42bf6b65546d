//! The experiments, one module each.

use crate::Experiment;

pub mod dam_break_front;
mod fluid_runs;
pub mod kernels;
pub mod neighbour_search;
pub mod pbf_bunny_density;
pub mod pbf_convergence;
pub mod pbf_performance;
pub mod pbf_stability;
pub mod pbf_vorticity;
pub mod symplectic_100myr;
pub mod symplectic_order;

/// Every registered experiment, in run order.
pub fn registry() -> Vec<Box<dyn Experiment>> {
    vec![
        Box::new(kernels::Kernels),
        Box::new(neighbour_search::NeighbourSearchExperiment),
        Box::new(symplectic_100myr::Symplectic100Myr),
        Box::new(symplectic_order::SymplecticOrder),
        Box::new(pbf_bunny_density::PbfBunnyDensity),
        Box::new(pbf_stability::PbfStability),
        Box::new(pbf_convergence::PbfConvergence),
        Box::new(pbf_vorticity::PbfVorticity),
        Box::new(dam_break_front::DamBreakFront),
        Box::new(pbf_performance::PbfPerformance),
    ]
}
