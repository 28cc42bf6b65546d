//! The experiments, one module each, grouped by the paper or work they replay.

use crate::Experiment;

pub mod boundary;
pub mod granular;
pub mod pbf;
pub mod sph;
pub mod ssfr;
pub mod symplectic;

pub(crate) use pbf::fluid_runs;

/// Every registered experiment, in run order.
pub fn registry() -> Vec<Box<dyn Experiment>> {
    vec![
        Box::new(sph::kernels::Kernels),
        Box::new(sph::neighbour_search::NeighbourSearchExperiment),
        Box::new(symplectic::symplectic_100myr::Symplectic100Myr),
        Box::new(symplectic::symplectic_order::SymplecticOrder),
        Box::new(symplectic::comet_population::CometPopulation),
        Box::new(boundary::boundary_rest::BoundaryRest),
        Box::new(pbf::pbf_bunny_density::PbfBunnyDensity),
        Box::new(pbf::pbf_stability::PbfStability),
        Box::new(pbf::pbf_convergence::PbfConvergence),
        Box::new(pbf::pbf_vorticity::PbfVorticity),
        Box::new(pbf::dam_break_front::DamBreakFront),
        Box::new(pbf::pbf_performance::PbfPerformance),
        Box::new(granular::repose::GranularRepose),
        Box::new(granular::column_collapse::GranularColumnCollapse),
        Box::new(granular::axisymmetric_collapse::GranularColumnCollapseAxisymmetric),
        Box::new(granular::iisph_convergence::IisphConvergence),
        Box::new(granular::granular_performance::GranularPerformance),
        Box::new(ssfr::ssfr_depth_accuracy::SsfrDepthAccuracy),
        Box::new(ssfr::ssfr_refraction::SsfrRefraction),
        Box::new(ssfr::ssfr_performance::SsfrPerformance),
    ]
}
