//! The experiments, one module each.

use crate::Experiment;

pub mod kernels;
pub mod neighbour_search;

/// Every registered experiment, in run order.
pub fn registry() -> Vec<Box<dyn Experiment>> {
    vec![
        Box::new(kernels::Kernels),
        Box::new(neighbour_search::NeighbourSearchExperiment),
    ]
}
