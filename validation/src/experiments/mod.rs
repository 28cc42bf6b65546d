//! The experiments, one module each (file name = experiment id), in one folder per paper of
//! `docs/papers.md`: the paper whose crates each experiment validates. No paper folder imports
//! another: what several share lives outside them ([`crate::scene_runs`], [`crate::helpers`]).

use crate::Experiment;

pub mod bui_2008;
pub mod chegodaeva_2004;
pub mod im_chan_2016;
pub mod macklin_muller_2013;
pub mod neder_2024;

/// Every registered experiment, in run order.
pub fn registry() -> Vec<Box<dyn Experiment>> {
    vec![
        Box::new(macklin_muller_2013::kernels::Kernels),
        Box::new(im_chan_2016::neighbour_search::NeighbourSearchExperiment),
        Box::new(chegodaeva_2004::symplectic_100myr::Symplectic100Myr),
        Box::new(chegodaeva_2004::symplectic_order::SymplecticOrder),
        Box::new(chegodaeva_2004::comet_population::CometPopulation),
        Box::new(chegodaeva_2004::comet_encounters::CometEncounters),
        Box::new(chegodaeva_2004::centaur_population::CentaurPopulation),
        Box::new(macklin_muller_2013::boundary_rest::BoundaryRest),
        Box::new(macklin_muller_2013::pbf_bunny_density::PbfBunnyDensity),
        Box::new(macklin_muller_2013::pbf_stability::PbfStability),
        Box::new(macklin_muller_2013::pbf_convergence::PbfConvergence),
        Box::new(macklin_muller_2013::pbf_vorticity::PbfVorticity),
        Box::new(macklin_muller_2013::dam_break_front::DamBreakFront),
        Box::new(macklin_muller_2013::pbf_performance::PbfPerformance),
        Box::new(bui_2008::granular_repose::GranularRepose),
        Box::new(bui_2008::granular_funnel_heap::GranularFunnelHeap),
        Box::new(neder_2024::granular_repose_thesis::GranularReposeThesis),
        Box::new(neder_2024::granular_column_collapse::GranularColumnCollapse),
        Box::new(
            neder_2024::granular_column_collapse_axisymmetric::GranularColumnCollapseAxisymmetric,
        ),
        Box::new(neder_2024::iisph_convergence::IisphConvergence),
        Box::new(neder_2024::granular_performance::GranularPerformance),
        Box::new(bui_2008::granular_column_bui::GranularColumnBui),
        Box::new(im_chan_2016::ssfr_depth_accuracy::SsfrDepthAccuracy),
        Box::new(im_chan_2016::ssfr_refraction::SsfrRefraction),
        Box::new(im_chan_2016::ssfr_performance::SsfrPerformance),
    ]
}
